"""The Monte Carlo of a whole circular test through the engine, beside the GUM."""

from __future__ import annotations

import numpy as np
import pytest

from mtmc.circular import Ballbar, circular_model, design, evaluate_uncertainty, identify
from mtmc.errors import InputError
from mtmc.uncertainty import Normal, Uniform, conformity

R = 150.0
T = np.linspace(0.0, 2 * np.pi, 90, endpoint=False)
DES = design(radius=R, theta_ccw=T, theta_cw=T)
SIGMA = 5e-4  # mm, the noise of each reading
M = 20_000
# the relative standard error of a Monte Carlo standard deviation is 1/sqrt(2M) = 0.5 %;
# 3 % is six of them
U_RTOL = 0.03


def _errors() -> dict[str, object]:
    return {
        "squareness": 2e-5,
        "scale_mismatch": 1e-5,
        "backlash_x": 0.003,
        "backlash_y": Normal(0.002, 0.0003),
        "servo_mismatch": 5e-4,
        "centre_x": Uniform(-0.005, 0.005),
        "centre_y": 0.001,
    }


@pytest.fixture(scope="module")
def result():  # type: ignore[no-untyped-def]
    bb = Ballbar(
        length_error=Normal(0.0, 0.0005),
        alpha=11.5e-6,
        temperature=Normal(20.5, 0.3),
        noise=SIGMA,
    )
    model, inputs = circular_model(DES, bb, errors=_errors())
    return model, evaluate_uncertainty(model, inputs, M, seed=3)


def test_identified_errors_monte_carlo_against_gum_and_closed_form(result) -> None:  # type: ignore[no-untyped-def]
    _, r = result
    cinv = np.linalg.inv(DES.matrix.T @ DES.matrix)
    for j, name in enumerate(DES.names):
        mc, g = r.monte_carlo(name), r.gum_result(name)
        # the identification is linear in the inputs: the GUM is exact ...
        if name in ("squareness", "scale_mismatch", "servo_mismatch", "backlash_x"):
            # ... and where only the noise varies, u = σ sqrt((AᵀA)⁻¹_jj) (constant inputs)
            assert g.u == pytest.approx(SIGMA * np.sqrt(cinv[j, j]), rel=1e-6), name
        assert mc.u == pytest.approx(g.u, rel=U_RTOL), name
    # the estimates: the injected means (the mean scale and the bar's length are `radius`)
    assert r.gum_result("squareness").estimate == pytest.approx(2e-5, rel=1e-9)
    assert r.gum_result("backlash_y").estimate == pytest.approx(0.002, rel=1e-9)
    assert r.gum_result("radius").estimate == pytest.approx(-11.5e-6 * 0.5 * R, rel=1e-9)
    # u(radius): the bar's calibration, its temperature and the noise, in quadrature
    u_rad = np.hypot(0.0005, 11.5e-6 * 0.3 * R)
    u_rad = np.hypot(u_rad, SIGMA * np.sqrt(cinv[0, 0]))
    assert r.gum_result("radius").u == pytest.approx(u_rad, rel=1e-6)


def test_extremes_lie_above_the_gum(result) -> None:  # type: ignore[no-untyped-def]
    _, r = result
    # G is a range over noisy points: the GUM linearises at the extreme points of the
    # mean trace, the Monte Carlo sees that the range of noisy points is wider
    for name in ("G_lsc", "G_mz", "H"):
        mc, g = r.monte_carlo(name), r.gum_result(name)
        assert mc.estimate > g.estimate + mc.u / 2, name
        assert not r.validation[name].passed
    assert r.monte_carlo("G_mz").estimate <= r.monte_carlo("G_lsc").estimate


def test_conformity_through_the_engine_rule(result) -> None:  # type: ignore[no-untyped-def]
    _, r = result
    mc = r.monte_carlo("G_lsc")
    tol = float(np.quantile(mc.samples, 0.8))
    c = conformity(mc, upper=tol)
    # p_c by the samples: the fraction at or below the limit, recomputed here
    assert c.p_c == pytest.approx(np.mean(mc.samples <= tol), abs=1e-12)
    guarded = conformity(mc, upper=tol, rule="guarded", guard=1.0)
    assert guarded.acceptance_upper == pytest.approx(tol - 2 * mc.u)


