"""Inverse CDFs of the input PDFs (for quasi-random sampling) against SciPy's or against
the integral of the PDF, and the maps from the unit cube of the vector PDFs."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, stats

from mtmc.errors import DistributionError
from mtmc.uncertainty.distributions import (
    IID,
    Arcsine,
    Constant,
    CurvilinearTrapezoid,
    Exponential,
    Gamma,
    MultivariateNormal,
    Normal,
    StudentT,
    Trapezoidal,
    Triangular,
    Uniform,
)

U = np.concatenate([[1e-12, 1e-6, 0.001], np.linspace(0.01, 0.99, 99), [0.999, 1 - 1e-6]])

CASES = [
    (Normal(1.5, 0.2), stats.norm(1.5, 0.2)),
    (Uniform(-2, 3), stats.uniform(-2, 5)),
    (Triangular(-1, 2), stats.triang(0.5, loc=-1, scale=3)),
    (Triangular(-1, 2, 0.0), stats.triang(1 / 3, loc=-1, scale=3)),
    (Triangular(0, 4, 0.0), stats.triang(0.0, loc=0, scale=4)),
    (Trapezoidal(-1, 3, 0.5), stats.trapezoid(0.25, 0.75, loc=-1, scale=4)),
    (Trapezoidal(-1, 3, 0.0), stats.triang(0.5, loc=-1, scale=4)),
    (Trapezoidal(-1, 3, 1.0), stats.uniform(-1, 4)),
    (Arcsine(2, 5), stats.arcsine(loc=2, scale=3)),
    (StudentT(3.5, 1.0, 0.25), stats.t(3.5, loc=1.0, scale=0.25)),
    (Exponential(2.0), stats.expon(scale=2.0)),
    (Gamma(3.0, 0.5), stats.gamma(3.0, scale=0.5)),
]


@pytest.mark.parametrize(
    ("dist", "ref"), CASES, ids=lambda c: str(c) if hasattr(c, "sample") else ""
)
def test_ppf_against_scipy(dist, ref):
    np.testing.assert_allclose(dist.ppf(U), ref.ppf(U), rtol=1e-10, atol=1e-12)
    assert dist.uniform_dims == 1
    np.testing.assert_array_equal(dist.from_uniform(U[:, None]), dist.ppf(U))


def _grid(n: int, d: int) -> np.ndarray:
    """The midpoints of a regular grid of n^d cells of the unit cube, (n^d, d)."""
    axes = np.meshgrid(*([(np.arange(n) + 0.5) / n] * d), indexing="ij")
    return np.stack([a.ravel() for a in axes], axis=1)


@pytest.mark.parametrize("d", [0.4, 2.0, 0.0])
def test_curvilinear_trapezoid_quantiles(d):
    # the CDF against the integral of the PDF of JCGM 101 §6.4.3.2, the quantiles
    # against the CDF, and the moments of the quantiles of a fine grid
    dist = CurvilinearTrapezoid(-1.0, 3.0, d)
    x = dist.ppf(U)
    assert np.all(np.diff(x) > 0)
    np.testing.assert_allclose(dist.cdf(x), U, rtol=0, atol=1e-15)
    lo, hi = 2.0 - d, 2.0 + d
    if d > 0:

        def pdf(t):
            y = abs(t - 1.0)
            return math.log(hi / max(y, lo)) / (4 * d) if y < hi else 0.0

        for t in (x[3], x[50], x[-3]):
            ref = integrate.quad(pdf, -1.0 - d, t, points=[1.0 - lo, 1.0 + lo], limit=200)[0]
            assert dist.cdf(t) == pytest.approx(ref, abs=1e-12)
    else:
        np.testing.assert_allclose(x, -1.0 + 4.0 * U, rtol=0, atol=1e-14)
    g = dist.ppf((np.arange(100_000) + 0.5) / 100_000)
    assert g.mean() == pytest.approx(dist.mean, abs=1e-12)
    assert g.std() == pytest.approx(dist.std, rel=1e-7)
    assert dist.uniform_dims == 1


def test_multivariate_normal_through_the_cholesky_factor():
    cov = np.array([[4.0, 1.2], [1.2, 1.0]])
    d = MultivariateNormal([1.0, -2.0], cov)
    assert d.uniform_dims == 2
    u = _grid(600, 2)
    x = d.from_uniform(u)
    np.testing.assert_allclose(x.mean(axis=0), [1.0, -2.0], atol=1e-12)
    np.testing.assert_allclose(np.cov(x.T), cov, rtol=2e-2)
    # the first component is the normal quantile of the first coordinate
    np.testing.assert_allclose(x[:, 0], Normal(1.0, 2.0).ppf(u[:, 0]), rtol=1e-14)


def test_iid_and_constant():
    d = IID(CurvilinearTrapezoid(0, 1, 0.1), 3)
    assert d.uniform_dims == 3
    u = np.random.default_rng(0).random((5, 3))
    x = d.from_uniform(u)
    assert x.shape == (5, 3)
    np.testing.assert_array_equal(x[:, 1], d.base.ppf(u[:, 1]))
    with pytest.raises(DistributionError, match="no quantile function"):
        MultivariateNormal([0, 0], np.eye(2)).ppf(0.5)
    c = Constant([1.0, 2.0])
    assert c.uniform_dims == 0
    np.testing.assert_array_equal(c.from_uniform(np.empty((3, 0))), [[1.0, 2.0]] * 3)
    assert Constant(2.5).ppf([0.1, 0.9]).tolist() == [2.5, 2.5]


def test_pseudo_random_asymmetric_triangular_unchanged():
    # the sampler of an asymmetric triangular PDF is its inverse CDF of one uniform number
    d = Triangular(0, 3, 1)
    a = d.sample(np.random.default_rng(4), 1000)
    np.testing.assert_array_equal(a, d.ppf(np.random.default_rng(4).random(1000)))
