"""Error generation functions against NumPy's polynomial modules and closed forms."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.polynomial import chebyshev, legendre, polynomial

from mtmc.errors import InputError
from mtmc.kinematics import (
    ChebyshevSeries,
    ConstantFunction,
    ErrorTable,
    FourierSeries,
    LegendreSeries,
    PolynomialFunction,
)

RNG = np.random.default_rng(np.random.SeedSequence(2024))
Q = RNG.uniform(0.0, 1500.0, 400)
C = RNG.normal(size=5) * 1e-3


def test_polynomial_matches_numpy() -> None:
    f = PolynomialFunction(C * np.array([1, 1e-3, 1e-6, 1e-9, 1e-12]))
    np.testing.assert_allclose(f(Q), polynomial.polyval(Q, f.coefficients), rtol=1e-13)
    np.testing.assert_allclose(f.basis(Q) @ f.coefficients, f(Q), rtol=1e-12, atol=1e-18)


def test_legendre_and_chebyshev_match_numpy() -> None:
    t = (2.0 * Q - 1500.0) / 1500.0
    f = LegendreSeries(C, low=0.0, high=1500.0)
    np.testing.assert_allclose(f(Q), legendre.legval(t, C), rtol=1e-12, atol=1e-16)
    g = ChebyshevSeries(C, low=0.0, high=1500.0)
    np.testing.assert_allclose(g(Q), chebyshev.chebval(t, C), rtol=1e-12, atol=1e-16)
    # P_k(1) = T_k(1) = 1 at the end of travel
    np.testing.assert_allclose(f(np.array([1500.0])), [C.sum()], rtol=1e-13)
    np.testing.assert_allclose(g(np.array([1500.0])), [C.sum()], rtol=1e-13)


def test_fourier_closed_form() -> None:
    a = np.array([1e-3, 2e-3, -1e-3, 5e-4, 3e-4])
    f = FourierSeries(a)
    th = np.linspace(-np.pi, np.pi, 50)
    ref = (
        a[0] + a[1] * np.cos(th) + a[2] * np.sin(th) + a[3] * np.cos(2 * th) + a[4] * np.sin(2 * th)
    )
    np.testing.assert_allclose(f(th), ref, atol=1e-17)
    assert f.order == 2
    with pytest.raises(InputError, match="odd number of coefficients"):
        FourierSeries([1.0, 2.0])


def test_table_linear_interpolation_and_period() -> None:
    pos = np.array([0.0, 100.0, 250.0, 500.0])
    val = np.array([0.0, 2e-3, -1e-3, 4e-3])
    f = ErrorTable(pos, val)
    x = RNG.uniform(0.0, 500.0, 100)
    np.testing.assert_allclose(f(x), np.interp(x, pos, val), atol=1e-17)
    np.testing.assert_allclose(f(pos), val, atol=1e-18)
    with pytest.raises(InputError, match=r"axis position 600.0 outside the table's range"):
        f(np.array([10.0, 600.0]))
    # a periodic map over a full turn wraps from the last position to the first
    ang = np.deg2rad([0.0, 90.0, 180.0, 270.0])
    g = ErrorTable(ang, np.array([1.0, 2.0, 3.0, 4.0]), period=2 * np.pi)
    np.testing.assert_allclose(g(np.deg2rad([315.0, -45.0, 360.0, 45.0])), [2.5, 2.5, 1.0, 1.5])
    with pytest.raises(InputError, match="strictly increasing"):
        ErrorTable([0.0, 0.0], [1.0, 2.0])
    with pytest.raises(InputError, match="expected 3 values"):
        ErrorTable([0.0, 1.0, 2.0], [1.0, 2.0])


def test_per_trial_coefficients_equal_one_at_a_time() -> None:
    m = 30
    coeffs = RNG.normal(size=(m, 4)) * 1e-3
    q = RNG.uniform(-200, 200, m)
    for cls in (PolynomialFunction, LegendreSeries, ChebyshevSeries):
        kw = {} if cls is PolynomialFunction else {"low": -200.0, "high": 200.0}
        batch = cls(coeffs, **kw)(q)
        one = np.array([cls(coeffs[i], **kw)(q[i : i + 1])[0] for i in range(m)])
        np.testing.assert_allclose(batch, one, rtol=1e-13, atol=1e-18)
    f = ConstantFunction(np.full((m, 1), 2e-3))
    np.testing.assert_allclose(f(q), 2e-3)


def test_with_coefficients_and_errors() -> None:
    f = LegendreSeries([0.0, 1.0], low=0.0, high=10.0)
    g = f.with_coefficients([1.0, 0.0])
    assert isinstance(g, LegendreSeries)
    assert g.high == 10.0
    np.testing.assert_allclose(g(np.array([3.0])), [1.0])
    with pytest.raises(InputError, match="expected 2 coefficients, got 3"):
        f.with_coefficients([1.0, 2.0, 3.0])
    # value objects: equal when of the same kind with the same settings and coefficients
    assert f == LegendreSeries([0.0, 1.0], low=0.0, high=10.0)
    assert f != LegendreSeries([0.0, 1.0], low=0.0, high=20.0)
    assert f != ChebyshevSeries([0.0, 1.0], low=0.0, high=10.0)
    with pytest.raises(InputError, match="low < high"):
        LegendreSeries([1.0], low=5.0, high=5.0)
    with pytest.raises(InputError, match="field coefficients: expected finite"):
        PolynomialFunction([np.nan])
    with pytest.raises(InputError, match=r"field q: expected axis positions of shape \(M,\)"):
        f(np.zeros((2, 2)))
