"""Correlated inputs: the copulas of the Monte Carlo and JCGM 100 eq. (13) of the GUM.

Each test compares with an independent reference: the closed form of the variance of a
sum of correlated normals, the rank correlations of the Gaussian and t copulas (Kendall's
τ = (2/π) asin r, Spearman's ρ_s = (6/π) asin(r/2)) computed by SciPy from the draws, the
joint exceedance probability of a t copula from SciPy's multivariate t, and hashes of
runs without correlation taken before correlation existed. Our own seeded draws are
compared bit for bit.
"""

from __future__ import annotations

import hashlib
import math

import numpy as np
import pytest
from scipy import stats

from mtmc.errors import InputError
from mtmc.uncertainty import (
    Constant,
    Copula,
    Correlation,
    Exponential,
    MultivariateNormal,
    Normal,
    Triangular,
    Uniform,
    expression,
    gum,
    monte_carlo,
    realised_correlation,
)
from mtmc.uncertainty.copula import MIN_T_DOF


def _sum(a, b):
    return a + b


def _both(a, b):
    return {"a": a, "b": b}


def _abc(a, b, c):
    return a * b + c


def _draws(inputs, corr, copula, trials, seed, **kw):
    """The drawn a and b of a run (the model returns them)."""
    r = monte_carlo(_both, inputs, trials, seed, correlation=corr, copula=copula, keep=True, **kw)
    return r["a"].samples, r["b"].samples


# ----------------------------------------------------------------- closed forms


@pytest.mark.parametrize("r", [0.6, -0.8])
@pytest.mark.parametrize("sampling", ["random", "sobol"])
def test_sum_of_correlated_normals_by_monte_carlo_and_gum(r, sampling):
    u1, u2 = 1.0, 2.0
    inputs = {"a": Normal(1.0, u1), "b": Normal(-2.0, u2)}
    exact = math.sqrt(u1**2 + u2**2 + 2 * r * u1 * u2)  # JCGM 100 eq. (13), Y = X1 + X2
    g = gum(expression("a + b"), inputs, correlation={("a", "b"): r})
    # linear model, complex-step sensitivities exact: u agrees to rounding
    assert g.u == pytest.approx(exact, rel=1e-14)
    m = 2**17
    mc = monte_carlo(_sum, inputs, m, 11, correlation={("a", "b"): r}, sampling=sampling)
    # Y is normal: the standard error of s is u/sqrt(2(M-1)); 4 of them
    assert mc.u == pytest.approx(exact, rel=4 / math.sqrt(2 * (m - 1)))
    assert mc.estimate == pytest.approx(-1.0, abs=4 * exact / math.sqrt(m))


def test_gum_matrix_and_pairs_agree_and_full_correlation_adds_uncertainties():
    inputs = {"a": Normal(0, 0.3), "b": Uniform(-1, 1), "c": Triangular(0, 2, 1)}
    model = expression("2*a - b + 3*c")
    pairs = {("a", "b"): 0.5, ("c", "a"): -0.2}
    matrix = Correlation.from_matrix(
        [[1, -0.2, 0.0], [-0.2, 1, 0.5], [0.0, 0.5, 1]], ["c", "a", "b"]
    )
    u = np.array([0.3, 1 / math.sqrt(3), math.sqrt(1 / 6)])
    c = np.array([2.0, -1.0, 3.0])
    rr = np.array([[1, 0.5, -0.2], [0.5, 1, 0], [-0.2, 0, 1]])
    exact = math.sqrt(c @ (np.outer(u, u) * rr) @ c)  # Σ c_i c_j u_i u_j r_ij
    assert gum(model, inputs, correlation=pairs).u == pytest.approx(exact, rel=1e-14)
    assert gum(model, inputs, correlation=matrix).u == pytest.approx(exact, rel=1e-14)
    # r = 1 (a singular, PSD matrix): u(a + b) = u(a) + u(b)
    full = gum(
        expression("a + b"), {"a": Normal(0, 1), "b": Normal(0, 2)}, correlation={("a", "b"): 1}
    )
    assert full.u == pytest.approx(3.0, rel=1e-14)


def test_full_correlation_draws_equal_values():
    inputs = {"a": Normal(0, 1), "b": Normal(5, 2)}
    a, b = _draws(inputs, {("a", "b"): 1.0}, "gaussian", 1000, 3)
    # one normal for both; the eigenvector factor is exact to a few ulp
    np.testing.assert_allclose(b, 5 + 2 * a, rtol=0, atol=1e-12)
    a, b = _draws(inputs, {("a", "b"): -1.0}, "gaussian", 1000, 3)
    np.testing.assert_allclose(b, 5 - 2 * a, rtol=0, atol=1e-12)


