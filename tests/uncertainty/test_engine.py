"""One engine for every model: named outputs, streamed moments, wide inputs, bounded memory."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from mtmc.errors import InputError
from mtmc.uncertainty.distributions import IID, Normal, Uniform, parse_distribution
from mtmc.uncertainty.montecarlo import monte_carlo
from mtmc.uncertainty.results import Moments, MonteCarloResult, MonteCarloResults
from mtmc.uncertainty.sampling import (
    MAX_SEED_BLOCK_VALUES,
    SEED_BLOCK_SIZE,
    input_generator,
    iter_blocks,
    sample_inputs,
    seed_block_trials,
)

INPUTS = {"x": Normal(1.0, 0.1), "y": Uniform(-1.0, 1.0)}


def _first(x, y):  # noqa: ARG001 (the engine passes every input by name)
    return x


def two(x, y):
    return {"sum": x + y, "pair": np.stack([x * y, x - y, np.exp(y)], axis=1)}


def test_iid_text_round_trip_and_moments():
    d = parse_distribution("iid(uniform(0, 2), 5)")
    assert isinstance(d, IID)
    assert d.dim == 5
    assert parse_distribution(str(d)) == d
    assert d.std.tolist() == pytest.approx([2 / np.sqrt(12)] * 5)
    z = d.sample(np.random.default_rng(3), 40_000)
    assert z.shape == (40_000, 5)
    # 200 000 values of U(0, 2): standard error of the mean 0.0013
    assert abs(z.mean() - 1.0) < 0.006
    with pytest.raises(Exception, match="scalar distribution"):
        IID(IID(Normal(0, 1), 2), 3)
    with pytest.raises(Exception, match="k >= 1"):
        parse_distribution("iid(normal(0, 1), 0)")


def test_seed_block_rule_keeps_narrow_inputs_and_bounds_wide_ones():
    assert seed_block_trials(0) == seed_block_trials(64) == SEED_BLOCK_SIZE
    assert seed_block_trials(65) == MAX_SEED_BLOCK_VALUES // 65
    assert seed_block_trials(10**7) == 1
    # a narrow input: still the first values of its seed block's generator
    x = sample_inputs({"x": Normal(0, 1)}, 10, seed=9)["x"]
    np.testing.assert_array_equal(x, input_generator(9, 0, "x").standard_normal(10))
    # a wide input: seed block k of its own size, row by row
    w = IID(Normal(0, 1), 300)
    s = seed_block_trials(300)
    got = sample_inputs({"w": w}, s + 5, seed=9)["w"]
    ref1 = input_generator(9, 1, "w").standard_normal(s * 300).reshape(s, 300)[:5]
    np.testing.assert_array_equal(got[s:], ref1)


@pytest.mark.parametrize("block_size", [1, 97, 4096, 100_000])
def test_wide_input_draws_do_not_depend_on_block_size(block_size):
    inputs = {"w": IID(Normal(0, 1), 500), "x": Normal(0, 1)}
    ref = sample_inputs(inputs, 5000, seed=4)
    got = {
        k: np.concatenate([s[k] for _, _, s in iter_blocks(inputs, 5000, 4, block_size)])
        for k in inputs
    }
    for k in inputs:
        np.testing.assert_array_equal(got[k], ref[k])


def test_wide_input_run_memory_is_bounded():
    """10 trials of a 16 224-component input: a few MiB, not 16 384 x 16 224 x 8 B = 2 GiB."""
    inputs = {"noise": IID(Normal(0, 0.004), 16_224)}
    tracemalloc.start()
    r = monte_carlo(lambda noise: noise.std(axis=1), inputs, trials=10, seed=1)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 64 * 2**20
    # each trial's std of 16 224 N(0, 0.004²) values is 0.004 to ±2 %
    assert np.all(np.abs(r.samples / 0.004 - 1) < 0.02)


def test_named_outputs_match_single_output_runs():
    r = monte_carlo(two, INPUTS, trials=30_000, seed=11)
    assert isinstance(r, MonteCarloResults)
    assert list(r) == ["sum", "pair"]
    assert len(r) == 2
    assert r.trials == 30_000
    alone = monte_carlo(lambda x, y: x + y, INPUTS, trials=30_000, seed=11)
    np.testing.assert_array_equal(r["sum"].samples, alone.samples)
    assert r["pair"].dim == 3
    assert r["sum"].dim == 0
    with pytest.raises(InputError, match="no output 'nope'"):
        r["nope"]


def test_moments_only_equal_the_sample_summaries():
    full = monte_carlo(two, INPUTS, trials=50_000, seed=2)
    light = monte_carlo(two, INPUTS, trials=50_000, seed=2, keep=False)
    for name in ("sum", "pair"):
        a, b = full[name], light[name]
        assert not b.kept
        assert b.m == a.m
        np.testing.assert_allclose(b.estimate_vector, a.estimate_vector, rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(b.u_vector, a.u_vector, rtol=1e-11)
        np.testing.assert_allclose(b.cov, a.cov, rtol=1e-10, atol=1e-16)
    with pytest.raises(InputError, match="not kept"):
        light["sum"].coverage_interval(0.95)
    some = monte_carlo(two, INPUTS, trials=1000, seed=2, keep=["pair"])
    assert some["pair"].kept
    assert not some["sum"].kept
    with pytest.raises(InputError, match="keep names other"):
        monte_carlo(two, INPUTS, trials=1000, seed=2, keep=["other"])


@pytest.mark.parametrize(
    ("block_size", "workers", "executor"),
    [(1000, 1, "thread"), (7777, 2, "thread"), (30_000, 2, "process")],
)
def test_streamed_summaries_are_bit_identical_whatever_the_blocks(block_size, workers, executor):
    ref = monte_carlo(_module_model, INPUTS, trials=70_000, seed=5, keep=False)
    got = monte_carlo(
        _module_model,
        INPUTS,
        trials=70_000,
        seed=5,
        keep=False,
        block_size=block_size,
        workers=workers,
        executor=executor,
    )
    for name in ref:
        np.testing.assert_array_equal(got[name].estimate_vector, ref[name].estimate_vector)
        np.testing.assert_array_equal(got[name].cov, ref[name].cov)


def _module_model(x, y):
    return two(x, y)


def test_nan_omitted_from_every_output_alike():
    def model(x, y):
        return {"a": np.where(y > 0.9, np.nan, x), "b": y}

    r = monte_carlo(model, INPUTS, trials=20_000, seed=3, nan_policy="omit")
    assert r.omitted == r["a"].omitted > 0
    assert r["a"].m == r["b"].m == 20_000 - r.omitted
    assert r["b"].samples.max() <= 0.9
    with pytest.raises(InputError, match="output 'a' is not finite"):
        monte_carlo(model, INPUTS, trials=20_000, seed=3)


def test_runs_that_cannot_fit_are_refused_before_they_start():
    with pytest.raises(InputError, match=r"needs 7.45e\+03 GiB, more than half"):
        monte_carlo(_first, INPUTS, trials=10**12, seed=1, keep=True)


def test_auto_keep_streams_past_its_size_with_a_sketch(monkeypatch):
    import mtmc.uncertainty.montecarlo as mc

    monkeypatch.setattr(mc, "KEEP_AUTO_BYTES", 8 * 100_000)  # 100 000 numbers
    small = monte_carlo(two, INPUTS, trials=20_000, seed=4)
    assert small["sum"].kept
    assert small["pair"].kept
    big = monte_carlo(two, INPUTS, trials=200_000, seed=4)
    assert not big["sum"].kept
    assert not big["pair"].kept
    assert big["sum"].sketch is not None
    assert big["pair"].sketch is None
    exact = monte_carlo(two, INPUTS, trials=200_000, seed=4, keep=True)["sum"]
    s = np.sort(exact.samples)
    err = big["sum"].rank_error
    assert 0 < err < 0.002 * 200_000
    lo, hi = big["sum"].coverage_interval(0.95, "symmetric")
    elo, ehi = exact.coverage_interval(0.95, "symmetric")
    # each endpoint within the stated rank error of the exact order statistic
    for got, ref in ((lo, elo), (hi, ehi)):
        assert abs(np.searchsorted(s, got) - np.searchsorted(s, ref)) <= err + 1
    # shortest: it holds q ± 2 err values, and is no longer than the exact shortest
    # interval holding q + 2 err + 1 of them (its position on a flat-topped PDF is free)
    lo, hi = big["sum"].coverage_interval(0.95, "shortest")
    q = int(0.95 * 200_000)
    inside = np.searchsorted(s, hi, "right") - np.searchsorted(s, lo, "left")
    assert abs(inside - q) <= 2 * err + 1
    wide = q + 2 * err + 1
    assert hi - lo <= np.min(s[wide:] - s[:-wide]) + 1e-12


def test_contradictory_calls_are_refused():
    with pytest.raises(InputError, match="adaptive=True"):
        monte_carlo(_first, INPUTS, trials=1000, seed=1, adaptive=True)
    with pytest.raises(TypeError):
        monte_carlo(_first, INPUTS, 1000, 1, False)  # options are keyword-only
    with pytest.raises(InputError, match="keep"):
        monte_carlo(_first, INPUTS, trials=1000, seed=1, keep="x")


def test_moments_merge_is_the_moments_of_the_union():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(1001, 4)) * [1, 10, 100, 1e-3] + 5
    m = Moments.of(x[:10]).merge(Moments.of(x[10:600])).merge(Moments.of(x[600:]))
    assert m.n == 1001
    np.testing.assert_allclose(m.mean, x.mean(axis=0), rtol=1e-14)
    np.testing.assert_allclose(m.cov, np.cov(x, rowvar=False), rtol=1e-12, atol=1e-15)


def test_vector_summaries_are_read_only():
    r = monte_carlo(two, INPUTS, trials=2000, seed=1)
    for arr in (r["pair"].estimate_vector, r["pair"].u_vector, r["pair"].cov, r["pair"].samples):
        with pytest.raises(ValueError, match="read-only"):
            arr[0] = 99.0
    light = MonteCarloResult(
        samples=None, moments=Moments.of(np.ones((3, 1)) * [[1], [2], [3]]), trials=3, seed=None
    )
    assert light.estimate == 2.0
    assert light.u == 1.0


def _moments_pair_by_pair(xt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and M2 of the columns of a (d, n) array, one einsum per pair of rows."""
    mean = np.add.reduce(xt, axis=1) / xt.shape[1]
    dev = xt - mean[:, None]
    d = xt.shape[0]
    m2 = np.empty((d, d))
    for i in range(d):
        for j in range(i, d):
            m2[i, j] = m2[j, i] = np.einsum("m,m->", dev[i], dev[j])
    return mean, m2


