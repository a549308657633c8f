"""Type A evaluation and degrees of freedom on any input (JCGM 100 §4.2, G.4; JCGM 101 §6.4.9).

References: s/√n, ν = n - 1 recomputed with NumPy and SciPy (``scipy.stats.sem``); the
Monte Carlo standard deviation of the t against s/√n·√(ν/(ν - 2)) (JCGM 101 §6.4.9.3);
draws against ``scipy.stats.t`` (Kolmogorov–Smirnov); JCGM 100 H.1 (the end gauge: u_c =
32 nm, ν_eff = 16, U95 = 67 nm, U99 = 93 nm) with its Type A input in the pooled form of
H.1.3.2 and its Type B inputs given by their relative uncertainties (G.4.2); the
Welch–Satterthwaite formula written out by hand.
"""

from __future__ import annotations

import itertools
import math
import warnings
from fractions import Fraction

import numpy as np
import pytest
from scipy import special, stats

from mtmc import (
    Arcsine,
    Constant,
    DistributionError,
    MultivariateNormal,
    Normal,
    StudentT,
    TypeA,
    Uniform,
    WithDof,
    expression,
    gum,
    monte_carlo,
    parse_distribution,
    type_a,
    with_dof,
)
from mtmc.uncertainty import (
    AutocorrelationWarning,
    autocorrelation_limit,
    dof_from_relative_uncertainty,
    lag1_autocorrelation,
    welch_satterthwaite,
)

OBS = [10.012, 10.007, 10.015, 10.009, 10.011, 10.004, 10.013, 10.010, 10.008, 10.014]


def _r1_by_hand(x):
    """Lag-1 autocorrelation written out with plain floats (Box, Jenkins and Reinsel)."""
    n = len(x)
    m = sum(x) / n
    num = sum((x[i] - m) * (x[i + 1] - m) for i in range(n - 1))
    den = sum((v - m) ** 2 for v in x)
    return num / den


# --------------------------------------------------------------------------- closed forms
def test_type_a_u_and_dof_against_numpy_and_scipy():
    x = type_a(OBS)
    a = np.asarray(OBS)
    # the same sums in another order: agreement to a few units of the last place
    assert x.n == 10
    assert x.mean == pytest.approx(float(np.mean(a)), rel=1e-15)
    assert x.s == pytest.approx(float(np.std(a, ddof=1)), rel=1e-14)
    assert x.u == pytest.approx(float(stats.sem(a)), rel=1e-14)
    assert x.dof == 9.0
    assert x.r1 == pytest.approx(_r1_by_hand(OBS), rel=1e-12, abs=1e-15)
    # the t PDF's own standard deviation (JCGM 101 §6.4.9.3) and the GUM's u differ
    assert x.std == pytest.approx(x.u * math.sqrt(9 / 7), rel=1e-15)
    assert x.std == pytest.approx(float(stats.t(9, scale=x.u).std()), rel=1e-14)


def test_type_a_gum_takes_s_over_root_n_with_n_minus_1():
    """JCGM 100 §4.2.3, G.3.3: u = s/√n, ν = n - 1, whatever the t's own variance."""
    a = np.asarray(OBS)
    r = gum(expression("x"), {"x": type_a(OBS)})
    assert r.estimate == pytest.approx(float(a.mean()), rel=1e-15)
    assert r.u == pytest.approx(float(stats.sem(a)), rel=1e-14)
    assert r.dof == pytest.approx(9.0, rel=1e-14)  # W-S of one input: its own ν
    assert r.budget[0].dof == 9.0


@pytest.mark.parametrize("obs", [[1.0, 1.2], [1.0, 1.2, 1.1]])
def test_small_series_t_has_no_std_but_the_gum_u_is_s_over_root_n(obs):
    """ν = 1, 2: the t of JCGM 101 has no standard deviation; the GUM still takes s/√n."""
    x = type_a(obs)
    assert x.std == math.inf
    assert x.mean == pytest.approx(float(np.mean(obs)), rel=1e-15)
    r = gum(expression("2 * x"), {"x": x})
    assert r.u == pytest.approx(2 * float(stats.sem(obs)), rel=1e-14)
    assert r.dof == pytest.approx(len(obs) - 1, rel=1e-14)
    # k from t_95(ν): 12.706 for ν = 1, 4.303 for ν = 2 (JCGM 100 Table G.2)
    assert round(r.coverage_factor(), 2) == {1: 12.71, 2: 4.30}[len(obs) - 1]