# ----------------------------------------------------------------- rank correlations


@pytest.mark.parametrize("r", [0.7, -0.4])
def test_gaussian_copula_of_uniforms_has_spearman_rho_of_asin(r):
    m = 100_000
    inputs = {"a": Uniform(0, 1), "b": Uniform(-3, 5)}
    a, b = _draws(inputs, {("a", "b"): r}, "gaussian", m, 21)
    expected = 6 / math.pi * math.asin(r / 2)
    rho = stats.spearmanr(a, b).statistic
    # the standard error of ρ_s is at most 1/sqrt(M - 1) (its value under independence)
    assert rho == pytest.approx(expected, abs=4 / math.sqrt(m - 1))
    # for uniform marginals the product-moment correlation is Spearman's
    assert np.corrcoef(a, b)[0, 1] == pytest.approx(expected, abs=4 / math.sqrt(m - 1))
    got = realised_correlation(inputs, m, 21, {("a", "b"): r})
    # the same draws as the run, reduced by seed-block moments: equal to rounding
    assert got[0, 1] == pytest.approx(np.corrcoef(a, b)[0, 1], abs=1e-12)


@pytest.mark.parametrize("sampling", ["random", "sobol"])
@pytest.mark.parametrize("copula", ["gaussian", ("t", 3)])
def test_kendall_tau_is_two_over_pi_asin_r_for_both_copulas(copula, sampling):
    m = 16_384  # one seed block: a whole Sobol point set
    r = 0.5
    inputs = {"a": Exponential(2.0), "b": Triangular(-1, 4, 0)}
    a, b = _draws(inputs, {("a", "b"): r}, copula, m, 5, sampling=sampling)
    tau = stats.kendalltau(a, b).statistic
    # standard error of τ is at most sqrt(2(2M + 5)/(9M(M - 1))) ≈ 0.0052 (its value
    # under independence; quasi-random points only make it smaller)
    se = math.sqrt(2 * (2 * m + 5) / (9 * m * (m - 1)))
    assert tau == pytest.approx(2 / math.pi * math.asin(r), abs=4 * se)


def test_t_copula_joint_tail_exceedance_matches_multivariate_t():
    # r = 0: uncorrelated, but the t copula still makes joint extremes more likely
    nu, q, m = 3.0, 0.95, 200_000
    inputs = {"a": Uniform(0, 1), "b": Uniform(0, 1)}
    corr = Correlation.from_matrix(np.eye(2), ["a", "b"])
    a, b = _draws(inputs, corr, ("t", nu), m, 8)
    got = float(np.mean((a > q) & (b > q)))
    tq = stats.t.ppf(q, nu)
    expected = stats.multivariate_t(loc=[0, 0], shape=np.eye(2), df=nu).cdf(
        [-tq, -tq], random_state=1
    )
    # binomial standard error of the proportion, 4 of them (SciPy's integration: ~1e-5)
    se = math.sqrt(expected * (1 - expected) / m)
    assert got == pytest.approx(expected, abs=4 * se)
    assert expected > 1.5 * (1 - q) ** 2  # far from the independent (1 - q)² = 0.0025
    # the Gaussian copula with r = 0 is independence: the same numbers as no correlation
    a0, b0 = _draws(inputs, corr, "gaussian", 4096, 8)
    a1, b1 = _draws(inputs, None, "gaussian", 4096, 8)
    assert np.array_equal(a0, a1)
    assert np.array_equal(b0, b1)


# ----------------------------------------------------------------- reproducibility

INPUTS3 = {"a": Normal(1.0, 0.2), "b": Uniform(-1, 2), "c": Triangular(0, 3, 1)}
CORR3 = {("a", "b"): 0.5, ("b", "c"): -0.3}


def _hash(x):
    return hashlib.sha256(np.ascontiguousarray(x).tobytes()).hexdigest()


# taken from this exact run before correlation was part of the engine
BEFORE = {
    "random": "f6aa107104a6ba0c9bded8cb6e59c24ac050db45ba2f152c5df3288559fb54d7",
    "sobol": "6ff44cda9d64dd7db97e54718d7e71c7caf376acd034b5b35283fc4d6f99c947",
}


@pytest.mark.parametrize("sampling", ["random", "sobol"])
def test_runs_without_correlation_are_unchanged(sampling):
    r = monte_carlo(_abc, INPUTS3, 40000, 12345, block_size=7000, sampling=sampling)
    assert _hash(r.samples) == BEFORE[sampling]
    zero = monte_carlo(
        _abc,
        INPUTS3,
        40000,
        12345,
        block_size=7000,
        sampling=sampling,
        correlation={("a", "c"): 0.0},
    )
    assert _hash(zero.samples) == BEFORE[sampling]


