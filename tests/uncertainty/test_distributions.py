"""Input PDFs (JCGM 101 §6.4): moments, KS tests against scipy.stats, text round trip, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from mtmc.errors import DistributionError
from mtmc.uncertainty.distributions import (
    IID,
    Arcsine,
    Constant,
    CurvilinearTrapezoid,
    Distribution,
    Exponential,
    Gamma,
    MultivariateNormal,
    Normal,
    StudentT,
    Trapezoidal,
    Triangular,
    Uniform,
    as_distribution,
    distribution_names,
    parse_distribution,
    register_distribution,
    standard_normal,
)

M = 200_000


def ctrap_cdf(x, low, high, d):
    """CDF of CTrap(a, b, d), integrated by hand from its PDF (JCGM 101 §6.4.3.2).

    With x0 = (a+b)/2, w = (b-a)/2, t = |x - x0|: g = ln((w+d)/max(t, w-d)) / (4d) for
    t <= w + d. P(|X - x0| <= t) = [(w-d) L0 + (s ln((w+d)/s) + s) |_{w-d}^{t}] / (2d)
    for w-d <= t <= w+d, with L0 = ln((w+d)/(w-d)); = t L0 / (2d) for t < w - d.
    """
    x = np.asarray(x, dtype=float)
    x0, w = 0.5 * (low + high), 0.5 * (high - low)
    t = np.abs(x - x0)
    lo, hi = w - d, w + d
    l0 = math.log(hi / lo)
    tt = np.clip(t, lo, hi)

    def prim(s):
        return s * np.log(hi / s) + s

    inner = np.where(t < lo, t * l0 / (2 * d), (lo * l0 + prim(tt) - prim(lo)) / (2 * d))
    inner = np.where(t >= hi, 1.0, inner)
    return 0.5 + np.sign(x - x0) * 0.5 * inner


# (distribution, scipy CDF or None)
SCALAR_CASES = [
    (Normal(1.0, 2.0), stats.norm(1.0, 2.0).cdf),
    (Uniform(-1.0, 3.0), stats.uniform(-1.0, 4.0).cdf),
    (Triangular(0.0, 3.0), stats.triang(0.5, 0.0, 3.0).cdf),
    (Triangular(0.0, 3.0, 0.5), stats.triang(0.5 / 3.0, 0.0, 3.0).cdf),
    (Trapezoidal(-2.0, 2.0, 0.4), stats.trapezoid(0.3, 0.7, -2.0, 4.0).cdf),
    (CurvilinearTrapezoid(-1.0, 1.0, 0.3), lambda x: ctrap_cdf(x, -1.0, 1.0, 0.3)),
    (Arcsine(-1.0, 2.0), stats.arcsine(-1.0, 3.0).cdf),
    (StudentT(5.0, 1.0, 0.5), stats.t(5.0, 1.0, 0.5).cdf),
    (Exponential(2.0), stats.expon(scale=2.0).cdf),
    (Gamma(2.5, 0.7), stats.gamma(2.5, scale=0.7).cdf),
]


def _moment_bounds(x, sigma):
    """5-sigma sampling bounds for the mean and the standard deviation of draws x."""
    n = x.size
    se_mean = sigma / math.sqrt(n)
    mu4 = np.mean((x - x.mean()) ** 4)
    se_std = math.sqrt(max(mu4 - sigma**4, 0.0) / n) / (2 * sigma)
    return 5 * se_mean, 5 * se_std


@pytest.mark.parametrize(
    ("dist", "cdf"), SCALAR_CASES, ids=lambda v: str(v) if isinstance(v, Distribution) else ""
)
@pytest.mark.parametrize("method", ["default", "box-muller"])
def test_scalar_moments_and_ks(dist, cdf, method):
    rng = np.random.default_rng(20240611)
    x = dist.sample(rng, M, normal_method=method)
    assert x.shape == (M,)
    assert x.dtype == np.float64
    tol_mean, tol_std = _moment_bounds(x, dist.std)
    assert abs(x.mean() - dist.mean) <= tol_mean
    assert abs(x.std(ddof=1) - dist.std) <= tol_std
    res = stats.kstest(x[:100_000], cdf)
    assert res.pvalue > 1e-3, res


@pytest.mark.parametrize(
    ("dist", "mean", "var"),
    [
        (Uniform(2, 5), 3.5, 9 / 12),
        (Triangular(-1, 1), 0.0, 4 / 24),
        (Triangular(0, 6, 0), 2.0, (36 + 0 + 0 - 0 - 0 - 0) / 18),
        (Trapezoidal(0, 4, 0.5), 2.0, 16 * 1.25 / 24),
        (CurvilinearTrapezoid(0, 4, 1), 2.0, 4 / 3 + 1 / 9),
        (Arcsine(0, 4), 2.0, 16 / 8),
        (StudentT(6, 2, 3), 2.0, 9 * 6 / 4),
        (Exponential(3), 3.0, 9.0),
        (Gamma(3, 2), 6.0, 12.0),
    ],
)
def test_closed_form_moments(dist, mean, var):
    assert dist.mean == pytest.approx(mean, abs=1e-15)
    assert dist.std**2 == pytest.approx(var, rel=1e-14)


def test_trapezoid_limits_are_triangle_and_rectangle():
    assert Trapezoidal(-1, 1, 0).std == pytest.approx(Triangular(-1, 1).std, rel=1e-15)
    assert Trapezoidal(-1, 1, 1).std == pytest.approx(Uniform(-1, 1).std, rel=1e-15)


def test_dof_and_dim():
    assert StudentT(7).dof == 7
    assert Normal(0, 1).dof == math.inf
    assert Normal(0, 1).dim == 0
    assert MultivariateNormal([0, 0, 0], np.eye(3)).dim == 3
    assert StudentT(2).std == math.inf
    assert math.isnan(StudentT(1).mean)


def test_multivariate_normal_moments_and_marginals():
    cov = np.array([[4.0, 1.2, 0.0], [1.2, 1.0, -0.3], [0.0, -0.3, 0.25]])
    d = MultivariateNormal([1.0, -2.0, 0.5], cov)
    for method in ("default", "box-muller"):
        x = d.sample(np.random.default_rng(5), M, normal_method=method)
        assert x.shape == (M, 3)
        se = np.sqrt(np.diag(cov) / M)
        assert np.all(np.abs(x.mean(axis=0) - d.mean) <= 5 * se)
        c = np.cov(x, rowvar=False)
        # se of a sample covariance: sqrt((s_ii s_jj + s_ij^2) / M)
        se_c = np.sqrt((np.outer(np.diag(cov), np.diag(cov)) + cov**2) / M)
        assert np.all(np.abs(c - cov) <= 5 * se_c)
        for j in range(3):
            assert stats.kstest(x[:50_000, j], stats.norm(d.mean[j], d.std[j]).cdf).pvalue > 1e-3


def test_multivariate_normal_singular_covariance():
    # perfectly correlated pair: Cholesky fails, the eigen factor is used
    d = MultivariateNormal([0.0, 0.0], [[1.0, 1.0], [1.0, 1.0]])
    x = d.sample(np.random.default_rng(1), 10_000)
    np.testing.assert_allclose(x[:, 0], x[:, 1], atol=1e-12)
    assert x[:, 0].std() == pytest.approx(1.0, abs=0.05)


@pytest.mark.parametrize(
    ("cov", "msg"),
    [
        ([[1.0, 0.5], [0.4, 1.0]], "symmetric"),
        ([[1.0, 2.0], [2.0, 1.0]], "positive semi-definite"),
        ([[1.0, 0.0, 0.0]], "2x2 matrix"),
    ],
)
def test_multivariate_normal_bad_covariance(cov, msg):
    with pytest.raises(DistributionError, match=msg) as exc:
        MultivariateNormal([0.0, 0.0], cov)
    assert exc.value.field == "cov"


def test_constant():
    c = Constant(3.25)
    assert c.mean == 3.25
    assert c.std == 0.0
    assert c.dim == 0
    np.testing.assert_array_equal(c.sample(np.random.default_rng(0), 4), [3.25] * 4)
    v = Constant([1.0, 2.0])
    assert v.sample(np.random.default_rng(0), 3).shape == (3, 2)
    np.testing.assert_array_equal(v.std, [0.0, 0.0])


def test_box_muller_is_the_transform_of_uniform_pairs():
    # independent recomputation of Stryczek eq. 6 from the same uniform stream
    z = standard_normal(np.random.default_rng(3), 7, "box-muller")
    u = np.random.default_rng(3).random((4, 2))
    r = np.sqrt(-2 * np.log(1 - u[:, 0]))
    expected = np.column_stack([r * np.cos(2 * np.pi * u[:, 1]), r * np.sin(2 * np.pi * u[:, 1])])
    np.testing.assert_allclose(z, expected.ravel()[:7], rtol=1e-15)


ALL = [d for d, _ in SCALAR_CASES] + [
    MultivariateNormal([0, 1.5], [[1, 0.25], [0.25, 2]]),
    Constant(2),
    Constant([1, 2.5]),
    StudentT(3),
    Normal(-0.1, 1e-5),
]


@pytest.mark.parametrize("dist", ALL, ids=str)
def test_text_round_trip(dist):
    text = str(dist)
    back = parse_distribution(text)
    assert back == dist
    assert str(back) == text
    assert type(back) is type(dist)


@pytest.mark.parametrize("method", ["default", "box-muller"])
@pytest.mark.parametrize("dist", ALL, ids=str)
def test_prefix_property(dist, method):
    a = dist.sample(np.random.default_rng(11), 101, normal_method=method)
    b = dist.sample(np.random.default_rng(11), 57, normal_method=method)
    if isinstance(dist, StudentT) and method == "box-muller":
        pytest.skip("normal and chi-squared draws come in two runs")
    np.testing.assert_array_equal(a[:57], b)


finite = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False, allow_subnormal=False)


@settings(max_examples=60, deadline=None)
@given(mean=finite, std=st.floats(min_value=0, max_value=1e6, allow_subnormal=False))
def test_normal_text_round_trip_property(mean, std):
    d = Normal(mean, std)
    e = parse_distribution(str(d))
    assert e == d
    assert e.mean == mean
    assert e.std == std


@settings(max_examples=60, deadline=None)
@given(a=finite, w=st.floats(min_value=1e-3, max_value=1e6), beta=st.floats(0, 1))
def test_trapezoid_text_round_trip_property(a, w, beta):
    b = a + w
    if not a < b:
        return
    d = Trapezoidal(a, b, beta)
    assert parse_distribution(str(d)) == d


def test_names_aliases_keywords():
    assert parse_distribution("rectangular(0, 1)") == Uniform(0, 1)
    assert parse_distribution("u_shaped(0, 1)") == Arcsine(0, 1)
    assert parse_distribution("curvilinear_trapezoid(0, 2, 0.5)") == CurvilinearTrapezoid(0, 2, 0.5)
    assert parse_distribution("student_t(4, 1, 2)") == StudentT(4, 1, 2)
    assert parse_distribution("Normal( mean = 1e-3 , std=2.5E-4 )") == Normal(1e-3, 2.5e-4)
    assert parse_distribution("mvnormal([0,0],[[1,0],[0,1]])").dim == 2
    assert parse_distribution("triangular(0, 1, mode=0.2)") == Triangular(0, 1, 0.2)
    assert {"normal", "uniform", "rectangular", "ctrap", "arcsine", "t", "mvnormal"} <= set(
        distribution_names()
    )


@pytest.mark.parametrize(
    ("text", "fragments"),
    [
        ("weibull(1, 2)", ["unknown distribution 'weibull'", "expected one of", "column 1"]),
        ("normal(0)", ["normal takes 2 parameters", "normal(mean, std)", "got 1"]),
        ("uniform(0, 1, 2)", ["uniform takes 2 parameters", "got 3"]),
        ("t()", ["t takes 1 to 3 parameters", "got 0"]),
        ("normal(0, -1)", ["field std", "expected a finite number >= 0, got -1"]),
        ("uniform(1, 1)", ["expected low < high"]),
        ("trapezoidal(0, 1, 1.5)", ["field beta", "0 <= beta <= 1"]),
        ("ctrap(0, 1, 0.6)", ["field d", "0 <= d <= (high - low)/2"]),
        ("triangular(0, 1, 2)", ["field mode", "low <= mode <= high"]),
        ("gamma(0, 1)", ["field shape", "> 0"]),
        ("exponential(-2)", ["field mean", "> 0"]),
        ("normal(0, 1", ["expected ',' or ')'", "end of text"]),
        ("normal(0, 1) 2", ["unexpected '2' after the closing ')'"]),
        ("normal(0, 1) + 2", ["unexpected character '+'", "column 14"]),
        ("normal(0; 1)", ["unexpected character ';'", "column 9"]),
        ("normal(0, sigma=1)", ["normal has no parameter 'sigma'"]),
        ("normal(0, mean=1)", ["parameter 'mean' given twice"]),
        ("normal([0, 1], 1)", ["field mean", "expected a finite number"]),
    ],
)
def test_parse_errors(text, fragments):
    with pytest.raises(DistributionError) as exc:
        parse_distribution(text)
    msg = str(exc.value)
    for frag in fragments:
        assert frag in msg, msg


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("normal(007, 1.e5)", Normal(7, 1e5)),  # numbers as written, not as Python reads them
        ("normal(-.5,\n +2E-3)", Normal(-0.5, 2e-3)),
        ("\tnormal(0,\u00a01)  ", Normal(0, 1)),
        ("iid(base=normal(0, 1), k=2)", IID(Normal(0, 1), 2)),
        ("mvnormal([0, 1], [[1, 0], [0, 1]])", MultivariateNormal([0, 1], [[1, 0], [0, 1]])),
    ],
)
def test_forms_python_would_read_otherwise(text, expected):
    assert parse_distribution(text) == expected


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("normal(0, 1,)", "expected a number or a list, got ')'"),
        ("normal((0), 1)", "expected a number or a list, got '('"),
        ("normal(0x10, 1)", "column 8: expected a finite number written with the digits 0-9"),
        ("normal(1_000, 1)", "and exponent: -1.5e-3), got '1_000'"),
        ("normal(0, \u0661)", "column 11: expected a finite number written with the digits 0-9"),
        ("normal(\uff11, 1)", "exponent: -1.5e-3), got '\uff11' in"),
        ("normal(0, 1" + "0" * 400 + ")", "(401 characters); at most 100 characters"),
        ("normal(0, 1e309)", "expected a finite number at most 1.8e+308 in size, got '1e309'"),
        ("normal(0, 1) # note", "unexpected character '#'"),
        ("normal('0', 1)", 'unexpected character "\'"'),
        ("normal(0, 1)[0]", "unexpected '[' after the closing ')'"),
        ("normal(None, 1)", "unknown distribution 'None'"),
        ("__import__('os')", 'unexpected character "\'"'),
        ("normal(0, mean=1, 2)", "positional parameter after a keyword parameter"),
        ("t(9, loc=1, loc=2)", "parameter 'loc' given twice"),
        ("iid(normal, 2)", "expected '(', got ','"),
        ("normal(0, [1, 2", "expected ',' or ']', got end of text"),
        ("[1, 2]", "column 1: expected a distribution name, got '['"),
        ("t(loc=1)", "t is missing parameter(s) df (t(df, loc, scale))"),
        ("normal([], 1)", "field mean: normal: expected a finite number, got []"),
        # deeper than Python's parser goes: refused, not a crash
        ("  constant(" + "[" * 250 + "1" + "]" * 250 + ")", "column 211: syntax error in"),
    ],
)
def test_what_python_reads_but_a_distribution_is_not(text, message):
    with pytest.raises(DistributionError) as exc:
        parse_distribution(text)
    assert message in str(exc.value)


def test_parse_error_names_file_line_field():
    with pytest.raises(DistributionError) as exc:
        parse_distribution("normal(0, -2)", file="study.toml", line=7, field="probe")
    msg = str(exc.value)
    assert msg.startswith("study.toml:7:1: field probe: ")
    assert exc.value.line == 7
    assert exc.value.file == "study.toml"


def test_as_distribution():
    d = Normal(0, 1)
    assert as_distribution(d) is d
    assert as_distribution(2) == Constant(2)
    assert as_distribution([1, 2]).dim == 2
    assert as_distribution("uniform(0, 1)") == Uniform(0, 1)
    for bad in (None, True, object(), [[1, 2], [3, 4]]):
        with pytest.raises(DistributionError, match="expected"):
            as_distribution(bad, field="x")


def test_constructor_validation_messages():
    with pytest.raises(DistributionError, match="low < high") as exc:
        Uniform(2, 1)
    assert exc.value.field == "high"
    with pytest.raises(DistributionError, match="finite"):
        Normal(math.nan, 1)
    with pytest.raises(DistributionError, match="number of draws"):
        Normal(0, 1).sample(np.random.default_rng(0), -1)
    with pytest.raises(DistributionError, match="normal method"):
        standard_normal(np.random.default_rng(0), 3, "polar")  # type: ignore[arg-type]


def test_registry_refuses_duplicates():
    with pytest.raises(DistributionError, match="already registered"):
        register_distribution("normal")(Normal)


def test_equality_and_hash():
    assert Normal(0, 1) == Normal(0.0, 1.0)
    assert Normal(0, 1) != Uniform(0, 1)
    assert len({Normal(0, 1), Normal(0.0, 1.0), Uniform(0, 1)}) == 2


@pytest.mark.parametrize(
    ("text", "components"),
    [("iid(normal(0, 1), 1e9)", 10**9), ("iid(normal(0, 1), 100000000)", 10**8)],
)
def test_a_text_of_more_components_than_the_gum_holds_is_refused_before_drawing(text, components):
    # 10⁹ ended in ArrayMemoryError, 10⁸ ran at 0 trials/s (the GUM's k × k covariance)
    with pytest.raises(DistributionError) as info:
        parse_distribution(text, file="s.toml", line=8, field="inputs.a")
    err = info.value
    assert (err.file, err.line, err.column, err.field) == ("s.toml", 8, 1, "inputs.a")
    assert f"iid: expected at most 4096 components, got {components}" in err.message
    assert parse_distribution("iid(normal(0, 1), 4096)").dim == 4096
