"""``mtmc positioning``: evaluate an ISO 230-2 positioning test with its uncertainty.

A thin shell over :mod:`mtmc.study.positioning` (the route ``mtmc run`` takes for a
``positioning`` study) and :mod:`mtmc.positioning`: it parses the arguments, runs the
study, prints the parameters (or one JSON object with ``--json``) and writes the
compensation table and the result folder where asked. Errors print one line naming the
file, the line and the field, and exit with status 2.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import typer
from rich import box
from rich.console import Console
from rich.table import Table

from mtmc.cli.common import JSON_OPTION, fail, load_study_of_kind, print_json
from mtmc.cli.run import StudyOptions, print_outcome, study_command
from mtmc.cli.run_options import run_message
from mtmc.csvtable import read_pairs
from mtmc.errors import InputError, MtmcError

__all__ = ["app", "evaluate_cmd", "parse_columns"]

app = typer.Typer(
    rich_markup_mode=None,
    help="Positioning tests of an axis (ISO 230-2): parameters with U by GUM and Monte Carlo.",
    no_args_is_help=True,
)


def parse_columns(text: str | None) -> dict[str, str] | None:
    """``"target=Pos,deviation=Error"`` as ``{"target": "Pos", "deviation": "Error"}``."""
    if not text:
        return None
    return dict(read_pairs(text, "columns", "OURS=THEIRS", "target=Position"))


def _study(
    data: Path,
    study_file: Path | None,
    units: str,
    columns: dict[str, str] | None,
    axis: str | None,
    type_a: str | None,
    directions: str | None = None,
) -> Any:
    from mtmc.positioning import UncertaintyModel, load_positioning_csv
    from mtmc.study.positioning import positioning_study

    if study_file is None:
        model = {} if type_a is None else {"type_a": type_a}
        return positioning_study(
            data,
            units=units,
            columns=columns,
            directions=directions,
            axis=axis or "X",
            model=model,
        )
    s = load_study_of_kind(study_file, "positioning")
    test = load_positioning_csv(data, columns=columns, units=units, directions=directions)
    model = s.model if type_a is None else dataclasses.replace(s.model, type_a=type_a)
    if not isinstance(model, UncertaintyModel):  # pragma: no cover - the study's own type
        raise InputError("not an uncertainty model", field="model")
    return dataclasses.replace(s, test=test, model=model, axis=axis or s.axis)


@app.command("evaluate")
@study_command
def evaluate_cmd(
    ctx: typer.Context,
    data: Path = typer.Argument(..., help="CSV file: target,run,direction,deviation per row."),
    study_file: Path | None = typer.Option(
        None,
        "--study",
        help="A positioning study whose environment, instrument, tolerances and [run] apply "
        "to DATA (default: the Type A evaluation of the readings alone).",
    ),
    units: str = typer.Option(
        "mm,um", "--units", help="TARGET,DEVIATION units: mm,um  mm,mm  deg,arcsec  deg,urad."
    ),
    columns: str | None = typer.Option(
        None, "--columns", help="The file's column names: target=Position,deviation=Error,..."
    ),
    directions: str | None = typer.Option(
        None,
        "--directions",
        help="The file's words of the two directions beyond +/-, up/down, Forward/Reverse, "
        "fwd/bwd, 1/-1: Hin=up,Rueck=down.",
    ),
    axis: str | None = typer.Option(
        None, "--axis", help="Axis letter (default X, or the study's)."
    ),
    type_a: str | None = typer.Option(
        None, "--type-a", help="means, means-and-s or none (default: means, or the study's)."
    ),
    as_json: bool = JSON_OPTION,
    compensation: Path | None = typer.Option(
        None, "--compensation", help="Write the pitch-error compensation table here."
    ),
    fmt: str = typer.Option("isg", "--format", help="Its format: isg, etalon or csv."),
    sign: str = typer.Option("error", "--sign", help="Its values: error or correction."),
    *,
    options: StudyOptions,
) -> None:
    """Evaluate DATA: the parameters of ISO 230-2, each with U by Monte Carlo and the GUM."""
    from mtmc.positioning import pitch_compensation
    from mtmc.study.positioning import summary
    from mtmc.verification.compensation import dump_compensation

    try:
        s = _study(data, study_file, units, parse_columns(columns), axis, type_a, directions)
        result = options.run(ctx, s, data.name)
        if compensation is not None:
            dump_compensation(pitch_compensation(s.test, s.axis, sign=sign), compensation, fmt)
    except (MtmcError, OSError) as exc:
        fail(run_message(exc))
    out = summary(result)
    if as_json:
        print_json(out)
        return
    if not options.quiet:
        _print(result, out)
    written = () if compensation is None else (f"compensation table: {compensation}",)
    print_outcome(result, options.outdir, seed_line=options.quiet, written=written)


def _decimals(text: str) -> int:
    """The decimal places of a number printed as text (``"0.0054"`` → 4)."""
    return len(text.partition(".")[2])


def _print(result: Any, out: dict[str, Any]) -> None:
    """The table of the parameters, what U covers, and the notes.

    The decisions and the rest follow (:func:`mtmc.cli.run.print_outcome`); the warnings
    went to stderr (:meth:`mtmc.cli.run.StudyOptions.run`).
    """
    unit = out["unit"]
    table = Table(
        title=f"{result.title} ({result.trials} trials, seed {result.seed})",
        caption=f"estimate: ISO 230-2's definition applied to the readings; U, interval "
        f"and mean: Monte Carlo, at p = {100 * result.p:g} %; in {unit}; GUM §8: the GUM "
        "validated by the Monte Carlo (JCGM 101 §8)",
        box=box.SIMPLE_HEAD,
    )
    for col in ("", "estimate", "U", "MC interval", "MC mean", "GUM U", "GUM §8"):
        table.add_column(col, justify="right" if col else "left", no_wrap=col != "MC interval")
    for name, p in out["parameters"].items():
        rep = p["reported"]
        lo, hi = p["interval"]
        if p["covers"].startswith("not evaluated"):
            cells = ("—", "not evaluated", "")
        elif p["U"] > 0:
            dec = _decimals(rep["U"])
            cells = (rep["U"], f"[{lo:.{dec}f}, {hi:.{dec}f}]", f"{p['mc_mean']:.{dec}f}")
        else:  # evaluated, but the interval at p is one value (said below the table)
            cells = ("0", "one value", f"{p['mc_mean']:.6g}")
        table.add_row(
            name,
            rep["estimate"],
            *cells,
            "" if p["gum"]["U"] is None else f"{p['gum']['U']:.2g}",
            {True: "yes", False: "no", None: "n/a"}[p["validated"]],
        )
    Console().print(table)
    typer.echo(out["covers"])
    for name, p in out["parameters"].items():
        if p["covers"].startswith("not evaluated") or p["U"] == 0:
            typer.echo(f"{name}: {p['covers']}")
    for note in out["notes"]:
        typer.echo(f"note: {note}")
