"""Reading a study file: the ``[run]`` settings and the registry of kinds.

A study file is TOML (``docs/study-format.md``), read and parsed once by
:mod:`mtmc.document` into a :class:`~mtmc.document.Fields` of its top table, whose errors
name the file, the line and the field. Study kinds register a loader under their name with
:func:`register_kind`; :func:`load_study` reads ``kind`` and hands the parsed file to the
loader of that kind; :meth:`RunSettings.read` is the one reader of ``[run]``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from mtmc.document import Fields, loads_toml, read_text
from mtmc.errors import InputError, MtmcError

#: The most Monte Carlo trials ``[run] trials`` may ask for.
MAX_TRIALS = 1_000_000_000

if TYPE_CHECKING:
    from mtmc.study.base import Study

__all__ = [
    "RunSettings",
    "StudyKind",
    "load_study",
    "loads_study",
    "register_kind",
    "study_kinds",
]


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
        return cls(
            trials=default_trials
            if adaptive
            else run.integer("trials", default_trials, minimum=2, maximum=MAX_TRIALS),
            adaptive=adaptive,
            nan_policy=run.text("nan_policy", "raise", choices=("raise", "omit")),
            seed=run.integer("seed", None, minimum=0),
            p=run.number("p", 0.95, low=0.0, high=1.0, open_low=True, open_high=True),
            interval=run.text("interval", "symmetric", choices=("symmetric", "shortest")),
            ndig=run.integer("ndig", 2, minimum=1, maximum=15),
            samples=run.flag("samples", False),
        )


@dataclass(frozen=True)
class StudyKind:
    """A kind of study: its name, a one-line description and its loader.

    Attributes
    ----------
    name : str
        The ``kind`` of the study file.
    summary : str
        What it computes, in one line.
    load : callable
        ``load(fields) -> Study``: validates the whole file (a :class:`Fields` of the
        top-level table) before anything runs.
    """

    name: str
    summary: str
    load: Callable[[Fields], Study]


_KINDS: dict[str, StudyKind] = {}


def register_kind(
    name: str, summary: str
) -> Callable[[Callable[[Fields], Study]], Callable[[Fields], Study]]:
    """Register the loader of a study kind (a decorator); a name is registered once.

    Parameters
    ----------
    name : str
        The ``kind`` a study file names.
    summary : str
        One line on what the kind computes.

    Returns
    -------
    callable
        The decorator, returning the loader unchanged.

    Raises
    ------
    ValueError
        If ``name`` is already registered.
    """

    def deco(load: Callable[[Fields], Study]) -> Callable[[Fields], Study]:
        if name in _KINDS:
            raise ValueError(f"study kind {name!r} is already registered")
        _KINDS[name] = StudyKind(name, summary, load)
        return load

    return deco


def study_kinds() -> dict[str, StudyKind]:
    """The registered study kinds, by name (sorted)."""
    return dict(sorted(_KINDS.items()))


def loads_study(text: str, *, file: str = "<study>", folder: Path | None = None) -> Study:
    """Read and validate a study from TOML text (see :func:`load_study`)."""
    top = loads_toml(text, file, folder)
    data = top.data
    known = study_kinds()
    kind = top.text("kind") if "kind" in data else None
    if kind is None:
        raise top.missing(f"missing kind; expected one of {', '.join(known)}", "kind")
    if kind not in known:
        raise top.error(f"unknown kind {kind!r}; expected one of {', '.join(known)}", "kind")
    try:
        study = known[kind].load(top)
    except MtmcError as exc:
        if exc.file is not None:
            raise
        # an error of the library below (a distribution, an expression, a graph) that
        # knows no file: it happened while reading this study.
        raise InputError(exc.message, file=file, line=exc.line, field=exc.field) from None
    from mtmc.study.options import unsupported_option

    refused = unsupported_option(study, study.settings)
    if refused is not None:
        key, message = refused
        run = top.table("run")
        assert run is not None  # an option other than the defaults was read from [run]
        raise run.error(message, key)
    return study


def load_study(path: str | Path) -> Study:
    """Read and validate a study file; nothing runs until ``.run()``.

    Parameters
    ----------
    path : str or Path
        The TOML study file (``docs/study-format.md``).

    Returns
    -------
    Study
        A frozen study of the kind the file names; ``study.run(...)`` runs it.

    Raises
    ------
    InputError
        If the file cannot be read, or any field is wrong: the message names the file,
        the line and the field and says what was expected (an unknown ``kind`` lists
        the known ones).
    ParseError
        If the file is not TOML.
    """
    p = Path(path)
    return loads_study(read_text(p, "study file"), file=str(path), folder=p.resolve().parent)
