"""Components of vector inputs in model expressions: ``x[0]``, ``x[1]`` (JCGM 102 inputs)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mtmc.errors import ExpressionError
from mtmc.uncertainty import (
    IID,
    MultivariateNormal,
    Normal,
    check_components,
    expression,
    gum,
    monte_carlo,
)

MEAN = [1.0, 2.0]
COV = [[0.01, 0.002], [0.002, 0.04]]


def test_a_component_is_the_numpy_column_of_every_trial():
    # reference: NumPy's own column access of the same (M, k) array
    rng = np.random.default_rng(3)
    x = rng.normal(size=(7, 3))
    a = rng.normal(size=7)
    f = expression("x[0] * a + x[2] ** 2")
    assert f.names == ("x", "a")
    assert dict(f.components) == {"x": 3}
    np.testing.assert_array_equal(f(x=x, a=a), x[:, 0] * a + x[:, 2] ** 2)  # same operations


def test_components_of_trials_of_several_axes_are_the_last_axis():
    # an input of shape (M, n, k): x[1] is x[..., 1], shape (M, n)
    x = np.arange(24.0).reshape(2, 3, 4)
    np.testing.assert_array_equal(expression("x[1] - x[0]")(x=x), x[..., 1] - x[..., 0])


def test_complex_values_are_carried_through_a_component():
    # the complex step of the GUM goes through x[i]: d/dx0 (x0² x1) = 2 x0 x1
    h = 1e-20
    x = np.array([[0.3 + 1j * h, 0.7]])
    got = expression("x[0] ** 2 * x[1]")(x=x)
    assert got.imag[0] / h == pytest.approx(2 * 0.3 * 0.7, rel=1e-15)  # exact to rounding


def test_gum_of_a_sum_of_components_is_the_sum_of_the_covariance():
    # closed form: u²(x0 + x1) = U00 + U11 + 2 U01 = 0.054 (JCGM 100 eq. (13))
    g = gum(expression("x[0] + x[1]"), {"x": MultivariateNormal(MEAN, COV)})
    assert g.method == "complex-step"
    assert g.estimate == 3.0
    assert g.u**2 == pytest.approx(0.054, rel=1e-14)  # one rounding per product and sum
    assert g.budget[0].sensitivity.tolist() == [[1.0, 1.0]]


def test_monte_carlo_of_a_sum_of_components_within_its_standard_error():
    # closed form u² = 0.054; the sample variance of M normal values has the standard
    # error u² sqrt(2/(M-1)): the estimate is within 4 of them, and the mean within 4 u/√M
    m = 40_000
    r = monte_carlo(
        expression("x[0] + x[1]"), {"x": MultivariateNormal(MEAN, COV)}, trials=m, seed=11
    )
    assert abs(r.u**2 - 0.054) <= 4 * 0.054 * math.sqrt(2 / (m - 1))
    assert abs(r.estimate - 3.0) <= 4 * math.sqrt(0.054 / m)


def test_monte_carlo_components_are_the_columns_of_the_drawn_input():
    # a second method: the model that returns the input itself gives the (M, 2) draws;
    # x[0] + x[1] must be the sum of their columns, bit for bit (the same seeded draws)
    x = {"x": MultivariateNormal(MEAN, COV)}
    whole = monte_carlo(lambda x: x, x, trials=5000, seed=5).values
    summed = monte_carlo(expression("x[0] + x[1]"), x, trials=5000, seed=5).values
    np.testing.assert_array_equal(summed, whole[:, 0] + whole[:, 1])


def test_gum_of_a_nonlinear_model_of_iid_components():
    # closed form: y = x0 x1 x2 of iid normal(2, 0.1): c_i = 4, u² = 3 (4 · 0.1)² = 0.48
    g = gum(expression("x[0] * x[1] * x[2]"), {"x": IID(Normal(2.0, 0.1), 3)})
    assert g.estimate == pytest.approx(8.0, rel=1e-15)  # 2·2·2, exact
    assert g.u**2 == pytest.approx(0.48, rel=1e-13)  # complex step: exact to rounding


def test_gum_of_a_not_complex_safe_model_with_components():
    # abs() makes the GUM use central differences; y = |x0 - x1| at (1, 2) has c = (-1, 1),
    # u² = U00 + U11 - 2 U01 = 0.046; central differences of a linear piece are exact to
    # rounding of the step (1e-3 u): a relative 1e-9
    g = gum(expression("abs(x[0] - x[1])"), {"x": MultivariateNormal(MEAN, COV)})
    assert g.method == "central-difference"
    assert g.u**2 == pytest.approx(0.046, rel=1e-9)


@pytest.mark.parametrize(
    ("dims", "fragment"),
    [
        ({"x": 2}, "x[2] in 'x[0] + x[2]' is out of range: x has 2 component(s), x[0] to x[1]"),
        ({"x": 0}, "x[2] in 'x[0] + x[2]' takes a component of x, but x is a scalar input"),
    ],
)
def test_an_index_the_input_cannot_serve_names_the_expression(dims, fragment):
    with pytest.raises(ExpressionError) as info:
        check_components(expression("x[0] + x[2]"), dims)
    assert fragment in str(info.value)
    assert info.value.field == "x"


def test_the_gum_refuses_an_index_out_of_range_before_evaluating():
    with pytest.raises(ExpressionError, match=r"x\[2\] in 'x\[2\] \* 2' is out of range"):
        gum(expression("x[2] * 2"), {"x": MultivariateNormal(MEAN, COV)})


def test_calling_with_a_value_without_components_is_refused():
    f = expression("x[1] + 1")
    with pytest.raises(ExpressionError, match=r"needs x as an array \(M, k\) of k >= 2"):
        f(x=np.ones(5))  # (M,): no component axis
    with pytest.raises(ExpressionError, match=r"got shape \(5, 1\)"):
        f(x=np.ones((5, 1)))


@pytest.mark.parametrize(
    ("text", "fragment", "column"),
    [
        ("x[-1]", "the negative index in x[-1]", 3),
        ("x[b]", "the index b of x", 3),
        ("x[0:2]", "slices in subscripts of x", 3),
        ("x[1.0]", "the index 1.0 of x", 3),
        ("x[True]", "the index True of x", 3),
        ("x[0, 1]", "the index 0, 1 of x", 3),
        ("x[0][1]", "subscripts of anything but a variable name", 1),
        ("sqrt(x)[0]", "subscripts of anything but a variable name", 1),
        ("x.real[0]", "subscripts of anything but a variable name", 1),
        ("pi[0]", "subscripts of 'pi'", 1),
        ("sqrt[0]", "subscripts of 'sqrt'", 1),
        ("_x[0]", "names starting with '_'", 1),
        ("x[__import__('os')]", "the index __import__('os') of x", 3),
        ("x[len(y)]", "the index len(y) of x", 3),
        ("x[0] + x", "using x both whole and by components", 8),
        ("x * x[1]", "using x both whole and by components", 5),
    ],
)
def test_unsafe_or_ambiguous_subscripts_are_refused_with_their_column(text, fragment, column):
    with pytest.raises(ExpressionError) as info:
        expression(text)
    msg = str(info.value)
    assert fragment in msg
    assert f"column {column}:" in msg
    assert "components x[0], x[1], ... of vector variables" in msg  # what is allowed


def test_parentheses_around_an_index_are_the_index():
    assert dict(expression("x[(1)]").components) == {"x": 2}


def test_an_expression_with_components_pickles_for_worker_processes():
    # a process pool sends the model by pickle: the copy evaluates alike, bit for bit
    import pickle

    f = expression("x[0] + x[2] * a")
    g = pickle.loads(pickle.dumps(f))
    assert g == f
    assert dict(g.components) == {"x": 3}
    x, a = np.arange(12.0).reshape(4, 3), np.arange(4.0)
    np.testing.assert_array_equal(g(x=x, a=a), f(x=x, a=a))
