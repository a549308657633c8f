"""Type A evaluation from observations, and degrees of freedom on any input.

:func:`type_a` turns ``n`` repeated observations ``x_1 … x_n`` of an input quantity into
the PDF of JCGM 101:2008 §6.4.9 and the standard uncertainty of JCGM 100:2008 §4.2:

* for the Monte Carlo, the scaled and shifted t ``t_ν(x̄, s²/n)`` with ``ν = n - 1``
  (JCGM 101 §6.4.9.2), drawn as :class:`~mtmc.uncertainty.distributions.StudentT` draws;
* for the GUM, the estimate ``x̄`` (§4.2.1), the standard uncertainty ``u = s/√n``
  (§4.2.3) and ``ν = n - 1`` degrees of freedom (G.3.3), which the Welch–Satterthwaite
  formula (G.4.1) takes.

With a pooled standard deviation ``s_p`` of ``ν_p`` degrees of freedom from an earlier,
larger series under the same conditions (JCGM 100 §4.2.4, H.1.3.2), ``u = s_p/√n`` and
``ν = ν_p``; the t of the Monte Carlo is then ``t_{ν_p}(x̄, s_p²/n)``.

The two differ for a small series: the t of JCGM 101 has the standard deviation
``(s/√n)·√(ν/(ν - 2))`` for ``ν > 2`` and none for ``ν <= 2`` (and no expectation for
``ν <= 1``), while the GUM's ``u`` is ``s/√n`` whatever ``n``; the GUM carries the
smallness of ``n`` in ``ν`` and so in its coverage factor ``t_p(ν_eff)`` (G.3, G.4). The
``std`` of a :class:`TypeA` is the first, what :func:`~mtmc.uncertainty.propagation.gum` takes is
the second (:func:`stated_moments`).

:func:`with_dof` gives any other input the degrees of freedom ``ν`` of its standard
uncertainty: given directly, or from the relative uncertainty ``Δu/u`` of ``u`` as
``ν = ½ (Δu/u)⁻²`` (JCGM 100 G.4.2, eq. (G.3)). The GUM takes ``u`` and ``ν`` as stated.
The Monte Carlo draws the scale of the input as uncertain: ``ξ = μ + (X - μ) √(ν/W)``
with ``X`` a draw of the PDF as written and ``W`` a χ²_ν draw (a scaled inverse χ²
variance). For a normal PDF this is exactly the scaled and shifted t ``t_ν(μ, u²)`` of
JCGM 101 §6.4.9, the PDF §6.4.9.2 assigns to a Type A evaluation, so that
``normal(x̄, s/√n, dof=n-1)`` and ``type_a([...])`` are the same input;
``docs/type-a.md`` says why, and where it is not the right model.

Examples
--------
>>> from mtmc.uncertainty import Normal, Uniform, parse_distribution
>>> x = type_a([10.1, 10.3, 10.2, 10.4, 10.2])
>>> x.n, round(x.mean, 12), round(x.s, 6), round(x.u, 6), x.dof
(5, 10.24, 0.114018, 0.05099, 4.0)
>>> d = with_dof(Normal(0, 1), u_rel_u=0.25)
>>> d.dof, str(d)
(8.0, 'normal(0, 1, u_rel_u=0.25)')
>>> parse_distribution("uniform(-1, 1, dof=8)") == with_dof(Uniform(-1, 1), 8)
True
"""

from __future__ import annotations

import math
import sys
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mtmc.errors import DistributionError
from mtmc.uncertainty.distributions import (
    IID,
    Distribution,
    Normal,
    NormalMethod,
    StudentT,
    register_distribution,
    register_modifier,
)

__all__ = [
    "AutocorrelationWarning",
    "TypeA",
    "WithDof",
    "autocorrelation_limit",
    "dof_from_relative_uncertainty",
    "lag1_autocorrelation",
    "stated_moments",
    "type_a",
    "with_dof",
]


class AutocorrelationWarning(UserWarning):
    """The observations of a Type A input are serially correlated: ``s/√n`` understates ``u``.

    JCGM 100 §4.2.7: where the observations are correlated (in time, say), the mean and
    the experimental standard deviation of the mean of §4.2.2 and §4.2.3 may be
    inappropriate estimators.
    """


