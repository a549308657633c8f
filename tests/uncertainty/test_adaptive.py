"""Adaptive Monte Carlo (JCGM 101 §7.9.4): stopping, tolerance, block multiples, reproducibility."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from mtmc.errors import ConvergenceError, InputError
from mtmc.uncertainty.montecarlo import adaptive_block_size, monte_carlo
from mtmc.uncertainty.tolerance import numerical_tolerance

INPUTS = {"x1": "normal(0, 1)", "x2": "normal(0.5, 0.5)"}


def model(x1, x2):
    return x1 + x2


def test_block_size_rule():
    # h = max(100/(1 - p), 10^4)
    assert adaptive_block_size(0.95) == 10_000
    assert adaptive_block_size(0.99) == 10_000
    assert adaptive_block_size(0.999) == 100_000
    assert adaptive_block_size(0.9999) == 1_000_000


def test_adaptive_stops_within_tolerance_of_exact_values():
    # Y = 1.7 (X1 + X2) ~ N(0.85, 1.7² 1.25): estimate, u and interval known in closed form;
    # u = 1.90 -> c = 19, l = -1 -> delta = 0.05 with ndig = 2
    # (with two blocks s rests on one degree of freedom and a run may stop there by chance;
    # seed 5 needs several blocks)
    r = monte_carlo(
        lambda x1, x2: 1.7 * (x1 + x2), INPUTS, seed=5, adaptive=True, ndig=2, kind="symmetric"
    )
    h = adaptive_block_size(0.95)
    assert r.adaptive
    assert r.trials % h == 0
    assert r.trials == r.blocks * h
    assert r.blocks >= 2
    assert r.block_trials == h
    assert r.samples.shape == (r.trials,)
    u = 1.7 * math.sqrt(1.25)
    delta = numerical_tolerance(r.u, 2)
    assert r.tolerance == delta == 0.05
    assert r.blocks > 2
    assert abs(r.estimate - 0.85) <= 2 * delta
    assert abs(r.u - u) <= 2 * delta
    lo, hi = r.coverage_interval(0.95, "symmetric")
    z = stats.norm.ppf(0.975)
    assert abs(lo - (0.85 - z * u)) <= 2 * delta
    assert abs(hi - (0.85 + z * u)) <= 2 * delta


def test_adaptive_matches_large_fixed_run_and_is_its_prefix():
    r = monte_carlo(model, INPUTS, seed=2, adaptive=True, tolerance=0.02)
    big = monte_carlo(model, INPUTS, trials=10**6, seed=2)
    assert r.tolerance == 0.02
    # same seed: the adaptive values are the first trials of the fixed run
    assert r.trials < 10**6
    np.testing.assert_array_equal(r.samples, big.samples[: r.trials])
    assert abs(r.estimate - big.estimate) <= 0.02
    assert abs(r.u - big.u) <= 0.02
    for a, b in zip(r.coverage_interval(), big.coverage_interval(), strict=True):
        assert abs(a - b) <= 2 * 0.02


def test_adaptive_stopping_rule_recomputed_by_hand():
    # the run stops at the first n >= 2 where 2 s <= delta for y, u and the shortest
    # interval's y_low, y_high
    r = monte_carlo(model, INPUTS, seed=3, adaptive=True, tolerance=0.015, kind="shortest")
    h = r.block_trials
    assert r.blocks > 3

    def criterion(n):
        blocks = r.samples[: n * h].reshape(n, h)
        srt = np.sort(blocks, axis=1)
        widths = srt[:, 9500:] - srt[:, : h - 9500]
        j = np.argmin(widths, axis=1)
        lo = srt[np.arange(n), j]
        hi = srt[np.arange(n), j + 9500]
        stats_ = np.stack([blocks.mean(1), blocks.std(1, ddof=1), lo, hi])
        s = stats_.std(axis=1, ddof=1) / math.sqrt(n)
        return bool(np.all(2 * s <= 0.015))

    assert criterion(r.blocks)
    assert not any(criterion(n) for n in range(2, r.blocks))


def test_adaptive_workers_identical():
    a = monte_carlo(model, INPUTS, seed=4, adaptive=True, ndig=1)
    b = monte_carlo(model, INPUTS, seed=4, adaptive=True, ndig=1, workers=3, block_size=3000)
    np.testing.assert_array_equal(a.samples, b.samples)
    assert a.blocks == b.blocks


def test_adaptive_vector_output():
    r = monte_carlo(
        lambda x1, x2: np.column_stack([x1 + x2, 10 * x2]), INPUTS, seed=5, adaptive=True, ndig=1
    )
    assert r.dim == 2
    assert r.trials % 10_000 == 0
    assert abs(r.u_vector[1] - 5.0) <= 2 * numerical_tolerance(5.0, 1)


def test_adaptive_gives_up():
    with pytest.raises(ConvergenceError, match="max_trials = 30000"):
        monte_carlo(model, INPUTS, seed=6, adaptive=True, ndig=4, max_trials=30_000)
    with pytest.raises(InputError, match="field tolerance"):
        monte_carlo(model, INPUTS, seed=6, adaptive=True, tolerance=-1.0)
