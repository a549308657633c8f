"""Joint summaries of several outputs: correlation and the GUM coverage region (JCGM 102)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from mtmc.errors import InputError
from mtmc.uncertainty import (
    MonteCarloResult,
    MultivariateNormal,
    correlation,
    gum,
    gum_coverage_ellipsoid,
    monte_carlo,
)

MEAN = [1.0, 2.0]
COV = np.array([[0.01, 0.002], [0.002, 0.04]])
# a linear model of two outputs, Y = C X + b: y1 = x0 + x1, y2 = 3 x0 - x1
C = np.array([[1.0, 1.0], [3.0, -1.0]])


def _linear(x):
    return np.stack([x[..., 0] + x[..., 1], 3.0 * x[..., 0] - x[..., 1]], axis=-1)


def test_correlation_of_a_closed_form_covariance():
    # r01 = 0.002 / (0.1 · 0.2) = 0.1, written out by hand
    r = correlation(COV)
    assert r[0, 0] == 1.0
    assert r[1, 1] == 1.0
    assert r[0, 1] == pytest.approx(0.1, rel=1e-15)  # one division and two roots
    assert r[1, 0] == r[0, 1]


def test_correlation_of_a_constant_component_is_undefined():
    r = correlation(np.array([[0.0, 0.0], [0.0, 1.0]]))
    assert np.isnan(r[0, 0])
    assert np.isnan(r[0, 1])
    assert r[1, 1] == 1.0


def test_gum_covariance_of_two_linear_outputs_is_c_ux_ct():
    # JCGM 102 §6.2.1.3: U_y = C U_x Cᵀ, recomputed here with NumPy
    g = gum(_linear, {"x": MultivariateNormal(MEAN, COV)})
    expected = C @ COV @ C.T
    np.testing.assert_allclose(g.cov, expected, rtol=1e-14, atol=0)  # rounding of two products
    np.testing.assert_allclose(correlation(g.cov), correlation(expected), rtol=1e-14)


def test_monte_carlo_covariance_of_two_linear_outputs_within_its_standard_error():
    # the sample covariance s_ij of M Gaussian pairs has the variance
    # (U_ii U_jj + U_ij²)/(M - 1); each entry lies within 4 standard errors of C U_x Cᵀ
    m = 40_000
    r = monte_carlo(_linear, {"x": MultivariateNormal(MEAN, COV)}, trials=m, seed=21)
    u_y = C @ COV @ C.T
    se = np.sqrt((np.outer(np.diag(u_y), np.diag(u_y)) + u_y**2) / (m - 1))
    assert np.all(np.abs(r.cov - u_y) <= 4 * se)


def test_gum_region_of_two_outputs_has_the_closed_form_k():
    # χ²₂(p) = -2 ln(1 - p): the closed form of the chi-squared quantile with 2 degrees of
    # freedom; SciPy's quantile agrees to rounding
    g = gum(_linear, {"x": MultivariateNormal(MEAN, COV)})
    for p in (0.5, 0.95, 0.99):
        e = gum_coverage_ellipsoid(g, p)
        assert e.k**2 == pytest.approx(-2.0 * math.log(1.0 - p), rel=1e-12)
        assert e.method == "chi2"
    # semi-axes: k sqrt(λ) of the eigenvalues of U_y, by NumPy
    e = gum_coverage_ellipsoid(g, 0.95)
    lam = np.linalg.eigvalsh(C @ COV @ C.T)
    np.testing.assert_allclose(e.semi_axes, e.k * np.sqrt(lam), rtol=1e-13)


def test_fraction_of_trials_inside_the_95_percent_ellipses():
    # For a linear model of Gaussian inputs the output is Gaussian and the GUM ellipse has
    # probability exactly 0.95 (P(χ²₂ <= -2 ln 0.05) = 0.95): the fraction of M trials
    # inside is binomial, within 4 sqrt(p(1-p)/M) of 0.95. The Monte Carlo ellipse holds
    # q of the M trials by construction (JCGM 102 §7.7.2, q = pM + 1/2 truncated).
    m = 20_000
    x = {"x": MultivariateNormal(MEAN, COV)}
    g = gum(_linear, x)
    mc = monte_carlo(_linear, x, trials=m, seed=9)
    inside_gum = float(np.mean(gum_coverage_ellipsoid(g, 0.95).contains(mc.values)))
    assert abs(inside_gum - 0.95) <= 4 * math.sqrt(0.95 * 0.05 / m)
    e_mc = mc.coverage_ellipsoid(0.95, method="mc")
    q = int(0.95 * m + 0.5)
    # the q-th trial lies on the boundary: k = sqrt(k²) squared back may round it out
    assert q - 1 <= int(np.count_nonzero(e_mc.contains(mc.values))) <= q
    # and its k² is the 95 % quantile of χ²₂ within 4 standard errors of a sample
    # quantile, sqrt(p(1-p)/M) / f(k²) with f the χ²₂ density at k²
    k2 = -2.0 * math.log(0.05)
    se = math.sqrt(0.95 * 0.05 / m) / stats.chi2.pdf(k2, 2)
    assert abs(e_mc.k**2 - k2) <= 4 * se


def test_gum_region_refuses_a_scalar_or_singular_output():
    x = {"x": MultivariateNormal(MEAN, COV)}
    with pytest.raises(InputError, match="needs a vector output"):
        gum_coverage_ellipsoid(gum(lambda x: x[:, 0], x))
    # y2 = 2 y1: U_y of rank 1
    with pytest.raises(InputError, match="singular"):
        gum_coverage_ellipsoid(gum(lambda x: np.stack([x[:, 0], 2 * x[:, 0]], axis=1), x))


def test_mc_and_gum_regions_agree_for_a_linear_gaussian_model():
    # a second method: the Monte Carlo region of the same model is the GUM region to
    # within sampling error (k within 4 sample-quantile errors as above, ~0.03 in k)
    m = 20_000
    x = {"x": MultivariateNormal(MEAN, COV)}
    mc = MonteCarloResult.from_samples(monte_carlo(_linear, x, trials=m, seed=4).values, seed=None)
    k_mc = mc.coverage_ellipsoid(0.95, "mc").k
    k_gum = gum_coverage_ellipsoid(gum(_linear, x), 0.95).k
    se_k2 = math.sqrt(0.95 * 0.05 / m) / stats.chi2.pdf(k_gum**2, 2)
    assert abs(k_mc**2 - k_gum**2) <= 4 * se_k2