def lag1_autocorrelation(x: ArrayLike) -> float:
    """The lag-1 sample autocorrelation ``r1`` of a series of observations.

    ``r1 = Σ_{i<n} (x_i - x̄)(x_{i+1} - x̄) / Σ_i (x_i - x̄)²`` (Box, Jenkins and Reinsel,
    *Time Series Analysis*, §2.1.5).

    Parameters
    ----------
    x : array_like, shape (n,)
        The observations in the order they were taken.

    Returns
    -------
    float
        ``r1`` in [-1, 1]; NaN for fewer than 2 observations or where they are all equal.

    Examples
    --------
    >>> lag1_autocorrelation([1, 2, 3, 4])
    0.25
    """
    a = np.asarray(x, dtype=np.float64)
    if a.size < 2:
        return math.nan
    d = a - a.mean()
    top = float(np.max(np.abs(d)))
    if top == 0.0 or not math.isfinite(top):
        return math.nan
    d = np.ldexp(d, -math.frexp(top)[1])  # |d| < 1 by a power of 2: no square under/overflows
    den = float(d @ d)
    if den == 0.0:
        return math.nan
    return float(d[:-1] @ d[1:]) / den


def autocorrelation_limit(n: int) -> float:
    """The limit ``2/√n`` above which ``|r1|`` of ``n`` observations is significant.

    For ``n`` independent observations ``r1`` is approximately normal with mean about 0
    and variance ``1/n`` (Bartlett 1946; Box, Jenkins and Reinsel, *Time Series Analysis*,
    §2.1.6): ``|r1| > 2/√n`` rejects independence at about the 5 % level.

    Parameters
    ----------
    n : int
        Number of observations, ``n >= 1``.

    Returns
    -------
    float

    Examples
    --------
    >>> autocorrelation_limit(16)
    0.5
    """
    return 2.0 / math.sqrt(n)


def dof_from_relative_uncertainty(u_rel_u: float) -> float:
    """``ν = ½ (Δu/u)⁻²``: degrees of freedom of a ``u`` known to a relative uncertainty.

    JCGM 100 G.4.2, eq. (G.3): a ``u`` judged reliable to 25 % (``Δu/u = 0.25``) has
    ``ν = 8``; to 50 %, ``ν = 2``; to 10 %, ``ν = 50``.

    Parameters
    ----------
    u_rel_u : float
        ``Δu/u > 0``.

    Returns
    -------
    float

    Raises
    ------
    DistributionError
        If ``u_rel_u`` is not a finite number > 0, or below 1.5e-154 (its square
        underflows).

    Examples
    --------
    >>> dof_from_relative_uncertainty(0.25), dof_from_relative_uncertainty(0.1)
    (8.0, 50.0)
    >>> dof_from_relative_uncertainty(1e-200)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    mtmc.errors.DistributionError: field u_rel_u: expected u_rel_u >= 1.5e-154, got 1e-200: ...
    """
    r = _positive("u_rel_u", u_rel_u)
    if r < _MIN_U_REL_U:
        raise DistributionError(
            f"expected u_rel_u >= {_MIN_U_REL_U:.2g}, got {u_rel_u!r}: u_rel_u² underflows "
            "and ν = ½ u_rel_u⁻² is lost (leave u_rel_u out: a u known exactly has ν = ∞)",
            field="u_rel_u",
        )
    return 0.5 / (r * r)


#: The smallest ``Δu/u``: its square is the smallest normal double (ν = 2.2e307).
_MIN_U_REL_U = math.sqrt(sys.float_info.min)


def _positive(name: str, value: Any, what: str = "a finite number > 0") -> float:
    """``value`` as a finite float > 0, or a :class:`DistributionError` naming ``name``."""
    message = f"expected {name} to be {what}, got {value!r}"
    if isinstance(value, bool | str) or np.ndim(value) != 0:
        raise DistributionError(message, field=name)
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise DistributionError(message, field=name) from None
    if not (math.isfinite(v) and v > 0.0):
        raise DistributionError(message, field=name)
    return v


def _caller_level() -> int:
    """The ``stacklevel`` of a warning that names the first caller outside the package.

    Frames of the package's modules and of the ``__init__`` a dataclass writes are skipped,
    so that the warning points at the line that made the object (``type_a(...)``,
    ``parse_distribution(...)``), not at the package.
    """
    package = str(Path(__file__).resolve().parents[1])
    level, frame = 1, sys._getframe(1)
    while frame is not None and (
        frame.f_code.co_filename == "<string>"
        or str(Path(frame.f_code.co_filename).resolve()).startswith(package)
    ):
        level += 1
        frame = frame.f_back  # type: ignore[assignment]
    return level


