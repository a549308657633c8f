"""``mtmc verify``: laser-tracker volumetric verification (Aguado et al. 2016, 2017).

A thin shell over :mod:`mtmc.verification`. Errors print one line and exit with status 2;
files are written atomically (:mod:`mtmc.io`).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import typer

from mtmc.cli.common import (
    EXECUTOR_OPTION,
    JSON_OPTION,
    PLOTS_OPTION,
    PROGRESS_OPTION,
    QUIET_OPTION,
    RESULT_OPTION,
    SCHEDULER_OPTION,
    WORKERS_OPTION,
    fail,
    load_study_of_kind,
    parallel_options,
    plots_value,
    print_json,
    print_trials_seed,
    progress_bar,
    progress_flag,
    seed_option,
    warn,
    with_u,
)
from mtmc.cli.run import command_line, print_outcome, run_study
from mtmc.errors import MtmcError

app = typer.Typer(
    rich_markup_mode=None,
    help="Laser-tracker volumetric verification: plan, simulate, identify, place.",
    no_args_is_help=True,
)

STUDY = typer.Argument(..., help="The verification study (TOML).")


def _load(path: Path) -> Any:
    """The study of ``path`` as ``mtmc run`` reads it; it must be a verification study."""
    return load_study_of_kind(path, "verification")


def _verification(path: Path, st: Any, points: str | None, tracker: str | None) -> Any:
    """The study's verification of ``--points`` and ``--tracker``.

    An unknown point set or tracker position is refused naming the study file and the
    option.
    """
    from mtmc.errors import InputError

    try:
        return st.verification(points, tracker)
    except InputError as exc:
        if exc.file is not None or exc.field not in ("points", "tracker"):
            raise
        raise InputError(exc.message, file=str(path), field=f"--{exc.field}") from None


@app.command("plan")
def plan_cmd(
    study: Path = STUDY,
    out: Path = typer.Option(
        Path("."),
        "-o",
        "--output",
        help="Folder for the NC programs and the points table; created with its parents.",
    ),
    as_json: bool = JSON_OPTION,
) -> None:
    """Discretise the workspace, write the NC programs and estimate the measuring time."""
    from mtmc.verification.ncprogram import estimate_time, load_plan_study, write_programs
    from mtmc.verification.visibility import load_plan_visibility

    try:
        plan, nc = load_plan_study(study)
        estimate = estimate_time(plan, nc)
        vis = load_plan_visibility(study, plan)
    except MtmcError as exc:
        fail(exc)
    try:
        out.mkdir(parents=True, exist_ok=True)
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
                "visibility": None
                if vis is None
                else {
                    name: {
                        "ok": v.ok,
                        "points": list(v.names),
                        "failures": v.failures(plan.axes),
                    }
                    for name, v in vis.items()
                },
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
    if vis is None:
        typer.echo("visibility: no [tracker.positions] in the study, not checked")
    else:
        typer.echo("visibility of the limit points (Aguado et al. 2016 eqs. 19-21):")
        for v in vis.values():
            typer.echo("  " + v.text(plan.axes).replace("\n", "\n  "))


def _coef_unit(model: Any, name: str) -> tuple[str, float]:
    """The unit of a parameter and its factor from the code's mm or rad (µm, µrad)."""
    from mtmc.study.verification import file_unit
    from mtmc.verification.identify import parameter_unit

    return file_unit(parameter_unit(model.machine, name))


def _in_um(value: Any) -> Any:
    """A length of the code's mm in the µm a verification study writes (``file_unit``)."""
    from mtmc.study.verification import file_unit

    return value * file_unit("mm")[1]


def _statement(q: Any) -> dict[str, Any]:
    """One volumetric-error statistic of the result: y, U (k, p) and u, in its unit."""
    mc = q.mc
    return {
        "estimate": mc.estimate,
        "U": mc.U,
        "k": mc.k,
        "p": mc.p,
        "u": mc.u,
        "unit": q.unit,
        "reported": q.reported.to_dict(),
    }