def test_measured_trace() -> None:
    rng = np.random.default_rng(4)
    beta = np.array([0.001, 0.002, -0.001, 2e-5, 1e-5, 0.003, 0.002, 5e-4])
    meas = DES.deviation(beta)[0] + rng.normal(0, SIGMA, DES.theta.size)
    ident = identify(DES, meas)
    s = float(ident.rms[0])
    model, inputs = circular_model(DES, Ballbar(noise=s), measured=meas)
    r = evaluate_uncertainty(model, inputs, 4000, seed=1)
    for j, name in enumerate(DES.names):
        g = r.gum_result(name)
        assert g.estimate == pytest.approx(ident.estimates[0, j], rel=1e-9, abs=1e-15)
        # the trace's own scatter as Type A: u is the identification's s sqrt((AᵀA)⁻¹)
        assert g.u == pytest.approx(np.sqrt(ident.covariance[0, j, j]), rel=1e-6)


def test_model_input_errors() -> None:
    with pytest.raises(InputError, match="either errors"):
        circular_model(DES, Ballbar())
    with pytest.raises(InputError, match="unknown error 'roundness'"):
        circular_model(DES, Ballbar(), errors={"roundness": 1.0})
    with pytest.raises(InputError, match="180 finite"):
        circular_model(DES, Ballbar(), measured=np.zeros(3))
    with pytest.raises(InputError, match="noise"):
        Ballbar(noise=-1.0)


def test_rtest_monte_carlo_against_gum() -> None:
    from mtmc.circular import follow_positions, rotary_displacement, rotary_model
    from mtmc.kinematics import Machine

    m = Machine.from_topology("wCBXfYZt")
    c = np.linspace(0.0, 2 * np.pi, 36, endpoint=False)
    ball = np.array([150.0, 0.0, 80.0])
    q = follow_positions(m, {"B": 0.0, "C": c}, ball)
    names = ["EX0C", "EY0C", "EA0C", "EB0C", "EXP", "EYP", "EZP"]
    J = m.jacobian(q, None, names=names)
    errors = dict(zip(names, [0.01, -0.02, 3e-5, -2e-5, 0.005, 0.004, -0.003], strict=True))
    errors["EX0C"] = Normal(0.01, 0.002)  # type: ignore[assignment]
    sigma = 2e-4
    model, inputs = rotary_model(J, errors, noise=sigma)
    assert model.outputs[:3] == ("range_x", "range_y", "range_z")
    r = evaluate_uncertainty(model, inputs, M, seed=2)
    flat = J.reshape(-1, len(names))
    cinv = np.linalg.inv(flat.T @ flat)
    for j, name in enumerate(names):
        g = r.gum_result(name)
        assert g.estimate == pytest.approx(float(np.mean(inputs[name].mean)), rel=1e-9)
        if name != "EX0C":
            # noise alone: u = σ sqrt((JᵀJ)⁻¹_jj), the GUM exact for a linear model
            assert g.u == pytest.approx(sigma * np.sqrt(cinv[j, j]), rel=1e-6), name
        assert r.monte_carlo(name).u == pytest.approx(g.u, rel=U_RTOL), name
    # the ranges at the input estimates: those of the exact kinematics, to second order
    # in the errors (offsets of 0.02 mm, tilts of 3e-5 rad at 150 mm: the displacements
    # differ by up to 1.4e-6 mm in z, a quarter of it when the errors halve)
    mean = {k: float(np.mean(inputs[k].mean)) for k in names}
    e = rotary_displacement(m, q, ball, mean)[0]
    for k, a in enumerate("xyz"):
        want = e[:, k].max() - e[:, k].min()
        assert r.gum_result(f"range_{a}").estimate == pytest.approx(want, abs=3e-6)
