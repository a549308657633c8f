"""JCGM 101 §8.2 validation: d_low, d_high, δ and the verdict, checked by hand on
Monte Carlo results whose coverage intervals are known exactly, then on real runs."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from mtmc import InputError, MonteCarloResult, Normal, Uniform, expression, monte_carlo
from mtmc.uncertainty.propagation import NOISE_MARGIN, Validation, endpoint_std_error, gum, validate


def _normal_quantile_samples(mu, sigma, m):
    """M values at the (i - 1/2)/M quantiles of N(mu, sigma²), shuffled deterministically."""
    i = np.arange(1, m + 1)
    values = mu + sigma * stats.norm.ppf((i - 0.5) / m)
    return values[np.random.default_rng(np.random.SeedSequence(7)).permutation(m)]


def test_validation_by_hand_normal_output_passes():
    mu, sigma, m = 10.0, 2.0, 40_000
    mc = MonteCarloResult.from_samples(_normal_quantile_samples(mu, sigma, m), seed=None)
    g = gum(expression("x"), {"x": Normal(mu, sigma)})
    v = validate(g, mc)
    # JCGM 101 §7.7.2: q = pM = 38000, r = (M - q)/2 = 1000, interval [ỹ_r, ỹ_{r+q}]
    sorted_values = np.sort(mc.samples)
    y_low, y_high = sorted_values[999], sorted_values[38_999]
    big_u = stats.norm.ppf(0.975) * sigma
    assert v.d_low == pytest.approx(abs(mu - big_u - y_low), rel=1e-12)
    assert v.d_high == pytest.approx(abs(mu + big_u - y_high), rel=1e-12)
    assert v.delta == 0.05  # u = 2.0 = 20 × 10⁻¹ -> δ = ½ × 10⁻¹
    assert v.passed
    assert isinstance(v, Validation)
    assert v.kind == "symmetric"
    assert v.p == 0.95


def test_validation_by_hand_rectangular_output_fails():
    # values 1..1000 (a rectangular output), GUM for Uniform(0.5, 1000.5):
    # y = 500.5, u = 1000/√12, U = 1.95996 u = 565.79; MC symmetric 95 %: [25, 975]
    mc = MonteCarloResult.from_samples(np.arange(1.0, 1001.0), seed=None)
    g = gum(expression("x"), {"x": Uniform(0.5, 1000.5)})
    v = validate(g, mc)
    big_u = stats.norm.ppf(0.975) * 1000 / math.sqrt(12)
    assert v.d_low == pytest.approx(abs(500.5 - big_u - 25.0), rel=1e-12)
    assert v.d_high == pytest.approx(abs(500.5 + big_u - 975.0), rel=1e-12)
    assert v.delta == 5.0  # u = 288.7 -> 29 × 10¹ -> δ = 5
    assert not v.passed
    # ndig = 1: u -> 3 × 10² -> δ = 50; still not validated (d ≈ 66)
    v1 = validate(g, mc, ndig=1)
    assert v1.delta == 50.0
    assert not v1.passed


def test_one_endpoint_off_is_enough_to_fail():
    """JCGM 101 §8.2: the GUF is validated only if *both* d_low and d_high are <= δ.
    Values at the normal quantiles of N(0, 1) with the upper half stretched by 1.1: the
    lower endpoint agrees with the GUM's y - U (d_low ≈ 0), the upper one is off by
    0.1 × 1.95996 ≈ 0.196 > δ = 0.05 (u = 1.0 = 10 × 10⁻¹)."""
    m = 40_000
    x = _normal_quantile_samples(0.0, 1.0, m)
    x = np.where(x > 0, 1.1 * x, x)
    mc = MonteCarloResult.from_samples(x, seed=None)
    g = gum(expression("x"), {"x": Normal(0.0, 1.0)})
    v = validate(g, mc)
    z = stats.norm.ppf(0.975)
    sorted_values = np.sort(x)
    assert v.d_low == pytest.approx(abs(-z - sorted_values[999]), rel=1e-12)
    assert v.d_high == pytest.approx(abs(z - sorted_values[38_999]), rel=1e-12)
    assert v.delta == 0.05
    assert v.d_low <= v.delta < v.d_high
    assert abs(v.d_high - 0.1 * z) <= 0.002
    assert not v.passed
    # and mirrored: the lower endpoint off, the upper one right
    mirrored = validate(g, MonteCarloResult.from_samples(-x, seed=None))
    assert mirrored.d_high <= mirrored.delta < mirrored.d_low
    assert not mirrored.passed


def test_other_p_recomputes_k_and_shortest_kind():
    mu, sigma, m = 0.0, 1.0, 100_000
    mc = MonteCarloResult.from_samples(_normal_quantile_samples(mu, sigma, m), seed=None)
    g = gum(expression("x"), {"x": Normal(mu, sigma)})
    v = validate(g, mc, p=0.99, kind="shortest")
    lo, hi = mc.coverage_interval(0.99, kind="shortest")
    k99 = stats.norm.ppf(0.995)
    assert v.d_low == pytest.approx(abs(-k99 - lo), rel=1e-12)
    assert v.d_high == pytest.approx(abs(k99 - hi), rel=1e-12)
    assert v.kind == "shortest"
    assert v.passed


def test_zero_gum_uncertainty_has_zero_tolerance():
    # y = x² at x = 0: first-order u(y) = 0 (JCGM 101 §9.4, x1 = 0): never validated
    rng = np.random.default_rng(np.random.SeedSequence(3))
    mc = MonteCarloResult.from_samples(rng.normal(0, 1, 1000) ** 2, seed=None)
    g = gum(expression("x**2"), {"x": Normal(0.0, 1.0)})
    assert g.u == 0.0
    v = validate(g, mc)
    assert v.delta == 0.0
    assert not v.passed


def test_real_monte_carlo_linear_model_validates():
    inputs = {"a": Normal(1.0, 0.3), "b": Normal(-2.0, 0.4)}
    expr = expression("a + b")
    mc = monte_carlo(expr, inputs, trials=200_000, seed=11)
    v = validate(gum(expr, inputs), mc)
    assert v.delta == 0.005  # u = 0.50 -> δ = 0.005
    assert v.passed


def test_bad_arguments():
    mc = MonteCarloResult.from_samples(np.arange(10.0), seed=None)
    g = gum(expression("x"), {"x": Normal(0, 1)})
    with pytest.raises(InputError, match="expected kind 'symmetric' or 'shortest'"):
        validate(g, mc, kind="widest")  # type: ignore[arg-type]
    with pytest.raises(InputError, match="0 < p < 1"):
        validate(g, mc, p=0)
    gv = gum(lambda x: np.stack([x, x], axis=1), {"x": Normal(0, 1)})
    with pytest.raises(InputError, match="scalar output"):
        validate(gv, mc)


@pytest.mark.parametrize(
    ("excess", "expected"),
    [
        (0.0, "not validated within Monte Carlo noise"),
        (2.9, "not validated within Monte Carlo noise"),
        (3.1, "not validated"),
        (10.0, "not validated"),
    ],
)
def test_the_verdict_allows_three_endpoint_errors_of_monte_carlo_noise(excess, expected):
    # d_high exceeds delta by `excess` endpoint standard errors; three of them, the
    # 99.7 % of a normal endpoint, may still be sampling noise
    noise = endpoint_std_error(0.01, 10_000, 0.95)
    v = Validation(d_low=0.0, d_high=0.005 + 1e-6 + excess * noise, delta=0.005, passed=False)
    assert v.verdict(noise) == expected
    assert NOISE_MARGIN == 3.0
    passed = Validation(d_low=0.0, d_high=0.004, delta=0.005, passed=True)
    assert passed.verdict(noise) == "validated"
