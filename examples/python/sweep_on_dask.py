"""The Stryczek Fig. 14 sweep on a local Dask cluster, checked against one process.

Run: python examples/python/sweep_on_dask.py [TRIALS_PER_POINT] [WORKERS]

The ``if __name__ == "__main__"`` guard is needed: Dask's worker processes import this
file again when they start, and must not start clusters of their own.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from distributed import Client

from mtmc.graph import load_graph
from mtmc.graph.sweep import sweep_graph
from mtmc.parallel import local_cluster

GRAPH = Path(__file__).resolve().parents[1] / "graphs" / "bcs_origin.toml"
VARY = {
    "probe.u_probe": np.linspace(0.0005, 0.0025, 5),  # mm
    "probe.u_axis": np.linspace(0.001, 0.005, 5),  # mm
}


def main(trials: int, workers: int) -> None:
    """Sweep in this process and on ``workers`` Dask worker processes; print both."""
    graph = load_graph(GRAPH)
    t0 = time.perf_counter()
    here = sweep_graph(graph, VARY, "d_ac", trials=trials, seed=1)
    t1 = time.perf_counter()
    with local_cluster(workers) as cluster, Client(cluster) as client:
        t2 = time.perf_counter()
        there = sweep_graph(
            graph, VARY, "d_ac", trials=trials, seed=1, executor="dask", scheduler=client
        )
        t3 = time.perf_counter()
    assert np.array_equal(here.u, there.u), "a cluster must not change a number"
    print(f"u(d_ac) / um over the grid (u_probe down, u_axis across), {trials} trials a point:")
    print(np.array2string(1e3 * here.u.reshape(5, 5), precision=3))
    print(f"one process {t1 - t0:.2f} s; {workers} Dask workers {t3 - t2:.2f} s; same numbers")


if __name__ == "__main__":
    main(
        int(sys.argv[1]) if len(sys.argv) > 1 else 100_000,
        int(sys.argv[2]) if len(sys.argv) > 2 else 2,
    )
