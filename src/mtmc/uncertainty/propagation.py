"""The GUM uncertainty framework (JCGM 100) and its validation by Monte Carlo (JCGM 101 §8).

:func:`gum` applies the law of propagation of uncertainty (JCGM 100 §5.1.2, §5.2.2 for
correlated inputs; JCGM 102 §6.2 for vector outputs) to the same vectorised model that
:func:`mtmc.monte_carlo` runs, with sensitivity coefficients computed numerically from
the model itself (complex step, or central differences where the model is not
complex-safe). The effective degrees of freedom come from the Welch–Satterthwaite
formula (JCGM 100 G.4.1) and the coverage factor from the t-distribution (G.3, G.4).

:func:`validate` compares the GUM interval with a Monte Carlo coverage interval as
JCGM 101 §8.2 prescribes and says whether the GUM is validated at a numerical tolerance.

Examples
--------
>>> from mtmc import Normal, expression
>>> r = gum(expression("a * b"), {"a": Normal(2.0, 0.1), "b": Normal(3.0, 0.2)})
>>> round(r.estimate, 12), round(r.u, 12)  # u² = (3 · 0.1)² + (2 · 0.2)² = 0.25
(6.0, 0.5)
>>> r.method
'complex-step'
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import InputError
from mtmc.frozen import frozen_value
from mtmc.uncertainty import copula as _copula
from mtmc.uncertainty import distributions as _distributions
from mtmc.uncertainty import tolerance as _tolerance
from mtmc.uncertainty import typea as _typea
from mtmc.uncertainty.checks import check_probability
from mtmc.uncertainty.formula import check_components, check_variables
from mtmc.uncertainty.results import MonteCarloResult

if TYPE_CHECKING:
    from mtmc.uncertainty.decision import Conformity

__all__ = [
    "BudgetEntry",
    "GumResult",
    "Validation",
    "NOISE_MARGIN",
    "ROUNDING_SPREAD",
    "coverage_factor",
    "endpoint_std_error",
    "one_value",
    "gum",
    "output_pdf",
    "validate",
    "welch_satterthwaite",
]

# Step sizes, relative to the standard uncertainty of each input component.
_COMPLEX_STEP = 1e-20
_CENTRAL_STEP = 1e-3
# Complex-step and central-difference sensitivities must agree to this fraction of the
# output's standard uncertainty, or the model is taken as not complex-safe.
_AGREEMENT = 1e-5


@dataclass(frozen=True)
class BudgetEntry:
    """One line of the uncertainty budget (as JCGM 100 Table H.1 lays it out).

    Attributes
    ----------
    name : str
        The input quantity.
    estimate : ndarray, shape (k,)
        Its estimate ``x`` (the expectation of its PDF); ``k = 1`` for a scalar input.
    u : ndarray, shape (k,)
        Its standard uncertainty ``u(x)``, per component.
    sensitivity : ndarray, shape (d, k)
        ``c = ∂f/∂x`` at the estimates, one row per output component (``d = 1`` for a
        scalar output), one column per input component: ``sensitivity[0, 0]`` for a
        scalar input and output.
    contribution : ndarray, shape (d,)
        ``|c| u(x)`` (for a vector input, ``sqrt(c V cᵀ)`` with V its covariance).
    share : ndarray, shape (d,)
        Its part of ``u²(y)``: ``contribution² / u²(y)`` (0 where ``u(y) = 0``).

    Every array is a read-only copy.
    dof : float
        Degrees of freedom of ``u(x)`` (``inf`` if exactly known).
    """

    name: str
    estimate: NDArray[np.float64]
    u: NDArray[np.float64]
    sensitivity: NDArray[np.float64]
    contribution: NDArray[np.float64]
    share: NDArray[np.float64]
    dof: float

    def __post_init__(self) -> None:
        for name, ndim in (
            ("estimate", 1),
            ("u", 1),
            ("sensitivity", 2),
            ("contribution", 1),
            ("share", 1),
        ):
            arr = np.array(getattr(self, name), dtype=np.float64)
            if arr.ndim != ndim:
                raise InputError(
                    f"expected {name} of {ndim} dimension(s), got shape {arr.shape}",
                    field=name,
                )
            object.__setattr__(self, name, frozen_value(arr))


@dataclass(frozen=True)
class GumResult:
    """Result of the GUM uncertainty framework for one (scalar or vector) output.

    Every attribute has one type: the arrays ``estimate_vector``, ``u_vector`` and
    ``dof_vector`` have shape ``(d,)`` for an output of ``d`` components (``(1,)`` for a
    scalar output); ``estimate``, ``u`` and ``dof`` are the floats of a scalar output (an
    :class:`~mtmc.errors.InputError` for a vector one), and so are
    :meth:`coverage_factor` and :meth:`expanded_uncertainty`, :meth:`coverage_interval` a
    pair of floats. Every array of the result is a read-only copy. The three coverage
    methods and the attribute names are those of
    :class:`~mtmc.uncertainty.results.MonteCarloResult`.

    Attributes
    ----------
    estimate_vector : ndarray, shape (d,)
        ``y = f(x)`` at the input estimates (JCGM 100 §4.1.4).
    u_vector : ndarray, shape (d,)
        Standard uncertainty ``u(y)`` of each component (JCGM 100 eq. (10), (13)).
    cov : ndarray, shape (d, d)
        Covariance ``U_y = C U_x Cᵀ`` (JCGM 102 §6.2); ``(1, 1)`` for a scalar output.
    dof_vector : ndarray, shape (d,)
        Effective degrees of freedom of each component by Welch–Satterthwaite
        (JCGM 100 eq. (G.2b)), not rounded (``inf`` where every input is exactly known).
    p : float
        Coverage probability of :func:`gum`, the default of the coverage methods.
    sensitivities : mapping of str to ndarray, shape (d, k)
        ``name -> c = ∂f/∂x`` for each input (as :attr:`BudgetEntry.sensitivity`),
        read-only.
    budget : tuple of BudgetEntry
        One entry per input, in the order of ``inputs``.
    method : str
        ``"complex-step"`` or ``"central-difference"``: how ``c`` was computed.
    scalar : bool
        Whether the output is a scalar (the model returned ``(m,)``) rather than a
        vector (``(m, d)``, even with ``d = 1``).
    """

    estimate_vector: NDArray[np.float64]
    u_vector: NDArray[np.float64]
    cov: NDArray[np.float64]
    dof_vector: NDArray[np.float64]
    p: float
    sensitivities: Mapping[str, NDArray[np.float64]]
    budget: tuple[BudgetEntry, ...]
    method: str
    scalar: bool = True

    def __post_init__(self) -> None:
        # read-only copies: arrays cannot be written, ``sensitivities`` gains no keys
        for name in ("estimate_vector", "u_vector", "dof_vector"):
            arr = np.atleast_1d(np.array(getattr(self, name), dtype=np.float64))
            object.__setattr__(self, name, arr)
        for name in ("estimate_vector", "u_vector", "cov", "dof_vector", "sensitivities", "budget"):
            object.__setattr__(self, name, frozen_value(getattr(self, name)))
        if self.scalar and self.estimate_vector.shape != (1,):
            raise InputError("a scalar output has one component", field="scalar")

    @property
    def dim(self) -> int:
        """0 for a scalar output, ``d`` for a vector output."""
        return 0 if self.scalar else int(self.estimate_vector.shape[0])

    def _scalar_value(self, name: str) -> float:
        if not self.scalar:
            raise InputError(
                f"{name} is the float of a scalar output; this one has d = {self.dim} "
                f"components: use {name}_vector (shape (d,)) or component(i)",
                field=name,
            )
        return float(getattr(self, f"{name}_vector")[0])

    @property
    def estimate(self) -> float:
        """``y = f(x)`` of a scalar output (JCGM 100 §4.1.4), a float.

        Raises
        ------
        InputError
            For a vector output: its estimate is :attr:`estimate_vector`.
        """
        return self._scalar_value("estimate")

    @property
    def u(self) -> float:
        """Standard uncertainty ``u(y)`` of a scalar output (JCGM 100 eq. (10)), a float.

        Raises
        ------
        InputError
            For a vector output: its standard uncertainties are :attr:`u_vector`.
        """
        return self._scalar_value("u")

    @property
    def dof(self) -> float:
        """Effective degrees of freedom ``ν_eff`` of a scalar output (JCGM 100 eq. (G.2b)).

        Raises
        ------
        InputError
            For a vector output: its degrees of freedom are :attr:`dof_vector`.
        """
        return self._scalar_value("dof")

    def component(self, i: int) -> GumResult:
        """The scalar result of component ``i`` of a vector output.

        Parameters
        ----------
        i : int
            Index of the component, ``0 <= i < d``.

        Returns
        -------
        GumResult
            Scalar: ``y_i``, ``u(y_i)``, ``ν_eff,i``, the sensitivities ``∂f_i/∂x`` and the
            budget lines of component ``i``; the same ``p`` and method.

        Raises
        ------
        InputError
            For a scalar output, or ``i`` out of range.
        """
        if self.scalar:
            raise InputError("component() needs a vector output", field="scalar")
        if not -self.dim <= i < self.dim:
            raise InputError(f"expected 0 <= i < {self.dim}, got {i}", field="i")
        j = i % self.dim
        return GumResult(
            estimate_vector=self.estimate_vector[j : j + 1],
            u_vector=self.u_vector[j : j + 1],
            cov=self.cov[j : j + 1, j : j + 1],
            dof_vector=self.dof_vector[j : j + 1],
            p=self.p,
            sensitivities={n: c[j : j + 1] for n, c in self.sensitivities.items()},
            budget=tuple(
                dataclasses.replace(
                    e,
                    sensitivity=e.sensitivity[j : j + 1],
                    contribution=e.contribution[j : j + 1],
                    share=e.share[j : j + 1],
                )
                for e in self.budget
            ),
            method=self.method,
            scalar=True,
        )

    def coverage_factor(self, p: float | None = None) -> float:
        """The coverage factor ``k_p`` with ``U_p = k_p u(y)`` (JCGM 100 G.3.2, G.4.1).

        Parameters
        ----------
        p : float, optional
            Coverage probability; default: the ``p`` of the result.

        Returns
        -------
        float
            ``t_{(1+p)/2}(⌊ν_eff⌋)`` (:func:`coverage_factor`), the normal quantile when
            ``ν_eff`` is infinite.

        Raises
        ------
        InputError
            For a vector output (see :meth:`component`).
        """
        return coverage_factor(self.p if p is None else p, self.dof)

    def expanded_uncertainty(self, p: float | None = None) -> float:
        """The expanded uncertainty ``U_p = k_p u(y)`` (JCGM 100 §6.2.1).

        Parameters
        ----------
        p : float, optional
            Coverage probability; default: the ``p`` of the result.

        Returns
        -------
        float

        Raises
        ------
        InputError
            For a vector output (see :meth:`component`).
        """
        return self.coverage_factor(p) * self.u

    def coverage_interval(self, p: float | None = None) -> tuple[float, float]:
        """The coverage interval ``(y - U_p, y + U_p)`` (JCGM 100 §6.2.1).

        Parameters
        ----------
        p : float, optional
            Coverage probability; default: the ``p`` of the result.

        Returns
        -------
        (float, float)
            ``(y_low, y_high)``.

        Raises
        ------
        InputError
            For a vector output (see :meth:`component`).
        """
        big_u = self.expanded_uncertainty(p)
        return self.estimate - big_u, self.estimate + big_u

    def conformity(
        self,
        lower: float | None = None,
        upper: float | None = None,
        *,
        rule: Literal["simple", "guarded"] = "simple",
        guard: float | None = None,
        max_consumer_risk: float | None = None,
        prior: Any = None,
        coverage_factor: float = 2.0,
    ) -> Conformity:
        """The conformity decision for tolerance limits (JCGM 106:2012).

        :func:`mtmc.uncertainty.decision.conformity` of this result: ``p_c`` from the
        normal PDF of ``estimate`` and ``u``, or the t PDF scaled by ``u`` for a finite
        ``ν_eff`` (JCGM 100 G.3).

        Returns
        -------
        Conformity
        """
        from mtmc.uncertainty.decision import conformity

        return conformity(
            self,
            lower,
            upper,
            rule=rule,
            guard=guard,
            max_consumer_risk=max_consumer_risk,
            prior=prior,
            coverage_factor=coverage_factor,
        )


@dataclass(frozen=True)
class Validation:
    """Outcome of the JCGM 101 §8.2 comparison of the GUM with Monte Carlo.

    Attributes
    ----------
    d_low, d_high : float
        ``|y - U_p - y_low|`` and ``|y + U_p - y_high|`` (JCGM 101 §8.2).
    delta : float
        Numerical tolerance δ of ``u(y)`` at ``ndig`` significant digits (§7.9.2).
    passed : bool
        True iff ``d_low <= delta`` and ``d_high <= delta``.
    p : float
        Coverage probability compared.
    kind : str
        Kind of Monte Carlo interval used: ``"symmetric"`` or ``"shortest"``.
    ndig : int
        Significant digits of ``u(y)`` regarded as meaningful.
    """

    d_low: float
    d_high: float
    delta: float
    passed: bool
    p: float = 0.95
    kind: str = "symmetric"
    ndig: int = 2

    def verdict(self, noise: float) -> str:
        """The verdict of the comparison, with the Monte Carlo noise of its endpoints.

        ``"validated"`` where it passed; ``"not validated"`` where ``d_low`` or ``d_high``
        exceeds δ by more than :data:`NOISE_MARGIN` times ``noise``, the standard error
        of a Monte Carlo endpoint (:func:`endpoint_std_error`); otherwise
        ``"not validated within Monte Carlo noise"``: more trials could still pass it.

        Examples
        --------
        >>> v = Validation(d_low=0.001, d_high=0.007, delta=0.005, passed=False)
        >>> v.verdict(noise=0.001), v.verdict(noise=0.0005)
        ('not validated within Monte Carlo noise', 'not validated')
        """
        if self.passed:
            return "validated"
        if max(self.d_low, self.d_high) > self.delta + NOISE_MARGIN * noise:
            return "not validated"
        return "not validated within Monte Carlo noise"


#: How many endpoint standard errors (:func:`endpoint_std_error`) a ``d`` of the JCGM 101
#: §8 comparison must exceed δ by for the GUM to be "not validated" outright.
NOISE_MARGIN = 3.0


#: A standard uncertainty at most this many units in the last place of the estimate
#: (``ε |y|``) is the rounding of the arithmetic, not a spread of the quantity.
ROUNDING_SPREAD = 16.0


def one_value(u_mc: float, u_gum: float, estimate: float) -> bool:
    """Whether both methods give one value, so that the JCGM 101 §8 comparison is moot.

    The GUM's ``u`` is zero and the Monte Carlo's is zero or the rounding of its
    arithmetic: at most :data:`ROUNDING_SPREAD` · ``ε |y|`` (``ε`` the double precision's
    machine epsilon). Such an output has no coverage interval to compare (δ of JCGM 101
    §7.9.2 is zero or below the rounding of ``y``): a parameter of an ISO 230-2 test
    computed from the readings alone, whose Monte Carlo values differ in the last bits
    only (``u = 4.4·10⁻¹⁶`` µm at ``y = 3.05`` µm), or an angle fixed by the graph.

    Examples
    --------
    >>> one_value(0.0, 0.0, 3.05), one_value(4.4e-16, 0.0, 3.05), one_value(1e-9, 0.0, 3.05)
    (True, True, False)
    >>> one_value(4.4e-16, 1e-3, 3.05)
    False
    """
    if u_gum > 0 or not math.isfinite(u_mc):
        return False
    return bool(u_mc <= ROUNDING_SPREAD * float(np.finfo(np.float64).eps) * abs(estimate))


def endpoint_std_error(u: float, m: int, p: float) -> float:
    """Standard error of an endpoint of a Monte Carlo ``100p %`` interval, normal output.

    The ``α = (1 - p)/2`` quantile of ``M`` draws from a PDF ``g`` has the asymptotic
    variance ``α(1 - α) / (M g(η_α)²)`` (order statistics); for a normal output of
    standard deviation ``u``, ``g(η_α) = φ(z_α)/u``. The JCGM 101 §8 comparison is only
    as sharp as this: where ``d_low`` or ``d_high`` exceeds δ by less than
    :data:`NOISE_MARGIN` of these, the verdict may be Monte Carlo noise
    (:meth:`Validation.verdict`).

    Examples
    --------
    >>> round(endpoint_std_error(1.0, 10**6, 0.95), 5)
    0.00267
    """
    from scipy.stats import norm

    a = (1.0 - p) / 2.0
    return float(u * math.sqrt(a * (1.0 - a) / m) / norm.pdf(norm.ppf(a)))


def coverage_factor(p: float, dof: float) -> float:
    """Coverage factor ``k_p`` for coverage probability ``p`` (JCGM 100 G.3.2, G.4.1).

    Parameters
    ----------
    p : float
        Coverage probability, ``0 < p < 1``.
    dof : float
        Effective degrees of freedom ν_eff (``inf`` for a normal output). A finite ν_eff
        is truncated to the next lower integer (at least 1) before ``t`` is looked up,
        as JCGM 100 G.4.1 allows and the worked example H.1 does.

    Returns
    -------
    float
        ``t_{(1+p)/2}(⌊ν⌋)``, or the standard normal quantile ``z_{(1+p)/2}``.

    Raises
    ------
    InputError
        If ``p`` is not in (0, 1) or ``dof`` is not positive.

    Examples
    --------
    >>> round(coverage_factor(0.95, 16.7), 2)  # GUM H.1: ν_eff = 16 -> k = 2.12
    2.12
    >>> round(coverage_factor(0.95, math.inf), 4)
    1.96
    >>> round(coverage_factor(0.95, 1e300), 4)  # ν_eff of an input far larger than the rest
    1.96
    """
    p = check_probability(p)
    if not dof > 0:
        raise InputError(f"expected positive degrees of freedom, got {dof}", field="dof")
    from scipy import stats  # imported here: scipy.stats costs ~0.5 s at import

    q = 0.5 * (1.0 + p)
    if math.isinf(dof):
        return float(stats.norm.ppf(q))
    # as a float: the floor of a huge ν is an integer too large for SciPy's t
    return float(stats.t.ppf(q, max(1.0, float(math.floor(dof)))))


def output_pdf(
    x: npt.ArrayLike, estimate: float, u: float, dof: float | None = None
) -> NDArray[np.float64]:
    """The PDF the GUM gives the output, at the values ``x`` (JCGM 100 §G.6).

    The normal PDF of ``y ± u`` for ``ν_eff = ∞`` (``dof`` None), else the t PDF of
    ``ν_eff`` degrees of freedom scaled by ``u`` and shifted to ``y`` (JCGM 100 §G.6.4;
    ``ν_eff`` as it is, not its floor: the curve drawn beside a Monte Carlo histogram).

    Parameters
    ----------
    x : array_like
        Values of the output.
    estimate, u : float
        ``y`` and ``u(y) > 0``.
    dof : float or None
        ``ν_eff``; None: infinite.

    Returns
    -------
    ndarray
        The density at ``x`` (per unit of ``x``).
    """
    from scipy import stats  # imported here: scipy.stats costs ~0.5 s at import

    if dof is None:
        return np.asarray(stats.norm.pdf(x, estimate, u), dtype=np.float64)
    return np.asarray(stats.t.pdf(x, dof, estimate, u), dtype=np.float64)


def welch_satterthwaite(variances: npt.ArrayLike, dofs: npt.ArrayLike) -> float:
    """Effective degrees of freedom by the Welch–Satterthwaite formula (JCGM 100 G.4.1).

    ``ν_eff = u⁴(y) / Σ_i u_i⁴(y)/ν_i`` with ``u_i²(y) = c_i² u²(x_i)`` the contributions
    and ``u²(y) = Σ u_i²(y)``. Terms with ``ν_i = inf`` or a zero contribution add
    nothing to the denominator.

    Parameters
    ----------
    variances : array_like, shape (n,)
        The contributions ``u_i²(y)`` (not their square roots).
    dofs : array_like, shape (n,)
        ``ν_i``, positive, ``inf`` allowed.

    Returns
    -------
    float
        ν_eff (``inf`` if every finite-ν term vanishes).

    Raises
    ------
    InputError
        On negative variances, non-positive ν, or mismatched shapes.

    Examples
    --------
    >>> round(welch_satterthwaite([1.0, 1.0], [10, 10]), 6)
    20.0
    """
    var = np.asarray(variances, dtype=np.float64)
    nu = np.asarray(dofs, dtype=np.float64)
    if var.shape != nu.shape or var.ndim != 1:
        raise InputError(
            f"expected variances and dofs of the same shape (n,), got {var.shape} and {nu.shape}"
        )
    if np.any(var < 0) or np.any(~(nu > 0)):
        raise InputError("expected non-negative variances and positive degrees of freedom")
    total = float(var.sum())
    keep = np.isfinite(nu) & (var > 0)
    denom = float(np.sum(var[keep] ** 2 / nu[keep]))
    if denom == 0.0:
        return math.inf
    return total**2 / denom


@dataclass(frozen=True)
class _Input:
    name: str
    dist: Any
    estimate: NDArray[np.float64]  # (k,) with k = 1 for a scalar input
    cov: NDArray[np.float64]  # (k, k)
    dof: float
    scalar: bool


def _gum_input(name: str, obj: Any) -> _Input:
    dist = _distributions.as_distribution(obj, field=name)
    mean = np.atleast_1d(np.asarray(dist.mean, dtype=np.float64))
    stated = _typea.stated_moments(dist)
    if stated is not None:
        # a Type A input, or u with ν (JCGM 100 §4.2, G.4): x̄ and u as stated, not the
        # moments of the PDF that Monte Carlo draws (infinite for ν <= 2)
        mean, cov = stated
    elif isinstance(dist, _distributions.StudentT):
        # JCGM 101 §6.4.9 / JCGM 100 §4.2: the GUM takes u(x) = s/√n (the scale) with
        # ν = n - 1 degrees of freedom; the t PDF's own standard deviation,
        # s/√n · sqrt(ν/(ν-2)), is what Monte Carlo propagates.
        cov = np.array([[dist.scale**2]])
    elif hasattr(dist, "cov"):
        cov = np.asarray(dist.cov, dtype=np.float64)
    else:
        std = np.atleast_1d(np.asarray(dist.std, dtype=np.float64))
        cov = np.diag(std**2)
    if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(cov))):
        raise InputError(
            f"the GUM needs a finite expectation and standard uncertainty; {dist} has "
            f"mean {dist.mean} and standard deviation {dist.std}",
            field=name,
        )
    return _Input(name, dist, mean, cov, float(dist.dof), dist.dim == 0)


def _evaluate(
    model: Callable[..., Any],
    inputs: list[_Input],
    rows: NDArray[Any],
    offsets: list[int],
) -> NDArray[Any]:
    """Call the model once on the stacked rows (R, N) of all input components."""
    kwargs = {}
    for inp, start in zip(inputs, offsets, strict=True):
        block = rows[:, start : start + inp.estimate.size]
        kwargs[inp.name] = block[:, 0] if inp.scalar else block
    out = np.asarray(model(**kwargs))
    if out.ndim not in (1, 2) or out.shape[0] != rows.shape[0]:
        raise InputError(
            f"the model must return shape (m,) or (m, d) for m = {rows.shape[0]} stacked "
            f"trials, got shape {out.shape}",
            field="model",
        )
    return out


def gum(
    model: Callable[..., Any],
    inputs: Mapping[str, Any],
    *,
    p: float = 0.95,
    correlation: Any = None,
) -> GumResult:
    """Propagate standard uncertainties through ``model`` by the GUM (first order).

    The law of propagation of uncertainty (JCGM 100 eq. (10), (13); JCGM 102 §6.2):
    ``U_y = C U_x Cᵀ`` with ``C = ∂f/∂x`` the ``(d, N)`` sensitivity matrix at the input
    estimates and ``U_x`` the ``(N, N)`` input covariance (block diagonal: ``u²(x_i)``
    for a scalar input, the covariance matrix of a multivariate normal input). The
    effective degrees of freedom are ``ν_eff = u⁴(y) / Σ_i u_i⁴(y)/ν_i`` (JCGM 100
    eq. (G.2b)) with ``u_i²(y)`` the contribution of input ``i`` and ``ν_i`` its
    ``dof``; the interval is ``y ± k u(y)`` with ``k`` from :func:`coverage_factor`.

    Sensitivities are computed from the model itself, with every evaluation in one
    batched call (the perturbed points stacked along the trial axis): the complex-step
    derivative ``c_j = Im f(x + i h e_j) / h`` (``h = 10⁻²⁰ u_j``, exact to rounding for a
    model analytic in its inputs), checked against central differences
    ``(f(x + h e_j) - f(x - h e_j)) / 2h`` (``h = 10⁻³ u_j``) evaluated in the same call.
    If the model refuses complex input, or the two disagree by more than 10⁻⁵ u(y)
    (``abs``, ``hypot``, ``arctan2``, a cast to real), the central differences are used
    and ``method`` says so. An :class:`~mtmc.uncertainty.formula.Expression` states
    whether it is complex-safe, and is not checked: its complex step is used as is, or
    it is evaluated once with the central differences only. (The check can reject a
    correct complex step where a callable is strongly non-linear on the scale of
    10⁻³ u; the central differences used then are what ``method`` reports.)

    Parameters
    ----------
    model : callable
        Vectorised model ``model(**arrays)``: each input by name, trial axis first
        (``(m,)`` or ``(m, k)``), returning ``(m,)`` or ``(m, d)``. An
        :class:`~mtmc.uncertainty.formula.Expression` works, as does any NumPy code.
    inputs : mapping of str to Distribution, number or str
        The input quantities (anything :func:`~mtmc.uncertainty.distributions.as_distribution`
        accepts). Estimate = the PDF's expectation; standard uncertainty = its standard
        deviation, except for a scaled-and-shifted t (a Type A evaluation, JCGM 101
        §6.4.9), where the GUM's ``u = s/√n`` (the ``scale``) is used with ``ν = df``,
        for :func:`~mtmc.uncertainty.typea.type_a` (``x̄``, ``u = s/√n``, ``ν = n - 1``)
        and for :func:`~mtmc.uncertainty.typea.with_dof` (the base PDF's moments, ``ν``
        as given): :func:`~mtmc.uncertainty.typea.stated_moments`.
    p : float, default 0.95, keyword-only
        Coverage probability.
    correlation : Correlation or mapping, optional, keyword-only
        Correlation coefficients ``r(x_i, x_j)`` between scalar inputs,
        ``{("a", "b"): 0.8}`` or a :class:`~mtmc.uncertainty.copula.Correlation`: the
        off-diagonal terms ``u(x_i, x_j) = r(x_i, x_j) u(x_i) u(x_j)`` of ``U_x``
        (JCGM 100 §5.2.2, eq. (13) and (14)), so that ``u²(y) = Σ_i Σ_j c_i c_j u(x_i)
        u(x_j) r(x_i, x_j)``. The budget's contributions and shares stay those of each
        input alone: with correlation they no longer add up to ``u²(y)``, the rest being
        the cross terms. The Welch–Satterthwaite formula (JCGM 100 G.4.1) assumes
        independent inputs; it is applied as is, with the correlated ``u(y)``.

    Returns
    -------
    GumResult
        Estimate, ``u``, covariance, ν_eff, ``k``, interval, sensitivities and budget.

    Raises
    ------
    InputError
        If an input has no finite mean or uncertainty, the names of an expression model
        and the inputs differ, the model returns the wrong shape, or ``p`` is not in (0, 1).
    """
    p = check_probability(p)
    if not inputs:
        raise InputError("expected at least one input quantity", field="inputs")
    check_variables(model, inputs)
    items = [_gum_input(str(name), obj) for name, obj in inputs.items()]
    check_components(model, {i.name: 0 if i.scalar else i.estimate.size for i in items})
    offsets: list[int] = []
    n = 0
    for inp in items:
        offsets.append(n)
        n += inp.estimate.size
    x0 = np.concatenate([inp.estimate for inp in items])
    ux = np.zeros((n, n))
    for inp, start in zip(items, offsets, strict=True):
        size = inp.estimate.size
        ux[start : start + size, start : start + size] = inp.cov
    corr = _copula.as_correlation(correlation)
    if corr is not None:  # JCGM 100 eq. (14): u(x_i, x_j) = r(x_i, x_j) u(x_i) u(x_j)
        corr.check_inputs({inp.name: inp.dist for inp in items}, quantiles=False)
        at = {inp.name: start for inp, start in zip(items, offsets, strict=True)}
        for a, b, r in corr.pairs():
            ia, ib = at[a], at[b]
            ux[ia, ib] = ux[ib, ia] = r * math.sqrt(ux[ia, ia] * ux[ib, ib])
    std = np.sqrt(np.diag(ux))
    scale = np.where(std > 0, std, np.maximum(np.abs(x0), 1.0) * 1e-6)
    h_cs = _COMPLEX_STEP * scale
    h_cd = _CENTRAL_STEP * scale
    eye = np.eye(n)

    method = "complex-step"
    out: NDArray[Any] | None = None
    # An Expression knows whether it is complex-safe; any other callable is checked.
    known_safe = getattr(model, "complex_safe", None) is True
    if getattr(model, "complex_safe", True):
        rows = np.concatenate(
            [
                x0[None, :].astype(np.complex128),
                x0 + 1j * h_cs[:, None] * eye,
                x0 + h_cd[:, None] * eye,
                x0 - h_cd[:, None] * eye,
            ]
        )
        try:
            # Perturbed points may leave the model's domain (sqrt at 0, say): such rows
            # give NaN, judged below, rather than a floating-point warning.
            with warnings.catch_warnings(), np.errstate(all="ignore"):
                warnings.simplefilter("error", np.exceptions.ComplexWarning)
                out = _evaluate(model, items, rows, offsets)
        except (TypeError, ValueError, ArithmeticError, np.exceptions.ComplexWarning):
            out = None
    if out is not None:
        out2 = out.reshape(out.shape[0], -1)
        y0 = np.real(out2[0])
        c_cs = (np.imag(out2[1 : n + 1]) / h_cs[:, None]).T
        c_cd = (np.real(out2[n + 1 : 2 * n + 1] - out2[2 * n + 1 :]) / (2 * h_cd[:, None])).T
        cs_ok = bool(np.all(np.isfinite(c_cs))) and np.iscomplexobj(out)
        if cs_ok and not known_safe and np.all(np.isfinite(c_cd)):
            u_ref = np.sqrt(np.einsum("dn,nm,dm->d", c_cd, ux, c_cd))
            gap = np.max(np.abs(c_cs - c_cd) * scale, axis=1)
            tol = _AGREEMENT * np.maximum(u_ref, 1e-300) + 1e-13 * np.abs(y0)
            cs_ok = bool(np.all(gap <= tol))
        if cs_ok:
            sens = c_cs
        else:
            sens = c_cd
            method = "central-difference"
    else:
        method = "central-difference"
        rows_r = np.concatenate([x0[None, :], x0 + h_cd[:, None] * eye, x0 - h_cd[:, None] * eye])
        with np.errstate(all="ignore"):
            out = _evaluate(model, items, rows_r, offsets)
        out2 = np.asarray(out, dtype=np.float64).reshape(out.shape[0], -1)
        y0 = out2[0]
        sens = ((out2[1 : n + 1] - out2[n + 1 :]) / (2 * h_cd[:, None])).T
    if not np.all(np.isfinite(y0)):
        raise InputError(
            f"the model is not finite at the input estimates (value {y0.tolist()})",
            field="model",
        )
    bad = ~np.all(np.isfinite(sens), axis=0)
    if np.any(bad):
        names = [_component_name(items, offsets, int(j)) for j in np.flatnonzero(bad)]
        raise InputError(
            "the model is not differentiable at the estimates with respect to "
            f"{', '.join(names)} (a sensitivity is not finite)",
            field=names[0],
        )
    vector_out = out.ndim == 2

    cov_y = sens @ ux @ sens.T
    cov_y = 0.5 * (cov_y + cov_y.T)
    var_y = np.clip(np.diag(cov_y), 0.0, None)
    u_y = np.sqrt(var_y)

    budget = []
    sensitivities: dict[str, NDArray[np.float64]] = {}
    contrib_var = []
    for inp, start in zip(items, offsets, strict=True):
        size = inp.estimate.size
        c_block = sens[:, start : start + size]  # (d, k)
        var_i = np.einsum("dk,kl,dl->d", c_block, inp.cov, c_block)
        contrib_var.append(var_i)
        with np.errstate(divide="ignore", invalid="ignore"):
            share = np.where(var_y > 0, var_i / np.where(var_y > 0, var_y, 1.0), 0.0)
        c_out = c_block.copy()
        sensitivities[inp.name] = c_out
        u_x = np.sqrt(np.diag(inp.cov))
        budget.append(
            BudgetEntry(
                name=inp.name,
                estimate=inp.estimate,
                u=u_x,
                sensitivity=c_out,
                contribution=np.sqrt(var_i),
                share=share,
                dof=inp.dof,
            )
        )
    dofs = np.array([inp.dof for inp in items])
    contrib = np.array(contrib_var)  # (n_inputs, d)
    nu = np.array([welch_satterthwaite(contrib[:, j], dofs) for j in range(contrib.shape[1])])
    return GumResult(
        estimate_vector=y0,
        u_vector=u_y,
        cov=cov_y,
        dof_vector=nu,
        p=p,
        sensitivities=sensitivities,
        budget=tuple(budget),
        method=method,
        scalar=not vector_out,
    )


def _component_name(items: list[_Input], offsets: list[int], j: int) -> str:
    for inp, start in zip(items, offsets, strict=True):
        if start <= j < start + inp.estimate.size:
            return inp.name if inp.scalar else f"{inp.name}[{j - start}]"
    return str(j)  # pragma: no cover


def validate(
    gum_result: GumResult,
    mc_result: MonteCarloResult,
    *,
    p: float = 0.95,
    ndig: int = 2,
    kind: Literal["symmetric", "shortest"] = "symmetric",
) -> Validation:
    """Validate the GUM result against a Monte Carlo result (JCGM 101 §8.2).

    With ``U_p = k_p u(y)`` the GUM expanded uncertainty for coverage probability
    ``p``, and ``[y_low, y_high]`` the Monte Carlo 100p % coverage interval,

    ``d_low = |y - U_p - y_low|``, ``d_high = |y + U_p - y_high|`` (JCGM 101 §8.2).

    The GUM is validated iff both are at most δ, the numerical tolerance of ``u(y)``
    written with ``ndig`` significant digits (§7.9.2: ``u = c × 10^l``, ``δ = ½ × 10^l``).

    Parameters
    ----------
    gum_result : GumResult
        From :func:`gum`, scalar output.
    mc_result : MonteCarloResult
        From :func:`mtmc.monte_carlo` for the same model and inputs.
    p : float, default 0.95, keyword-only
        Coverage probability; ``k_p`` is recomputed from ``gum_result.dof`` when it
        differs from ``gum_result.p``.
    ndig : int, default 2, keyword-only
        Significant digits of ``u(y)`` regarded as meaningful.
    kind : {"symmetric", "shortest"}, default "symmetric", keyword-only
        Monte Carlo interval compared: probabilistically symmetric (the default), or
        shortest (as JCGM 101 Table 8 does for the mass calibration of §9.3).

    Returns
    -------
    Validation

    Raises
    ------
    InputError
        For a vector output, an unknown ``kind``, or ``p`` outside (0, 1).
    """
    p = check_probability(p)
    if not gum_result.scalar:
        raise InputError(
            "JCGM 101 §8 validation is defined for a scalar output; got an output of "
            f"{gum_result.dim} components",
            field="gum_result",
        )
    if kind not in ("symmetric", "shortest"):
        raise InputError(f"expected kind 'symmetric' or 'shortest', got {kind!r}", field="kind")
    expanded = gum_result.expanded_uncertainty(p)
    y_low, y_high = mc_result.coverage_interval(p, kind=kind)
    y = gum_result.estimate
    d_low = abs(y - expanded - float(y_low))
    d_high = abs(y + expanded - float(y_high))
    # A GUM u(y) = 0 (a first-order sensitivity that vanishes, JCGM 101 §9.4) has no
    # meaningful digits: δ = 0, and only an exact match would validate.
    delta = _tolerance.numerical_tolerance(gum_result.u, ndig) if gum_result.u > 0 else 0.0
    return Validation(
        d_low=float(d_low),
        d_high=float(d_high),
        delta=float(delta),
        passed=bool(d_low <= delta and d_high <= delta),
        p=p,
        kind=kind,
        ndig=int(ndig),
    )