def simulate_record(result: Any, outdir: Path | None) -> dict[str, Any]:
    """The ``--json`` object of ``verify simulate``, every number the result's (µm, µrad)."""
    from mtmc.verification.simulate import VE_NAMES

    extra = result.extra["verification"]
    out: dict[str, Any] = {
        "unit": "µm",
        "trials": result.trials,
        "seed": result.seed,
        "p": result.p,
        "points": extra["points"],
        "point_set": extra["point_set"],
        "tracker": extra["tracker"],
    }
    for which in ("initial", "residual", "compensated"):
        out[f"{which}_ve_um"] = {
            name.split(".")[1]: _statement(result.quantity(f"volumetric_error.{name}"))
            for name in VE_NAMES
            if name.startswith(f"{which}.")
        }
    out["point_mean_ve_um"] = extra["point_mean_ve_um"]
    coefs, gum_u = {}, {}
    table = next(t for t in result.tables if t.name == "coefficients")
    for name, unit, _free, est, u, u_gum in table.rows:
        coefs[name] = {"estimate": est, "u": u, "unit": unit}
        gum_u[name] = {"u": u_gum, "unit": unit}
    out["coefficients"] = coefs
    out["gum"] = gum_u
    values = next(f for f in result.fields if f.name == "calibration_u").values
    out["point_u_um"] = {"max": float(values.max()), "mean": float(values.mean())}
    out["point_u_gum_um"] = extra["point_u_gum_um"]
    out["warnings"] = result.warnings
    out["run"] = result.extra.get("run")
    out["output"] = None if outdir is None else str(outdir)
    return out


def _print_simulated(out: dict[str, Any]) -> None:
    """The text of ``verify simulate``: U (k, p) with u beside it, in µm."""
    from mtmc.uncertainty.tolerance import round_to_uncertainty

    typer.echo(
        f"{out['trials']} verifications (seed {out['seed']}), {out['points']} points "
        f"({out['point_set']}), tracker {out['tracker']}"
    )
    typer.echo(
        f"volumetric error over the points, µm: y, U (k, p = {100 * out['p']:g} %) "
        "and u (standard uncertainty, JCGM 100 §7.2.6)"
    )
    for which, label in (
        ("initial", "initial"),
        ("residual", "residual (eq. 17)"),
        ("compensated", "after compensation"),
    ):
        for stat, d in out[f"{which}_ve_um"].items():
            k = "" if d["k"] is None else f" (k = {d['k']:.3f})"
            u = round_to_uncertainty(d["u"], d["u"])[1] if d["u"] > 0 else f"{d['u']:g}"
            typer.echo(
                f"{label:>18} {stat:<4}: {d['reported']['estimate']}  "
                f"U = {d['reported']['U']}{k}  u = {u}"
            )
    typer.echo(
        "each point's error averaged over the verifications, µm: max, mean, min over the "
        "points (u: the spread of one verification there)"
    )
    for which, label in (("initial", "initial"), ("compensated", "after compensation")):
        d = out["point_mean_ve_um"][which]
        typer.echo(
            f"{label:>18}: "
            + ", ".join(
                f"{s} {with_u(d[s]['estimate'], d[s]['u'])}" for s in ("max", "mean", "min")
            )
        )
    pu = out["point_u_um"]
    mx, mean = (round_to_uncertainty(pu[k], pu[k])[1] for k in ("max", "mean"))
    typer.echo(f"calibration u per point: max {mx} µm, mean {mean} µm (MC)")


@app.command("simulate")
def simulate_cmd(
    ctx: typer.Context,
    study: Path = STUDY,
    trials: int | None = typer.Option(None, "--trials", "-n", min=2, help="Trials (tests)."),
    seed: int | None = seed_option("the study's run.seed, or fresh entropy"),
    points: str | None = typer.Option(None, "--points", help="A point set of the study."),
    tracker: str | None = typer.Option(None, "--tracker", help="A tracker position of the study."),
    outdir: Path | None = RESULT_OPTION,
    as_json: bool = typer.Option(
        False, "--json", help="Print one JSON object (lengths in µm, angles in µrad, as it says)."
    ),
    quiet: bool = QUIET_OPTION,
    workers: int = WORKERS_OPTION,
    executor: str = EXECUTOR_OPTION,
    scheduler: str | None = SCHEDULER_OPTION,
    progress: bool | None = PROGRESS_OPTION,
    plots: str | None = PLOTS_OPTION,
) -> None:
    """Monte Carlo of the whole verification: volumetric errors, coefficients, point u.

    The study runs as mtmc run runs it; with -o its result folder and report are written.
    """
    plotted = plots_value(plots)
    if outdir is not None and (points is not None or tracker is not None):
        fail(
            "-o writes the study as its file gives it, which simulates its default point "
            "set and tracker position: not with --points or --tracker"
        )
    try:
        kind = _load(study)
        _verification(study, kind.study, points, tracker)
        kind = dataclasses.replace(kind, points=points, tracker=tracker)
        result = run_study(
            kind,
            outdir,
            label=f"{study.name}: verifications",
            trials=trials,
            seed=seed,
            progress=progress_flag(progress, quiet),
            argv=command_line(ctx),
            parallel=parallel_options(workers, executor, scheduler),
            plotted=plotted,
        )
    except MtmcError as exc:
        if exc.field == "trials" and exc.message.endswith("run fewer trials"):
            fail(f"{exc.message} (--trials N, or trials in the [run] table of {study})")
        fail(exc)
    except OSError as exc:
        fail(f"{outdir}: cannot write: {exc.strerror or exc}")
    out = simulate_record(result, outdir)
    warn(out["warnings"])
    if as_json:
        print_json(out)
        return
    if not quiet:
        _print_simulated(out)
    print_outcome(result, outdir, seed_line=True)


