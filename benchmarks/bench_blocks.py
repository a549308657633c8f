"""Blocks of trials under load: the verification kernel and the artefact's thin products.

Each case runs the code of 2026-11-25 (kept below, or patched back in) and today's side by
side in one process, in interleaved rounds, and reports the best and the median wall and
CPU time of each, the load average of the machine beside every round, and how far the
numbers of the two lie apart:

1. the Monte Carlo (``mtmc.uncertainty.monte_carlo``: drawing, the model, the summaries) of
   1000 verifications of the Aguado et al. 2016 mesh of 96 points and of 5408 points,
   tracker at pos4, the reference identification done once beforehand (timed apart).
   Before: the spherical coordinates and standard deviations of the true readings
   recomputed in every block; the chord iterations through two products over all ``3N``
   readings each; the exact steps through the machine's whole Jacobian per trial. Today:
   the noise at the true readings computed once per model, the chord operators
   precomputed (one product over the readings per trial), the exact gradient in reverse
   mode (``Machine.jacobian_transpose``), the block evaluated in slices of trials. Peak
   memory traced by ``tracemalloc`` in one further run of each (the engine's included).
   Targets: 96 points ≤ 0.3 s, 5408 points ≤ 2 s and ≤ 500 MB.
2. the fiducial-artefact study ``wang2022.toml``: its 45 thin products of one block alone,
   at the engine's block (689 trials) and at ten times it, and the Monte Carlo of 10⁴
   trials of point noise. Before: one BLAS product ``(m R, 90) @ (90, 3)`` per pose and
   ball over a whole block; today: the same product in slices of 960 rows, which OpenBLAS
   runs on one thread. Target ≤ 5 s.

Nothing pins the BLAS threads: the script runs as the user's Python does (it prints the
BLAS and its thread setting). On a machine whose other cores are busy, BLAS threads that
wait for each other are what the slices avoid; on an idle machine both ways cost alike.

Run: ``python benchmarks/bench_blocks.py [--trials 1000] [--artefact-trials 10000]
[--rounds 3] [--skip-5408]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import statistics
import time
import tracemalloc
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

import mtmc.artefact.simulation as artefact_study
from mtmc.geometry import matrix_from_rotation_vector
from mtmc.geometry.transforms import rotation_vector_from_matrix
from mtmc.study import load_study
from mtmc.uncertainty import monte_carlo
from mtmc.uncertainty.heap import keep_heap
from mtmc.verification.simulate import (
    _ROWS,
    VerificationModel,
    _rows,
    reference_identification,
)

ROOT = Path(__file__).resolve().parents[1]
VERIFICATION = ROOT / "examples" / "studies" / "aguado2016.toml"
ARTEFACT = ROOT / "examples" / "studies" / "wang2022.toml"


def _blas() -> str:
    cfg: Any = np.show_config(mode="dicts")
    blas = cfg.get("Build Dependencies", {}).get("blas", {})
    env = {k: os.environ[k] for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS") if k in os.environ}
    threads = ", ".join(f"{k}={v}" for k, v in env.items()) or "threads not set (BLAS default)"
    return f"{blas.get('name', '?')} {blas.get('version', '')}, {threads}"


# --- the verification model of 2026-11-25 ------------------------------------------------


class _PerBlockNoise:
    """The noise of the true readings recomputed for every block, as before."""

    def __init__(self, noise: Any, x: np.ndarray) -> None:
        self.noise, self.x = noise, x

    def perturb(self, z: np.ndarray) -> np.ndarray:
        return self.noise.perturb(np.broadcast_to(self.x, z.shape), z)  # type: ignore[no-any-return]


@dataclasses.dataclass(frozen=True)
class _Before(VerificationModel):
    """:class:`VerificationModel` with the chord iterations and exact gradient of 2026-11-25."""

    def __call__(
        self, noise: Any, repeatability: Any = None, pose: Any = None, reflector: Any = None
    ) -> dict[str, Any]:
        return self._trials(noise, repeatability, pose, reflector)  # the block in one pass

    def _solve(self, x_meas: Any) -> tuple[Any, Any, Any, Any]:
        m, N = x_meas.shape[:2]
        k = self.n_theta
        est = np.broadcast_to(self.est0, (m, self.est0.size)).copy()
        R = np.broadcast_to(self.R_ref, (m, 3, 3)).copy()
        t = np.broadcast_to(self.t_ref, (m, 3)).copy()
        Jt = self.Jp.reshape(3 * N, k).T
        for _ in range(self.iterations):
            p = self.p_fit + _rows(est[:, :k] - self.est0[:k], Jt).reshape(m, N, 3)
            r = (p - t[:, None, :]) @ R - x_meas
            d = -_rows(r.reshape(m, 3 * N), self.A.T)
            est += d
            if self.pose:
                R = R @ matrix_from_rotation_vector(d[:, k : k + 3])
                t = t + d[:, k + 3 : k + 6]
        for _ in range(self.refine):
            d = -_rows(self.gradient(est, R, t, x_meas), self.Hinv)
            est[:, :k] += d[:, :k]
            if self.pose:
                R = R @ matrix_from_rotation_vector(d[:, k : k + 3])
                t = t + d[:, k + 3 : k + 6]
        if self.pose:
            est[:, k : k + 3] = rotation_vector_from_matrix(np.swapaxes(self.R_nom, -1, -2) @ R)
            est[:, k + 3 : k + 6] = t - self.t_nom
        p = self.p_fit + _rows(est[:, :k] - self.est0[:k], Jt).reshape(m, N, 3)
        return est, (p - t[:, None, :]) @ R, R, t  # the model readings (see _trials)

    def gradient(self, est: Any, R: Any, t: Any, x_meas: Any) -> Any:
        m, N = x_meas.shape[:2]
        k = self.n_theta
        mach = self.model.machine
        th = np.broadcast_to(self.base, (m, self.base.size)).copy()
        th[:, self.free] = est[:, :k]
        g_th = np.zeros((m, self.base.size))
        g = np.zeros(est.shape)
        names = tuple(n for n, _, _ in self.basis)
        step = max(1, _ROWS // N)
        for a in range(0, m, step):
            b = min(m, a + step)
            qq = np.broadcast_to(self.q, (b - a, *self.q.shape)).reshape((b - a) * N, -1)
            errs = {n: _rows(th[a:b, idx], B.T).ravel() for n, idx, B in self.basis}
            p = mach.tool_position(qq, errs, exact=self.exact).reshape(b - a, N, 3)
            xr = (p - t[a:b, None, :]) @ R[a:b]
            r = xr - x_meas[a:b]
            w = np.einsum("mij,mnj->mni", R[a:b], r).reshape(-1, 3)
            Je = mach.jacobian(qq, errs, names=names, exact=self.exact)
            s = np.einsum("rce,rc->re", Je, w).reshape(b - a, N, -1)
            for ie, (_, idx, B) in enumerate(self.basis):
                g_th[a:b, idx] = _rows(s[:, :, ie], B)
            if self.pose:
                g[a:b, k : k + 3] = np.sum(np.cross(r, xr), axis=1)
                g[a:b, k + 3 : k + 6] = -np.einsum("mij,mj->mi", R[a:b], r.sum(axis=1))
        g[:, :k] = g_th[:, self.free]
        return g


def _before(vm: VerificationModel) -> _Before:
    kw = {f.name: getattr(vm, f.name) for f in dataclasses.fields(vm)}
    kw["noise_at"] = _PerBlockNoise(vm.noise, vm.x_true)
    kw["at_measured"] = False  # the compensated readings by their own product, as before
    return _Before(**kw)


# --- timing --------------------------------------------------------------------------------


def _rounds(
    runs: dict[str, Callable[[], Any]], rounds: int
) -> tuple[dict[str, list[tuple[float, float]]], list[float]]:
    """Each run once per round, in turn; (wall, CPU) of each, and the load per round."""
    times: dict[str, list[tuple[float, float]]] = {k: [] for k in runs}
    load = []
    for _ in range(rounds):
        load.append(os.getloadavg()[0])
        for name, run in runs.items():
            t, c = time.perf_counter(), time.process_time()
            run()
            times[name].append((time.perf_counter() - t, time.process_time() - c))
    return times, load


def _report(label: str, times: dict[str, list[tuple[float, float]]], load: list[float]) -> None:
    print(f"{label} (load average {min(load):.1f}-{max(load):.1f} over the rounds):", flush=True)
    base = None
    for name, tt in times.items():
        wall, cpu = [w for w, _ in tt], [c for _, c in tt]
        line = (
            f"  {name:7s} wall best {min(wall):.3f} s, median {statistics.median(wall):.3f} s; "
            f"CPU best {min(cpu):.3f} s, median {statistics.median(cpu):.3f} s"
        )
        if base is None:
            base = (min(wall), min(cpu))
        else:
            line += (
                f"  (before / today: wall {base[0] / min(wall):.2f}x, "
                f"CPU {base[1] / min(cpu):.2f}x)"
            )
        print(line, flush=True)


def _peak_mb(run: Callable[[], Any]) -> float:
    tracemalloc.start()
    try:
        run()
        return tracemalloc.get_traced_memory()[1] / 1e6
    finally:
        tracemalloc.stop()


def bench_verification(st: Any, points: str, trials: int, rounds: int, target: float) -> None:
    ver = st.verification(points, "pos4")
    t = time.perf_counter()
    vm = VerificationModel.build(ver, reference_identification(ver))
    t_ref = time.perf_counter() - t
    old = _before(vm)
    inputs = vm.inputs()
    out: dict[str, Any] = {}

    def run(name: str, model: Any) -> Callable[[], Any]:
        def go() -> Any:
            out[name] = monte_carlo(model, inputs, trials, 2016, keep=["ve", "coef"])

        return go

    runs = {"before": run("before", old), "today": run("today", vm)}
    runs["today"]()  # warm both once
    runs["before"]()
    times, load = _rounds(runs, rounds)
    _report(
        f"verification, {trials} trials x {ver.n_points} points, refine={vm.refine} "
        f"(reference identification and model, once: {t_ref:.2f} s)",
        times,
        load,
    )
    peak = {k: _peak_mb(r) for k, r in runs.items()}
    a, b = out["before"], out["today"]
    rel = 0.0
    for key in ("coef", "ve"):
        sa, sb = np.asarray(a[key].samples), np.asarray(b[key].samples)
        rel = max(rel, float(np.max(np.abs(sa - sb) / np.maximum(np.abs(sa), 1e-300))))
    ua, ub = np.asarray(a["coef"].u_vector), np.asarray(b["coef"].u_vector)
    du = np.max(np.abs(np.asarray(a["coef"].samples) - np.asarray(b["coef"].samples)) / ua)
    best = min(w for w, _ in times["today"])
    print(
        f"  peak traced memory: before {peak['before']:.0f} MB, today {peak['today']:.0f} MB; "
        f"largest difference of a trial's coefficient or statistic: {rel:.1e} relative, "
        f"{du:.1e} u; u of the coefficients {np.max(np.abs(ua / ub - 1)):.1e} relative; "
        f"target <= {target:g} s: {'met' if best <= target else 'NOT met'} ({best:.2f} s)",
        flush=True,
    )


def bench_products(rounds: int) -> None:
    """The 45 thin products of one block alone, at the engine's block and ten times it."""
    study: Any = load_study(ARTEFACT)
    model: Any = artefact_study.study_model(study.study, split=True)[0]
    KpT = model.KpT  # (P N, 90, 3)
    R = study.study.repetitions
    rng = np.random.default_rng(np.random.SeedSequence(3))
    for m in (689, 6890):  # 689: the engine's block of 64 MiB of drawn inputs
        zf = rng.normal(size=(m * R, KpT.shape[0], KpT.shape[1]))
        dc = np.empty((m * R, KpT.shape[0], 3))

        def products(slices: bool, zf: np.ndarray = zf, dc: np.ndarray = dc) -> np.ndarray:
            for i in range(KpT.shape[0]):
                if slices:
                    artefact_study._thin_matmul(zf[:, i], KpT[i], dc[:, i])
                else:
                    np.matmul(zf[:, i], KpT[i], out=dc[:, i])
            return dc

        same = np.array_equal(products(False).copy(), products(True))
        times, load = _rounds(
            {"before": lambda: products(False), "today": lambda: products(True)}, rounds
        )
        _report(f"artefact, the 45 products of a block of {m} trials ({m * R} rows)", times, load)
        cpu_wall = {k: min(c for _, c in v) / min(w for w, _ in v) for k, v in times.items()}
        print(
            f"  same bits: {same}; CPU / wall (above 1: BLAS threads at work): "
            f"before {cpu_wall['before']:.2f}, today {cpu_wall['today']:.2f}",
            flush=True,
        )