def _number_text(x: float) -> str:
    """A float as text that parses back to the same float (integers without a point)."""
    if x.is_integer() and abs(x) < 1e15:
        return str(int(x))
    return repr(x)


# --------------------------------------------------------------------------- Type A
@register_distribution("type_a")
@dataclass(frozen=True, eq=False)
class TypeA(Distribution):
    """A Type A evaluation from repeated observations (JCGM 100 §4.2; JCGM 101 §6.4.9).

    Parameters
    ----------
    observations : array_like, shape (n,)
        The observations ``x_1 … x_n``, finite, in the order they were taken (the order
        matters only to ``r1``). At least 2, or at least 1 with a pooled ``s``.
    pooled_s : float, optional
        A pooled standard deviation ``s_p > 0`` of single observations from an earlier
        series under the same conditions (JCGM 100 §4.2.4).
    pooled_dof : float, optional
        Its degrees of freedom ``ν_p > 0`` (given with ``pooled_s``, and only with it).

    Attributes
    ----------
    n : int
        Number of observations.
    mean : float
        ``x̄``, the estimate (JCGM 100 eq. (3)), and the location of the t.
    s : float
        The experimental standard deviation of the observations (JCGM 100 eq. (4),
        divisor ``n - 1``); NaN for one observation.
    r1 : float
        Their lag-1 autocorrelation (:func:`lag1_autocorrelation`); NaN where undefined.
    u : float
        The GUM's standard uncertainty ``s/√n`` (§4.2.3), or ``s_p/√n`` (§4.2.4).
    dof : float
        ``ν = n - 1``, or ``ν_p``.
    std : float
        The standard deviation of the t PDF, ``u √(ν/(ν - 2))`` for ``ν > 2``, else
        ``inf`` (JCGM 101 §6.4.9.3).
    warning : str or None
        Why ``s/√n`` may understate ``u``, where it may: ``|r1| > 2/√n``
        (:func:`autocorrelation_limit`; JCGM 100 §4.2.7). An
        :class:`AutocorrelationWarning` with this text is issued when the object is made.

    Notes
    -----
    Sampling (JCGM 101 §6.4.9.5): ``ξ = x̄ + u t`` with ``t`` a standard t draw of ``ν``
    degrees of freedom, by :meth:`StudentT.sample` (the same numbers as
    ``StudentT(ν, x̄, u)``). For ``ν <= 2`` the Monte Carlo output has no standard
    deviation to converge to (``docs/type-a.md``).

    Examples
    --------
    >>> x = type_a([2.0, 2.2], pooled_s=0.1, pooled_dof=19)
    >>> round(x.u, 12) == round(0.1 / math.sqrt(2), 12), x.dof
    (True, 19.0)
    >>> str(x)
    'type_a([2, 2.2], pooled_s=0.1, pooled_dof=19)'
    """

    observations: NDArray[np.float64]
    pooled_s: float | None = None
    pooled_dof: float | None = None
    _t: StudentT = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        try:
            x = np.array(self.observations, dtype=np.float64)
        except (TypeError, ValueError):
            raise DistributionError(
                f"type_a: expected a list of numbers, got {self.observations!r}",
                field="observations",
            ) from None
        if x.ndim != 1:
            raise DistributionError(
                f"type_a: expected a flat list of observations, got shape {x.shape}",
                field="observations",
            )
        bad = np.flatnonzero(~np.isfinite(x))
        if bad.size:
            raise DistributionError(
                f"type_a: expected finite observations, observation {int(bad[0]) + 1} is "
                f"{float(x[bad[0]])!r}",
                field="observations",
            )
        pooled = self.pooled_s is not None or self.pooled_dof is not None
        if pooled and (self.pooled_s is None or self.pooled_dof is None):
            missing = "pooled_dof" if self.pooled_dof is None else "pooled_s"
            raise DistributionError(
                "type_a: expected pooled_s and pooled_dof together (JCGM 100 §4.2.4), "
                f"{missing} is missing",
                field=missing,
            )
        least = 1 if pooled else 2
        if x.size < least:
            raise DistributionError(
                f"type_a: expected at least {least} observation{'s' if least > 1 else ''}"
                f"{'' if pooled else ' (or a pooled_s and pooled_dof)'}, got {x.size}",
                field="observations",
            )
        x.setflags(write=False)
        object.__setattr__(self, "observations", x)
        if pooled:
            object.__setattr__(self, "pooled_s", _positive("pooled_s", self.pooled_s))
            object.__setattr__(self, "pooled_dof", _positive("pooled_dof", self.pooled_dof))
        if not pooled and np.all(x == x[0]):
            raise DistributionError(
                f"type_a: the {x.size} observations are all equal "
                f"({_number_text(float(x[0]))}), so s = 0; give a pooled_s and pooled_dof from "
                "an earlier series (JCGM 100 §4.2.4), or the resolution of the indication as a "
                "Type B input",
                field="observations",
            )
        if not self.u >= sys.float_info.min:
            raise DistributionError(
                f"type_a: u = s/√n = {self.u:.3g} of the {x.size} observations is below the "
                f"smallest normal double ({sys.float_info.min:.3g}); give them in a smaller unit",
                field="observations",
            )
        object.__setattr__(self, "_t", StudentT(self.dof, self.mean, self.u))
        if self.warning is not None:
            warnings.warn(self.warning, AutocorrelationWarning, stacklevel=_caller_level())

    def __repr__(self) -> str:
        pooled = (
            ""
            if self.pooled_s is None
            else f", pooled_s={self.pooled_s}, pooled_dof={self.pooled_dof}"
        )
        return f"TypeA(observations={self.observations.tolist()}{pooled})"

    def __str__(self) -> str:
        obs = ", ".join(_number_text(float(v)) for v in self.observations)
        if self.pooled_s is None or self.pooled_dof is None:
            return f"type_a([{obs}])"
        return (
            f"type_a([{obs}], pooled_s={_number_text(self.pooled_s)}, "
            f"pooled_dof={_number_text(self.pooled_dof)})"
        )

    @property
    def n(self) -> int:
        """Number of observations."""
        return int(self.observations.size)

    @property
    def mean(self) -> float:
        """``x̄`` (JCGM 100 eq. (3)): the estimate, whatever ``ν``."""
        return float(np.mean(self.observations))

    @property
    def s(self) -> float:
        """Experimental standard deviation ``s`` (JCGM 100 eq. (4)); NaN for ``n = 1``."""
        if self.n < 2:
            return math.nan
        x = self.observations
        with np.errstate(over="ignore", under="ignore"):
            s = float(np.std(x, ddof=1))
        if (s == 0.0 or not math.isfinite(s)) and np.any(x != x[0]):
            # the squared deviations underflowed (or overflowed): the same sum on x / 2^k,
            # an exact scaling, with 2^k the size of the largest |x|
            k = math.frexp(float(np.max(np.abs(x))))[1]
            s = math.ldexp(float(np.std(np.ldexp(x, -k), ddof=1)), k)
        return s

    @property
    def r1(self) -> float:
        """Lag-1 autocorrelation of the observations (:func:`lag1_autocorrelation`)."""
        return lag1_autocorrelation(self.observations)

    @property
    def pooled(self) -> bool:
        """Whether ``u`` and ``ν`` come from a pooled ``s_p`` (JCGM 100 §4.2.4)."""
        return self.pooled_s is not None

    @property
    def u(self) -> float:
        """The GUM's standard uncertainty: ``s/√n`` (§4.2.3) or ``s_p/√n`` (§4.2.4)."""
        s = self.s if self.pooled_s is None else self.pooled_s
        return s / math.sqrt(self.n)

    @property
    def dof(self) -> float:
        """``ν = n - 1`` (JCGM 100 G.3.3), or ``ν_p`` for a pooled ``s``."""
        if self.pooled_dof is not None:
            return float(self.pooled_dof)
        return float(self.n - 1)

    @property
    def std(self) -> float:
        """Standard deviation of the t PDF: ``u √(ν/(ν - 2))`` for ``ν > 2``, else ``inf``."""
        return self._t.std

    @property
    def autocorrelated(self) -> bool:
        """Whether ``|r1| > 2/√n`` (:func:`autocorrelation_limit`)."""
        r1 = self.r1
        return bool(math.isfinite(r1) and abs(r1) > autocorrelation_limit(self.n))

    @property
    def warning(self) -> str | None:
        """The text of the :class:`AutocorrelationWarning`, or None."""
        if not self.autocorrelated:
            return None
        return (
            f"the {self.n} observations are serially correlated: lag-1 autocorrelation "
            f"r1 = {self.r1:.3g}, beyond ±2/√n = ±{autocorrelation_limit(self.n):.3g}; "
            "s/√n then understates the standard uncertainty of the mean (JCGM 100 §4.2.7)"
        )

    def sample(
        self, rng: np.random.Generator, n: int, *, normal_method: NormalMethod = "default"
    ) -> NDArray[np.float64]:
        """Draw ``n`` values, shape ``(n,)``, from ``t_ν(x̄, u²)`` (JCGM 101 §6.4.9.5)."""
        return self._t.sample(rng, n, normal_method=normal_method)

    def ppf(self, u: Any) -> NDArray[np.float64]:
        """``x̄ + u t_ν⁻¹(p)``."""
        return self._t.ppf(u)

    def stated(self) -> tuple[float, float, float]:
        """``(x̄, u, ν)`` as the GUM takes them (JCGM 100 §4.2, G.3.3)."""
        return self.mean, self.u, self.dof


