"""What every study returns: a frozen :class:`StudyResult` of quantities, regions and tables.

A study's runner turns the Monte Carlo values of each scalar output quantity, with the GUM
result of the same model beside them, into a :class:`Quantity`: the estimate, ``u``, the
expanded uncertainty with ``k`` and ``p``, the symmetric and shortest coverage intervals
(JCGM 101 §7.7), the GUM result and the JCGM 101 §8 verdict, the uncertainty budget
(JCGM 100 §5.1.3: ``u_i(y) = |c_i| u(x_i)``, shares of ``u²(y)``), the histogram and the
convergence of the estimate and of ``u`` over the trials. Two-dimensional outputs (a point
seen in a coordinate plane, an axis location and direction) get a :class:`Region`: the
JCGM 102 §7.7 coverage ellipse. :meth:`StudyResult.to_dict` is the ``result.json`` of a
result folder (``docs/results-format.md``); the report is drawn from that alone.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields, replace
from typing import Any, ClassVar, TypeVar

import numpy as np
from numpy.typing import NDArray

from mtmc.document import InputFile
from mtmc.frozen import frozen_array, frozen_floats
from mtmc.io import to_jsonable
from mtmc.report.folder import RESULT_FORMAT  # the ``format`` of result.json: its reader's
from mtmc.study.settings import RunSettings
from mtmc.uncertainty.propagation import GumResult, endpoint_std_error, one_value, validate
from mtmc.uncertainty.results import Histogram, IntervalKind, MonteCarloResult
from mtmc.uncertainty.tolerance import numerical_tolerance, round_to_uncertainty

__all__ = [
    "RESULT_FORMAT",
    "BudgetLine",
    "Convergence",
    "GumSummary",
    "Histogram",
    "MonteCarloSummary",
    "PointField",
    "Quantity",
    "Region",
    "Reported",
    "StudyResult",
    "Table",
    "ValidationSummary",
    "quantity",
    "region",
]


#: Bins of the histograms kept in a result.
HISTOGRAM_BINS = 60
#: Points of the convergence curves kept in a result.
CONVERGENCE_POINTS = 60
#: Trials drawn as dots in the plots of a coverage region.
SCATTER_POINTS = 400
#: The JCGM 101 §8 verdict of an output that both methods give as one value
#: (:func:`mtmc.uncertainty.propagation.one_value`).
NOT_APPLICABLE = "not applicable"


def _plain(obj: Any) -> Any:
    return to_jsonable(obj, nonfinite_as_null=True)


def _plain_dict(obj: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = _plain(obj)
    return out


@dataclass(frozen=True)
class Table:
    """A table of a result: a title, column names (with units) and rows of numbers or text.

    Written as ``NAME.csv`` and shown in the report.
    """

    name: str
    title: str
    columns: tuple[str, ...]
    rows: tuple[tuple[Any, ...], ...]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "name": self.name,
            "title": self.title,
            "columns": list(self.columns),
            "rows": _plain([list(r) for r in self.rows]),
        }

    def to_csv(self) -> str:
        """The table as CSV text (header first; floats as ``repr``, i.e. exactly)."""
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(self.columns)
        for r in self.rows:
            w.writerow([repr(float(v)) if isinstance(v, float | np.floating) else v for v in r])
        return buf.getvalue()


def _scaled(x: float | None, factor: float) -> float | None:
    return None if x is None else float(x) * factor


_D = TypeVar("_D")


def _times(record: _D, factor: float, *names: str) -> _D:
    """``record`` (a frozen dataclass, or None) with the fields ``names`` times ``factor``.

    A field is a number or a pair of numbers (an interval).
    """
    if record is None:
        return record

    def times(x: Any) -> Any:
        return (x[0] * factor, x[1] * factor) if isinstance(x, tuple) else x * factor

    return replace(record, **{n: times(getattr(record, n)) for n in names})  # type: ignore[type-var]


def _dof_of(x: Any) -> float:
    """A ``dof`` read from JSON: ``null`` is ``∞`` (an exactly known ``u``)."""
    return math.inf if x is None else float(x)


def _pair(x: Any) -> tuple[float, float]:
    lo, hi = x
    return (float(lo), float(hi))


class _Written:
    """A frozen summary written as a flat JSON object, one key per field, in field order.

    Tuples are written as lists; :attr:`_read` names the fields read back through a
    converter (a pair of interval ends, a ``dof`` written ``null`` for ``∞``).
    """

    _read: ClassVar[Mapping[str, Callable[[Any], Any]]] = {}

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (its entry in ``result.json``; an infinite ``dof`` is ``None``)."""
        out = {}
        for f in fields(self):  # type: ignore[arg-type]
            v = getattr(self, f.name)
            out[f.name] = list(v) if isinstance(v, tuple) else v
        return _plain_dict(out)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Any:
        """The value that :meth:`to_dict` wrote."""
        return cls(
            **{f.name: cls._read.get(f.name, _same)(d[f.name]) for f in fields(cls)}  # type: ignore[arg-type]
        )