@pytest.mark.parametrize("n", [2, 7, 8192, 8193, 16384, 20001])
@pytest.mark.parametrize("d", [1, 3, 6])
def test_moments_side_by_side_are_those_of_each_set(n: int, d: int) -> None:
    rng = np.random.default_rng(n + d)
    xs = [np.ascontiguousarray(rng.normal(size=(d, n)) * 0.01 + 150.0) for _ in range(3)]
    both = Moments.of_stack(xs)
    assert both.mean.shape == (3, d)
    assert both.m2.shape == (3, d, d)
    ys = [np.ascontiguousarray(rng.normal(size=(d, 99))) for _ in range(3)]
    merged = both.merge(Moments.of_stack(ys)).unstack()
    for p, x in enumerate(xs):
        mean, m2 = _moments_pair_by_pair(x)
        one = Moments.of_columns(x)
        np.testing.assert_array_equal(both.mean[p], one.mean)
        np.testing.assert_array_equal(both.m2[p], one.m2)
        # against one einsum per pair: the same bits with the NumPy of this writing, whose
        # einsum sums chunks of 8192 values in order; compared to rounding, so that
        # another NumPy's summation order does not fail a correct result
        np.testing.assert_allclose(one.mean, mean, rtol=1e-15)
        np.testing.assert_allclose(one.m2, m2, rtol=1e-12, atol=1e-15 * np.abs(m2).max())
        alone = Moments.of_columns(x).merge(Moments.of_columns(ys[p]))
        np.testing.assert_array_equal(merged[p].mean, alone.mean)
        np.testing.assert_array_equal(merged[p].m2, alone.m2)
