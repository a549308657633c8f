"""Worked examples on built-in defaults, printed as tables (``python -m mtmc.demo``).

The demo tells one story, from the reference case of JCGM 101 to a five-axis machine:

1. ``mass-calibration``: JCGM 101 §9.3, Monte Carlo and GUM beside the published values.
2. ``ball-centre``: the centre of a calibration ball from 4 + 1 probed points (seed 000
   Fig. 5-6), its Monte Carlo uncertainty beside the closed form of the probe model.
3. ``rotary-axes``: the rotary axes C and A from three ball positions each (seed 000
   eqs. 8-19), location and direction with Monte Carlo and GUM uncertainties, and the
   95 % coverage ellipse of the axis location in the plane normal to the axis (JCGM 102).
4. ``bcs-origin``: the A-C distance d_AC and the origin of the base coordinate system
   (seed 000 eq. 30, Fig. 12-13), Monte Carlo against the GUM with the JCGM 101 §8
   validation, then the σ_probe × σ_machine sweep of Fig. 14 with the surrogate of eq. 31.
5. ``five-axis``: a five-axis table-table machine (``wCAXfYZt``) with uncertain ISO 230-1
   and ISO 230-7 geometric errors propagated by Monte Carlo through the forward
   kinematics at several rotary poses, beside the linear GUM ``u = sqrt(J U Jᵀ)`` from
   the analytic Jacobian and the §8 validation.

Every number printed also goes to ``results.json`` in the output folder (``--out``,
default ``mtmc-demo/``), with the seed, the trials, the inputs, the mtmc version and the
date, beside drawings (``ball_centre.svg``, ``bcs_origin.svg``, ``machine.svg``) and
plots (``d_ac_histogram.png``, ``sweep.png``); each file is written atomically
(:mod:`mtmc.io`). The graphs are the package's copies of ``examples/graphs/*.toml``
(``mtmc/data/graphs``), so the demo runs from an installed package.

Run ``python -m mtmc.demo --trials 200000 --seed 7`` to change the number of trials or
the seed; ``--section NAME`` runs one section, ``--quick`` runs with few trials.
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from rich.console import Console
from rich.table import Table

from mtmc.graph.model import Graph
from mtmc.uncertainty.distributions import Distribution, Normal, Uniform
from mtmc.uncertainty.expression import Expression, expression
from mtmc.uncertainty.gum import gum, validate
from mtmc.uncertainty.montecarlo import monte_carlo

__all__ = [
    "DemoOptions",
    "FIVE_AXIS_ERRORS",
    "FIVE_AXIS_MACHINE",
    "FIVE_AXIS_POSES",
    "GRAPH_FILES",
    "SECTIONS",
    "SWEEP_GRID",
    "ball_centre",
    "bcs_origin",
    "demo_graph",
    "five_axis",
    "five_axis_model",
    "fmt",
    "main",
    "mass_calibration",
    "mass_calibration_inputs",
    "mass_calibration_model",
    "rotary_axes",
]

#: µm per mm and µrad per rad: the machine-tool results are printed in µm and µrad.
UM = 1e3
URAD = 1e6

#: The graph files shipped with the package (copies of ``examples/graphs``).
GRAPH_FILES: tuple[str, ...] = ("ball_centre.toml", "axis_c.toml", "axis_a.toml", "bcs_origin.toml")


@dataclass(frozen=True)
class DemoOptions:
    """Settings shared by every section.

    Attributes
    ----------
    trials : int
        Monte Carlo trials of the mass calibration (JCGM 101 §9 uses 10⁶).
    graph_trials : int
        Monte Carlo trials of the machine-tool sections (2 to 5).
    sweep_trials : int
        Trials per grid point of the Fig. 14 sweep (seed 000: 1000).
    seed : int
        Seed of every Monte Carlo run; printed with the results so they can be repeated.
    out : pathlib.Path or None
        Folder for the drawings and plots (None: write none).
    """

    trials: int = 10**6
    graph_trials: int = 10**6
    sweep_trials: int = 1000
    seed: int = 101
    out: Path | None = None


def fmt(x: float) -> str:
    """The demo's number format: six significant digits (``f"{x:.6g}"``)."""
    return f"{x:.6g}"


def _f4(x: float) -> str:
    """Four significant digits, for µm and µrad tables."""
    return f"{x:.4g}"


def _mm(x: float) -> str:
    """A length in mm to 1 nm (six decimals): the resolution of the µm tables."""
    text = f"{x:.6f}"
    return text.lstrip("-") if float(text) == 0.0 else text


def _unit(x: float) -> str:
    """A component of a unit vector to 10⁻⁹ (1 nrad)."""
    text = f"{x:.9f}"
    return text.lstrip("-") if float(text) == 0.0 else text


def _table(title: str, *columns: str) -> Table:
    table = Table(title=title, title_justify="left")
    for i, col in enumerate(columns):
        table.add_column(col, justify="left" if i == 0 else "right")
    return table


