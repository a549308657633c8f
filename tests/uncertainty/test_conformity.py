"""Conformity assessment (JCGM 106:2012) against closed forms and independent recomputations.

References used here, none of them the code under test:

* ``Φ`` from the C library's ``erfc`` (``math.erfc``): ``Φ(x) = erfc(-x/√2)/2``;
* the t distribution function by quadrature of the t density written from its formula;
* the standard normal quantile of :class:`statistics.NormalDist`;
* the global risks of JCGM 106 §9.5 by a two-dimensional quadrature
  (``scipy.integrate.dblquad``) of ``g_0(η) h(η_m | η)``, by the bivariate normal
  distribution function of ``(η, η_m)`` (Genz's algorithm in SciPy), and by a plain
  NumPy Monte Carlo of the measurand–measurement pair;
* counts of Monte Carlo values by NumPy boolean masks.
"""

from __future__ import annotations

import math
from statistics import NormalDist

import numpy as np
import pytest
from scipy import integrate, special, stats

import mtmc
from mtmc.errors import InputError
from mtmc.uncertainty import (
    Conformity,
    GumResult,
    MonteCarloResult,
    conformance_probability,
    conformity,
    expression,
    global_risks,
    gum,
    monte_carlo,
    normal_conformance_probability,
)


def phi(x: float) -> float:
    """The standard normal distribution function from libm's erfc."""
    return 0.5 * math.erfc(-x / math.sqrt(2.0))


def t_cdf_by_quadrature(x: float, nu: float) -> float:
    """``F_ν(x)`` by integrating the t density from its formula (not scipy.stats.t)."""
    log_c = special.gammaln((nu + 1) / 2) - special.gammaln(nu / 2) - 0.5 * math.log(nu * math.pi)

    def pdf(t: float) -> float:
        return math.exp(log_c - (nu + 1) / 2 * math.log1p(t * t / nu))

    half = integrate.quad(pdf, 0.0, abs(x), epsabs=1e-14, epsrel=1e-13)[0]
    return 0.5 + math.copysign(half, x)


def gum_result(y: float, u: float, dof: float = math.inf) -> GumResult:
    """A scalar GUM result of estimate ``y``, uncertainty ``u`` and ``ν_eff = dof``."""
    return GumResult(
        estimate_vector=[y],
        u_vector=[u],
        cov=[[u * u]],
        dof_vector=[dof],
        p=0.95,
        sensitivities={},
        budget=(),
        method="complex-step",
    )


# ---------------------------------------------------------------- closed forms (GUM PDF)
@pytest.mark.parametrize(
    ("y", "u", "lower", "upper"),
    [
        (0.0, 1.0, -2.0, 2.0),
        (9.7, 0.1, 9.0, 10.0),
        (0.3, 0.2, None, 0.5),
        (0.3, 0.2, 0.1, None),
        (5.0, 0.5, 6.0, 8.0),  # both limits above: the upper tails carry the digits
        (-1.0, 3.0, -1e-3, 1e-3),
    ],
)
def test_normal_pc_is_the_difference_of_phi(y, u, lower, upper):
    # JCGM 106 §7: p_c = Φ((T_U - y)/u) - Φ((T_L - y)/u)
    hi = 1.0 if upper is None else phi((upper - y) / u)
    lo = 0.0 if lower is None else phi((lower - y) / u)
    expected = hi - lo
    got = normal_conformance_probability(y, u, lower, upper)
    # two evaluations of Φ, each within a few ulp in SciPy's ndtr and in libm's erfc
    assert got == pytest.approx(expected, rel=1e-14, abs=1e-16)
    assert gum_result(y, u).conformity(lower, upper).p_c == got  # the same computation


@pytest.mark.parametrize("nu", [3.0, 7.5, 30.0])
def test_t_pc_for_finite_dof(nu):
    # JCGM 100 G.3: (Y - y)/u is t with ν_eff degrees of freedom, scaled by u (not by sd)
    y, u, tl, tu = 10.0, 0.2, 9.7, 10.5
    expected = t_cdf_by_quadrature((tu - y) / u, nu) - t_cdf_by_quadrature((tl - y) / u, nu)
    got = gum_result(y, u, nu).conformity(tl, tu)
    # quadrature to 1e-13 relative; SciPy's t distribution function to ~1e-15
    assert got.p_c == pytest.approx(expected, rel=1e-11)
    assert got.basis.startswith("GUM, t with ν_eff")
    # heavier tails than the normal of the same u: a lower p_c
    assert got.p_c < normal_conformance_probability(y, u, tl, tu)