def test_pooled_form_jcgm100_h132():
    """JCGM 100 H.1.3.2: d̄ of 5 readings with a pooled s_p = 13 nm of ν = 24 from 25
    earlier ones: u(d̄) = 13/√5 = 5.8 nm, ν = 24 (only the number of readings enters)."""
    x = type_a([205.0, 210.0, 215.0, 220.0, 225.0], pooled_s=13, pooled_dof=24)
    assert x.mean == 215.0
    assert x.u == pytest.approx(13 / math.sqrt(5), rel=1e-15)
    assert round(x.u, 1) == 5.8
    assert x.dof == 24.0
    assert x.s == pytest.approx(float(np.std([205, 210, 215, 220, 225], ddof=1)), rel=1e-15)
    one = type_a([3.0], pooled_s=0.5, pooled_dof=19)  # one reading is enough with s_p
    assert (one.u, one.dof, math.isnan(one.s)) == (0.5, 19.0, True)


# --------------------------------------------------------------------------- Monte Carlo
def test_monte_carlo_draws_the_t_of_jcgm101_6_4_9():
    x = type_a(OBS)
    mc = monte_carlo(expression("x"), {"x": x}, trials=200_000, seed=11)
    # the same seeded draws as StudentT(ν, x̄, s/√n): bit for bit
    ref = monte_carlo(expression("x"), {"x": StudentT(9, x.mean, x.u)}, trials=200_000, seed=11)
    assert np.array_equal(np.asarray(mc.samples), np.asarray(ref.samples))
    # standard deviation s/√n·√(ν/(ν - 2)): 5 standard errors of a sample standard
    # deviation, σ√((κ - 1)/(4M)) with the t's kurtosis κ = 3 + 6/(ν - 4) = 4.2
    sigma = x.u * math.sqrt(9 / 7)
    se = sigma * math.sqrt((3 + 6 / 5 - 1) / (4 * 200_000))
    assert abs(mc.u - sigma) < 5 * se
    assert abs(mc.estimate - x.mean) < 5 * sigma / math.sqrt(200_000)
    # the shape: Kolmogorov–Smirnov against scipy's t (p > 10⁻³)
    draws = x.sample(np.random.default_rng(5), 100_000)
    assert stats.kstest(draws, stats.t(9, loc=x.mean, scale=x.u).cdf).pvalue > 1e-3


def test_normal_with_dof_is_the_same_input_as_type_a():
    """normal(x̄, s/√n, dof = n - 1) and type_a: the same GUM line, the same draws."""
    x = type_a(OBS)
    d = with_dof(Normal(x.mean, x.u), 9)
    rng_a, rng_b = np.random.default_rng(3), np.random.default_rng(3)
    assert np.array_equal(x.sample(rng_a, 1000), d.sample(rng_b, 1000))
    u = np.linspace(0.01, 0.99, 7)
    assert np.array_equal(x.ppf(u), d.ppf(u))
    ga, gb = gum(expression("x"), {"x": x}), gum(expression("x"), {"x": d})
    assert (ga.u, ga.dof) == (gb.u, gb.dof)


