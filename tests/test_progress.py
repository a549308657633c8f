"""Progress callbacks of the long runs: they see every block and change no number.

Reference: the same run without a callback (bit-for-bit equality of every result), and
the block layout itself (``done`` runs through the block ends ``min(k·b, M)``).
"""

from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rich.console import Console

from mtmc.cli.common import progress_bar, progress_wanted
from mtmc.graph import load_graph, run_graph, sweep_graph
from mtmc.uncertainty.montecarlo import adaptive_block_size, monte_carlo

EXAMPLES = Path(__file__).resolve().parent / ".." / "examples" / "graphs"
INPUTS = {"a": "normal(2, 0.1)", "b": "uniform(2.5, 3.5)", "c": "t(8, 0, 0.05)"}


def model(a, b, c):
    return a * b + c


class Recorder:
    def __init__(self) -> None:
        self.calls: list[tuple[int, int | None]] = []

    def __call__(self, done: int, total: int | None) -> None:
        self.calls.append((done, total))

    @property
    def done(self) -> list[int]:
        return [d for d, _ in self.calls]


@pytest.mark.parametrize("workers", [1, 2])
def test_fixed_monte_carlo_same_numbers_and_every_block(workers):
    rec = Recorder()
    kw = {"trials": 50_000, "seed": 11, "block_size": 7_000, "workers": workers}
    plain = monte_carlo(model, INPUTS, **kw)
    seen = monte_carlo(model, INPUTS, **kw, progress=rec)
    np.testing.assert_array_equal(seen.samples, plain.samples)
    assert (seen.estimate, seen.u) == (plain.estimate, plain.u)
    assert rec.done == [min(k * 7_000, 50_000) for k in range(1, 9)]
    assert {t for _, t in rec.calls} == {50_000}


@settings(max_examples=25, deadline=None)
@given(trials=st.integers(2, 3_000), block=st.integers(1, 1_200))
def test_fixed_monte_carlo_done_runs_through_the_block_ends(trials, block):
    rec = Recorder()
    r = monte_carlo(model, INPUTS, trials=trials, seed=5, block_size=block, progress=rec)
    assert rec.done == [min(k * block, trials) for k in range(1, math.ceil(trials / block) + 1)]
    assert all(t == trials for _, t in rec.calls)
    assert r.trials == trials


def test_adaptive_total_unknown_until_it_stops():
    rec = Recorder()
    kw = {"seed": 3, "adaptive": True, "ndig": 1}
    plain = monte_carlo(model, INPUTS, **kw)
    seen = monte_carlo(model, INPUTS, **kw, progress=rec)
    np.testing.assert_array_equal(seen.samples, plain.samples)
    h = adaptive_block_size(0.95)
    n = plain.blocks
    assert n is not None
    assert n >= 2
    # one call per block with total None, then the final (M, M)
    assert rec.calls == [(k * h, None) for k in range(1, n + 1)] + [(n * h, n * h)]
    assert rec.calls[-1] == (plain.trials, plain.trials)


def test_run_graph_same_numbers_and_every_block():
    g = load_graph(EXAMPLES / "axis_c.toml")
    rec = Recorder()
    plain = run_graph(g, 20_000, seed=9, block_size=3_000, keep=["axis_c"])
    seen = run_graph(g, 20_000, seed=9, block_size=3_000, keep=["axis_c"], progress=rec)
    for name, s in plain.places.items():
        np.testing.assert_array_equal(seen.places[name].estimate_vector, s.estimate_vector)
        np.testing.assert_array_equal(seen.places[name].cov, s.cov)
    np.testing.assert_array_equal(seen.result("axis_c").samples, plain.result("axis_c").samples)
    assert rec.calls == [(min(k * 3_000, 20_000), 20_000) for k in range(1, 8)]


def test_sweep_counts_trials_over_the_whole_grid():
    g = load_graph(EXAMPLES / "ball_centre.toml")
    vary = {"probe.u_probe": [0.001, 0.002, 0.003], "probe.u_axis": [0.001, 0.002]}
    rec = Recorder()
    plain = sweep_graph(g, vary, "cx", trials=700, seed=4)
    seen = sweep_graph(g, vary, "cx", trials=700, seed=4, progress=rec)
    np.testing.assert_array_equal(seen.u, plain.u)
    np.testing.assert_array_equal(seen.estimate, plain.estimate)
    # 700 trials fit in one graph block: one call per grid point
    assert rec.calls == [(700 * k, 6 * 700) for k in range(1, 7)]


def test_progress_errors_propagate():
    def boom(*_):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        monte_carlo(model, INPUTS, trials=1_000, seed=1, progress=boom)


def test_progress_bar_helper_off_and_on():
    assert not progress_wanted(False)
    assert progress_wanted(True)
    with progress_bar("x", False) as bar:  # no bar: only the estimate of a long run
        assert not hasattr(bar, "__self__")
        assert type(bar).__name__ == "_Estimate"
    buf = io.StringIO()
    con = Console(file=buf, width=100)  # not a terminal: the final state printed once
    with progress_bar("Monte Carlo", True, console=con) as bar:
        assert bar is not None
        monte_carlo(model, INPUTS, trials=30_000, seed=2, block_size=10_000, progress=bar)
    text = buf.getvalue()
    assert text.count("\n") == 1
    assert "Monte Carlo" in text
    assert "30000/30000 trials" in text


def test_progress_wanted_follows_stderr(monkeypatch):
    class Tty(io.StringIO):
        def isatty(self) -> bool:
            return True

    monkeypatch.setattr("sys.stderr", io.StringIO())
    assert progress_wanted(None) is False
    monkeypatch.setattr("sys.stderr", Tty())
    assert progress_wanted(None) is True


def test_sweep_with_several_blocks_per_grid_point():
    from mtmc.graph.run import GRAPH_BLOCK_SIZE

    g = load_graph(EXAMPLES / "ball_centre.toml")
    trials = GRAPH_BLOCK_SIZE + 100
    rec = Recorder()
    res = sweep_graph(
        g, {"probe.u_axis": [0.001, 0.002]}, "cz", trials=trials, seed=8, progress=rec
    )
    plain = sweep_graph(g, {"probe.u_axis": [0.001, 0.002]}, "cz", trials=trials, seed=8)
    np.testing.assert_array_equal(res.u, plain.u)
    ends = [GRAPH_BLOCK_SIZE, trials]
    assert rec.done == [*ends, *(trials + e for e in ends)]
    assert {t for _, t in rec.calls} == {2 * trials}
