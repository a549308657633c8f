r"""Conformity assessment with measurement uncertainty (JCGM 106:2012).

A measurand ``Y`` conforms to a specification when its true value lies in the tolerance
interval ``C = [T_L, T_U]`` (one limit may be absent: ``T_L = -∞`` or ``T_U = +∞``,
JCGM 106). Given the PDF of ``Y`` after a measurement, this module computes

* the *conformance probability* ``p_c = Pr(T_L <= Y <= T_U)`` (JCGM 106 §7):
  from the Monte Carlo values of a :class:`~mtmc.uncertainty.results.MonteCarloResult`
  (the fraction of them in ``C``, JCGM 101 §7.5 PDF), or from the GUM's normal or scaled
  and shifted t distribution of a :class:`~mtmc.uncertainty.propagation.GumResult`
  (``p_c = F_ν((T_U - y)/u) - F_ν((T_L - y)/u)``, JCGM 106 §7 for the normal
  ``F_∞ = Φ``; JCGM 100 G.3 for t);
* a decision by a *decision rule* (JCGM 106 §8): *simple acceptance* (accept when the
  estimate ``y`` lies in ``C``, §8.2) or *guarded acceptance* (accept when ``y`` lies in
  the acceptance interval ``[A_L, A_U] = [T_L + w, T_U - w]`` with the guard band
  ``w = r U``, §8.3; or with ``w`` chosen so that the specific consumer's risk of an
  accepted item does not exceed a stated ``α``, i.e. accept when ``p_c >= 1 - α``,
  §8.3 and §9.3);
* the *specific* risks of the decision (JCGM 106 §9.3): the specific consumer's risk
  ``R*_C = 1 - p_c`` of an accepted item, the specific producer's risk ``R*_P = p_c`` of
  a rejected one;
* given a prior for the measurand (the production process, a normal ``N(y_0, u_0²)``,
  JCGM 106 §9) and a normal measurement model ``h(η_m | η) = N(η, u_m²)`` (§9), the
  *global* risks of the acceptance interval ``A`` (JCGM 106 §9.5)::

      R_C = ∫_{η ∉ C} ∫_{η_m ∈ A} g_0(η) h(η_m | η) dη_m dη
      R_P = ∫_{η ∈ C} ∫_{η_m ∉ A} g_0(η) h(η_m | η) dη_m dη

  The inner integral is ``Φ((A_U - η)/u_m) - Φ((A_L - η)/u_m)`` in closed form; the
  outer one is computed by adaptive quadrature (``scipy.integrate.quad``).

Examples
--------
A measured value 0.3 mm below the upper tolerance limit with ``u = 0.1`` mm:

>>> from mtmc.uncertainty.propagation import GumResult
>>> g = GumResult(estimate_vector=[9.7], u_vector=[0.1], cov=[[0.01]],
...               dof_vector=[float("inf")], p=0.95, sensitivities={}, budget=(),
...               method="complex-step")
>>> c = conformity(g, lower=9.0, upper=10.0, rule="guarded", guard=0.5)
>>> c.text
'conforms, p_c = 0.9987, rule: guarded acceptance, w = 0.5·U'
>>> c.acceptance_lower, c.acceptance_upper
(9.1, 9.9)
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal, Protocol

import numpy as np
from numpy.typing import NDArray

from mtmc.errors import InputError
from mtmc.uncertainty.distributions import Normal


class ScalarResult(Protocol):
    """What a decision reads of the result of one output.

    A :class:`~mtmc.uncertainty.results.MonteCarloResult` (its values, or its quantile
    sketch) or a :class:`~mtmc.uncertainty.propagation.GumResult` (its estimate, ``u`` and
    ``ν_eff``). Named here by what is read, so that the results, which decide through
    :func:`conformity`, and this module import each other neither at run time nor for
    their types.
    """

    @property
    def estimate(self) -> float: ...

    @property
    def u(self) -> float: ...


__all__ = [
    "Conformity",
    "GlobalRisks",
    "conformance_probability",
    "conformity",
    "global_risks",
    "normal_conformance_probability",
]

Rule = Literal["simple", "guarded"]
#: A normal prior of the measurand: ``(mean, sd)``, ``{"mean": ..., "sd": ...}`` or a Normal.
Prior = tuple[float, float] | Mapping[str, float] | object

#: The coverage factor of the expanded uncertainty ``U = k u`` that a guard band
#: ``w = r U`` multiplies (JCGM 106 §8.3 takes ``U = 2u``).
GUARD_COVERAGE_FACTOR = 2.0

#: A cap on the bisection steps of an acceptance limit on Monte Carlo values: halving an
#: interval between two finite doubles reaches two adjacent doubles in fewer steps (about
#: 2 × 1075 at most), where the search stops.
_MAX_BISECTIONS = 2200


# ---------------------------------------------------------------------------- limits
def _number(value: Any, field: str) -> float:
    if isinstance(value, bool):
        raise InputError(f"expected a number, got {value!r}", field=field)
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(f"expected a number, got {value!r}", field=field) from None
    if not math.isfinite(x):
        raise InputError(f"expected a finite number, got {value!r}", field=field)
    return x


def _limits(lower: Any, upper: Any) -> tuple[float, float]:
    """``(T_L, T_U)`` as floats, ``∓inf`` for an absent limit; at least one given."""
    if lower is None and upper is None:
        raise InputError(
            "expected a tolerance limit: lower, upper or both (JCGM 106)", field="lower"
        )
    tl = -math.inf if lower is None else _number(lower, "lower")
    tu = math.inf if upper is None else _number(upper, "upper")
    if not tl < tu:
        raise InputError(
            f"expected lower < upper, got lower = {tl!r} and upper = {tu!r}", field="upper"
        )
    return tl, tu


# ---------------------------------------------------------------- closed forms (GUM)
def normal_conformance_probability(
    estimate: float,
    u: float,
    lower: float | None = None,
    upper: float | None = None,
    dof: float = math.inf,
) -> float:
    """``p_c`` for a normal or scaled and shifted t PDF of the measurand.

    ``p_c = F_ν((T_U - y)/u) - F_ν((T_L - y)/u)`` with ``F_ν`` the t distribution
    function of ``ν`` degrees of freedom, ``F_∞ = Φ`` (JCGM 106 §7 for the normal;
    JCGM 100 G.3 for ``(Y - y)/u ~ t_ν``). The difference is taken on the side of
    the smaller tail, so that a probability near 1 keeps its digits.

    Parameters
    ----------
    estimate : float
        The estimate ``y``.
    u : float
        Its standard uncertainty ``u(y) >= 0`` (with ``u = 0``, ``p_c`` is 1 or 0).
    lower, upper : float, optional
        The tolerance limits ``T_L`` and ``T_U`` (at least one).
    dof : float, default inf
        Degrees of freedom ``ν`` (``inf``: the normal PDF).

    Returns
    -------
    float

    Examples
    --------
    >>> round(normal_conformance_probability(0.0, 1.0, -2.0, 2.0), 6)  # Φ(2) - Φ(-2)
    0.9545
    >>> normal_conformance_probability(10.0, 0.1, upper=10.0)  # at the limit
    0.5
    """
    from scipy import stats

    y = _number(estimate, "estimate")
    uu = _number(u, "u")
    if uu < 0:
        raise InputError(f"expected u >= 0, got {u!r}", field="u")
    nu = float(dof)
    if not nu > 0:
        raise InputError(f"expected degrees of freedom > 0, got {dof!r}", field="dof")
    tl, tu = _limits(lower, upper)
    if uu == 0.0:
        return 1.0 if tl <= y <= tu else 0.0
    a, b = (tl - y) / uu, (tu - y) / uu
    dist = stats.norm if math.isinf(nu) else stats.t(nu)
    if a > 0:  # both limits above the estimate: the upper tails keep the digits
        return float(dist.sf(a) - dist.sf(b))
    return float(dist.cdf(b) - dist.cdf(a))


# ------------------------------------------------------------ empirical (Monte Carlo)
@dataclass(frozen=True)
class _Empirical:
    """Sorted values with cumulative weights: the Monte Carlo distribution function."""

    values: NDArray[np.float64]
    cumulative: NDArray[np.float64]
    n: float
    error: float  # bound on the error of any count (0 for kept samples)

    @classmethod
    def of_samples(cls, samples: NDArray[np.float64]) -> _Empirical:
        s = np.sort(np.asarray(samples, dtype=np.float64))
        return cls(s, np.arange(1.0, s.size + 1.0), float(s.size), 0.0)

    @classmethod
    def of_sketch(
        cls, levels: Sequence[NDArray[np.float64]], n: int, rank_error: int
    ) -> _Empirical:
        vals = np.concatenate([np.asarray(a, dtype=np.float64) for a in levels])
        wts = np.concatenate([np.full(np.size(a), 2.0**i) for i, a in enumerate(levels)])
        order = np.argsort(vals, kind="stable")
        return cls(vals[order], np.cumsum(wts[order]), float(n), float(rank_error))

    def count(self, low: float, high: float) -> float:
        """The (weighted) number of values in ``[low, high]``."""
        hi = int(np.searchsorted(self.values, high, side="right"))
        lo = int(np.searchsorted(self.values, low, side="left"))
        c_hi = self.cumulative[hi - 1] if hi > 0 else 0.0
        c_lo = self.cumulative[lo - 1] if lo > 0 else 0.0
        return float(c_hi - c_lo)

    def fraction(self, low: float, high: float) -> float:
        return min(1.0, max(0.0, self.count(low, high) / self.n))


@dataclass(frozen=True)
class _Probability:
    """``p_c`` of one result, how it was obtained, and the means to shift its PDF."""

    p_c: float
    error: float
    basis: str
    estimate: float
    u: float
    empirical: _Empirical | None
    dof: float

    def shifted(self, at: float, tl: float, tu: float) -> float:
        """``p_c`` of the same PDF translated so that its estimate is ``at``."""
        if self.empirical is None:
            return normal_conformance_probability(at, self.u, _opt(tl), _opt(tu), self.dof)
        d = at - self.estimate
        return self.empirical.fraction(tl - d, tu - d)


def _opt(x: float) -> float | None:
    return None if math.isinf(x) else x


def _is_monte_carlo(result: Any) -> bool:
    return hasattr(result, "samples") and hasattr(result, "sketch")


def _require_scalar(result: Any) -> None:
    if getattr(result, "dim", 0) != 0:
        raise InputError(
            f"conformity needs a scalar output; this one has d = {result.dim} components: "
            "assess result.component(i)",
            field="result",
        )


def _probability(result: Any, tl: float, tu: float) -> _Probability:
    _require_scalar(result)
    y, u = float(result.estimate), float(result.u)
    if _is_monte_carlo(result):
        if result.samples is not None:
            emp = _Empirical.of_samples(result.samples)
            p = emp.fraction(tl, tu)
            se = math.sqrt(p * (1.0 - p) / emp.n)
            return _Probability(p, se, "samples", y, u, emp, math.inf)
        if result.sketch is not None:
            sk = result.sketch
            emp = _Empirical.of_sketch(sk.levels, sk.n, sk.rank_error)
            p = emp.fraction(tl, tu)
            ends = int(math.isfinite(tl)) + int(math.isfinite(tu))
            return _Probability(p, ends * emp.error / emp.n, "sketch", y, u, emp, math.inf)
        p = normal_conformance_probability(y, u, _opt(tl), _opt(tu))
        return _Probability(
            p, 0.0, "normal from the Monte Carlo estimate and u", y, u, None, math.inf
        )
    if hasattr(result, "dof_vector"):
        nu = float(result.dof)
        p = normal_conformance_probability(y, u, _opt(tl), _opt(tu), nu)
        basis = "GUM, normal" if math.isinf(nu) else f"GUM, t with ν_eff = {nu:.4g}"
        return _Probability(p, 0.0, basis, y, u, None, nu)
    raise InputError(
        f"expected a MonteCarloResult or a GumResult, got {type(result).__name__}",
        field="result",
    )


def conformance_probability(
    result: ScalarResult,
    lower: float | None = None,
    upper: float | None = None,
) -> tuple[float, float, str]:
    """The conformance probability ``p_c`` of a result (JCGM 106 §7).

    Parameters
    ----------
    result : MonteCarloResult or GumResult
        A scalar result.
    lower, upper : float, optional
        The tolerance limits ``T_L``, ``T_U`` (at least one).

    Returns
    -------
    p_c : float
        Where the Monte Carlo values were kept: the fraction of them in ``[T_L, T_U]``
        (JCGM 106 §7.1 with the discrete PDF of JCGM 101 §7.5). Where only a quantile
        sketch was kept: its weighted fraction. Where neither: the normal with the Monte
        Carlo estimate and ``u``. For a GUM result: the normal or, for a finite
        ``ν_eff``, the t distribution scaled by ``u`` (:func:`normal_conformance_probability`).
    error : float
        For kept values, the standard error ``sqrt(p_c (1 - p_c)/M)`` of the fraction
        (binomial sampling); for a sketch, the hard bound ``rank_error/M`` per finite
        limit on ``|p_c - fraction of the values|``; 0 for a closed form.
    basis : str
        ``"samples"``, ``"sketch"``, ``"normal from the Monte Carlo estimate and u"``,
        ``"GUM, normal"`` or ``"GUM, t with ν_eff = ..."``.
    """
    tl, tu = _limits(lower, upper)
    pr = _probability(result, tl, tu)
    return pr.p_c, pr.error, pr.basis


# ------------------------------------------------------------------ acceptance limits
def _acceptance_for_risk(
    pr: _Probability, tl: float, tu: float, alpha: float
) -> tuple[float, float]:
    """Acceptance limits where ``p_c`` of the translated PDF equals ``1 - α``.

    ``A_U`` is the largest estimate in ``[mid, T_U]`` whose ``p_c >= 1 - α``, ``A_L`` the
    smallest in ``[T_L, mid]`` (JCGM 106 §8.3, the guard band of a required conformance
    probability); ``mid`` is the centre of a two-sided tolerance, and for a single limit
    an estimate so far inside it (50 u, and the whole spread of the values) that
    ``p_c = 1`` there. For a closed form the root of ``p_c(A) = 1 - α`` is found by Brent's
    method to the last bits; for Monte Carlo values ``p_c(A)`` is a step function and
    the limit is found by bisection down to two adjacent doubles. Returns ``(nan, nan)``
    when no estimate reaches ``1 - α`` (the tolerance is too narrow for ``u``).
    """
    target = 1.0 - alpha
    span = max(pr.u, 1e-300)
    if math.isfinite(tl) and math.isfinite(tu):
        mid = 0.5 * (tl + tu)
    elif math.isfinite(tu):
        mid = tu - 50.0 * span - (pr.empirical.values[-1] - pr.estimate if pr.empirical else 0.0)
    else:
        mid = tl + 50.0 * span + (pr.estimate - pr.empirical.values[0] if pr.empirical else 0.0)
    if pr.shifted(mid, tl, tu) < target:
        return math.nan, math.nan

    def ok(a: float) -> bool:
        return pr.shifted(a, tl, tu) >= target

    def search(good: float, bad: float) -> float:
        if pr.empirical is None:
            from scipy.optimize import brentq

            def f(a: float) -> float:
                return pr.shifted(a, tl, tu) - target

            scale = max(abs(good), abs(bad), span)
            root = float(
                brentq(
                    f,
                    good,
                    bad,
                    xtol=1e-15 * scale,
                    rtol=4 * float(np.finfo(float).eps),
                    maxiter=500,
                )
            )
            # the side of the root where the rule holds (a few ulp at most)
            for _ in range(64):
                if ok(root):
                    break
                root = float(np.nextafter(root, good))
            return root
        for _ in range(_MAX_BISECTIONS):
            m = 0.5 * (good + bad)
            if m in (good, bad):
                break
            if ok(m):
                good = m
            else:
                bad = m
        return good

    a_u = search(mid, tu) if math.isfinite(tu) else math.inf
    a_l = search(mid, tl) if math.isfinite(tl) else -math.inf
    return a_l, a_u


# ------------------------------------------------------------------------ the results
@dataclass(frozen=True)
class GlobalRisks:
    """The global consumer's and producer's risks of a decision rule (JCGM 106 §9.5).

    Attributes
    ----------
    consumer : float
        ``R_C``: the probability that an item of the process is non-conforming and
        accepted (JCGM 106 §9.5).
    producer : float
        ``R_P``: the probability that an item is conforming and rejected (§9.5).
    prior_mean, prior_sd : float
        ``y_0`` and ``u_0`` of the normal prior ``g_0`` of the measurand (§9).
    u_m : float
        Standard uncertainty of the normal measurement model ``h(η_m | η)`` (§9).
    prior_conformance : float
        ``p_0 = Pr(T_L <= Y <= T_U)`` under the prior alone.
    capability : float or None
        The measurement capability index ``C_m = (T_U - T_L)/(4 u_m)`` (JCGM 106
        §7), for a two-sided tolerance.
    """

    consumer: float
    producer: float
    prior_mean: float
    prior_sd: float
    u_m: float
    prior_conformance: float
    capability: float | None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "consumer": self.consumer,
            "producer": self.producer,
            "prior_mean": self.prior_mean,
            "prior_sd": self.prior_sd,
            "u_m": self.u_m,
            "prior_conformance": self.prior_conformance,
            "capability": self.capability,
        }


def global_risks(
    lower: float | None,
    upper: float | None,
    *,
    u_m: float,
    prior_mean: float,
    prior_sd: float,
    acceptance: tuple[float | None, float | None] | None = None,
) -> GlobalRisks:
    """Global consumer's and producer's risks for a normal process and measurement.

    ``R_C = ∫_{η ∉ C} g_0(η) P_A(η) dη`` and ``R_P = ∫_{η ∈ C} g_0(η) (1 - P_A(η)) dη``
    with ``g_0 = N(y_0, u_0²)`` the prior of the measurand, ``C = [T_L, T_U]`` and
    ``P_A(η) = Φ((A_U - η)/u_m) - Φ((A_L - η)/u_m)`` the probability that a measurement
    of an item of true value ``η`` is accepted: the inner integral of the double
    integrals of JCGM 106 §9.5, in closed form. The outer integral is
    taken by ``scipy.integrate.quad`` over ``y_0 ± 12 u_0`` (the prior mass outside is
    below ``10⁻³²``), cut at the tolerance and acceptance limits.

    Parameters
    ----------
    lower, upper : float or None
        Tolerance limits (at least one).
    u_m : float
        Standard uncertainty of the measurement, ``> 0``.
    prior_mean, prior_sd : float
        ``y_0`` and ``u_0 > 0``.
    acceptance : (float or None, float or None), optional
        ``(A_L, A_U)``; default the tolerance limits (simple acceptance). ``(nan, nan)``:
        nothing is accepted.

    Returns
    -------
    GlobalRisks
    """
    from scipy import integrate, stats

    tl, tu = _limits(lower, upper)
    um = _number(u_m, "u_m")
    y0 = _number(prior_mean, "prior.mean")
    u0 = _number(prior_sd, "prior.sd")
    if not um > 0:
        raise InputError(f"expected u_m > 0, got {u_m!r}", field="u_m")
    if not u0 > 0:
        raise InputError(f"expected a prior sd > 0, got {prior_sd!r}", field="prior.sd")
    if acceptance is None:
        al, au = tl, tu
    else:
        al = -math.inf if acceptance[0] is None else float(acceptance[0])
        au = math.inf if acceptance[1] is None else float(acceptance[1])
    p0 = normal_conformance_probability(y0, u0, _opt(tl), _opt(tu))
    cm = (tu - tl) / (4.0 * um) if math.isfinite(tl) and math.isfinite(tu) else None
    if math.isnan(al) or math.isnan(au):  # nothing accepted
        return GlobalRisks(0.0, p0, y0, u0, um, p0, cm)
    norm = stats.norm

    def accepted(eta: float) -> float:
        return float(norm.cdf((au - eta) / um) - norm.cdf((al - eta) / um))

    def rc(eta: float) -> float:
        return float(norm.pdf(eta, y0, u0)) * accepted(eta)

    def rp(eta: float) -> float:
        return float(norm.pdf(eta, y0, u0)) * (1.0 - accepted(eta))

    lo, hi = y0 - 12.0 * u0, y0 + 12.0 * u0
    breaks = sorted(
        {x for x in (al, au, al - 6 * um, au + 6 * um) if lo < x < hi and math.isfinite(x)}
    )

    def piece(f: Any, a: float, b: float) -> float:
        a, b = max(a, lo), min(b, hi)
        if not a < b:
            return 0.0
        pts = [x for x in breaks if a < x < b]
        val = integrate.quad(f, a, b, points=pts or None, limit=200, epsabs=1e-16, epsrel=1e-12)[0]
        return float(val)

    consumer = piece(rc, -math.inf, tl) + piece(rc, tu, math.inf)
    producer = piece(rp, tl, tu)
    return GlobalRisks(consumer, producer, y0, u0, um, p0, cm)


def _prior_pair(prior: object) -> tuple[float, float]:
    if isinstance(prior, Mapping):
        if set(prior) != {"mean", "sd"}:
            raise InputError(
                f"expected a prior with keys mean and sd, got keys {sorted(prior)}", field="prior"
            )
        return _number(prior["mean"], "prior.mean"), _number(prior["sd"], "prior.sd")
    if isinstance(prior, tuple | list) and len(prior) == 2:
        return _number(prior[0], "prior.mean"), _number(prior[1], "prior.sd")
    if isinstance(prior, Normal):
        return float(prior.mean), float(prior.std)
    raise InputError(
        f"expected a prior (mean, sd), {{'mean': ..., 'sd': ...}} or a Normal, got {prior!r}",
        field="prior",
    )


def _format_p(p: float) -> str:
    """A probability to the digits that show its distance from 0 or 1 (two of them)."""
    q = min(p, 1.0 - p)
    if q <= 0:
        return f"{p:.0f}"
    digits = max(3, min(12, 1 - math.floor(math.log10(q))))
    return f"{p:.{digits}f}"


def _g(x: float) -> str:
    return f"{x:.3g}"


@dataclass(frozen=True)
class Conformity:
    """A conformity decision with its probability and risks (JCGM 106 §7–§9).

    Attributes
    ----------
    lower, upper : float or None
        Tolerance limits ``T_L``, ``T_U`` (None: no limit on that side).
    estimate, u : float
        The measurement's estimate ``y`` and standard uncertainty ``u(y)``.
    p_c : float
        Conformance probability (JCGM 106 §7).
    p_c_error : float
        Its standard error (kept Monte Carlo values), bound (a sketch) or 0 (a closed
        form): see :func:`conformance_probability`.
    basis : str
        What ``p_c`` was computed from (:func:`conformance_probability`).
    rule : {"simple", "guarded"}
        Simple acceptance (JCGM 106 §8.2) or guarded acceptance (§8.3).
    guard : float or None
        ``r`` of a guard band ``w = r U`` (given, or, with ``max_consumer_risk``, the
        ``w/U`` that results).
    max_consumer_risk : float or None
        ``α``: accept when the specific consumer's risk ``1 - p_c <= α``.
    coverage_factor : float
        ``k`` of ``U = k u`` (2, JCGM 106 §8.3).
    guard_lower, guard_upper : float or None
        The guard bands ``w_L = A_L - T_L`` and ``w_U = T_U - A_U``.
    acceptance_lower, acceptance_upper : float
        ``A_L`` and ``A_U`` (``∓inf`` without that limit; NaN when no estimate can be
        accepted at this ``u``).
    conforms : bool
        The decision: accepted as conforming.
    consumer_risk : float or None
        Specific consumer's risk ``R*_C = 1 - p_c`` of an accepted item (JCGM 106 §9.3).
    producer_risk : float or None
        Specific producer's risk ``R*_P = p_c`` of a rejected item (§9.3).
    global_risks : GlobalRisks or None
        ``R_C`` and ``R_P`` of the rule for the process (§9.5), where a prior was given.
    guard_band : float or None
        The guard band ``w`` where it was given as a width (in the unit of the result)
        rather than as ``r`` of ``w = r U``.
    """

    lower: float | None
    upper: float | None
    estimate: float
    u: float
    p_c: float
    p_c_error: float
    basis: str
    rule: Rule
    guard: float | None
    max_consumer_risk: float | None
    coverage_factor: float
    guard_lower: float | None
    guard_upper: float | None
    acceptance_lower: float
    acceptance_upper: float
    conforms: bool
    consumer_risk: float | None
    producer_risk: float | None
    global_risks: GlobalRisks | None = None
    guard_band: float | None = None

    @property
    def decision(self) -> str:
        """``"conforms"`` or ``"does not conform"``."""
        return "conforms" if self.conforms else "does not conform"

    @property
    def expanded_uncertainty(self) -> float:
        """``U = k u`` that the guard band is measured in."""
        return self.coverage_factor * self.u

    @property
    def text(self) -> str:
        """One line: ``conforms, p_c = 0.998, rule: guarded acceptance, w = 0.5·U``."""
        head = f"{self.decision}, p_c = {_format_p(self.p_c)}"
        if self.rule == "simple":
            return f"{head}, rule: simple acceptance"
        if self.guard_band is not None:
            return f"{head}, rule: guarded acceptance, w = {_g(self.guard_band)}"
        if self.max_consumer_risk is None:
            return f"{head}, rule: guarded acceptance, w = {_g(self.guard or 0.0)}·U"
        bound = f"R*_C ≤ {_g(self.max_consumer_risk)}"
        if self.guard is None:
            return f"{head}, rule: guarded acceptance, {bound} (no estimate can be accepted)"
        return f"{head}, rule: guarded acceptance, {bound} (w = {_g(self.guard)}·U)"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (infinite or undefined acceptance limits as None)."""

        def fin(x: float) -> float | None:
            return x if math.isfinite(x) else None

        return {
            "decision": self.decision,
            "conforms": self.conforms,
            "text": self.text,
            "lower": self.lower,
            "upper": self.upper,
            "estimate": self.estimate,
            "u": self.u,
            "p_c": self.p_c,
            "p_c_error": self.p_c_error,
            "basis": self.basis,
            "rule": self.rule,
            "guard": self.guard,
            "max_consumer_risk": self.max_consumer_risk,
            "coverage_factor": self.coverage_factor,
            "U": self.expanded_uncertainty,
            "guard_lower": self.guard_lower,
            "guard_upper": self.guard_upper,
            "acceptance": [fin(self.acceptance_lower), fin(self.acceptance_upper)],
            "consumer_risk": self.consumer_risk,
            "producer_risk": self.producer_risk,
            "global_risks": None if self.global_risks is None else self.global_risks.to_dict(),
            "guard_band": self.guard_band,
        }