def test_uncertain_scale_of_a_rectangular_pdf():
    """Uniform(-1, 1) with ν = 10: ξ = X √(ν/W); E[ξ²] = E[X²] ν/(ν - 2) (W ~ χ²_ν)."""
    d = parse_distribution("uniform(-1, 1, dof=10)")
    assert d.std == pytest.approx(math.sqrt(1 / 3) * math.sqrt(10 / 8), rel=1e-15)
    m = 200_000
    mc = monte_carlo(expression("x"), {"x": d}, trials=m, seed=2)
    # kurtosis of the mixture: E[X⁴]E[F²]/(E[X²]E[F])² = 1.8 (ν - 2)/(ν - 4) = 2.4;
    # 5 standard errors of a sample standard deviation, σ√((κ - 1)/(4M))
    se = d.std * math.sqrt((2.4 - 1) / (4 * m))
    assert abs(mc.u - d.std) < 5 * se
    # its quasi-random map: the base from the first coordinate, W from the second through
    # the χ²_ν quantile (scipy.stats.chi2), to rounding
    pts = np.array([[0.1, 0.3], [0.75, 0.9], [0.5, 0.02]])
    want = (-1 + 2 * pts[:, 0]) * np.sqrt(10 / stats.chi2.ppf(pts[:, 1], 10))
    assert d.uniform_dims == 2
    assert np.allclose(d.from_uniform(pts), want, rtol=1e-12, atol=0)
    # the GUM takes the rectangle's u = 1/√3 and ν = 10 (JCGM 100 G.4.2)
    r = gum(expression("x"), {"x": d})
    assert (r.u, r.dof) == (pytest.approx(1 / math.sqrt(3), rel=1e-15), pytest.approx(10.0))


def test_vector_base_draws_one_scale_per_trial():
    """A bivariate normal with ν = 6: the multivariate t, covariance V ν/(ν - 2)."""
    v = np.array([[4.0, 1.0], [1.0, 1.0]])
    d = with_dof(MultivariateNormal([0.0, 1.0], v), 6)
    x = d.sample(np.random.default_rng(9), 200_000)
    cov = np.cov(x.T)
    # the (0, 0) entry: 5 standard errors of a sample variance √((κ - 1)/M)·σ², with the
    # marginal t_6 kurtosis κ = 3 + 6/(6 - 4) = 6
    assert abs(cov[0, 0] - 4 * 1.5) < 5 * 6.0 * math.sqrt(5 / 200_000)
    # the (0, 1) entry, 1.5: 5 standard errors √((E[X²Y²] - c²)/M), E[X²Y²] = E[F²](V00 V11 +
    # 2 V01²) = 27 for the multivariate t (F = ν/W, E[F²] = ν²/((ν - 2)(ν - 4)) = 4.5); one W
    # per trial is what makes the entries scale together
    assert abs(cov[0, 1] - 1.5) < 5 * math.sqrt((27 - 1.5**2) / 200_000)
    g = gum(lambda a: a[:, 0] + a[:, 1], {"a": d})
    assert g.u == pytest.approx(math.sqrt(4 + 1 + 2), rel=1e-9)  # u² = 1ᵀ V 1
    assert g.dof == pytest.approx(6.0)


# --------------------------------------------------------------------------- ν of Type B
def test_relative_uncertainty_of_u_gives_nu_jcgm100_g42():
    """JCGM 100 G.4.2, eq. (G.3): ν = ½ (Δu/u)⁻²: 25 % → 8, 10 % → 50, 50 % → 2."""
    assert dof_from_relative_uncertainty(0.25) == 8.0
    assert dof_from_relative_uncertainty(0.10) == pytest.approx(50.0, rel=1e-15)
    assert dof_from_relative_uncertainty(0.5) == 2.0
    assert parse_distribution("triangular(-1, 1, u_rel_u=0.25)").dof == 8.0