def test_simple_acceptance_at_the_limit_has_half_the_probability():
    # JCGM 106 §8.2: an estimate on a single tolerance limit conforms with p_c = 1/2
    c = gum_result(10.0, 0.1).conformity(upper=10.0)
    assert c.p_c == 0.5  # Φ(0) = 1/2 exactly in SciPy's ndtr
    assert c.conforms
    assert c.consumer_risk == 0.5
    assert c.producer_risk is None


def test_guard_band_of_one_expanded_uncertainty_gives_977_per_mille():
    # JCGM 106 §8.3: with w = U = 2u (r = 1) an item accepted on the acceptance limit
    # of a single upper tolerance limit conforms with p_c = Φ(2) = 0.977
    u, tu = 0.1, 10.0
    c = gum_result(tu - 2 * u, u).conformity(upper=tu, rule="guarded", guard=1.0)
    assert c.acceptance_upper == tu - 2 * u  # w = r k u, bit for bit
    assert c.conforms
    assert c.p_c == pytest.approx(phi(2.0), rel=1e-14)  # as in the first test
    assert round(c.p_c, 3) == 0.977
    # one ulp above the acceptance limit: rejected, the specific producer's risk is p_c
    above = gum_result(float(np.nextafter(tu - 2 * u, np.inf)), u).conformity(
        upper=tu, rule="guarded", guard=1.0
    )
    assert not above.conforms
    assert above.producer_risk == above.p_c
    assert above.consumer_risk is None


def test_the_one_line_text():
    c = gum_result(9.7, 0.1).conformity(9.0, 10.0, rule="guarded", guard=0.5)
    # p_c = Φ(3) - Φ(-7) = 0.99865: four decimals show two digits of 1 - p_c
    assert c.text == "conforms, p_c = 0.9987, rule: guarded acceptance, w = 0.5·U"
    assert c.decision == "conforms"
    assert (c.acceptance_lower, c.acceptance_upper) == (9.0 + 0.1, 10.0 - 0.1)
    r = gum_result(9.95, 0.1).conformity(9.0, 10.0)
    assert r.text == "conforms, p_c = 0.691, rule: simple acceptance"  # Φ(0.5) = 0.6915
    assert r.to_dict()["acceptance"] == [9.0, 10.0]


# --------------------------------------------------------- guard band from a maximum risk
@pytest.mark.parametrize("alpha", [0.05, 0.01, 0.001])
def test_guard_band_for_a_maximum_consumers_risk_normal(alpha):
    u, tl, tu = 0.1, 9.0, 10.0
    c = gum_result(9.5, u).conformity(tl, tu, rule="guarded", max_consumer_risk=alpha)
    # at the acceptance limits the conformance probability is 1 - α (the root)
    for a in (c.acceptance_lower, c.acceptance_upper):
        pc = phi((tu - a) / u) - phi((tl - a) / u)
        # Brent to a few ulp in A; p_c changes by φ(z)/u · δA, far below 1e-13
        assert pc == pytest.approx(1.0 - alpha, abs=1e-13)
    # the other limit 10u away: the guard band is nearly the normal quantile, z_{1-α} u;
    # that limit's tail, Φ(-(10 - z)) <= 3e-12 at α = 0.001, moves A by at most
    # 3e-12 u/φ(z) = 1e-10 u, i.e. 3e-10 relative to w
    z = NormalDist().inv_cdf(1.0 - alpha)
    assert c.guard_upper == pytest.approx(z * u, rel=1e-9)
    assert c.guard == pytest.approx(z / 2.0, rel=1e-9)  # w / U with U = 2u
    assert c.guard_lower == pytest.approx(c.guard_upper, rel=1e-12)  # symmetric PDF
    one_sided = gum_result(9.5, u).conformity(upper=tu, rule="guarded", max_consumer_risk=alpha)
    assert one_sided.acceptance_upper == pytest.approx(tu - z * u, rel=1e-14)
    assert one_sided.acceptance_lower == -math.inf


