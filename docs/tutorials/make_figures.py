"""The figures and the numbers of the tutorials, from runs of the shipped studies.

Run from the repository root::

    python docs/tutorials/make_figures.py                 # every tutorial
    python docs/tutorials/make_figures.py stryczek        # one (stryczek, aguado2017, ...)
    python docs/tutorials/make_figures.py --check         # the tutorials' tables are current?

For each tutorial it runs the shipped studies of ``examples/studies`` at the seed and
trial counts stated in the tutorial, and writes

- ``docs/tutorials/figures/NAME_*.png``: our figures, one per figure of the paper;
- ``docs/tutorials/numbers/NAME.json``: every number the tutorial quotes, with the spread
  over the trials of the statistic it is the mean of (``sd``) and the trials (``n``), so
  that a run at fewer trials can be compared within its Monte Carlo tolerance;
- the tables of ``docs/tutorials/NAME.md`` between ``<!-- generated: KEY -->`` and
  ``<!-- end generated -->``: the paper's printed numbers (read from its text, in this
  file) beside ours (from the JSON). No number of our side is typed by hand.

``tests/test_tutorials.py`` reruns each case at a few trials and checks the JSON and the
tables against it.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import re
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
STUDIES = ROOT / "examples" / "studies"
FIGURES = HERE / "figures"
NUMBERS = HERE / "numbers"

Numbers = dict[str, Any]


# ---------------------------------------------------------------------------- helpers


def mc(value: float, sd: float, n: int) -> dict[str, float]:
    """A Monte Carlo number: the mean over ``n`` trials of a statistic whose spread is ``sd``."""
    return {"value": float(value), "sd": float(sd), "n": int(n)}


#: The relative tolerance of a rerun at the same trials of a number whose route has no
#: ill-conditioned step: our seeded draws (bit-identical on every machine), our reductions,
#: NumPy's elementwise functions (their SIMD loops differ between CPUs by an ulp or two) and
#: well-conditioned LAPACK calls. Measured across the OpenBLAS kernels SkylakeX, Haswell and
#: Zen, such numbers differ by at most 1.2e-13 relative; 1e-9 leaves room for any other CPU.
RTOL = 1e-9

#: The unit roundoff of binary64.
EPS = float(np.finfo(np.float64).eps)


def exact(value: float, tol: float | None = None, why: str | None = None) -> dict[str, Any]:
    """A number that does not depend on the trials (noise-free, or a closed form).

    ``tol`` (with its reason ``why``) is the absolute tolerance of a number whose route
    amplifies rounding (a central difference, an ill-conditioned fit): BLAS kernels sum in
    different orders, so such a number is reproducible to its conditioning, not to the bit.
    """
    out: dict[str, Any] = {"value": float(value)}
    if tol is not None:
        if not why:
            raise ValueError("a tolerance needs its reason")
        out["tol"] = float(tol)
        out["why"] = why
    return out


def tolerance(doc: Mapping[str, Any], run: Mapping[str, Any]) -> float:
    """How far a rerun may lie from a documented number.

    :data:`RTOL` relative, or the number's own ``tol`` (from its conditioning) where it is
    larger; plus, for a Monte Carlo number rerun at other trials, 5 standard errors of both.
    """
    tol = max(RTOL * max(1.0, abs(doc["value"])), float(doc.get("tol", 0.0)))
    if "sd" not in doc or doc["n"] == run["n"]:
        return tol
    se = doc["sd"] * math.sqrt(1.0 / doc["n"] + 1.0 / run["n"])
    return 5.0 * se + tol


def v(numbers: Numbers, key: str) -> float:
    """The value of a number of the JSON."""
    return float(numbers["values"][key]["value"])


def fmt(x: float, nd: int = 1) -> str:
    """A number for a table (``—`` for NaN)."""
    return "—" if not math.isfinite(x) else f"{x:.{nd}f}"


def table(header: list[str], rows: list[list[str]]) -> str:
    """A Markdown table."""
    out = [
        "| " + " | ".join(header) + " |",
        "|" + "|".join(" --- " for _ in header) + "|",
    ]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(out)


def new_figure(w: float, h: float) -> Any:
    """A Matplotlib figure without pyplot's global state."""
    from matplotlib.figure import Figure

    return Figure(figsize=(w, h), dpi=90)


def save(fig: Any, out: Path, name: str) -> Path:
    """Write ``fig`` as ``out/name`` (PNG, no time stamp)."""
    out.mkdir(parents=True, exist_ok=True)
    path = out / name
    fig.savefig(path, format="png", metadata={"Software": None})
    return path


def load(name: str) -> Any:
    """A shipped study."""
    import mtmc

    return mtmc.load_study(STUDIES / f"{name}.toml")


# ---------------------------------------------------------------------------- Stryczek


def stryczek(scale: float = 1.0) -> tuple[Numbers, dict[str, Any]]:
    """Stryczek: Fig. 4, Fig. 1 (a probed ball centre) and Fig. 14-15 (the sweep, eq. 31).

    Fig. 4 is a sum of two normals; Fig. 14-15 u of the A-C distance over sigma_p x sigma_m.
    Returns the numbers (JSON-ready) and the data of the figures.
    """
    import mtmc

    values: dict[str, Any] = {}
    data: dict[str, Any] = {}

    # Fig. 4: X1 + X2, X1 ~ N(0, 1), X2 ~ N(0.5, 0.5), 3000 samples as the paper
    n4 = max(200, int(3000 * scale))
    r4 = mtmc.monte_carlo(
        mtmc.expression("X1 + X2"),
        {"X1": "normal(0, 1)", "X2": "normal(0.5, 0.5)"},
        trials=n4,
        seed=4,
        keep=True,
    )
    values["fig4.mean"] = mc(r4.estimate, r4.u, n4)
    values["fig4.u"] = mc(r4.u, r4.u / math.sqrt(2.0), n4)
    values["fig4.u_exact"] = exact(math.sqrt(1.0 + 0.25))
    # the 95 % probabilistically symmetric interval (JCGM 101 §7.7), as Stryczek's "after
    # rejecting 5 % of values": its ends, its length (his U) and its half-width (JCGM's U)
    lo, hi = (float(e) for e in r4.coverage_interval(0.95))
    half = 1.959963984540054 * math.sqrt(1.25)
    for key, x, ex in (("low", lo, 0.5 - half), ("high", hi, 0.5 + half)):
        values[f"fig4.interval_{key}"] = mc(x, 2.2 * r4.u, n4)  # s.d. of a 2.5 % quantile
        values[f"fig4.interval_{key}_exact"] = exact(ex)
    values["fig4.interval_length"] = mc(hi - lo, 2.2 * r4.u, n4)
    values["fig4.interval_length_exact"] = exact(2.0 * half)
    data["fig4"] = np.asarray(r4.samples, dtype=np.float64).ravel()

    # Fig. 1: the ball centre from 4 + 1 probed points
    study = ball = load("ball_centre")
    n1 = max(1000, int(study.settings.trials * scale))
    res = study.run(trials=n1, seed=study.settings.seed)
    probe = study.graph.probe
    u_w = math.sqrt(probe.u_axis**2 + probe.u_probe**2 + probe.u_perp**2)  # along the probing
    u_r1 = float(study.graph.place("neg_r1").u)
    closed = {
        "x": u_w / math.sqrt(2.0),
        "y": u_w / math.sqrt(2.0),
        "z": math.hypot(u_w, u_r1),
    }
    for c in "xyz":
        q = res.quantity(f"p.{c}")
        u = float(q.mc.u)
        values[f"fig1.u_{c}_um"] = mc(1e3 * u, 1e3 * u / math.sqrt(2.0), n1)
        values[f"fig1.u_{c}_closed_um"] = exact(1e3 * closed[c])
        values[f"fig1.gum_u_{c}_um"] = exact(1e3 * float(q.gum.u))
    values["fig1.u_w_um"] = exact(1e3 * u_w)
    values["fig1.u_1_um"] = exact(1e3 * probe.u_axis)
    data["fig1"] = [r.to_dict() for r in res.regions if r.name in ("p: x, y", "p: x, z")]

    # Fig. 14-15: the sweep of u(d_AC) and its surrogate
    study = load("bcs_origin")
    n14 = max(1000, int(study.settings.trials * scale))
    res = study.run(trials=n14, seed=study.settings.seed)
    d = res.quantity("d_ac")
    values["d_ac.estimate_mm"] = mc(d.mc.estimate, d.mc.u, n14)
    values["d_ac.u_um"] = mc(1e3 * d.mc.u, 1e3 * d.mc.u / math.sqrt(2.0), n14)
    values["d_ac.gum_u_um"] = exact(1e3 * d.gum.u)
    values["d_ac.sigma_p_um"] = exact(1e3 * study.graph.probe.u_probe)
    values["d_ac.sigma_m_um"] = exact(1e3 * study.graph.probe.u_axis)
    sw = res.extra["sweep"]
    data["sweep"] = sw
    # the sweep keeps its trials per grid point whatever the scale: the same numbers
    m = int(sw["trials"])
    u_grid = np.asarray(sw["u"], dtype=np.float64)
    for i, (sp, sm) in enumerate(np.asarray(sw["grid"])):
        values[f"sweep.u_um[{1e3 * sp:g},{1e3 * sm:g}]"] = exact(1e3 * u_grid[i])
    # common random numbers, and sigma_p and sigma_m both entering each probed coordinate
    # as one normal of s.d. sqrt(u1² + u2² + u3²), make the grid exactly symmetric
    n_side = round(math.sqrt(u_grid.size))
    square = u_grid.reshape(n_side, n_side)
    values["sweep.asymmetry_um"] = exact(1e3 * float(np.max(np.abs(square - square.T))))
    # the same grid with an independent seed per point, as a sweep without common random
    # numbers would be: how far apart sampling alone puts the two sensitivities
    from mtmc.graph import run_graph
    from mtmc.graph.sweep import apply_setting, fit_surrogate

    grid = np.asarray(sw["grid"], dtype=np.float64)
    names = list(sw["names"])
    u_ind = []
    for i, row in enumerate(grid):
        g = study.graph
        for key, val in zip(names, row / study.graph.factor, strict=True):
            g = apply_setting(g, key, float(val))
        r = run_graph(g, m, study.settings.seed + 1 + i, outputs=["d_ac"])
        u_ind.append(float(r.places["d_ac"].u))
    ind = fit_surrogate(grid, np.asarray(u_ind), intercept=True)
    cp_i, cm_i = (math.sqrt(float(c)) for c in ind.coefficients)
    values["surrogate.independent.sens_p"] = mc(cp_i, cp_i / math.sqrt(2.0 * m), m)
    values["surrogate.independent.sens_m"] = mc(cm_i, cm_i / math.sqrt(2.0 * m), m)
    values["surrogate.independent.ratio_pct"] = exact(100.0 * abs(cp_i / cm_i - 1.0))
    values["sweep.rel_se_u_pct"] = exact(100.0 / math.sqrt(2.0 * (m - 1)))
    fits = (
        ("intercept", sw["surrogate"]),
        ("no_intercept", sw["surrogate_no_intercept"]),
    )
    for key, fit in fits:
        cp, cm = (float(c) for c in fit["coefficients"])
        values[f"surrogate.{key}.sens_p"] = exact(math.sqrt(cp))
        values[f"surrogate.{key}.sens_m"] = exact(math.sqrt(cm))
        values[f"surrogate.{key}.c0_um"] = exact(1e3 * math.sqrt(fit["c0"]))
        values[f"surrogate.{key}.max_rel_error_pct"] = exact(100.0 * fit["max_rel_error"])
    settings = {
        "fig4": {"trials": n4, "seed": 4},
        "ball_centre": {"trials": n1, "seed": ball.settings.seed},
        "bcs_origin": {"trials": n14, "seed": study.settings.seed, "sweep_trials": m},
    }
    return {"settings": settings, "values": values}, data