def _json(obj: Any) -> Any:
    """``obj`` with NumPy arrays and scalars turned into plain Python values."""
    if isinstance(obj, dict):
        return {str(k): _json(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_json(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _json(obj.tolist())
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def _mc_rel_tolerance(trials: int) -> float:
    """Relative standard error of a Monte Carlo standard deviation, ``1/sqrt(2(M-1))``.

    For a normal output the sample standard deviation of ``M`` values has a relative
    standard deviation of about ``1/sqrt(2(M - 1))``; the tables quote it so that the
    agreement of Monte Carlo with a closed form can be judged.
    """
    return 1.0 / math.sqrt(2.0 * (trials - 1))


def _endpoint_std_error(u: float, trials: int, p: float = 0.95) -> float:
    """Standard error of an endpoint of a Monte Carlo 100p % interval of a normal output.

    The ``α = (1 - p)/2`` quantile of ``M`` draws from a PDF ``g`` has the asymptotic
    variance ``α(1 - α) / (M g(η_α)²)`` (order statistics); for a normal output of
    standard deviation ``u``, ``g(η_α) = φ(z_α)/u``. The JCGM 101 §8 comparison is only
    as sharp as this: where it is not small beside δ, a ``no`` may be Monte Carlo noise
    (run with more trials).
    """
    from scipy.stats import norm

    a = (1.0 - p) / 2.0
    return u * math.sqrt(a * (1.0 - a) / trials) / float(norm.pdf(norm.ppf(a)))


def _clean(x: float) -> float:
    """``x`` rounded to 10⁻⁹ (mm): nominal positions without rounding noise (-1e-16)."""
    return round(float(x), 9) + 0.0


def _probe_record(graph: Graph) -> dict[str, Any]:
    """The probe settings of a graph in µm, for ``results.json``."""
    p = graph.probe
    f = graph.factor * UM
    return {"u_axis_um": p.u_axis * f, "u_probe_um": p.u_probe * f, "u_perp_um": p.u_perp * f}


def demo_graph(name: str) -> Graph:
    """Load one of the package's example graphs (``mtmc/data/graphs/NAME``).

    Parameters
    ----------
    name : str
        A file of :data:`GRAPH_FILES`, e.g. ``"ball_centre.toml"``.

    Returns
    -------
    Graph
        The checked graph, its ``file`` set to ``name``.
    """
    from mtmc.graph.toml_format import loads

    text = resources.files("mtmc").joinpath("data", "graphs", name).read_text(encoding="utf-8")
    return loads(text, file=name)


# ---------------------------------------------------------------------------------------
# 1. JCGM 101 §9.3


def mass_calibration_model() -> Expression:
    """JCGM 101 §9.3 model, in mg: the weight's conventional mass minus 100 g.

    ``δm = (m_R,c + δm_R,c) (1 + (ρ_a - ρ_a0)(1/ρ_W - 1/ρ_R)) - m_nom`` with
    ``ρ_a0 = 1.2 kg/m³`` and ``m_nom = 100 000 mg``.

    Returns
    -------
    Expression
    """
    return expression("(m_rc + dm_rc) * (1 + (rho_a - 1.2) * (1 / rho_w - 1 / rho_r)) - 100000")


def mass_calibration_inputs() -> dict[str, Distribution]:
    """JCGM 101 §9.3 Table 6: the input PDFs (mg, kg/m³).

    Returns
    -------
    dict of str to Distribution
        ``m_rc`` N(100 000.000, 0.050²), ``dm_rc`` N(1.234, 0.020²), ``rho_a``
        R(1.10, 1.30), ``rho_w`` R(7 000, 9 000), ``rho_r`` R(7 950, 8 050).
    """
    return {
        "m_rc": Normal(100_000.000, 0.050),
        "dm_rc": Normal(1.234, 0.020),
        "rho_a": Uniform(1.10, 1.30),
        "rho_w": Uniform(7_000.0, 9_000.0),
        "rho_r": Uniform(7_950.0, 8_050.0),
    }


# JCGM 101 Tables 7 and 8, as printed (mg).
_PUBLISHED_MC = {"estimate": "1.2341", "u": "0.0754", "shortest": "[1.0834, 1.3825]"}
_PUBLISHED_GUM = {"estimate": "1.2340", "u": "0.0539", "interval": "[1.1285, 1.3395]"}
_PUBLISHED_VALIDATION = {"d_low": "0.0451", "d_high": "0.0430", "delta": "0.0005"}


def mass_calibration(console: Console, options: DemoOptions) -> dict[str, Any]:
    """JCGM 101 §9.3: calibration of a 100 g weight against a reference (mg).

    Prints the inputs, the Monte Carlo result (fixed number of trials, shortest 95 %
    interval as in Table 7), the first-order GUM result with its budget, and the §8
    validation with the shortest interval (Table 8), beside the published values.

    Parameters
    ----------
    console : rich.console.Console
        Where to print.
    options : DemoOptions
        Trials and seed.

    Returns
    -------
    dict
        Every number printed (JSON-ready), in mg.
    """
    model = mass_calibration_model()
    inputs = mass_calibration_inputs()
    console.rule("1. JCGM 101 §9.3 — mass calibration")
    console.print(f"model: δm = {model.text}   [mg]")

    t_in = _table("Inputs (JCGM 101 Table 6)", "quantity", "PDF", "expectation", "std. dev.")
    for name, dist in inputs.items():
        t_in.add_row(name, str(dist), fmt(dist.mean), fmt(dist.std))
    console.print(t_in)

    start = time.perf_counter()
    mc = monte_carlo(model, inputs, trials=options.trials, seed=options.seed)
    elapsed = time.perf_counter() - start
    lo, hi = mc.coverage_interval(0.95, kind="shortest")
    t_mc = _table("Monte Carlo (JCGM 101 §7)", "", "mtmc", "JCGM 101 Table 7 (M = 10⁶)")
    t_mc.add_row("estimate δm / mg", fmt(mc.estimate), _PUBLISHED_MC["estimate"])
    t_mc.add_row("u(δm) / mg", fmt(mc.u), _PUBLISHED_MC["u"])
    t_mc.add_row(
        "shortest 95 % interval / mg", f"[{fmt(lo)}, {fmt(hi)}]", _PUBLISHED_MC["shortest"]
    )
    t_mc.add_row("length of that interval / mg", fmt(hi - lo), "0.2991")
    t_mc.add_row("trials", str(mc.trials), "")
    t_mc.add_row("seed", str(mc.seed), "")
    t_mc.add_row("time / s", f"{elapsed:.2f}", "")
    console.print(t_mc)
    console.print(
        "The output PDF is nearly flat near the ends of the shortest interval: its length "
        "is well determined, its position moves by about ±0.002 mg from seed to seed at "
        "M = 10⁶ (JCGM 101 §7.7.3)."
    )

    g = gum(model, inputs)
    t_g = _table("GUM, first order (JCGM 100 §5)", "", "mtmc", "JCGM 101 Table 7")
    t_g.add_row("estimate δm / mg", fmt(g.estimate), _PUBLISHED_GUM["estimate"])
    t_g.add_row("u(δm) / mg", fmt(g.u), _PUBLISHED_GUM["u"])
    t_g.add_row("k", fmt(g.k), "1.96")
    t_g.add_row(
        "95 % interval / mg",
        f"[{fmt(g.interval[0])}, {fmt(g.interval[1])}]",
        _PUBLISHED_GUM["interval"],
    )
    t_g.add_row("sensitivities by", g.method, "")
    console.print(t_g)

    t_b = _table("Uncertainty budget", "input", "x", "u(x)", "c", "|c| u(x)", "share of u²")
    for entry in g.budget:
        t_b.add_row(
            entry.name,
            fmt(entry.estimate),
            fmt(entry.u),
            fmt(entry.sensitivity),
            fmt(entry.contribution),
            f"{100 * entry.share:.1f} %",
        )
    console.print(t_b)

    v = validate(g, mc, p=0.95, ndig=2, kind="shortest")
    t_v = _table("Validation of the GUM by MC (JCGM 101 §8)", "", "mtmc", "JCGM 101 Table 8")
    t_v.add_row("d_low / mg", fmt(v.d_low), _PUBLISHED_VALIDATION["d_low"])
    t_v.add_row("d_high / mg", fmt(v.d_high), _PUBLISHED_VALIDATION["d_high"])
    t_v.add_row("δ (ndig = 2) / mg", fmt(v.delta), _PUBLISHED_VALIDATION["delta"])
    t_v.add_row("GUM validated", "yes" if v.passed else "no", "no")
    console.print(t_v)
    console.print(
        "The first-order GUM misses the buoyancy term: its sensitivities to ρ_W and ρ_R "
        "vanish at the estimates, while their product with (ρ_a - ρ_a0) does not."
    )
    return {
        "unit": "mg",
        "model": model.text,
        "inputs": {n: str(d) for n, d in inputs.items()},
        "trials": mc.trials,
        "seed": mc.seed,
        "monte_carlo": {"estimate": mc.estimate, "u": mc.u, "shortest_95": [lo, hi]},
        "gum": {
            "estimate": g.estimate,
            "u": g.u,
            "k": g.k,
            "interval_95": list(g.interval),
            "budget": {
                e.name: {"sensitivity": e.sensitivity, "contribution": e.contribution}
                for e in g.budget
            },
        },
        "validation": {
            "d_low": v.d_low,
            "d_high": v.d_high,
            "delta": v.delta,
            "passed": v.passed,
            "kind": v.kind,
        },
        "published": {
            "monte_carlo": _PUBLISHED_MC,
            "gum": _PUBLISHED_GUM,
            "validation": _PUBLISHED_VALIDATION,
        },
        "time_s": elapsed,
    }


# ---------------------------------------------------------------------------------------
# 2. Ball centre


def _probe_u_dir(graph: Graph) -> float:
    """Standard uncertainty of a coordinate probed along its own axis, mm.

    The probe model of seed 000 (``docs/graph-format.md``): u1 = ``u_axis`` on every
    coordinate, u2 = ``u_probe`` and u3 = ``u_perp`` along the probing direction, so a
    coordinate probed along its axis has ``u_dir² = u1² + u2² + u3²``.
    """
    p = graph.probe
    return math.sqrt(p.u_axis**2 + p.u_probe**2 + p.u_perp**2) * graph.factor


def _write_drawing(graph: Graph, out: Path | None, name: str) -> str | None:
    """Draw ``graph`` to ``out/name`` atomically; return the file name (None: not written)."""
    if out is None:
        return None
    from mtmc.graph.draw import draw
    from mtmc.io import atomic_path

    with atomic_path(out / name) as tmp:
        draw(graph, tmp)
    return name


def ball_centre(console: Console, options: DemoOptions) -> dict[str, Any]:
    """Ball centre from 4 + 1 probed points (seed 000 Fig. 5-6, ``ball_centre.toml``).

    ``cx = (x1 + x2)/2``, ``cy = (y1 + y2)/2``, ``cz = z1 - r1``. Each probed coordinate
    carries ``u_dir = sqrt(u1² + u2² + u3²)`` (the probe model), independently, so the
    closed form is ``u(cx) = u(cy) = u_dir/√2`` and ``u(cz) = sqrt(u_dir² + u(r1)²)``.
    The Monte Carlo standard uncertainty of each coordinate is printed beside it, with
    the relative standard error ``1/sqrt(2(M - 1))`` of a Monte Carlo standard deviation.

    Parameters
    ----------
    console : rich.console.Console
        Where to print.
    options : DemoOptions
        Trials, seed and output folder.

    Returns
    -------
    dict
        Every number printed (JSON-ready), in µm.
    """
    from mtmc.graph.run import run_graph

    graph = demo_graph("ball_centre.toml")
    console.rule("2. Ball centre from 4 + 1 probed points (seed 000 Fig. 5-6)")
    p = graph.probe
    r1 = graph.place("neg_r1")
    u_r1 = (r1.u or 0.0) * graph.factor if r1 is not None else 0.0
    t_in = _table("Probe model (seed 000)", "input", "standard uncertainty / µm")
    t_in.add_row("u1, axis position (every coordinate)", _f4(p.u_axis * graph.factor * UM))
    t_in.add_row("u2, probe (along the probing direction)", _f4(p.u_probe * graph.factor * UM))
    t_in.add_row("u3, non-perpendicularity (along it)", _f4(p.u_perp * graph.factor * UM))
    t_in.add_row("u(r1), calibrated ball radius", _f4(u_r1 * UM))
    console.print(t_in)

    start = time.perf_counter()
    res = run_graph(graph, options.graph_trials, options.seed, outputs=["p"])
    elapsed = time.perf_counter() - start
    est, u_mc, _ = res.places["p"].part("value")
    u_dir = _probe_u_dir(graph)
    closed = np.array([u_dir / math.sqrt(2.0), u_dir / math.sqrt(2.0), math.hypot(u_dir, u_r1)])
    tol = _mc_rel_tolerance(res.trials)
    t = _table(
        f"Ball centre (M = {res.trials}, seed {res.seed}, {elapsed:.2f} s)",
        "coordinate",
        "estimate / mm",
        "u MC / µm",
        "u closed form / µm",
        "MC / closed − 1",
        "MC rel. std. error",
    )
    forms = ("u_dir/√2", "u_dir/√2", "√(u_dir² + u(r1)²)")
    for i, c in enumerate("xyz"):
        t.add_row(
            f"{c}  ({forms[i]})",
            _mm(est[i]),
            _f4(u_mc[i] * UM),
            _f4(closed[i] * UM),
            f"{u_mc[i] / closed[i] - 1:+.2%}",
            f"{tol:.2%}",
        )
    console.print(t)
    console.print(f"u_dir = √(u1² + u2² + u3²) = {_f4(u_dir * UM)} µm.")
    drawing = _write_drawing(graph, options.out, "ball_centre.svg")
    return {
        "unit": "µm (estimate in mm)",
        "graph": graph.file,
        "trials": res.trials,
        "seed": res.seed,
        "probe_um": {
            "u_axis": p.u_axis * graph.factor * UM,
            "u_probe": p.u_probe * graph.factor * UM,
            "u_perp": p.u_perp * graph.factor * UM,
            "u_r1": u_r1 * UM,
        },
        "estimate_mm": est,
        "u_mc_um": u_mc * UM,
        "u_closed_form_um": closed * UM,
        "u_dir_um": u_dir * UM,
        "mc_rel_std_error": tol,
        "drawing": drawing,
        "time_s": elapsed,
    }


# ---------------------------------------------------------------------------------------
# 3. Rotary axes


def _plane_basis(direction: NDArray[np.float64]) -> NDArray[np.float64]:
    """Two orthonormal columns spanning the plane normal to ``direction``, shape (3, 2)."""
    from scipy.linalg import null_space

    return np.asarray(null_space(direction.reshape(1, 3)), dtype=np.float64)


def _axis_study(name: str, place: str, options: DemoOptions) -> dict[str, Any]:
    """Monte Carlo and GUM of one rotary axis (a ``line`` place) of a demo graph."""
    from mtmc.graph.run import graph_model, run_graph
    from mtmc.uncertainty.results import MonteCarloResult

    graph = demo_graph(name)
    start = time.perf_counter()
    res = run_graph(graph, options.graph_trials, options.seed, outputs=[place], keep=[place])
    elapsed = time.perf_counter() - start
    summ = res.places[place]
    point, u_point, _ = summ.part("point")
    direction, u_dir, _ = summ.part("direction")
    model, inputs = graph_model(graph, place)
    g = gum(model, inputs)
    u_gum = np.asarray(g.u, dtype=np.float64)
    # The axis location in the plane normal to the estimated axis direction.
    line = res.samples[place]
    basis = _plane_basis(np.asarray(direction, dtype=np.float64))
    local = np.asarray(line.point, dtype=np.float64) @ basis
    loc = MonteCarloResult.from_samples(local, seed=res.seed)
    ell = loc.coverage_ellipsoid(0.95, method="mc")
    ell_chi2 = loc.coverage_ellipsoid(0.95, method="chi2")
    return {
        "graph": graph.file,
        "probe": _probe_record(graph),
        "place": place,
        "trials": res.trials,
        "seed": res.seed,
        "point_mm": point,
        "u_point_mc_um": u_point * UM,
        "u_point_gum_um": u_gum[:3] * UM,
        "direction": direction,
        "u_direction_mc_urad": u_dir * URAD,
        "u_direction_gum_urad": u_gum[3:6] * URAD,
        "plane_basis": basis.T,
        "ellipse_semi_axes_um": ell.semi_axes * UM,
        "ellipse_k": ell.k,
        "ellipse_semi_axes_chi2_um": ell_chi2.semi_axes * UM,
        "ellipse_k_chi2": ell_chi2.k,
        "gum_method": g.method,
        "time_s": elapsed,
    }


def rotary_axes(console: Console, options: DemoOptions) -> dict[str, Any]:
    """Rotary axes C and A from three ball positions each (seed 000 eqs. 8-19).

    For each axis: the location (the centre P0 of the circle through the three ball
    centres) and the direction (its normal), with the Monte Carlo standard uncertainty
    beside the first-order GUM one (:func:`mtmc.gum` on :func:`mtmc.graph_model`), and
    the 95 % coverage ellipse of the location in the plane normal to the axis (JCGM 102
    §7.7.2: ``k²`` the 95 % quantile of the squared Mahalanobis distances of the trials),
    beside the Gaussian ellipse ``k² = χ²₂(0.95)`` (JCGM 102 §6.5.2.3).

    The components of the unit direction vector are dimensionless: a small change ``δv``
    normal to ``v`` is a rotation by ``|δv|`` rad, so their uncertainties are given in
    µrad.

    Parameters
    ----------
    console : rich.console.Console
        Where to print.
    options : DemoOptions
        Trials, seed and output folder.

    Returns
    -------
    dict
        Per axis, every number printed (JSON-ready).
    """
    console.rule("3. Rotary axes C and A from three ball positions (seed 000 eqs. 8-19)")
    out: dict[str, Any] = {}
    for label, file, place in (("C", "axis_c.toml", "axis_c"), ("A", "axis_a.toml", "axis_a")):
        r = _axis_study(file, place, options)
        out[label] = r
        t = _table(
            f"Axis {label} ({file}, M = {r['trials']}, seed {r['seed']}, {r['time_s']:.2f} s)",
            "component",
            "estimate",
            "u MC",
            "u GUM",
            "MC / GUM",
        )
        for i, c in enumerate("xyz"):
            t.add_row(
                f"location {c} / mm, u / µm",
                _mm(r["point_mm"][i]),
                _f4(r["u_point_mc_um"][i]),
                _f4(r["u_point_gum_um"][i]),
                f"{r['u_point_mc_um'][i] / r['u_point_gum_um'][i]:.4f}",
            )
        for i, c in enumerate("xyz"):
            u_g = r["u_direction_gum_urad"][i]
            t.add_row(
                f"direction {c} / 1, u / µrad",
                _unit(r["direction"][i]),
                _f4(r["u_direction_mc_urad"][i]),
                _f4(u_g),
                f"{r['u_direction_mc_urad'][i] / u_g:.4f}" if u_g > 0 else "— (2nd order)",
            )
        console.print(t)
        te = _table(
            f"95 % coverage ellipse of the location of {label} in the plane normal to the axis",
            "",
            "MC (JCGM 102 §7.7.2)",
            "Gaussian, χ²₂ (JCGM 102 §6.5.2.3)",
        )
        te.add_row("k", _f4(r["ellipse_k"]), _f4(r["ellipse_k_chi2"]))
        te.add_row(
            "semi-axes / µm",
            ", ".join(_f4(a) for a in r["ellipse_semi_axes_um"]),
            ", ".join(_f4(a) for a in r["ellipse_semi_axes_chi2_um"]),
        )
        console.print(te)
    console.print(
        "The GUM column linearises the circle through the three ball centres by "
        f"{out['C']['gum_method']} sensitivities; the location estimate is the circle centre. "
        "The component of the unit direction along the axis moves only to second order "
        "(1 - cos θ): its first-order u is 0."
    )
    return out


# ---------------------------------------------------------------------------------------
# 4. A-C distance and BCS origin

#: The σ_probe × σ_machine grid of the Fig. 14 sweep (mm): ``probe.u_probe`` is the probe
#: σ_p, ``probe.u_axis`` the machine σ_m, each 1 µm to 5 µm in 5 steps.
SWEEP_GRID: dict[str, tuple[float, ...]] = {
    "probe.u_probe": (0.001, 0.002, 0.003, 0.004, 0.005),
    "probe.u_axis": (0.001, 0.002, 0.003, 0.004, 0.005),
}


def _plot_histogram(path: Path, mc: Any, g: Any, interval: tuple[float, float]) -> None:
    """Histogram of d_AC (µm from the estimate) with the shortest 95 % interval and GUM PDF."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure
    from scipy.stats import norm

    from mtmc.io import atomic_path

    hist = mc.histogram(bins=80)
    ref = float(g.estimate)
    edges = (hist.edges - ref) * UM
    fig = Figure(figsize=(7.0, 4.2))
    ax = fig.add_subplot(1, 1, 1)
    ax.stairs(hist.density / UM, edges, fill=True, alpha=0.5, label="Monte Carlo")
    x = np.linspace(edges[0], edges[-1], 400)
    ax.plot(x, norm.pdf(x, 0.0, float(g.u) * UM), "k-", lw=1.2, label="GUM: normal PDF")
    for v in interval:
        ax.axvline((v - ref) * UM, color="C3", ls="--", lw=1.0)
    ax.plot([], [], color="C3", ls="--", label="shortest 95 % interval (MC)")
    ax.set_xlabel(f"d_AC − {ref:.6f} mm / µm")
    ax.set_ylabel("probability density / µm⁻¹")
    ax.set_title("A-C distance d_AC (seed 000 eq. 30)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp)


def _plot_sweep(path: Path, sw: Any, fit: Any) -> None:
    """Contours of U(σ_p, σ_m) from the sweep (filled) and from the surrogate (lines), µm."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from mtmc.io import atomic_path

    a = np.unique(sw.grid[:, 0])
    b = np.unique(sw.grid[:, 1])
    u = sw.u.reshape(len(a), len(b)) * UM
    aa, bb = np.meshgrid(a, b, indexing="ij")
    fa, fb = np.meshgrid(np.linspace(a[0], a[-1], 60), np.linspace(b[0], b[-1], 60), indexing="ij")
    pred = fit.predict(np.column_stack([fa.ravel(), fb.ravel()])).reshape(fa.shape) * UM
    fig = Figure(figsize=(6.0, 4.8))
    ax = fig.add_subplot(1, 1, 1)
    cf = ax.contourf(aa * UM, bb * UM, u, levels=12, cmap="viridis")
    cs = ax.contour(fa * UM, fb * UM, pred, levels=cf.levels, colors="w", linewidths=0.8)
    ax.clabel(cs, fontsize=7, fmt="%.2f")
    fig.colorbar(cf, ax=ax, label="u(d_AC) / µm (Monte Carlo)")
    ax.set_xlabel("σ_p = probe.u_probe / µm")
    ax.set_ylabel("σ_m = probe.u_axis / µm")
    ax.set_title("Fig. 14 sweep (filled) and surrogate U² = c0 + Σ cᵢσᵢ² (lines)", fontsize=9)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp)


def bcs_origin(console: Console, options: DemoOptions) -> dict[str, Any]:
    """A-C distance and BCS origin (seed 000 eq. 30, Fig. 12-14, ``bcs_origin.toml``).

    The graph gives P_O (axis A meets the plane through P_C normal to A), P_C (the
    attachment point of C moved onto the table) and their distance d_AC. d_AC is run by
    Monte Carlo (:func:`mtmc.monte_carlo` on :func:`mtmc.graph_model`) and by the GUM
    with the JCGM 101 §8 validation (probabilistically symmetric interval). Then the
    Fig. 14 sweep: u(d_AC) on a 5 × 5 grid of σ_p (``probe.u_probe``) and σ_m
    (``probe.u_axis``), ``options.sweep_trials`` trials per point, with the surrogate
    ``U² = c0 + Σ cᵢ σᵢ²`` (the form of seed eq. 31 with an intercept for the inputs not
    swept) and its largest relative error on the grid (the seed: at most 5 %).

    Parameters
    ----------
    console : rich.console.Console
        Where to print.
    options : DemoOptions
        Trials, seed and output folder.

    Returns
    -------
    dict
        Every number printed (JSON-ready).
    """
    from mtmc.graph.run import graph_model, run_graph
    from mtmc.graph.sweep import sweep

    graph = demo_graph("bcs_origin.toml")
    console.rule("4. A-C distance and BCS origin (seed 000 eq. 30, Fig. 12-14)")
    start = time.perf_counter()
    res = run_graph(graph, options.graph_trials, options.seed, outputs=["p_o", "p_c", "d_ac"])
    model, inputs = graph_model(graph, "d_ac")
    mc = monte_carlo(model, inputs, trials=options.graph_trials, seed=options.seed)
    elapsed = time.perf_counter() - start
    g = gum(model, inputs)
    v = validate(g, mc, p=0.95, ndig=2, kind="symmetric")
    lo_s, hi_s = mc.coverage_interval(0.95, kind="shortest")
    lo_y, hi_y = mc.coverage_interval(0.95, kind="symmetric")

    t_p = _table(
        f"Points (run_graph, M = {res.trials}, seed {res.seed})",
        "place",
        "estimate / mm",
        "u(x, y, z) / µm",
    )
    points = {}
    for name, label in (("p_o", "P_O, BCS origin on axis A"), ("p_c", "P_C, on axis C")):
        est, u, _ = res.places[name].part("value")
        points[name] = {"estimate_mm": est, "u_um": u * UM}
        t_p.add_row(label, ", ".join(_mm(x) for x in est), ", ".join(_f4(x) for x in u * UM))
    console.print(t_p)

    t = _table(
        f"d_AC: Monte Carlo vs GUM (M = {mc.trials}, seed {mc.seed}, {elapsed:.2f} s)",
        "",
        "Monte Carlo",
        "GUM (first order)",
    )
    t.add_row("estimate / mm", _mm(mc.estimate), _mm(g.estimate))
    t.add_row("u / µm", _f4(mc.u * UM), _f4(g.u * UM))
    t.add_row(
        "95 % interval / mm (MC: symmetric)",
        f"[{_mm(lo_y)}, {_mm(hi_y)}]",
        f"[{_mm(g.interval[0])}, {_mm(g.interval[1])}]",
    )
    t.add_row("shortest 95 % interval / mm", f"[{_mm(lo_s)}, {_mm(hi_s)}]", "")
    t.add_row("same trials by run_graph: u / µm", _f4(res.places["d_ac"].u * UM), "")
    console.print(t)
    se_end = _endpoint_std_error(float(mc.u), mc.trials)
    t_v = _table("Validation of the GUM by MC (JCGM 101 §8, symmetric interval)", "", "µm")
    t_v.add_row("d_low", _f4(v.d_low * UM))
    t_v.add_row("d_high", _f4(v.d_high * UM))
    t_v.add_row("δ (ndig = 2)", _f4(v.delta * UM))
    t_v.add_row("MC std. error of an endpoint", _f4(se_end * UM))
    t_v.add_row("GUM validated", "yes" if v.passed else "no")
    console.print(t_v)
    firm = se_end <= v.delta / 3.0
    console.print(
        "§8 compares d_low, d_high with δ; the endpoints of the Monte Carlo interval carry "
        "their own sampling error (order statistics, normal output), so a verdict is firm "
        "only where that error is small beside δ"
        + (
            "; here it is."
            if firm
            else f": at M = {mc.trials} it is not (run with more trials, --trials N)."
        )
    )

    start = time.perf_counter()
    sw = sweep(
        graph,
        {k: np.asarray(v_) for k, v_ in SWEEP_GRID.items()},
        "d_ac",
        trials=options.sweep_trials,
        seed=options.seed,
    )
    fit = sw.fit(intercept=True)
    fit0 = sw.fit(intercept=False)
    sweep_time = time.perf_counter() - start
    pred = fit.predict(sw.grid)
    a_vals = SWEEP_GRID["probe.u_probe"]
    b_vals = SWEEP_GRID["probe.u_axis"]
    t_s = _table(
        f"Fig. 14: u(d_AC) / µm, {sw.trials} trials per point, seed {sw.seed} "
        f"({sweep_time:.2f} s); MC (surrogate)",
        "σ_p \\ σ_m / µm",
        *(_f4(b * UM) for b in b_vals),
    )
    nb = len(b_vals)
    for i, a in enumerate(a_vals):
        cells = [f"{_f4(sw.u[i * nb + j] * UM)} ({_f4(pred[i * nb + j] * UM)})" for j in range(nb)]
        t_s.add_row(_f4(a * UM), *cells)
    console.print(t_s)
    t_f = _table(
        "Surrogate fitted to the sweep (seed 000 eq. 31 form), σ in mm, U in mm",
        "form",
        "c0 / mm²",
        "c_p",
        "c_m",
        "largest |rel. error| on the grid",
        "seed 000",
    )
    t_f.add_row(
        "U² = c0 + c_p σ_p² + c_m σ_m²",
        f"{fit.c0:.4g}",
        f"{fit.coefficients[0]:.4g}",
        f"{fit.coefficients[1]:.4g}",
        f"{fit.max_rel_error:.2%}",
        "≤ 5 %",
    )
    t_f.add_row(
        "U² = c_p σ_p² + c_m σ_m² (eq. 31)",
        "0",
        f"{fit0.coefficients[0]:.4g}",
        f"{fit0.coefficients[1]:.4g}",
        f"{fit0.max_rel_error:.2%}",
        "≤ 5 %",
    )
    console.print(t_f)
    console.print(
        "σ_p and σ_m enter every coordinate probed along a machine axis as u2² + u1², so "
        "their coefficients come out equal; the constant c0 carries u3 and the "
        "uncertainties of r1, r2 that the sweep leaves fixed."
    )

    files: dict[str, str | None] = {"drawing": None, "histogram": None, "sweep": None}
    if options.out is not None:
        files["drawing"] = _write_drawing(graph, options.out, "bcs_origin.svg")
        _plot_histogram(options.out / "d_ac_histogram.png", mc, g, (lo_s, hi_s))
        _plot_sweep(options.out / "sweep.png", sw, fit)
        files["histogram"] = "d_ac_histogram.png"
        files["sweep"] = "sweep.png"
    return {
        "graph": graph.file,
        "probe": _probe_record(graph),
        "trials": mc.trials,
        "seed": mc.seed,
        "points": points,
        "d_ac": {
            "monte_carlo": {
                "estimate_mm": mc.estimate,
                "u_um": mc.u * UM,
                "symmetric_95_mm": [lo_y, hi_y],
                "shortest_95_mm": [lo_s, hi_s],
            },
            "run_graph_u_um": res.places["d_ac"].u * UM,
            "gum": {
                "estimate_mm": g.estimate,
                "u_um": g.u * UM,
                "k": g.k,
                "interval_95_mm": list(g.interval),
                "method": g.method,
            },
            "validation_um": {
                "d_low": v.d_low * UM,
                "d_high": v.d_high * UM,
                "delta": v.delta * UM,
                "passed": v.passed,
                "kind": v.kind,
                "endpoint_std_error": se_end * UM,
            },
        },
        "sweep": {
            "names": list(sw.names),
            "grid_mm": sw.grid,
            "u_um": sw.u * UM,
            "u_surrogate_um": pred * UM,
            "trials_per_point": sw.trials,
            "seed": sw.seed,
            "surrogate": {
                "c0_mm2": fit.c0,
                "coefficients": fit.coefficients,
                "max_rel_error": fit.max_rel_error,
                "formula": fit.formula(),
            },
            "surrogate_no_intercept": {
                "coefficients": fit0.coefficients,
                "max_rel_error": fit0.max_rel_error,
                "formula": fit0.formula(),
            },
            "paper_max_rel_error": 0.05,
            "time_s": sweep_time,
        },
        "files": files,
        "time_s": elapsed,
    }


# ---------------------------------------------------------------------------------------
# 5. Five-axis machine

#: The library machine of section 5: five-axis table-table, C on an A cradle on X.
FIVE_AXIS_MACHINE = "table-table"

#: Uncertain ISO 230-7 location errors of C and A and ISO 230-1 squareness errors of the
#: linear axes (mm, rad): zero expectation, the standard uncertainties of a machine
#: calibrated with a ball bar and a laser (a plausible set, not a published one).
FIVE_AXIS_ERRORS: dict[str, Distribution] = {
    "EX0C": Normal(0.0, 0.003),  # C: location in x, 3 µm
    "EY0C": Normal(0.0, 0.003),  # C: location in y, 3 µm
    "EA0C": Uniform(-10e-6, 10e-6),  # C: tilt about x, ±10 µrad
    "EB0C": Uniform(-10e-6, 10e-6),  # C: tilt about y, ±10 µrad
    "EY0A": Normal(0.0, 0.005),  # A: location in y, 5 µm
    "EZ0A": Normal(0.0, 0.005),  # A: location in z, 5 µm
    "EB0A": Uniform(-15e-6, 15e-6),  # A: tilt about y, ±15 µrad
    "EC0A": Uniform(-15e-6, 15e-6),  # A: tilt about z, ±15 µrad
    "EC0Y": Normal(0.0, 4e-6),  # squareness Y to X, 4 µrad
    "EB0Z": Normal(0.0, 4e-6),  # squareness Z to X, 4 µrad
    "EA0Z": Normal(0.0, 4e-6),  # squareness Z to Y, 4 µrad
}

#: Axis positions (X, Y, Z mm; A, C rad) of the poses of section 5.
FIVE_AXIS_POSES: tuple[tuple[float, float, float, float, float], ...] = (
    (150.0, 0.0, -100.0, math.radians(-30.0), 0.0),
    (100.0, 50.0, -50.0, math.radians(-45.0), math.radians(90.0)),
    (100.0, 50.0, -50.0, math.radians(-90.0), math.radians(-135.0)),
    (-200.0, 100.0, -150.0, math.radians(-60.0), math.radians(45.0)),
)


def five_axis_model(machine: Any, poses: Any) -> Callable[..., NDArray[np.float64]]:
    """The tool positions at the poses as a model of the errors, for :func:`monte_carlo`.

    Parameters
    ----------
    machine : Machine
        The machine.
    poses : array_like, shape (P, n_axes)
        Axis positions (mm, rad).

    Returns
    -------
    callable
        ``model(**errors)``, each error an array ``(m,)`` (one value per trial), returning
        ``(m, 3 P)``: x, y, z of pose 1, then of pose 2, ... (mm). One call of
        :meth:`~mtmc.kinematics.Machine.tool_position` per pose, batched over the trials.
    """
    q = np.asarray(poses, dtype=np.float64)

    def model(**errors: Any) -> NDArray[np.float64]:
        return np.hstack([machine.tool_position(q[i], errors) for i in range(q.shape[0])])

    return model


def five_axis(console: Console, options: DemoOptions) -> dict[str, Any]:
    """Five-axis table-table machine with uncertain ISO 230 geometric errors.

    The errors of :data:`FIVE_AXIS_ERRORS` are drawn by Monte Carlo (one value per trial,
    an array ``(M,)`` per error) and propagated through the forward kinematics
    :meth:`~mtmc.kinematics.Machine.tool_position` at each pose of
    :data:`FIVE_AXIS_POSES`. Beside it, the linear GUM from the analytic Jacobian
    ``J = ∂p/∂e`` at zero errors (:meth:`~mtmc.kinematics.Machine.jacobian`):
    ``U_p = J U_e Jᵀ`` with ``U_e = diag(u²(e))`` (JCGM 102 §6.2), ``u = sqrt(diag U_p)``.
    The §8 validation (JCGM 101) of each coordinate uses the GUM of :func:`mtmc.gum`
    (sensitivities of the same model by differentiation), whose u equals the
    Jacobian's to rounding.

    Parameters
    ----------
    console : rich.console.Console
        Where to print.
    options : DemoOptions
        Trials, seed and output folder.

    Returns
    -------
    dict
        Every number printed (JSON-ready), in µm.
    """
    from mtmc.io import write_text_atomic
    from mtmc.kinematics.draw import draw_chain
    from mtmc.kinematics.library import library_machine

    machine = library_machine(FIVE_AXIS_MACHINE)
    console.rule(f"5. Five-axis machine {machine.topology} with ISO 230 geometric errors")
    names = tuple(FIVE_AXIS_ERRORS)
    t_in = _table(
        f"Uncertain geometric errors of {machine.topology} ({FIVE_AXIS_MACHINE}), zero mean",
        "error",
        "ISO",
        "PDF",
        "u",
    )
    for n, d in FIVE_AXIS_ERRORS.items():
        term = machine.error_term(n)
        angular = n[1] in "ABC"
        u_txt = f"{_f4(d.std * URAD)} µrad" if angular else f"{_f4(d.std * UM)} µm"
        iso = "230-7 location" if term.kind == "location" else f"230-1 {term.kind}"
        t_in.add_row(n, iso, str(d), u_txt)
    console.print(t_in)

    poses = np.array(FIVE_AXIS_POSES, dtype=np.float64)
    model = five_axis_model(machine, poses)
    start = time.perf_counter()
    mc = monte_carlo(model, FIVE_AXIS_ERRORS, trials=options.graph_trials, seed=options.seed)
    elapsed = time.perf_counter() - start
    nominal = machine.tool_position(poses)
    J = machine.jacobian(poses, names=names)  # (P, 3, N)
    u_e = np.array([FIVE_AXIS_ERRORS[n].std for n in names])
    cov_p = np.einsum("pin,n,pjn->pij", J, u_e**2, J)
    u_jac = np.sqrt(np.einsum("pii->pi", cov_p))
    u_mc = np.asarray(mc.u, dtype=np.float64).reshape(-1, 3)
    est_mc = np.asarray(mc.estimate, dtype=np.float64).reshape(-1, 3)
    tol = _mc_rel_tolerance(mc.trials)

    t_q = _table("Poses", "pose", "X / mm", "Y / mm", "Z / mm", "A / °", "C / °")
    for i, pose in enumerate(poses):
        t_q.add_row(
            str(i + 1), *(fmt(x) for x in pose[:3]), *(fmt(math.degrees(a)) for a in pose[3:])
        )
    console.print(t_q)
    rows: list[dict[str, Any]] = []
    t = _table(
        f"Tool position: MC (M = {mc.trials}, seed {mc.seed}, {elapsed:.2f} s) vs GUM "
        "u = √(J U Jᵀ); JCGM 101 §8 (symmetric, ndig = 2); u, d, δ, σ(end) in µm",
        "pose",
        "",
        "nominal/mm",
        "u MC",
        "u GUM",
        "MC/GUM",
        "k MC",
        "d_low",
        "d_high",
        "δ",
        "σ(end)",
        "§8",
    )
    for i, pose in enumerate(poses):
        for j, c in enumerate("xyz"):
            col = 3 * i + j

            def comp(_col: int = col, **a: Any) -> NDArray[np.float64]:
                return model(**a)[:, _col]

            g = gum(comp, FIVE_AXIS_ERRORS)
            mc_c = mc.component(col)
            v = validate(g, mc_c, p=0.95, ndig=2, kind="symmetric")
            k_mc = mc_c.coverage_factor(0.95, kind="symmetric")
            ratio = u_mc[i, j] / u_jac[i, j]
            se_end = _endpoint_std_error(u_mc[i, j], mc.trials)
            rows.append(
                {
                    "pose": i + 1,
                    "q": pose,
                    "coordinate": c,
                    "nominal_mm": _clean(nominal[i, j]),
                    "mc_estimate_mm": est_mc[i, j],
                    "u_mc_um": u_mc[i, j] * UM,
                    "u_gum_jacobian_um": u_jac[i, j] * UM,
                    "u_gum_differentiated_um": float(g.u) * UM,
                    "ratio_mc_gum": ratio,
                    "k_mc": k_mc,
                    "k_gum": float(g.k),
                    "d_low_um": v.d_low * UM,
                    "d_high_um": v.d_high * UM,
                    "delta_um": v.delta * UM,
                    "endpoint_std_error_um": se_end * UM,
                    "validated": v.passed,
                }
            )
            t.add_row(
                str(i + 1) if j == 0 else "",
                c,
                fmt(_clean(nominal[i, j])),
                _f4(u_mc[i, j] * UM),
                _f4(u_jac[i, j] * UM),
                f"{ratio:.4f}",
                f"{k_mc:.3f}",
                _f4(v.d_low * UM),
                _f4(v.d_high * UM),
                _f4(v.delta * UM),
                _f4(se_end * UM),
                "yes" if v.passed else "no",
            )
    console.print(t)
    console.print(
        "MC / GUM is 1 to within a few Monte Carlo relative standard errors of u "
        f"({tol:.2%} at this M): to first order the tool position is linear in the errors. "
        "k MC is the half-width of the Monte Carlo 95 % interval over u (the GUM uses k = "
        f"{rows[0]['k_gum']:.2f}): below it where rectangular errors dominate a coordinate, "
        "whose PDF is then flatter than a normal one and the GUM interval too wide. The GUM "
        "of the §8 validation takes sensitivities of the same model by differentiation, "
        "which equal the Jacobian's. σ(end) is the sampling error of a Monte Carlo interval "
        "endpoint: where it is not small beside δ, a 'no' may be Monte Carlo noise (run "
        "with more trials, --trials N)."
    )
    firm = [
        f"pose {r['pose']} {r['coordinate']}"
        for r in rows
        if not r["validated"]
        and max(r["d_low_um"], r["d_high_um"]) > r["delta_um"] + 3.0 * r["endpoint_std_error_um"]
    ]
    if firm:
        console.print(
            "Not validated beyond Monte Carlo noise (d > δ + 3 σ(end)): "
            + ", ".join(firm)
            + ": there the GUM's normal interval misses the output PDF."
        )
    drawing = None
    if options.out is not None:
        write_text_atomic(options.out / "machine.svg", draw_chain(machine))
        drawing = "machine.svg"
    return {
        "machine": FIVE_AXIS_MACHINE,
        "topology": str(machine.topology),
        "trials": mc.trials,
        "seed": mc.seed,
        "errors": {
            n: {"pdf": str(d), "u": d.std, "unit": "rad" if n[1] in "ABC" else "mm"}
            for n, d in FIVE_AXIS_ERRORS.items()
        },
        "poses_mm_rad": poses,
        "rows": rows,
        "mc_rel_std_error": tol,
        "drawing": drawing,
        "time_s": elapsed,
    }


#: The demo's sections, run in order: (name, function).
SECTIONS: list[tuple[str, Callable[[Console, DemoOptions], dict[str, Any]]]] = [
    ("mass-calibration", mass_calibration),
    ("ball-centre", ball_centre),
    ("rotary-axes", rotary_axes),
    ("bcs-origin", bcs_origin),
    ("five-axis", five_axis),
]


def main(argv: Sequence[str] | None = None, console: Any = None) -> int:
    """Run the demo sections, print their tables and write the output folder.

    Parameters
    ----------
    argv : sequence of str, optional
        ``[--trials N] [--seed S] [--out DIR] [--quick] [--section NAME]`` (default:
        ``sys.argv[1:]``). ``--trials`` sets the trials of every section (default 10⁶
        for each); ``--quick`` runs 2·10⁴ and 10⁴.
    console : rich.console.Console, optional
        Where to print (default: standard output).

    Returns
    -------
    int
        0.
    """
    from mtmc import __version__
    from mtmc.io import write_text_atomic

    parser = argparse.ArgumentParser(
        prog="python -m mtmc.demo",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--trials", type=int, default=None, help="trials of every section")
    parser.add_argument("--seed", type=int, default=DemoOptions.seed)
    parser.add_argument("--out", type=Path, default=Path("mtmc-demo"), help="output folder")
    parser.add_argument("--quick", action="store_true", help="few trials (a smoke run)")
    parser.add_argument("--section", choices=[name for name, _ in SECTIONS], default=None)
    args = parser.parse_args(argv)
    if args.trials is not None and args.trials < 2:
        parser.error(f"--trials: expected an integer >= 2, got {args.trials}")
    trials, graph_trials = (20_000, 10_000) if args.quick else (10**6, 10**6)
    if args.trials is not None:
        trials = graph_trials = args.trials
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        parser.error(f"--out: expected a folder, but {out} is a file")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        parser.error(f"--out: cannot create the folder {out}: {exc.strerror}")
    options = DemoOptions(trials=trials, graph_trials=graph_trials, seed=args.seed, out=out)
    if console is None:
        console = Console()
        if console.width < 110:
            console = Console(width=110)
    start = time.perf_counter()
    record: dict[str, Any] = {
        "mtmc_version": __version__,
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "seed": options.seed,
        "trials": {
            "mass-calibration": options.trials,
            "graphs": options.graph_trials,
            "sweep_per_point": options.sweep_trials,
        },
        "sections": {},
    }
    for name, section in SECTIONS:
        if args.section in (None, name):
            record["sections"][name] = section(console, options)
    record["time_s"] = time.perf_counter() - start
    write_text_atomic(
        out / "results.json", json.dumps(_json(record), indent=2, ensure_ascii=False) + "\n"
    )
    console.print(f"Results written to {out}/ (results.json) in {record['time_s']:.1f} s.")
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
