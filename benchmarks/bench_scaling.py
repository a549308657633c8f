"""In-process vs two workers (threads, a Dask LocalCluster of two processes), same seed.

Three runs of the scaling page (docs/scaling.md), each with the defaults a user gets:

* the Stryczek Fig. 14 sweep of examples/graphs/bcs_origin.toml: 25 grid points
  (u_probe x u_axis, 5 x 5) of 10^5 trials each, grouped into about 4 tasks a worker;
* a scalar Monte Carlo of 10^8 trials (samples kept while they fit in 2 GiB; blocks
  grouped into about 8 tasks a worker), then with keep=False (moments and quantile
  sketches, merged by groups of 2^20 trials where they ran);
* the Monte Carlo of 4000 verifications of the 5408-point mesh of Aguado et al. 2016
  (examples/studies/aguado2016.toml, tracker at pos4): the run a user would move to a
  cluster.

Every parallel run is checked to give the same numbers as the in-process one. The Dask
cluster (`mtmc.parallel.local_cluster`) is started once, before the timings (its start-up
is printed apart), as a user with many runs would. Each run is timed in rounds (the
sweep 5, the verification 3, the kept samples 2, `keep=False` 1: the short runs more
often, as the machine's load moves them more), each round in-process, then 2 threads,
then Dask, so that a change in the load falls on the three alike; the table gives the
best of the rounds, their range, and the ratios of the best times. For the fastest Dask
round the time is split:

* workers' compute: the tasks' compute time on the workers (Dask's task stream), summed
  and divided by the workers, against the in-process run;
* waiting: the client's time waiting for the next task's result (submission, transfer,
  deserialisation, and workers still computing);
* merging: the client's time between results (the engine merging the digests in order);
* the rest: the one trial evaluated in the client to learn the outputs' shapes, setting
  up (a verification's reference identification and model, the shared arrays of kept
  samples) and the final summaries;
* bytes back: the pickled size of what the tasks returned (a second, untimed run); kept
  samples are written by the workers into the client's arrays (shared memory) and are
  not among them.

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
        f"(shapes, set-up, summaries) {rest:.2f} s; bytes back "
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
    rows: list[tuple[str, list[float], list[float], list[float]]] = []
    splits = []

    def case(
        name: str,
        make: Callable[..., Callable[[], Any]],
        same: Callable[[Any, Any], bool],
        rounds: int,
    ) -> None:
        """``rounds`` rounds of: in-process, 2 threads, Dask (interleaved, so that the
        machine's load falls on the three alike); the split of the fastest Dask round."""
        one, thr, dsk = [], [], []
        best = None
        for _ in range(rounds):
            t1, ref = timed(make())
            t2, got_t = timed(make(workers=2))
            t3, got_d, split = dask_run(make(executor="dask", scheduler=client), client)
            assert same(ref, got_t), name
            assert same(ref, got_d), name
            one.append(t1)
            thr.append(t2)
            dsk.append(t3)
            if best is None or t3 < best[0]:
                best = (t3, split)
            del ref, got_t, got_d
        assert best is not None
        rows.append((name, one, thr, dsk))
        splits.append((name, best[1]))

    def sweep(**kw: Any) -> Callable[[], Any]:
        return lambda: sweep_graph(graph, vary, "d_ac", trials=n_sweep, seed=1, **kw)

    def same_sweep(a: Any, b: Any) -> bool:
        return bool(np.array_equal(a.u, b.u))

    case(f"sweep 25 x {n_sweep:.0e} trials", sweep, same_sweep, rounds=5)

    # the defaults a user gets: samples kept while they fit in 2 GiB; then the same run
    # with keep=False (moments and the quantile sketch, streamed)
    for label, extra, rounds in (
        ("samples kept", {}, 2),
        ("keep=False", {"keep": False, "sketch": True}, 1),
    ):

        def scalar(extra: dict[str, Any] = extra, **kw: Any) -> Callable[[], Any]:
            return lambda: monte_carlo(model, INPUTS, trials=n_mc, seed=1, **extra, **kw)

        def same_scalar(a: Any, b: Any) -> bool:
            return bool(
                a.u == b.u
                and a.estimate == b.estimate
                and a.coverage_interval(0.95) == b.coverage_interval(0.95)
            )

        case(f"scalar MC {n_mc:.0e}, {label}", scalar, same_scalar, rounds=rounds)

    ver = load_study(ROOT / "examples" / "studies" / "aguado2016.toml").study.verification(
        "mesh5408", "pos4"
    )

    def verification(**kw: Any) -> Callable[[], Any]:
        return lambda: simulate(ver, n_ver, 7, **kw)

    def same_ver(a: Any, b: Any) -> bool:
        return bool(np.array_equal(a.ve_u, b.ve_u) and np.array_equal(a.ve_samples, b.ve_samples))

    case(f"verification 5408 pts x {n_ver}", verification, same_ver, rounds=3)

    def span(ts: list[float]) -> str:
        return f"{min(ts):.2f}" + (f" ({min(ts):.2f}-{max(ts):.2f})" if len(ts) > 1 else "")

    print("best of the rounds (range); ratios of the best times")
    print(f"{'run':<34}{'rounds':>7}{'1 process s':>20}{'2 threads':>26}{'Dask 2 procs':>26}")
    for name, a, b, c in rows:
        print(
            f"{name:<34}{len(a):>7}{span(a):>20}{span(b):>18} ({min(a) / min(b):.2f}x)"
            f"{span(c):>18} ({min(a) / min(c):.2f}x)"
        )
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