#: Stryczek eq. (31): U = 0.05999 sqrt(sigma_p^2/845 + sigma_m^2/868); Fig. 4: 0.502, 1.117.
STRYCZEK_EQ31 = (0.05999, 845.0, 868.0)
STRYCZEK_FIG4 = (0.502, 1.117)
#: Stryczek, text below eq. 6 (Fig. 4): "95% of values η is included in the interval
#: [-1.658, 2.663]" and "U equals 4.321 µm" (the interval's length).
STRYCZEK_FIG4_INTERVAL = (-1.658, 2.663, 4.321)


def stryczek_eq31_um(sp_um: Any, sm_um: Any) -> Any:
    """Eq. (31) read with sigma in µm and U in mm, returned in µm."""
    a, b, c = STRYCZEK_EQ31
    return 1e3 * a * np.sqrt(np.asarray(sp_um) ** 2 / b + np.asarray(sm_um) ** 2 / c)


def stryczek_figures(data: dict[str, Any], out: Path) -> list[Path]:
    """Fig. 4, Fig. 1 and Fig. 14-15 of Stryczek, redrawn from our runs."""
    from matplotlib.patches import Ellipse

    paths = []
    x = data["fig4"]
    fig = new_figure(4.2, 2.8)
    fig.subplots_adjust(left=0.13, right=0.97, bottom=0.16, top=0.9)
    ax = fig.add_subplot(1, 1, 1)
    ax.hist(x, bins=40, density=True, color="C0", alpha=0.6, label=f"{x.size} trials")
    t = np.linspace(-4, 5, 200)
    s = math.sqrt(1.25)
    ax.plot(
        t,
        np.exp(-0.5 * ((t - 0.5) / s) ** 2) / (s * math.sqrt(2 * math.pi)),
        "k-",
        lw=1,
    )
    ax.set_xlabel("Y = X1 + X2")
    ax.set_title("X1 ~ N(0, 1), X2 ~ N(0.5, 0.5) (Stryczek Fig. 4)", fontsize=8)
    ax.legend(fontsize=7)
    paths.append(save(fig, out, "stryczek_fig4.png"))

    fig = new_figure(6.4, 3.2)
    fig.subplots_adjust(left=0.1, right=0.98, bottom=0.15, top=0.9, wspace=0.35)
    for i, r in enumerate(data["fig1"]):
        ax = fig.add_subplot(1, 2, i + 1)
        pts = (np.asarray(r["scatter"]) - np.asarray(r["centre"])) * 1e3
        ax.plot(pts[:, 0], pts[:, 1], ".", ms=1.5, color="C0", alpha=0.4)
        axes = np.asarray(r["axes"])
        semi = np.asarray(r["semi_axes"]) * 1e3
        ang = float(np.degrees(np.arctan2(axes[1, 1], axes[0, 1])))
        ell = Ellipse((0, 0), 2 * semi[1], 2 * semi[0], angle=ang, fill=False, color="C3", lw=1.4)
        ax.add_patch(ell)
        ax.set_aspect("equal")
        lim = 1.2 * float(np.abs(pts).max())
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim, lim)
        a, b = r["labels"]
        ax.set_xlabel(f"{a} − {a}₀ / µm")
        ax.set_ylabel(f"{b} − {b}₀ / µm")
        ax.set_title(f"ball centre, {a}–{b}: 95 % region", fontsize=8)
    paths.append(save(fig, out, "stryczek_fig1.png"))

    sw = data["sweep"]
    grid = np.asarray(sw["grid"]) * 1e3
    u = np.asarray(sw["u"]) * 1e3
    fit = sw["surrogate"]
    a = np.linspace(grid[:, 0].min(), grid[:, 0].max(), 25)
    aa, bb = np.meshgrid(a, a, indexing="ij")
    cp, cm = fit["coefficients"]
    zz = 1e3 * np.sqrt(fit["c0"] + cp * (aa / 1e3) ** 2 + cm * (bb / 1e3) ** 2)
    fig = new_figure(8.4, 3.6)
    fig.subplots_adjust(left=0.0, right=0.97, bottom=0.06, top=0.92, wspace=0.05)
    ax1: Any = fig.add_subplot(1, 2, 1, projection="3d")
    n = round(math.sqrt(len(u)))
    ax1.plot_surface(
        grid[:, 0].reshape(n, n),
        grid[:, 1].reshape(n, n),
        u.reshape(n, n),
        cmap="viridis",
    )
    ax1.set_title(f"Fig. 14: Monte Carlo, {sw['trials']} trials per point", fontsize=8)
    ax2: Any = fig.add_subplot(1, 2, 2, projection="3d")
    ax2.plot_surface(aa, bb, zz, cmap="viridis", alpha=0.6)
    ax2.plot_wireframe(aa, bb, stryczek_eq31_um(aa, bb), color="k", lw=0.4, rstride=4, cstride=4)
    ax2.scatter(grid[:, 0], grid[:, 1], u, color="C3", s=8)
    ax2.set_title("Fig. 15: our surrogate (colour), eq. 31 (black)", fontsize=8)
    for ax in (ax1, ax2):
        ax.set_xlabel("σ_p / µm", fontsize=7)
        ax.set_ylabel("σ_m / µm", fontsize=7)
        ax.set_zlabel("u(d_AC) / µm", fontsize=7)
        ax.tick_params(labelsize=6)
    paths.append(save(fig, out, "stryczek_fig14_15.png"))
    return paths


def stryczek_tables(nb: Numbers) -> dict[str, str]:
    """The generated tables of ``stryczek.md``."""
    s = nb["settings"]
    a, b, c = STRYCZEK_EQ31
    out = {}
    out["fig4"] = table(
        [
            "",
            "Stryczek Fig. 4 (3000 samples)",
            f"mtmc ({s['fig4']['trials']} trials)",
            "exact",
        ],
        [
            [
                "mean of Y",
                f"{STRYCZEK_FIG4[0]:.3f}",
                fmt(v(nb, "fig4.mean"), 3),
                "0.500",
            ],
            [
                "standard deviation of Y",
                f"{STRYCZEK_FIG4[1]:.3f}",
                fmt(v(nb, "fig4.u"), 3),
                fmt(v(nb, "fig4.u_exact"), 3),
            ],
            [
                "95 % of the values in",
                f"[{STRYCZEK_FIG4_INTERVAL[0]:.3f}, {STRYCZEK_FIG4_INTERVAL[1]:.3f}]",
                f"[{fmt(v(nb, 'fig4.interval_low'), 3)}, {fmt(v(nb, 'fig4.interval_high'), 3)}]",
                (
                    f"[{fmt(v(nb, 'fig4.interval_low_exact'), 3)}, "
                    f"{fmt(v(nb, 'fig4.interval_high_exact'), 3)}]"
                ),
            ],
            [
                "length of that interval (Stryczek's U)",
                f"{STRYCZEK_FIG4_INTERVAL[2]:.3f}",
                fmt(v(nb, "fig4.interval_length"), 3),
                fmt(v(nb, "fig4.interval_length_exact"), 3),
            ],
            [
                "its half-width (U of JCGM 101, k ≈ 1.96)",
                f"{STRYCZEK_FIG4_INTERVAL[2] / 2:.3f} (our division)",
                fmt(v(nb, "fig4.interval_length") / 2, 3),
                fmt(v(nb, "fig4.interval_length_exact") / 2, 3),
            ],
        ],
    )
    rows = []
    for ch in "xyz":
        rows.append(
            [
                f"u(p.{ch}) / µm",
                fmt(v(nb, f"fig1.u_{ch}_um"), 3),
                fmt(v(nb, f"fig1.gum_u_{ch}_um"), 3),
                fmt(v(nb, f"fig1.u_{ch}_closed_um"), 3),
            ]
        )
    out["fig1"] = (
        f"u_w = {fmt(v(nb, 'fig1.u_w_um'), 3)} µm along the probing direction, "
        f"u_1 = {fmt(v(nb, 'fig1.u_1_um'), 3)} µm across it "
        f"({s['ball_centre']['trials']} trials, seed {s['ball_centre']['seed']}).\n\n"
        + table(["", "Monte Carlo", "GUM", "closed form"], rows)
    )
    rows = []
    for key, label in (
        ("intercept", "with c0"),
        ("no_intercept", "without c0 (eq. 31's form)"),
    ):
        rows.append(
            [
                f"mtmc, {label}",
                fmt(v(nb, f"surrogate.{key}.sens_p"), 3),
                fmt(v(nb, f"surrogate.{key}.sens_m"), 3),
                fmt(v(nb, f"surrogate.{key}.c0_um"), 2),
                fmt(v(nb, f"surrogate.{key}.max_rel_error_pct"), 2),
            ]
        )
    out["fig15"] = table(
        ["", "√c_p = u/σ_p", "√c_m = u/σ_m", "√c0 / µm", "largest relative error / %"],
        [
            [
                "Stryczek eq. 31 (U in mm, σ in µm)",
                f"{1e3 * a / math.sqrt(b):.3f}",
                f"{1e3 * a / math.sqrt(c):.3f}",
                "—",
                "≤ 5",
            ],
            *rows,
            [
                "mtmc, with c0, an independent seed per grid point",
                fmt(v(nb, "surrogate.independent.sens_p"), 3),
                fmt(v(nb, "surrogate.independent.sens_m"), 3),
                "—",
                "—",
            ],
        ],
    )
    out["sweep_symmetry"] = (
        f"With common random numbers the largest difference between u(d_AC) at (σ_p, σ_m) = "
        f"(a, b) and at (b, a) is {v(nb, 'sweep.asymmetry_um'):.3g} µm on our grid. With an "
        f"independent seed per grid point the two fitted sensitivities are "
        f"{fmt(v(nb, 'surrogate.independent.ratio_pct'), 1)} % apart; the relative standard "
        f"error of one u from {nb['settings']['bcs_origin']['sweep_trials']} trials is "
        f"{fmt(v(nb, 'sweep.rel_se_u_pct'), 1)} %."
    )
    grid = [k for k in nb["values"] if k.startswith("sweep.u_um[")]
    rows = []
    for k in grid:
        sp, sm = (float(t) for t in k[len("sweep.u_um[") : -1].split(","))
        if sp == sm or (sp, sm) in ((1.0, 5.0), (5.0, 1.0)):
            rows.append(
                [
                    f"{sp:g}",
                    f"{sm:g}",
                    fmt(float(stryczek_eq31_um(sp, sm)), 2),
                    fmt(v(nb, k), 2),
                ]
            )
    out["fig14"] = table(["σ_p / µm", "σ_m / µm", "eq. 31 U / µm", "mtmc u(d_AC) / µm"], rows)
    d = s["bcs_origin"]
    out["d_ac"] = (
        f"d_AC = {fmt(v(nb, 'd_ac.estimate_mm'), 4)} mm, u = {fmt(v(nb, 'd_ac.u_um'), 2)} µm "
        f"(GUM {fmt(v(nb, 'd_ac.gum_u_um'), 2)} µm) at the file's "
        f"σ_p = {v(nb, 'd_ac.sigma_p_um'):g} µm, σ_m = {v(nb, 'd_ac.sigma_m_um'):g} µm; "
        f"{d['trials']} trials, seed {d['seed']}; the sweep {d['sweep_trials']} trials per "
        "grid point."
    )
    return out