def _same(x: Any) -> Any:
    return x


@dataclass(frozen=True)
class MonteCarloSummary(_Written):
    """The Monte Carlo result of one scalar output quantity (JCGM 101).

    Attributes
    ----------
    estimate : float
        The mean of the Monte Carlo values (JCGM 101 §7.6).
    u : float
        Their standard deviation, the standard uncertainty (JCGM 101 §7.6).
    U : float
        Half the length of the ``interval`` kind of coverage interval (the study's
        ``[run] interval``).
    k : float or None
        ``U/u`` (None where ``u = 0``).
    p : float
        The coverage probability.
    interval : str
        The kind of coverage interval that gives ``U``: ``"symmetric"`` or ``"shortest"``.
    shortest : tuple of float
        The shortest coverage interval (JCGM 101 §7.7).
    symmetric : tuple of float
        The probabilistically symmetric coverage interval (JCGM 101 §7.7).
    trials : int
        The number of trials ``M``.
    omitted : int
        Trials left out (their value NaN or infinite).
    """

    _read: ClassVar[Mapping[str, Callable[[Any], Any]]] = {"shortest": _pair, "symmetric": _pair}

    estimate: float
    u: float
    U: float
    k: float | None
    p: float
    interval: str
    shortest: tuple[float, float]
    symmetric: tuple[float, float]
    trials: int
    omitted: int

    @property
    def coverage_interval(self) -> tuple[float, float]:
        """The ends of the coverage interval of the :attr:`interval` kind, which gives ``U``."""
        return self.shortest if self.interval == "shortest" else self.symmetric


@dataclass(frozen=True)
class GumSummary(_Written):
    """The GUM result of one scalar output quantity (JCGM 100).

    Attributes
    ----------
    estimate : float
        The estimate ``y`` (JCGM 100 §4.1.4).
    u : float
        The combined standard uncertainty ``u_c(y)`` (JCGM 100 §5.1.2).
    k : float
        The coverage factor ``k_p`` (JCGM 100 G.3.2, G.4.1): the t quantile for ``dof``,
        the normal one where ``dof`` is infinite.
    U : float
        The expanded uncertainty ``k u`` (JCGM 100 §6.2.1).
    dof : float
        The effective degrees of freedom by Welch–Satterthwaite (JCGM 100 eq. (G.2b);
        ``inf`` where every input is exactly known).
    interval : tuple of float
        The coverage interval ``[y - U, y + U]``.
    method : str
        ``"complex-step"`` or ``"central-difference"``: how the sensitivities were
        computed.
    """

    _read: ClassVar[Mapping[str, Callable[[Any], Any]]] = {"dof": _dof_of, "interval": _pair}

    estimate: float
    u: float
    k: float
    U: float
    dof: float
    interval: tuple[float, float]
    method: str


