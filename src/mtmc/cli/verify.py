"""``mtmc verify``: laser-tracker volumetric verification (Aguado et al. 2016, 2017).

A thin shell over :mod:`mtmc.verification`. Errors print one line and exit with status 2;
files are written atomically (:mod:`mtmc.io`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

from mtmc.cli.common import (
    EXECUTOR_OPTION,
    JSON_OPTION,
    PROGRESS_OPTION,
    SCHEDULER_OPTION,
    WORKERS_OPTION,
    fail,
    load_study_of_kind,
    parallel_options,
    print_json,
    print_trials_seed,
    progress_bar,
    seed_option,
    warn,
    with_u,
)
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


def _stats_um(r: Any, which: str) -> dict[str, dict[str, float]]:
    """Max, mean and min of one volumetric error over the points, µm (``r.ve``)."""
    out = {}
    for k in ("max", "mean", "min"):
        est, u = r.ve(f"{which}.{k}")
        out[k] = {"estimate": est * 1e3, "u": u * 1e3}
    return out


def _point_stats_um(r: Any) -> dict[str, dict[str, dict[str, float]]]:
    """``point_mean_ve_um``: max, mean, min over the points of each point's mean error."""
    return {
        which: {
            k: {"estimate": est * 1e3, "u": u * 1e3}
            for k, (est, u) in r.point_mean_ve(which).items()
        }
        for which in ("initial", "compensated")
    }


def _coef_unit(model: Any, name: str) -> tuple[str, float]:
    """File unit of a parameter: µm for lengths, µrad for angles (pose: µrad and µm)."""
    from mtmc.verification.identify import parameter_unit

    return ("urad", 1e6) if parameter_unit(model.machine, name) == "rad" else ("um", 1e3)


@app.command("simulate")
def simulate_cmd(
    study: Path = STUDY,
    trials: int | None = typer.Option(None, "--trials", "-n", min=2, help="Trials (tests)."),
    seed: int | None = seed_option("the study's run.seed, or fresh entropy"),
    points: str | None = typer.Option(None, "--points", help="A point set of the study."),
    tracker: str | None = typer.Option(None, "--tracker", help="A tracker position of the study."),
    as_json: bool = JSON_OPTION,
    workers: int = WORKERS_OPTION,
    executor: str = EXECUTOR_OPTION,
    scheduler: str | None = SCHEDULER_OPTION,
    progress: bool | None = PROGRESS_OPTION,
) -> None:
    """Monte Carlo of the whole verification: volumetric errors, coefficients, point u."""
    from mtmc.verification.visibility import study_visibility, visibility_warnings

    try:
        kind = _load(study)
        st = kind.study
        ver = _verification(study, st, points, tracker)
        warnings = visibility_warnings(
            study_visibility(st, points, [tracker or st.default_tracker]), st.machine.axes
        )
        warn(warnings)
        par = parallel_options(workers, executor, scheduler)
        m = kind.settings.trials if trials is None else trials
        s = kind.settings.seed if seed is None else seed
        with progress_bar(f"{study.name}: verifications", progress) as bar:
            r = st.simulate(m, s, points=points, tracker=tracker, progress=bar, **par)
    except MtmcError as exc:
        if exc.field == "trials" and exc.message.endswith("run fewer trials"):
            fail(f"{exc.message} (--trials N, or trials in the [run] table of {study})")
        fail(exc)
    coefs = {}
    gum_u = {}
    for i, n in enumerate(r.names):
        unit, f = _coef_unit(st.model, n)
        coefs[n] = {
            "estimate": float(r.coef_estimate[i]) * f,
            "u": float(r.coef_u[i]) * f,
            "unit": unit,
        }
        gum_u[n] = {"u": float(r.gum.u[i]) * f, "unit": unit}
    out: dict[str, Any] = {
        "trials": r.trials,
        "seed": r.seed,
        "points": ver.n_points,
        "point_set": points or st.default_points,
        "tracker": tracker or st.default_tracker,
        "initial_ve_um": _stats_um(r, "initial"),
        "residual_ve_um": _stats_um(r, "residual"),
        "compensated_ve_um": _stats_um(r, "compensated"),
        "point_mean_ve_um": _point_stats_um(r),
        "coefficients": coefs,
        "gum": gum_u,
        "point_u_um": {"max": float(r.point_u.max()) * 1e3, "mean": float(r.point_u.mean()) * 1e3},
        "point_u_gum_um": {
            "max": float(r.gum.point_u.max()) * 1e3,
            "mean": float(r.gum.point_u.mean()) * 1e3,
        },
        "warnings": warnings,
    }
    if as_json:
        print_json(out)
        return
    typer.echo(
        f"{r.trials} verifications (seed {r.seed}), {ver.n_points} points "
        f"({out['point_set']}), tracker {out['tracker']}"
    )
    typer.echo(
        "volumetric error over the points, µm: Monte Carlo mean (u: its standard "
        "uncertainty, k = 1, to two digits, JCGM 100 §7.2.6)"
    )
    for key, label in (
        ("initial_ve_um", "initial"),
        ("residual_ve_um", "residual (eq. 17)"),
        ("compensated_ve_um", "after compensation"),
    ):
        d = out[key]
        typer.echo(
            f"{label:>18}: "
            + ", ".join(
                f"{s} {with_u(d[s]['estimate'], d[s]['u'])}" for s in ("max", "mean", "min")
            )
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
    from mtmc.uncertainty.tolerance import round_to_uncertainty

    mx, mean = (round_to_uncertainty(pu[k], pu[k])[1] for k in ("max", "mean"))
    typer.echo(f"calibration u per point: max {mx} µm, mean {mean} µm (MC)")


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
    ini, res = r.initial_stats()[0] * 1e3, r.residual_stats()[0] * 1e3
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
    workers: int = WORKERS_OPTION,
    executor: str = EXECUTOR_OPTION,
    scheduler: str | None = SCHEDULER_OPTION,
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
        r = place(
            ver,
            st.limits,
            references=st.trackers,
            n_xy=grid,
            refine=refine,
            trials=trials,
            seed=used_seed,
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
            "u_um": r.u_best * 1e3,
            "u_mc_um": None if r.u_best_mc is None else r.u_best_mc * 1e3,
        },
        "reference": {n: {"u_um": u * 1e3} for n, u in r.reference.items()},
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
