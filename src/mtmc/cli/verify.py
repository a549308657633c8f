"""``mtmc verify``: laser-tracker volumetric verification (Aguado et al. 2016, 2017).

A thin shell over :mod:`mtmc.verification`. Errors print one line and exit with status 2;
files are written atomically (:mod:`mtmc.io`).
"""

from __future__ import annotations

from pathlib import Path

import typer

from mtmc.cli.common import fail, print_json
from mtmc.errors import MtmcError

app = typer.Typer(
    help="Laser-tracker volumetric verification: plan the points and the NC program.",
    no_args_is_help=True,
)

STUDY = typer.Argument(..., help="The verification study (TOML).")
JSON_OPTION = typer.Option(False, "--json", help="Print one JSON object.")


@app.command("plan")
def plan_cmd(
    study: Path = STUDY,
    out: Path = typer.Option(
        Path("."), "-o", "--outdir", help="Folder for the NC programs and the points table."
    ),
    as_json: bool = JSON_OPTION,
) -> None:
    """Discretise the workspace, write the NC programs and estimate the measuring time."""
    from mtmc.verification.ncprogram import estimate_time, load_plan_study, write_programs

    try:
        plan, nc = load_plan_study(study)
        estimate = estimate_time(plan, nc)
    except MtmcError as exc:
        fail(exc)
    if not out.is_dir():
        fail(f"{out}: the output folder does not exist")
    try:
        files = write_programs(plan, nc, out)
    except OSError as exc:
        fail(f"{out}: cannot write: {exc.strerror or exc}")
    if as_json:
        print_json(
            {
                "axes": list(plan.axes),
                "distribution": plan.kind,
                "points": plan.n_points,
                "offsets": plan.n_offsets,
                "measurements": plan.n_measurements,
                "moves": int(plan.moves.shape[0]),
                "seed": plan.seed,
                "files": {k: str(v) for k, v in files.items()},
                "time": estimate.to_dict(),
            }
        )
        return
    t = estimate
    typer.echo(
        f"{plan.n_points} points ({plan.kind}, axes {' '.join(plan.axes)}) x {plan.n_offsets} "
        f"offsets = {plan.n_measurements} measurements, {plan.moves.shape[0]} moves"
    )
    typer.echo(
        f"time: dwell {t.dwell_s / 60.0:.1f} min + travel {t.travel_s / 60.0:.1f} min "
        f"({t.model} model, path {t.path_length_mm / 1000.0:.1f} m) = {t.total_s / 3600.0:.2f} h"
        + (f", plus {t.stops} reflector changes" if t.stops else "")
    )
    for kind, path in files.items():
        typer.echo(f"{kind}: {path}")
