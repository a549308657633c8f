"""Identification: injected coefficients back; rank deficiency by name; batched = one at a time."""

from __future__ import annotations

import numpy as np
import pytest

from mtmc.errors import IdentifiabilityError
from mtmc.geometry import matrix_from_rotation_vector
from mtmc.instruments import LaserTracker
from mtmc.kinematics import ErrorModel, PolynomialFunction
from mtmc.verification.identify import identify


def _readings(s, theta, tracker=None):  # type: ignore[no-untyped-def]
    lt = tracker or s["tracker"]
    return lt.to_tracker(s["model"].tool_position(s["q"], theta))


def test_noise_free_returns_injected_coefficients_and_pose(setup) -> None:  # type: ignore[no-untyped-def]
    s = setup
    true_lt = LaserTracker(
        s["tracker"].rotation @ matrix_from_rotation_vector([2e-4, -1e-4, 3e-4]),
        s["tracker"].position + np.array([0.5, -0.3, 0.2]),
    )
    meas = _readings(s, s["theta"], true_lt)
    r = identify(s["model"], s["q"], meas, s["tracker"], fixed=s["fixed"])
    assert r.converged.all()
    free = [s["model"].parameter_names.index(n) for n in r.names[:-6]]
    rel = np.abs(r.estimate[0, :-6] / s["theta"][free] - 1.0)
    assert rel.max() < 1e-9
    assert np.allclose(r.rotation[0], true_lt.rotation, atol=1e-13)
    assert np.allclose(r.position[0], true_lt.position, atol=1e-10)
    assert r.residual_ve.max() < 1e-10
    assert r.initial_ve.max() > 1e-2


def test_model_poorer_than_the_machine_leaves_a_residual(setup) -> None:  # type: ignore[no-untyped-def]
    s = setup
    truth = dict(s["model"].errors(s["theta"]))
    truth["EXX"] = PolynomialFunction([*truth["EXX"].coefficients, 1e-12])  # quartic term
    meas = s["tracker"].to_tracker(s["machine"].tool_position(s["q"], truth))
    r = identify(s["model"], s["q"], meas, s["tracker"], fixed=s["fixed"])
    assert r.converged.all()
    assert 1e-4 < r.residual_ve.max() < r.initial_ve.max()


def test_rank_deficient_case_is_reported_by_name(setup) -> None:  # type: ignore[no-untyped-def]
    s = setup
    meas = _readings(s, s["theta"])
    # a constant positioning error vs the tracker's x-position
    fixed = tuple(n for n in s["fixed"] if n != "EXX[0]")
    with pytest.raises(IdentifiabilityError) as exc:
        identify(s["model"], s["q"], meas, s["tracker"], fixed=fixed)
    assert len(exc.value.combinations) == 1
    assert "EXX[0]" in exc.value.combinations[0]
    assert "LT.x" in exc.value.combinations[0]
    # the linear term of a straightness vs the squareness (no tracker pose)
    fixed = tuple(n for n in s["fixed"] if n != "EXY[1]")
    r = identify(
        s["model"], s["q"], meas, s["tracker"], fixed=fixed, pose=False, on_rank_deficient="report"
    )
    assert r.identifiability.groups == (("EXY[1]", "EC0Y"),)
    assert r.identifiability.combinations[0] in ("1·EXY[1] +1·EC0Y", "-1·EXY[1] -1·EC0Y")
    assert "EXY[1]" in r.identifiability.text()
    # a rotation without lever arm: the yaw of Y turns the reflector about its own line
    model = ErrorModel(
        s["machine"], {**s["model"].templates, "ECY": PolynomialFunction([0.0, 0.0])}
    )
    with pytest.raises(IdentifiabilityError, match=r"ECY\[1\]"):
        identify(model, s["q"], meas, s["tracker"], fixed=s["fixed"] + ("ECY[0]",))


def test_default_model_is_identifiable(setup) -> None:  # type: ignore[no-untyped-def]
    s = setup
    r = identify(s["model"], s["q"], _readings(s, s["theta"]), s["tracker"], fixed=s["fixed"])
    assert r.identifiability.ok
    assert r.identifiability.rank == len(r.names)


