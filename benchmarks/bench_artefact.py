"""The fiducial-artefact study of Wang, Cheung and Kong (2022): nine poses, three repetitions.

Times the Monte Carlo of ``examples/studies/wang2022.toml`` (5 balls x 30 points x 27
probings = 12 150 probing-noise values per trial, the CMM calibration's 15, the exact
identification, distances, r_max/r_avg and rigid best fits of every trial, batched over
trials), the noise-free chain and the GUM beside it. Target: 10^4 trials in <= 5 s.

Run: ``python benchmarks/bench_artefact.py [--trials N] [--workers W] [--repeat R]``.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

import numpy as np

from mtmc import parallel
from mtmc.artefact.simulation import gum_outputs, study_model
from mtmc.study import load_study
from mtmc.uncertainty import monte_carlo
from mtmc.uncertainty.heap import keep_heap

STUDY = Path(__file__).resolve().parents[1] / "examples" / "studies" / "wang2022.toml"


def main() -> int:
    keep_heap()  # as the mtmc command does when it starts
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=10_000)
    ap.add_argument("--workers", type=int, nargs="*", default=[1, 2])
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args()
    threads = os.environ.get("OPENBLAS_NUM_THREADS", "not set (BLAS default)")
    print(
        f"python {platform.python_version()}, numpy {np.__version__}, {os.cpu_count()} CPUs, "
        f"OPENBLAS_NUM_THREADS {threads}, load average {os.getloadavg()[0]:.1f}"
    )
    study = load_study(STUDY).study
    t0 = time.perf_counter()
    model, inputs, pr = study_model(study, split=True)
    t_prep = time.perf_counter() - t0
    print(f"noise-free chain (Newton readings, 45 sphere fits, maps): {t_prep:.3f} s")
    t0 = time.perf_counter()
    gum_outputs(study, pr)
    print(
        f"GUM beside it (420 inputs, central differences in one batch): "
        f"{time.perf_counter() - t0:.2f} s"
    )
    width = sum(d.dim for d in inputs.values())
    print(f"inputs per trial: {width} ({', '.join(f'{k} {d.dim}' for k, d in inputs.items())})")
    ref = None
    for w in args.workers:
        # one BLAS thread inside the blocks (mtmc's default), beside the process's own
        # setting inside them (the user's default BLAS threads), alternately in one run
        best = {1: np.inf, None: np.inf}
        cpu = {1: np.inf, None: np.inf}
        for _ in range(args.repeat):
            for blas in (1, None):
                parallel.BLAS_THREADS = blas
                t0, c0 = time.perf_counter(), time.process_time()
                res = monte_carlo(
                    model, inputs, trials=args.trials, seed=2022, keep=False, workers=w
                )
                best[blas] = min(best[blas], time.perf_counter() - t0)
                cpu[blas] = min(cpu[blas], time.process_time() - c0)
                r = np.array([res[f"r_max_measured/{p}"].u for p in range(9)])
                if ref is None:
                    ref = r
                same = np.allclose(r, ref, rtol=1e-12, atol=0)
        parallel.BLAS_THREADS = 1
        print(
            f"Monte Carlo {args.trials} trials, workers={w}: {best[1]:.2f} s wall, "
            f"{cpu[1]:.2f} s CPU ({args.trials / best[1]:,.0f} trials/s; same numbers as "
            f"workers=1: {same}); with the process's BLAS threads in the blocks "
            f"{best[None]:.2f} s wall, {cpu[None]:.2f} s CPU ({best[None] / best[1]:.2f}x); "
            f"target <= 5 s for 10^4: {'met' if best[1] * 1e4 / args.trials <= 5 else 'NOT met'}"
        )
    print("u(r_max) per pose, um:", np.round(ref * 1e3, 3).tolist())
    print(f"load average after the runs: {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
