"""Laser-tracker verification: identification and Monte Carlo of whole verifications.

The Aguado et al. 2016 case (``examples/studies/aguado2016.toml``, XFYZ, tracker at pos4):

1. one identification of the 5408-point mesh with the tracker pose (noisy readings);
2. the Monte Carlo of 1000 verifications of the 96-point mesh, and of the 5408-point mesh
   (time and peak resident memory of this process);
3. the plain way beside ours on the 96-point case: a Python loop of
   ``scipy.optimize.least_squares`` per trial with a finite-difference Jacobian (central
   differences, tolerances 1e-15, ``x_scale='jac'``), on the first ``--plain`` trials
   (time scaled to 1000), on the same readings; every coefficient and pose parameter of
   both is compared, relative and in units of its standard uncertainty.

Run: ``python benchmarks/bench_verification.py [--trials 1000] [--plain 20] [--skip-5408]
[--only-5408]``.
Nothing pins the BLAS threads: the script runs as the user's Python does and prints the
thread setting it found. On a loaded machine BLAS threads slow the factorisations of the
identifications down (one 16 270 × 46 QR took 3 s instead of 0.09 s on one thread at a
load average of 8 on 2 cores); set ``OPENBLAS_NUM_THREADS=1`` to time the one-thread case.
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import time
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares as scipy_lsq

from mtmc.geometry import matrix_from_rotation_vector
from mtmc.study import load_study
from mtmc.uncertainty.heap import keep_heap
from mtmc.verification.identify import identify
from mtmc.verification.simulate import (
    VerificationModel,
    reference_identification,
    simulate,
)

STUDY = Path(__file__).resolve().parents[1] / "examples" / "studies" / "aguado2016.toml"


def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def bench_identification(st, repeat: int) -> None:  # type: ignore[no-untyped-def]
    ver = st.verification("mesh5408", "pos4")
    x = ver.readings()
    rng = np.random.default_rng(np.random.SeedSequence(1))
    xm = ver.tracker.noise.perturb(x, rng.normal(size=x.shape))
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        r = identify(ver.model, ver.q, xm, ver.tracker, fixed=ver.fixed)
        best = min(best, time.perf_counter() - t)
    print(
        f"identification, 5408 points, {len(r.names)} parameters (pose included): "
        f"{best:.3f} s best of {repeat} ({r.iterations[0]} iterations, {r.messages()[0]}); "
        f"target <= 0.5 s",
        flush=True,
    )


def bench_mc(st, points: str, trials: int, target: float) -> None:  # type: ignore[no-untyped-def]
    ver = st.verification(points, "pos4")
    t = time.perf_counter()
    r = simulate(ver, trials, 2016)
    dt = time.perf_counter() - t
    print(
        f"Monte Carlo, {trials} verifications of {ver.n_points} points: {dt:.2f} s "
        f"(target <= {target:g} s), peak RSS of the process {_peak_mb():.0f} MB; "
        f"initial VE mean {r.ve_estimate[1] * 1e3:.1f} ± {r.ve_u[1] * 1e3:.1f} um, "
        f"residual mean {r.ve_estimate[4] * 1e3:.1f} ± {r.ve_u[4] * 1e3:.1f} um",
        flush=True,
    )


def bench_plain(st, trials: int, n_plain: int) -> None:  # type: ignore[no-untyped-def]
    ver = st.verification("mesh96", "pos4")
    ref = reference_identification(ver)
    vm = VerificationModel.build(ver, ref)
    N = ver.n_points
    rng = np.random.default_rng(np.random.SeedSequence(7))
    z = rng.normal(size=(trials, N, 3))
    x = vm.noise.perturb(np.broadcast_to(vm.x_true, z.shape), z)
    t = time.perf_counter()
    ours, _, _, _ = vm.solve(x)
    t_ours = time.perf_counter() - t
    model, free = ver.model, [ver.model.parameter_names.index(n) for n in ref.names[:-6]]
    k = len(free)
    R0, t0 = ver.tracker.rotation, ver.tracker.position
    w0 = ref.estimate[0]
    # scipy's relative steps act on variables near 1, v = 1 + (w - w0)/step: 1e-3 for the
    # coefficients (mm or rad; the readings are linear in each), 1e-5 rad for the rotation
    # (central differences err by h²/6 there), 1 mm for the position
    step = np.r_[np.full(k, 1e-3), np.full(3, 1e-5), np.full(3, 1.0)]

    def residual(v: np.ndarray, meas: np.ndarray) -> np.ndarray:
        w = w0 + (v - 1.0) * step
        th = np.zeros(model.n_parameters)
        th[free] = w[:k]
        R = R0 @ matrix_from_rotation_vector(w[k : k + 3])
        p = model.tool_position(ver.q, th)
        return ((p - (t0 + w[k + 3 :])) @ R - meas).ravel()

    t = time.perf_counter()
    plain = []
    for i in range(n_plain):  # the plain way: one trial at a time
        sol = scipy_lsq(
            residual, np.ones(step.size), args=(x[i],), jac="3-point", diff_step=1.0,
            x_scale="jac", xtol=1e-15, ftol=1e-15, gtol=1e-15,
        )  # fmt: skip
        plain.append(w0 + (sol.x - 1.0) * step)
    t_plain = (time.perf_counter() - t) * trials / n_plain
    # a loop over trials of our own analytic identification: what batching alone buys
    t = time.perf_counter()
    for i in range(n_plain):
        identify(ver.model, ver.q, x[i : i + 1], ver.tracker, fixed=ver.fixed)
    t_loop = (time.perf_counter() - t) * trials / n_plain
    plain_a = np.array(plain)
    exact = identify(ver.model, ver.q, x[:n_plain], ver.tracker, fixed=ver.fixed)
    u = exact.u
    d_ours = np.abs(ours[:n_plain] - plain_a)
    d_exact = np.abs(exact.estimate - plain_a)
    t = time.perf_counter()
    simulate(ver, trials, 7)
    t_mc = time.perf_counter() - t
    print(
        f"plain way (scipy least_squares, 3-point finite differences, a loop over trials), "
        f"96 points: {t_plain:.1f} s for {trials} trials (from {n_plain}); ours: the whole "
        f"Monte Carlo {t_mc:.2f} s ({t_plain / t_mc:.0f}x), the identification of the "
        f"{trials} trials alone {t_ours:.3f} s",
        flush=True,
    )
    print(
        f"a loop over trials of mtmc's own identify(), 96 points: {t_loop:.1f} s for {trials} "
        f"trials (from {n_plain}): the whole Monte Carlo is {t_loop / t_mc:.0f}x faster",
        flush=True,
    )
    pairs = (("ours (MC solver)", d_ours, ours[:n_plain]), ("identify", d_exact, exact.estimate))
    for label, d, est in pairs:
        rel = d / np.abs(plain_a)
        big = np.abs(plain_a) > 1e-3 * u
        print(
            f"  coefficients and pose, {label} vs plain, {n_plain} trials x {d.shape[1]}: "
            f"max relative {rel.max():.2e} (where |value| > 1e-3 u: {rel[big].max():.2e}), "
            f"max |diff| {(d / u).max():.2e} u; smallest |value| {(np.abs(est) / u).min():.1e} u",
            flush=True,
        )


def main() -> None:
    keep_heap()  # as the mtmc command does when it starts
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=1000)
    ap.add_argument("--plain", type=int, default=20)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--skip-5408", action="store_true")
    ap.add_argument("--only-5408", action="store_true")
    a = ap.parse_args()
    threads = os.environ.get("OPENBLAS_NUM_THREADS", "not set (BLAS default)")
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"OPENBLAS_NUM_THREADS {threads}, load average {os.getloadavg()[0]:.1f}",
          flush=True)  # fmt: skip
    st = load_study(STUDY).study
    if not a.only_5408:
        bench_identification(st, a.repeat)
        bench_mc(st, "mesh96", a.trials, 2.0)
        bench_plain(st, a.trials, a.plain)
    if not a.skip_5408:
        bench_mc(st, "mesh5408", a.trials, 20.0)


if __name__ == "__main__":
    main()
