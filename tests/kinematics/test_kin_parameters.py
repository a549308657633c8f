"""Parameter vector <-> named errors, and the Jacobian w.r.t. the parameter vector."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mtmc.errors import InputError
from mtmc.kinematics import (
    ChebyshevSeries,
    ErrorModel,
    FourierSeries,
    LegendreSeries,
    PolynomialFunction,
    library_machine,
)


def _model() -> ErrorModel:
    m = library_machine("table-table")
    return ErrorModel(
        m,
        {
            "EXX": LegendreSeries(np.zeros(4), low=-400.0, high=400.0),
            "EYZ": ChebyshevSeries(np.zeros(3), low=-400.0, high=0.0),
            "ECX": PolynomialFunction(np.zeros(3)),
            "ECC": FourierSeries(np.zeros(5)),
            "EX0C": 0.0,
            "C0Y": 0.0,
            "EA0C": 0.0,
        },
    )


def test_names_and_round_trip() -> None:
    model = _model()
    assert model.n_parameters == 4 + 3 + 3 + 5 + 3
    assert model.parameter_names[:5] == ("EXX[0]", "EXX[1]", "EXX[2]", "EXX[3]", "EYZ[0]")
    assert model.parameter_names[-3:] == ("EX0C", "EC0Y", "EA0C")
    rng = np.random.default_rng(np.random.SeedSequence(5))
    theta = rng.normal(size=model.n_parameters)
    np.testing.assert_array_equal(model.vector(model.errors(theta)), theta)
    thetas = rng.normal(size=(7, model.n_parameters))
    np.testing.assert_array_equal(model.vector(model.errors(thetas)), thetas)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(-1e-3, 1e-3), min_size=18, max_size=18))
def test_round_trip_property(values: list[float]) -> None:
    model = _model()
    theta = np.array(values)
    back = model.vector(model.errors(theta))
    np.testing.assert_array_equal(back, theta)


@pytest.mark.parametrize("exact", [False, True])
def test_parameter_jacobian_matches_central_differences(exact: bool) -> None:
    model = _model()
    rng = np.random.default_rng(np.random.SeedSequence(6))
    m = 5
    q = np.column_stack(
        [rng.uniform(-400, 400, (m, 2)), rng.uniform(-400, 0, m), rng.uniform(-2, 2, (m, 2))]
    )
    theta = rng.normal(size=model.n_parameters) * 1e-5
    J = model.jacobian(q, theta, exact=exact)
    for k in range(model.n_parameters):
        # exact rotations are non-linear in the angles: a step that moves every error value
        # by about 1e-6 (q^2 terms are 1e5 times larger); rounding then costs ~1e-13 |p| / h
        h = 1e-6 / max(1.0, float(np.max(np.abs(J[:, :, k]))) / 1e3) if exact else 1e-6
        tol = 1e-6 + 2e-13 * 1e3 / h
        d = np.zeros(model.n_parameters)
        d[k] = h
        fd = (
            model.tool_position(q, theta + d, exact=exact)
            - model.tool_position(q, theta - d, exact=exact)
        ) / (2 * h)
        np.testing.assert_allclose(
            J[:, :, k], fd, rtol=1e-6, atol=tol, err_msg=model.parameter_names[k]
        )
    # closed forms at A = C = 0 (no rotation between the axes and the workpiece): the
    # constant terms of EXX (Legendre P0 = 1) and EYZ (Chebyshev T0 = 1) move the tool by
    # their value along x and y; the linear terms by it times P1 = x/400 on [-400, 400] and
    # T1 = (z + 200)/200 on [-400, 0]
    q[:, 3:] = 0.0
    p0 = model.tool_position(q, np.zeros(model.n_parameters), exact=exact)
    one, zero = np.ones(m), np.zeros(m)
    for name, shift in (
        ("EXX[0]", [one, zero, zero]),
        ("EXX[1]", [q[:, 0] / 400, zero, zero]),
        ("EYZ[0]", [zero, one, zero]),
        ("EYZ[1]", [zero, (q[:, 2] + 200) / 200, zero]),
    ):
        d = np.zeros(model.n_parameters)
        d[model.parameter_names.index(name)] = 1e-4
        got = model.tool_position(q, d, exact=exact) - p0
        np.testing.assert_allclose(got, 1e-4 * np.column_stack(shift), atol=1e-12, err_msg=name)


def test_bad_models_and_vectors() -> None:
    m = library_machine("xfyz")
    with pytest.raises(InputError, match="EC0Y is a squareness error: expected a number"):
        ErrorModel(m, {"EC0Y": PolynomialFunction([0.0, 0.0])})
    model = ErrorModel(m, {"EXX": PolynomialFunction([0.0, 0.0]), "EYY": 0.0})
    with pytest.raises(InputError, match=r"expected a parameter vector of shape \(3,\)"):
        model.errors(np.zeros(4))
    with pytest.raises(InputError, match="no value for error EYY of the model"):
        model.vector({"EXX": PolynomialFunction([0.0, 1.0])})
    with pytest.raises(InputError, match="expected a PolynomialFunction with 2 coefficients"):
        model.vector({"EXX": PolynomialFunction([0.0, 1.0, 2.0]), "EYY": 0.0})
    with pytest.raises(InputError, match="error EZZ is not in the model"):
        model.vector({"EXX": PolynomialFunction([0.0, 1.0]), "EYY": 0.0, "EZZ": 1.0})
