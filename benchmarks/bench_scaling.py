"""In-process vs two workers (threads, a Dask LocalCluster of two processes), same seed.

Three runs of the scaling page (docs/scaling.md), each with the defaults a user gets:

* the Stryczek Fig. 14 sweep of examples/graphs/bcs_origin.toml: 25 grid points
  (u_probe x u_axis, 5 x 5) of 10^5 trials each; one grid point is one task;
* a scalar Monte Carlo of 10^8 trials (samples kept while they fit in 2 GiB; blocks
  grouped into about 8 tasks a worker), then with keep=False (moments and quantile
  sketches, merged by groups of 2^20 trials where they ran);
* the Monte Carlo of 4000 verifications of the 5408-point mesh of Aguado et al. 2016
  (examples/studies/aguado2016.toml, tracker at pos4): the run a user would move to a
  cluster.

Every parallel run is checked to give the same numbers as the in-process one. The Dask
cluster (`mtmc.parallel.local_cluster`) is started once, before the timings (its start-up
is printed apart), as a user with many runs would. For each Dask run the time is split:

* workers' compute: the tasks' compute time on the workers (Dask's task stream), summed
  and divided by the workers, against the in-process run;
* waiting: the client's time waiting for the next task's result (submission, transfer,
  deserialisation, and workers still computing);
* merging: the client's time between results (the engine merging the digests in order);
* the rest: the first block (run in the client to learn the outputs' shapes), setting up
  and the final summaries;
* bytes back: the pickled size of what the tasks returned (a second, untimed run).

The per-block scheduling overhead is measured with a model that does nothing: (time of N
empty blocks on Dask) / N.

Usage: python benchmarks/bench_scaling.py [scale]   (scale 1 = the sizes above)
"""

from __future__ import annotations

import os
import pickle
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from mtmc import parallel
from mtmc.graph import load_graph
from mtmc.graph.sweep import sweep_graph
from mtmc.parallel import local_cluster, map_blocks
from mtmc.study import load_study
from mtmc.uncertainty.heap import keep_heap
from mtmc.uncertainty.montecarlo import monte_carlo
from mtmc.verification.simulate import simulate

ROOT = Path(__file__).resolve().parents[1]


def model(x1, x2, x3):
    return x1 * np.cos(x2) + x3


INPUTS = {"x1": "normal(10, 0.1)", "x2": "uniform(-0.1, 0.1)", "x3": "t(5, 0, 0.01)"}


def timed(fn: Callable[[], Any]) -> tuple[float, Any]:
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


class Stages:
    """The client's side of Dask runs: time waiting for results and between them, bytes."""

    def __init__(self, count_bytes: bool = False) -> None:
        self.wait = self.merge = 0.0
        self.tasks = self.bytes = 0
        self.count_bytes = count_bytes
        self._orig = parallel._dask_map

    def __enter__(self) -> Stages:
        orig = self._orig

        def staged(fn: Any, tasks: Any, client: Any) -> Iterator[Any]:
            it = orig(fn, tasks, client)
            while True:
                t0 = time.perf_counter()
                try:
                    result = next(it)
                except StopIteration:
                    self.wait += time.perf_counter() - t0
                    return
                self.wait += time.perf_counter() - t0
                self.tasks += 1
                if self.count_bytes:
                    self.bytes += len(pickle.dumps(result))
                t1 = time.perf_counter()
                yield result
                self.merge += time.perf_counter() - t1

        parallel._dask_map = staged  # type: ignore[assignment]
        return self

    def __exit__(self, *exc: object) -> None:
        parallel._dask_map = self._orig  # type: ignore[assignment]


def dask_run(run: Callable[[], Any], client: Any) -> tuple[float, Any, str]:
    """Time ``run`` on Dask and split its time; its bytes back from a second run."""
    import distributed

    with distributed.get_task_stream(client) as ts, Stages() as st:
        wall, out = timed(run)
    compute = sum(
        s["stop"] - s["start"]
        for rec in ts.data
        for s in rec["startstops"]
        if s["action"] == "compute"
    )
    with Stages(count_bytes=True) as sb:
        run()
    workers = max(1, len(client.scheduler_info()["workers"]))
    rest = wall - st.wait - st.merge
    split = (
        f"{st.tasks} tasks; workers' compute {compute:.2f} s ({compute / workers:.2f} s a "
        f"worker); client waiting {st.wait:.2f} s, merging {st.merge:.2f} s, the rest "
        f"(first block here, set-up, summaries) {rest:.2f} s; bytes back "
        f"{sb.bytes / 2**20:.1f} MiB ({sb.bytes / max(1, sb.tasks) / 2**20:.2f} MiB a task)"
    )
    return wall, out, split


