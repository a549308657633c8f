"""The first-order model's closed forms against the exact geometry, and its identification."""

from __future__ import annotations

import numpy as np
import pytest

from mtmc.circular import circular_parameters, design, identify, lsc_fit
from mtmc.errors import IdentifiabilityError, InputError

R = 100.0
FEED = 1000.0 / 60.0  # mm/s
T = np.linspace(0.0, 2 * np.pi, 720, endpoint=False)
# 1e-9 mm: the second-order rest of errors of 1e-6 on R = 100 mm is R (1e-6)² = 1e-10
TOL = 1e-9


def _exact(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.asarray(np.hypot(x, y) - R)


def _column(name: str, d: int = 1) -> np.ndarray:
    kw = {"theta_ccw": T} if d > 0 else {"theta_cw": T}
    des = design(radius=R, feed=FEED, terms=[name], **kw)  # type: ignore[arg-type]
    return des.matrix[:, 0]


def test_squareness_closed_form() -> None:
    s = 1e-6  # EC0Y: Y tilted about +z, Δx = -y S (docs/conventions.md)
    x, y = R * np.cos(T), R * np.sin(T)
    exact = _exact(x - np.sin(s) * y, np.cos(s) * y)
    np.testing.assert_allclose(s * _column("squareness"), exact, rtol=0, atol=TOL)
    np.testing.assert_allclose(-(R * s / 2) * np.sin(2 * T), exact, rtol=0, atol=TOL)


def test_scale_closed_form() -> None:
    ex = 1e-6
    exact = _exact((1 + ex) * R * np.cos(T), R * np.sin(T))
    np.testing.assert_allclose(R * ex * np.cos(T) ** 2, exact, rtol=0, atol=TOL)
    # in the model: the mean scale in `radius`, the mismatch ε_x - ε_y in its own column
    model = R * ex / 2 * _column("radius") + ex * _column("scale_mismatch")
    np.testing.assert_allclose(model, exact, rtol=0, atol=TOL)


@pytest.mark.parametrize("d", [1, -1])
def test_backlash_closed_form(d: int) -> None:
    b = 1e-6  # X lags its command by b/2 in its direction of motion
    x, y = R * np.cos(T), R * np.sin(T)
    xdot_sign = np.sign(-d * np.sin(T))
    exact = _exact(x - b / 2 * xdot_sign, y)
    col = b * _column("backlash_u", d)
    np.testing.assert_allclose(col, exact, rtol=0, atol=TOL)
    # ±(b/2) cos θ, and a step of b (outwards) at the reversals of X, θ = 0° and 180°
    # (at a reversal itself, sin θ = 0, the model takes the mean of the two sides)
    moving = np.sin(T) != 0
    np.testing.assert_allclose(
        np.abs(col[moving]), b / 2 * np.abs(np.cos(T[moving])), rtol=1e-15, atol=0
    )
    eps = 1e-9
    before = design(radius=R, theta_ccw=[-eps, 1, 2, 3], terms=["backlash_u"]).matrix[0, 0]
    after = design(radius=R, theta_ccw=[eps, 1, 2, 3], terms=["backlash_u"]).matrix[0, 0]
    assert b * (after - before) == pytest.approx(b, rel=1e-12)


def test_servo_lag_closed_form_flips_with_direction() -> None:
    omega = FEED / R
    tau = 1e-6 / omega  # a lag of X whose angle ωτ is 1e-6
    devs = {}
    for d in (1, -1):
        # X follows its command late: x(t - τ) = R cos(θ - d ω τ)
        exact = _exact(R * np.cos(T - d * omega * tau), R * np.sin(T))
        col = tau * _column("servo_mismatch", d)
        np.testing.assert_allclose(col, exact, rtol=0, atol=TOL)
        devs[d] = col
    # an ellipse whose long axis lies at 45° CCW and at 135° CW
    assert np.degrees(T[np.argmax(devs[1])]) % 180 == pytest.approx(45.0)
    assert np.degrees(T[np.argmax(devs[-1])]) % 180 == pytest.approx(135.0)


def test_centre_offset_closed_form_and_lsc_removes_it() -> None:
    a, b = 1e-6, -0.7e-6  # the path's centre relative to the table ball
    exact = _exact(R * np.cos(T) + a, R * np.sin(T) + b)
    model = a * _column("centre_u") + b * _column("centre_v")
    np.testing.assert_allclose(model, exact, rtol=0, atol=TOL)
    _, res = lsc_fit(T, exact)
    assert np.max(np.abs(res)) < TOL
    p = circular_parameters(theta_ccw=T, ccw=exact)
    assert p["G_lsc"][0] < TOL
    assert p["F_max"][0] < TOL


def _both() -> dict[str, np.ndarray]:
    return {"theta_ccw": T, "theta_cw": T}


def test_identification_recovers_injected_errors() -> None:
    des = design(
        radius=R,
        feed=FEED,
        terms=[
            *design(radius=R, **_both()).terms,
            "spike_u",
            "spike_v",
            "cyclic_u_cos",
            "cyclic_u_sin",
        ],
        cyclic_period=(5.0, 5.0),
        centre=(250.0, 100.0),
        **_both(),
    )
    rng = np.random.default_rng(5)
    scale = np.array([1e-3, 5e-3, 5e-3, 2e-5, 1e-5, 3e-3, 2e-3, 1e-4, 2e-3, 1e-3, 5e-4, 5e-4])
    truth = rng.normal(0, 1, (4, scale.size)) * scale
    ident = identify(des, des.deviation(truth))
    # a linear least-squares fit on an exact model: the design's conditioning (~1e2) times
    # rounding
    np.testing.assert_allclose(ident.estimates, truth, rtol=1e-6, atol=0)
    assert ident.identifiability.ok
    assert np.all(ident.rms < 1e-15)
    assert ident.value("backlash_x").shape == (4,)
    assert any("ballbar's calibrated length" in n for n in ident.notes)


def test_identifiability_of_one_direction() -> None:
    des = design(radius=R, theta_ccw=T, terms=["radius", "squareness", "servo_mismatch"])
    with pytest.raises(IdentifiabilityError, match="squareness"):
        identify(des, np.zeros(T.size))
    ok = design(radius=R, theta_ccw=T)
    assert "servo_mismatch" not in ok.terms
    assert any("servo mismatch" in n for n in identify(ok, np.zeros(T.size)).notes)


def test_design_errors() -> None:
    with pytest.raises(InputError, match="plane"):
        design(radius=R, theta_ccw=T, plane="YX")
    with pytest.raises(InputError, match="unknown term"):
        design(radius=R, theta_ccw=T, terms=["roundness"])
    with pytest.raises(InputError, match="cyclic_period"):
        design(radius=R, theta_ccw=T, terms=["cyclic_u_cos"])
    with pytest.raises(InputError, match="radius"):
        design(radius=-1.0, theta_ccw=T)
    names = design(radius=R, theta_ccw=T, plane="YZ").names
    assert names[:3] == ("radius", "centre_y", "centre_z")