def test_welch_satterthwaite_uses_the_nu_of_type_b_inputs():
    """ν_eff = u⁴(y)/Σ c_i⁴u_i⁴/ν_i (JCGM 100 eq. (G.2b)), written out by hand."""
    inputs = {
        "a": parse_distribution("uniform(-1, 1, u_rel_u=0.25)"),  # u = 1/√3, ν = 8
        "b": parse_distribution("normal(0, 0.5, dof=4)"),
        "c": parse_distribution("arcsine(-0.2, 0.2)"),  # ν = ∞
        "d": type_a([1.0, 1.4, 1.1, 1.3]),  # u = s/2, ν = 3
    }
    r = gum(expression("a + 3 * b - c + 2 * d"), inputs)
    s_d = float(np.std([1.0, 1.4, 1.1, 1.3], ddof=1))
    parts = np.array([1 / math.sqrt(3), 3 * 0.5, 0.4 / math.sqrt(8), 2 * s_d / 2])
    nus = [8.0, 4.0, math.inf, 3.0]
    hand = float(np.sum(parts**2)) ** 2 / sum(p**4 / n for p, n in zip(parts, nus, strict=True))
    assert r.u == pytest.approx(math.sqrt(float(np.sum(parts**2))), rel=1e-12)
    assert r.dof == pytest.approx(hand, rel=1e-12)
    assert [e.dof for e in r.budget] == nus
    assert welch_satterthwaite(parts**2, nus) == pytest.approx(hand, rel=1e-14)


def test_jcgm100_h1_end_gauge_with_type_a_and_relative_uncertainties():
    """JCGM 100 H.1 with its inputs as the GUM states them: u(d̄) from 5 readings with the
    pooled s_p = 13 nm (ν = 24, H.1.3.2), u(d2) reliable to 25 % (ν = 8), u(δα) to 10 %
    (ν = 50), u(δθ) to 50 % (ν = 2) (H.1.3.5, H.1.3.6), l_s with ν = 18 and d1 with ν = 5
    from their sources. Published (H.1.5, H.1.6): u_c = 32 nm, ν_eff = 16, U95 = 67 nm
    (k = 2.12), U99 = 93 nm (k = 2.92), l = 50.000 838 mm."""
    inputs = {
        "l_s": parse_distribution("normal(50000623.6, 25, dof=18)"),
        "d_bar": type_a([205.0, 210.0, 215.0, 220.0, 225.0], pooled_s=13, pooled_dof=24),
        "d1": parse_distribution("normal(0, 3.9, dof=5)"),
        "d2": parse_distribution("normal(0, 6.7, u_rel_u=0.25)"),
        "alpha_s": parse_distribution("uniform(9.5e-6, 13.5e-6)"),
        "theta_bar": parse_distribution("normal(-0.1, 0.2)"),
        "Delta": Arcsine(-0.5, 0.5),
        "dalpha": parse_distribution("normal(0, 0.58e-6, u_rel_u=0.1)"),
        "dtheta": parse_distribution("normal(0, 0.029, u_rel_u=0.5)"),
    }
    model = expression(
        "l_s + d_bar + d1 + d2 - l_s * (alpha_s * dtheta + dalpha * (theta_bar + Delta))"
    )
    r = gum(model, inputs)
    assert math.floor(r.estimate) == 50_000_838  # "50.000 838 mm"
    assert round(r.u) == 32
    assert math.floor(r.dof) == 16
    assert round(r.coverage_factor(0.95), 2) == 2.12
    assert round(r.expanded_uncertainty(0.95)) == 67
    assert round(r.coverage_factor(0.99), 2) == 2.92
    assert round(r.expanded_uncertainty(0.99)) == 93
    # eq. (G.2b) by hand from the contributions c_i u(x_i) of Table H.1 (u(d̄) unrounded)
    c_dalpha, c_dtheta = 50_000_623.6 * 0.1, 50_000_623.6 * 11.5e-6
    contrib = np.array([25.0, 13 / math.sqrt(5), 3.9, 6.7, c_dalpha * 0.58e-6, c_dtheta * 0.029])
    nu = np.array([18, 24, 5, 8, 50, 2.0])
    hand = (contrib**2).sum() ** 2 / np.sum(contrib**4 / nu)
    assert r.dof == pytest.approx(hand, rel=1e-9)  # sensitivities by complex step: exact


