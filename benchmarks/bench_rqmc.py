"""Trials and seconds to two significant digits: pseudo-random vs randomised quasi-MC.

For each case (JCGM 101 §9.2.2-9.2.4, §9.3, §9.4 and the ``axis_c`` measurement graph) and
each ``sampling`` of :func:`mtmc.uncertainty.monte_carlo`, the standard deviation over
``R`` seeds of ``u`` and of the endpoints of the probabilistically symmetric 95 %
interval is measured for runs of ``n`` trials. Two significant digits of ``u`` give the
numerical tolerance ``δ = numerical_tolerance(u, 2)`` (JCGM 101 §7.9.2), and a run is
good enough when ``2 s <= δ`` for ``u`` and both endpoints (the stopping rule of §7.9.4).

- pseudo-random: ``s`` falls as ``n^(-1/2)``, so the trials needed are
  ``n (2 s / δ)²`` from runs of ``n = 2¹⁴``;
- RQMC: ``s`` of one scrambling is measured for every ``n = 2⁴, 2⁵, ..., 2¹⁴``; the
  trials needed are the smallest such ``n`` that meets the rule, else
  ``2¹⁴ ⌈(2 s / δ)²⌉`` (whole independent scramblings, whose average has ``s / √r``).

Two figures per sampling: for ``u`` alone, and for ``u`` and both endpoints.

The seconds are the trials needed times the time per trial of a run of 2¹⁸ trials of
that sampling (best of 3), measured in the same process. Beside them, ``--runs`` also
times one whole run of the trials needed for ``u`` (``monte_carlo`` or ``run_graph``
with ``u`` and the interval read, best of 5), fixed costs included: what a user waits.
§9.3's output PDF is symmetric, so its shortest interval is the symmetric one; the
symmetric endpoints are used because the position of a shortest interval is poorly
determined for any sampling (see ``docs/performance.md``).

Run: ``python benchmarks/bench_rqmc.py [case ...] [--seeds R]`` (cases: 9.2.2 9.2.3
9.2.4 9.3 9.4 9.4r axis_c; all by default, a few minutes: run them one by one on a
shared machine). ``python benchmarks/bench_rqmc.py adaptive --seeds 5``: the adaptive
procedure on §9.3, both samplings, symmetric and shortest intervals.
"""

from __future__ import annotations

import argparse
import math
import os
import time
from pathlib import Path

import numpy as np

from mtmc import MultivariateNormal, Normal, Uniform, expression, monte_carlo
from mtmc.graph import check_graph, load_graph, run_graph
from mtmc.uncertainty.heap import keep_heap
from mtmc.uncertainty.tolerance import numerical_tolerance

ROOT = Path(__file__).resolve().parents[1]
N_BLOCK = 2**14
SIZES = tuple(2**k for k in range(4, 15))
TIMING_TRIALS = 2**18

SUM4 = expression("x1 + x2 + x3 + x4")
MASS = expression("(m_rc + dm_rc) * (1 + (rho_a - 1.2) * (1 / rho_w - 1 / rho_r)) - 100000")
LOSS = expression("x1**2 + x2**2")
A3 = math.sqrt(3.0)


def _loss_corr(x):
    return x[:, 0] ** 2 + x[:, 1] ** 2


CASES = {
    "9.2.2": (SUM4, {f"x{i}": Normal(0, 1) for i in range(1, 5)}),
    "9.2.3": (SUM4, {f"x{i}": Uniform(-A3, A3) for i in range(1, 5)}),
    "9.2.4": (
        SUM4,
        {
            "x1": Normal(0, 1),
            "x2": Normal(0, 1),
            "x3": Normal(0, 1),
            "x4": Uniform(-10 * A3, 10 * A3),
        },
    ),
    "9.3": (
        MASS,
        {
            "m_rc": Normal(100_000.000, 0.050),
            "dm_rc": Normal(1.234, 0.020),
            "rho_a": Uniform(1.10, 1.30),
            "rho_w": Uniform(7_000.0, 9_000.0),
            "rho_r": Uniform(7_950.0, 8_050.0),
        },
    ),
    "9.4": (LOSS, {"x1": Normal(0.010, 0.005), "x2": Normal(0.0, 0.005)}),
    "9.4r": (
        _loss_corr,
        {"x": MultivariateNormal([0.010, 0.0], 0.005**2 * np.array([[1.0, 0.9], [0.9, 1.0]]))},
    ),
}


def summaries(case: str, n: int, seed: int, sampling: str) -> np.ndarray:
    """u and the symmetric 95 % endpoints of each output component: (3, k)."""
    if case == "axis_c":
        plan = _axis_c()
        res = run_graph(plan, n, seed, outputs=["p_c"], keep=["p_c"], sampling=sampling)
        mc = res.places["p_c"].result
        comps = [mc.component(j) for j in range(2)]  # x and y of the axis point
    else:
        model, inputs = CASES[case]
        comps = [monte_carlo(model, inputs, n, seed, sampling=sampling)]
    rows = []
    for c in comps:
        lo, hi = c.coverage_interval(0.95, "symmetric")
        rows.append((c.u, lo, hi))
    return np.array(rows).T


_PLAN = None


def _axis_c():
    global _PLAN
    if _PLAN is None:
        _PLAN = check_graph(load_graph(ROOT / "examples" / "graphs" / "axis_c.toml"))
    return _PLAN


def spread(case: str, n: int, sampling: str, seeds: int) -> tuple[np.ndarray, np.ndarray]:
    vals = np.stack([summaries(case, n, 1000 + s, sampling) for s in range(seeds)])
    return vals.mean(axis=0), vals.std(axis=0, ddof=1)


