"""Randomised quasi-Monte Carlo (sampling="sobol"): the points of a seed block are a
scrambled Sobol net (balanced in every coordinate), independent from block to block; the
numbers do not depend on the evaluation blocks, the workers or the order of the inputs;
and the error of a smooth model's u falls far below that of pseudo-random draws."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mtmc import MultivariateNormal, Normal, Uniform, expression, monte_carlo
from mtmc.errors import InputError
from mtmc.uncertainty.montecarlo import RQMC_MIN_BLOCKS
from mtmc.uncertainty.sampling import (
    SEED_BLOCK_SIZE,
    sample_inputs,
    sobol_block_trials,
    sobol_layout,
    sobol_points,
)

SUM = expression("x1 + x2")
INPUTS = {"x1": Normal(0.0, 1.0), "x2": Normal(0.5, 0.5)}


def test_each_seed_block_is_a_balanced_net_scrambled_independently():
    n = 4096
    a, b = sobol_points(11, 0, 3, n), sobol_points(11, 1, 3, n)
    assert np.all((a > 0) & (a < 1))
    for u in (a, b):
        for j in range(3):  # one point in each of n equal intervals, in every coordinate
            assert np.array_equal(np.sort(np.floor(u[:, j] * n)), np.arange(n))
        # and one point in each of the n elementary boxes of 64 x 64 in coordinates 0, 1
        cells = np.floor(u[:, 0] * 64) * 64 + np.floor(u[:, 1] * 64)
        assert np.array_equal(np.sort(cells), np.arange(n))
    assert not np.allclose(a, b)  # another scrambling
    assert np.array_equal(a, sobol_points(11, 0, 3, n))


def test_numbers_do_not_depend_on_blocks_workers_or_input_order():
    m = 2 * SEED_BLOCK_SIZE
    r = monte_carlo(SUM, INPUTS, m, seed=5, sampling="sobol")
    r2 = monte_carlo(SUM, INPUTS, m, seed=5, sampling="sobol", block_size=5000, workers=2)
    swapped = {"x2": INPUTS["x2"], "x1": INPUTS["x1"]}
    r3 = monte_carlo(SUM, swapped, m, seed=5, sampling="sobol", block_size=777)
    assert np.array_equal(r.samples, r2.samples)
    assert np.array_equal(r.samples, r3.samples)
    assert r.sampling == "sobol"
    assert r.trials == m
    # the first trials of a longer run are those of a shorter one
    r4 = monte_carlo(SUM, INPUTS, 3 * SEED_BLOCK_SIZE, seed=5, sampling="sobol")
    assert np.array_equal(r4.samples[:m], r.samples)
    # sample_inputs() gives the same inputs: x1 from dimension 0, x2 from dimension 1 (sorted names)
    x = sample_inputs(INPUTS, m, 5, sampling="sobol")
    u = sobol_points(5, 1, 2, SEED_BLOCK_SIZE)
    np.testing.assert_array_equal(x["x2"][SEED_BLOCK_SIZE:], INPUTS["x2"].ppf(u[:, 1]))
    np.testing.assert_array_equal(r.samples, x["x1"] + x["x2"])


def test_short_run_maps_a_prefix_of_the_point_set_with_the_same_numbers():
    # a run of fewer trials than a seed block maps only the first 2^j points of it; the
    # numbers are those of the whole block, whatever the evaluation blocks
    whole = sample_inputs(INPUTS, SEED_BLOCK_SIZE, 9, sampling="sobol")
    u = sobol_points(9, 0, 2, SEED_BLOCK_SIZE)
    np.testing.assert_array_equal(whole["x1"], INPUTS["x1"].ppf(u[:, 0]))
    for m in (2, 16, 100, 3000):
        r = monte_carlo(SUM, INPUTS, m, seed=9, sampling="sobol", block_size=37)
        np.testing.assert_array_equal(r.samples, (whole["x1"] + whole["x2"])[:m])
        np.testing.assert_array_equal(sobol_points(9, 0, 2, 64), u[:64])


def test_error_of_u_far_below_pseudo_random():
    # u = sqrt(1.25): over 8 seeds of one seed block each, the RQMC error of u stays
    # below 1/20 of the pseudo-random standard error u / sqrt(2M)
    exact = math.sqrt(1.25)
    m = SEED_BLOCK_SIZE
    se_mc = exact / math.sqrt(2 * m)
    errs = [monte_carlo(SUM, INPUTS, m, seed=s, sampling="sobol").u - exact for s in range(8)]
    assert max(abs(e) for e in errs) < se_mc / 20
    errs_mc = [monte_carlo(SUM, INPUTS, m, seed=s).u - exact for s in range(8)]
    assert max(abs(e) for e in errs_mc) > se_mc / 4  # the check above can fail


def test_correlated_normals_through_the_cholesky_factor():
    cov = [[1.0, 0.8], [0.8, 2.0]]
    r = monte_carlo(
        lambda x: x[:, 0] - x[:, 1],
        {"x": MultivariateNormal([1.0, 0.0], cov)},
        SEED_BLOCK_SIZE,
        seed=2,
        sampling="sobol",
    )
    assert r.estimate == pytest.approx(1.0, abs=1e-4)
    assert r.u == pytest.approx(math.sqrt(1.0 + 2.0 - 1.6), abs=1e-4)


def test_adaptive_stops_on_independent_scramblings():
    kw = {"adaptive": True, "ndig": 3, "kind": "symmetric"}
    r = monte_carlo(SUM, INPUTS, seed=3, sampling="sobol", **kw)
    assert r.block_trials == SEED_BLOCK_SIZE
    assert r.trials == r.blocks * SEED_BLOCK_SIZE
    exact_u = math.sqrt(1.25)
    assert abs(r.u - exact_u) <= r.tolerance
    assert abs(r.coverage_interval(0.95, "symmetric")[1] - (0.5 + 1.959964 * exact_u)) <= 0.005
    plain = monte_carlo(SUM, INPUTS, seed=3, **kw)
    assert r.blocks == RQMC_MIN_BLOCKS
    assert r.trials * 5 <= plain.trials


def test_layout_block_size_and_bad_arguments():
    layout = sobol_layout({"b": Uniform(0, 1), "a": MultivariateNormal([0, 0], np.eye(2))})
    assert layout == {"a": (0, 2), "b": (2, 1)}
    assert sobol_block_trials(1) == SEED_BLOCK_SIZE
    assert sobol_block_trials(100) == 8192
    with pytest.raises(InputError, match="sampling"):
        monte_carlo(SUM, INPUTS, 100, seed=1, sampling="halton")
    with pytest.raises(InputError, match="normal_method"):
        monte_carlo(SUM, INPUTS, 100, seed=1, sampling="sobol", normal_method="box-muller")
    with pytest.raises(InputError, match="power of two"):
        sobol_points(1, 0, 2, 1000)
