"""``mtmc circle``: evaluate an ISO 230-4 circular test (ballbar) with its uncertainty.

A thin shell over :mod:`mtmc.circular`: it reads the trace, evaluates it (the ISO 230-4
parameters and the identified errors, each with U by Monte Carlo beside the GUM) and
prints a table, or one JSON object with ``--json``. Errors print one line naming the
file, the line and the column, and exit with status 2.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer
from rich.console import Console
from rich.table import Table

from mtmc.cli.common import (
    EXECUTOR_OPTION,
    JSON_OPTION,
    PROGRESS_OPTION,
    SCHEDULER_OPTION,
    WORKERS_OPTION,
    fail,
    load_study_of_kind,
    nan_policy,
    parallel_options,
    print_json,
    print_trials_seed,
    seed_option,
)
from mtmc.cli.positioning import parse_columns
from mtmc.cli.run_options import ADAPTIVE_OPTION, RUN_NAN_POLICY_OPTION, run_lines, run_message
from mtmc.csvtable import read_pairs
from mtmc.errors import MtmcError

__all__ = ["app", "evaluate_cmd", "simulate_cmd"]

app = typer.Typer(
    help="Circular tests (ISO 230-4 ballbar): parameters and errors with U by GUM and Monte Carlo.",
    no_args_is_help=True,
)


def _directions(text: str | None) -> dict[str, str] | None:
    """``"clockwise=cw,anti=ccw"`` as a mapping of the file's words onto cw/ccw."""
    if not text:
        return None
    return dict(read_pairs(text, "directions", "WORD=cw or WORD=ccw", "clockwise=cw"))


@app.command("evaluate")
def evaluate_cmd(
    data: Path = typer.Argument(..., help="CSV file: angle,direction,deviation per row."),
    radius: float = typer.Option(..., "--radius", help="Nominal radius R, mm."),
    feed: float = typer.Option(1000.0, "--feed", help="Feed, mm/min."),
    plane: str = typer.Option("XY", "--plane", help="XY, YZ or ZX."),
    units: str = typer.Option("deg,um", "--units", help="ANGLE,DEVIATION: deg,um  deg,mm  rad,um."),
    columns: str | None = typer.Option(
        None, "--columns", help="The file's column names: angle=Angle,deviation=Error,..."
    ),
    directions: str | None = typer.Option(
        None, "--directions", help="The file's direction words: clockwise=cw,counter=ccw."
    ),
    trials: int = typer.Option(10_000, "--trials", "-n", min=2, help="Monte Carlo trials."),
    seed: int | None = seed_option("fresh entropy"),
    as_json: bool = JSON_OPTION,
) -> None:
    """Evaluate DATA: F, G (LSC, MZ), H, G(b) and the identified errors, each with U."""
    from mtmc.circular import evaluate_trace, load_circular_csv

    try:
        tr = load_circular_csv(
            data, columns=parse_columns(columns), units=units, directions=_directions(directions)
        )
        out: dict[str, Any] = evaluate_trace(
            tr.theta_ccw,
            tr.ccw,
            tr.theta_cw,
            tr.cw,
            radius=radius,
            feed=feed / 60.0,
            plane=plane,
            trials=trials,
            seed=seed,
            deviation_unit=tr.unit,
        )
    except (MtmcError, OSError) as exc:
        fail(exc)
    res = out.pop("result")
    out["trials"] = int(res.mc.trials)
    seed_used = res.mc.seed
    assert seed_used is not None  # a run records the seed it drew
    out["seed"] = int(seed_used)
    if as_json:
        print_json(out)
        return
    table = Table(title=f"{data.name}: circular test ({out['trials']} trials)")
    for col in ("quantity", "estimate", "U (MC, 95 %)", "U (GUM, 95 %)", "unit", "GUM §8"):
        table.add_column(col, justify="left" if col in ("quantity", "unit") else "right")
    for group in ("parameters", "errors"):
        for name, e in out[group].items():
            table.add_row(
                name,
                f"{e['estimate']:.4g}",
                f"{e['U']:.2g}",
                f"{e['U_gum']:.2g}",
                e["unit"],
                "validated" if e["validated"] else "not validated",
            )
    Console().print(table)
    print_trials_seed(out["trials"], out["seed"])
    for note in out["notes"]:
        typer.echo(f"note: {note}")


@app.command("simulate")
def simulate_cmd(
    ctx: typer.Context,
    study: Path = typer.Argument(..., help='A circular study (kind = "circular").'),
    trials: int | None = typer.Option(None, "--trials", "-n", min=2, help="Monte Carlo trials."),
    seed: int | None = seed_option("the study's run.seed, or fresh entropy"),
    as_json: bool = JSON_OPTION,
    outdir: Path | None = typer.Option(
        None, "-o", "--output", help="Also write the result folder with its HTML report."
    ),
    workers: int = WORKERS_OPTION,
    executor: str = EXECUTOR_OPTION,
    scheduler: str | None = SCHEDULER_OPTION,
    progress: bool | None = PROGRESS_OPTION,
    adaptive: bool = ADAPTIVE_OPTION,
    nan: str | None = RUN_NAN_POLICY_OPTION,
) -> None:
    """Simulate STUDY as mtmc run does: the parameters and the identified errors with U."""
    from mtmc.cli.run import command_line, run_study

    try:
        result = run_study(
            load_study_of_kind(study, "circular"),
            outdir,
            label=study.name,
            trials=trials,
            seed=seed,
            progress=progress,
            argv=command_line(ctx),
            parallel=parallel_options(workers, executor, scheduler),
            adaptive=True if adaptive else None,
            nan_policy=None if nan is None else nan_policy(nan),
        )
    except (MtmcError, OSError) as exc:
        fail(run_message(exc))
    out: dict[str, Any] = {
        "trials": result.trials,
        "seed": result.seed,
        "quantities": {
            q.name: {
                "estimate": q.mc.estimate,
                "U": q.mc.U,
                "U_gum": None if q.gum is None else q.gum.U,
                "unit": q.unit,
                "validated": None if q.validation is None else q.validation.passed,
                **({"conformity": q.conformity} if q.conformity else {}),
            }
            for q in result.quantities
        },
        "notes": result.extra["circular"]["notes"],
    }
    if as_json:
        print_json(out)
        return
    table = Table(title=f"{result.title} ({result.trials} trials)")
    for col in ("quantity", "estimate", "U (MC)", "U (GUM)", "unit", "GUM §8"):
        table.add_column(col, justify="left" if col in ("quantity", "unit") else "right")
    for q in result.quantities:
        table.add_row(
            q.name,
            f"{q.mc.estimate:.4g}",
            f"{q.mc.U:.2g}",
            "" if q.gum is None else f"{q.gum.U:.2g}",
            q.unit,
            "" if q.validation is None else q.validation.verdict,
        )
    Console().print(table)
    print_trials_seed(result.trials, result.seed)
    for line in run_lines(result.extra.get("run")):
        typer.echo(line)
    for note in out["notes"]:
        typer.echo(f"note: {note}")
    if outdir is not None:
        typer.echo(f"report: {outdir / 'report.html'}")
