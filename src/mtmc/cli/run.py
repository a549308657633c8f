"""``mtmc run`` and ``mtmc report``: run a study file into a result folder, render a report.

A thin shell over :mod:`mtmc.study` and :mod:`mtmc.report`: it parses the arguments,
shows a progress bar on stderr, prints the summary and the path of the report (the last
line). Errors print one line naming the file, the line and the field, and exit with
status 2; a failed or interrupted run leaves no result folder.
"""

from __future__ import annotations

import functools
import inspect
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import typer
from rich.console import Console
from rich.table import Table

from mtmc.cli.common import (
    EXECUTOR_OPTION,
    JSON_OPTION,
    PLOTS_OPTION,
    PROGRESS_OPTION,
    QUIET_OPTION,
    RESULT_OPTION,
    SCHEDULER_OPTION,
    WORKERS_OPTION,
    check_trials,
    fail,
    nan_policy,
    parallel_options,
    plots_value,
    print_json,
    print_trials_seed,
    progress_bar,
    progress_flag,
    seed_option,
    warn,
)
from mtmc.cli.run_options import (
    ADAPTIVE_OPTION,
    RUN_NAN_POLICY_OPTION,
    run_lines,
    run_message,
)
from mtmc.errors import MtmcError

__all__ = [
    "decision_lines",
    "default_outdir",
    "print_outcome",
    "report_cmd",
    "run_cmd",
    "command_line",
    "StudyOptions",
    "run_study",
    "run_summary",
    "study_command",
    "summary_table",
]


def default_outdir(study: Path) -> Path:
    """The result folder of a study when ``-o`` is not given: ``mtmc-results/STEM``."""
    return Path("mtmc-results") / study.stem


def summary_table(result: Any) -> Table:
    """A Rich table of the quantities of a result: y and U as the GUM rounds them, k, §8.

    The expanded uncertainty is labelled with what it is: ``U (k, p = 95 %)`` over the
    column, and each cell gives ``U (k = …)``, with ``k = U/u`` of that quantity; y and U
    are in the quantity's unit (JCGM 100 §7.2.4).
    """
    table = Table(
        title=f"{result.title} ({result.trials} trials, seed {result.seed})",
        caption="y: estimate; U: expanded uncertainty, k = U/u; p: coverage probability",
    )
    big_u = f"U (k, p = {100 * result.p:g} %)"
    for col in ("quantity", "y", big_u, "unit", "GUM §8"):
        table.add_column(col, justify="left" if col in ("quantity", "unit") else "right")
    for q in result.quantities:
        v = q.validation
        k = "" if q.mc.k is None else f" (k = {q.mc.k:.3f})"
        table.add_row(
            q.name,
            q.reported.estimate,
            q.reported.U + k,
            q.unit,
            "" if v is None else v.verdict,
        )
    return table


def decision_lines(result: Any) -> list[str]:
    """The JCGM 106 decision of each output with a ``[conformity]`` table, a line each.

    The decision (:attr:`mtmc.uncertainty.decision.Conformity.text`), then the estimate
    and the limits it was held to: the tolerance limits ``T_L``, ``T_U`` and, under
    guarded acceptance, the acceptance limits ``A_L``, ``A_U``, in the output's unit.

    Examples
    --------
    >>> from types import SimpleNamespace as N
    >>> c = {"text": "conforms, p_c = 0.998, rule: guarded acceptance, w = 0.5·U",
    ...      "estimate": 5.2, "lower": None, "upper": 10.0, "rule": "guarded",
    ...      "acceptance": [None, 9.1]}
    >>> decision_lines(N(quantities=[N(name="E", unit="µm", conformity=c)]))
    ['conformity of E (JCGM 106): conforms, p_c = 0.998, rule: guarded acceptance,
      w = 0.5·U; E = 5.2 µm against T_U = 10 µm, acceptance limit A_U = 9.1 µm']
    """
    lines = []
    for q in result.quantities:
        c = q.conformity
        if c is None:
            continue
        unit = q.unit
        tolerance = (c["lower"], c["upper"])
        limits = [
            f"T_{s} = {v:g} {unit}" for s, v in zip("LU", tolerance, strict=True) if v is not None
        ]
        line = (
            f"conformity of {q.name} (JCGM 106): {c['text']}; {q.name} = {c['estimate']:.6g} {unit}"
        )
        line += " against " + ", ".join(limits)
        if c["rule"] == "guarded":
            accept = [
                f"A_{s} = {a:.6g} {unit}"
                for s, a, t in zip("LU", c["acceptance"], tolerance, strict=True)
                if a is not None and t is not None
            ]
            if accept:
                line += f", acceptance limit{'s' if len(accept) > 1 else ''} " + ", ".join(accept)
        lines.append(line)
    return lines


