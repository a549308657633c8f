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

from mtmc.cli.common import (
    JSON_OPTION,
    fail,
    load_study_of_kind,
    print_json,
    print_trials_seed,
)
from mtmc.cli.positioning import parse_columns
from mtmc.cli.run import StudyOptions, print_outcome, study_command, summary_table
from mtmc.cli.run_options import run_message
from mtmc.csvtable import read_pairs
from mtmc.errors import InputError, MtmcError

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


def _measured_study(
    data: Path,
    study_file: Path | None,
    overrides: dict[str, Any],
    path: dict[str, Any],
) -> Any:
    """The ``circular`` study of a measured trace: the options over ``--study``'s file."""
    import tomlkit

    from mtmc.document import read_text
    from mtmc.study import loads_study
    from mtmc.study.circular import measured_study_text

    if study_file is None:
        if path.get("radius") is None:
            raise InputError(
                "expected --radius R (mm), or --study with [path] radius", field="radius"
            )
        text = measured_study_text(str(data.resolve()), **path, **overrides)
        return loads_study(text, file=f"{data.name} (circle evaluate)", folder=Path.cwd())
    load_study_of_kind(study_file, "circular")  # the file checked: its errors name its lines
    doc = tomlkit.parse(read_text(study_file, "study"))
    doc.pop("errors", None)  # the test's errors are identified from DATA
    doc["data"] = str(data.resolve())
    for key, value in overrides.items():
        if value is not None:
            doc[key] = value
    if "rotary" in doc:  # a rotary-axis test: its positions are the file's
        rotary = doc["rotary"]
        for key in ("start", "stop", "steps"):
            rotary.pop(key, None)
        doc.pop("directions", None)
        bad = [k for k, v in path.items() if v is not None]
        if bad:
            raise InputError(
                f"a rotary-axis test ([rotary] in {study_file}) has no --{bad[0]}", field=bad[0]
            )
        return loads_study(
            tomlkit.dumps(doc), file=str(study_file), folder=study_file.resolve().parent
        )
    for key in ("identify", "rtest"):
        doc.pop(key, None)
    table = doc.setdefault("path", tomlkit.table())
    for key in list(table):
        if key not in ("plane", "radius", "feed", "overrun"):
            del table[key]  # the programmed path is the file's
    for key, value in path.items():
        if value is not None:
            table[key] = value
    text = tomlkit.dumps(doc)
    return loads_study(text, file=str(study_file), folder=study_file.resolve().parent)


@app.command("evaluate")
@study_command
def evaluate_cmd(
    ctx: typer.Context,
    data: Path = typer.Argument(
        ...,
        help="CSV file: angle,direction,deviation per row (with --study of a rotary-axis "
        "test: angle,dx,dy,dz or angle,deviation).",
    ),
    study_file: Path | None = typer.Option(
        None,
        "--study",
        help="A circular study whose [path] radius, plane and feed, [ballbar], [conformity] "
        "and [run] apply to DATA (its [errors] are identified from DATA instead).",
    ),
    radius: float | None = typer.Option(None, "--radius", help="Nominal radius R, mm."),
    overrun: float | None = typer.Option(
        None,
        "--overrun",
        help="The overrun arc before the evaluated turn, deg (default: equal arcs at the two "
        "ends of a path longer than one turn).",
    ),
    feed: float | None = typer.Option(None, "--feed", help="Feed, mm/min (default 1000)."),
    plane: str | None = typer.Option(None, "--plane", help="XY, YZ or ZX (default XY)."),
    units: str | None = typer.Option(
        None, "--units", help="ANGLE,DEVIATION: deg,um  deg,mm  rad,um (default deg,um)."
    ),
    columns: str | None = typer.Option(
        None, "--columns", help="The file's column names: angle=Angle,deviation=Error,..."
    ),
    directions: str | None = typer.Option(
        None, "--directions", help="The file's direction words: clockwise=cw,counter=ccw."
    ),
    as_json: bool = JSON_OPTION,
    *,
    options: StudyOptions,
) -> None:
    """Evaluate DATA: F, G (LSC, MZ), H, G(b) and the identified errors, each with U."""
    try:
        overrides = {
            "units": units,
            "columns": parse_columns(columns),
            "directions": _directions(directions),
        }
        path = {"radius": radius, "plane": plane, "feed": feed, "overrun": overrun}
        if study_file is None:
            overrides = {k: v for k, v in overrides.items() if v is not None}
            path = {k: v for k, v in path.items() if v is not None or k == "radius"}
            path.setdefault("overrun", None)
        s = _measured_study(data, study_file, overrides, path)
        result = options.run(ctx, s, data.name)
    except (MtmcError, OSError) as exc:
        fail(run_message(exc))
    circ = result.extra["circular"]
    out: dict[str, Any] = {"parameters": {}, "errors": {}}
    for q in result.quantities:
        group = "parameters" if q.name in circ["symbols"] else "errors"
        out[group][q.name] = {
            "estimate": q.mc.estimate if q.gum is None else q.gum.estimate,
            "U": q.mc.U,
            "U_gum": None if q.gum is None else q.gum.U,
            "unit": q.unit,
            "validated": None if q.validation is None else q.validation.passed,
            "mc_mean": q.mc.estimate,
            **({"conformity": q.conformity} if q.conformity else {}),
        }
    out["notes"] = circ["notes"]
    out["identifiability"] = circ["identifiability"]
    out["rms"] = circ["rms_um"]
    out["trials"] = result.trials
    out["seed"] = result.seed
    _print(result, out, as_json, options)


def _print(result: Any, out: dict[str, Any], as_json: bool, options: StudyOptions) -> None:
    """What both circle commands print of their result.

    ``out`` with --json; else the table of mtmc run, the trials and seed and the notes,
    then what every study command ends with (:func:`mtmc.cli.run.print_outcome`).
    """
    if as_json:
        print_json(out)
        return
    if not options.quiet:
        Console().print(summary_table(result))  # the table of mtmc run, as the report rounds
        print_trials_seed(result.trials, result.seed)
        for note in out["notes"]:
            typer.echo(f"note: {note}")
    print_outcome(result, options.outdir, seed_line=options.quiet)


@app.command("simulate")
@study_command
def simulate_cmd(
    ctx: typer.Context,
    study: Path = typer.Argument(..., help='A circular study (kind = "circular").'),
    as_json: bool = JSON_OPTION,
    *,
    options: StudyOptions,
) -> None:
    """Simulate STUDY as mtmc run does: the parameters and the identified errors with U."""
    try:
        result = options.run(ctx, load_study_of_kind(study, "circular"), study.name)
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
    _print(result, out, as_json, options)
