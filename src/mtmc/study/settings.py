"""The ``[run]`` table of a study: the settings every study kind runs with.

:class:`RunSettings` is the one reader of the keys of ``[run]`` that every study has
(trials, seed, ``p``, interval, ``ndig``, samples, ``nan_policy``); a kind reads its own
extra keys itself.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

from mtmc.document import Fields
from mtmc.errors import InputError
from mtmc.uncertainty.results import require_trials

__all__ = ["MAX_TRIALS", "RunSettings"]

#: The most Monte Carlo trials ``[run] trials`` may ask for.
MAX_TRIALS = 1_000_000_000


@dataclass(frozen=True)
class RunSettings:
    """The ``[run]`` table of a study: how many trials, which seed, which probability.

    Attributes
    ----------
    trials : int
        Monte Carlo trials ``M`` (JCGM 101 §7.2); not used by an adaptive run.
    adaptive : bool
        Choose ``M`` by the adaptive procedure of JCGM 101 §7.9 (``trials = "adaptive"``
        in the file): blocks of trials are added until every output the study reports
        has ``ndig`` significant digits of ``u`` stable.
    seed : int or None
        The seed (None: fresh entropy, recorded in the result).
    p : float
        Coverage probability of the intervals.
    interval : str
        The Monte Carlo coverage interval reported (its half-length is ``U``) and used
        in the JCGM 101 §8 validation: ``"symmetric"`` (probabilistically symmetric,
        JCGM 101 §7.7.2, the default of mtmc) or ``"shortest"`` (§7.7.3).
    ndig : int
        Significant digits of ``u(y)`` regarded as meaningful (JCGM 101 §7.9.2).
    samples : bool
        Keep the model values and write them as ``.npy``.
    nan_policy : {"raise", "omit"}
        Trials whose model value is NaN or infinite stop the run (``"raise"``) or are
        left out and counted (``"omit"``).
    workers, executor, scheduler
        Where the blocks of trials (or the grid points of a sweep) are evaluated (see
        :func:`mtmc.parallel.map_blocks`); not read from the file, since they do not
        change a number: given to :meth:`Study.run` or on the command line.
    """

    trials: int = 200_000
    seed: int | None = None
    p: float = 0.95
    interval: str = "symmetric"
    ndig: int = 2
    samples: bool = False
    workers: int = 1
    executor: str = "thread"
    scheduler: Any = None
    adaptive: bool = False
    nan_policy: Literal["raise", "omit"] = "raise"

    @property
    def parallel(self) -> dict[str, Any]:
        """The ``workers``, ``executor`` and ``scheduler`` keywords of the engine."""
        return {"workers": self.workers, "executor": self.executor, "scheduler": self.scheduler}

    @property
    def engine(self) -> dict[str, Any]:
        """The keywords of :func:`mtmc.uncertainty.monte_carlo` that ``[run]`` sets.

        ``trials`` (None for an adaptive run), ``adaptive``, ``ndig``, ``p`` and ``kind``
        (the interval whose endpoints the JCGM 101 §7.9.4 rule watches), ``nan_policy``,
        and :attr:`parallel`; not the seed.
        """
        return {
            "trials": None if self.adaptive else self.trials,
            "adaptive": self.adaptive,
            "ndig": self.ndig,
            "p": self.p,
            "kind": self.interval,
            "nan_policy": self.nan_policy,
            **self.parallel,
        }

    @classmethod
    def read(
        cls, top: Fields, default_trials: int = 200_000, extra: tuple[str, ...] = ()
    ) -> RunSettings:
        """Read ``[run]`` (every key optional): the one reader of the keys every study has.

        Parameters
        ----------
        top : Fields
            The top table of the study file.
        default_trials : int
            The trials of the kind when the file gives none.
        extra : tuple of str
            Keys of ``[run]`` that the kind reads itself (a verification's point set and
            tracker position); any other key is refused.

        Notes
        -----
        ``trials = "adaptive"`` asks for the adaptive procedure of JCGM 101 §7.9;
        whether the kind offers it (and ``nan_policy = "omit"``) is checked by
        :func:`loads_study` once the kind is known.
        """
        run = top.table("run", required=False)
        if run is None:
            return cls(trials=default_trials)
        run.only(("trials", "seed", "p", "interval", "ndig", "samples", "nan_policy", *extra))
        given = run.data.get("trials")
        adaptive = given == "adaptive"
        if isinstance(given, str) and not adaptive:
            raise run.error(f'expected an integer >= 2 or "adaptive", got {given!r}', "trials")
        p = run.number("p", 0.95, low=0.0, high=1.0, open_low=True, open_high=True)
        trials = (
            default_trials
            if adaptive
            else run.integer("trials", default_trials, minimum=2, maximum=MAX_TRIALS)
        )
        try:
            require_trials(trials, p)
        except InputError as exc:
            raise run.error(exc.message, "trials") from None
        return cls(
            trials=trials,
            adaptive=adaptive,
            nan_policy=run.text("nan_policy", "raise", choices=("raise", "omit")),
            seed=run.integer("seed", None, minimum=0),
            p=p,
            interval=run.text("interval", "symmetric", choices=("symmetric", "shortest")),
            ndig=run.integer("ndig", 2, minimum=1, maximum=15),
            samples=run.flag("samples", False),
        )