def conformity(
    result: ScalarResult,
    lower: float | None = None,
    upper: float | None = None,
    *,
    rule: Rule = "simple",
    guard: float | None = None,
    max_consumer_risk: float | None = None,
    prior: Prior | None = None,
    coverage_factor: float = GUARD_COVERAGE_FACTOR,
    guard_band: float | None = None,
    estimate: float | None = None,
) -> Conformity:
    """Decide whether a measured quantity conforms to its tolerance (JCGM 106 §7–§9).

    Parameters
    ----------
    result : MonteCarloResult or GumResult
        A scalar result: the PDF of the measurand after the measurement.
    lower, upper : float, optional
        Tolerance limits ``T_L`` and ``T_U``; at least one.
    rule : {"simple", "guarded"}, default "simple"
        ``"simple"``: accept when ``T_L <= y <= T_U`` (JCGM 106 §8.2).
        ``"guarded"``: accept when ``A_L <= y <= A_U``, ``A_L = T_L + w``,
        ``A_U = T_U - w`` (§8.3), with ``w = r U`` from ``guard = r``, or, with
        ``max_consumer_risk = α``, accept when ``p_c >= 1 - α`` (the specific consumer's
        risk of an accepted item at most ``α``, §9.3); the acceptance limits are then
        the estimates at which the result's PDF, translated, has ``p_c = 1 - α``.
    guard : float, optional
        ``r`` of ``w = r U``; negative for guarded rejection (§8.3).
    max_consumer_risk : float, optional
        ``α``, ``0 < α < 0.5``.
    prior : (mean, sd), mapping or Normal, optional
        The process: a normal prior ``g_0`` of the measurand (JCGM 106 §9); gives
        :attr:`Conformity.global_risks` for the normal measurement model with
        ``u_m = u(y)`` (§9), whatever the basis of ``p_c``.
    coverage_factor : float, default 2
        ``k`` of ``U = k u`` (JCGM 106 §8.3).
    guard_band : float, optional
        The guard band ``w`` itself, in the unit of the result (a test's own width, or
        the ``U`` of a coverage interval), instead of ``guard``; negative for guarded
        rejection.
    estimate : float, optional
        The measured value that the rule compares with the acceptance interval, where
        it is not the result's own estimate (the value a standard defines from the
        readings, beside a Monte Carlo PDF whose mean lies elsewhere); ``p_c`` is always
        that of the result's PDF.

    Returns
    -------
    Conformity

    Raises
    ------
    InputError
        For a vector result, absent or crossed limits, an unknown rule, a rule with a
        missing or an extra parameter, a guard band that leaves no acceptance interval.
    """
    tl, tu = _limits(lower, upper)
    if rule not in ("simple", "guarded"):
        raise InputError(f"expected rule 'simple' or 'guarded', got {rule!r}", field="rule")
    k = _number(coverage_factor, "coverage_factor")
    if not k > 0:
        raise InputError(
            f"expected a coverage factor > 0, got {coverage_factor!r}", field="coverage_factor"
        )
    r: float | None = None
    alpha: float | None = None
    w_given: float | None = None
    if rule == "simple":
        for name, value in (
            ("guard", guard),
            ("guard_band", guard_band),
            ("max_consumer_risk", max_consumer_risk),
        ):
            if value is not None:
                raise InputError(
                    f"{name} needs rule = 'guarded'; simple acceptance has none", field=name
                )
    else:
        given = [g for g in (guard, guard_band, max_consumer_risk) if g is not None]
        if len(given) != 1:
            raise InputError(
                "guarded acceptance needs one of guard (r of w = r·U), guard_band (w) or "
                "max_consumer_risk",
                field="guard",
            )
        if guard_band is not None:
            w_given = _number(guard_band, "guard_band")
        elif guard is not None:
            r = _number(guard, "guard")
        else:
            alpha = _number(max_consumer_risk, "max_consumer_risk")
            if not 0.0 < alpha < 0.5:
                raise InputError(
                    f"expected 0 < max_consumer_risk < 0.5, got {max_consumer_risk!r}",
                    field="max_consumer_risk",
                )
    pr = _probability(result, tl, tu)
    y = pr.estimate if estimate is None else _number(estimate, "estimate")
    u = pr.u
    big_u = k * u
    if alpha is not None:
        al, au = _acceptance_for_risk(pr, tl, tu, alpha)
        conforms = pr.p_c >= 1.0 - alpha
    else:
        w = w_given if w_given is not None else (0.0 if r is None else r * big_u)
        al, au = tl + w, tu - w
        if not al <= au:
            raise InputError(
                f"the guard band w = {w:.6g} (r = {r}, U = {big_u:.6g}) leaves no acceptance "
                f"interval in [{tl:.6g}, {tu:.6g}]",
                field="guard",
            )
        conforms = al <= y <= au
    w_l = al - tl if math.isfinite(tl) and math.isfinite(al) else None
    w_u = tu - au if math.isfinite(tu) and math.isfinite(au) else None
    if (alpha is not None or w_given is not None) and big_u > 0:
        w_main = w_u if w_u is not None else w_l
        r = None if w_main is None else w_main / big_u
    risks = None
    if prior is not None:
        y0, u0 = _prior_pair(prior)
        risks = global_risks(
            _opt(tl), _opt(tu), u_m=u, prior_mean=y0, prior_sd=u0, acceptance=(al, au)
        )
    return Conformity(
        lower=_opt(tl),
        upper=_opt(tu),
        estimate=y,
        u=u,
        p_c=pr.p_c,
        p_c_error=pr.error,
        basis=pr.basis,
        rule=rule,
        guard=r,
        max_consumer_risk=alpha,
        coverage_factor=k,
        guard_lower=w_l,
        guard_upper=w_u,
        acceptance_lower=al,
        acceptance_upper=au,
        conforms=bool(conforms),
        consumer_risk=1.0 - pr.p_c if conforms else None,
        producer_risk=pr.p_c if not conforms else None,
        global_risks=risks,
        guard_band=w_given,
    )