def per_trial(case: str, sampling: str) -> float:
    best = math.inf
    for _ in range(3):
        t0 = time.perf_counter()
        summaries(case, TIMING_TRIALS, 7, sampling)
        best = min(best, time.perf_counter() - t0)
    return best / TIMING_TRIALS


def whole_run(case: str, n: int, sampling: str) -> float:
    """Seconds of one run of ``n`` trials, everything included (best of 5)."""
    best = math.inf
    for s in range(5):
        t0 = time.perf_counter()
        summaries(case, n, 50 + s, sampling)
        best = min(best, time.perf_counter() - t0)
    return best


def _needed(sd_at: dict[int, np.ndarray], delta: np.ndarray, rows: slice) -> int:
    """Trials for ``2 s <= δ`` on the summaries ``rows`` (see the module notes)."""
    for n in SIZES:
        if n in sd_at and np.all(2 * sd_at[n][rows] <= delta):
            return n
    n = max(sd_at)
    return n * math.ceil(float(np.max((2 * sd_at[n][rows] / delta) ** 2)))


def two_digits(case: str, seeds: int) -> dict[str, tuple[int, int, float]]:
    """Per sampling: trials for u, trials for u and the endpoints, seconds per trial."""
    mean, sd = spread(case, N_BLOCK, "random", seeds)
    delta = np.array([[numerical_tolerance(float(u), 2) for u in mean[0]]])
    out = {}
    ratio = (2 * sd / delta) ** 2  # pseudo-random: s ~ n^(-1/2)
    out["random"] = (
        max(2, math.ceil(N_BLOCK * float(np.max(ratio[:1])))),
        max(2, math.ceil(N_BLOCK * float(np.max(ratio)))),
        per_trial(case, "random"),
    )
    sd_at = {n: spread(case, n, "sobol", seeds)[1] for n in SIZES}
    out["sobol"] = (
        _needed(sd_at, delta, slice(0, 1)),
        _needed(sd_at, delta, slice(0, 3)),
        per_trial(case, "sobol"),
    )
    return out


def adaptive(seeds: int) -> None:
    """JCGM 101 §7.9.4 on §9.3 (ndig = 2): trials and seconds, per sampling and kind."""
    model, inputs = CASES["9.3"]
    print("adaptive §9.3, ndig = 2, median over seeds of trials and seconds")
    for kind in ("symmetric", "shortest"):
        for sampling in ("random", "sobol"):
            trials, secs = [], []
            for s in range(seeds):
                t0 = time.perf_counter()
                r = monte_carlo(
                    model, inputs, seed=100 + s, adaptive=True, ndig=2, kind=kind, sampling=sampling
                )
                secs.append(time.perf_counter() - t0)
                trials.append(r.trials)
            print(
                f"  {kind:<10}{sampling:<8}{_sig2(float(np.median(trials))):>10} trials"
                f"{_sig2(float(np.median(secs))):>8} s"
            )


def _sig2(x: float) -> str:
    return f"{float(f'{x:.2g}'):g}"


def main() -> None:
    keep_heap()  # as the mtmc command does when it starts
    ap = argparse.ArgumentParser()
    ap.add_argument("cases", nargs="*", default=[*CASES, "axis_c"])
    ap.add_argument("--seeds", type=int, default=12)
    ap.add_argument("--runs", action="store_true", help="also time whole runs (see notes)")
    args = ap.parse_args()
    load0 = os.getloadavg()[0]
    monte_carlo(SUM4, CASES["9.2.2"][1], 2**10, 1, sampling="sobol")  # SciPy's import
    if args.cases == ["adaptive"]:
        adaptive(args.seeds)
        return
    rows = []
    for case in args.cases:
        r = two_digits(case, args.seeds)
        rows.append((case, r))
    load1 = os.getloadavg()[0]
    print(
        f"trials (seconds) to two significant digits, 2 s <= δ over {args.seeds} seeds; "
        f"load average {load0:.1f} -> {load1:.1f}"
    )
    print(
        f"{'case':<8}{'u: random':>18}{'u: sobol':>18}{'ratio':>7}"
        f"{'u, 95 %: random':>20}{'u, 95 %: sobol':>18}{'ratio':>7}"
    )
    for case, r in rows:
        (ur, er, tr), (uq, eq, tq) = r["random"], r["sobol"]
        cells = []
        for m, t in ((ur, tr), (uq, tq)):
            cells.append(f"{_sig2(m)} ({_sig2(m * t)})")
        ratio_u = (ur * tr) / (uq * tq)
        cells2 = []
        for m, t in ((er, tr), (eq, tq)):
            cells2.append(f"{_sig2(m)} ({_sig2(m * t)})")
        ratio_e = (er * tr) / (eq * tq)
        print(
            f"{case:<8}{cells[0]:>18}{cells[1]:>18}{_sig2(ratio_u):>7}"
            f"{cells2[0]:>20}{cells2[1]:>18}{_sig2(ratio_e):>7}"
        )
    print("ratio: time to two digits, pseudo-random / RQMC (target >= 10)")
    if args.runs:
        print("whole runs of the trials needed for u, seconds (best of 5): random, sobol, ratio")
        for case, r in rows:
            nr, nq = r["random"][0], r["sobol"][0]
            tr = whole_run(case, max(nr, 2), "random")
            tq = whole_run(case, nq, "sobol")
            print(f"{case:<8}{nr:>9}{tr:>10.5f}{nq:>9}{tq:>10.5f}{tr / tq:>7.2g}")


if __name__ == "__main__":
    main()