def type_a(
    observations: ArrayLike,
    *,
    pooled_s: float | None = None,
    pooled_dof: float | None = None,
) -> TypeA:
    """The Type A evaluation of an input from its observations (JCGM 100 §4.2).

    Parameters
    ----------
    observations : array_like, shape (n,)
        Finite observations, in the order they were taken; ``n >= 2`` (``n >= 1`` with a
        pooled ``s``).
    pooled_s, pooled_dof : float, optional, keyword-only
        A pooled standard deviation of single observations and its degrees of freedom,
        from an earlier series (JCGM 100 §4.2.4): then ``u = s_p/√n`` and ``ν = ν_p``.

    Returns
    -------
    TypeA
        For the Monte Carlo ``t_ν(x̄, u²)`` (JCGM 101 §6.4.9), for the GUM ``x̄``,
        ``u`` and ``ν``; with ``n``, ``s`` and the lag-1 autocorrelation ``r1``.

    Raises
    ------
    DistributionError
        Fewer observations than that, a value that is not finite, observations all equal
        without a pooled ``s``, only one of ``pooled_s`` and ``pooled_dof``, or either not
        a finite number > 0.

    Warns
    -----
    AutocorrelationWarning
        Where ``|r1| > 2/√n`` (JCGM 100 §4.2.7).

    Examples
    --------
    >>> x = type_a([50.2, 49.8, 50.1, 49.9])
    >>> round(x.u, 12) == round(float(np.std(x.observations, ddof=1)) / 2, 12)
    True
    """
    return TypeA(np.asarray(observations), pooled_s=pooled_s, pooled_dof=pooled_dof)


