"""A test simulated on a machine model: the exact kinematic route against the first order."""

from __future__ import annotations

import numpy as np
import pytest

from mtmc.circular import (
    AxisEffects,
    design,
    first_order_circle,
    follow_positions,
    identify,
    linear_identification,
    rotary_ballbar,
    rotary_design,
    rotary_displacement,
    simulate_circle,
)
from mtmc.errors import IdentifiabilityError, InputError
from mtmc.kinematics import Machine, PolynomialFunction

R = 100.0
FEED = 1000.0 / 60.0
T = np.linspace(0.0, 2 * np.pi, 360, endpoint=False)
XYZ = Machine.from_topology("XFYZ")


def _case(k: float) -> tuple[dict[str, object], AxisEffects, tuple[float, float, float]]:
    errors: dict[str, object] = {
        "EC0Y": 2e-5 * k,
        "EXX": PolynomialFunction([0.0, 1e-5 * k]),
        "EYY": PolynomialFunction([0.0, -0.5e-5 * k]),
    }
    eff = AxisEffects(backlash={"X": 0.003 * k, "Y": 0.002 * k}, lag={"X": 1e-3 * k, "Y": 2e-4 * k})
    return errors, eff, (0.01 * k, -0.02 * k, 0.0)


def _routes(k: float, d: int) -> tuple[np.ndarray, np.ndarray]:
    errors, eff, off = _case(k)
    kw = {"radius": R, "direction": d, "errors": errors, "effects": eff, "offset": off}
    kw["centre"] = {"Z": -50.0}
    return simulate_circle(XYZ, T, **kw), first_order_circle(XYZ, T, **kw)  # type: ignore[arg-type]


@pytest.mark.parametrize("d", [1, -1])
def test_exact_and_first_order_agree_to_second_order(d: int) -> None:
    ex1, fo1 = _routes(1.0, d)
    ex2, fo2 = _routes(0.5, d)
    gap1 = np.max(np.abs(ex1 - fo1))
    gap2 = np.max(np.abs(ex2 - fo2))
    # deviations of some 30 µm, their gap some 5 nm (|e|²/2R): halving the errors
    # quarters it
    assert np.max(np.abs(ex1)) > 0.02
    assert gap1 < 1e-5
    assert gap1 / gap2 == pytest.approx(4.0, rel=0.02)


def test_machine_trace_identified_by_the_model() -> None:
    off = _case(1.0)[2]
    fo = np.concatenate([_routes(1.0, 1)[1], _routes(1.0, -1)[1]], axis=1)
    des = design(radius=R, theta_ccw=T, theta_cw=T, feed=FEED)
    ident = identify(des, fo)
    got = dict(zip(des.names, ident.estimates[0], strict=True))
    # the machine's errors in the model's terms (module docstring of mtmc.circular.model)
    want = {
        "radius": R * (1e-5 - 0.5e-5) / 2,
        "centre_x": -off[0],
        "centre_y": -off[1],
        "squareness": 2e-5,
        "scale_mismatch": 1e-5 + 0.5e-5,
        "backlash_x": 0.003,
        "backlash_y": 0.002,
        "servo_mismatch": 1e-3 - 2e-4,
    }
    for name, value in want.items():
        # an exact first-order model: rounding times the design's conditioning
        assert got[name] == pytest.approx(value, rel=1e-9), name


def test_effects_vectorised_over_trials() -> None:
    b = np.array([0.001, 0.002, 0.004])
    eff = AxisEffects(backlash={"X": b})
    many = simulate_circle(XYZ, T, radius=R, effects=eff, errors={"EC0Y": np.full(3, 1e-5)})
    for i in range(3):
        one = simulate_circle(
            XYZ, T, radius=R, effects=AxisEffects(backlash={"X": b[i]}), errors={"EC0Y": 1e-5}
        )
        np.testing.assert_allclose(many[i], one[0], rtol=0, atol=1e-15)


def test_circle_input_errors() -> None:
    with pytest.raises(InputError, match="does not move"):
        simulate_circle(XYZ, T, radius=R, effects=AxisEffects(backlash={"Z": 0.001}))
    with pytest.raises(InputError, match="direction"):
        simulate_circle(XYZ, T, radius=R, direction=0)
    with pytest.raises(InputError, match="decay"):
        AxisEffects(spike_decay=0.0)


FIVE = Machine.from_topology("wCBXfYZt")
C = np.linspace(0.0, 2 * np.pi, 36, endpoint=False)
BALL = np.array([150.0, 0.0, 80.0])
NAMES = ["EX0C", "EY0C", "EA0C", "EB0C", "EXP", "EYP", "EZP"]
TRUTH = np.array([0.01, -0.02, 3e-5, -2e-5, 0.005, 0.004, -0.003])