def bench_artefact(trials: int, rounds: int) -> None:
    study: Any = load_study(ARTEFACT)
    study = study.study
    model, inputs, _ = artefact_study.study_model(study, split=True)
    today = artefact_study._thin_matmul

    def whole(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> np.ndarray:
        return np.matmul(a, b, out=out)

    res: dict[str, Any] = {}

    def run(name: str, product: Callable[..., np.ndarray]) -> Callable[[], Any]:
        def go() -> Any:
            artefact_study._thin_matmul = product
            try:
                res[name] = monte_carlo(model, inputs, trials=trials, seed=2022, keep=False)
            finally:
                artefact_study._thin_matmul = today

        return go

    runs = {"before": run("before", whole), "today": run("today", today)}
    times, load = _rounds(runs, rounds)
    _report(f"artefact wang2022, {trials} trials of point noise", times, load)
    ua = np.array([res["before"][f"r_max_measured/{p}"].u for p in range(9)])
    ub = np.array([res["today"][f"r_max_measured/{p}"].u for p in range(9)])
    best = min(w for w, _ in times["today"]) * 1e4 / trials
    print(
        f"  u(r_max) of the nine poses the same bits: {np.array_equal(ua, ub)}; "
        f"target <= 5 s for 10^4: {'met' if best <= 5 else 'NOT met'} ({best:.2f} s)",
        flush=True,
    )


def main() -> None:
    keep_heap()  # as the mtmc command does when it starts
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=1000)
    ap.add_argument("--artefact-trials", type=int, default=10_000)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--skip-5408", action="store_true")
    a = ap.parse_args()
    print(
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, python "
        f"{platform.python_version()}, numpy {np.__version__}, BLAS {_blas()}; load average "
        f"{os.getloadavg()[0]:.1f}",
        flush=True,
    )
    st: Any = load_study(VERIFICATION)
    st = st.study
    bench_verification(st, "mesh96", a.trials, a.rounds, 0.3)
    if not a.skip_5408:
        bench_verification(st, "mesh5408", a.trials, a.rounds, 2.0)
    bench_products(a.rounds)
    bench_artefact(a.artefact_trials, a.rounds)
    print(f"load average at the end: {os.getloadavg()[0]:.1f}", flush=True)


if __name__ == "__main__":
    main()