def _check_identified(r: Any, data: Path) -> None:
    """Refuse an identification that did not converge or gives non-finite numbers."""
    import numpy as np

    from mtmc.errors import ConvergenceError

    check = (
        "check that the readings are in mm and in the tracker's frame, that the axis columns "
        "match the study's axes, and the tracker position (--tracker)"
    )
    if not bool(r.converged[0]):
        raise ConvergenceError(
            f"the identification did not converge ({r.messages()[0]} after "
            f"{int(r.iterations[0])} iterations): {check}",
            file=str(data),
        )
    values = (r.estimate[0], r.u[0], r.initial_ve[0], r.residual_ve[0])
    if not all(np.all(np.isfinite(v)) for v in values):
        raise ConvergenceError(
            f"the identification gives non-finite coefficients, uncertainties or volumetric "
            f"errors: {check}",
            file=str(data),
        )


@app.command("identify")
def identify_cmd(
    data: Path = typer.Argument(
        ..., help="CSV: axis positions and tracker-frame coordinates or lengths per station (mm)."
    ),
    study: Path = typer.Option(..., "--study", help="The verification study (TOML)."),
    tracker: str | None = typer.Option(None, "--tracker", help="Nominal tracker position."),
    as_json: bool = JSON_OPTION,
    export: str | None = typer.Option(None, "--export", help="isg, etalon or csv."),
    out: Path | None = typer.Option(None, "-o", "--output", help="The compensation file."),
    self_cal: bool = typer.Option(
        False,
        "--self-calibrate",
        help="Lengths per station: find the four or more stations' positions from the "
        "lengths too (the study's positions only start the iteration); the tracker pose "
        "is then identified.",
    ),
) -> None:
    """Identify the error functions (and the tracker pose) from measured data."""
    from mtmc.verification.compensation import (
        compensation_table,
        dump_compensation,
        measured_grid,
    )

    if (export is None) != (out is None):
        fail("--export and -o go together")
    if export is not None and export not in ("isg", "etalon", "csv"):
        fail(f"--export: expected isg, etalon or csv, got {export!r}")
    try:
        st = _load(study).study
        ver = _verification(study, st, None, tracker)
        from mtmc.verification.datafile import load_identification_csv, measured_points
        from mtmc.verification.identify import identify

        d = load_identification_csv(data, st.machine.axes, st.trackers)
        q = d.q
        meas, lt = measured_points(
            d, st.machine, st.trackers, ver.tracker, self_calibrated=self_cal
        )
        r = identify(st.model, q, meas, lt, pose=st.pose or self_cal, fixed=st.fixed)
        _check_identified(r, data)
        if export is not None and out is not None:
            table = compensation_table(st.model, measured_grid(st.model, q), theta=r.theta[0])
            dump_compensation(table, out, export)
    except MtmcError as exc:
        fail(exc)
    except OSError as exc:
        fail(f"{out}: cannot write: {exc.strerror or exc}")
    u = r.u[0]
    coefs: dict[str, dict[str, Any]] = {}
    for i, n in enumerate(r.names):
        unit, f = _coef_unit(st.model, n)
        coefs[n] = {"estimate": float(r.estimate[0, i]) * f, "u": float(u[i]) * f, "unit": unit}
    ini, res = _in_um(r.initial_stats()[0]), _in_um(r.residual_stats()[0])
    result = {
        "points": int(q.shape[0]),
        "data": d.kind,
        "stations": list(d.stations),
        "self_calibrated": self_cal,
        "status": r.messages()[0],
        "converged": bool(r.converged[0]),
        "iterations": int(r.iterations[0]),
        "initial_ve_um": dict(zip(("max", "mean", "min"), map(float, ini), strict=True)),
        "residual_ve_um": dict(zip(("max", "mean", "min"), map(float, res), strict=True)),
        "coefficients": coefs,
        "identifiability": r.identifiability.text(),
        "export": None if out is None else str(out),
    }
    if as_json:
        print_json(result)
        return
    typer.echo(f"{q.shape[0]} points: {result['status']} after {result['iterations']} iterations")
    if d.kind == "lengths":
        how = "self-calibrated from the lengths" if self_cal else "as the study places them"
        typer.echo(f"points from the lengths of {len(d.stations)} stations, positions {how}")
    typer.echo(
        f"VE µm: initial max {ini[0]:.2f} mean {ini[1]:.2f} min {ini[2]:.2f}; "
        f"residual max {res[0]:.2f} mean {res[1]:.2f} min {res[2]:.2f}"
    )
    for n, c in coefs.items():
        typer.echo(f"  {n:>10} = {with_u(c['estimate'], c['u'])} {c['unit']}")
    if out is not None:
        typer.echo(f"compensation ({export}): {out}")


