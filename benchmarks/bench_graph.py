"""Graph run of examples/graphs/axis_c.toml vs just drawing its random inputs, side by side.

The floor for any Monte Carlo of a model is drawing its inputs; the graph engine should
cost at most 1.5x that (target of docs/performance.md). Both sides use the same inputs,
the same seed and block size, and the same sampler (mtmc.uncertainty.iter_blocks); the
runs keep no samples. The graph is run as a user runs it, ``run_graph(load_graph(path),
trials=M)`` (file read and checked, every place summarised), and with the two outputs
only. For comparison the script also times plain NumPy drawing the same number of normal
values from one Generator (no seed blocks, no name-keyed streams), and drawing the inputs
and firing every transition with nothing summarised (the compiled model on each block of
``iter_blocks``): what any summary of the places is added to.

Each line is timed in interleaved repeats (best of ``repeats``), by the wall clock and by
the CPU time of this process (user + system: on a shared machine the wall time also
counts the time other processes held the core; page faults are system time). The load
average is printed with the figures.

Usage: python benchmarks/bench_graph.py [M] [repeats]
"""

from __future__ import annotations

import os
import resource
import sys
import time
from pathlib import Path

import numpy as np

from mtmc.graph import check_graph, load_graph, run_graph
from mtmc.graph.run import GRAPH_BLOCK_SIZE, GraphModel, random_inputs
from mtmc.uncertainty.heap import keep_heap
from mtmc.uncertainty.sampling import iter_blocks

ROOT = Path(__file__).resolve().parents[1]
FILE = ROOT / "examples" / "graphs" / "axis_c.toml"


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def timed(fn):
    c0, t0 = _cpu(), time.perf_counter()
    fn()
    return time.perf_counter() - t0, _cpu() - c0


def main() -> None:
    m = int(float(sys.argv[1])) if len(sys.argv) > 1 else 1_000_000
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    kept = keep_heap()  # as the mtmc command does when it starts
    plan = check_graph(load_graph(FILE))
    inputs = random_inputs(plan)
    outputs = ["axis_c", "p_c"]

    def draw_only():
        for _a, _b, _samples in iter_blocks(inputs, m, 1234, GRAPH_BLOCK_SIZE):
            pass

    def plain_numpy():
        rng = np.random.default_rng(1234)
        for d in inputs.values():
            rng.normal(d.mean, d.std, m)  # type: ignore[attr-defined]

    model = GraphModel(plan, ())

    def transitions_only():
        for _a, _b, samples in iter_blocks(inputs, m, 1234, GRAPH_BLOCK_SIZE):
            model(**samples)

    def as_a_user():
        run_graph(load_graph(FILE), trials=m, seed=1234)

    def outputs_only():
        run_graph(load_graph(FILE), trials=m, seed=1234, outputs=outputs)

    cases = {
        "draw the inputs only (iter_blocks), the floor": draw_only,
        "plain NumPy: one Generator, rng.normal": plain_numpy,
        "run_graph(load_graph(file), trials=M): all places": as_a_user,
        "the same, outputs axis_c and p_c": outputs_only,
        "draw and fire every transition, nothing summarised": transitions_only,
    }
    as_a_user()  # warm-up
    best = {k: [np.inf, np.inf] for k in cases}
    for _ in range(repeats):  # interleaved, so that all see the same machine load
        for k, fn in cases.items():
            wall, cpu = timed(fn)
            best[k][0] = min(best[k][0], wall)
            best[k][1] = min(best[k][1], cpu)
    keys = list(cases)
    floor = best[keys[0]]
    print(
        f"axis_c.toml: {len(inputs)} random inputs, {len(plan.steps)} transitions, "
        f"{len(plan.types)} places, M = {m:.0e}, block {GRAPH_BLOCK_SIZE}, best of {repeats}; "
        f"heap kept: {kept}; load average {os.getloadavg()[0]:.2f}"
    )
    print(f"{'what':<52}{'wall s':>8}{'ratio':>7}{'CPU s':>8}{'ratio':>7}")
    for k, (wall, cpu) in best.items():
        print(f"{k:<52}{wall:>8.3f}{wall / floor[0]:>7.2f}{cpu:>8.3f}{cpu / floor[1]:>7.2f}")
    for k, short in ((keys[2], "all places"), (keys[3], "outputs only")):
        ok = best[k][1] <= 1.5 * floor[1]
        print(f"target, {short}: CPU time <= 1.5 x drawing: {'met' if ok else 'NOT met'}")


if __name__ == "__main__":
    main()