# --------------------------------------------------------------------------- text and equality
@pytest.mark.parametrize(
    "text",
    [
        "normal(0, 1, dof=8)",
        "uniform(-1, 1, u_rel_u=0.25)",
        "ctrap(-1, 1, 0.2, dof=3.5)",
        "iid(normal(0, 1, dof=8), 3)",
        "mvnormal([0, 1], [[1, 0], [0, 2]], dof=5)",
        "type_a([10.1, 10.3, 10.2])",
        "type_a([1, 2], pooled_s=0.25, pooled_dof=19)",
    ],
)
def test_text_round_trip(text):
    d = parse_distribution(text)
    assert str(d) == text
    assert parse_distribution(str(d)) == d
    assert hash(parse_distribution(text)) == hash(d)


def test_keywords_apply_to_the_distribution_they_close():
    assert isinstance(parse_distribution("iid(normal(0, 1), 2, dof=4)"), WithDof)
    inner = parse_distribution("iid(normal(0, 1, dof=4), 2)")
    assert not isinstance(inner, WithDof)
    assert inner.dof == 4.0
    g = gum(lambda v: v[:, 0] - v[:, 1], {"v": inner})
    assert g.u == pytest.approx(math.sqrt(2), rel=1e-12)  # each component u = 1 (stated)
    assert isinstance(type_a([1, 2]), TypeA)


# --------------------------------------------------------------------------- warnings
def test_autocorrelated_observations_warn():
    """A drift (1, 2, ..., 16): r1 = 0.8125 > 2/√16 = 0.5 (JCGM 100 §4.2.7)."""
    drift = [float(i) for i in range(1, 17)]
    with pytest.warns(AutocorrelationWarning, match=r"r1 = 0\.812.*±0\.5.*§4\.2\.7"):
        x = type_a(drift)
    assert x.r1 == pytest.approx(_r1_by_hand(drift), rel=1e-14)
    assert x.autocorrelated
    assert "understates" in (x.warning or "")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        quiet = type_a(OBS)  # |r1| = 0.56 < 2/√10 = 0.63
    assert quiet.warning is None
    assert abs(quiet.r1) < autocorrelation_limit(10)
    assert lag1_autocorrelation([1, 2, 3, 4]) == pytest.approx(_r1_by_hand([1, 2, 3, 4]))


def test_the_2_over_root_n_limit_has_its_nominal_level():
    """Independent normal series: |r1| > 2/√n about as often as P(|Z| > 2) = 4.55 % (the
    large-sample law of r1, Bartlett 1946), never more than that plus 5 binomial standard
    errors; for n = 200 not less than 3.5 % (E[r1] = -1/n and Var r1 < 1/n make the test
    slightly conservative at finite n)."""
    rng = np.random.default_rng(2024)
    trials = 20_000
    x = rng.standard_normal((trials, 200))
    d = x - x.mean(axis=1, keepdims=True)
    r1 = np.sum(d[:, :-1] * d[:, 1:], axis=1) / np.sum(d * d, axis=1)
    rate = float(np.mean(np.abs(r1) > autocorrelation_limit(200)))
    p = 2 * special.ndtr(-2.0)
    assert 0.035 < rate < p + 5 * math.sqrt(p * (1 - p) / trials)
    assert lag1_autocorrelation(x[0]) == pytest.approx(float(r1[0]), rel=1e-12)


