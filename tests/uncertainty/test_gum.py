"""GUM propagation: sensitivities vs analytic derivatives, u vs closed forms,
Welch–Satterthwaite vs JCGM 100 H.1, correlated inputs vs C U Cᵀ, one batched call."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mtmc import (
    Arcsine,
    Constant,
    InputError,
    MultivariateNormal,
    Normal,
    StudentT,
    Uniform,
    expression,
    monte_carlo,
    parse_distribution,
    validate,
)
from mtmc.uncertainty.distributions import Distribution
from mtmc.uncertainty.propagation import GumResult, coverage_factor, gum, welch_satterthwaite

REFERENCE = Path(__file__).resolve().parents[1] / "reference"


def gauge_block_inputs(table: str) -> dict[str, Distribution]:
    """The end-gauge inputs of ``tests/reference/gauge_block/inputs.toml``: shared + ``table``."""
    text = (REFERENCE / "gauge_block" / "inputs.toml").read_text(encoding="utf-8")
    data = tomllib.loads(text)
    return {
        name: parse_distribution(pdf) for name, pdf in {**data["shared"], **data[table]}.items()
    }


X0 = {"a": 1.3, "b": 0.7, "c": 2.1}
U0 = {"a": 0.01, "b": 0.02, "c": 0.05}


def _inputs(names):
    return {n: Normal(X0[n], U0[n]) for n in names}


# (formula, analytic gradient at X0) -- gradients written out by hand
a, b, c = X0["a"], X0["b"], X0["c"]
MODELS = [
    ("a * b / c", {"a": b / c, "b": a / c, "c": -a * b / c**2}),
    ("a ** b", {"a": b * a ** (b - 1), "b": a**b * math.log(a)}),
    ("sin(a) * cos(b)", {"a": math.cos(a) * math.cos(b), "b": -math.sin(a) * math.sin(b)}),
    (
        "exp(a) * log(c) + sqrt(b)",
        {"a": math.exp(a) * math.log(c), "b": 0.5 / math.sqrt(b), "c": math.exp(a) / c},
    ),
    (
        "arctan(a / c) + arcsin(b)",
        {"a": c / (a**2 + c**2), "c": -a / (a**2 + c**2), "b": 1 / math.sqrt(1 - b**2)},
    ),
    ("log10(a) - tan(b)", {"a": 1 / (a * math.log(10)), "b": -1 / math.cos(b) ** 2}),
]


@pytest.mark.parametrize(("text", "grad"), MODELS)
def test_complex_step_sensitivities_match_analytic_derivatives(text, grad):
    expr = expression(text)
    res = gum(expr, _inputs(expr.names))
    assert res.method == "complex-step"
    for name, value in grad.items():
        assert res.sensitivities[name] == pytest.approx(value, rel=1e-13, abs=1e-15)
    u_ref = math.sqrt(sum((grad[n] * U0[n]) ** 2 for n in grad))
    assert res.u == pytest.approx(u_ref, rel=1e-13)
    f = {n: np.array([X0[n]]) for n in expr.names}
    assert res.estimate == pytest.approx(float(expr(**f)[0]), rel=1e-15)


def test_model_not_complex_safe_falls_back_to_central_differences():
    # np.abs drops the imaginary part: the complex-step row gives c_a = 0, the central
    # differences in the same call give c_a = sign(a) * b; the check must notice.
    res = gum(lambda a, b: np.abs(a - 2.0) * b, {"a": Normal(1.3, 0.01), "b": Normal(0.7, 0.02)})
    assert res.method == "central-difference"
    assert res.sensitivities["a"] == pytest.approx(-0.7, rel=1e-8)
    assert res.sensitivities["b"] == pytest.approx(0.7, rel=1e-8)


def test_model_refusing_complex_input_uses_central_differences():
    res = gum(lambda a, b: np.hypot(a, b), {"a": Normal(3.0, 0.1), "b": Normal(4.0, 0.1)})
    assert res.method == "central-difference"
    assert res.sensitivities["a"] == pytest.approx(0.6, rel=1e-8)
    assert res.sensitivities["b"] == pytest.approx(0.8, rel=1e-8)
    assert res.u == pytest.approx(0.1, rel=1e-8)
    expr = expression("hypot(a, b)")
    assert not expr.complex_safe
    assert gum(expr, {"a": Normal(3.0, 0.1), "b": Normal(4.0, 0.1)}).method == "central-difference"


def test_all_sensitivity_evaluations_in_one_batched_call():
    calls = []

    def model(a, b, c):
        calls.append(a.shape)
        return a * b + np.exp(c)

    gum(model, _inputs("abc"))
    assert len(calls) == 1
    assert calls[0] == (1 + 3 * 3,)


def test_linear_model_u_closed_form_and_budget():
    # y = 2 x1 - 3 x2 + x3: u² = 4 u1² + 9 u2² + u3², shares = the terms / u².
    inputs = {"x1": Normal(1.0, 0.3), "x2": Uniform(-1.0, 1.0), "x3": Arcsine(-2.0, 2.0)}
    res = gum(expression("2*x1 - 3*x2 + x3"), inputs)
    u1, u2, u3 = 0.3, 1 / math.sqrt(3), 2 / math.sqrt(2)
    terms = np.array([(2 * u1) ** 2, (3 * u2) ** 2, u3**2])
    assert res.u == pytest.approx(math.sqrt(terms.sum()), rel=1e-14)
    assert [e.name for e in res.budget] == ["x1", "x2", "x3"]
    for entry, term, c, ux in zip(res.budget, terms, (2, -3, 1), (u1, u2, u3), strict=True):
        assert entry.sensitivity == pytest.approx(c, rel=1e-14)
        assert entry.u == pytest.approx(ux, rel=1e-14)
        assert entry.contribution == pytest.approx(math.sqrt(term), rel=1e-14)
        assert entry.share == pytest.approx(term / terms.sum(), rel=1e-13)
    assert sum(e.share for e in res.budget) == pytest.approx(1.0, rel=1e-14)
    assert res.dof == math.inf
    k = res.coverage_factor()
    assert k == pytest.approx(1.959963984540054, rel=1e-14)
    assert res.coverage_interval()[0] == pytest.approx(res.estimate - k * res.u, rel=1e-14)
    assert res.expanded_uncertainty() == pytest.approx(k * res.u)
    assert res.coverage_factor(0.99) == pytest.approx(2.5758293035489004, rel=1e-14)
    assert isinstance(res, GumResult)


def test_product_relative_uncertainty_closed_form():
    # y = a b / c: (u/y)² = Σ (u_i/x_i)² (JCGM 100 eq. (12)).
    res = gum(expression("a * b / c"), _inputs("abc"))
    rel = math.sqrt(sum((U0[n] / X0[n]) ** 2 for n in "abc"))
    assert res.u / res.estimate == pytest.approx(rel, rel=1e-13)


def test_constant_input_contributes_nothing():
    res = gum(expression("a + k * b"), {"a": Normal(1, 0.1), "b": Normal(2, 0.2), "k": 3.0})
    assert res.u == pytest.approx(math.sqrt(0.01 + 9 * 0.04), rel=1e-14)
    entry = next(e for e in res.budget if e.name == "k")
    assert entry.u == 0
    assert entry.contribution == 0
    assert entry.sensitivity == pytest.approx(2.0)
    assert isinstance(Constant(3.0).std, float)


def test_welch_satterthwaite_gum_h1_end_gauge():
    """JCGM 100 H.1 (end-gauge calibration), model (H.3) with the inputs of Table H.1,
    in nm and °C. A scaled-and-shifted t carries each (u, ν) pair: the GUM takes its
    scale as u. Published: u_c(l) = 32 nm, ν_eff(l) = 16, k = t_95(16) = 2.12, U = 67 nm,
    l = 50.000 838 mm."""
    inputs = gauge_block_inputs("gum_h1")
    model = expression(
        "l_s + d_bar + d1 + d2 - l_s * (alpha_s * dtheta + dalpha * (theta_bar + Delta))"
    )
    res = gum(model, inputs)
    assert round(res.estimate) == 50_000_839  # 50 000 838.6 nm: "50.000 838 mm"
    assert round(res.u) == 32
    # Table H.1 sensitivities: c(δα) = -l_s θ, c(δθ) = -l_s α_s; c(α_s) = c(θ) = 0.
    assert res.sensitivities["dalpha"] == pytest.approx(50_000_623.6 * 0.1, rel=1e-12)
    assert res.sensitivities["dtheta"] == pytest.approx(-50_000_623.6 * 11.5e-6, rel=1e-12)
    assert res.sensitivities["alpha_s"] == 0.0
    assert math.floor(res.dof) == 16
    assert round(res.coverage_factor(), 2) == 2.12
    assert round(res.expanded_uncertainty()) == 67
    # hand computation of eq. (G.2b) from the contributions c_i u_i of Table H.1
    contrib = np.array(
        [25.0, 5.8, 3.9, 6.7, 50_000_623.6 * 0.1 * 0.58e-6, 50_000_623.6 * 11.5e-6 * 0.029]
    )
    nu = np.array([18, 24, 5, 8, 50, 2.0])
    hand = (contrib**2).sum() ** 2 / np.sum(contrib**4 / nu)
    assert res.dof == pytest.approx(hand, rel=1e-9)
    assert welch_satterthwaite(contrib**2, nu) == pytest.approx(hand, rel=1e-14)


def test_welch_satterthwaite_gum_h1_combined_length_difference():
    """JCGM 100 H.1.3.2: d = d̄ + d1 + d2 with u = 5.8, 3.9, 6.7 nm and ν = 24, 5, 8;
    published u(d) = 9.7 nm, ν(d) = 25.6 (also asserted by suncal's
    ``test/test_examples.py::test_GUMH1``). H.1 forms ν(d) with u(d) rounded to 9.7 nm;
    unrounded, eq. (G.2b) gives 25.4."""
    u = np.array([5.8, 3.9, 6.7])
    nu = np.array([24.0, 5.0, 8.0])
    u_d = math.sqrt(float(np.sum(u**2)))
    denom = float(np.sum(u**4 / nu))
    assert welch_satterthwaite(u**2, nu) == pytest.approx(u_d**4 / denom, rel=1e-14)
    assert round(welch_satterthwaite(u**2, nu), 1) == 25.4


@pytest.mark.published_data
def test_gum_h1_prints_nu_from_the_rounded_u():
    """H.1.3.2's own arithmetic (no mtmc call): ν(d) = 25.6 comes from u(d) rounded to
    9.7 nm, where the unrounded u(d) gives 25.4."""
    u = np.array([5.8, 3.9, 6.7])
    nu = np.array([24.0, 5.0, 8.0])
    assert round(math.sqrt(float(np.sum(u**2))), 1) == 9.7
    assert round(9.7**4 / float(np.sum(u**4 / nu)), 1) == 25.6


def test_welch_satterthwaite_edge_cases():
    assert welch_satterthwaite([1.0, 2.0], [math.inf, math.inf]) == math.inf
    assert welch_satterthwaite([1.0, 0.0], [4.0, 1.0]) == pytest.approx(4.0)
    with pytest.raises(InputError, match="same shape"):
        welch_satterthwaite([1.0], [1.0, 2.0])
    with pytest.raises(InputError, match="positive degrees of freedom"):
        welch_satterthwaite([1.0], [0.0])


def test_coverage_factor_against_t_table():
    # t-table values (JCGM 100 Table G.2): ν = 16, p = 95 % -> 2.12; ν = 2 -> 4.30;
    # p = 99 %, ν = inf -> 2.576
    assert round(coverage_factor(0.95, 16), 2) == 2.12
    assert round(coverage_factor(0.95, 2.9), 2) == 4.30
    assert round(coverage_factor(0.99, math.inf), 3) == 2.576
    assert round(coverage_factor(0.6827, math.inf), 3) == 1.000
    with pytest.raises(InputError, match="0 < p < 1"):
        coverage_factor(1.0, 5)


def test_multivariate_input_closed_form_correlated():
    # y = x1 + x2 with corr r: u² = u1² + u2² + 2 r u1 u2 (JCGM 100 eq. (13))
    u1, u2, r = 0.3, 0.4, -0.6
    cov = [[u1**2, r * u1 * u2], [r * u1 * u2, u2**2]]
    res = gum(lambda x: x[:, 0] + x[:, 1], {"x": MultivariateNormal([1.0, 2.0], cov)})
    assert res.u == pytest.approx(math.sqrt(u1**2 + u2**2 + 2 * r * u1 * u2), rel=1e-13)
    assert res.sensitivities["x"] == pytest.approx(np.array([[1.0, 1.0]]))
    assert res.budget[0].share == pytest.approx(1.0)


def test_vector_output_covariance_is_c_ux_ct():
    """Polar to Cartesian with a correlated (r, φ) input and an independent offset:
    U_y = C U_x Cᵀ with C the analytic Jacobian (JCGM 102 §6.2)."""
    r0, phi0, off = 2.0, 0.6, 0.1
    vx = np.array([[0.01, 0.002], [0.002, 0.0009]])
    u_off = 0.05

    def model(x, o):
        return np.stack([x[:, 0] * np.cos(x[:, 1]) + o, x[:, 0] * np.sin(x[:, 1])], axis=1)

    res = gum(model, {"x": MultivariateNormal([r0, phi0], vx), "o": Normal(off, u_off)})
    jac = np.array(
        [
            [np.cos(phi0), -r0 * np.sin(phi0), 1.0],
            [np.sin(phi0), r0 * np.cos(phi0), 0.0],
        ]
    )
    ux = np.zeros((3, 3))
    ux[:2, :2] = vx
    ux[2, 2] = u_off**2
    ref = jac @ ux @ jac.T
    np.testing.assert_allclose(res.cov, ref, rtol=1e-13)
    np.testing.assert_allclose(res.u_vector, np.sqrt(np.diag(ref)), rtol=1e-13)
    np.testing.assert_allclose(res.estimate_vector, [r0 * np.cos(phi0) + off, r0 * np.sin(phi0)])
    np.testing.assert_allclose(res.sensitivities["x"], jac[:, :2], rtol=1e-13)
    np.testing.assert_allclose(res.sensitivities["o"], jac[:, 2:], atol=1e-15)
    for i in range(2):
        one = res.component(i)
        k = coverage_factor(res.p, res.dof_vector[i])
        assert one.estimate == res.estimate_vector[i]
        assert one.u == res.u_vector[i]
        assert one.coverage_interval() == pytest.approx(
            (
                res.estimate_vector[i] - k * res.u_vector[i],
                res.estimate_vector[i] + k * res.u_vector[i],
            ),
            rel=1e-15,
        )
        np.testing.assert_allclose(one.sensitivities["x"], jac[i : i + 1, :2], rtol=1e-13)
        assert one.budget[1].sensitivity == pytest.approx(jac[i, 2], abs=1e-15)
    with pytest.raises(InputError, match="u_vector"):
        _ = res.u
    with pytest.raises(InputError, match="component"):
        res.coverage_interval()
    shares = sum(e.share for e in res.budget)
    np.testing.assert_allclose(shares, [1.0, 1.0], rtol=1e-13)


@settings(max_examples=25, deadline=None)
@given(
    st.floats(0.5, 3.0),
    st.floats(-1.0, 1.0),
    st.floats(1e-3, 0.5),
    st.floats(1e-3, 0.5),
)
def test_sensitivities_agree_with_finite_differences(x, y, ux, uy):
    """Property: for a smooth model the complex-step sensitivities equal high-order
    finite differences computed independently here."""
    expr = expression("x * exp(y) + sin(x * y)")
    res = gum(expr, {"x": Normal(x, ux), "y": Normal(y, uy)})

    def f(xv, yv):
        return xv * math.exp(yv) + math.sin(xv * yv)

    h = 1e-4
    dfx = (-f(x + 2 * h, y) + 8 * f(x + h, y) - 8 * f(x - h, y) + f(x - 2 * h, y)) / (12 * h)
    dfy = (-f(x, y + 2 * h) + 8 * f(x, y + h) - 8 * f(x, y - h) + f(x, y - 2 * h)) / (12 * h)
    assert res.sensitivities["x"] == pytest.approx(dfx, rel=1e-8, abs=1e-10)
    assert res.sensitivities["y"] == pytest.approx(dfy, rel=1e-8, abs=1e-10)


def test_errors_name_the_field():
    for bad in ("x", None, 0.0, 1.0, float("nan")):
        with pytest.raises(InputError, match=r"field p: expected a coverage probability 0 < p < 1"):
            gum(expression("a"), {"a": Normal(0, 1)}, p=bad)
    with pytest.raises(InputError, match=r"the model's variable\(s\) b have no input") as info:
        gum(expression("a + b"), {"a": Normal(0, 1)})
    assert info.value.field == "b"
    with pytest.raises(InputError, match=r"input z is not a variable of the model 'a'"):
        gum(expression("a"), {"a": Normal(0, 1), "z": Normal(0, 1)})
    with pytest.raises(InputError, match="shape \\(m,\\) or \\(m, d\\)"):
        gum(lambda a: np.zeros((2, 2, 2)), {"a": Normal(0, 1)})  # noqa: ARG005
    with pytest.raises(InputError, match="finite expectation") as info:
        gum(lambda a: a, {"a": StudentT(1.0)})
    assert info.value.field == "a"
    with pytest.raises(InputError, match="0 < p < 1"):
        gum(lambda a: a, {"a": Normal(0, 1)}, p=95)
    with pytest.raises(InputError, match="at least one input"):
        gum(lambda: 0, {})


def test_inputs_as_strings_and_numbers():
    res = gum(expression("a * b"), {"a": "normal(2, 0.1)", "b": 3})
    assert res.u == pytest.approx(0.3, rel=1e-14)


def test_estimate_at_the_edge_of_the_domain_uses_complex_step():
    # sqrt(x) at x = 1e-4 with u = 1: x - h leaves the domain for the central difference
    # (NaN, no warning); the complex step stays exact: c = 1 / (2 sqrt(x)) = 50.
    res = gum(expression("sqrt(x)"), {"x": Normal(1e-4, 1.0)})
    assert res.method == "complex-step"
    assert res.sensitivities["x"] == pytest.approx(50.0, rel=1e-12)


def test_not_differentiable_or_not_finite_is_an_error_naming_the_input():
    # not complex-safe (abs): central differences, and x - h leaves the domain of x**0.5
    with pytest.raises(InputError, match=r"not differentiable .* x") as info:
        gum(expression("x**0.5 * abs(y)"), {"x": Normal(0.0, 1.0), "y": Normal(1, 1)})
    assert info.value.field == "x"
    with pytest.raises(InputError, match="not finite at the input estimates"):
        gum(expression("log(x)"), {"x": Normal(0.0, 1.0)})


# JCGM 100 Table H.2: five simultaneous observations of V (V), I (mA) and φ (rad); the
# same numbers are in suncal's test/test_GUMH2.csv and the R package errors' GUM.H.2.
H2 = np.array(
    [
        [5.007, 19.663, 1.0456],
        [4.994, 19.639, 1.0438],
        [5.005, 19.640, 1.0468],
        [4.990, 19.685, 1.0428],
        [4.999, 19.678, 1.0433],
    ]
)


H2_Y = np.array([127.732, 219.847, 254.260])  # Table H.4: R, X, Z in Ω
H2_U = np.array([0.071, 0.295, 0.236])
H2_R = {(0, 1): -0.588, (0, 2): -0.485, (1, 2): 0.993}


def _rxz(x):
    v, i, phi = x[:, 0], x[:, 1] * 1e-3, x[:, 2]
    z = v / i
    return np.column_stack([z * np.cos(phi), z * np.sin(phi), z])


@pytest.mark.published_data
def test_gum_h2_approach_2_reproduces_the_published_values():
    """H.2.4, approach 2, computed here without mtmc: R, X, Z of each of the five sets,
    their means and the standard deviations of the means give every printed digit."""
    per_set = _rxz(H2)
    np.testing.assert_allclose(per_set.mean(axis=0), H2_Y, atol=0.0005)
    cov2 = np.cov(per_set, rowvar=False, ddof=1) / 5
    np.testing.assert_allclose(np.sqrt(np.diag(cov2)), H2_U, atol=0.0005)
    for (i, j), r in H2_R.items():
        assert abs(cov2[i, j] / math.sqrt(cov2[i, i] * cov2[j, j]) - r) <= 0.0005


def test_gum_h2_resistance_reactance_impedance_with_correlated_inputs():
    """JCGM 100 H.2: R = (V/I) cos φ, X = (V/I) sin φ, Z = V/I from correlated means.
    Published (Table H.4, also asserted by suncal's ``test_GUMH2``): R = 127.732 Ω,
    X = 219.847 Ω, Z = 254.260 Ω; u = 0.071, 0.295, 0.236 Ω; correlation coefficients
    r(R, X) = -0.588, r(R, Z) = -0.485, r(X, Z) = 0.993.

    Approach 2 of H.2.4 reproduces every printed digit (checked on its own, below).
    Approach 1 (H.2.3: the means and the covariance of the means through the
    sensitivities) is what ``gum`` does: checked against the analytic Jacobian written
    out here (to 1e-9), it gives u(X) = 0.29558 Ω, which rounds to 0.296, not 0.295; the
    published u are matched by it within one unit of the last printed digit (as in
    suncal's test) and the correlations to their rounding."""
    mean = H2.mean(axis=0)
    cov = np.cov(H2, rowvar=False, ddof=1) / 5
    g = gum(_rxz, {"x": MultivariateNormal(mean, cov)})
    published_y, published_u, published_r = H2_Y, H2_U, H2_R
    # approach 1 against the analytic Jacobian of (R, X, Z) w.r.t. (V, I in mA, φ)
    v, i_a, phi = mean[0], mean[1] * 1e-3, mean[2]
    jac = np.array(
        [
            [math.cos(phi) / i_a, -v * math.cos(phi) / i_a**2 * 1e-3, -v * math.sin(phi) / i_a],
            [math.sin(phi) / i_a, -v * math.sin(phi) / i_a**2 * 1e-3, v * math.cos(phi) / i_a],
            [1 / i_a, -v / i_a**2 * 1e-3, 0.0],
        ]
    )
    np.testing.assert_allclose(g.cov, jac @ cov @ jac.T, rtol=1e-9)
    np.testing.assert_allclose(g.estimate_vector, published_y, atol=0.0005)
    np.testing.assert_allclose(g.u_vector, published_u, atol=0.001)
    for (i, j), r in published_r.items():
        assert abs(g.cov[i, j] / (g.u_vector[i] * g.u_vector[j]) - r) <= 0.0005


@pytest.mark.parametrize(("a", "method"), [(9.0, "complex-step"), (11.0, "central-difference")])
def test_complex_step_is_kept_while_it_agrees_with_central_differences(a, method):
    # f = x + a x³ at x = 0 with u(x) = 1: the complex step gives c = 1 exactly, the central
    # difference with h = 1e-3 u gives 1 + a h², a gap of a·1e-6 u(y) against the stated
    # agreement of 1e-5 u(y): kept up to a = 10, replaced beyond
    res = gum(lambda x: x + a * x**3, {"x": Normal(0.0, 1.0)})
    assert res.method == method
    c = 1.0 if method == "complex-step" else 1.0 + a * 1e-6
    assert res.sensitivities["x"] == pytest.approx(c, rel=1e-12)


def test_options_are_keyword_only():
    inputs = {"a": Normal(1.0, 0.1)}
    model = expression("2 * a")
    with pytest.raises(TypeError):
        gum(model, inputs, 0.99)  # options are keyword-only
    g = gum(model, inputs, p=0.99)
    assert g.p == 0.99
    mc = monte_carlo(model, inputs, trials=20_000, seed=1)
    with pytest.raises(TypeError):
        validate(g, mc, 0.99)  # options are keyword-only
    v = validate(g, mc, p=0.99, ndig=1)
    assert (v.p, v.ndig, v.passed) == (0.99, 1, True)


def test_output_pdf_is_the_normal_or_the_scaled_t() -> None:
    """The GUM's PDF of the output: the normal density, and for ν = 1 the Cauchy density
    ``1 / (π u (1 + z²))`` (both closed forms; 1e-15 relative, a few roundings)."""
    from mtmc.uncertainty.propagation import output_pdf

    x = np.linspace(-3.0, 5.0, 17)
    z = (x - 1.0) / 0.5
    normal = np.exp(-0.5 * z**2) / (0.5 * np.sqrt(2.0 * np.pi))
    np.testing.assert_allclose(output_pdf(x, 1.0, 0.5), normal, rtol=1e-14)
    cauchy = 1.0 / (np.pi * 0.5 * (1.0 + z**2))
    np.testing.assert_allclose(output_pdf(x, 1.0, 0.5, 1.0), cauchy, rtol=1e-14)