@pytest.mark.parametrize("sampling", ["random", "sobol"])
@pytest.mark.parametrize("copula", ["gaussian", {"kind": "t", "dof": 4}])
def test_same_bits_for_any_block_size_workers_and_order(sampling, copula):
    m = 40_000  # three seed blocks, the last one partial
    ref = monte_carlo(_abc, INPUTS3, m, 9, correlation=CORR3, copula=copula, sampling=sampling)
    for kw in (
        {"block_size": 999},
        {"block_size": 16384},
        {"block_size": 5000, "workers": 2, "executor": "thread"},
        {"block_size": 15000, "workers": 2, "executor": "process"},
    ):
        got = monte_carlo(
            _abc, INPUTS3, m, 9, correlation=CORR3, copula=copula, sampling=sampling, **kw
        )
        assert np.array_equal(got.samples, ref.samples), kw
    # the inputs in another order, the matrix in another order: the same numbers
    matrix = Correlation.from_matrix([[1, -0.3, 0], [-0.3, 1, 0.5], [0, 0.5, 1]], ["c", "b", "a"])
    other = monte_carlo(
        _abc,
        dict(reversed(INPUTS3.items())),
        m,
        9,
        correlation=matrix,
        copula=copula,
        sampling=sampling,
    )
    assert np.array_equal(other.samples, ref.samples)
    # and a different run from the independent one
    plain = monte_carlo(_abc, INPUTS3, m, 9, sampling=sampling)
    assert not np.array_equal(plain.samples, ref.samples)


@pytest.mark.parametrize("copula", ["gaussian", ("t", 4)])
def test_inputs_outside_the_group_draw_what_they_draw_alone(copula):
    inputs = {**INPUTS3, "d": Uniform(0, 1)}
    alone = monte_carlo(lambda **x: x["d"], inputs, 20_000, 4)
    joined = monte_carlo(lambda **x: x["d"], inputs, 20_000, 4, correlation=CORR3, copula=copula)
    assert np.array_equal(alone.samples, joined.samples)


def test_first_trials_are_those_of_a_longer_run():
    short = monte_carlo(_abc, INPUTS3, 1000, 2, correlation=CORR3, copula=("t", 5))
    long = monte_carlo(_abc, INPUTS3, 30_000, 2, correlation=CORR3, copula=("t", 5))
    assert np.array_equal(short.samples, long.samples[:1000])


def test_marginals_are_kept_by_the_copula():
    m = 50_000
    inputs = {"a": Triangular(0, 3, 1), "b": Exponential(2.0)}
    a, b = _draws(inputs, {("a", "b"): 0.9}, ("t", 2.5), m, 17)
    # Kolmogorov–Smirnov against each marginal's CDF: the copula changes no marginal
    assert stats.kstest(a, stats.triang(c=1 / 3, loc=0, scale=3).cdf).pvalue > 1e-3
    assert stats.kstest(b, stats.expon(scale=2.0).cdf).pvalue > 1e-3


@pytest.mark.parametrize("sampling", ["random", "sobol"])
@pytest.mark.parametrize("dof", [0.1, 0.3, 1.0, 30.0])
def test_marginals_are_kept_down_to_the_smallest_dof(dof, sampling):
    m = 50_000
    inputs = {"a": Normal(0.0, 1.0), "b": Uniform(-1.0, 1.0)}
    a, b = _draws(inputs, {("a", "b"): 0.5}, ("t", dof), m, 5, sampling=sampling)
    # KS against the input CDFs (at 10⁻⁶ a seeded draw of a kept marginal fails one run in
    # a million; at ν = 10⁻³ the statistic was 0.35, at ν = 0.02 the 0.08 % of trials whose
    # χ² draw underflowed alone gave p = 10⁻³⁵ in 2·10⁵ trials)
    assert stats.kstest(a, stats.norm.cdf).pvalue > 1e-6
    assert stats.kstest(b, stats.uniform(loc=-1.0, scale=2.0).cdf).pvalue > 1e-6
    # and the 0.1 % and 99.9 % quantiles of a, within 5 of their standard errors
    for q in (0.001, 0.999):
        se = math.sqrt(q * (1 - q) / m) / stats.norm.pdf(stats.norm.ppf(q))
        assert abs(np.quantile(a, q) - stats.norm.ppf(q)) < 5 * se


