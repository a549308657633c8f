"""In-process vs two workers (threads, a Dask LocalCluster of two processes), same seed.

Two runs of the scaling page (docs/scaling.md):

* the Stryczek Fig. 14 sweep of examples/graphs/bcs_origin.toml: 25 grid points
  (u_probe x u_axis, 5 x 5) of 10^5 trials each; one grid point is one task;
* a scalar Monte Carlo of 10^8 trials with the defaults a user gets (samples kept while
  they fit in 2 GiB; blocks grouped into about 8 tasks a worker), then with keep=False
  (moments and quantile sketches, merged by groups of 2^20 trials where they ran).

Every parallel run is checked to give the same numbers as the in-process one. The Dask
cluster (`mtmc.parallel.local_cluster`) is started once, before the timings (its start-up
is printed apart), as a user with many runs would. The per-block scheduling overhead is
measured with a model that does nothing: (time of N empty blocks on Dask) / N.

Usage: python benchmarks/bench_scaling.py [scale]   (scale 1 = the sizes above)
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from mtmc.graph import load_graph
from mtmc.graph.sweep import sweep_graph
from mtmc.parallel import local_cluster, map_blocks
from mtmc.uncertainty.heap import keep_heap
from mtmc.uncertainty.montecarlo import monte_carlo

ROOT = Path(__file__).resolve().parents[1]


def model(x1, x2, x3):
    return x1 * np.cos(x2) + x3


INPUTS = {"x1": "normal(10, 0.1)", "x2": "uniform(-0.1, 0.1)", "x3": "t(5, 0, 0.01)"}


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def main() -> None:
    keep_heap()  # as the mtmc command does when it starts
    import distributed

    scale = float(sys.argv[1]) if len(sys.argv) > 1 else 1.0
    t_start, (cluster, client) = timed(lambda: (c := local_cluster(2), distributed.Client(c)))
    print(f"Dask LocalCluster, 2 worker processes: start-up {t_start:.2f} s")
    graph = load_graph(ROOT / "examples" / "graphs" / "bcs_origin.toml")
    vary = {
        "probe.u_probe": np.linspace(0.0005, 0.0025, 5),
        "probe.u_axis": np.linspace(0.001, 0.005, 5),
    }
    n_sweep = max(1000, int(1e5 * scale))
    n_mc = max(10**6, int(1e8 * scale))
    rows = []

    t1, ref = timed(lambda: sweep_graph(graph, vary, "d_ac", trials=n_sweep, seed=1))
    t2, thr = timed(lambda: sweep_graph(graph, vary, "d_ac", trials=n_sweep, seed=1, workers=2))
    t3, dsk = timed(
        lambda: sweep_graph(
            graph, vary, "d_ac", trials=n_sweep, seed=1, executor="dask", scheduler=client
        )
    )
    assert np.array_equal(ref.u, thr.u)
    assert np.array_equal(ref.u, dsk.u)
    rows.append((f"sweep 25 x {n_sweep:.0e} trials", t1, t2, t3))

    # the defaults a user gets: samples kept while they fit in 2 GiB; then the same run
    # with keep=False (moments and the quantile sketch, streamed)
    for label, extra in (("samples kept", {}), ("keep=False", {"keep": False, "sketch": True})):
        kw: dict[str, Any] = {"trials": n_mc, "seed": 1, **extra}
        t1, ref = timed(lambda kw=kw: monte_carlo(model, INPUTS, **kw))
        t2, thr = timed(lambda kw=kw: monte_carlo(model, INPUTS, workers=2, **kw))
        t3, dsk = timed(
            lambda kw=kw: monte_carlo(model, INPUTS, executor="dask", scheduler=client, **kw)
        )
        assert ref.u == thr.u == dsk.u
        assert ref.estimate == thr.estimate == dsk.estimate
        assert ref.coverage_interval(0.95) == dsk.coverage_interval(0.95)
        rows.append((f"scalar MC {n_mc:.0e}, {label}", t1, t2, t3))

    print(f"{'run':<30}{'1 process s':>12}{'2 threads':>16}{'Dask 2 procs':>16}")
    for name, a, b, c in rows:
        print(f"{name:<30}{a:>12.2f}{b:>9.2f} ({a / b:.2f}x){c:>9.2f} ({a / c:.2f}x)")
    print("same numbers in every column: yes (checked)")

    ntask = 200
    t_empty, _ = timed(
        lambda: list(map_blocks(int, range(ntask), executor="dask", scheduler=client))
    )
    print(f"Dask scheduling overhead: {1e3 * t_empty / ntask:.1f} ms per task ({ntask} tasks)")
    client.close()
    cluster.close()


if __name__ == "__main__":
    main()