def print_outcome(
    result: Any, outdir: Path | None, *, seed_line: bool, written: tuple[str, ...] = ()
) -> None:
    """The lines every study command prints after its own table and notes.

    With ``seed_line`` (``-q``, where no table states the seed) first the line
    ``trials M  seed S``; then how the run went
    (:func:`mtmc.cli.run_options.run_lines`: adaptive, trials left out), the JCGM 106
    decisions (:func:`decision_lines`), the files ``written`` beside the folder (``"what:
    path"``), and last the report's path where there is a result folder.
    """
    if seed_line:
        print_trials_seed(result.trials, result.seed)
    for line in [*run_lines(result.extra.get("run")), *decision_lines(result), *written]:
        typer.echo(line)
    if outdir is not None:
        typer.echo(f"report: {outdir / 'report.html'}")


def run_summary(result: Any, outdir: Path) -> dict[str, Any]:
    """The summary that ``mtmc run --json`` prints: what the table says, as numbers.

    Parameters
    ----------
    result : StudyResult
        The run's result.
    outdir : Path
        Its result folder.

    Returns
    -------
    dict
        ``title``, ``kind``, ``study_file``, ``seed``, ``trials``, ``p``, ``output`` (the
        result folder), ``report`` and ``quantities``: per quantity its ``name``, ``unit``
        (of ``estimate``, ``u``, ``U`` and ``interval``), ``estimate``, ``u`` (standard
        uncertainty), ``U`` (expanded uncertainty, half the ``interval_kind`` coverage
        interval), ``k`` (``U/u``), ``p``, ``interval``, ``reported`` (y and U rounded as
        JCGM 100 §7.2.6 says) and ``verdict`` (JCGM 101 §8, or None); ``warnings``, and
        ``run`` (how the Monte Carlo went: adaptive, trials left out; or None).
    """
    quantities = []
    for q in result.quantities:
        mc = q.mc
        quantities.append(
            {
                "name": q.name,
                "unit": q.unit,
                "estimate": mc.estimate,
                "u": mc.u,
                "U": mc.U,
                "k": mc.k,
                "p": mc.p,
                "interval_kind": mc.interval,
                "interval": list(mc.coverage_interval),
                "reported": q.reported.to_dict(),
                "verdict": None if q.validation is None else q.validation.verdict,
            }
        )
    return {
        "title": result.title,
        "kind": result.kind,
        "study_file": result.study_file,
        "seed": result.seed,
        "trials": result.trials,
        "p": result.p,
        "output": str(outdir),
        "report": str(outdir / "report.html"),
        "quantities": quantities,
        "warnings": result.warnings,
        "run": result.extra.get("run"),
    }


def run_study(
    study: Any,
    outdir: Path | None,
    *,
    label: str,
    trials: int | None = None,
    seed: int | None = None,
    samples: bool | None = None,
    progress: bool | None = None,
    argv: list[str] | None = None,
    parallel: dict[str, Any] | None = None,
    adaptive: bool | None = None,
    nan_policy: str | None = None,
    plotted: int | str | None = None,
) -> Any:
    """Run a loaded study and, with ``outdir``, write its result folder: every command's route.

    Parameters
    ----------
    study : Study
        The study (:func:`mtmc.study.load_study` or :func:`mtmc.study.loads_study`).
    outdir : Path or None
        The result folder to write (created with its parents), with the study's text as
        ``study.toml`` and ``report.html`` (:func:`mtmc.study.write_result`); None: none.
    label : str
        The text before the progress bar.
    trials, seed, samples, adaptive, nan_policy, parallel
        As :meth:`mtmc.study.Study.run` (None: as the study says); ``parallel`` holds
        its ``workers``, ``executor`` and ``scheduler``.
    progress : bool or None
        ``--progress/--no-progress`` (None: when stderr is a terminal).
    argv : list of str, optional
        The command line, for ``provenance.json``.
    plotted : int or "all", optional
        ``--plots``: how many quantities of the report get a histogram and a convergence
        plot (:func:`mtmc.report.plotted_count`).

    Returns
    -------
    StudyResult
    """
    from mtmc.study import write_result
    from mtmc.study.write import now

    started = now()
    with progress_bar(f"{label}: Monte Carlo", progress) as bar:
        result = study.run(
            trials=trials,
            seed=seed,
            samples=samples,
            progress=bar,
            adaptive=adaptive,
            nan_policy=nan_policy,
            **(parallel or {}),
        )
    if outdir is not None:
        write_result(
            result,
            outdir,
            study_text=study.source.text,
            started=started,
            argv=argv,
            plotted=plotted,
        )
    return result