@app.command("place")
def place_cmd(
    study: Path = STUDY,
    points: str | None = typer.Option(None, "--points", help="A point set of the study."),
    trials: int = typer.Option(200, "--trials", "-n", min=0, help="MC trials confirming the best."),
    seed: int | None = seed_option("the study's run.seed, or fresh entropy"),
    grid: int = typer.Option(11, "--grid", min=2, help="Candidates per horizontal axis."),
    refine: int = typer.Option(300, "--refine", min=0, help="Evaluations of the refinement."),
    as_json: bool = JSON_OPTION,
    quiet: bool = QUIET_OPTION,
    workers: int = WORKERS_OPTION,
    executor: str = EXECUTOR_OPTION,
    scheduler: str | None = SCHEDULER_OPTION,
    progress: bool | None = PROGRESS_OPTION,
) -> None:
    """Search the tracker position with the smallest mean calibration uncertainty."""
    import math

    from mtmc.uncertainty.sampling import resolve_seed
    from mtmc.verification.placement import place
    from mtmc.verification.visibility import study_visibility, visibility_warnings

    try:
        kind = _load(study)
        st = kind.study
        if st.limits is None:
            fail(f"{study}: placement needs [tracker.limits] with height_mm")
        ver = _verification(study, st, points, None)
        warnings = visibility_warnings(study_visibility(st, points), st.machine.axes)
        warn(warnings)
        used_seed = resolve_seed(kind.settings.seed if seed is None else seed)
        with progress_bar(
            f"{study.name}: placement", progress_flag(progress, quiet), unit="steps"
        ) as bar:
            r = place(
                ver,
                st.limits,
                references=st.trackers,
                n_xy=grid,
                refine=refine,
                trials=trials,
                seed=used_seed,
                progress=bar,
                **parallel_options(workers, executor, scheduler),
            )
    except MtmcError as exc:
        fail(exc)
    p = r.best.position
    out: dict[str, Any] = {
        "best": {
            "unit": "mm",
            "x": float(p[0]),
            "y": float(p[1]),
            "z": float(p[2]),
            "euler": st.euler,
            "euler_deg": [math.degrees(a) for a in r.best.euler(st.euler)],
            "u_um": _in_um(r.u_best),
            "u_mc_um": None if r.u_best_mc is None else _in_um(r.u_best_mc),
        },
        "reference": {n: {"u_um": _in_um(u)} for n, u in r.reference.items()},
        "candidates": r.candidates,
        "rejected": r.rejected,
        "trials": trials,
        "seed": used_seed,
        "warnings": warnings,
    }
    if as_json:
        print_json(out)
        return
    b = out["best"]
    if quiet:
        print_trials_seed(trials, used_seed)
        return
    typer.echo(
        f"best of {r.candidates} candidates ({r.rejected} out of the limits): "
        f"({b['x']:.0f}, {b['y']:.0f}, {b['z']:.0f}) mm, Euler {b['euler']} "
        f"({', '.join(f'{a:.1f}' for a in b['euler_deg'])}) deg: mean point u "
        f"{b['u_um']:.2f} µm (GUM)"
        + ("" if b["u_mc_um"] is None else f", {b['u_mc_um']:.2f} µm (MC)")
    )
    for n, v in out["reference"].items():
        typer.echo(f"  {n}: {v['u_um']:.2f} µm")
    print_trials_seed(trials, used_seed)
