"""ISO 230-4 parameters from their definitions: by hand, against LP and the geometric fit."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

from mtmc.circular import circular_parameters, hysteresis, lsc_fit, minimum_zone
from mtmc.circular.parameters import periodic_interpolation
from mtmc.errors import InputError
from mtmc.geometry import fit_circle


def _lp_zone(theta: np.ndarray, f: np.ndarray) -> float:
    """min (u - l) s.t. l <= f_i - a cos θ_i - b sin θ_i <= u: an independent LP (HiGHS)."""
    c, s = np.cos(theta), np.sin(theta)
    n = theta.size
    # variables a, b, l, u
    A_up = np.stack([-c, -s, np.zeros(n), -np.ones(n)], axis=1)  # f - a c - b s - u <= 0
    A_lo = np.stack([c, s, np.ones(n), np.zeros(n)], axis=1)  # l - f + a c + b s <= 0
    res = linprog(
        [0.0, 0.0, -1.0, 1.0],
        A_ub=np.concatenate([A_up, A_lo]),
        b_ub=np.concatenate([-f, f]),
        bounds=[(None, None)] * 4,
        method="highs",
    )
    assert res.success
    return float(res.fun)


def test_small_trace_by_hand() -> None:
    # eight points at 45° steps; deviations in mm chosen so each parameter is plain
    t = np.radians(np.arange(0, 360, 45))
    ccw = np.array([[0.002, 0.001, 0.0, -0.001, 0.0, 0.0, 0.001, 0.0]])
    cw = np.array([[0.002, 0.0, 0.0, -0.001, 0.0, 0.003, 0.001, 0.0]])
    p = circular_parameters(theta_ccw=t, ccw=ccw, theta_cw=t, cw=cw, centre="setup")
    # F about the set-up centre: the extremes as read
    assert p["F_max_ccw"][0] == 0.002
    assert p["F_min_ccw"][0] == -0.001
    assert p["F_max"][0] == 0.003
    assert p["F_min"][0] == -0.001
    # H: largest |cw - ccw| at one angle: 0.003 at 225°
    assert p["H"][0] == pytest.approx(0.003, abs=1e-18)
    # G about the LSC: the LSC of eight equally spaced points is the mean and the first
    # Fourier pair, written out here by hand
    c0 = ccw.mean()
    a = 2 * np.mean(ccw * np.cos(t))
    b = 2 * np.mean(ccw * np.sin(t))
    r = ccw - c0 - a * np.cos(t) - b * np.sin(t)
    assert p["G_lsc_ccw"][0] == pytest.approx(r.max() - r.min(), abs=1e-15)
    coef, _ = lsc_fit(t, ccw)
    np.testing.assert_allclose(coef[0], [c0, a, b], atol=1e-16)
    assert p["G_mz_ccw"][0] <= p["G_lsc_ccw"][0] + 1e-16


def test_minimum_zone_against_linear_programming() -> None:
    rng = np.random.default_rng(7)
    n, m = 90, 40
    t = np.sort(rng.uniform(0, 2 * np.pi, n))
    # random traces: harmonics 0-5 and noise, up to some 10 µm
    k = np.arange(6)
    coef = rng.normal(0, 0.004, (m, 6, 2))
    f = np.einsum("mk,kn->mn", coef[..., 0], np.cos(np.outer(k, t)))
    f += np.einsum("mk,kn->mn", coef[..., 1], np.sin(np.outer(k, t)))
    f += rng.normal(0, 0.0005, (m, n))
    w, c = minimum_zone(t, f)
    lp = np.array([_lp_zone(t, f[i]) for i in range(m)])
    # HiGHS solves to ~1e-9 relative on widths of some 0.01 mm
    np.testing.assert_allclose(w, lp, rtol=0, atol=1e-10)
    # the Chebyshev levelling: the zone found is the range about the centre found
    r = f - c[:, 1:2] * np.cos(t) - c[:, 2:3] * np.sin(t)
    np.testing.assert_allclose(r.max(axis=1) - r.min(axis=1), w, atol=1e-15)
    # the order of the points does not matter
    perm = rng.permutation(n)
    np.testing.assert_allclose(minimum_zone(t[perm], f[:, perm])[0], w, atol=1e-15)


def test_lsc_against_the_geometric_circle_fit() -> None:
    rng = np.random.default_rng(3)
    R, n = 100.0, 360
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    dev = 0.005 * np.sin(3 * t) + 0.02 * np.cos(t) - 0.01 * np.sin(t) + 0.003
    dev = dev + rng.normal(0, 0.001, n)
    coef, res = lsc_fit(t, dev)
    pts = np.stack([(R + dev) * np.cos(t), (R + dev) * np.sin(t), np.zeros(n)], axis=1)
    fit = fit_circle(pts, orientation=[0, 0, 1])
    # the limaçon fit agrees with the orthogonal-distance fit to second order: |ΔR|²/R
    # with |ΔR| ~ 0.03 mm and R = 100 mm is ~1e-5 mm
    np.testing.assert_allclose(coef[0, 1:], fit.geometry.centre[0, :2], atol=1e-5)
    assert coef[0, 0] == pytest.approx(fit.geometry.radius[0] - R, abs=1e-5)
    np.testing.assert_allclose(res[0], fit.residuals[0], atol=1e-5)


def test_batch_equals_one_at_a_time() -> None:
    rng = np.random.default_rng(11)
    t = np.linspace(0, 2 * np.pi, 72, endpoint=False)
    a = rng.normal(0, 0.003, (5, 72))
    b = rng.normal(0, 0.003, (5, 72))
    whole = circular_parameters(theta_ccw=t, ccw=a, theta_cw=t, cw=b)
    for i in range(5):
        one = circular_parameters(theta_ccw=t, ccw=a[i], theta_cw=t, cw=b[i])
        for k, v in one.items():
            # one BLAS product per batch: the rows agree to rounding
            assert v[0] == pytest.approx(whole[k][i], abs=1e-17), k
    # G_b: the range of both paths about one centre, never below the least range of
    # either path about any centre, its G_mz
    assert np.all(whole["G_b"] >= np.maximum(whole["G_mz_ccw"], whole["G_mz_cw"]) - 1e-17)


def test_hysteresis_interpolates_the_cw_path() -> None:
    ta = np.radians([0.0, 90.0, 180.0, 270.0])
    tb = ta + np.radians(45.0)
    # cw linear between its points: at 90° it is the mean of its values at 45° and 135°
    cw = np.array([[0.001, 0.003, 0.0, 0.0]])
    ccw = np.zeros((1, 4))
    assert hysteresis(ta, ccw, tb, cw)[0] == pytest.approx(0.002, abs=1e-18)
    i0, i1, w = periodic_interpolation(tb, [np.radians(10.0)])
    # 10° lies between 315° and 45° (wrapping): 55° / 90° of the way
    assert (i0[0], i1[0]) == (3, 0)
    assert w[0] == pytest.approx(55 / 90)


def test_bad_input() -> None:
    t = np.linspace(0, 2 * np.pi, 8, endpoint=False)
    with pytest.raises(InputError, match="distinct angles"):
        minimum_zone(np.concatenate([t, t[:1] + 2 * np.pi]), np.zeros(9))
    with pytest.raises(InputError, match=r"shape \(M, 8\)"):
        lsc_fit(t, np.zeros(7))
    with pytest.raises(InputError, match="at least one trace"):
        circular_parameters()
    with pytest.raises(InputError, match="centre"):
        circular_parameters(theta_ccw=t, ccw=np.zeros(8), centre="mz")  # type: ignore[arg-type]