# ---------------------------------------------------------------------------- Aguado et al.


def per_point(ver: Any, trials: int, seed: int) -> Any:
    """Whole verifications with the per-point error vectors kept (engine-seeded, as simulate).

    The model is :class:`mtmc.verification.simulate.VerificationModel` with two more
    outputs: ``initial`` (reading minus nominal reading, tracker frame) and ``residual``
    (eq. 17's model minus reading), both ``(m, 3N)``. The inputs and the seed are those of
    :func:`mtmc.verification.simulate.simulate`, so its trials are the same verifications.
    """
    import mtmc
    from mtmc.verification.simulate import VerificationModel, reference_identification

    vm = VerificationModel.build(ver, reference_identification(ver))
    n = vm.x_true.shape[0]

    def model(noise: Any) -> dict[str, Any]:
        m = noise.shape[0]
        out: dict[str, Any] = vm(noise)
        x_meas = vm.noise.perturb(vm.true_readings(m), noise.reshape(m, n, 3))
        _, r, _, _ = vm.solve(x_meas)
        out["initial"] = (x_meas - vm.x_nom).reshape(m, -1)
        out["residual"] = r.reshape(m, -1)
        return out

    keep = ["ve", "initial", "residual", "comp"]
    res = mtmc.monte_carlo(model, vm.inputs(), trials, seed, keep=keep)
    return res, vm


def pooled(values: Any, n: int, key: str, out: dict[str, Any], factor: float = 1e3) -> None:
    """Mean and s.d. over all points of all trials of ``values`` (trials x points), µm."""
    a = np.asarray(values, dtype=np.float64) * factor
    per_mean, per_sd = a.mean(axis=1), a.std(axis=1)
    out[f"{key}.mean"] = mc(a.mean(), per_mean.std(ddof=1), n)
    out[f"{key}.sd"] = mc(a.std(), per_sd.std(ddof=1) + per_mean.std(ddof=1), n)


#: Aguado et al. 2017 §3: initial 77.39 +- 40.91 µm, residual 12.34 +- 7.06 µm.
AGUADO2017 = {"initial": (77.39, 40.91), "final": (12.34, 7.06)}

#: The steps of the mesh over 0-400 x 0-400 mm that the tutorial compares (mm): 5 x 5,
#: 6 x 6, 9 x 9 (the study's) and 17 x 17 points.
AGUADO2017_STEPS = (100.0, 80.0, 50.0, 25.0)


def aguado2017(scale: float = 1.0) -> tuple[Numbers, dict[str, Any]]:
    """Aguado et al. 2017: the initial and final errors (Fig. 5-6), their statistics."""
    from mtmc.verification.simulate import simulate
    from mtmc.verification.workspace import mesh

    kind = load("aguado2017")
    study = kind.study
    n = max(50, int(kind.settings.trials * scale))
    seed = kind.settings.seed
    ver = study.verification()
    sim = simulate(ver, n, seed)
    res, vm = per_point(ver, n, seed)
    init = np.asarray(res["initial"].samples).reshape(n, -1, 3)
    comp = np.asarray(res["comp"].samples).reshape(n, -1, 3)
    values: dict[str, Any] = {}
    pooled(np.linalg.norm(init, axis=-1), n, "initial", values)
    data: dict[str, Any] = {"initial": init * 1e3}
    pooled(np.linalg.norm(comp, axis=-1), n, "final", values)
    data["final"] = comp * 1e3
    for name in (
        "initial.mean",
        "residual.mean",
        "compensated.mean",
        "compensated.max",
    ):
        est, u = sim.ve(name)
        values[f"ve.{name}"] = mc(1e3 * est, 1e3 * u, n)
    pu, gu = np.asarray(sim.point_u) * 1e3, np.asarray(sim.gum.point_u) * 1e3
    values["point_u.mean"] = mc(pu.mean(), pu.mean() / math.sqrt(2.0), n)
    values["point_u.max"] = mc(pu.max(), pu.max() / math.sqrt(2.0), n)
    values["point_u_gum.mean"] = exact(gu.mean())
    values["points"] = exact(vm.x_true.shape[0])
    # the same trials as the study's run: its per-trial means equal ours
    values["check.same_trials"] = exact(
        float(np.allclose(np.asarray(sim.ve_samples), np.asarray(res["ve"].samples), atol=1e-12))
    )
    data["points"] = np.asarray(study.machine.tool_position(ver.q))
    data["point_u"] = pu
    data["bias"] = np.linalg.norm(np.asarray(sim.comp_bias), axis=1) * 1e3
    # the truth is representable: without noise the compensated error is rounding only
    zero = np.zeros((1, 3 * vm.x_true.shape[0]))
    comp0 = np.asarray(vm(zero)["comp"]).reshape(-1, 3)
    # (a flag, not the value: the value, about 1e-4 µm, is the convergence tolerance of the
    # noise-free identification and rounding, whose digits no two BLAS kernels share)
    worst = 1e3 * float(np.linalg.norm(comp0, axis=-1).max())
    values["noise_free.final_below_1nm"] = exact(float(worst < 1e-3))
    # the same verifications of a machine without errors: the tracker's noise alone
    res0, _ = per_point(dataclasses.replace(ver, true_errors={}), n, seed)
    comp = np.asarray(res0["comp"].samples).reshape(n, -1, 3)
    pooled(np.linalg.norm(comp, axis=-1), n, "no_errors.final", values)
    # the step of the mesh, which the paper does not give: 25 to 289 points over the area
    for step in AGUADO2017_STEPS:
        q = mesh([0.0, 0.0, 0.0], [400.0, 400.0, 0.0], step=[step, step, step])
        res_s, vm_s = per_point(dataclasses.replace(ver, q=q), n, seed)
        comp = np.asarray(res_s["comp"].samples).reshape(n, -1, 3)
        pooled(np.linalg.norm(comp, axis=-1), n, f"step{step:g}.final", values)
        values[f"step{step:g}.points"] = exact(vm_s.x_true.shape[0])
    return {
        "settings": {"aguado2017": {"trials": n, "seed": seed}},
        "values": values,
    }, data


def _hist_row(fig: Any, row: int, rows: int, e: Any, title: str) -> None:
    labels = ("X", "Y", "Z")
    for j in range(4):
        ax = fig.add_subplot(rows, 4, 4 * row + j + 1)
        x = (np.linalg.norm(e, axis=-1) if j == 3 else e[..., j]).ravel()
        ax.hist(x, bins=50, color="C0" if j < 3 else "C3", alpha=0.8)
        ax.set_xlabel(("distance" if j == 3 else f"error in {labels[j]}") + " / µm", fontsize=7)
        ax.tick_params(labelsize=6)
        ax.set_yticks([])
        if j == 0:
            ax.set_title(title, fontsize=8, loc="left")


def aguado2017_figures(data: dict[str, Any], out: Path) -> list[Path]:
    """Fig. 5-6 (histograms) and maps of the per-point errors and calibration u."""
    fig = new_figure(9.0, 4.4)
    fig.subplots_adjust(left=0.03, right=0.98, bottom=0.11, top=0.93, hspace=0.55, wspace=0.12)
    _hist_row(fig, 0, 2, data["initial"], "Fig. 5: initial error, all points of all tests")
    _hist_row(fig, 1, 2, data["final"], "Fig. 6: error after compensation")
    paths = [save(fig, out, "aguado2017_fig5_6.png")]

    pts = data["points"]
    maps = (
        (np.linalg.norm(data["initial"], axis=-1).mean(axis=0), "mean initial error"),
        (
            np.linalg.norm(data["final"], axis=-1).mean(axis=0),
            "mean error after compensation",
        ),
        (data["point_u"], "calibration u (Monte Carlo)"),
    )
    fig = new_figure(9.6, 3.0)
    fig.subplots_adjust(left=0.06, right=0.95, bottom=0.16, top=0.9, wspace=0.55)
    for i, (val, title) in enumerate(maps):
        ax = fig.add_subplot(1, 3, i + 1)
        sc = ax.scatter(pts[:, 0], pts[:, 1], c=val, cmap="viridis", s=40, edgecolors="k", lw=0.3)
        fig.colorbar(sc, ax=ax, shrink=0.85, label="µm")
        ax.set_title(title, fontsize=8)
        ax.set_xlabel("X / mm", fontsize=7)
        ax.set_ylabel("Y / mm", fontsize=7)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=6)
    paths.append(save(fig, out, "aguado2017_maps.png"))
    return paths


