"""The common part of every study kind: :class:`Study`, its settings and its ``run``.

A kind (``propagate``, ``graph``, ``kinematics``, ``verification``, ``artefact``,
``positioning``, ``circular``) is a frozen :class:`Study` whose ``execute`` runs its model;
:meth:`Study.run` resolves the trials, the seed and the options of ``[run]`` against the
command's, refuses an option the kind does not offer, names the study's file and line in
an engine's error, and returns the :class:`~mtmc.study.result.StudyResult`
(:mod:`mtmc.study.result`) that every kind returns.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

from mtmc.document import Source
from mtmc.study.options import unsupported_option
from mtmc.study.result import StudyResult
from mtmc.study.settings import RunSettings
from mtmc.uncertainty.sampling import resolve_seed

__all__ = ["ProgressFn", "Study"]

#: ``progress(done, total)`` after each block of trials.
ProgressFn = Callable[[int, int | None], None]


@dataclass(frozen=True)
class Study:
    """A validated study, ready to run: the common part of every kind.

    Attributes
    ----------
    title : str
        What the study is.
    source : Source
        The study file.
    settings : RunSettings
        Trials, seed, coverage probability.
    """

    kind: ClassVar[str] = ""
    #: The options of :mod:`mtmc.study.options` the kind offers (``"adaptive"``,
    #: ``"nan_policy"``); a study asking for another is refused, naming the key.
    run_options: ClassVar[frozenset[str]] = frozenset()
    #: Why the kind has no adaptive run, where it has none (said when one is asked for).
    no_adaptive: ClassVar[str] = ""
    title: str
    source: Source
    settings: RunSettings

    def run(
        self,
        *,
        trials: int | None = None,
        seed: int | None = None,
        samples: bool | None = None,
        progress: ProgressFn | None = None,
        workers: int = 1,
        executor: str = "thread",
        scheduler: Any = None,
        adaptive: bool | None = None,
        nan_policy: str | None = None,
    ) -> StudyResult:
        """Run the study.

        Parameters
        ----------
        trials : int, optional
            Overrides ``[run] trials`` (and an adaptive run of the file: the run then has
            this fixed number of trials).
        seed : int, optional
            Overrides ``[run] seed``; with neither, fresh entropy is drawn and recorded.
        samples : bool, optional
            Overrides ``[run] samples`` (keep the model values in the result).
        progress : callable, optional
            ``progress(done, total)`` after each block of trials.
        workers, executor, scheduler
            Where the blocks of trials run (:func:`mtmc.uncertainty.monte_carlo`):
            ``workers`` threads, processes or Dask workers, or the Dask cluster of
            ``scheduler`` (an address or a ``distributed.Client``). The numbers do not
            depend on them.
        adaptive : bool, optional
            Overrides ``[run] trials = "adaptive"``: choose the number of trials by the
            adaptive procedure of JCGM 101 §7.9 (not with ``trials``).
        nan_policy : {"raise", "omit"}, optional
            Overrides ``[run] nan_policy``: stop at a trial whose model value is NaN or
            infinite, or leave such trials out (counted in the result's ``run``).

        Returns
        -------
        StudyResult

        Raises
        ------
        InputError
            Fewer trials than the coverage interval needs
            (:func:`mtmc.uncertainty.require_trials`); ``adaptive`` with ``trials``; an
            option the kind does not offer (:func:`mtmc.study.options.unsupported_option`),
            naming it.
        """
        from mtmc.errors import InputError, MtmcError
        from mtmc.uncertainty.results import require_trials

        s = self.settings
        if adaptive and trials is not None:
            raise InputError(
                f"trials = {trials} was given with adaptive, which chooses the number of "
                "trials itself (JCGM 101 §7.9); give one of them",
                field="adaptive",
            )
        if nan_policy is not None and nan_policy not in ("raise", "omit"):
            raise InputError(f"expected 'raise' or 'omit', got {nan_policy!r}", field="nan_policy")
        t = s.trials if trials is None else int(trials)
        if not (adaptive or (s.adaptive and trials is None)):
            require_trials(t, s.p)
        chosen = s.seed if seed is None else seed
        settings = RunSettings(
            trials=t,
            seed=resolve_seed(chosen),
            p=s.p,
            interval=s.interval,
            ndig=s.ndig,
            samples=s.samples if samples is None else bool(samples),
            workers=workers,
            executor=executor,
            scheduler=scheduler,
            adaptive=(s.adaptive and trials is None) if adaptive is None else bool(adaptive),
            nan_policy=s.nan_policy
            if nan_policy is None
            else ("omit" if nan_policy == "omit" else "raise"),
        )
        refused = unsupported_option(self, settings)
        if refused is not None:
            key, message = refused
            raise InputError(message, field="adaptive" if key == "trials" else key)
        try:
            return self.execute(settings, progress)
        except MtmcError as exc:  # an engine's error about the study: name its file and line
            if exc.file is not None:
                raise
            at: tuple[str, ...] = (exc.field,) if exc.field else ()
            raise type(exc)(
                exc.message, file=self.source.file, line=self.source.line(at), field=exc.field
            ) from None

    def execute(self, settings: RunSettings, progress: ProgressFn | None) -> StudyResult:
        """Run with resolved settings (the seed an int); each kind implements it."""
        raise NotImplementedError

    def _result(
        self, settings: RunSettings, *, run: Mapping[str, Any] | None = None, **kw: Any
    ) -> StudyResult:
        """The result; ``run`` (:func:`mtmc.study.options.run_record`) gives its trials."""
        assert settings.seed is not None
        if run is not None:
            kw["extra"] = {**kw.get("extra", {}), "run": dict(run)}
        return StudyResult(
            kind=self.kind,
            title=self.title,
            study_file=self.source.file,
            study_sha256=self.source.sha256,
            seed=settings.seed,
            trials=settings.trials if run is None else int(run["trials"]),
            p=settings.p,
            input_files=tuple(self.source.files),
            **kw,
        )
