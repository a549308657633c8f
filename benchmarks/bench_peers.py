"""Peer comparison on the newer inputs: mtmc against Sandia's suncal.

Cases, M = 10^6 Monte Carlo trials each, everything included (draw, evaluate, u and the
shortest 95 % coverage interval), each tool run as a user runs it, in a fresh process, best
of REPEAT, in two interleaved rounds:

* correlated inputs under a Gaussian copula: the difference of two gauge blocks with
  normal PDFs and r = 0.9; the worked example of docs/correlation.md, whose correlated
  inputs are rectangular (r = 0.9 between the two thermal errors);
* a Type A input from ten observations (JCGM 101 §6.4.9) plus the resolution of the
  indication;
* the worked example of docs/type-a.md: that Type A input, a Type B input whose u is
  reliable to 25 % (ν = 8), and the resolution; its GUM ν_eff, k and U from both tools.

suncal draws a Type A input from a normal PDF of standard deviation s/√n, and a normal
Type B input with stated ν from the normal PDF (ν only enters its GUM). mtmc draws both
from the scaled and shifted t. Where the two differ, a second suncal row gives the same
input to suncal as a t PDF of scale s/√n (resp. u) and ν degrees of freedom, the PDF mtmc
draws: those rows must agree with mtmc within the Monte Carlo noise.

Agreement: two independent runs of M trials; y agrees if |Δy| ≤ 3·√2·u/√M, u if
|Δu| ≤ 3·√2·σ_u with σ_u = u·√((β₂ − 1)/(4M)) (β₂ the kurtosis of the output), each
endpoint if |Δ| ≤ 3·√2·σ_e with σ_e = √(α(1 − α)/M) / g(η_α), g the output density at the
endpoint estimated from the spacing of the sorted mtmc values. For the GUM, u, ν_eff and U
are deterministic and compared to 10⁻⁶ relative.

Run: ``python benchmarks/bench_peers.py`` (needs suncal: ``pip install -e '.[bench]'``).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import subprocess
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

import mtmc
from mtmc import expression, gum, monte_carlo, parse_distribution, type_a
from mtmc.uncertainty import Normal, Uniform

M = 10**6
REPEAT = 3
ROUNDS = 2
SEED = 20240601
P = 0.95

# docs/type-a.md: ten readings of a comparator, mm
OBS = [10.012, 10.007, 10.015, 10.009, 10.011, 10.004, 10.013, 10.010, 10.008, 10.014]
N_OBS = len(OBS)
S_MEAN = float(np.std(OBS, ddof=1) / math.sqrt(N_OBS))  # s/√n, the GUM's u of the mean


def _mtmc_inputs(case: str) -> dict[str, Any]:
    if case == "blocks normal r=0.9":
        return {"l1": Normal(50.000020, 0.000025), "l2": Normal(49.999990, 0.000020)}
    if case == "thermal uniform r=0.9":
        return {
            "l1": Normal(100.000040, 0.000010),
            "l2": Normal(50.000010, 0.000010),
            "e1": Uniform(-0.00006, 0.00006),
            "e2": Uniform(-0.00003, 0.00003),
        }
    if case == "Type A, n=10":
        return {"x": type_a(OBS), "r": Uniform(-0.0005, 0.0005)}
    if case == "Type A + B(nu=8)":
        return {
            "x": type_a(OBS),
            "b": parse_distribution("normal(0, 0.002, u_rel_u=0.25)"),
            "r": Uniform(-0.0005, 0.0005),
        }
    raise KeyError(case)


# expression, correlated pairs, suncal inputs {name: (value(s), [(dist, kwargs), ...])}
# and, where suncal draws another PDF than mtmc, the inputs that make it draw mtmc's
CASES: dict[str, dict[str, Any]] = {
    "blocks normal r=0.9": {
        "expr": "l1 - l2",
        "corr": {("l1", "l2"): 0.9},
        "suncal": {
            "l1": (50.000020, [("normal", {"std": 0.000025})]),
            "l2": (49.999990, [("normal", {"std": 0.000020})]),
        },
    },
    "thermal uniform r=0.9": {
        "expr": "(l1 + e1) - (l2 + e2)",
        "corr": {("e1", "e2"): 0.9},
        "suncal": {
            "l1": (100.000040, [("normal", {"std": 0.000010})]),
            "l2": (50.000010, [("normal", {"std": 0.000010})]),
            "e1": (0.0, [("uniform", {"a": 0.00006})]),
            "e2": (0.0, [("uniform", {"a": 0.00003})]),
        },
    },
    "Type A, n=10": {
        "expr": "x + r",
        "corr": None,
        "suncal": {"x": (OBS, []), "r": (0.0, [("uniform", {"a": 0.0005})])},
        "suncal t": {
            "x": (float(np.mean(OBS)), [("t", {"scale": S_MEAN, "df": N_OBS - 1})]),
            "r": (0.0, [("uniform", {"a": 0.0005})]),
        },
    },
    "Type A + B(nu=8)": {
        "expr": "x + b + r",
        "corr": None,
        "suncal": {
            "x": (OBS, []),
            "b": (0.0, [("normal", {"std": 0.002, "degf": 8})]),
            "r": (0.0, [("uniform", {"a": 0.0005})]),
        },
        "suncal t": {
            "x": (float(np.mean(OBS)), [("t", {"scale": S_MEAN, "df": N_OBS - 1})]),
            "b": (0.0, [("t", {"scale": 0.002, "df": 8})]),
            "r": (0.0, [("uniform", {"a": 0.0005})]),
        },
    },
}


def mtmc_mc(case: str, m: int) -> list[float]:
    c = CASES[case]
    r = monte_carlo(
        expression(c["expr"]), _mtmc_inputs(case), trials=m, seed=SEED, correlation=c["corr"]
    )
    lo, hi = r.coverage_interval(P, "shortest")
    return [r.estimate, r.u, lo, hi]


def _suncal_model(case: str, spec_key: str) -> Any:
    import suncal

    c = CASES[case]
    model = suncal.Model("y = " + c["expr"])
    for name, (value, components) in c[spec_key].items():
        v = model.var(name).measure(value)
        for dist, kwargs in components:
            v.typeb(dist=dist, **kwargs)
    for (a, b), r in (c["corr"] or {}).items():
        model.variables.correlate(a, b, r)
    return model


def _suncal_mc(case: str, m: int, spec_key: str) -> list[float]:
    res = _suncal_model(case, spec_key).monte_carlo(samples=m)
    exp = res.expand("y", shortest=True, conf=P)
    return [float(res.expected["y"]), float(res.uncertainty["y"]), float(exp.low), float(exp.high)]


def suncal_mc(case: str, m: int) -> list[float]:
    return _suncal_mc(case, m, "suncal")


def suncal_t_mc(case: str, m: int) -> list[float]:
    return _suncal_mc(case, m, "suncal t")


def mtmc_gum(case: str, m: int) -> list[float]:
    del m
    c = CASES[case]
    g = gum(expression(c["expr"]), _mtmc_inputs(case), p=P, correlation=c["corr"])
    return [
        float(g.estimate),
        float(g.u),
        float(g.dof),
        g.coverage_factor(),
        g.expanded_uncertainty(),
    ]


def suncal_gum(case: str, m: int) -> list[float]:
    del m
    from suncal.common import ttable

    g = _suncal_model(case, "suncal").calculate_gum()
    u, dof = float(g.uncertainty["y"]), float(g.degf["y"])
    k = float(ttable.k_factor(P, dof))
    return [float(g.expected["y"]), u, dof, k, k * u]


METHODS: dict[str, Callable[[str, int], list[float]]] = {
    "mtmc": mtmc_mc,
    "suncal": suncal_mc,
    "suncal t": suncal_t_mc,
    "mtmc GUM": mtmc_gum,
    "suncal GUM": suncal_gum,
}


def child(method: str, case: str, m: int) -> None:
    """In a fresh process, as a user runs it: best of REPEAT; print time and results."""
    best, out = float("inf"), None
    for _ in range(REPEAT):
        t0 = time.perf_counter()
        out = METHODS[method](case, m)
        best = min(best, time.perf_counter() - t0)
    print(json.dumps([best, *out]))


def in_child(method: str, case: str, m: int) -> tuple[float, list[float]]:
    out = subprocess.run(
        [sys.executable, __file__, "--child", method, case, "--trials", str(m)],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    dt, *vals = json.loads(out.strip().splitlines()[-1])
    return dt, vals


def noise(case: str, m: int) -> tuple[float, float, float]:
    """σ of u, of the lower and of the upper endpoint for one run of m trials."""
    c = CASES[case]
    r = monte_carlo(
        expression(c["expr"]), _mtmc_inputs(case), trials=m, seed=SEED + 1, correlation=c["corr"]
    )
    y = np.sort(np.asarray(r.values, dtype=float).ravel())
    d = y - y.mean()
    b2 = float(np.mean(d**4) / np.mean(d**2) ** 2)
    s_u = float(y.std(ddof=1)) * math.sqrt((b2 - 1.0) / (4.0 * m))
    lo, hi = r.coverage_interval(P, "shortest")
    a = (1.0 - P) / 2.0
    h = max(1, m // 1000)  # density from the spacing of 2h order statistics

    def s_end(x: float) -> float:
        j = int(np.clip(np.searchsorted(y, x), h, m - h - 1))
        g = 2 * h / (m * (y[j + h] - y[j - h]))
        return math.sqrt(a * (1 - a) / m) / g

    return s_u, s_end(lo), s_end(hi)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    ap.add_argument("--trials", type=int, default=M)
    args = ap.parse_args()
    if args.child:
        child(args.child[0], args.child[1], args.trials)
        return 0
    try:
        import suncal
    except ImportError:
        print("suncal not installed: nothing to compare (pip install suncal)")
        return 0

    m = args.trials
    print(
        f"mtmc {mtmc.__version__}, suncal {suncal.version.__version__}, NumPy {np.__version__}, "
        f"Python {platform.python_version()}, {platform.machine()}, {os.cpu_count()} CPUs, "
        f"{datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC"
    )
    print(
        f"M = {m}, best of {REPEAT} in a fresh process, {ROUNDS} interleaved rounds; "
        f"load average at the start {os.getloadavg()[0]:.2f}"
    )
    head = (
        f"{'case':<22} {'method':<10} {'time/s':>7} {'/suncal':>7} {'y':>16} {'u':>10} "
        f"{'shortest 95 % interval':>34}  agree (|Δ|/tol: y, u, lo, hi)"
    )
    print(head)
    print("-" * len(head))
    for case, c in CASES.items():
        labels = ["mtmc", "suncal"] + (["suncal t"] if "suncal t" in c else [])
        best = {lb: float("inf") for lb in labels}
        outs: dict[str, list[float]] = {}
        for _ in range(ROUNDS):
            for lb in labels:
                dt, outs[lb] = in_child(lb, case, m)
                best[lb] = min(best[lb], dt)
        s_u, s_lo, s_hi = noise(case, m)
        tol = 3.0 * math.sqrt(2.0)
        y0, u0, lo0, hi0 = outs["mtmc"]
        for lb in labels:
            y, u, lo, hi = outs[lb]
            agree = ""
            if lb != "mtmc":
                q = (
                    abs(y - y0) / (tol * u0 / math.sqrt(m)),
                    abs(u - u0) / (tol * s_u),
                    abs(lo - lo0) / (tol * s_lo),
                    abs(hi - hi0) / (tol * s_hi),
                )
                verdict = "yes" if max(q) <= 1.0 else "NO"
                agree = f"{verdict} ({q[0]:.2f}, {q[1]:.2f}, {q[2]:.2f}, {q[3]:.2f})"
            print(
                f"{case:<22} {lb:<10} {best[lb]:7.3f} {best[lb] / best['suncal']:7.2f} "
                f"{y:16.10g} {u:10.4g}   [{lo:16.10g}, {hi:16.10g}]  {agree}"
            )
        print(
            f"{'':<22} noise σ (one run): u {s_u:.2g}, lo {s_lo:.2g}, hi {s_hi:.2g}; "
            f"load average {os.getloadavg()[0]:.2f}"
        )
    print()
    head = (
        f"{'case':<22} {'method':<10} {'time/s':>7} {'/suncal':>7} {'u':>10} {'nu_eff':>9} "
        f"{'k':>7} {'U':>10}  agree (rel. 1e-6: u, nu_eff, U)"
    )
    print("GUM (JCGM 100), p = 0.95")
    print(head)
    print("-" * len(head))
    for case in CASES:
        res = {}
        for lb in ("mtmc GUM", "suncal GUM"):
            dt = float("inf")
            for _ in range(ROUNDS):
                t, res[lb] = in_child(lb, case, m)
                dt = min(dt, t)
            res[lb] = [dt, *res[lb]]
        t_ref = res["suncal GUM"][0]
        for lb in ("mtmc GUM", "suncal GUM"):
            dt, _, u, dof, k, big_u = res[lb]
            agree = ""
            if lb == "suncal GUM":
                ref = res["mtmc GUM"]
                same = [
                    math.isclose(a, b, rel_tol=1e-6) or (math.isinf(a) and math.isinf(b))
                    for a, b in ((u, ref[2]), (dof, ref[3]), (big_u, ref[5]))
                ]
                agree = ", ".join("yes" if s else "NO" for s in same)
            print(
                f"{case:<22} {lb:<10} {dt:7.3f} {dt / t_ref:7.2f} {u:10.4g} {dof:9.3f} "
                f"{k:7.4f} {big_u:10.4g}  {agree}"
            )
    print(f"load average at the end {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