def aguado2017_tables(nb: Numbers) -> dict[str, str]:
    """The generated tables of ``aguado2017.md``."""
    s = nb["settings"]["aguado2017"]
    (pi, psi), (pf, psf) = AGUADO2017["initial"], AGUADO2017["final"]
    rows = [
        [
            "initial volumetric error, mean ± s.d. (Fig. 5)",
            f"{pi:.2f} ± {psi:.2f}",
            f"{fmt(v(nb, 'initial.mean'), 2)} ± {fmt(v(nb, 'initial.sd'), 2)}",
        ],
        [
            "error after compensation, mean ± s.d. (Fig. 6)",
            f"{pf:.2f} ± {psf:.2f}",
            f"{fmt(v(nb, 'final.mean'), 2)} ± {fmt(v(nb, 'final.sd'), 2)}",
        ],
        [
            "residual of the fit (eq. 17 of Aguado et al. 2016), mean",
            "—",
            fmt(v(nb, "ve.residual.mean"), 2),
        ],
        [
            "calibration u per point, mean (Monte Carlo / GUM)",
            "—",
            f"{fmt(v(nb, 'point_u.mean'), 2)} / {fmt(v(nb, 'point_u_gum.mean'), 2)}",
        ],
    ]
    same = "the same" if v(nb, "check.same_trials") == 1.0 else "NOT the same"
    head = (
        f"{int(v(nb, 'points'))} points, {s['trials']} tests, seed {s['seed']}; µm "
        f"(the per-point run gives {same} verifications as `simulate`)."
    )
    out = {"stats": head + "\n\n" + table(["", "Aguado et al. 2017", "mtmc"], rows)}
    below = v(nb, "noise_free.final_below_1nm") == 1.0
    out["noise_alone"] = (
        "Without noise, the largest error left after compensation at any point is "
        + ("below 0.001 µm" if below else "NOT below 0.001 µm")
        + f". The same {s['trials']} verifications of a machine with no errors at all give "
        f"{fmt(v(nb, 'no_errors.final.mean'), 2)} ± {fmt(v(nb, 'no_errors.final.sd'), 2)} µm "
        f"after compensation, against {fmt(v(nb, 'final.mean'), 2)} ± "
        f"{fmt(v(nb, 'final.sd'), 2)} µm with the study's errors."
    )
    rows = []
    for step in AGUADO2017_STEPS:
        k = f"step{step:g}"
        rows.append(
            [
                f"{step:g}",
                f"{int(v(nb, f'{k}.points'))}",
                f"{fmt(v(nb, f'{k}.final.mean'), 2)} ± {fmt(v(nb, f'{k}.final.sd'), 2)}",
            ]
        )
    rows.append(["not printed", "not printed", f"{pf:.2f} ± {psf:.2f} (Aguado et al. 2017 §3)"])
    out["steps"] = table(["step / mm", "points", "error after compensation / µm"], rows)
    # the mean falls as 1/sqrt(N) (20.39 * 5 = 16.92 * 6 = 11.15 * 9 = 5.83 * 17 within 3 %):
    # the number of points at which the study's row would give the paper's mean
    n_eq = v(nb, "points") * (v(nb, "final.mean") / pf) ** 2
    out["steps"] += (
        f"\n\nThe mean falls as 1/√N; scaled from our {int(v(nb, 'points'))}-point row, the "
        f"paper's {pf:.2f} µm corresponds to N ≈ {n_eq:.0f} points in this model."
    )
    return out


#: Aguado et al. 2016 Tables I-IV: (initial max, mean, min, final max, mean, min), µm.
AGUADO2016: dict[tuple[str, str], tuple[float, ...]] = {
    ("mesh96", "none"): (63.7, 35.3, 0.0, 16.3, 7.7, 0.0),
    ("mesh96", "pos1"): (121.1, 72.0, 44.8, 81.4, 41.6, 7.7),
    ("mesh96", "pos2"): (85.0, 53.1, 29.4, 55.3, 25.9, 1.7),
    ("mesh96", "pos3"): (122.1, 71.2, 43.0, 74.3, 32.3, 2.6),
    ("mesh96", "pos4"): (111.1, 70.0, 26.8, 40.8, 21.5, 4.4),
    ("cloud96", "pos1"): (121.1, 72.0, 45.5, 81.9, 32.8, 2.5),
    ("cloud96", "pos2"): (85.0, 53.4, 29.4, 55.3, 26.1, 4.4),
    ("cloud96", "pos3"): (140.7, 88.6, 29.4, 61.5, 39.0, 6.6),
    ("cloud96", "pos4"): (108.3, 65.3, 25.6, 37.1, 16.3, 3.0),
    ("mesh5408", "none"): (63.7, 33.7, 0.0, 14.6, 6.6, 0.0),
    ("mesh5408", "pos1"): (121.1, 69.9, 44.8, 98.2, 35.1, 1.9),
    ("mesh5408", "pos2"): (85.2, 50.2, 29.2, 88.0, 47.0, 22.2),
    ("mesh5408", "pos3"): (140.7, 87.0, 6.15, 113.4, 40.5, 1.2),
    ("mesh5408", "pos4"): (108.3, 63.6, 25.3, 46.1, 16.3, 8.0),
}
#: The table of each point set in Aguado et al. 2016.
AGUADO2016_TABLE = {"mesh96": "Table II", "cloud96": "Table III", "mesh5408": "Table IV"}
#: Aguado et al. 2016 Table I: tracker position (mm) and angles (α, β, φ) (deg).
AGUADO2016_T1: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    "pos1": ((3500.0, -1500.0, 500.0), (15.0, 37.0, 26.0)),
    "pos2": ((4500.0, -800.0, 500.0), (32.0, 17.0, 12.0)),
    "pos3": ((1250.0, 2000.0, 600.0), (5.0, 65.0, 32.0)),
    "pos4": ((1100.0, -1000.0, 600.0), (63.0, 14.0, 35.0)),
}
#: Aguado et al. 2016 §5 (before Table II): the angular noise, µrad on each angle.
AGUADO2016_ANGLE_URAD = 24.0
#: The reading of Table I's angles before the study chose ``ZYZ``.
AGUADO2016_OLD_EULER = "xyz"
STATS = (
    "initial.max",
    "initial.mean",
    "initial.min",
    "residual.max",
    "residual.mean",
    "residual.min",
)
#: The paper's final error is read as the error left after compensation (see the tutorial).
FINAL = ("compensated.max", "compensated.mean", "compensated.min")
POSITIONS = ("pos1", "pos2", "pos3", "pos4")


def euler_readings(chosen: str) -> list[tuple[str, bool]]:
    """Every reading of three Euler angles, ``chosen`` and the old one first.

    The 12 sequences, extrinsic (lower case) or intrinsic (upper case), the matrix ``R``
    (tracker frame to machine frame) or its transpose.
    """
    seqs = ["xyz", "xzy", "yxz", "yzx", "zxy", "zyx", "xyx", "xzx", "yxy", "yzy", "zxz", "zyz"]
    every = [(c, t) for s in seqs for c in (s, s.upper()) for t in (False, True)]
    first = [(chosen, False), (AGUADO2016_OLD_EULER, False)]
    return first + [r for r in every if r not in first]


def reading_name(seq: str, transposed: bool) -> str:
    """``ZYZ``, or ``xyz, Rᵀ``."""
    return f"{seq}, Rᵀ" if transposed else seq


def implied_angle_urad(ver: Any, target_um: float, n: int, seed: int) -> tuple[float, float]:
    """The angular noise (µrad, both angles) whose mean initial error is ``target_um``.

    The initial error needs no identification: the readings of the true machine, perturbed
    as the tracker's noise model does (radial part unchanged), against the nominal
    readings, averaged over the points and ``n`` trials of standard normals drawn once
    (``SeedSequence(seed)``), so that the mean is a smooth function of the angle. Returns
    the angle and its Monte Carlo spread (the spread of one trial's mean over the slope).
    """
    import dataclasses

    from scipy.optimize import brentq

    tr = ver.tracker
    x_true = ver.readings()
    x_nom = tr.to_tracker(ver.model.machine.tool_position(ver.q))
    z = np.random.default_rng(np.random.SeedSequence(seed)).standard_normal((n, *x_true.shape))

    def per_trial(urad: float) -> Any:
        noise = dataclasses.replace(tr.noise, azimuth=urad * 1e-6, elevation=urad * 1e-6)
        return np.linalg.norm(noise.perturb(x_true, z) - x_nom, axis=-1).mean(axis=1) * 1e3

    def f(urad: float) -> float:
        return float(per_trial(urad).mean()) - target_um

    a = float(brentq(f, 0.0, 1000.0, xtol=1e-9))
    h = 0.05
    slope = (f(a + h) - f(a - h)) / (2.0 * h)
    return a, float(per_trial(a).std(ddof=1)) / slope


def aguado2016(scale: float = 1.0) -> tuple[Numbers, dict[str, Any]]:
    """Aguado et al. 2016: Tables I-IV (3 point sets x 4 tracker positions) and Fig. 9.

    Besides the tables: the Euler readings of Table I against our visibility limits, the
    results of the study's reading against the old one, and the angular noise each
    position's initial error of Table II implies.
    """
    import dataclasses

    import mtmc
    from mtmc.geometry.transforms import matrix_from_euler
    from mtmc.verification.identify import ve_stats
    from mtmc.verification.simulate import (
        VerificationModel,
        reference_identification,
        simulate,
    )

    study = load("aguado2016")
    vs = study.study
    n = max(50, int(study.settings.trials * scale))
    n9 = max(20, int(100 * scale))
    seed = int(study.settings.seed or 0)
    values: dict[str, Any] = {}
    data: dict[str, Any] = {}
    for pts in ("mesh96", "cloud96", "mesh5408"):
        ver0 = vs.verification(points=pts, tracker="pos1")
        ref = reference_identification(ver0)
        stats = np.concatenate([ve_stats(ref.initial_ve)[0], ve_stats(ref.residual_ve)[0]])
        # the residual of the noise-free fit is a small difference of readings of up to
        # L = 4.5 m: one rounding of a reading is EPS * L (1e-9 µm), and the fit adds up
        # many; observed across BLAS kernels: 2.7e-10 µm at most
        reach_um = 1e3 * float(np.abs(np.asarray(ver0.readings())).max())
        for name, x in zip(STATS, stats, strict=True):
            values[f"{pts}.none.{name}"] = (
                exact(1e3 * x)
                if name.startswith("initial")
                else exact(
                    1e3 * x,
                    tol=100.0 * EPS * reach_um,
                    why="a least-squares residual: 100 roundings of readings of 4.5 m",
                )
            )
        for pos in POSITIONS:
            ver = vs.verification(points=pts, tracker=pos)
            sim = simulate(ver, n, seed)
            for name in (*STATS, *FINAL):
                est, u = sim.ve(name)
                values[f"{pts}.{pos}.{name}"] = mc(1e3 * est, 1e3 * u, n)
            for which in ("initial", "compensated"):
                for k, (est, u) in sim.point_mean_ve(which).items():
                    values[f"{pts}.{pos}.point.{which}.{k}"] = mc(1e3 * est, 1e3 * u, n)
            pu = np.asarray(sim.point_u) * 1e3
            values[f"{pts}.{pos}.point_u.mean"] = mc(pu.mean(), pu.mean() / math.sqrt(2.0), n)
            values[f"{pts}.{pos}.point_u_gum.mean"] = exact(1e3 * float(np.mean(sim.gum.point_u)))
            if pts == "mesh96":
                values["fit.parameters"] = exact(len(sim.names))
                values["fit.readings"] = exact(3 * ver.n_points)
                # the old reading of Table I's angles, the rest unchanged
                R = matrix_from_euler(np.radians(AGUADO2016_T1[pos][1]), AGUADO2016_OLD_EULER)
                old = dataclasses.replace(ver.tracker, rotation=R)
                sim_old = simulate(dataclasses.replace(ver, tracker=old), n, seed)
                for name in ("initial.mean", "residual.mean", "compensated.mean"):
                    est, u = sim_old.ve(name)
                    values[f"{pts}.{pos}.old.{name}"] = mc(1e3 * est, 1e3 * u, n)
                L = np.linalg.norm(ver.readings(), axis=-1) * 1e-3
                values[f"distance.{pos}.min_m"] = exact(L.min())
                values[f"distance.{pos}.max_m"] = exact(L.max())
                a, sd = implied_angle_urad(ver, AGUADO2016[(pts, pos)][1], n, seed)
                values[f"implied.{pos}.angle_urad"] = mc(a, sd, n)
            if pts == "mesh5408" and pos in ("pos1", "pos4"):
                vm = VerificationModel.build(ver, reference_identification(ver))
                keep = ["point_initial", "point_compensated"]
                res = mtmc.monte_carlo(vm, vm.inputs(), n9, seed, keep=keep)
                data[pos] = tuple(np.asarray(res[k].samples) * 1e3 for k in keep)
    data["none"] = (ref.initial_ve[0] * 1e3, ref.residual_ve[0] * 1e3)
    # Table I's angles read every way: the elevation of the beam over the 5408 points
    p = vs.machine.tool_position(vs.points["mesh5408"].q)
    for seq, tr in euler_readings(vs.euler):
        for pos, (t, ang) in AGUADO2016_T1.items():
            R = matrix_from_euler(np.radians(ang), seq)
            x = (p - np.asarray(t)) @ (R.T if tr else R)
            el = np.degrees(np.arctan2(x[:, 2], np.hypot(x[:, 0], x[:, 1])))
            key = f"reading.{reading_name(seq, tr)}.{pos}"
            values[f"{key}.elevation_min_deg"] = exact(el.min())
            values[f"{key}.elevation_max_deg"] = exact(el.max())
            values[f"{key}.tilt_deg"] = exact(math.degrees(math.acos(min(1.0, R[2, 2]))))
    lim = vs.limits
    assert lim is not None
    settings = {
        "aguado2016": {
            "trials": n,
            "seed": seed,
            "fig9_trials": n9,
            "euler": vs.euler,
            "elevation_deg": [math.degrees(x) for x in lim.elevation],
        }
    }
    return {"settings": settings, "values": values}, data