#: The options of a command that runs a study it builds or loads, as its ``--help`` lists
#: them after the command's own: (parameter, type, typer option). One declaration for
#: ``circle simulate``, ``circle evaluate``, ``positioning evaluate`` and ``artefact
#: simulate`` (:func:`study_command`): one name, default and help text each.
_STUDY_OPTIONS: tuple[tuple[str, Any, Any], ...] = (
    ("trials", int | None, typer.Option(None, "--trials", "-n", min=2, help="Monte Carlo trials.")),
    ("seed", int | None, seed_option("the study's run.seed, or fresh entropy")),
    ("outdir", Path | None, RESULT_OPTION),
    ("workers", int, WORKERS_OPTION),
    ("executor", str, EXECUTOR_OPTION),
    ("scheduler", str | None, SCHEDULER_OPTION),
    ("progress", bool | None, PROGRESS_OPTION),
    ("quiet", bool, QUIET_OPTION),
    ("adaptive", bool, ADAPTIVE_OPTION),
    ("nan", str | None, RUN_NAN_POLICY_OPTION),
    ("plots", str | None, PLOTS_OPTION),
)


@dataclass(frozen=True)
class StudyOptions:
    """The shared options of a study command (:func:`study_command`), as typer gives them.

    ``plotted`` is ``--plots`` read by :func:`mtmc.cli.common.plots_value`, checked before
    the command runs anything.
    """

    trials: int | None
    seed: int | None
    outdir: Path | None
    workers: int
    executor: str
    scheduler: str | None
    progress: bool | None
    quiet: bool
    adaptive: bool
    nan: str | None
    plotted: int | str | None

    def run(self, ctx: typer.Context, study: Any, label: str, *, samples: bool = False) -> Any:
        """:func:`run_study` of ``study`` with these options; ``label`` heads the bar.

        ``samples`` is ``mtmc run --samples``: the samples also written as ``.npy``. The
        result's warnings (:attr:`mtmc.study.StudyResult.warnings`) are printed on stderr,
        ``mtmc: warning: …``, before the command prints anything else.
        """
        result = run_study(
            study,
            self.outdir,
            label=label,
            trials=self.trials,
            seed=self.seed,
            samples=True if samples else None,
            progress=progress_flag(self.progress, self.quiet),
            argv=command_line(ctx),
            parallel=parallel_options(self.workers, self.executor, self.scheduler),
            adaptive=True if self.adaptive else None,
            nan_policy=None if self.nan is None else nan_policy(self.nan),
            plotted=self.plotted,
        )
        warn(result.warnings)
        return result


def study_command(fn: Callable[..., None]) -> Callable[..., None]:
    """``fn(..., options: StudyOptions)`` as a typer command with the shared options.

    The command's ``--help`` lists its own options, then those of ``_STUDY_OPTIONS``;
    ``fn`` gets them as one :class:`StudyOptions`. A new study command takes the options
    by this decorator, so that every such command spells and explains them one way.
    """
    sig = inspect.signature(fn, eval_str=True)
    own = [p for p in sig.parameters.values() if p.name != "options"]
    shared = [
        inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=option, annotation=kind)
        for name, kind, option in _STUDY_OPTIONS
    ]

    @functools.wraps(fn)
    def command(*args: Any, **kwargs: Any) -> None:
        values = {name: kwargs.pop(name) for name, _kind, _option in _STUDY_OPTIONS}
        values["plotted"] = plots_value(values.pop("plots"))
        fn(*args, options=StudyOptions(**values), **kwargs)

    params = [*own, *shared]
    command.__signature__ = sig.replace(parameters=params)  # type: ignore[attr-defined]
    command.__annotations__ = {p.name: p.annotation for p in params} | {"return": None}
    return command


def command_line(ctx: typer.Context) -> list[str]:
    """The command line of ``ctx`` as :func:`mtmc.cli.main.main` received it."""
    return list((ctx.find_root().obj or {}).get("argv", ["mtmc", *sys.argv[1:]]))


def _reader_of(path: Path, exc: BaseException) -> str:
    """Where a file without ``kind`` is not a study: the command that reads it, else ``""``.

    A measurement graph (``[[place]]``, ``[[transition]]``) is run by ``mtmc graph run``;
    an artefact definition (``[[ball]]``) is named by an artefact study's ``artefact`` key.
    """
    import tomllib

    if not (isinstance(exc, MtmcError) and exc.field == "kind" and "missing kind" in exc.message):
        return ""
    try:
        keys = set(tomllib.loads(path.read_text(encoding="utf-8")))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return ""
    if keys & {"place", "transition"}:
        return f"; {path} is a measurement graph: run it with mtmc graph run {path}"
    if "ball" in keys:
        return (
            f"; {path} defines an artefact's balls: an artefact study names it "
            '(kind = "artefact", artefact = "FILE"), run by mtmc artefact simulate or mtmc run'
        )
    return ""


