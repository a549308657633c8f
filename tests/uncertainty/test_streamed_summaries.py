"""The histogram and convergence curve of a run that does not keep its samples.

A run too large to keep its samples (``keep=False``, or ``keep="auto"`` above
``KEEP_AUTO_BYTES``) still gives the report its histogram and convergence curve: the
curve streamed by the engine at seed-block ends and the histogram of the quantile
sketch. They are compared here with the same run's kept samples (a second method), and
the streamed curve is the same bits whatever the workers and evaluation blocks.
"""

from __future__ import annotations

import numpy as np
import pytest

from mtmc.uncertainty import monte_carlo
from mtmc.uncertainty import montecarlo as mc_module
from mtmc.uncertainty.results import CONVERGENCE_CHUNK, convergence
from mtmc.uncertainty.sampling import SEED_BLOCK_SIZE

INPUTS = {"a": "normal(1, 0.1)", "b": "uniform(0, 2)"}
TRIALS = 300_000


def model(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a * b + np.sin(a)


@pytest.fixture(scope="module")
def runs():
    kept = monte_carlo(model, INPUTS, trials=TRIALS, seed=3, keep=True)
    streamed = monte_carlo(model, INPUTS, trials=TRIALS, seed=3, keep=False, sketch=True)
    return kept, streamed


def test_streamed_curve_is_the_curve_of_the_kept_samples(runs):
    kept, streamed = runs
    m, est, u = streamed.convergence()
    x = kept.samples
    assert m[0] == SEED_BLOCK_SIZE
    assert m[-1] == TRIALS
    # read at the first seed-block end at or past TRACE_STEP times the one before
    s, step = SEED_BLOCK_SIZE, mc_module.TRACE_STEP
    want = [s]
    while want[-1] < TRIALS:
        want.append(min(TRIALS, max(want[-1] + s, -(-int(np.ceil(want[-1] * step)) // s) * s)))
    assert m.tolist() == want
    ref_est = np.array([x[:k].mean() for k in m])
    ref_u = np.array([x[:k].std(ddof=1) for k in m])
    # merged block moments against NumPy's two-pass sums: rounding of ~M additions
    scale = kept.u
    assert np.max(np.abs(est - ref_est)) <= 1e-12 * scale
    assert np.max(np.abs(u - ref_u)) <= 1e-12 * scale
    assert est[-1] == streamed.estimate
    assert u[-1] == streamed.u


def test_streamed_curve_is_the_same_bits_on_any_workers(runs):
    _, streamed = runs
    other = monte_carlo(
        model, INPUTS, trials=TRIALS, seed=3, keep=False, sketch=True, workers=2, block_size=5000
    )
    for a, b in zip(streamed.convergence(), other.convergence(), strict=True):
        assert np.array_equal(a, b)


def test_histogram_of_the_sketch_within_its_rank_error(runs):
    kept, streamed = runs
    h = streamed.histogram(60)
    assert h.counts.sum() == TRIALS
    exact, _ = np.histogram(kept.samples, bins=h.edges)
    # each bin has two edges, each read to within the sketch's rank error
    assert np.max(np.abs(exact - h.counts)) <= 2 * streamed.rank_error
    assert np.isclose(np.sum(h.density * np.diff(h.edges)), 1.0, rtol=1e-12)


def test_histogram_of_a_sketch_needs_a_number_of_bins(runs):
    _, streamed = runs
    with pytest.raises(Exception, match="number of bins"):
        streamed.histogram("auto")


@pytest.mark.parametrize("n", [2, 3, 10, CONVERGENCE_CHUNK, CONVERGENCE_CHUNK + 7])
def test_convergence_in_chunks_is_one_cumsum(n):
    # the curve of kept samples is summed in chunks of CONVERGENCE_CHUNK values: the
    # same additions in the same order as one cumsum over all values
    x = np.random.default_rng(5).normal(5.0, 2.0, size=n)
    m, est, u = convergence(x, 60)
    shift = float(np.mean(x[: min(n, 100)]))
    d = x - shift
    s1, s2 = np.cumsum(d)[m - 1], np.cumsum(d * d)[m - 1]
    assert np.array_equal(est, shift + s1 / m)
    assert np.array_equal(u, np.sqrt(np.clip((s2 - s1 * s1 / m) / (m - 1), 0.0, None)))


def test_a_study_too_large_to_keep_its_samples_has_its_report_summaries(monkeypatch):
    from mtmc.study.spec import loads_study

    text = (
        'kind = "propagate"\nmodel = "a * b"\n[inputs]\na = "normal(1, 0.1)"\nb = "uniform(0, 2)"\n'
    )
    study = loads_study(text, file="s.toml")
    kept = study.run(trials=100_000, seed=1).quantities[0]
    # the same study above the size kept for the report: the same summaries, streamed
    monkeypatch.setattr(mc_module, "KEEP_AUTO_BYTES", 0)
    q = study.run(trials=100_000, seed=1).quantities[0]
    assert q.convergence.m[-1] == 100_000
    assert len(q.histogram.edges) == 61
    # the kept run's u is a two-pass sum over the samples, the streamed one merged block
    # moments: the same value to the rounding of M additions
    assert q.mc.u == pytest.approx(kept.mc.u, rel=1e-12)
    assert q.mc.estimate == pytest.approx(kept.mc.estimate, rel=1e-12)
    # the intervals: order statistics against the sketch's, to within its rank error
    assert q.mc.symmetric == pytest.approx(kept.mc.symmetric, abs=1e-2 * kept.mc.u)
    assert q.convergence.u[-1] == pytest.approx(kept.convergence.u[-1], rel=1e-12)


def test_sketch_with_the_default_sort_is_the_stable_sort_bits(monkeypatch):
    from mtmc.uncertainty import sketch as sk

    # ties and zeros of both signs, where a sort that is not stable could show
    rng = np.random.default_rng(2)
    x = np.round(rng.normal(size=100_000), 1) * rng.choice([1.0, -1.0], size=100_000)
    x[::7] = -0.0

    def build():
        a = sk.QuantileSketch.of(x[:60_000], capacity=512)
        return a.merge(sk.QuantileSketch.of(x[60_000:], capacity=512))

    fast = build()
    real_sort = np.sort
    monkeypatch.setattr(
        sk.np, "sort", lambda a, *args, **kw: real_sort(a, *args, **{**kw, "kind": "stable"})
    )
    stable = build()
    assert len(fast.levels) == len(stable.levels)
    for a, b in zip(fast.levels, stable.levels, strict=True):
        assert a.tobytes() == b.tobytes()
