"""Summaries of a Monte Carlo run: estimate, u, coverage intervals (JCGM 101 §7.7), ellipsoids."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from mtmc.errors import InputError
from mtmc.uncertainty.results import MonteCarloResult, coverage_indices

M = 200_000


def quantile_se(p, m, density):
    """Standard error of the p-quantile of m draws from a PDF with the given density there."""
    return math.sqrt(p * (1 - p) / m) / density


def test_coverage_indices_jcgm101():
    # JCGM 101 §7.7.1: q = pM when integer, else int(pM + 1/2); §7.7.2: r
    assert coverage_indices(10**6, 0.95) == (950_000, 25_000)
    assert coverage_indices(10**4, 0.99) == (9_900, 50)
    assert coverage_indices(1001, 0.95) == (951, 25)  # pM = 950.95 -> 951; (M-q)=50 -> r=25
    assert coverage_indices(1000, 0.953) == (953, 24)  # (M-q)=47 odd -> r=(47+1)/2
    with pytest.raises(InputError, match="too few"):
        coverage_indices(10, 0.99)
    with pytest.raises(InputError, match="0 < p < 1"):
        coverage_indices(100, 1.0)


def test_intervals_exact_on_small_sample():
    r = MonteCarloResult.from_samples(np.arange(1.0, 101.0), seed=None)
    assert r.coverage_interval(0.9, "symmetric") == (5.0, 95.0)
    # equally spaced: every width is q, the first one wins
    assert r.coverage_interval(0.9, "shortest") == (1.0, 91.0)
    assert r.expanded_uncertainty(0.9, "symmetric") == 45.0


def test_shortest_is_brute_force_minimum():
    rng = np.random.default_rng(4)
    x = rng.gamma(2.0, 1.0, 2001)
    r = MonteCarloResult.from_samples(x, seed=None)
    q, _ = coverage_indices(x.size, 0.95)
    s = sorted(x.tolist())
    best = min(range(len(s) - q), key=lambda j: (s[j + q] - s[j], j))
    assert r.coverage_interval(0.95, "shortest") == (s[best], s[best + q])
    assert r.coverage_interval(0.95) == r.coverage_interval(0.95, "symmetric")


def test_normal_samples_vs_closed_form():
    rng = np.random.default_rng(7)
    mu, sigma = 3.0, 0.2
    r = MonteCarloResult.from_samples(rng.normal(mu, sigma, M), seed=7)
    assert abs(r.estimate - mu) <= 5 * sigma / math.sqrt(M)
    assert abs(r.u - sigma) <= 5 * sigma / math.sqrt(2 * M)
    z = stats.norm.ppf(0.975)
    se = quantile_se(0.025, M, stats.norm.pdf(z) / sigma)
    lo, hi = r.coverage_interval(0.95, "symmetric")
    assert abs(lo - (mu - z * sigma)) <= 5 * se
    assert abs(hi - (mu + z * sigma)) <= 5 * se
    # the shortest interval of a symmetric PDF: the same length; its position is less
    # well determined (the width varies only to second order near the optimum)
    slo, shi = r.coverage_interval(0.95, "shortest")
    assert shi - slo <= hi - lo
    assert abs((shi - slo) - 2 * z * sigma) <= 5 * math.sqrt(2) * se
    assert abs(0.5 * (slo + shi) - mu) <= 0.05 * sigma
    assert r.expanded_uncertainty() == pytest.approx(z * sigma, abs=5 * se)
    assert r.expanded_uncertainty(kind="symmetric") == pytest.approx(0.5 * (hi - lo))
    # k = U/u: the error of U (5 se) plus that of u (5 σ/√(2M)), relative to σ
    assert r.coverage_factor() == pytest.approx(z, abs=5 * se / sigma + 5 * z / math.sqrt(2 * M))


def test_rectangular_samples_vs_closed_form():
    rng = np.random.default_rng(8)
    a, b = -1.0, 3.0
    r = MonteCarloResult.from_samples(rng.uniform(a, b, M), seed=8)
    assert abs(r.u - (b - a) / math.sqrt(12)) <= 5 * (b - a) / math.sqrt(12) / math.sqrt(M)
    se = quantile_se(0.025, M, 1 / (b - a))
    lo, hi = r.coverage_interval(0.95, "symmetric")
    assert abs(lo - (a + 0.025 * (b - a))) <= 5 * se
    assert abs(hi - (b - 0.025 * (b - a))) <= 5 * se
    # every 95 % interval of a rectangular PDF has length 0.95 (b - a); the shortest too
    lo, hi = r.coverage_interval(0.95, "shortest")
    assert abs((hi - lo) - 0.95 * (b - a)) <= 10 * se


def test_shortest_interval_of_exponential_starts_at_zero():
    # closed form: for Ex with mean mu the shortest 95 % interval is [0, -mu ln 0.05]
    rng = np.random.default_rng(9)
    mu = 2.0
    r = MonteCarloResult.from_samples(rng.exponential(mu, M), seed=9)
    lo, hi = r.coverage_interval(0.95, "shortest")
    assert 0.0 <= lo <= 1e-3
    x95 = -mu * math.log(0.05)
    assert abs(hi - x95) <= 5 * quantile_se(0.95, M, math.exp(-x95 / mu) / mu)
    slo, shi = r.coverage_interval(0.95, "symmetric")
    assert shi - slo > hi - lo


def test_histogram_density_integrates_to_one():
    r = MonteCarloResult.from_samples(np.random.default_rng(1).normal(0, 1, 10_000), seed=1)
    h = r.histogram(50)
    assert h.counts.sum() == 10_000
    assert h.edges.size == 51
    assert float(np.sum(h.density * np.diff(h.edges))) == pytest.approx(1.0, rel=1e-12)


def test_u_is_stryczek_eq5():
    x = np.random.default_rng(2).normal(0, 1, 3000)
    r = MonteCarloResult.from_samples(x, seed=2)
    mu = sum(x) / len(x)
    assert r.u == pytest.approx(math.sqrt(sum((v - mu) ** 2 for v in x) / (len(x) - 1)), rel=1e-12)


def _gaussian_vector(m, seed):
    cov = np.array([[4.0, 1.5], [1.5, 1.0]])
    x = np.random.default_rng(seed).multivariate_normal([1.0, -1.0], cov, m)
    return x, cov


def test_vector_cov_and_components():
    x, cov = _gaussian_vector(M, 10)
    r = MonteCarloResult.from_samples(x, seed=10)
    assert r.dim == 2
    assert r.cov.shape == (2, 2)
    se = np.sqrt((np.outer(np.diag(cov), np.diag(cov)) + cov**2) / M)
    assert np.all(np.abs(r.cov - cov) <= 5 * se)
    np.testing.assert_allclose(r.u_vector, np.sqrt(np.diag(r.cov)), rtol=1e-12)
    c1 = r.component(1)
    assert c1.estimate == pytest.approx(r.estimate_vector[1], rel=1e-15)
    with pytest.raises(InputError, match="need a scalar output"):
        r.coverage_interval()


def test_ellipse_chi2_covers_p_of_fresh_gaussian_samples():
    x, _ = _gaussian_vector(M, 11)
    ell = MonteCarloResult.from_samples(x, seed=11).coverage_ellipsoid(0.95, method="chi2")
    assert ell.k**2 == pytest.approx(-2 * math.log(0.05), rel=1e-12)  # chi2 with 2 dof
    fresh, _ = _gaussian_vector(M, 12)
    frac = ell.contains(fresh).mean()
    assert abs(frac - 0.95) <= 5 * math.sqrt(0.95 * 0.05 / M) + 0.002


def test_ellipse_mc_quantile():
    x, _ = _gaussian_vector(M, 13)
    r = MonteCarloResult.from_samples(x, seed=13)
    ell = r.coverage_ellipsoid(0.95)  # JCGM 102 7.7.2: from the values themselves
    q, _ = coverage_indices(M, 0.95)
    assert int(ell.contains(x).sum()) == q
    # for a Gaussian output the MC scale approaches the chi-squared one: k² is the
    # 0.95-quantile of d² ~ χ²_2 (density (1 - p)/2 there), within five standard errors
    assert ell.k**2 == pytest.approx(-2 * math.log(0.05), abs=5 * quantile_se(0.95, M, 0.025))
    # boundary points lie at Mahalanobis distance k, semi-axes from the eigenvalues
    np.testing.assert_allclose(ell.mahalanobis2(ell.boundary(50)), ell.k**2, rtol=1e-10)
    lam = np.linalg.eigvalsh(r.cov)
    np.testing.assert_allclose(ell.semi_axes, ell.k * np.sqrt(lam), rtol=1e-12)
    np.testing.assert_allclose(ell.axes.T @ ell.axes, np.eye(2), atol=1e-12)


def test_ellipsoid_errors():
    r = MonteCarloResult.from_samples(np.random.default_rng(0).normal(size=100), seed=0)
    with pytest.raises(InputError, match="needs a vector output"):
        r.coverage_ellipsoid()
    v = np.random.default_rng(0).normal(size=(100, 2))
    v[:, 1] = v[:, 0]
    with pytest.raises(InputError, match="singular"):
        MonteCarloResult.from_samples(v, seed=0).coverage_ellipsoid()


def test_bad_samples():
    with pytest.raises(InputError, match=r"2 of 4 values are not finite \(first at index 1\)"):
        MonteCarloResult.from_samples([1.0, np.nan, 2.0, np.inf], seed=None)
    with pytest.raises(InputError, match="at least 2 values"):
        MonteCarloResult.from_samples([1.0], seed=None)
    with pytest.raises(InputError, match="'shortest' or 'symmetric'"):
        MonteCarloResult.from_samples([1.0, 2.0, 3.0], seed=None).coverage_interval(0.5, "x")  # type: ignore[arg-type]


def test_result_is_frozen_and_read_only():
    r = MonteCarloResult.from_samples([1.0, 2.0, 3.0], seed=5)
    with pytest.raises(AttributeError):
        r.seed = 6  # type: ignore[misc]
    with pytest.raises(ValueError, match="read-only"):
        r.samples[0] = 0.0
    s = r.summary(0.5)
    assert s["seed"] == 5
    assert s["trials"] == 3
    assert s["estimate"] == 2.0


def test_histogram_of_values_a_few_ulp_apart_has_distinct_edges():
    # uniform(1, 1.00000000000001) spans 45 ulp: 60 bins ended in "Too many bins"
    from mtmc.uncertainty import Uniform, monte_carlo

    r = monte_carlo(lambda a: a, {"a": Uniform(1.0, 1.00000000000001)}, 20_000, 3, keep=True)
    h = r.histogram(60)
    assert 1 <= len(h.counts) <= 60
    assert np.all(np.diff(h.edges) > 0)
    # every value in its bin, counted once (bit-for-bit: the same comparisons of doubles)
    assert int(h.counts.sum()) == 20_000
    idx = np.clip(np.searchsorted(h.edges, r.samples, side="right") - 1, 0, len(h.counts) - 1)
    assert np.array_equal(np.bincount(idx, minlength=len(h.counts)), h.counts)
    wide = monte_carlo(lambda a: a, {"a": Uniform(1.0, 2.0)}, 20_000, 3, keep=True)
    assert len(wide.histogram(60).counts) == 60  # a range of many ulp keeps its bins
