"""Graph run of examples/graphs/axis_c.toml vs just drawing its random inputs, side by side.

The floor for any Monte Carlo of a model is drawing its inputs; the graph engine should
cost at most 1.5x that (target of docs/performance.md). Both sides use the same inputs,
the same seed and block size, and the same sampler (mtmc.uncertainty.iter_blocks); the
run summarises the output places (running sums) and keeps no samples.

Usage: python benchmarks/bench_graph.py [M] [repeats]
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from mtmc.graph import check_graph, load_graph, run_graph
from mtmc.graph.run import GRAPH_BLOCK_SIZE, random_inputs
from mtmc.uncertainty.sampling import iter_blocks

ROOT = Path(__file__).resolve().parents[1]


def best(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    m = int(float(sys.argv[1])) if len(sys.argv) > 1 else 1_000_000
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    plan = check_graph(load_graph(ROOT / "examples" / "graphs" / "axis_c.toml"))
    inputs = random_inputs(plan)
    outputs = ["axis_c", "p_c"]

    def draw_only():
        for _a, _b, _samples in iter_blocks(inputs, m, 1234, GRAPH_BLOCK_SIZE):
            pass

    def graph_run():
        run_graph(plan, m, 1234, outputs=outputs)

    def graph_run_all():
        run_graph(plan, m, 1234)

    graph_run()  # warm-up
    t_draw, t_run = [], []
    for _ in range(repeats):  # interleaved, so both see the same machine load
        t_draw.append(best(draw_only, 1))
        t_run.append(best(graph_run, 1))
    t_draw, t_run = min(t_draw), min(t_run)
    t_all = best(graph_run_all, 1)
    n_trans = len(plan.steps)
    print(
        f"axis_c.toml: {len(inputs)} random inputs, {n_trans} transitions, M = {m:.0e}, "
        f"block {GRAPH_BLOCK_SIZE}, best of {repeats}"
    )
    print(f"{'what':<46}{'time s':>9}{'ratio':>8}")
    print(f"{'draw the inputs only (iter_blocks), the floor':<46}{t_draw:>9.3f}{1.0:>8.2f}")
    print(f"{'graph run, outputs axis_c and p_c':<46}{t_run:>9.3f}{t_run / t_draw:>8.2f}")
    print(
        f"{'graph run, all ' + str(len(plan.types)) + ' places summarised':<46}{t_all:>9.3f}"
        f"{t_all / t_draw:>8.2f}"
    )
    print(f"target: graph run <= 1.5 x drawing: {'met' if t_run <= 1.5 * t_draw else 'NOT met'}")


if __name__ == "__main__":
    main()