# --------------------------------------------------------------------------- ν on any input
@dataclass(frozen=True, eq=False)
class WithDof(Distribution):
    """A PDF whose standard uncertainty ``u`` has ``ν`` degrees of freedom (JCGM 100 G.4).

    Made by :func:`with_dof`, or by a distribution text ending in ``dof=ν`` or
    ``u_rel_u=r``.

    Parameters
    ----------
    base : Distribution
        The PDF as written: its expectation and standard deviation are the estimate and
        ``u`` the GUM takes.
    nu : float
        ``ν > 0``, finite.
    u_rel_u : float or None
        The relative uncertainty of ``u`` that ``ν`` came from (``ν = ½ r⁻²``), kept so
        that the text shows what was given.

    Notes
    -----
    GUM: estimate ``base.mean``, ``u = base.std`` and ``ν`` (JCGM 100 G.4.1, G.4.2).

    Monte Carlo: ``ξ = μ + (X - μ) √(ν/W)``, ``X`` a draw of ``base``, ``W`` a χ²_ν draw
    (``2 × standard_gamma(ν/2)``), one per trial: the variance of the base PDF scaled by
    a scaled inverse χ²_ν variable, as the t of JCGM 101 §6.4.9.2 scales that of a normal.
    For a normal base this is the scaled and shifted t ``t_ν(μ, u²)`` exactly, and is drawn
    as :class:`StudentT` draws (the same numbers as ``StudentT(ν, μ, u)``); for a vector
    base one ``W`` serves all components (for a multivariate normal, a multivariate t).
    The standard deviation of the PDF is ``u √(ν/(ν - 2))`` for ``ν > 2`` and infinite
    otherwise. For randomised quasi-Monte Carlo, ``W`` takes one more coordinate of the
    unit cube than the base (none more for a normal base).

    Examples
    --------
    >>> from mtmc.uncertainty import Normal
    >>> d = WithDof(Normal(1, 0.5), 4)
    >>> d.mean, d.dof, d.std == 0.5 * math.sqrt(2), str(d)
    (1.0, 4.0, True, 'normal(1, 0.5, dof=4)')
    """

    base: Distribution
    nu: float
    u_rel_u: float | None = None

    def __post_init__(self) -> None:
        base = self.base
        if not isinstance(base, Distribution):
            raise DistributionError(
                f"expected a distribution to give degrees of freedom to, got {base!r}", field="base"
            )
        if math.isfinite(base.dof):
            raise DistributionError(
                f"{base} already has ν = {_number_text(float(base.dof))} degrees of "
                "freedom; give them once",
                field="dof",
            )
        if not np.all(np.asarray(base.std, dtype=np.float64) > 0):
            raise DistributionError(
                f"{base} has a zero standard deviation; degrees of freedom describe "
                "how well a non-zero u is known",
                field="dof",
            )
        if self.u_rel_u is not None:
            r = _positive("u_rel_u", self.u_rel_u)
            nu = dof_from_relative_uncertainty(r)
            if self.nu is not None and not math.isclose(_positive("dof", self.nu), nu):
                raise DistributionError(
                    f"dof = {self.nu!r} and u_rel_u = {r!r} disagree: u_rel_u gives "
                    f"ν = ½ u_rel_u⁻² = {nu:.6g} (JCGM 100 G.4.2)",
                    field="u_rel_u",
                )
            object.__setattr__(self, "u_rel_u", r)
            object.__setattr__(self, "nu", nu)
        else:
            object.__setattr__(self, "nu", _positive("dof", self.nu))

    def __str__(self) -> str:
        text = str(self.base)
        extra = (
            f"dof={_number_text(self.nu)}"
            if self.u_rel_u is None
            else f"u_rel_u={_number_text(self.u_rel_u)}"
        )
        return f"{text[:-1]}, {extra})"

    @property
    def mean(self) -> Any:
        """The expectation of the base PDF."""
        return self.base.mean

    @property
    def u(self) -> Any:
        """The stated standard uncertainty: the standard deviation of the base PDF."""
        return self.base.std

    @property
    def std(self) -> Any:
        """Standard deviation of the PDF drawn: ``u √(ν/(ν - 2))`` for ``ν > 2``, else ``inf``."""
        factor = math.sqrt(self.nu / (self.nu - 2.0)) if self.nu > 2.0 else math.inf
        if self.dim == 0:
            return float(self.base.std) * factor
        return np.asarray(self.base.std, dtype=np.float64) * factor

    @property
    def dim(self) -> int:
        """That of the base PDF."""
        return self.base.dim

    @property
    def dof(self) -> float:
        """``ν``."""
        return self.nu

    @property
    def _normal(self) -> bool:
        return type(self.base) is Normal

    def _t(self) -> StudentT:
        return StudentT(self.nu, float(self.base.mean), float(self.base.std))

    def sample(
        self, rng: np.random.Generator, n: int, *, normal_method: NormalMethod = "default"
    ) -> NDArray[np.float64]:
        """Draw ``n`` values, shape ``(n,)`` or ``(n, k)``: the base, then ``W`` (see Notes)."""
        if self._normal:
            return self._t().sample(rng, n, normal_method=normal_method)
        x = self.base.sample(rng, n, normal_method=normal_method)
        w = np.asarray(2.0 * rng.standard_gamma(0.5 * self.nu, size=x.shape[0]))
        return self._scale(x, w)

    def _scale(self, x: NDArray[np.float64], w: NDArray[np.float64]) -> NDArray[np.float64]:
        # W = 0 underflows only for ν far below 1: the smallest positive float keeps ξ finite
        f = np.sqrt(self.nu / np.maximum(w, np.finfo(np.float64).tiny))
        mu = np.asarray(self.base.mean, dtype=np.float64)
        out = x - mu
        out *= f if x.ndim == 1 else f[:, None]
        out += mu
        return out

    def ppf(self, u: Any) -> NDArray[np.float64]:
        """The t quantile ``μ + u t_ν⁻¹(p)`` for a normal base; otherwise none exists here."""
        if self._normal:
            return self._t().ppf(u)
        return super().ppf(u)

    @property
    def uniform_dims(self) -> int:
        """One for a normal base (the t's inverse CDF); else the base's and one for ``W``."""
        return 1 if self._normal else self.base.uniform_dims + 1

    def from_uniform(self, u: NDArray[np.float64]) -> NDArray[np.float64]:
        """The base from the first coordinates, ``W`` from the last (its χ²_ν quantile)."""
        if self._normal:
            return self._t().ppf(u[:, 0])
        from scipy.special import gammaincinv

        x = self.base.from_uniform(u[:, :-1])
        w = 2.0 * gammaincinv(0.5 * self.nu, u[:, -1])
        return self._scale(x, np.asarray(w, dtype=np.float64))

    def stated(self) -> tuple[Any, Any, float]:
        """``(estimate, u, ν)`` as the GUM takes them (JCGM 100 G.4)."""
        return self.base.mean, self.base.std, self.nu