@dataclass(frozen=True)
class ValidationSummary(_Written):
    """The JCGM 101 §8 comparison of the GUM with the Monte Carlo for one quantity.

    Attributes
    ----------
    d_low, d_high : float
        The differences of the interval ends (JCGM 101 §8.2).
    delta : float
        The numerical tolerance δ of ``u`` to ``ndig`` significant digits (JCGM 101
        §7.9.2).
    passed : bool or None
        Whether both ``d`` are within δ; None where both methods give one value.
    kind : str
        The kind of Monte Carlo interval compared: ``"symmetric"`` or ``"shortest"``.
    ndig : int
        Significant digits of ``u``.
    endpoint_std_error : float
        The standard error of a Monte Carlo interval end
        (:func:`~mtmc.uncertainty.propagation.endpoint_std_error`).
    verdict : str
        "validated", "not validated", or "not validated within Monte Carlo noise" (a
        ``d`` above δ by less than three endpoint standard errors); "not applicable"
        where both methods give one value: ``u = 0``, or the Monte Carlo's at the rounding
        of the estimate (:func:`~mtmc.uncertainty.propagation.one_value`).
    """

    d_low: float
    d_high: float
    delta: float
    passed: bool | None
    kind: str
    ndig: int
    endpoint_std_error: float
    verdict: str


@dataclass(frozen=True)
class BudgetLine(_Written):
    """One input of the uncertainty budget of a quantity (JCGM 100 §5.1.3).

    Attributes
    ----------
    name : str
        The input.
    components : int
        Its number of components ``k``.
    estimate : float or None
        Its estimate ``x`` (None for a ``k``-variate input, ``k > 1``).
    u : float or None
        Its standard uncertainty ``u(x)`` (None for ``k > 1``).
    sensitivity : float or None
        The sensitivity coefficient ``c`` (None for ``k > 1``).
    contribution : float
        ``|c| u(x)``; for a ``k``-variate input ``sqrt(c V cᵀ)``.
    share : float
        Its share of ``u²(y)`` (the shares sum to 1 for uncorrelated inputs).
    dof : float
        ν of ``u(x)`` (JCGM 100 G.4.1; ``inf`` where ``u(x)`` is exactly known).
    """

    _read: ClassVar[Mapping[str, Callable[[Any], Any]]] = {"dof": _dof_of}

    name: str
    components: int
    estimate: float | None
    u: float | None
    sensitivity: float | None
    contribution: float
    share: float
    dof: float


def _same_fields(a: Any, b: Any) -> bool:
    """Whether two values of one dataclass with array fields have equal fields."""
    for f in fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if not (np.array_equal(x, y) if isinstance(x, np.ndarray) else x == y):
            return False
    return True


class _ArrayFields:
    """A frozen value with array fields: equal where every field is (arrays element-wise)."""

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return _same_fields(self, other)

    __hash__ = None  # type: ignore[assignment]