# --------------------------------------------------------------------------- errors
@pytest.mark.parametrize(
    ("call", "field", "words"),
    [
        (lambda: type_a([1.0]), "observations", "at least 2 observations"),
        (lambda: type_a([]), "observations", "at least 2 observations"),
        (lambda: type_a([1.0, math.nan, 2.0]), "observations", "observation 2 is nan"),
        (lambda: type_a([1.0, math.inf]), "observations", "observation 2 is inf"),
        (lambda: type_a([[1.0, 2.0]]), "observations", "flat list"),
        (lambda: type_a(["a", "b"]), "observations", "list of numbers"),
        (lambda: type_a([2.0, 2.0, 2.0]), "observations", "all equal"),
        (lambda: type_a([1.0, 2.0], pooled_s=0.1), "pooled_dof", "pooled_dof is missing"),
        (lambda: type_a([1.0, 2.0], pooled_dof=3), "pooled_s", "pooled_s is missing"),
        (lambda: type_a([1.0, 2.0], pooled_s=-1, pooled_dof=3), "pooled_s", "> 0"),
        (lambda: type_a([1.0, 2.0], pooled_s=1, pooled_dof=0), "pooled_dof", "> 0"),
        (lambda: with_dof(Normal(0, 1)), "dof", "got neither"),
        (lambda: with_dof(Normal(0, 1), 3, u_rel_u=0.2), "dof", "got both"),
        (lambda: with_dof(Normal(0, 1), 0), "dof", "> 0"),
        (lambda: with_dof(Normal(0, 1), math.inf), "dof", "finite"),
        (lambda: with_dof(Normal(0, 1), u_rel_u=-0.1), "u_rel_u", "> 0"),
        (lambda: with_dof(StudentT(3), 4), "dof", "already has ν = 3"),
        (lambda: with_dof(type_a([1, 2]), 4), "dof", "already has ν = 1"),
        (lambda: with_dof(with_dof(Normal(0, 1), 3), 4), "dof", "already has ν = 3"),
        (lambda: with_dof(Constant(1.0), 4), "dof", "zero standard deviation"),
        (lambda: with_dof(Normal(0, 0), 4), "dof", "zero standard deviation"),
        (lambda: WithDof(Normal(0, 1), 3, u_rel_u=0.25), "u_rel_u", "gives ν = ½ u_rel_u⁻² = 8"),
    ],
)
def test_errors_name_the_field(call, field, words):
    with pytest.raises(DistributionError) as info:
        call()
    assert info.value.field == field
    assert words in info.value.message


@pytest.mark.parametrize(
    ("text", "column", "words"),
    [
        ("normal(0, 1, dof=0)", 1, "expected dof to be a finite number > 0, got 0.0"),
        ("  uniform(-1, 1, dof=-2)", 3, "expected dof to be a finite number > 0"),
        ("normal(0, 1, dof=3, u_rel_u=0.5)", 1, "got both"),
        ("t(3, dof=2)", 1, "t(3) already has ν = 3 degrees of freedom"),
        ("normal(0, 1, nu=3)", 1, "expected one of mean, std, dof, u_rel_u"),
        ("type_a([1])", 1, "at least 2 observations"),
        ("type_a([1, 2], dof=4)", 1, "already has ν = 1"),
        ("iid(normal(0, 1, dof=-1), 2)", 5, "expected dof to be a finite number > 0"),
    ],
)
def test_text_errors_name_the_column(text, column, words):
    with pytest.raises(DistributionError) as info:
        parse_distribution(text, file="s.toml", line=7, field="inputs.x")
    err = info.value
    assert (err.file, err.line, err.column, err.field) == ("s.toml", 7, column, "inputs.x")
    assert words in err.message
    assert repr(text.strip()) in err.message


def test_uniform_with_dof_has_no_single_quantile_function():
    with pytest.raises(DistributionError, match="no quantile function"):
        with_dof(Uniform(0, 1), 5).ppf(0.5)