def test_guard_band_for_a_maximum_consumers_risk_samples():
    rng = np.random.default_rng(7)
    values = rng.gamma(3.0, 0.05, 50_001) + 9.5  # a skewed PDF: no closed form used
    r = MonteCarloResult.from_samples(values, seed=7)
    alpha, tl, tu = 0.05, 9.45, 10.0
    c = r.conformity(tl, tu, rule="guarded", max_consumer_risk=alpha)
    d = values - r.estimate  # the PDF translated to an estimate A is d + A

    def pc_at(a: float) -> float:
        return np.count_nonzero((d >= tl - a) & (d <= tu - a)) / d.size

    # the limits found by bisection are exact: p_c >= 1 - α on them, < 1 - α one ulp out
    assert pc_at(c.acceptance_upper) >= 1 - alpha
    assert pc_at(float(np.nextafter(c.acceptance_upper, np.inf))) < 1 - alpha
    assert pc_at(c.acceptance_lower) >= 1 - alpha
    assert pc_at(float(np.nextafter(c.acceptance_lower, -np.inf))) < 1 - alpha
    # the decision is the rule p_c >= 1 - α on the values themselves
    assert c.p_c == np.count_nonzero((values >= tl) & (values <= tu)) / values.size
    assert c.conforms == (c.p_c >= 1 - alpha)
    # skewed to the right: the upper guard band is the wider one
    assert c.guard_upper > c.guard_lower


def test_no_estimate_can_be_accepted_when_the_tolerance_is_too_narrow():
    # T_U - T_L = 2u: even centred, p_c = Φ(1) - Φ(-1) = 0.683 < 0.95
    c = gum_result(0.0, 1.0).conformity(-1.0, 1.0, rule="guarded", max_consumer_risk=0.05)
    assert not c.conforms
    assert math.isnan(c.acceptance_upper)
    assert c.guard is None
    assert c.p_c == pytest.approx(phi(1.0) - phi(-1.0), rel=1e-14)
    assert "no estimate can be accepted" in c.text
    assert c.to_dict()["acceptance"] == [None, None]


# ------------------------------------------------------------------- Monte Carlo PDF
def test_sample_pc_is_the_fraction_of_values():
    r = MonteCarloResult.from_samples(np.arange(1.0, 101.0), seed=None)
    p_c, err, basis = conformance_probability(r, 10.0, 40.0)
    assert (p_c, basis) == (31 / 100, "samples")  # 10, 11, ..., 40 inclusive
    assert err == math.sqrt(0.31 * 0.69 / 100)  # binomial standard error, same formula


def test_monte_carlo_pc_agrees_with_the_gum_for_a_linear_normal_model():
    model = expression("a + 2 * b")
    inputs = {"a": "normal(1, 0.03)", "b": "normal(2, 0.02)"}  # y = 5, u = 0.05
    mc = monte_carlo(model, inputs, trials=200_000, seed=11)
    g = gum(model, inputs)
    tl, tu = 4.95, 5.08
    c_mc = mc.conformity(tl, tu)
    c_gum = g.conformity(tl, tu)
    # y ~ N(5, 0.05²) exactly (a linear model of normal inputs): the GUM p_c is exact,
    # Φ(1.6) - Φ(-1) = 0.7865
    assert c_gum.p_c == pytest.approx(phi(1.6) - phi(-1.0), rel=1e-12)
    # the Monte Carlo fraction is binomial with standard error sqrt(p(1-p)/M) = 0.00092;
    # four of them is a false alarm once in 16 000 seeds
    assert abs(c_mc.p_c - c_gum.p_c) <= 4 * c_mc.p_c_error
    assert c_mc.basis == "samples"
    assert c_gum.basis == "GUM, normal"


def test_sketch_pc_is_within_its_rank_bound_of_the_exact_fraction():
    model = expression("a * b")
    inputs = {"a": "uniform(0.9, 1.1)", "b": "normal(1, 0.1)"}
    kept = monte_carlo(model, inputs, trials=60_000, seed=5)
    sketched = monte_carlo(model, inputs, trials=60_000, seed=5, keep=False, sketch=True)
    assert sketched.samples is None
    assert sketched.sketch is not None
    exact = kept.conformity(0.85, 1.12).p_c
    c = sketched.conformity(0.85, 1.12)
    assert c.basis == "sketch"
    # each count read from the sketch is within rank_error of the true count (a hard
    # bound, mtmc.uncertainty.sketch): two limits, two counts
    assert abs(c.p_c - exact) <= c.p_c_error
    assert c.p_c_error == 2 * sketched.sketch.rank_error / 60_000


def test_a_vector_component_without_samples_uses_the_normal_of_its_moments():
    model = lambda x: np.stack([x, 2 * x], axis=1)  # noqa: E731
    r = monte_carlo(model, {"x": "normal(0, 1)"}, trials=20_000, seed=3, keep=False)
    comp = r.component(1)
    c = comp.conformity(-1.0, 1.0)
    assert c.basis == "normal from the Monte Carlo estimate and u"
    y, u = comp.estimate, comp.u
    assert c.p_c == pytest.approx(phi((1.0 - y) / u) - phi((-1.0 - y) / u), rel=1e-14)
    with pytest.raises(InputError, match=r"component\(i\)"):
        r.conformity(-1.0, 1.0)