def aguado2016_figures(data: dict[str, Any], out: Path) -> list[Path]:
    """Fig. 9: initial and final errors on the 5408-point mesh, no noise and pos 1 and 4."""
    fig = new_figure(8.4, 3.0)
    fig.subplots_adjust(left=0.05, right=0.98, bottom=0.17, top=0.88, wspace=0.15)
    titles = (("initial error", 0), ("final error (after compensation)", 1))
    for i, (title, idx) in enumerate(titles):
        ax = fig.add_subplot(1, 2, i + 1)
        hi = max(float(np.percentile(data[k][idx], 99.5)) for k in ("none", "pos1", "pos4"))
        bins = np.linspace(0.0, hi, 60)
        for key, label, c in (
            ("none", "no noise", "k"),
            ("pos1", "pos 1", "C3"),
            ("pos4", "pos 4", "C0"),
        ):
            ax.hist(
                np.ravel(data[key][idx]),
                bins=bins,
                density=True,
                histtype="step",
                color=c,
                lw=1.2,
                label=label,
            )
        ax.set_xlabel(f"{title} / µm", fontsize=8)
        ax.set_yticks([])
        ax.set_title(f"Fig. 9: {title}, 5408 points", fontsize=8)
        ax.legend(fontsize=7)
        ax.tick_params(labelsize=7)
    return [save(fig, out, "aguado2016_fig9.png")]


def printed(x: float) -> str:
    """A number of the paper as printed (one decimal, two where it has them)."""
    return f"{x:.1f}" if abs(10 * x - round(10 * x)) < 1e-9 else f"{x:.2f}"


def _pct(new: float, old: float) -> str:
    """The relative change from ``old`` to ``new``, signed, in per cent."""
    return f"{100.0 * (new / old - 1.0):+.1f} %"


def aguado2016_pos4_readings(nb: Numbers) -> str:
    """The sentence on the readings of Table I under which position 4 sees every point.

    Under each of them: where position 3 leaves the elevation limits (below the lower, above
    the upper), whether positions 1 and 2 see, and how far position 4's elevations span.
    """
    s = nb["settings"]["aguado2016"]
    lo, hi = s["elevation_deg"]

    def el(name: str, pos: str) -> tuple[float, float]:
        k = f"reading.{name}.{pos}"
        return v(nb, f"{k}.elevation_min_deg"), v(nb, f"{k}.elevation_max_deg")

    def sees(name: str, pos: str) -> bool:
        a, b = el(name, pos)
        return bool(lo <= a and b <= hi)

    names = [reading_name(q, tr) for q, tr in euler_readings(s["euler"])]
    ok4 = [n for n in names if sees(n, "pos4")]
    low = [n for n in ok4 if el(n, "pos3")[0] < lo]
    high = [n for n in ok4 if el(n, "pos3")[1] > hi]
    all3 = [n for n in ok4 if sees(n, "pos1") and sees(n, "pos2") and sees(n, "pos3")]
    wide = max(ok4, key=lambda n: el(n, "pos4")[1] - el(n, "pos4")[0])
    a4, b4 = el(wide, "pos4")
    return (
        f"Position 4 sees every point under {len(ok4)} of the {len(names)} readings; "
        f"positions 1–3 all see as well under {len(all3)} of them. Position 3 leaves the "
        f"limits below {lo:.0f}° under {len(low)} of the {len(ok4)} and above {hi:.0f}° under "
        f"{len(high)} ({', '.join(f'`{n}`' for n in high)}). Position 4's own elevations "
        f"span up to {b4 - a4:.0f}° under these readings: {a4:.1f}° … {b4:.1f}° under "
        f"`{wide}`."
    )


