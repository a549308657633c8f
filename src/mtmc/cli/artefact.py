"""``mtmc artefact``: simulate a fiducial-artefact study, fit a ball to probed points.

A thin shell over :mod:`mtmc.artefact` (Wang, Cheung and Kong 2022). Errors print one
line (``mtmc: error: FILE:LINE: field F: ...``) and exit with status 2; figures are
written atomically.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import typer
from rich.console import Console
from rich.table import Table

from mtmc.cli.common import fail, load_study_of_kind, print_json, with_u
from mtmc.cli.run import StudyOptions, print_outcome, study_command
from mtmc.cli.run_options import run_message
from mtmc.errors import InputError, MtmcError

app = typer.Typer(
    rich_markup_mode=None,
    help="Fiducial artefacts (Wang, Cheung and Kong 2022): simulate a study, fit probed balls.",
    no_args_is_help=True,
)

FIG_SUFFIXES = (".svg", ".png", ".pdf")


def _check_options(
    figure: Path | None, adaptive_and_trials: bool, noise: str, outdir: Path | None, no_gum: bool
) -> None:
    """Refuse the options of ``artefact simulate`` that do not go together (one line)."""
    if figure is not None and figure.suffix.lower() not in FIG_SUFFIXES:
        fail(f"{figure}: expected a file ending in {', '.join(FIG_SUFFIXES)}")
    if adaptive_and_trials:
        fail("--adaptive chooses the number of trials itself (JCGM 101 §7.9); not with --trials")
    if noise not in ("points", "centres"):
        fail(f"--noise: expected points or centres, got {noise!r}")
    if outdir is not None and (no_gum or noise != "points"):
        fail(
            "-o writes the study as its file gives it, which runs the GUM and draws every "
            "probed point's noise: not with --no-gum or --noise centres"
        )


@app.command("simulate")
@study_command
def simulate_cmd(
    ctx: typer.Context,
    study: Path = typer.Argument(..., help="Artefact study file (.toml)."),
    figure: Path | None = typer.Option(
        None, "--figure", help="Write the error-vector plot (Fig. 7) here: .svg, .png, .pdf."
    ),
    magnification: float = typer.Option(
        10_000.0, "--magnification", min=1.0, help="Factor the error vectors are drawn at."
    ),
    no_gum: bool = typer.Option(False, "--no-gum", help="Skip the GUM beside the Monte Carlo."),
    noise: str = typer.Option(
        "points",
        "--noise",
        help="points: draw every probed coordinate's noise; centres: each fit's centre "
        "noise from its covariance (same Gaussian law, 30 times fewer draws).",
    ),
    as_json: bool = typer.Option(
        False, "--json", help="Print one JSON object (lengths in µm, as its unit says)."
    ),
    *,
    options: StudyOptions,
) -> None:
    """Simulate STUDY: probe, identify setup errors, Table 2 and 3 with uncertainties.

    The study runs as mtmc run runs it; with -o its result folder and report are written.
    """
    outdir = options.outdir
    _check_options(figure, options.adaptive and options.trials is not None, noise, outdir, no_gum)
    simulated: list[Any] = []
    try:
        kind = load_study_of_kind(study, "artefact")  # the study as ``mtmc run`` reads it
        kind = dataclasses.replace(kind, noise=noise, gum=not no_gum, on_simulated=simulated.append)
        result = options.run(ctx, kind, study.name)
        res = simulated[0]
        if figure is not None:
            from mtmc.artefact.plot import plot_error_vectors

            try:
                plot_error_vectors(res, figure, magnification=magnification)
            except OSError as exc:
                fail(f"{figure}: cannot write: {exc}")
    except MtmcError as exc:
        fail(run_message(exc))
    except OSError as exc:
        fail(f"{outdir}: cannot write: {exc.strerror or exc}")
    st = kind.study
    run = result.extra["run"]
    out = res.to_json()
    if as_json:
        output = None if outdir is None else str(outdir)
        print_json(
            out
            | {
                "unit": "µm",
                "omitted": run["omitted"],
                "adaptive": run["adaptive"],
                "run": run,
                "output": output,
            }
        )
        return
    if options.quiet:
        print_outcome(result, outdir, seed_line=True)
        return
    con = Console()
    t = Table(
        title=f"{st.title}: errors of the fiducial distances (µm), Table 2 layout; "
        "① measured, ② model; Monte Carlo mean (u: its standard uncertainty)"
    )
    axes = [a.lower() for a in st.setup.rotary]
    for a in axes:
        t.add_column(a, justify="right")
    for col in ("① r_max", "① r_avg", "② r_max", "② r_avg", "①–② r_max", "①–② r_avg"):
        t.add_column(col, justify="right")
    for row in out["poses"]:
        m1, a1 = row["r_max_um"], row["r_avg_um"]
        m2, a2 = row["r_max_model_um"], row["r_avg_model_um"]
        t.add_row(
            *(f"{row[f'{a}_deg']:g}°" for a in axes),
            with_u(m1["estimate"], m1["u"]),
            with_u(a1["estimate"], a1["u"]),
            with_u(m2["estimate"], m2["u"]),
            with_u(a2["estimate"], a2["u"]),
            f"{m1['estimate'] - m2['estimate']:.2f}",
            f"{a1['estimate'] - a2['estimate']:.2f}",
        )
    con.print(t)
    s = Table(title="Setup errors (µm): injected, identified (noise-free), MC mean (u), GUM u")
    for col in ("name", "injected", "noise-free", "MC", "GUM u"):
        s.add_column(col, justify="right")
    for name, v in out["setup_errors"].items():
        s.add_row(
            name,
            f"{v['injected']:.3f}",
            f"{v['noise_free']:.3f}",
            with_u(v["estimate"], v["u"]),
            f"{v['gum_u']:.3f}" if "gum_u" in v else "-",
        )
    con.print(s)
    typer.echo(
        f"mean volumetric error {out['volumetric_mean_um']:.2f} µm; "
        f"trials {out['trials']}  seed {out['seed']}"
    )
    print_outcome(result, outdir, seed_line=False)


@app.command("fit")
def fit_cmd(
    points: Path = typer.Argument(..., help="CSV of probed points x,y,z (header optional)."),
    radius: float | None = typer.Option(
        None, "--radius", help="Calibrated radius, in --units (default: fitted)."
    ),
    units: str = typer.Option("mm", "--units", help="Unit of the file and --radius: mm, m or um."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object (mm)."),
) -> None:
    """Fit a sphere to POINTS (orthogonal distances), with standard uncertainties."""
    from mtmc.artefact.probing import UNITS, fit_points, load_points

    if units not in UNITS:
        fail(f"--units: expected mm, m or um, got {units!r}")
    if radius is not None and not radius > 0:
        fail(f"--radius: expected a radius > 0, got {radius}")
    try:
        P = load_points(points, units)
        f = fit_points(P, None if radius is None else radius * UNITS[units])
    except MtmcError as exc:
        fail(exc)
    u_all = (*f.u_centre, f.u_radius)
    if not all(math.isfinite(v) for v in u_all):
        k = 3 if f.radius_known else 4
        fail(
            InputError(
                f"{f.n} points leave no residual to give the fit's uncertainty ({k} parameters): "
                f"probe at least {k + 1} points"
                + ("" if f.radius_known else ", or give the calibrated radius (--radius)"),
                file=str(points),
            )
        )
    if as_json:
        print_json(
            {
                "centre": list(f.centre),
                "radius": f.radius,
                "u_centre": list(f.u_centre),
                "u_radius": f.u_radius,
                "rms": f.rms,
                "n": f.n,
                "units": "mm",
                "radius_known": f.radius_known,
            }
        )
        return
    c, u = f.centre, f.u_centre
    typer.echo(f"{points.name}: {f.n} points, sphere fit (orthogonal distances), mm")
    typer.echo(f"centre  {c[0]:.6f} {c[1]:.6f} {c[2]:.6f}   u {u[0]:.2e} {u[1]:.2e} {u[2]:.2e}")
    known = " (given)" if f.radius_known else f"   u {f.u_radius:.2e}"
    typer.echo(f"radius  {f.radius:.6f}{known}")
    typer.echo(f"rms     {f.rms:.3e}")


@app.command("gravity")
def gravity_cmd(
    measurements: Path = typer.Argument(
        ..., help="CSV with the header orientation,ball,x,y,z (H, O, V; mm)."
    ),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object (µm)."),
) -> None:
    """The gravity effect between mountings (eqs. 1-2): O-H and V-H per ball and mean."""
    from mtmc.artefact.gravity import load_gravity

    try:
        g = load_gravity(measurements)
    except MtmcError as exc:
        fail(exc)
    out: dict[str, dict[str, Any]] = {
        f"{o}-H": {
            "balls": {
                b: {
                    "dx_um": float(g.delta[k, i, 0] * 1e3),
                    "dy_um": float(g.delta[k, i, 1] * 1e3),
                    "dz_um": float(g.delta[k, i, 2] * 1e3),
                    "dd_um": float(g.delta_d[k, i] * 1e3),
                }
                for i, b in enumerate(g.balls)
            },
            "mean_abs_dx_um": float(g.mean_abs[k, 0] * 1e3),
            "mean_abs_dy_um": float(g.mean_abs[k, 1] * 1e3),
            "mean_abs_dz_um": float(g.mean_abs[k, 2] * 1e3),
            "mean_dd_um": float(g.mean_d[k] * 1e3),
        }
        for k, o in enumerate(g.orientations)
    }
    if as_json:
        print_json(out)
        return
    con = Console()
    for key, v in out.items():
        t = Table(title=f"{key} (µm), eqs. 1-2")
        for col in ("ball", "Δx", "Δy", "Δz", "Δd"):
            t.add_column(col, justify="right")
        for b, d in v["balls"].items():
            t.add_row(b, *(f"{d[c]:.3f}" for c in ("dx_um", "dy_um", "dz_um", "dd_um")))
        t.add_row(
            "mean |.|",
            *(f"{v[c]:.3f}" for c in ("mean_abs_dx_um", "mean_abs_dy_um", "mean_abs_dz_um")),
            f"{v['mean_dd_um']:.3f}",
        )
        con.print(t)
