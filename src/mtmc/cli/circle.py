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

from mtmc.cli.common import JSON_OPTION, fail, print_json, print_trials_seed, seed_option
from mtmc.cli.positioning import parse_columns
from mtmc.errors import InputError, MtmcError

__all__ = ["app", "evaluate_cmd"]

app = typer.Typer(
    help="Circular tests (ISO 230-4 ballbar): parameters and errors with U by GUM and Monte Carlo.",
    no_args_is_help=True,
)


def _directions(text: str | None) -> dict[str, str] | None:
    """``"clockwise=cw,anti=ccw"`` as a mapping of the file's words onto cw/ccw."""
    if not text:
        return None
    out: dict[str, str] = {}
    for part in text.split(","):
        word, sep, meaning = part.partition("=")
        if not sep or not word.strip() or not meaning.strip():
            raise InputError(
                f"expected --directions as WORD=cw|ccw pairs, got {part!r}", field="directions"
            )
        out[word.strip()] = meaning.strip()
    return out


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
