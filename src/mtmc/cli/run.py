"""``mtmc run`` and ``mtmc report``: run a study file into a result folder, render a report.

A thin shell over :mod:`mtmc.study` and :mod:`mtmc.report`: it parses the arguments,
shows a progress bar on stderr, prints the summary and the path of the report (the last
line). Errors print one line naming the file, the line and the field, and exit with
status 2; a failed or interrupted run leaves no result folder.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import typer
from rich.console import Console
from rich.table import Table

from mtmc.cli.common import (
    EXECUTOR_OPTION,
    SCHEDULER_OPTION,
    WORKERS_OPTION,
    check_trials,
    fail,
    parallel_options,
    progress_bar,
    warn,
)
from mtmc.errors import MtmcError

__all__ = ["default_outdir", "report_cmd", "run_cmd", "run_study_file", "summary_table"]


def default_outdir(study: Path) -> Path:
    """The result folder of a study when ``-o`` is not given: ``mtmc-results/STEM``."""
    return Path("mtmc-results") / study.stem


def summary_table(result: Any) -> Table:
    """A Rich table of the quantities of a result: y and U as the GUM rounds them, k, §8."""
    table = Table(title=f"{result.title} ({result.trials} trials, seed {result.seed})")
    for col in ("quantity", "y", "U", "unit", "k", "GUM §8"):
        table.add_column(col, justify="left" if col in ("quantity", "unit") else "right")
    for q in result.quantities:
        v = q.validation
        table.add_row(
            q.name,
            q.reported["estimate"],
            q.reported["U"],
            q.unit,
            "" if q.mc["k"] is None else f"{q.mc['k']:.3f}",
            "" if v is None else v["verdict"],
        )
    return table


def run_study_file(
    study: Path,
    outdir: Path,
    *,
    trials: int | None = None,
    seed: int | None = None,
    samples: bool | None = None,
    progress: bool | None = None,
    argv: list[str] | None = None,
    parallel: dict[str, Any] | None = None,
) -> Any:
    """Load, run and write one study (the library calls of ``mtmc run``); return the result.

    ``parallel`` holds the ``workers``, ``executor`` and ``scheduler`` of
    :meth:`mtmc.study.Study.run`.
    """
    from mtmc.study import load_study, write_result
    from mtmc.study.write import now

    s = load_study(study)
    started = now()
    with progress_bar(f"{study.name}: Monte Carlo", progress) as bar:
        result = s.run(trials=trials, seed=seed, samples=samples, progress=bar, **(parallel or {}))
    write_result(result, outdir, study_text=s.source.text, started=started, argv=argv)
    return result


def run_cmd(
    ctx: typer.Context,
    study: Path = typer.Argument(..., help="The study file (TOML)."),
    outdir: Path | None = typer.Option(
        None, "-o", "--outdir", help="Result folder (default: mtmc-results/STUDY-NAME)."
    ),
    trials: int | None = typer.Option(
        None, "--trials", "-n", help="Trials (default: the study's run.trials)."
    ),
    seed: int | None = typer.Option(None, "--seed", help="Seed (default: the study's run.seed)."),
    samples: bool = typer.Option(False, "--samples", help="Also write the samples as .npy."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar, no table."),
    workers: int = WORKERS_OPTION,
    executor: str = EXECUTOR_OPTION,
    scheduler: str | None = SCHEDULER_OPTION,
) -> None:
    """Run STUDY and write its result folder and HTML report."""
    if trials is not None and trials < 2:
        fail(f"--trials: expected an integer >= 2, got {trials}")
    check_trials(trials)
    out = outdir if outdir is not None else default_outdir(study)
    try:
        result = run_study_file(
            study,
            out,
            trials=trials,
            seed=seed,
            samples=True if samples else None,
            progress=False if quiet else None,
            argv=(ctx.obj or {}).get("argv", ["mtmc", *sys.argv[1:]]),
            parallel=parallel_options(workers, executor, scheduler),
        )
    except (MtmcError, OSError) as exc:
        fail(exc)
    warn(result.extra.get("warnings", ()))
    if not quiet:
        Console().print(summary_table(result))
    typer.echo(f"report: {out / 'report.html'}")


def report_cmd(
    outdir: Path = typer.Argument(..., help="A result folder (it holds result.json)."),
) -> None:
    """Render OUTDIR/report.html again from the result files."""
    from mtmc.report import render

    try:
        path = render(outdir)
    except (MtmcError, OSError) as exc:
        fail(exc)
    typer.echo(f"report: {path}")


def demo_cmd(
    out: Path = typer.Option(Path("mtmc-demo"), "-o", "--outdir", help="Output folder."),
    trials: int | None = typer.Option(None, "--trials", "-n", help="Trials of every study."),
    seed: int | None = typer.Option(None, "--seed", help="Seed of every study."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bars."),
    workers: int = WORKERS_OPTION,
    executor: str = EXECUTOR_OPTION,
    scheduler: str | None = SCHEDULER_OPTION,
) -> None:
    """Run the shipped studies into OUTDIR and write OUTDIR/index.html linking their reports."""
    from mtmc.demo import run_demo

    if trials is not None and trials < 2:
        fail(f"--trials: expected an integer >= 2, got {trials}")
    check_trials(trials)

    def bar(label: str) -> Any:
        return progress_bar(f"{label}: Monte Carlo", False if quiet else None)

    try:
        run_demo(
            out,
            trials=trials,
            seed=seed,
            progress=bar,
            echo=typer.echo,
            **parallel_options(workers, executor, scheduler),
        )
    except (MtmcError, OSError) as exc:
        fail(exc)