@register_modifier("dof", "u_rel_u")
def with_dof(
    dist: Distribution, dof: float | None = None, *, u_rel_u: float | None = None
) -> WithDof:
    """Give an input's standard uncertainty ``ν`` degrees of freedom (JCGM 100 G.4).

    Parameters
    ----------
    dist : Distribution
        The PDF (not a t, a Type A or another ``with_dof``: they have their ``ν``
        already; not a constant: it has no uncertainty).
    dof : float, optional
        ``ν > 0``, finite.
    u_rel_u : float, optional, keyword-only
        Instead of ``dof``: the relative uncertainty ``Δu/u`` of ``u``, giving
        ``ν = ½ (Δu/u)⁻²`` (JCGM 100 G.4.2, eq. (G.3)).

    Returns
    -------
    WithDof
        Its text is the distribution's with ``dof=`` or ``u_rel_u=`` added; the GUM takes
        ``u`` and ``ν`` as stated, the Monte Carlo draws the scale (:class:`WithDof`).

    Raises
    ------
    DistributionError
        Neither or both of ``dof`` and ``u_rel_u``, a value not a finite number > 0, or
        a ``dist`` as excluded above.

    Examples
    --------
    >>> from mtmc.uncertainty import Normal, Uniform
    >>> with_dof(Uniform(-1, 1), 8).dof
    8.0
    >>> with_dof(Normal(0, 1), u_rel_u=0.5).dof
    2.0
    """
    if (dof is None) == (u_rel_u is None):
        raise DistributionError(
            "expected one of dof and u_rel_u (ν = ½ u_rel_u⁻², JCGM 100 G.4.2), got "
            f"{'both' if dof is not None else 'neither'}",
            field="dof",
        )
    if u_rel_u is not None:
        return WithDof(dist, dof_from_relative_uncertainty(u_rel_u), u_rel_u)
    return WithDof(dist, _positive("dof", dof))