def run_cmd(
    ctx: typer.Context,
    study: Path = typer.Argument(..., help="The study file (TOML)."),
    outdir: Path | None = typer.Option(
        None, "-o", "--output", help="Result folder (default: mtmc-results/STUDY-NAME)."
    ),
    trials: int | None = typer.Option(
        None, "--trials", "-n", help="Trials (default: the study's run.trials)."
    ),
    seed: int | None = seed_option("the study's run.seed, or fresh entropy"),
    samples: bool = typer.Option(False, "--samples", help="Also write the samples as .npy."),
    quiet: bool = QUIET_OPTION,
    progress: bool | None = PROGRESS_OPTION,
    as_json: bool = JSON_OPTION,
    workers: int = WORKERS_OPTION,
    executor: str = EXECUTOR_OPTION,
    scheduler: str | None = SCHEDULER_OPTION,
    adaptive: bool = ADAPTIVE_OPTION,
    nan: str | None = RUN_NAN_POLICY_OPTION,
    plots: str | None = PLOTS_OPTION,
) -> None:
    """Run STUDY and write its result folder and HTML report."""
    plotted = plots_value(plots)
    if trials is not None and trials < 2:
        fail(f"--trials: expected an integer >= 2, got {trials}")
    check_trials(trials)
    if adaptive and trials is not None:
        fail("--adaptive chooses the number of trials itself (JCGM 101 §7.9); not with --trials")
    out = outdir if outdir is not None else default_outdir(study)
    options = StudyOptions(
        trials=trials,
        seed=seed,
        outdir=out,
        workers=workers,
        executor=executor,
        scheduler=scheduler,
        progress=progress,
        quiet=quiet,
        adaptive=adaptive,
        nan=nan,
        plotted=plotted,
    )
    try:
        from mtmc.study import load_study

        result = options.run(ctx, load_study(study), study.name, samples=samples)
    except (MtmcError, OSError) as exc:
        fail(run_message(exc) + _reader_of(study, exc))
    if as_json:
        print_json(run_summary(result, out))
        return
    if not quiet:
        Console().print(summary_table(result))
    print_outcome(result, out, seed_line=quiet)


def report_cmd(
    outdir: Path = typer.Argument(..., help="A result folder (it holds result.json)."),
    plots: str | None = PLOTS_OPTION,
) -> None:
    """Render OUTDIR/report.html again from the result files."""
    from mtmc.report import render

    plotted = plots_value(plots)
    try:
        path = render(outdir, plotted=plotted)
    except (MtmcError, OSError) as exc:
        fail(exc)
    typer.echo(f"report: {path}")


def demo_cmd(
    out: Path = typer.Option(Path("mtmc-demo"), "-o", "--output", help="Output folder."),
    trials: int | None = typer.Option(None, "--trials", "-n", help="Trials of every study."),
    seed: int | None = seed_option("each study's run.seed"),
    quiet: bool = QUIET_OPTION,
    progress: bool | None = PROGRESS_OPTION,
    as_json: bool = JSON_OPTION,
    workers: int = WORKERS_OPTION,
    executor: str = EXECUTOR_OPTION,
    scheduler: str | None = SCHEDULER_OPTION,
    plots: str | None = PLOTS_OPTION,
) -> None:
    """Run the shipped studies into OUTPUT and write OUTPUT/index.html linking their reports.

    Each study's line states its seed. With --json: one object of the output folder, the
    index page and the studies, each as mtmc run --json summarises it.
    """
    from mtmc.demo import run_demo

    if trials is not None and trials < 2:
        fail(f"--trials: expected an integer >= 2, got {trials}")
    check_trials(trials)
    plotted = plots_value(plots)

    def bar(label: str) -> Any:
        return progress_bar(f"{label}: Monte Carlo", progress_flag(progress, quiet))

    summaries: list[dict[str, Any]] = []
    try:
        index = run_demo(
            out,
            trials=trials,
            seed=seed,
            progress=bar,
            echo=(lambda _line: None) if as_json else typer.echo,
            on_result=lambda folder, result: summaries.append(run_summary(result, folder)),
            plotted=plotted,
            **parallel_options(workers, executor, scheduler),
        )
    except (MtmcError, OSError) as exc:
        fail(exc)
    if as_json:
        print_json({"output": str(out), "index": str(index), "studies": summaries})