def main() -> None:
    keep_heap()  # as the mtmc command does when it starts
    import distributed

    scale = float(sys.argv[1]) if len(sys.argv) > 1 else 1.0
    print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f} at the start")
    t_start, (cluster, client) = timed(lambda: (c := local_cluster(2), distributed.Client(c)))
    print(f"Dask LocalCluster, 2 worker processes: start-up {t_start:.2f} s")
    graph = load_graph(ROOT / "examples" / "graphs" / "bcs_origin.toml")
    vary = {
        "probe.u_probe": np.linspace(0.0005, 0.0025, 5),
        "probe.u_axis": np.linspace(0.001, 0.005, 5),
    }
    n_sweep = max(1000, int(1e5 * scale))
    n_mc = max(10**6, int(1e8 * scale))
    n_ver = max(200, int(4000 * scale))
    rows = []
    splits = []

    t1, ref = timed(lambda: sweep_graph(graph, vary, "d_ac", trials=n_sweep, seed=1))
    t2, thr = timed(lambda: sweep_graph(graph, vary, "d_ac", trials=n_sweep, seed=1, workers=2))
    t3, dsk, split = dask_run(
        lambda: sweep_graph(
            graph, vary, "d_ac", trials=n_sweep, seed=1, executor="dask", scheduler=client
        ),
        client,
    )
    assert np.array_equal(ref.u, thr.u)
    assert np.array_equal(ref.u, dsk.u)
    name = f"sweep 25 x {n_sweep:.0e} trials"
    rows.append((name, t1, t2, t3))
    splits.append((name, split))

    # the defaults a user gets: samples kept while they fit in 2 GiB; then the same run
    # with keep=False (moments and the quantile sketch, streamed)
    for label, extra in (("samples kept", {}), ("keep=False", {"keep": False, "sketch": True})):
        kw: dict[str, Any] = {"trials": n_mc, "seed": 1, **extra}
        t1, ref = timed(lambda kw=kw: monte_carlo(model, INPUTS, **kw))
        t2, thr = timed(lambda kw=kw: monte_carlo(model, INPUTS, workers=2, **kw))
        t3, dsk, split = dask_run(
            lambda kw=kw: monte_carlo(model, INPUTS, executor="dask", scheduler=client, **kw),
            client,
        )
        assert ref.u == thr.u == dsk.u
        assert ref.estimate == thr.estimate == dsk.estimate
        assert ref.coverage_interval(0.95) == dsk.coverage_interval(0.95)
        name = f"scalar MC {n_mc:.0e}, {label}"
        rows.append((name, t1, t2, t3))
        splits.append((name, split))
        del ref, thr, dsk

    ver = load_study(ROOT / "examples" / "studies" / "aguado2016.toml").study.verification(
        "mesh5408", "pos4"
    )
    t1, ref = timed(lambda: simulate(ver, n_ver, 7))
    t2, thr = timed(lambda: simulate(ver, n_ver, 7, workers=2))
    t3, dsk, split = dask_run(
        lambda: simulate(ver, n_ver, 7, executor="dask", scheduler=client), client
    )
    assert np.array_equal(ref.ve_u, thr.ve_u)
    assert np.array_equal(ref.ve_u, dsk.ve_u)
    name = f"verification 5408 pts x {n_ver}"
    rows.append((name, t1, t2, t3))
    splits.append((name, split))

    print(f"{'run':<34}{'1 process s':>12}{'2 threads':>16}{'Dask 2 procs':>16}")
    for name, a, b, c in rows:
        print(f"{name:<34}{a:>12.2f}{b:>9.2f} ({a / b:.2f}x){c:>9.2f} ({a / c:.2f}x)")
    print("same numbers in every column: yes (checked)")
    print("Dask runs, where the time went:")
    for name, split in splits:
        print(f"  {name}: {split}")

    ntask = 200
    t_empty, _ = timed(
        lambda: list(map_blocks(int, range(ntask), executor="dask", scheduler=client))
    )
    print(f"Dask scheduling overhead: {1e3 * t_empty / ntask:.1f} ms per task ({ntask} tasks)")
    print(f"load average at the end {os.getloadavg()[0]:.1f}")
    client.close()
    cluster.close()


if __name__ == "__main__":
    main()