def stated_moments(dist: Distribution) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """The estimate ``(k,)`` and covariance ``(k, k)`` the GUM takes, where not the PDF's moments.

    For a :class:`TypeA` input ``x̄`` and ``u² = s²/n`` (JCGM 100 §4.2), for a
    :class:`WithDof` input the base PDF's expectation and variance (G.4), and for ``k``
    independent copies of one of these (:class:`IID`) the same ``k`` times. (A
    :class:`StudentT` given as such is read by :func:`~mtmc.uncertainty.propagation.gum` itself:
    its location and ``scale``, where it has an expectation.)

    Parameters
    ----------
    dist : Distribution

    Returns
    -------
    (ndarray, ndarray) or None
        None for any other PDF: the GUM then takes its expectation and standard
        deviation (or covariance).
    """
    if isinstance(dist, IID):
        inner = stated_moments(dist.base)
        if inner is None:
            return None
        return np.full(dist.k, inner[0][0]), np.eye(dist.k) * inner[1][0, 0]
    if isinstance(dist, TypeA):
        return np.array([dist.mean]), np.array([[dist.u**2]])
    if isinstance(dist, WithDof):
        mean = np.atleast_1d(np.asarray(dist.base.mean, dtype=np.float64))
        cov = getattr(dist.base, "cov", None)
        if cov is None:
            cov = np.diag(np.atleast_1d(np.asarray(dist.base.std, dtype=np.float64)) ** 2)
        return mean, np.asarray(cov, dtype=np.float64)
    return None