@pytest.mark.parametrize("dof", [1e-3, 0.0999, 1e-300])
def test_a_dof_below_what_the_numerics_carry_is_refused_with_the_limit(dof):
    with pytest.raises(InputError) as info:
        Copula("t", dof)
    assert info.value.field == "copula.dof"
    assert f"expected {MIN_T_DOF:g} <= dof < inf for the t copula" in info.value.message
    assert "underflows" in info.value.message
    assert MIN_T_DOF == 0.1  # the limit the docs state (docs/correlation.md)
    # where W ~ χ²_ν underflows in fewer than one trial in 10^15 (independent: scipy's χ²)
    assert stats.chi2.cdf(np.finfo(np.float64).tiny, MIN_T_DOF) < 1e-15
    assert stats.chi2.cdf(np.finfo(np.float64).tiny, 0.5 * MIN_T_DOF) > 1e-9


# ----------------------------------------------------------------- errors


@pytest.mark.parametrize(
    ("build", "field", "text"),
    [
        (
            lambda: Correlation.from_pairs({("x", "y"): 0.9, ("y", "z"): 0.9, ("x", "z"): -0.9}),
            "correlation",
            "not positive semi-definite",
        ),
        (
            lambda: Correlation.from_matrix([[1, 0.5], [0.4, 1]], ["x", "y"]),
            "correlation[x, y]",
            "symmetric",
        ),
        (
            lambda: Correlation.from_matrix([[1, 0.5], [0.5, 0.9]], ["x", "y"]),
            "correlation[y, y]",
            "1 on the diagonal",
        ),
        (lambda: Correlation.from_pairs({("x", "y"): 1.2}), "correlation[x, y]", r"\[-1, 1\]"),
        (lambda: Correlation.from_pairs({("x", "x"): 0.5}), "correlation[x, x]", "different"),
        (
            lambda: Correlation.from_pairs([("x", "y", 0.1), ("y", "x", 0.2)]),
            "correlation[y, x]",
            "twice",
        ),
        (lambda: Correlation.from_matrix(np.eye(3), ["x", "y"]), "correlation.matrix", "3"),
        (lambda: Copula("t", 0), "copula.dof", "0.1 <= dof"),
        (lambda: Copula("clayton"), "copula", "'gaussian' or 't'"),
    ],
)
def test_bad_correlations_are_refused_with_the_pair(build, field, text):
    with pytest.raises(InputError, match=text) as info:
        build()
    assert info.value.field == field


@pytest.mark.parametrize(
    ("inputs", "corr", "copula", "field", "text"),
    [
        (
            {"a": Normal(0, 1), "b": Normal(0, 1)},
            {("a", "q"): 0.5},
            "gaussian",
            "correlation[q]",
            "not an input",
        ),
        (
            {"a": Normal(0, 1), "b": MultivariateNormal([0, 0], np.eye(2))},
            {("a", "b"): 0.5},
            "gaussian",
            "correlation[b]",
            "vector input",
        ),
        (
            {"a": Normal(0, 1), "b": Constant(2.0)},
            {("a", "b"): 0.5},
            "gaussian",
            "correlation[b]",
            "known exactly",
        ),
        ({"a": Normal(0, 1), "b": Normal(0, 1)}, None, ("t", 4), "copula", "give correlation"),
        (
            {"a": Normal(0, 1), "b": Normal(0, 1)},
            {("a", "b"): 0.5},
            "t",
            "copula",
            "degrees of freedom",
        ),
        (
            {"a": Normal(0, 1), "b": Normal(0, 1)},
            [[1, 0], [0, 1]],
            "gaussian",
            "correlation",
            "from_matrix",
        ),
    ],
)
def test_monte_carlo_and_gum_refuse_a_correlation_that_does_not_fit(
    inputs, corr, copula, field, text
):
    with pytest.raises(InputError, match=text) as info:
        monte_carlo(_sum, inputs, 100, 1, correlation=corr, copula=copula)
    assert info.value.field == field
    if copula == "gaussian":
        with pytest.raises(InputError, match=text):
            gum(_sum, inputs, correlation=corr)


def test_an_input_without_inverse_cdf_is_refused_by_the_copula_not_by_the_gum():
    from mtmc.uncertainty.typea import with_dof

    # a rectangular PDF with 8 degrees of freedom: its draws take two uniform numbers
    inputs = {"a": Normal(0, 1), "b": with_dof(Uniform(0, 1), 8)}
    corr = {("a", "b"): 0.5}
    with pytest.raises(InputError, match="no inverse CDF") as info:
        monte_carlo(_sum, inputs, 100, 1, correlation=corr)
    assert info.value.field == "correlation[b]"
    ub = 1 / math.sqrt(12)  # the rectangle's u, as stated
    exact = math.sqrt(1 + ub**2 + 2 * 0.5 * ub)  # JCGM 100 eq. (13)
    assert gum(expression("a + b"), inputs, correlation=corr).u == pytest.approx(exact, rel=1e-14)