def test_docs_worked_example(capsys):
    """docs/type-a.md: its code, run as is, prints the output the page shows."""
    import re
    from pathlib import Path

    page = (Path(__file__).resolve().parents[2] / "docs" / "type-a.md").read_text(encoding="utf-8")
    section = page.split("## Worked example", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    shown = re.search(r"```text\n(.*?)```", section, re.S).group(1)
    exec(compile(code, "type-a.md", "exec"), {"__name__": "docs"})
    assert capsys.readouterr().out == shown


def test_same_bits_whatever_the_blocks_and_workers_and_pickled():
    """One seed, one set of numbers: evaluation blocks and threads change nothing (our own
    seeded draws: bit for bit); the inputs cross a process boundary intact."""
    import pickle

    model = expression("a + b + c")
    inputs = {
        "a": type_a([1.0, 1.3, 1.1]),
        "b": parse_distribution("uniform(-1, 1, dof=5)"),
        "c": parse_distribution("normal(0, 1, u_rel_u=0.3)"),
    }
    one = monte_carlo(model, inputs, trials=40_000, seed=3)
    other = monte_carlo(model, inputs, trials=40_000, seed=3, block_size=777)
    threads = monte_carlo(model, inputs, trials=40_000, seed=3, workers=2, block_size=5000)
    assert np.array_equal(np.asarray(one.samples), np.asarray(other.samples))
    assert np.array_equal(np.asarray(one.samples), np.asarray(threads.samples))
    for d in inputs.values():
        back = pickle.loads(pickle.dumps(d))
        assert back == d
        assert np.array_equal(
            back.sample(np.random.default_rng(1), 50), d.sample(np.random.default_rng(1), 50)
        )


def test_quasi_random_sampling_takes_the_extra_coordinate():
    """sampling="sobol": a Type A input and a normal with ν take one coordinate of the unit
    cube (the t quantile), a rectangular with ν two (its own, then χ²_ν); the Monte Carlo
    values against the same Sobol points mapped by hand with scipy.stats quantiles."""
    from mtmc.uncertainty.sampling import sobol_layout, sobol_points

    inputs = {
        "a": type_a([1.0, 1.3, 1.1]),
        "b": parse_distribution("uniform(-1, 1, dof=5)"),
        "c": parse_distribution("normal(0, 1, dof=6)"),
    }
    layout = sobol_layout(inputs)
    assert {k: n for k, (_, n) in layout.items()} == {"a": 1, "b": 2, "c": 1}
    mc = monte_carlo(expression("a + b + c"), inputs, trials=1024, seed=4, sampling="sobol")
    u = sobol_points(4, 0, 4, 1024)
    a = inputs["a"]
    by_hand = a.mean + a.u * stats.t.ppf(u[:, layout["a"][0]], 2)
    fb = layout["b"][0]
    by_hand = by_hand + (-1 + 2 * u[:, fb]) * np.sqrt(5 / stats.chi2.ppf(u[:, fb + 1], 5))
    by_hand = by_hand + stats.t.ppf(u[:, layout["c"][0]], 6)
    # scipy's quantile functions against scipy.special's: agreement to rounding
    assert np.allclose(np.asarray(mc.samples), by_hand, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize(
    "obs", [[1e-200, 2e-200, 3e-200, 1e-200], [1e300, 1.1e300, -1.2e300, 1e300], [1.0, 1.1, 1.3]]
)
def test_s_and_r1_of_tiny_and_huge_observations_equal_exact_arithmetic(obs, recwarn):
    d = type_a(obs)
    x = [Fraction(v) for v in obs]  # exact: no square under- or overflows
    mean = sum(x) / len(x)
    dev = [v - mean for v in x]
    k = math.frexp(max(abs(v) for v in obs))[1]  # s = 2^k √(var / 4^k), var exact
    s = math.ldexp(math.sqrt(sum(v * v for v in dev) / (len(x) - 1) / Fraction(4) ** k), k)
    r1 = float(sum(a * b for a, b in itertools.pairwise(dev)) / sum(v * v for v in dev))
    # a few ulp: the float sums round at each of n ≤ 4 steps where the Fractions do not
    assert d.s == pytest.approx(s, rel=1e-14)
    assert d.r1 == pytest.approx(r1, rel=1e-13, abs=1e-15)
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


def test_observations_equal_or_below_the_doubles_name_the_value_as_a_number():
    with pytest.raises(DistributionError) as info:
        type_a([5e-324, 5e-324, 5e-324])
    assert "all equal (5e-324)" in info.value.message  # was "np.float64(5e-324)"
    with pytest.raises(DistributionError) as info:
        type_a([5e-324, 1e-323, 5e-324])  # not equal: s underflows
    assert "below the smallest normal double" in info.value.message


def test_a_relative_uncertainty_whose_square_underflows_is_refused():
    assert dof_from_relative_uncertainty(1.5e-154) == pytest.approx(0.5 / 1.5e-154**2)
    with pytest.raises(DistributionError) as info:  # was ZeroDivisionError
        parse_distribution("normal(0, 1, u_rel_u=1e-200)")
    assert "expected u_rel_u >= 1.5e-154, got 1e-200" in info.value.message
