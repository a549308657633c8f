"""Vector outputs (JCGM 102:2011, GUM Supplement 2).

Two checks of a two-output model:

* a linear model ``Y = A X`` of a bivariate normal ``X``: its output is exactly normal
  with covariance ``A V Aᵀ``, so the coverage ellipse of JCGM 102 §7.7 has the exact
  ``k_p² = χ²_2(p) = -2 ln(1 - p)``, and the GUM (first order, exact here) gives
  ``A V Aᵀ`` to rounding;
* JCGM 102 §9.2, magnitude and phase ``(|Z|, arg Z)`` of a complex quantity
  ``Z = X1 + i X2`` with ``X ~ N((x1, 0), u² [[1, r], [r, 1]])``, ``u = 0.010``. The
  Monte Carlo results are checked against the exact moments of that output, computed in
  the test by quadrature of the density of the angle of a bivariate normal (closed form
  in the radius, see ``_polar_moments``), and against the published values of JCGM 102
  Tables 6-7 as quoted in suncal's ``test/test_examples.py::test_GUMSUP2``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, stats

from mtmc import MultivariateNormal, monte_carlo
from mtmc.uncertainty.propagation import gum
from mtmc.uncertainty.results import MonteCarloResult


def test_linear_two_output_model_ellipse_against_bivariate_normal():
    a = np.array([[1.0, 2.0], [0.5, -1.0]])
    v = np.array([[0.04, 0.01], [0.01, 0.09]])
    mean = np.array([1.0, -2.0])
    exact_cov = a @ v @ a.T
    m = 100_000

    def model(x):
        return x @ a.T

    inputs = {"x": MultivariateNormal(mean, v)}
    mc = monte_carlo(model, inputs, trials=m, seed=1021)
    # covariance entries within five standard errors sqrt((C_ii C_jj + C_ij²)/M)
    se = np.sqrt((np.outer(np.diag(exact_cov), np.diag(exact_cov)) + exact_cov**2) / m)
    assert np.all(np.abs(mc.cov - exact_cov) <= 5 * se)
    se_mean = np.sqrt(np.diag(exact_cov) / m)
    assert np.all(np.abs(mc.estimate_vector - a @ mean) <= 5 * se_mean)

    p = 0.95
    k2_exact = -2.0 * math.log(1.0 - p)  # χ²_2 quantile, closed form
    assert stats.chi2.ppf(p, 2) == pytest.approx(k2_exact, rel=1e-12)
    ell = mc.coverage_ellipsoid(p)  # JCGM 102 §7.7.2, from the values
    # the p-quantile of d² ~ χ²_2 (density g = (1 - p)/2 there) has standard error
    # sqrt(p (1 - p) / M) / g; the estimated centre and covariance add O(1/M).
    g = 0.5 * (1.0 - p)
    se_k2 = math.sqrt(p * (1.0 - p) / m) / g
    assert abs(ell.k**2 - k2_exact) <= 5 * se_k2
    # semi-axes: k times the square roots of the eigenvalues of the exact covariance
    lam = np.linalg.eigvalsh(exact_cov)
    np.testing.assert_allclose(
        np.sort(ell.semi_axes), math.sqrt(k2_exact) * np.sqrt(lam), rtol=0.01
    )

    gres = gum(model, inputs)
    np.testing.assert_allclose(gres.cov, exact_cov, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(gres.estimate_vector, a @ mean, rtol=1e-12)


def _polar_moments(mu, v):
    """Exact E[R], E[θ], E[θ²] of (R, θ) = (|X|, atan2(X2, X1)), X ~ N(mu, v), θ in (-π, π].

    The density of ``X`` in polar coordinates is ``r φ₂(r e(θ))``; integrating over ``r``
    in closed form with ``a = eᵀV⁻¹e``, ``b = eᵀV⁻¹μ``, ``c = μᵀV⁻¹μ``:
    ``I0 = √(2π/a) exp(b²/2a) Φ(b/√a)``, ``I1 = (1 + b I0)/a``, ``I2 = (I0 + b I1)/a``
    (``Ik = ∫₀^∞ r^k exp(-a r²/2 + b r) dr``, by parts); the angle density is
    ``exp(-c/2) I1 / (2π √det V)`` and ``E[R]`` integrates ``I2`` instead.
    """
    w = np.linalg.inv(v)
    c = mu @ w @ mu
    norm = math.exp(-c / 2) / (2 * math.pi * math.sqrt(np.linalg.det(v)))

    def ik(theta):
        e = np.array([math.cos(theta), math.sin(theta)])
        a = e @ w @ e
        b = e @ w @ mu
        i0 = (
            math.sqrt(2 * math.pi / a)
            * math.exp(b * b / (2 * a))
            * stats.norm.cdf(b / math.sqrt(a))
        )
        i1 = (1 + b * i0) / a
        i2 = (i0 + b * i1) / a
        return i1, i2

    def quad(f):
        return integrate.quad(f, -math.pi, math.pi, epsabs=1e-13, epsrel=1e-11, limit=200)[0]

    total = quad(lambda t: norm * ik(t)[0])
    e_r = quad(lambda t: norm * ik(t)[1])
    e_t = quad(lambda t: t * norm * ik(t)[0])
    e_t2 = quad(lambda t: t * t * norm * ik(t)[0])
    return total, e_r, e_t, e_t2


def _mag_phase(x):
    return np.column_stack([np.hypot(x[:, 0], x[:, 1]), np.arctan2(x[:, 1], x[:, 0])])


# JCGM 102 §9.2, Tables 6-7 (as quoted by suncal): x1, r; MCM |Z|, u; arg Z, u;
# GUF u(|Z|), u(arg Z). Three decimals printed.
TABLE = [
    (0.001, 0.0, 0.013, 0.007, 0.000, 1.744, 0.010, 10.000),
    (0.001, 0.9, 0.012, 0.008, -0.556, 1.599, 0.010, 10.000),
    (0.010, 0.9, 0.015, 0.008, -0.343, 0.903, 0.010, 1.000),
]


@pytest.mark.parametrize(("x1", "r", "mag", "u_mag", "ph", "u_ph", "gu_mag", "gu_ph"), TABLE)
def test_jcgm102_magnitude_and_phase(x1, r, mag, u_mag, ph, u_ph, gu_mag, gu_ph):
    u = 0.010
    mu = np.array([x1, 0.0])
    v = u**2 * np.array([[1.0, r], [r, 1.0]])
    m = 400_000
    inputs = {"x": MultivariateNormal(mu, v)}
    mc = monte_carlo(_mag_phase, inputs, trials=m, seed=int(1000 * x1) + int(10 * r))

    total, e_r, e_t, e_t2 = _polar_moments(mu, v)
    assert total == pytest.approx(1.0, abs=1e-9)  # the density integrates to 1
    sd_r = math.sqrt(mu @ mu + np.trace(v) - e_r**2)  # E[R²] = |μ|² + tr V exactly
    sd_t = math.sqrt(e_t2 - e_t**2)
    if r == 0.0:  # Rice distribution: a second closed form
        rice = stats.rice(x1 / u, scale=u)
        assert e_r == pytest.approx(rice.mean(), rel=1e-9)
        assert sd_r == pytest.approx(rice.std(), rel=1e-8)
        assert e_t == pytest.approx(0.0, abs=1e-12)

    # Monte Carlo against the exact moments: 5 standard errors (that of a standard
    # deviation from the sample fourth moment).
    y, s = mc.samples[:, 0], mc.samples[:, 1]
    for vals, est, unc, exact_mean, exact_sd in (
        (y, mc.estimate_vector[0], mc.u_vector[0], e_r, sd_r),
        (s, mc.estimate_vector[1], mc.u_vector[1], e_t, sd_t),
    ):
        m4 = np.mean((vals - vals.mean()) ** 4)
        se_sd = math.sqrt(max(m4 - exact_sd**4, 0.0) / m) / (2 * exact_sd)
        assert abs(est - exact_mean) <= 5 * exact_sd / math.sqrt(m)
        assert abs(unc - exact_sd) <= 5 * se_sd

    # published values (three decimals) against the exact moments: half a unit of the
    # last printed decimal; the Monte Carlo values are tied to them by the checks above.
    def close(value, published):
        assert abs(value - published) <= 0.0005, f"{value} vs published {published}"

    close(e_r, mag)
    close(sd_r, u_mag)
    close(e_t, ph)
    close(sd_t, u_ph)

    # GUF: sensitivities (1, 0) and (0, 1/x1) at (x1, 0): u(|Z|) = u, u(arg Z) = u/x1
    g = gum(_mag_phase, inputs)
    close(g.u_vector[0], gu_mag)
    close(g.u_vector[1], gu_ph)
    np.testing.assert_allclose(g.u_vector, [u, u / x1], rtol=1e-4)


def test_ellipse_scale_from_values_of_a_known_region():
    """JCGM 102 §7.7.2 on values whose region is known: the 2-D standard normal scaled
    by diag(2, 3); k_p² = -2 ln(1 - p) and the semi-axes 2k, 3k."""
    rng = np.random.default_rng(np.random.SeedSequence(7702))
    m = 200_000
    x = rng.standard_normal((m, 2)) * [2.0, 3.0]
    ell = MonteCarloResult.from_samples(x, seed=7702).coverage_ellipsoid(0.99)
    k_exact = math.sqrt(-2 * math.log(0.01))
    g = 0.5 * 0.01
    se_k2 = math.sqrt(0.99 * 0.01 / m) / g
    assert abs(ell.k**2 - k_exact**2) <= 5 * se_k2
    np.testing.assert_allclose(np.sort(ell.semi_axes), [2 * k_exact, 3 * k_exact], rtol=0.01)