def test_batched_equals_one_at_a_time(setup) -> None:  # type: ignore[no-untyped-def]
    s = setup
    rng = np.random.default_rng(np.random.SeedSequence(11))
    x = _readings(s, s["theta"])
    meas = x[None] + rng.normal(0, 0.005, (4, *x.shape))
    batch = identify(s["model"], s["q"], meas, s["tracker"], fixed=s["fixed"])
    for m in range(4):
        one = identify(s["model"], s["q"], meas[m], s["tracker"], fixed=s["fixed"])
        assert np.allclose(one.estimate[0], batch.estimate[m], rtol=1e-9, atol=1e-15)
        assert np.allclose(one.residual_ve[0], batch.residual_ve[m], rtol=1e-9, atol=1e-12)


def test_against_scipy_least_squares(setup) -> None:  # type: ignore[no-untyped-def]
    """Batched (3 sets at once) equals scipy's, one set at a time, finite-difference
    Jacobian: 1e-6 relative on every coefficient and pose parameter, or 1e-9 u for one
    within 10⁻³ u of zero (the second set has one at 2·10⁻⁴ u; the rounding floor of
    either solution is about 10⁻¹⁰ u)."""
    from scipy.optimize import least_squares as sp_lsq

    s = setup
    rng = np.random.default_rng(np.random.SeedSequence(3))
    x = _readings(s, s["theta"])
    meas = x[None] + rng.normal(0, 0.005, (3, *x.shape))
    r = identify(s["model"], s["q"], meas, s["tracker"], fixed=s["fixed"])
    assert r.converged.all()
    model, lt = s["model"], s["tracker"]
    free = [model.parameter_names.index(n) for n in r.names[:-6]]
    k = len(free)

    def fun(w: np.ndarray, m: np.ndarray) -> np.ndarray:
        th = np.zeros(model.n_parameters)
        th[free] = w[:k]
        R = lt.rotation @ matrix_from_rotation_vector(w[k : k + 3])
        return ((model.tool_position(s["q"], th) - lt.position - w[k + 3 :]) @ R - m).ravel()

    # variables near 1 so that scipy's relative steps are these (mm, rad): the readings
    # are linear in each coefficient, the rotation's central difference errs by h²/6
    step = np.r_[np.full(k, 1e-3), np.full(3, 1e-5), np.full(3, 1.0)]
    for m in range(3):
        sp = sp_lsq(
            lambda v, mm: fun((v - 1.0) * step, mm),
            np.ones(step.size),
            args=(meas[m],),
            jac="3-point",
            diff_step=1.0,
            x_scale="jac",
            xtol=1e-15,
            ftol=1e-15,
            gtol=1e-15,
        )
        diff = np.abs((sp.x - 1.0) * step - r.estimate[m])
        assert np.all(diff <= 1e-6 * np.abs(r.estimate[m]) + 1e-9 * r.u[m])
        big = np.abs(r.estimate[m]) > 1e-3 * r.u[m]
        assert (diff / np.abs(r.estimate[m]))[big].max() < 1e-6


def test_small_model_docstring_case() -> None:
    from mtmc.kinematics import Machine

    m = Machine.from_topology("XFYZ")
    em = ErrorModel(m, {"EXX": PolynomialFunction([0.0, 0.0]), "EC0Y": 0.0})
    q = np.array([[x, y, 0.0] for x in (0, 200, 400) for y in (0, 200, 400)])
    lt = LaserTracker.from_euler([-800.0, 200.0, 600.0], [0.0, 0.0, 0.5])
    meas = lt.to_tracker(m.tool_position(q, {"EXX": PolynomialFunction([0.0, 2e-5]), "EC0Y": 1e-5}))
    r = identify(em, q, meas, lt, pose=False, fixed={"EXX[0]": 0.0})
    assert np.allclose(r.estimate[0], [2e-5, 1e-5], rtol=1e-9)


def test_identifiability_with_fewer_readings_than_parameters() -> None:
    """Two readings of three parameters: the third direction is the null space of J,
    found from the full SVD (x1 - x2 + 0·x3 does not change these readings; x3 alone
    is seen)."""
    from mtmc.verification.identify import identifiability

    J = np.array([[1.0, 1.0, 0.0], [0.0, 0.0, 2.0]])
    ident = identifiability(J, ["x1", "x2", "x3"])
    assert not ident.ok
    assert ident.groups == (("x1", "x2"),)
    # the combination named is the null vector of J, in the parameters' own units
    (combo,) = ident.combinations
    assert combo.replace(" ", "") in ("1·x1-1·x2", "-1·x1+1·x2")
    # one reading of three parameters: two null directions, none an IndexError
    assert len(identifiability(J[:1], ["x1", "x2", "x3"]).groups) == 2