def test_follow_positions_hold_the_tool_on_the_ball() -> None:
    q = follow_positions(FIVE, {"B": 0.0, "C": C}, BALL)
    np.testing.assert_allclose(FIVE.tool_position(q), np.tile(BALL, (C.size, 1)), atol=1e-12)
    with pytest.raises(InputError, match="rotary axes"):
        follow_positions(FIVE, {"C": C}, BALL)


def _check_second_order_rest(q: np.ndarray, names: list[str], truth: np.ndarray) -> None:
    """Identified from the exact kinematics, the errors differ from ``truth`` by a second
    order rest: below 10⁻³ relative, and halved when the errors are halved."""
    A = rotary_design(FIVE, q, names)
    rel = []
    for k in (1.0, 0.5):
        e = rotary_displacement(FIVE, q, BALL, dict(zip(names, k * truth, strict=True)))
        est, *_ = linear_identification(A, names, e.reshape(1, -1))
        rel.append(np.max(np.abs(est[0] / (k * truth) - 1)))
    assert rel[0] < 1e-3
    assert rel[0] / rel[1] == pytest.approx(2.0, rel=0.05)


def test_rtest_recovers_c_axis_location_errors() -> None:
    q = follow_positions(FIVE, {"B": 0.0, "C": C}, BALL)
    A = rotary_design(FIVE, q, NAMES)
    # the first-order route: recovered to rounding
    est, _, _, rms, ident = linear_identification(A, NAMES, (A @ TRUTH)[None])
    np.testing.assert_allclose(est[0], TRUTH, rtol=1e-9)
    assert ident.ok
    assert rms[0] < 1e-15
    # the exact kinematics: the rest is second order
    _check_second_order_rest(q, NAMES, TRUTH)


def test_ballbar_sees_what_it_can_of_the_c_axis() -> None:
    q = follow_positions(FIVE, {"B": 0.0, "C": C}, BALL)
    radial = rotary_design(FIVE, q, NAMES, direction=[1, 0, 0])
    err = dict(zip(NAMES, TRUTH, strict=True))
    reading = rotary_ballbar(FIVE, q, BALL, [1, 0, 0], 100.0, err)
    # the reading of the exact kinematics is the first-order one to second order
    assert np.max(np.abs(reading[0] - radial @ TRUTH)) < 2e-5
    # one radial bar at one height cannot separate an offset of the axis from its tilt,
    # nor see the set-up across the bar: the report names them
    with pytest.raises(IdentifiabilityError, match="EYP") as info:
        linear_identification(radial, NAMES, reading)
    assert "EA0C" in str(info.value)
    # the offset alone (tilts and set-up known to be zero) it sees
    sub = rotary_design(FIVE, q, ["EX0C", "EY0C"], direction=[1, 0, 0])
    est, *_ = linear_identification(sub, ["EX0C", "EY0C"], sub @ TRUTH[:2])
    np.testing.assert_allclose(est[0], TRUTH[:2], rtol=1e-9)


B = np.radians(np.linspace(-60.0, 60.0, 25))
B_NAMES = ["EX0B", "EZ0B", "EA0B", "EC0B", "EXP", "EYP", "EZP"]
B_TRUTH = np.array([0.01, -0.008, 2e-5, -1.5e-5, 0.003, -0.002, 0.004])


def test_rtest_recovers_b_axis_location_errors() -> None:
    """The B-axis test (B tilting through ±60°, C held, X, Y, Z following): ISO 230-7's
    EX0B, EZ0B (offsets of the axis) and EA0B, EC0B (its tilts) from the exact kinematics,
    the rest second order as for the C axis."""
    q = follow_positions(FIVE, {"B": B, "C": 0.0}, BALL)
    np.testing.assert_allclose(FIVE.tool_position(q), np.tile(BALL, (B.size, 1)), atol=1e-12)
    A = rotary_design(FIVE, q, B_NAMES)
    est, _, _, _, ident = linear_identification(A, B_NAMES, (A @ B_TRUTH)[None])
    np.testing.assert_allclose(est[0], B_TRUTH, rtol=1e-9)
    assert ident.ok
    _check_second_order_rest(q, B_NAMES, B_TRUTH)
    # along its own direction an axis has no location error: the zero of B is EBB's
    with pytest.raises(InputError, match="not a location error of rotary axis B"):
        rotary_design(FIVE, q, [*B_NAMES, "EY0B"])