@dataclass(frozen=True, eq=False)
class Convergence(_ArrayFields):
    """How the estimate and ``u`` of a quantity settle as the trials grow (JCGM 101 §7.9).

    Attributes
    ----------
    m : ndarray
        Numbers of trials (read-only int64).
    estimate, u : ndarray
        The estimate and ``u`` from the first ``m`` trials (read-only float64).
    last_half_estimate, last_half_u : float
        How far the estimate and ``u`` move (max - min) over ``m >= M/2``.
    delta : float or None
        The numerical tolerance of ``u`` to ``ndig`` significant digits (JCGM 101
        §7.9.2; None where ``u = 0``), the scale to read those moves against.
    ndig : int
        Significant digits of ``u``.
    """

    m: NDArray[np.int64]
    estimate: NDArray[np.float64]
    u: NDArray[np.float64]
    last_half_estimate: float
    last_half_u: float
    delta: float | None
    ndig: int

    def __post_init__(self) -> None:
        object.__setattr__(self, "m", frozen_array(np.asarray(self.m, dtype=np.int64)))
        object.__setattr__(self, "estimate", frozen_floats(self.estimate))
        object.__setattr__(self, "u", frozen_floats(self.u))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (``convergence`` of a quantity)."""
        return _plain_dict(
            {
                "m": self.m,
                "estimate": self.estimate,
                "u": self.u,
                "last_half": {"estimate": self.last_half_estimate, "u": self.last_half_u},
                "delta": self.delta,
                "ndig": self.ndig,
            }
        )

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Convergence:
        """The curves that :meth:`to_dict` wrote."""
        return cls(
            m=d["m"],
            estimate=d["estimate"],
            u=d["u"],
            last_half_estimate=d["last_half"]["estimate"],
            last_half_u=d["last_half"]["u"],
            delta=d["delta"],
            ndig=d["ndig"],
        )


@dataclass(frozen=True)
class Reported:
    """The estimate and ``U`` of a quantity as text, rounded as JCGM 100 §7.2.6 says.

    Two significant digits on ``U``, the estimate to the same decimal place.

    Attributes
    ----------
    estimate : str
        The estimate ``y``.
    U : str
        The expanded uncertainty.
    """

    estimate: str
    U: str

    def to_dict(self) -> dict[str, str]:
        """JSON-ready form (``reported`` of a quantity)."""
        return {"estimate": self.estimate, "U": self.U}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Reported:
        """The text that :meth:`to_dict` wrote."""
        return cls(estimate=d["estimate"], U=d["U"])


@dataclass(frozen=True)
class Quantity:
    """The uncertainty statement of one scalar output quantity.

    Attributes
    ----------
    name : str
        The output (``d_ac``, ``p.x``, ``axis_c.direction.y``).
    unit : str
        Its unit (``mm``, ``rad``, ``1``, or what a study file says).
    mc : MonteCarloSummary
        The Monte Carlo estimate, ``u``, ``U`` (half the length of the ``interval`` kind
        of coverage interval, the study's ``[run] interval``), ``k = U/u``, ``p`` and
        both coverage intervals (JCGM 101 §7.6–7.7).
    gum : GumSummary or None
        The GUM result of the same model (JCGM 100).
    validation : ValidationSummary or None
        The JCGM 101 §8 comparison of the two and its verdict.
    budget : tuple of BudgetLine
        Per input: its ``u(x)``, sensitivity, contribution and share of ``u²(y)``
        (JCGM 100 §5.1.3).
    histogram : Histogram
        The histogram of the Monte Carlo values (empty where ``u = 0``).
    convergence : Convergence
        The estimate and ``u`` from the first ``m`` trials (JCGM 101 §7.9).
    reported : Reported
        ``estimate`` and ``U`` as text, rounded as JCGM 100 §7.2.6 says (two significant
        digits on ``U``, the estimate to the same decimal place).
    conformity : dict or None
        Where the study gives tolerance limits: the JCGM 106 decision on the Monte Carlo
        PDF (:meth:`mtmc.uncertainty.decision.Conformity.to_dict`) with ``gum_p_c``,
        the conformance probability of the GUM's PDF beside it.
    """

    name: str
    unit: str
    mc: MonteCarloSummary
    gum: GumSummary | None
    validation: ValidationSummary | None
    budget: tuple[BudgetLine, ...]
    histogram: Histogram = field(repr=False)
    convergence: Convergence = field(repr=False)
    reported: Reported
    conformity: dict[str, Any] | None = None

    def in_unit(self, unit: str, factor: float) -> Quantity:
        """The same statement in another unit: every value of the quantity times ``factor``.

        A study whose file is written in µm (an artefact or a verification study, whose
        models compute in mm) gives its quantities in µm with ``in_unit("µm", 1e3)``
        (``docs/results-format.md``, the unit rule). Estimates, ``u``, ``U``, the interval
        ends, the GUM's values, the §8 differences ``d``, the budget's sensitivities and
        contributions and the convergence curves are multiplied by ``factor``, the
        histogram's density divided by it; ``k``, ``p``, ν, the shares and the verdict stay,
        ``reported`` is rounded again (JCGM 100 §7.2.6) and the numerical tolerances δ are
        those of the new ``u`` (JCGM 101 §7.9.2).

        Parameters
        ----------
        unit : str
            The new unit.
        factor : float
            Units of ``unit`` per unit of :attr:`unit` (1000 from mm to µm).

        Returns
        -------
        Quantity

        Raises
        ------
        ValueError
            If ``factor`` is not a positive finite number, or the quantity has a
            conformity decision (its limits are in the study's unit already).
        """
        if not (math.isfinite(factor) and factor > 0):
            raise ValueError(f"a unit factor must be positive and finite, got {factor!r}")
        if self.conformity is not None:
            raise ValueError("a quantity with a conformity decision keeps its study's unit")

        mc = _times(self.mc, factor, "estimate", "u", "U", "shortest", "symmetric")
        gum = _times(self.gum, factor, "estimate", "u", "U", "interval")
        validation = _times(
            self.validation, factor, "d_low", "d_high", "delta", "endpoint_std_error"
        )
        budget = tuple(
            replace(
                b,
                sensitivity=_scaled(b.sensitivity, factor),
                contribution=b.contribution * factor,
            )
            for b in self.budget
        )
        histogram = Histogram(
            edges=self.histogram.edges * factor, density=self.histogram.density / factor
        )
        conv = self.convergence
        u = mc.u
        convergence = replace(
            conv,
            estimate=conv.estimate * factor,
            u=conv.u * factor,
            last_half_estimate=conv.last_half_estimate * factor,
            last_half_u=conv.last_half_u * factor,
            delta=numerical_tolerance(u, conv.ndig) if 0 < u < math.inf else None,
        )
        if mc.U > 0:
            y_txt, u_txt = round_to_uncertainty(mc.estimate, mc.U, conv.ndig)
        else:
            y_txt, u_txt = f"{mc.estimate:.6g}", "0"
        return Quantity(
            name=self.name,
            unit=unit,
            mc=mc,
            gum=gum,
            validation=validation,
            budget=budget,
            histogram=histogram,
            convergence=convergence,
            reported=Reported(estimate=y_txt, U=u_txt),
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (the entry of ``quantities`` in ``result.json``)."""
        return _plain_dict(
            {
                "name": self.name,
                "unit": self.unit,
                "monte_carlo": self.mc.to_dict(),
                "gum": None if self.gum is None else self.gum.to_dict(),
                "validation": None if self.validation is None else self.validation.to_dict(),
                "budget": [b.to_dict() for b in self.budget],
                "reported": self.reported.to_dict(),
                "histogram": self.histogram.to_dict(),
                "convergence": self.convergence.to_dict(),
                **({} if self.conformity is None else {"conformity": self.conformity}),
            }
        )


def quantity(
    name: str,
    unit: str,
    mc: MonteCarloResult,
    gum_result: GumResult | None,
    settings: RunSettings,
) -> Quantity:
    """The :class:`Quantity` of a scalar Monte Carlo result, with the GUM beside it.

    Parameters
    ----------
    name, unit : str
        The output and its unit.
    mc : MonteCarloResult
        Scalar Monte Carlo values (JCGM 101).
    gum_result : GumResult or None
        The GUM result of the same model and inputs (scalar), or None.
    settings : RunSettings
        ``p``, ``interval`` (the kind of Monte Carlo interval that gives ``U`` and that
        the GUM is compared with, JCGM 101 §8) and ``ndig``.

    Returns
    -------
    Quantity
    """
    p = settings.p
    lo_s, hi_s = mc.coverage_interval(p, "shortest")
    lo_y, hi_y = mc.coverage_interval(p, "symmetric")
    u = mc.u
    kind: IntervalKind = "shortest" if settings.interval == "shortest" else "symmetric"
    mc_s = MonteCarloSummary(
        estimate=float(mc.estimate),
        u=float(u),
        U=float(mc.expanded_uncertainty(p, kind)),
        k=float(mc.coverage_factor(p, kind)) if u > 0 else None,
        p=float(p),
        interval=kind,
        shortest=(float(lo_s), float(hi_s)),
        symmetric=(float(lo_y), float(hi_y)),
        trials=int(mc.trials),
        omitted=int(mc.omitted),
    )
    gum_s = None
    val_s = None
    budget: list[BudgetLine] = []
    if gum_result is not None:
        gk = gum_result.coverage_factor()
        gu = gum_result.u
        g_lo, g_hi = gum_result.coverage_interval()
        gum_s = GumSummary(
            estimate=float(gum_result.estimate),
            u=float(gu),
            k=float(gk),
            U=float(gk * gu),
            dof=float(gum_result.dof),
            interval=(float(g_lo), float(g_hi)),
            method=gum_result.method,
        )
        v = validate(gum_result, mc, p=p, ndig=settings.ndig, kind=settings.interval)  # type: ignore[arg-type]
        noise = endpoint_std_error(u, mc.m, p)
        # both methods give one value and no interval: the JCGM 101 §8 comparison has
        # nothing to compare
        constant = one_value(u, gu, mc.estimate)
        verdict = NOT_APPLICABLE if constant else v.verdict(noise)
        val_s = ValidationSummary(
            d_low=float(v.d_low),
            d_high=float(v.d_high),
            delta=float(v.delta),
            passed=None if constant else bool(v.passed),
            kind=v.kind,
            ndig=int(v.ndig),
            endpoint_std_error=float(noise),
            verdict=verdict,
        )
        for e in gum_result.budget:
            # a k-variate input has k estimates, u and sensitivities: the line gives
            # its contribution sqrt(c V cᵀ) and share, not the first component's x, u, c
            k = int(e.u.size)
            budget.append(
                BudgetLine(
                    name=e.name,
                    components=k,
                    estimate=float(e.estimate[0]) if k == 1 else None,
                    u=float(e.u[0]) if k == 1 else None,
                    sensitivity=float(e.sensitivity[0, 0]) if k == 1 else None,
                    contribution=float(e.contribution[0]),
                    share=float(e.share[0]),
                    dof=float(e.dof),  # ν of u(x), JCGM 100 G.4.1; null in JSON for ∞
                )
            )
    hist = mc.histogram(bins=HISTOGRAM_BINS) if u > 0 else None  # no histogram of one value
    m, est, us = mc.convergence(CONVERGENCE_POINTS)
    late = m >= m[-1] / 2  # the curves over the last half of the trials
    if mc_s.U > 0:
        y_txt, u_txt = round_to_uncertainty(mc.estimate, mc_s.U, settings.ndig)
    else:
        y_txt, u_txt = f"{mc.estimate:.6g}", "0"
    return Quantity(
        name=name,
        unit=unit,
        mc=mc_s,
        gum=gum_s,
        validation=val_s,
        budget=tuple(budget),
        histogram=Histogram(edges=np.empty(0), density=np.empty(0))
        if hist is None
        else Histogram(edges=hist.edges, density=hist.density),
        convergence=Convergence(
            m=m,
            estimate=est,
            u=us,
            last_half_estimate=float(np.ptp(est[late])),
            last_half_u=float(np.ptp(us[late])),
            delta=numerical_tolerance(u, settings.ndig) if 0 < u < math.inf else None,
            ndig=settings.ndig,
        ),
        reported=Reported(estimate=y_txt, U=u_txt),
    )


@dataclass(frozen=True)
class Region:
    """A 95 % (or ``p``) coverage ellipse of a two-component output (JCGM 102 §7.7).

    Attributes
    ----------
    name : str
        What it is (``"p: x, y"``, ``"axis_c: location normal to the axis"``).
    labels : tuple of str
        The two coordinates.
    unit : str
        Their unit.
    centre : ndarray, shape (2,)
    cov : ndarray, shape (2, 2)
    k, k_chi2 : float
        Scale of the Monte Carlo region (JCGM 102 §7.7.2) and of the Gaussian one
        (``k² = χ²₂(p)``, JCGM 102 §6.5.2.3).
    p : float
    semi_axes : ndarray, shape (2,)
        ``k sqrt(λ_i)``, ascending.
    axes : ndarray, shape (2, 2)
        Unit eigenvectors, as columns.
    scatter : ndarray, shape (n, 2)
        The first trials, for the plot.
    """

    name: str
    labels: tuple[str, str]
    unit: str
    centre: NDArray[np.float64]
    cov: NDArray[np.float64]
    k: float
    k_chi2: float
    p: float
    semi_axes: NDArray[np.float64]
    axes: NDArray[np.float64]
    scatter: NDArray[np.float64] = field(repr=False)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (an entry of ``regions`` in ``result.json``)."""
        return _plain_dict(
            {
                "name": self.name,
                "labels": list(self.labels),
                "unit": self.unit,
                "centre": self.centre,
                "cov": self.cov,
                "k": self.k,
                "k_chi2": self.k_chi2,
                "p": self.p,
                "semi_axes": self.semi_axes,
                "axes": self.axes,
                "scatter": self.scatter,
            }
        )


def region(
    name: str, labels: tuple[str, str], unit: str, samples: NDArray[np.float64], p: float
) -> Region | None:
    """The coverage ellipse of ``(M, 2)`` values (None where their covariance is singular)."""
    from mtmc.errors import InputError

    res = MonteCarloResult.from_samples(samples, seed=None)
    try:
        ell = res.coverage_ellipsoid(p, method="mc")
        chi = res.coverage_ellipsoid(p, method="chi2")
    except InputError:
        return None
    return Region(
        name=name,
        labels=labels,
        unit=unit,
        centre=frozen_floats(ell.centre),
        cov=frozen_floats(ell.cov),
        k=float(ell.k),
        k_chi2=float(chi.k),
        p=p,
        semi_axes=frozen_floats(ell.semi_axes),
        axes=frozen_floats(ell.axes),
        scatter=frozen_floats(samples[:SCATTER_POINTS]),
    )


@dataclass(frozen=True)
class PointField:
    """Values at points of the workspace, drawn by the report in xy, xz and 3D views.

    A scalar per point (``values`` of shape ``(n,)``: a map, e.g. the uncertainty of the
    tool position or of a calibrated error at each measured point, Aguado et al. 2017
    Fig. 5–6) or a vector per point (``(n, 3)``: error vectors drawn as arrows
    magnified by ``magnification``, Wang, Cheung and Kong 2022 Fig. 7).

    Attributes
    ----------
    name, title : str
        Key and caption.
    points : ndarray, shape (n, 3)
        Where, mm.
    values : ndarray, shape (n,) or (n, 3)
        What, in ``unit``.
    unit : str
        Unit of the values, the study's (``mm``, ``µm``), in which the report shows them.
    labels : tuple of str
        A group label per point (e.g. the pose), or empty.
    axes : tuple of str
        Names of the three coordinates of ``points``.
    magnification : float
        Scale of the arrows of a vector field.
    """

    name: str
    title: str
    points: NDArray[np.float64]
    values: NDArray[np.float64]
    unit: str
    labels: tuple[str, ...] = ()
    axes: tuple[str, str, str] = ("x", "y", "z")
    magnification: float = 1.0

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (an entry of ``fields`` in ``result.json``)."""
        return _plain_dict(
            {
                "name": self.name,
                "title": self.title,
                "kind": "vectors" if np.ndim(self.values) == 2 else "map",
                "points": self.points,
                "values": self.values,
                "unit": self.unit,
                "labels": list(self.labels),
                "axes": list(self.axes),
                "magnification": self.magnification,
            }
        )


@dataclass(frozen=True)
class StudyResult:
    """The frozen result of a study run: what ``result.json`` holds, and the samples.

    Attributes
    ----------
    kind, title : str
        The study's kind and title.
    study_file : str
        The study file as named when it was read.
    study_sha256 : str
        SHA-256 of its text.
    seed : int
        The seed of the run (every Monte Carlo run of the study uses it).
    trials : int
        Monte Carlo trials ``M``.
    p : float
        Coverage probability.
    quantities : tuple of Quantity
        One per scalar output.
    regions : tuple of Region
        Coverage ellipses of two-component outputs.
    tables : tuple of Table
        Further tables of the kind (inputs, a sweep grid, ...).
    fields : tuple of PointField
        Maps and error vectors over the workspace.
    inputs : tuple of dict
        The input quantities: ``name``, ``distribution`` (text), ``estimate``, ``u``.
    extra : dict
        Kind-specific JSON-ready data (a sweep and its surrogate, the graph's text).
    samples : dict of str to ndarray
        The model values by output, when the study asked to keep them (not in JSON).
    input_files : tuple of InputFile
        The files the study file names and the run read (a graph, a CSV), each with its
        SHA-256; a result folder holds a copy of each (``copy``), listed in
        ``provenance.json`` (not in ``result.json``).
    """

    kind: str
    title: str
    study_file: str
    study_sha256: str
    seed: int
    trials: int
    p: float
    quantities: tuple[Quantity, ...] = ()
    regions: tuple[Region, ...] = ()
    tables: tuple[Table, ...] = ()
    fields: tuple[PointField, ...] = ()
    inputs: tuple[dict[str, Any], ...] = ()
    extra: Mapping[str, Any] = field(default_factory=dict)
    samples: Mapping[str, NDArray[np.float64]] = field(default_factory=dict, repr=False)
    input_files: tuple[InputFile, ...] = ()

    @property
    def warnings(self) -> list[str]:
        """Every warning of the run: the study's and its kind's, one line each.

        The study's are ``extra["warnings"]`` (a Type A input, a tracker position that
        cannot see a point); a kind's own, ``extra[kind]["warnings"]`` (the readings of a
        positioning test that Grubbs' test flags).
        """
        own = self.extra.get(self.kind)
        kinds = own.get("warnings", ()) if isinstance(own, Mapping) else ()
        return [*self.extra.get("warnings", ()), *kinds]

    def quantity(self, name: str) -> Quantity:
        """The quantity called ``name``."""
        for q in self.quantities:
            if q.name == name:
                return q
        raise KeyError(f"no quantity {name!r}; the result has {[q.name for q in self.quantities]}")

    def to_dict(self) -> dict[str, Any]:
        """``result.json``: every summary, JSON-ready (``docs/results-format.md``)."""
        return _plain_dict(
            {
                "format": RESULT_FORMAT,
                "kind": self.kind,
                "title": self.title,
                "study_file": self.study_file,
                "study_sha256": self.study_sha256,
                "seed": self.seed,
                "trials": self.trials,
                "p": self.p,
                "inputs": list(self.inputs),
                "quantities": [q.to_dict() for q in self.quantities],
                "regions": [r.to_dict() for r in self.regions],
                "tables": [t.to_dict() for t in self.tables],
                "fields": [f.to_dict() for f in self.fields],
                **{k: v for k, v in self.extra.items()},
            }
        )

    def summary_table(self) -> Table:
        """One row per quantity: estimate, u, U, k, intervals, GUM u, §8 verdict."""
        rows = []
        for q in self.quantities:
            mc, g, v = q.mc, q.gum, q.validation
            rows.append(
                (
                    q.name,
                    q.unit,
                    mc.estimate,
                    mc.u,
                    mc.U,
                    mc.k if mc.k is not None else "",
                    mc.p,
                    mc.shortest[0],
                    mc.shortest[1],
                    mc.symmetric[0],
                    mc.symmetric[1],
                    "" if g is None else g.u,
                    "" if g is None else g.k,
                    "" if v is None else v.verdict,
                )
            )
        return Table(
            "quantities",
            "Output quantities",
            (
                "quantity",
                "unit",
                "estimate",
                "u",
                "U",
                "k",
                "p",
                "shortest_low",
                "shortest_high",
                "symmetric_low",
                "symmetric_high",
                "gum_u",
                "gum_k",
                "gum_validated",
            ),
            tuple(rows),
        )

    def csv_tables(self) -> dict[str, str]:
        """The CSV files of the result folder: file name to text."""
        out = {"quantities.csv": self.summary_table().to_csv()}
        budget_rows = [
            (
                q.name,
                b.name,
                b.components,
                b.estimate,
                b.u,
                b.sensitivity,
                b.contribution,
                b.share,
                b.dof,
            )
            for q in self.quantities
            for b in q.budget
        ]
        if budget_rows:
            out["budget.csv"] = Table(
                "budget",
                "Uncertainty budget",
                (
                    "quantity",
                    "input",
                    "components",
                    "estimate",
                    "u",
                    "sensitivity",
                    "contribution",
                    "share",
                    "dof",
                ),
                tuple(budget_rows),
            ).to_csv()
        for t in self.tables:
            out[f"{t.name}.csv"] = t.to_csv()
        return out