def aguado2016_tables(nb: Numbers) -> dict[str, str]:
    """The generated blocks of ``aguado2016.md``: Tables I-IV and the analyses beside them."""
    out = {}
    s = nb["settings"]["aguado2016"]
    header = ["", "initial max", "mean", "min", "final max", "mean", "min"]
    extra = ["residual of eq. 17, max / mean / min", "calibration u mean, MC / GUM"]
    for pts in ("mesh96", "cloud96", "mesh5408"):
        paper = AGUADO2016.get((pts, "none"))
        none = [fmt(v(nb, f"{pts}.none.{k}")) for k in STATS]
        rows = [
            ["paper, no noise", *(printed(x) for x in paper)] if paper else None,
            ["mtmc, no noise", *none],
        ]
        if pts == "mesh96":
            out["table1"] = table(header, [r for r in rows if r])
            trows = []
        else:
            trows = [[*r, "—", "—"] for r in rows if r]
        for pos in POSITIONS:
            p = AGUADO2016[(pts, pos)]
            k = f"{pts}.{pos}"
            trows.append([f"paper, {pos}", *(printed(x) for x in p), "—", "—"])
            trows.append(
                [
                    f"mtmc, {pos}: each point's mean",
                    *(fmt(v(nb, f"{k}.point.initial.{x}")) for x in ("max", "mean", "min")),
                    *(fmt(v(nb, f"{k}.point.compensated.{x}")) for x in ("max", "mean", "min")),
                    "—",
                    f"{fmt(v(nb, f'{k}.point_u.mean'))} / {fmt(v(nb, f'{k}.point_u_gum.mean'))}",
                ]
            )
            trows.append(
                [
                    f"mtmc, {pos}: each verification's",
                    *(fmt(v(nb, f"{k}.{x}")) for x in STATS[:3]),
                    *(fmt(v(nb, f"{k}.{x}")) for x in FINAL),
                    " / ".join(fmt(v(nb, f"{k}.{x}")) for x in STATS[3:]),
                    "—",
                ]
            )
        out[f"table.{pts}"] = table(header + extra, trows)
    out["settings"] = (
        f"{s['trials']} verifications per row, seed {s['seed']}; Fig. 9 pools "
        f"{s['fig9_trials']} verifications per position."
    )
    # "final": the compensated error, not the residual of eq. 17
    p_, n3 = v(nb, "fit.parameters"), v(nb, "fit.readings")
    keep = math.sqrt(1.0 - p_ / n3)
    pos4 = AGUADO2016[("mesh96", "pos4")]
    out["final"] = (
        f"The identification fits {p_:.0f} parameters (the tracker's pose among them) to "
        f"{n3:.0f} readings (96 points × 3); a least-squares fit leaves "
        f"√(1 − {p_:.0f}/{n3:.0f}) = {keep:.3f} of the noise in its residual. At pos4 the "
        f"paper's Table II gives {printed(pos4[1])} µm initial and {printed(pos4[4])} µm final "
        f"(mean): as a residual, {printed(pos4[4])} µm would need a noise of at most "
        f"{pos4[4] / keep:.1f} µm, while the initial mean needs one that brings "
        f"{fmt(v(nb, 'mesh96.none.initial.mean'))} µm of machine error to {printed(pos4[1])} µm. "
        f"Ours at pos4: initial {fmt(v(nb, 'mesh96.pos4.initial.mean'))} µm, residual "
        f"{fmt(v(nb, 'mesh96.pos4.residual.mean'))} µm, after compensation "
        f"{fmt(v(nb, 'mesh96.pos4.compensated.mean'))} µm. With more points (Tables II → IV, "
        f"pos4) the paper's final mean goes {printed(pos4[4])} → "
        f"{printed(AGUADO2016[('mesh5408', 'pos4')][4])} µm; ours after compensation "
        f"{fmt(v(nb, 'mesh96.pos4.compensated.mean'))} → "
        f"{fmt(v(nb, 'mesh5408.pos4.compensated.mean'))} µm, our residual "
        f"{fmt(v(nb, 'mesh96.pos4.residual.mean'))} → "
        f"{fmt(v(nb, 'mesh5408.pos4.residual.mean'))} µm."
    )
    t4 = AGUADO2016[("mesh5408", "pos2")]
    out["mixed"] = (
        f"Table IV, pos2: final mean {printed(t4[4])} µm against initial {printed(t4[1])} µm "
        f"(ratio {t4[4] / t4[1]:.2f}), final minimum {printed(t4[5])} µm. Ours on that mesh "
        f"at pos2: residual / initial = {fmt(v(nb, 'mesh5408.pos2.residual.mean'))} / "
        f"{fmt(v(nb, 'mesh5408.pos2.initial.mean'))} µm (ratio "
        f"{v(nb, 'mesh5408.pos2.residual.mean') / v(nb, 'mesh5408.pos2.initial.mean'):.2f}), "
        f"after compensation {fmt(v(nb, 'mesh5408.pos2.compensated.mean'))} µm."
    )
    mx = [AGUADO2016[(p, "pos1")][0] for p in ("mesh96", "cloud96", "mesh5408")]
    out["maxima"] = (
        f"The paper's initial maximum at pos1 is {' / '.join(printed(x) for x in mx)} µm in "
        f"Tables II / III / IV, at pos3 {printed(AGUADO2016[('cloud96', 'pos3')][0])} and "
        f"{printed(AGUADO2016[('mesh5408', 'pos3')][0])} µm and at pos4 "
        f"{printed(AGUADO2016[('cloud96', 'pos4')][0])} and "
        f"{printed(AGUADO2016[('mesh5408', 'pos4')][0])} µm in Tables III and IV. The mean over "
        f"the verifications of each one's maximum grows with the points: ours at pos1 "
        f"{fmt(v(nb, 'mesh96.pos1.initial.max'))} µm (96 points) → "
        f"{fmt(v(nb, 'mesh5408.pos1.initial.max'))} µm (5408 points); the maximum over the "
        f"points of each point's mean error does not: "
        f"{fmt(v(nb, 'mesh96.pos1.point.initial.max'))} → "
        f"{fmt(v(nb, 'mesh5408.pos1.point.initial.max'))} µm."
    )
    # the readings of Table I's angles
    lo, hi = s["elevation_deg"]
    rrows = []
    for seq, tr in euler_readings(s["euler"]):
        name = reading_name(seq, tr)
        cells, seen = [], 0
        for pos in POSITIONS:
            k = f"reading.{name}.{pos}"
            a, b = v(nb, f"{k}.elevation_min_deg"), v(nb, f"{k}.elevation_max_deg")
            ok = lo <= a and b <= hi
            seen += ok
            cells.append(f"{a:.1f} … {b:.1f}{'' if ok else ' ✗'} ({v(nb, f'{k}.tilt_deg'):.0f}°)")
        label = "extrinsic" if seq.islower() else "intrinsic"
        note = " (the study's)" if (seq, tr) == (s["euler"], False) else ""
        note = " (before)" if (seq, tr) == (AGUADO2016_OLD_EULER, False) else note
        rrows.append([f"`{name}`{note}", label, *cells, str(seen)])
    out["readings"] = table(["reading", "", *POSITIONS, "positions seen"], rrows)
    out["readings_pos4"] = aguado2016_pos4_readings(nb)
    crows = []
    for pos in POSITIONS:
        row = [pos]
        for name in ("initial.mean", "residual.mean", "compensated.mean"):
            old, new = v(nb, f"mesh96.{pos}.old.{name}"), v(nb, f"mesh96.{pos}.{name}")
            row.append(f"{fmt(old)} → {fmt(new)} ({_pct(new, old)})")
        crows.append(row)
    out["reading_change"] = table(
        [
            f"mesh of 96, `{AGUADO2016_OLD_EULER}` → `{s['euler']}`",
            "initial mean / µm",
            "residual mean / µm",
            "after compensation, mean / µm",
        ],
        crows,
    )
    e, o = s["euler"], AGUADO2016_OLD_EULER
    out["reading_summary"] = (
        f"Under `{e}`, position 4 is tilted {v(nb, f'reading.{e}.pos4.tilt_deg'):.0f}° from "
        f"upright, the least of the four, and sees the points between "
        f"{v(nb, f'reading.{e}.pos4.elevation_min_deg'):.1f}° and "
        f"{v(nb, f'reading.{e}.pos4.elevation_max_deg'):.1f}°; under `{o}` its beam goes down "
        f"to {v(nb, f'reading.{o}.pos4.elevation_min_deg'):.1f}°. Position 3, "
        f"{v(nb, 'distance.pos3.min_m'):.2f} m from the nearest of the 96 points, reaches "
        f"{v(nb, f'reading.{e}.pos3.elevation_min_deg'):.1f}° under `{e}`."
    )

    def change(pos: str, name: str) -> float:
        return 100.0 * (v(nb, f"mesh96.{pos}.{name}") / v(nb, f"mesh96.{pos}.old.{name}") - 1.0)

    others = ("residual.mean", "compensated.mean")
    out["reading_change_summary"] = (
        f"The initial means change by at most "
        f"{max(abs(change(p, 'initial.mean')) for p in POSITIONS[:3]):.1f} % at positions 1–3 "
        f"and by {change('pos4', 'initial.mean'):+.1f} % at position 4, where the paper's "
        f"Table II gives {printed(AGUADO2016[('mesh96', 'pos4')][1])} µm; the residual and the "
        f"error after compensation by at most "
        f"{max(abs(change(p, n)) for p in POSITIONS for n in others):.1f} %."
    )
    d = [v(nb, f"distance.{p}.{k}_m") for p in ("pos1", "pos2") for k in ("min", "max")]
    out["distances"] = (
        f"Positions 1 and 2 stand {min(d):.2f} to {max(d):.2f} m from the 96 points, where "
        f"{AGUADO2016_ANGLE_URAD:g} µrad on an angle (§5) moves a reading by "
        f"{AGUADO2016_ANGLE_URAD * min(d):.0f} to {AGUADO2016_ANGLE_URAD * max(d):.0f} µm "
        f"across the beam:"
    )
    irows = []
    for pos in POSITIONS:
        a, b = v(nb, f"distance.{pos}.min_m"), v(nb, f"distance.{pos}.max_m")
        irows.append(
            [
                pos,
                f"{a:.2f} … {b:.2f}",
                f"{AGUADO2016_ANGLE_URAD * a:.0f} … {AGUADO2016_ANGLE_URAD * b:.0f}",
                printed(AGUADO2016[("mesh96", pos)][1]),
                fmt(v(nb, f"mesh96.{pos}.initial.mean")),
                fmt(v(nb, f"implied.{pos}.angle_urad")),
            ]
        )
    out["implied"] = table(
        [
            "",
            "distance to the 96 points / m",
            f"{AGUADO2016_ANGLE_URAD:g} µrad × distance / µm",
            "paper's initial mean (Table II) / µm",
            f"ours at {AGUADO2016_ANGLE_URAD:g} µrad / µm",
            "angular noise that gives the paper's / µrad",
        ],
        irows,
    )
    return out


# ---------------------------------------------------------------------------- Wang et al.

#: Wang, Cheung and Kong 2022 Table 2, keyed by the printed (b, c) in degrees (the paper's
#: sign of b; mtmc's b is the negative): measured r_max, r_avg, model r_max, r_avg (µm).
WANG2022_T2 = {
    (0, 0): (0.9, 0.4, 0.8, 0.4),
    (0, 5): (5.5, 1.3, 5.1, 1.2),
    (0, -5): (5.4, 1.1, 5.3, 1.1),
    (5, 0): (1.1, 0.6, 0.8, 0.4),
    (5, 5): (5.6, 1.6, 5.5, 1.5),
    (5, -5): (5.7, 1.4, 5.4, 1.5),
    (10, 0): (1.6, 0.6, 1.3, 0.8),
    (10, 5): (6.8, 2.3, 6.2, 2.0),
    (10, -5): (6.4, 2.2, 6.1, 1.8),
}
#: Table 3: per sphere, the residuals x, y, z after the best fit (µm); Fig. 7: mean 4.5 µm.
WANG2022_T3 = ((0.4, 0.9, 0.2), (0.5, 0.8, 0.4), (0.7, 0.8, 0.3), (0.7, 1.0, 0.3), (0.6, 0.7, 0.2))
WANG2022_FIG7 = 4.5
#: §2.3: "the Cartesian repeatability ranges contributed by the pooled standard deviation"
#: (x, y, z, µm), and "the best fitted standard deviations of the sphere center coordinates".
WANG2022_REPEAT = (0.36, 0.41, 0.25)
WANG2022_CENTRE_SD = (0.18, 0.21, 0.24)


def _wang2022_paper_b(b_deg: float) -> int:
    """The paper's printed b of one of our poses (ISO 841: the paper's b is our -b)."""
    return round(-b_deg) + 0  # + 0: no "-0"


def _wang2022_noise_free(study: Any, errors: Mapping[str, Any], setup: Any) -> tuple[Any, Any, Any]:
    """Noise-free ① ``r_max``, ``r_avg`` per pose (µm) and the distance errors (P, 10), µm."""
    from mtmc.artefact.analysis import analyse

    s = study.setup
    meas = s.measure(study.poses, errors, setup, free_radius=study.free_radius)
    pinv = np.linalg.pinv(s.setup_jacobian(study.poses))
    a = analyse(
        meas.centres[None, None], s.artefact.mounted_centres(), pinv, s.probe_jacobian(study.poses)
    )
    P = study.poses.shape[0]
    return (
        a.r_max_measured[0] * 1e3,
        a.r_avg_measured[0] * 1e3,
        a.distance_error_measured[0].reshape(P, -1) * 1e3,
    )


def _wang2022_row_floor(study: Any, plane: bool = True) -> tuple[float, float]:
    """The least ``r_avg / r_max`` of one row of balls shifted against the other.

    The balls of Table 1 stand in two rows along y (1, 2 at y ≈ 0; 3, 4, 5 at y ≈ 60 mm):
    a displacement ``δ`` of one row against the other changes the distance ``ij`` of a pair
    across the rows by ``δ · u_ij``. Over the directions of ``δ`` in the artefact's xy plane
    (0.01° steps), or with ``plane=False`` over every direction in space (0.1° steps of
    azimuth and of polar angle), the least mean over the 10 pairs of ``|δ · u_ij|`` over its
    maximum; and ``|δ_z|`` of the direction that gives it.
    """
    c = np.asarray(study.setup.artefact.centres, dtype=np.float64)
    row = (c[:, 1] > 0.5 * (c[:, 1].min() + c[:, 1].max())).astype(np.float64)
    i, j = np.triu_indices(len(c), 1)
    u = (c[j] - c[i]) / np.linalg.norm(c[j] - c[i], axis=1)[:, None]
    across = (row[j] - row[i])[:, None] * u  # (10, 3); 0 for pairs within a row
    if plane:
        th = np.radians(np.arange(0.0, 180.0, 0.01))
        d = np.stack([np.cos(th), np.sin(th), np.zeros_like(th)], axis=1)
    else:
        az, po = np.meshgrid(
            np.radians(np.arange(0.0, 180.0, 0.1)), np.radians(np.arange(0.0, 180.1, 0.1))
        )
        az, po = az.ravel(), po.ravel()
        d = np.stack([np.sin(po) * np.cos(az), np.sin(po) * np.sin(az), np.cos(po)], axis=1)
    r = np.abs(d @ across.T)  # (directions, 10)
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.where(r.max(axis=1) > 0, r.mean(axis=1) / r.max(axis=1), np.inf)
    k = int(np.argmin(share))
    return float(share[k]), float(abs(d[k, 2]))