# ---------------------------------------------------------------------- global risks
def _npdf(x: float, mean: float, sd: float) -> float:
    z = (x - mean) / sd
    return math.exp(-0.5 * z * z) / (sd * math.sqrt(2.0 * math.pi))


def _risks_by_dblquad(tl, tu, al, au, um, y0, u0):
    # the double integrals of JCGM 106 §9.5 as they stand, over (η, η_m)
    def f(eta_m: float, eta: float) -> float:
        return _npdf(eta, y0, u0) * _npdf(eta_m, eta, um)

    lo, hi = y0 - 12 * u0, y0 + 12 * u0
    opts = {"epsabs": 1e-14, "epsrel": 1e-10}
    rc = integrate.dblquad(f, lo, tl, al, au, **opts)[0]
    rc += integrate.dblquad(f, tu, hi, al, au, **opts)[0]
    rp = integrate.dblquad(f, tl, tu, al - 12 * um, al, **opts)[0]
    rp += integrate.dblquad(f, tl, tu, au, au + 12 * um, **opts)[0]
    return rc, rp


def _risks_by_bivariate_normal(tl, tu, al, au, um, y0, u0):
    # (η, η_m) is bivariate normal: mean (y0, y0), cov [[u0², u0²], [u0², u0² + um²]];
    # R_C = Pr(accepted) - Pr(conforming and accepted), R_P = Pr(conforming) - the same
    mvn = stats.multivariate_normal(
        [y0, y0], [[u0**2, u0**2], [u0**2, u0**2 + um**2]], abseps=1e-12, releps=1e-12
    )
    both = mvn.cdf([tu, au]) - mvn.cdf([tl, au]) - mvn.cdf([tu, al]) + mvn.cdf([tl, al])
    s_m = math.hypot(u0, um)
    accepted = phi((au - y0) / s_m) - phi((al - y0) / s_m)
    conforming = phi((tu - y0) / u0) - phi((tl - y0) / u0)
    return accepted - both, conforming - both


@pytest.mark.parametrize(
    ("cm", "y0", "u0", "r"),
    [(2.0, 0.0, 0.5, 0.0), (2.0, 0.0, 0.5, 1.0), (4.0, 0.3, 0.4, 0.5), (1.0, -0.2, 0.6, 0.0)],
)
def test_global_risks_against_two_independent_integrations(cm, y0, u0, r):
    # JCGM 106 §9.5 for T = [-1, 1], C_m = (T_U - T_L)/(4 u_m)
    tl, tu = -1.0, 1.0
    um = (tu - tl) / (4 * cm)
    c = gum_result(0.0, um).conformity(tl, tu, rule="guarded", guard=r, prior=(y0, u0))
    if r == 0.0:
        c = gum_result(0.0, um).conformity(tl, tu, prior={"mean": y0, "sd": u0})
    g = c.global_risks
    assert g is not None
    assert g.capability == pytest.approx(cm, rel=1e-15)
    al, au = c.acceptance_lower, c.acceptance_upper
    rc2, rp2 = _risks_by_dblquad(tl, tu, al, au, um, y0, u0)
    rc3, rp3 = _risks_by_bivariate_normal(tl, tu, al, au, um, y0, u0)
    # dblquad to 1e-10 relative per piece
    assert g.consumer == pytest.approx(rc2, rel=1e-8, abs=1e-13)
    assert g.producer == pytest.approx(rp2, rel=1e-8, abs=1e-13)
    # Genz's algorithm at abseps 1e-12, four corners: a few 1e-12
    assert g.consumer == pytest.approx(rc3, abs=1e-10)
    assert g.producer == pytest.approx(rp3, abs=1e-10)
    assert g.prior_conformance == pytest.approx(
        phi((tu - y0) / u0) - phi((tl - y0) / u0), rel=1e-13
    )