def _wang2022_centre_sd(study: Any) -> dict[str, Any]:
    """§2.3's two readings: the centre s.d. of the study's 30-point fit, both ways (µm)."""
    from mtmc.artefact.probing import fit_sensitivity, patch_points

    art = study.setup.artefact
    pts = patch_points(np.zeros(3), art.radius, (0.0, 0.0, 1.0), study.setup.offsets)
    out: dict[str, Any] = {}
    var_point = np.tile(np.square(WANG2022_REPEAT), len(pts))
    for radius, free in (("cal", False), ("free", True)):
        K = fit_sensitivity(pts, np.zeros(3), free)[0]  # (3, 3n): d centre / d points
        sd = np.sqrt((K * K) @ var_point)
        iso = np.sqrt((K * K).sum(axis=1))  # centre s.d. per unit isotropic point s.d.
        for a, ax in enumerate("xyz"):
            out[f"rep.point.{radius}.{ax}"] = exact(sd[a])
            out[f"rep.iso.{radius}.{ax}"] = exact(WANG2022_CENTRE_SD[a] / iso[a])
    return out


def _wang2022_gum_tolerance(res: Any) -> tuple[float, str]:
    """The reproducibility of the artefact's GUM u across BLAS kernels (µm), and why.

    ``r_max`` is not analytic (a maximum of norms), so the sensitivities are central
    differences with the step ``h_j = 1e-3 u_j`` (:func:`mtmc.uncertainty.gum`). Each
    difference is of outputs computed from ball centres of size ``L`` (mm) through GEMMs
    whose order of summation depends on the BLAS kernel: a rounding of ``EPS·L`` in each,
    so ``|δc_j| ≤ EPS·L/(2 h_j)`` and ``|δu| ≤ √N · max_j |δc_j| u_j = 500·EPS·L·√N`` over
    the ``N`` input components.
    """
    budget = next(iter(res.gum.values())).result.budget
    n_inputs = sum(np.asarray(e.u).size for e in budget)
    big_l = float(np.abs(np.asarray(res.measurement.centres)).max())
    tol = 1e3 * 500.0 * EPS * big_l * math.sqrt(n_inputs)
    why = (
        f"central differences (h = 1e-3 u) of outputs of {big_l:.0f} mm centres through "
        f"BLAS, {n_inputs} inputs: 500 EPS L sqrt(N)"
    )
    return tol, why


def wang2022(scale: float = 1.0) -> tuple[Numbers, dict[str, Any]]:
    """Wang, Cheung and Kong 2022: Table 2, Table 3 and Fig. 7 of the shipped study.

    Also: the noise-free Table 2 ① with each chosen machine error alone (what drives each
    row), the share of ``r_avg`` in ``r_max``, §2.3's two readings of the probing
    repeatability, Table 2 ① under the second one and without the CMM's uncertainty, and
    the identified setup errors.
    """
    from dataclasses import replace

    from mtmc.artefact.simulation import simulate_artefact

    kind = load("wang2022")
    study = kind.study
    n = max(200, int(kind.settings.trials * scale))
    seed = kind.settings.seed
    res = simulate_artefact(study, trials=n, seed=seed)
    j = res.to_json()
    gum_tol = _wang2022_gum_tolerance(res)
    values: dict[str, Any] = {}
    keys = []
    for pose in j["poses"]:
        b, c = _wang2022_paper_b(pose["b_deg"]), round(pose["c_deg"])
        keys.append(f"[{b},{c}]")
        for key in ("r_max_um", "r_avg_um", "r_max_model_um", "r_avg_model_um"):
            e = pose[key]
            k = f"t2[{b},{c}].{key[:-3]}"
            values[f"{k}.noise_free"] = exact(e["noise_free"])
            values[f"{k}.mc"] = mc(e["estimate"], e["u"], n)
            values[f"{k}.mc_u"] = mc(e["u"], e["u"] / math.sqrt(2.0), n)
            values[f"{k}.gum_u"] = exact(e["gum_u"], *gum_tol)
    # what drives each row: every chosen machine error alone, and the setup errors alone
    zero = np.zeros_like(study.setup_errors)
    alone = {name: ({name: f}, zero) for name, f in study.errors.items()}
    alone["setup"] = ({}, study.setup_errors)
    for name, (errs, setup) in alone.items():
        rm, ra, _ = _wang2022_noise_free(study, errs, setup)
        for p, k in enumerate(keys):
            values[f"drive.{name}{k}.r_max"] = exact(rm[p])
            values[f"drive.{name}{k}.r_avg"] = exact(ra[p])
    # r_avg against r_max: what turning C adds to the distance errors, and the least share
    # a shift of one row of balls against the other can give
    _, _, dist = _wang2022_noise_free(study, study.errors, study.setup_errors)
    c_deg = np.round(np.degrees(study.poses[:, 1]))
    for p, k in enumerate(keys):
        if c_deg[p] != 0:
            ref = next(
                q
                for q in range(len(keys))
                if c_deg[q] == 0 and study.poses[q, 0] == study.poses[p, 0]
            )
            dr = np.abs(dist[p] - dist[ref])
            values[f"share{k}.c_part"] = exact(dr.mean() / dr.max())
    values["share.row_floor"] = exact(_wang2022_row_floor(study)[0])
    floor3, z3 = _wang2022_row_floor(study, plane=False)
    values["share.row_floor_3d"] = exact(floor3)
    values["share.row_floor_3d_z"] = exact(z3)
    # §2.3 read two ways
    values.update(_wang2022_centre_sd(study))
    um = 1e-3
    other = replace(
        study,
        repeatability=np.zeros(3),
        machine_repeatability=np.asarray(WANG2022_CENTRE_SD) * um,
    )
    res_b = simulate_artefact(other, trials=n, seed=seed, gum_too=False)
    for pose, k in zip(res_b.to_json()["poses"], keys, strict=True):
        for key in ("r_max_um", "r_avg_um"):
            e = pose[key]
            values[f"t2centre{k}.{key[:-3]}.mc"] = mc(e["estimate"], e["u"], n)
            values[f"t2centre{k}.{key[:-3]}.mc_u"] = mc(e["u"], e["u"] / math.sqrt(2.0), n)
    res_p = simulate_artefact(replace(study, cmm=False), trials=n, seed=seed, gum_too=False)
    for pose, k in zip(res_p.to_json()["poses"], keys, strict=True):
        for key in ("r_max_um", "r_avg_um"):
            e = pose[key]
            values[f"t2probing{k}.{key[:-3]}.mc"] = mc(e["estimate"], e["u"], n)
            values[f"t2probing{k}.{key[:-3]}.mc_u"] = mc(e["u"], e["u"] / math.sqrt(2.0), n)
    for name, e in j["setup_errors"].items():
        values[f"setup.{name}.injected"] = exact(e["injected"])
        values[f"setup.{name}.noise_free"] = exact(e["noise_free"])
        values[f"setup.{name}.mc"] = mc(e["estimate"], e["u"], n)
        values[f"setup.{name}.gum_u"] = exact(e["gum_u"], *gum_tol)
    t3 = np.asarray(j["table3_um"], dtype=np.float64)
    t3_mean = np.asarray(res.mc_mean["table3"]).reshape(t3.shape) * 1e3
    t3_u = np.asarray(res.mc_u["table3"]).reshape(t3.shape) * 1e3
    for i in range(t3.shape[0]):
        for a, ax in enumerate("xyz"):
            values[f"t3[{i + 1}].{ax}.noise_free"] = exact(t3[i, a])
            values[f"t3[{i + 1}].{ax}.mc"] = mc(t3_mean[i, a], t3_u[i, a], n)
    vol = np.linalg.norm(np.asarray(j["volumetric_um"]), axis=-1)
    values["fig7.mean_um"] = exact(j["volumetric_mean_um"])
    values["fig7.max_um"] = exact(vol.max())
    settings = {"trials": n, "seed": seed, "errors": list(study.errors)}
    return {"settings": {"wang2022": settings}, "values": values}, {"res": res}


def wang2022_figures(data: dict[str, Any], out: Path) -> list[Path]:
    """Fig. 7: the error vectors at the balls, magnified 10 000 times (the library's plot)."""
    from mtmc.artefact.plot import plot_error_vectors

    out.mkdir(parents=True, exist_ok=True)
    import matplotlib

    with matplotlib.rc_context({"figure.dpi": 80, "savefig.dpi": 80}):
        path = plot_error_vectors(data["res"], out / "wang2022_fig7.png")
    return [path]


def wang2022_order(
    ours: Mapping[tuple[int, int], float], u: Mapping[tuple[int, int], float], col: int
) -> tuple[int, int, int]:
    """Pairs of Table 2's poses ordered as the paper orders them: (agreeing, pairs, ties).

    One rule for ties: a pair whose printed column ``col`` (0: ① ``r_max``, 1: ① ``r_avg``)
    differs by no more than the combined standard uncertainty of our Monte Carlo,
    ``√(u_p² + u_q²)`` from ``u``, is a tie and not counted (a printed difference of 0.1 µm
    always is: every combined u is above it). ``ours`` and ``u`` keyed by the paper's (b, c).
    """
    poses = list(WANG2022_T2)
    agree = total = ties = 0
    for i, p in enumerate(poses):
        for q in poses[i + 1 :]:
            d = WANG2022_T2[p][col] - WANG2022_T2[q][col]
            if abs(d) <= math.hypot(u[p], u[q]):
                ties += 1
                continue
            total += 1
            agree += d * (ours[p] - ours[q]) > 0
    return agree, total, ties


def _wang2022_pattern(nb: Numbers) -> str:
    """The sentence on the pattern of Table 2 ①: pairs of poses ordered as the paper's."""
    parts = []
    for col, name in ((0, "r_max"), (1, "r_avg")):
        u = {bc: v(nb, f"t2[{bc[0]},{bc[1]}].{name}.mc_u") for bc in WANG2022_T2}
        counts = []
        for kind in ("noise_free", "mc"):
            ours = {bc: v(nb, f"t2[{bc[0]},{bc[1]}].{name}.{kind}") for bc in WANG2022_T2}
            counts.append(wang2022_order(ours, u, col))
        parts.append(
            f"`{name}`: {counts[0][2]} ties; of the other {counts[0][1]} pairs, "
            f"{counts[0][0]} ordered alike noise-free and {counts[1][0]} as MC means"
        )
    n = len(WANG2022_T2) * (len(WANG2022_T2) - 1) // 2
    return (
        f"Of the {n} pairs of poses, a pair whose printed ① values differ by no more than the "
        "combined u of our Monte Carlo, √(u₁² + u₂²), is a tie; the others, ordered as the "
        "paper orders them: " + "; ".join(parts) + "."
    )