def test_global_risks_against_a_monte_carlo_of_the_pair():
    # the measurand-measurement pair drawn directly: η ~ g_0, η_m = η + N(0, u_m²)
    tl, tu, um, y0, u0 = -1.0, 1.0, 0.25, 0.1, 0.45
    c = gum_result(0.0, um).conformity(tl, tu, rule="guarded", guard=0.5, prior=(y0, u0))
    n = 2_000_000
    rng = np.random.default_rng(2012)
    eta = rng.normal(y0, u0, n)
    eta_m = eta + rng.normal(0.0, um, n)
    accepted = (eta_m >= c.acceptance_lower) & (eta_m <= c.acceptance_upper)
    conforming = (eta >= tl) & (eta <= tu)
    rc = np.count_nonzero(accepted & ~conforming) / n
    rp = np.count_nonzero(~accepted & conforming) / n
    g = c.global_risks
    assert g is not None
    # binomial standard errors sqrt(R(1-R)/n); five of them
    assert abs(g.consumer - rc) <= 5 * math.sqrt(rc * (1 - rc) / n)
    assert abs(g.producer - rp) <= 5 * math.sqrt(rp * (1 - rp) / n)
    # the guard band trades producer's risk for consumer's risk (JCGM 106 §9.5)
    simple = gum_result(0.0, um).conformity(tl, tu, prior=(y0, u0)).global_risks
    assert simple is not None
    assert g.consumer < simple.consumer
    assert g.producer > simple.producer


def test_global_risks_of_a_rule_that_accepts_nothing():
    g = global_risks(
        -1.0, 1.0, u_m=0.5, prior_mean=0.0, prior_sd=0.5, acceptance=(math.nan, math.nan)
    )
    assert g.consumer == 0.0
    assert g.producer == g.prior_conformance


# ------------------------------------------------------------------------------ API
def test_methods_and_top_level_names_are_the_module_function():
    g = gum_result(1.0, 0.1)
    assert mtmc.conformity is conformity
    assert mtmc.Conformity is Conformity
    assert g.conformity(0.8, 1.1, rule="guarded", guard=0.25) == conformity(
        g, 0.8, 1.1, rule="guarded", guard=0.25
    )


@pytest.mark.parametrize(
    ("kwargs", "field", "match"),
    [
        ({}, "lower", "tolerance limit"),
        ({"lower": 1.0, "upper": 1.0}, "upper", "lower < upper"),
        ({"upper": 1.0, "rule": "strict"}, "rule", "'simple' or 'guarded'"),
        ({"upper": 1.0, "rule": "guarded"}, "guard", "one of guard"),
        ({"upper": 1.0, "guard": 0.5}, "guard", "needs rule = 'guarded'"),
        ({"upper": 1.0, "rule": "guarded", "max_consumer_risk": 0.7}, "max_consumer_risk", "< 0.5"),
        ({"lower": 0.9, "upper": 1.1, "rule": "guarded", "guard": 1.0}, "guard", "no acceptance"),
        ({"upper": 1.0, "prior": (0.0,)}, "prior", "a prior"),
        ({"upper": 1.0, "prior": (0.0, 0.0)}, "prior.sd", "sd > 0"),
    ],
)
def test_bad_arguments_name_their_field(kwargs, field, match):
    with pytest.raises(InputError, match=match) as info:
        conformity(gum_result(1.0, 0.1), **kwargs)
    assert info.value.field == field


def test_a_guard_band_given_as_a_width_and_a_decision_on_another_estimate():
    # w given in the unit of the result: A_U = T_U - w exactly, whatever u; the rule
    # decides on the estimate given, p_c stays that of the PDF (the values)
    mc = MonteCarloResult.from_samples(np.linspace(0.0, 10.0, 1001), seed=None)
    c = conformity(mc, upper=8.0, rule="guarded", guard_band=1.5)
    assert (c.acceptance_upper, c.guard_upper, c.guard_band) == (6.5, 1.5, 1.5)
    assert c.conforms  # the mean 5.0 is below 6.5
    assert c.p_c == 801 / 1001  # the values at or below 8
    assert c.text.endswith("rule: guarded acceptance, w = 1.5")
    assert c.to_dict()["guard_band"] == 1.5
    assert c.guard == pytest.approx(1.5 / (2 * float(mc.u)), rel=1e-15)
    d = conformity(mc, upper=8.0, rule="guarded", guard_band=1.5, estimate=7.0)
    assert (d.conforms, d.estimate, d.p_c) == (False, 7.0, c.p_c)
    assert conformity(mc, upper=8.0, estimate=7.9).conforms  # simple acceptance
    with pytest.raises(InputError, match="guard_band"):
        conformity(mc, upper=8.0, rule="guarded", guard=1.0, guard_band=1.5)
    with pytest.raises(InputError, match="simple acceptance has none"):
        conformity(mc, upper=8.0, guard_band=1.5)