def wang2022_tables(nb: Numbers) -> dict[str, str]:
    """The generated tables of ``wang2022.md``."""
    s = nb["settings"]["wang2022"]

    def pair(k: str, a: str = "r_max", b: str = "r_avg", nd: int = 2) -> str:
        return f"{fmt(v(nb, f'{k}.{a}'), nd)} / {fmt(v(nb, f'{k}.{b}'), nd)}"

    def mcu(k: str) -> str:
        return f"{fmt(v(nb, f'{k}.mc'), 2)} ± {fmt(v(nb, f'{k}.mc_u'), 2)}"

    rows = []
    for (b, c), p in WANG2022_T2.items():
        k = f"t2[{b},{c}]"
        rows.append(
            [
                f"{b}°",
                f"{-b + 0}°",
                f"{c}°",
                f"{p[0]:.1f} / {p[1]:.1f}",
                pair(k, "r_max.noise_free", "r_avg.noise_free"),
                f"{mcu(f'{k}.r_max')} / {mcu(f'{k}.r_avg')}",
                pair(k, "r_max.gum_u", "r_avg.gum_u"),
                f"{p[2]:.1f} / {p[3]:.1f}",
                pair(k, "r_max_model.noise_free", "r_avg_model.noise_free"),
            ]
        )
    t2 = table(
        [
            "b (paper)",
            "b (mtmc)",
            "c",
            "paper ① r_max / r_avg",
            "mtmc ① noise-free",
            "mtmc ① MC mean ± u",
            "mtmc ① GUM u",
            "paper ② r_max / r_avg",
            "mtmc ② noise-free",
        ],
        rows,
    )
    names = [*s["errors"], "setup"]
    rows = []
    for (b, c), p in WANG2022_T2.items():
        k = f"[{b},{c}]"
        rows.append(
            [
                f"{b}°, {c}°",
                f"{p[0]:.1f} / {p[1]:.1f}",
                pair(f"t2{k}", "r_max.noise_free", "r_avg.noise_free"),
            ]
            + [pair(f"drive.{n}{k}") for n in names]
        )
    drive = table(
        ["b, c (paper)", "paper ①", "all"]
        + [f"{n} alone" for n in s["errors"]]
        + ["setup errors alone"],
        rows,
    )
    rows = []
    for (b, c), p in WANG2022_T2.items():
        if c == 0:
            continue
        k = f"[{b},{c}]"
        rows.append(
            [
                f"{b}°, {c}°",
                f"{p[1] / p[0]:.2f}",
                fmt(v(nb, f"t2{k}.r_avg.mc") / v(nb, f"t2{k}.r_max.mc"), 2),
                fmt(v(nb, f"share{k}.c_part"), 2),
                fmt(v(nb, f"t2{k}.r_avg.mc") / p[1], 2),
            ]
        )
    share = table(
        [
            "b, c (paper)",
            "paper r_avg / r_max",
            "mtmc r_avg / r_max (MC means)",
            "mtmc, the part C adds",
            "mtmc r_avg / paper r_avg",
        ],
        rows,
    )
    share += (
        "\n\nThe least `r_avg / r_max` that a shift of one row of balls against the other, "
        f"in the artefact's plane, can give: {fmt(v(nb, 'share.row_floor'), 2)}. Over every "
        f"direction in space: {fmt(v(nb, 'share.row_floor_3d'), 2)}, for a shift "
        f"{fmt(v(nb, 'share.row_floor_3d_z'), 3)} of whose unit direction lies along z, "
        "out of the artefact's plane."
    )
    rows = [
        [
            "printed: the best-fit centre s.d.",
            " / ".join(f"{x:.2f}" for x in WANG2022_CENTRE_SD),
            "—",
        ],
        [
            "per-point s.d. (0.36 / 0.41 / 0.25), calibrated radius (the study)",
            " / ".join(fmt(v(nb, f"rep.point.cal.{a}"), 2) for a in "xyz"),
            "—",
        ],
        [
            "per-point s.d. (0.36 / 0.41 / 0.25), free radius",
            " / ".join(fmt(v(nb, f"rep.point.free.{a}"), 2) for a in "xyz"),
            "—",
        ],
        [
            "isotropic per-point s.d. that gives the printed centre s.d., calibrated radius",
            " / ".join(f"{x:.2f}" for x in WANG2022_CENTRE_SD),
            " / ".join(fmt(v(nb, f"rep.iso.cal.{a}"), 2) for a in "xyz"),
        ],
        [
            "the same, free radius",
            " / ".join(f"{x:.2f}" for x in WANG2022_CENTRE_SD),
            " / ".join(fmt(v(nb, f"rep.iso.free.{a}"), 2) for a in "xyz"),
        ],
    ]
    repeat = table(["reading (§2.3)", "centre s.d. x / y / z", "per-point s.d. x / y / z"], rows)
    rows = []
    for (b, c), p in WANG2022_T2.items():
        k = f"[{b},{c}]"
        rows.append(
            [
                f"{b}°, {c}°",
                f"{p[0]:.1f} / {p[1]:.1f}",
                f"{mcu(f't2{k}.r_max')} / {mcu(f't2{k}.r_avg')}",
                f"{mcu(f't2centre{k}.r_max')} / {mcu(f't2centre{k}.r_avg')}",
                f"{mcu(f't2probing{k}.r_max')} / {mcu(f't2probing{k}.r_avg')}",
            ]
        )
    t2centre = table(
        [
            "b, c (paper)",
            "paper ①",
            "mtmc ①, per-point reading (the study)",
            "mtmc ①, centre reading",
            "mtmc ①, per-point reading, CMM calibration exact",
        ],
        rows,
    )
    rows = []
    for name in (
        k[len("setup.") : -len(".injected")]
        for k in nb["values"]
        if k.startswith("setup.") and k.endswith(".injected")
    ):
        k = f"setup.{name}"
        rows.append(
            [
                name,
                fmt(v(nb, f"{k}.injected"), 2),
                fmt(v(nb, f"{k}.noise_free"), 3),
                f"{fmt(v(nb, f'{k}.mc'), 3)} ± {fmt(nb['values'][f'{k}.mc']['sd'], 3)}",
                fmt(v(nb, f"{k}.gum_u"), 3),
            ]
        )
    setup = table(["name", "injected", "identified, noise-free", "MC mean ± u", "GUM u"], rows)
    rows = []
    for i, p3 in enumerate(WANG2022_T3):
        k = f"t3[{i + 1}]"
        rows.append(
            [
                str(i + 1),
                " / ".join(f"{x:.1f}" for x in p3),
                " / ".join(fmt(v(nb, f"{k}.{a}.noise_free"), 2) for a in "xyz"),
                ", ".join(fmt(v(nb, f"{k}.{a}.mc"), 2) for a in "xyz"),
            ]
        )
    t3 = table(
        ["sphere", "paper x / y / z", "mtmc noise-free x / y / z", "mtmc MC mean x, y, z"], rows
    )
    fig7 = (
        f"Mean length of the 45 error vectors: paper {WANG2022_FIG7:.1f} µm, mtmc "
        f"{fmt(v(nb, 'fig7.mean_um'), 2)} µm (largest {fmt(v(nb, 'fig7.max_um'), 2)} µm)."
    )
    head = f"{s['trials']} trials, seed {s['seed']}; µm."
    return {
        "settings": head,
        "table2": t2,
        "pattern": _wang2022_pattern(nb),
        "drivers": drive,
        "share": share,
        "repeatability": repeat,
        "table2_centre": t2centre,
        "setup": setup,
        "table3": t3,
        "fig7": fig7,
    }


# ---------------------------------------------------------------------------- driver

Case = tuple[
    Callable[[float], tuple[Numbers, dict[str, Any]]],
    Callable[[dict[str, Any], Path], list[Path]],
    Callable[[Numbers], dict[str, str]],
]

CASES: dict[str, Case] = {
    "stryczek": (stryczek, stryczek_figures, stryczek_tables),
    "aguado2017": (aguado2017, aguado2017_figures, aguado2017_tables),
    "aguado2016": (aguado2016, aguado2016_figures, aguado2016_tables),
    "wang2022": (wang2022, wang2022_figures, wang2022_tables),
}

_BLOCK = re.compile(r"(<!-- generated: (\S+) -->\n)(.*?)(^<!-- end generated -->)", re.S | re.M)


def fill(text: str, blocks: Mapping[str, str]) -> str:
    """``text`` with every generated block replaced by ``blocks[KEY]``.

    Raises
    ------
    KeyError
        A block of the text that ``blocks`` lacks.
    """

    def sub(m: re.Match[str]) -> str:
        return m.group(1) + blocks[m.group(2)].rstrip("\n") + "\n" + m.group(4)

    return _BLOCK.sub(sub, text)


def blocks(name: str, numbers: Numbers) -> dict[str, str]:
    """Every generated block of a tutorial: its tables and the shipped studies it shows.

    A block ``study:STEM`` is the file ``examples/studies/STEM.toml`` as a TOML code block.
    """
    _, _, tables = CASES[name]
    out = dict(tables(numbers))
    text = (HERE / f"{name}.md").read_text(encoding="utf-8")
    for key in re.findall(r"<!-- generated: study:(\S+) -->", text):
        body = (STUDIES / f"{key}.toml").read_text(encoding="utf-8")
        out[f"study:{key}"] = f"```toml\n{body.rstrip()}\n```"
    return out


def read_numbers(name: str) -> Numbers:
    """The committed numbers of a tutorial."""
    result: Numbers = json.loads((NUMBERS / f"{name}.json").read_text(encoding="utf-8"))
    return result


def main(argv: list[str] | None = None) -> int:
    """Run the cases and write figures, numbers and tables (or ``--check`` the tables)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="*", help=f"of {sorted(CASES)} (default all)")
    ap.add_argument("--check", action="store_true", help="only check the tables are current")
    args = ap.parse_args(argv)
    stale = []
    for name in args.cases or list(CASES):
        run, figures, _ = CASES[name]
        md = HERE / f"{name}.md"
        if args.check:
            text = md.read_text(encoding="utf-8")
            if fill(text, blocks(name, read_numbers(name))) != text:
                stale.append(name)
            continue
        numbers, data = run(1.0)
        NUMBERS.mkdir(parents=True, exist_ok=True)
        (NUMBERS / f"{name}.json").write_text(json.dumps(numbers, indent=1) + "\n")
        for p in figures(data, FIGURES):
            print(f"{p.relative_to(ROOT)}: {p.stat().st_size // 1024} kB")
        md.write_text(
            fill(md.read_text(encoding="utf-8"), blocks(name, numbers)),
            encoding="utf-8",
        )
        print(f"{md.relative_to(ROOT)}: tables written")
    if stale:
        print("stale tables: " + ", ".join(stale), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
