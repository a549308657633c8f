"""Probability density functions for the input quantities (JCGM 101:2008 §6.4).

Each PDF is a small frozen dataclass with its expectation ``mean``, its standard deviation
``std`` (the standard uncertainty it implies), its dimension ``dim`` (0 for a scalar, ``k``
for a ``k``-variate PDF), the degrees of freedom ``dof`` it implies (``math.inf`` unless
the PDF itself carries a finite number, as the scaled-and-shifted t does), and a
``sample(rng, n)`` method returning ``(n,)`` or ``(n, k)`` draws made with the numbered
procedure of the clause cited in its docstring.

Every PDF prints as text that :func:`parse_distribution` reads back to an equal object:

>>> str(Normal(0, 1))
'normal(0, 1)'
>>> parse_distribution("uniform(-1, 1)")
Uniform(low=-1.0, high=1.0)
>>> parse_distribution(str(Trapezoidal(-2, 2, 0.5))) == Trapezoidal(-2, 2, 0.5)
True

For randomised quasi-Monte Carlo (``sampling="sobol"`` of
:func:`~mtmc.uncertainty.montecarlo.monte_carlo`) each PDF also maps points of the unit
cube to draws: ``uniform_dims`` coordinates per draw through ``from_uniform``, for a
scalar PDF its inverse CDF ``ppf`` (a ``k``-variate normal: ``k`` coordinates, the
Cholesky factor applied to their normal quantiles).

Standard normal draws come from the Generator's ziggurat sampler by default; the
Box–Muller transform (Stryczek eq. 6) is available as ``normal_method=
"box-muller"`` for reproducing that paper's figure (see :func:`standard_normal`).
"""

from __future__ import annotations

import abc
import ast
import dataclasses
import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from typing import TYPE_CHECKING, Any, ClassVar, Literal, NoReturn, TypeVar, cast

import numpy as np
from numpy.typing import NDArray

from mtmc.document import read_number
from mtmc.errors import DistributionError, MtmcError
from mtmc.uncertainty.formula import parse_tree

__all__ = [
    "Arcsine",
    "Constant",
    "CurvilinearTrapezoid",
    "Distribution",
    "Exponential",
    "Gamma",
    "IID",
    "MultivariateNormal",
    "Normal",
    "NormalMethod",
    "StudentT",
    "Trapezoidal",
    "Triangular",
    "Uniform",
    "as_distribution",
    "distribution_names",
    "parse_distribution",
    "register_distribution",
    "register_modifier",
    "standard_normal",
]

NormalMethod = Literal["default", "box-muller"]
_NORMAL_METHODS = ("default", "box-muller")


def standard_normal(
    rng: np.random.Generator, size: int | tuple[int, ...], method: NormalMethod = "default"
) -> NDArray[np.float64]:
    """Draw standard normal numbers, by the Generator or by the Box–Muller transform.

    Parameters
    ----------
    rng : numpy.random.Generator
        The source of randomness.
    size : int or tuple of int
        Shape of the result; values fill it in C order.
    method : {"default", "box-muller"}
        ``"default"``: ``rng.standard_normal`` (ziggurat). ``"box-muller"``: the
        transform of Stryczek eq. 6 on pairs ``(U1, U2)`` of uniform draws,
        ``Z1 = sqrt(-2 ln U1) cos(2π U2)`` and its companion ``Z2 = sqrt(-2 ln U1)
        sin(2π U2)`` (Stryczek prints only the cosine branch; both are independent
        N(0, 1), so each pair gives two draws). ``U1`` is taken in (0, 1] so that the
        logarithm is finite.

    Returns
    -------
    ndarray of float64, shape ``size``

    Raises
    ------
    DistributionError
        If ``method`` is not one of the two names.

    Notes
    -----
    Both methods have the prefix property: the first ``m`` values of a draw of ``n >= m``
    values equal a draw of ``m`` values from the same generator state.

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> z = standard_normal(rng, 100_000, "box-muller")
    >>> bool(abs(z.mean()) < 0.02), bool(abs(z.std() - 1) < 0.02)
    (True, True)
    """
    shape = (size,) if isinstance(size, int | np.integer) else tuple(size)
    if method == "default":
        return rng.standard_normal(shape)
    if method == "box-muller":
        n = math.prod(shape)
        pairs = rng.random(((n + 1) // 2, 2))
        radius = np.sqrt(-2.0 * np.log1p(-pairs[:, 0]))  # ln(1 - U), 1 - U in (0, 1]
        angle = (2.0 * np.pi) * pairs[:, 1]
        z = np.empty(((n + 1) // 2, 2))
        np.multiply(radius, np.cos(angle), out=z[:, 0])
        np.multiply(radius, np.sin(angle), out=z[:, 1])
        return z.reshape(-1)[:n].reshape(shape)
    raise DistributionError(
        f"unknown normal method {method!r}; expected one of {', '.join(_NORMAL_METHODS)}",
        field="normal_method",
    )


# --------------------------------------------------------------------------- helpers
def _fmt(x: Any) -> str:
    """Format a number or nested list of numbers so that the text parses back exactly."""
    if isinstance(x, Distribution):
        return str(x)
    if isinstance(x, np.ndarray):
        return "[" + ", ".join(_fmt(v) for v in x) + "]"
    xf = float(x)
    if xf.is_integer() and abs(xf) < 1e15:
        return str(int(xf))
    return repr(xf)


def _real(
    name: str,
    value: Any,
    dist: str,
    *,
    positive: bool = False,
    nonnegative: bool = False,
) -> float:
    """Coerce a scalar parameter to a finite float, with a clear error if it is not."""
    kind = "a finite number"
    if positive:
        kind = "a finite number > 0"
    elif nonnegative:
        kind = "a finite number >= 0"
    if isinstance(value, bool | str) or np.ndim(value) != 0:
        raise DistributionError(f"{dist}: expected {kind}, got {value!r}", field=name)
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise DistributionError(f"{dist}: expected {kind}, got {value!r}", field=name) from None
    if not math.isfinite(v) or (positive and v <= 0.0) or (nonnegative and v < 0.0):
        raise DistributionError(f"{dist}: expected {kind}, got {value!r}", field=name)
    return v


def _check_n(n: Any) -> int:
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 0:
        raise DistributionError(f"expected a number of draws >= 0, got {n!r}", field="n")
    return int(n)


def _check_interval(dist: str, low: float, high: float) -> None:
    if not low < high:
        raise DistributionError(
            f"{dist}: expected low < high, got low={_fmt(low)}, high={_fmt(high)}", field="high"
        )


_REGISTRY: dict[str, type[Distribution]] = {}
_D = TypeVar("_D", bound="type[Distribution]")


def register_distribution(*names: str) -> Callable[[_D], _D]:
    """Class decorator registering a PDF under one or more text names.

    The first name is the canonical one (used by ``str``); the others are aliases.
    A name already taken raises :class:`DistributionError`, so no PDF silently replaces
    another.

    Parameters
    ----------
    *names : str
        Lower-case identifiers, e.g. ``"uniform", "rectangular"``.

    Returns
    -------
    callable
        The decorator; it sets ``cls.name`` to the first name.

    Raises
    ------
    DistributionError
        If a name is already registered or is not an identifier.
    """

    def decorate(cls: _D) -> _D:
        for nm in names:
            if not nm.isidentifier():
                raise DistributionError(f"expected an identifier, got {nm!r}", field="name")
            if nm in _REGISTRY:
                raise DistributionError(
                    f"distribution name {nm!r} is already registered to {_REGISTRY[nm].__name__}",
                    field="name",
                )
        for nm in names:
            _REGISTRY[nm] = cls
        cls.name = names[0]
        return cls

    return decorate


#: Keywords that the text of any distribution may end with (``dof=``, ``u_rel_u=``), each
#: with the function that applies it: ``apply(dist, **given) -> Distribution``.
_MODIFIERS: dict[str, Callable[..., Distribution]] = {}
_F = TypeVar("_F", bound="Callable[..., Distribution]")


def register_modifier(*keywords: str) -> Callable[[_F], _F]:
    """Function decorator registering keywords that the text of any distribution may take.

    ``parse_distribution("normal(0, 1, dof=8)")`` reads ``normal(0, 1)``, then calls the
    function registered for ``dof`` with that distribution and the keywords given:
    ``apply(Normal(0, 1), dof=8.0)``. A keyword that is a parameter of the distribution
    itself stays its parameter. A keyword already taken raises :class:`DistributionError`.

    Parameters
    ----------
    *keywords : str
        Identifiers, e.g. ``"dof", "u_rel_u"``.

    Returns
    -------
    callable
        The decorator.
    """

    def decorate(fn: _F) -> _F:
        for kw in keywords:
            if not kw.isidentifier() or kw in _MODIFIERS:
                raise DistributionError(
                    f"expected a new identifier as a modifier keyword, got {kw!r}", field="name"
                )
        for kw in keywords:
            _MODIFIERS[kw] = fn
        return fn

    return decorate


def distribution_names() -> list[str]:
    """All registered text names (canonical names and aliases), sorted.

    Returns
    -------
    list of str

    Examples
    --------
    >>> "normal" in distribution_names() and "rectangular" in distribution_names()
    True
    """
    return sorted(_REGISTRY)


# --------------------------------------------------------------------------- base class
class Distribution(abc.ABC):
    """A probability density function for an input quantity (JCGM 101 §6.4).

    Every subclass is a frozen dataclass and provides ``mean`` (expectation: float, or
    ``(k,)`` array for a ``k``-variate PDF), ``std`` (standard deviation, i.e. the
    standard uncertainty; same shape) and ``sample``; ``dim`` is 0 (scalar) unless
    overridden, ``dof`` is ``math.inf`` unless the PDF implies a finite number.

    Two distributions are equal when they have the same type and the same parameters
    (their canonical text is the same).
    """

    name: ClassVar[str] = "distribution"

    if TYPE_CHECKING:

        @property
        def mean(self) -> Any:
            """Expectation: float, or ``(k,)`` array for a ``k``-variate PDF."""

        @property
        def std(self) -> Any:
            """Standard deviation (the standard uncertainty): float or ``(k,)`` array."""

    @property
    def dim(self) -> int:
        """0 for a scalar PDF, ``k`` for a ``k``-variate one."""
        return 0

    @property
    def dof(self) -> float:
        """Effective degrees of freedom implied by the PDF (``math.inf`` by default)."""
        return math.inf

    @abc.abstractmethod
    def sample(
        self, rng: np.random.Generator, n: int, *, normal_method: NormalMethod = "default"
    ) -> NDArray[np.float64]:
        """Draw ``n`` values: shape ``(n,)`` (scalar) or ``(n, k)`` (``k``-variate)."""

    def ppf(self, u: Any) -> NDArray[np.float64]:
        """Inverse CDF (quantile function) of a scalar PDF at probabilities ``u`` in (0, 1).

        Parameters
        ----------
        u : array_like
            Probabilities, any shape.

        Returns
        -------
        ndarray
            The quantiles, the shape of ``u``.

        Raises
        ------
        DistributionError
            For a PDF without a quantile function (a vector PDF, or one drawn from
            several uniform numbers: see :attr:`uniform_dims`).
        """
        raise DistributionError(
            f"{self}: no quantile function (a draw takes {self.uniform_dims} uniform numbers)",
            field="ppf",
        )

    @property
    def uniform_dims(self) -> int:
        """Coordinates of a point of the unit cube that one draw takes (``from_uniform``)."""
        return 1

    def from_uniform(self, u: NDArray[np.float64]) -> NDArray[np.float64]:
        """Draws from points of the unit cube: ``(n, uniform_dims)`` -> ``(n,)`` or ``(n, k)``.

        A scalar PDF maps its one coordinate through :meth:`ppf` (the inverse-CDF
        method of JCGM 101 §6.4.1 NOTE applied to a quasi-random point instead of a
        pseudo-random number).
        """
        return self.ppf(u[:, 0])

    def _params(self) -> tuple[Any, ...]:
        return tuple(getattr(self, f.name) for f in dataclasses.fields(cast(Any, self)) if f.init)

    def __str__(self) -> str:
        return f"{self.name}({', '.join(_fmt(p) for p in self._params())})"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Distribution):
            return NotImplemented
        return type(self) is type(other) and str(self) == str(other)

    def __hash__(self) -> int:
        return hash((type(self).__name__, str(self)))


# --------------------------------------------------------------------------- scalar PDFs
@register_distribution("normal", "gaussian")
@dataclass(frozen=True, eq=False)
class Normal(Distribution):
    """Gaussian PDF N(μ, σ²) (JCGM 101 §6.4.7).

    Parameters
    ----------
    mean : float
        Expectation μ.
    std : float
        Standard deviation σ >= 0 (σ = 0 gives the constant μ).

    Notes
    -----
    Sampling (§6.4.7.4): ``ξ = μ + σ z`` with ``z`` a standard normal draw.

    Examples
    --------
    >>> d = Normal(10, 0.5)
    >>> d.mean, d.std, d.dim, d.dof
    (10.0, 0.5, 0, inf)
    """

    mean: float
    std: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "mean", _real("mean", self.mean, "normal"))
        object.__setattr__(self, "std", _real("std", self.std, "normal", nonnegative=True))

    def sample(
        self, rng: np.random.Generator, n: int, *, normal_method: NormalMethod = "default"
    ) -> NDArray[np.float64]:
        """Draw ``n`` values, shape ``(n,)`` (§6.4.7.4)."""
        z = standard_normal(rng, _check_n(n), normal_method)
        z *= self.std
        z += self.mean
        return z

    def ppf(self, u: Any) -> NDArray[np.float64]:
        """``μ + σ Φ⁻¹(u)``."""
        from scipy.special import ndtri

        return np.asarray(self.mean + self.std * ndtri(u), dtype=np.float64)


@dataclass(frozen=True, eq=False)
class _Interval(Distribution):
    """A PDF on the interval ``[a, b]``, symmetric about its middle: limits and expectation."""

    low: float
    high: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "low", _real("low", self.low, self.name))
        object.__setattr__(self, "high", _real("high", self.high, self.name))
        _check_interval(self.name, self.low, self.high)

    @property
    def mean(self) -> float:
        """Expectation ``(a + b)/2``."""
        return 0.5 * (self.low + self.high)


@register_distribution("uniform", "rectangular")
@dataclass(frozen=True, eq=False)
class Uniform(_Interval):
    """Rectangular PDF R(a, b) (JCGM 101 §6.4.2).

    Parameters
    ----------
    low, high : float
        Limits ``a < b``.

    Notes
    -----
    Expectation ``(a + b)/2``, variance ``(b - a)²/12`` (§6.4.2.3); sampling ``ξ = a +
    (b - a) r`` with ``r`` from R(0, 1) (§6.4.2.4).

    Examples
    --------
    >>> d = Uniform(-1, 1)
    >>> d.mean, round(d.std**2, 12)
    (0.0, 0.333333333333)
    """

    @property
    def std(self) -> float:
        """Standard deviation ``(b - a)/√12``."""
        return (self.high - self.low) / math.sqrt(12.0)

    def sample(
        self, rng: np.random.Generator, n: int, *, normal_method: NormalMethod = "default"
    ) -> NDArray[np.float64]:
        """Draw ``n`` values, shape ``(n,)`` (§6.4.2.4)."""
        r = rng.random(_check_n(n))
        r *= self.high - self.low
        r += self.low
        return r

    def ppf(self, u: Any) -> NDArray[np.float64]:
        """``a + (b - a) u``."""
        return np.asarray(self.low + (self.high - self.low) * np.asarray(u, dtype=np.float64))


@register_distribution("triangular")
@dataclass(frozen=True, eq=False)
class Triangular(Distribution):
    """Triangular PDF on ``[a, b]`` with mode ``c`` (JCGM 101 §6.4.5; asymmetric extension).

    Parameters
    ----------
    low, high : float
        Limits ``a < b``.
    mode : float or None
        Peak ``c`` with ``a <= c <= b``; ``None`` (default) is the symmetric case
        ``c = (a + b)/2`` of §6.4.5.

    Notes
    -----
    Expectation ``(a + b + c)/3`` and variance ``(a² + b² + c² - ab - ac - bc)/18``
    (both reduce to §6.4.5.3, ``(b - a)²/24``, for the symmetric case). Sampling: for
    ``mode=None`` ``ξ = a + (b - a)(r1 + r2)/2`` (§6.4.5.4); for a given mode, which
    §6.4.5 does not treat, the inverse CDF ``ξ = a + sqrt(r (b - a)(c - a))`` for
    ``r < (c - a)/(b - a)``, else ``b - sqrt((1 - r)(b - a)(b - c))``.

    Examples
    --------
    >>> str(Triangular(0, 3)), str(Triangular(0, 3, 1))
    ('triangular(0, 3)', 'triangular(0, 3, 1)')
    """

    low: float
    high: float
    mode: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "low", _real("low", self.low, "triangular"))
        object.__setattr__(self, "high", _real("high", self.high, "triangular"))
        _check_interval("triangular", self.low, self.high)
        if self.mode is not None:
            c = _real("mode", self.mode, "triangular")
            if not self.low <= c <= self.high:
                raise DistributionError(
                    f"triangular: expected low <= mode <= high, got mode={_fmt(c)} outside "
                    f"[{_fmt(self.low)}, {_fmt(self.high)}]",
                    field="mode",
                )
            object.__setattr__(self, "mode", c)

    def _params(self) -> tuple[Any, ...]:
        if self.mode is None:
            return (self.low, self.high)
        return (self.low, self.high, self.mode)

    @property
    def _c(self) -> float:
        return 0.5 * (self.low + self.high) if self.mode is None else self.mode

    @property
    def mean(self) -> float:
        """Expectation ``(a + b + c)/3``."""
        return (self.low + self.high + self._c) / 3.0

    @property
    def std(self) -> float:
        """Standard deviation ``sqrt((a² + b² + c² - ab - ac - bc)/18)``."""
        a, b, c = self.low, self.high, self._c
        return math.sqrt((a * a + b * b + c * c - a * b - a * c - b * c) / 18.0)

    def sample(
        self, rng: np.random.Generator, n: int, *, normal_method: NormalMethod = "default"
    ) -> NDArray[np.float64]:
        """Draw ``n`` values, shape ``(n,)`` (§6.4.5.4 or the inverse CDF)."""
        n = _check_n(n)
        a, b = self.low, self.high
        if self.mode is None:
            r = rng.random((n, 2))
            return a + (0.5 * (b - a)) * (r[:, 0] + r[:, 1])
        return self.ppf(rng.random(n))

    def ppf(self, u: Any) -> NDArray[np.float64]:
        """The inverse CDF: ``a + sqrt(u (b - a)(c - a))`` below ``(c - a)/(b - a)``.

        Above it ``b - sqrt((1 - u)(b - a)(b - c))``.
        """
        a, b, c = self.low, self.high, self._c
        r = np.asarray(u, dtype=np.float64)
        split = (c - a) / (b - a)
        left = a + np.sqrt(r * ((b - a) * (c - a)))
        right = b - np.sqrt((1.0 - r) * ((b - a) * (b - c)))
        return np.asarray(np.where(r < split, left, right))


@register_distribution("trapezoidal", "trapezoid")
@dataclass(frozen=True, eq=False)
class Trapezoidal(_Interval):
    """Symmetric trapezoidal PDF Trap(a, b, β) (JCGM 101 §6.4.4).

    Parameters
    ----------
    low, high : float
        Limits ``a < b`` of the base.
    beta : float
        Ratio ``0 <= β <= 1`` of the width of the top to that of the base (β = 0 is the
        triangular PDF, β = 1 the rectangular one).

    Notes
    -----
    Expectation ``(a + b)/2``, variance ``(b - a)²(1 + β²)/24`` (§6.4.4.3). Sampling as
    the sum of two rectangular variables (§6.4.4.4): ``ξ = a + (b - a)[(1 + β) r1 +
    (1 - β) r2]/2``.

    Examples
    --------
    >>> round(Trapezoidal(-1, 1, 1).std, 12) == round(Uniform(-1, 1).std, 12)
    True
    """

    beta: float

    def __post_init__(self) -> None:
        super().__post_init__()
        beta = _real("beta", self.beta, "trapezoidal")
        if not 0.0 <= beta <= 1.0:
            raise DistributionError(
                f"trapezoidal: expected 0 <= beta <= 1, got {_fmt(beta)}", field="beta"
            )
        object.__setattr__(self, "beta", beta)

    @property
    def std(self) -> float:
        """Standard deviation ``(b - a) sqrt((1 + β²)/24)``."""
        return (self.high - self.low) * math.sqrt((1.0 + self.beta**2) / 24.0)

    def sample(
        self, rng: np.random.Generator, n: int, *, normal_method: NormalMethod = "default"
    ) -> NDArray[np.float64]:
        """Draw ``n`` values, shape ``(n,)`` (§6.4.4.4)."""
        r = rng.random((_check_n(n), 2))
        half = 0.5 * (self.high - self.low)
        return self.low + half * ((1.0 + self.beta) * r[:, 0] + (1.0 - self.beta) * r[:, 1])

    def ppf(self, u: Any) -> NDArray[np.float64]:
        """Inverse of the piecewise quadratic / linear / quadratic CDF.

        With ``h = (b - a)/2``, ``t = β h`` and the height ``H = 1/(h + t)`` of the PDF,
        ``F = H (y + h)²/(2(h - t))`` on the rising side (``y = x - (a + b)/2``), linear
        with slope ``H`` on the top, and symmetric.
        """
        r = np.asarray(u, dtype=np.float64)
        h = 0.5 * (self.high - self.low)
        t = self.beta * h
        H = 1.0 / (h + t)
        u1 = 0.5 * H * (h - t)  # the CDF at the start of the top
        q = np.minimum(r, 1.0 - r)
        side = -h + np.sqrt(2.0 * q * (h - t) / H)
        y = np.where(q < u1, side, -t + (q - u1) / H)
        y = np.where(r <= 0.5, y, -y)
        return np.asarray(0.5 * (self.low + self.high) + y)


@register_distribution("ctrap", "curvilinear_trapezoid")
@dataclass(frozen=True, eq=False)
class CurvilinearTrapezoid(_Interval):
    """Curvilinear trapezoidal PDF CTrap(a, b, d) (JCGM 101 §6.4.3).

    A rectangular PDF with limits ``a``, ``b`` that are themselves inexact by ``±d``:
    the semi-width is uniform on ``[w - d, w + d]`` with ``w = (b - a)/2``.

    Parameters
    ----------
    low, high : float
        Nominal limits ``a < b``.
    d : float
        Half-width of the inexactness of the limits, ``0 <= d <= (b - a)/2``.

    Notes
    -----
    Expectation ``(a + b)/2``, variance ``w²/3 + d²/9`` (§6.4.3.3). Sampling (§6.4.3.4):
    ``a_s = (a - d) + 2 d r1``, ``b_s = (a + b) - a_s``, ``ξ = a_s + (b_s - a_s) r2``.

    Examples
    --------
    >>> d = CurvilinearTrapezoid(-1, 1, 0.3)
    >>> round(d.std**2, 12) == round(1 / 3 + 0.09 / 9, 12)
    True
    """

    d: float

    def __post_init__(self) -> None:
        super().__post_init__()
        d = _real("d", self.d, "ctrap", nonnegative=True)
        if d > 0.5 * (self.high - self.low):
            raise DistributionError(
                f"ctrap: expected 0 <= d <= (high - low)/2 = {_fmt(0.5 * (self.high - self.low))},"
                f" got {_fmt(d)}",
                field="d",
            )
        object.__setattr__(self, "d", d)

    @property
    def std(self) -> float:
        """Standard deviation ``sqrt(w²/3 + d²/9)``, ``w = (b - a)/2``."""
        w = 0.5 * (self.high - self.low)
        return math.sqrt(w * w / 3.0 + self.d**2 / 9.0)

    def sample(
        self, rng: np.random.Generator, n: int, *, normal_method: NormalMethod = "default"
    ) -> NDArray[np.float64]:
        """Draw ``n`` values, shape ``(n,)`` (§6.4.3.4)."""
        r = rng.random((_check_n(n), 2))
        a_s = (self.low - self.d) + (2.0 * self.d) * r[:, 0]
        b_s = (self.low + self.high) - a_s
        return a_s + (b_s - a_s) * r[:, 1]

    def cdf(self, x: Any) -> NDArray[np.float64]:
        """The distribution function, in closed form.

        With ``y = x - (a + b)/2``, ``w = (b - a)/2`` and the half-width ``s`` uniform on
        ``[w - d, w + d]``, ``F = 1/2 + sign(y) G(|y|)/2`` where ``G(y) = E[min(1, y/s)]``:
        ``y ln((w + d)/(w - d))/(2d)`` for ``y <= w - d``, ``(y - w + d + y ln((w + d)/y))
        /(2d)`` up to ``w + d``, then 1 (``y/w`` for ``d = 0``). Its derivative is the PDF
        of §6.4.3.2, ``ln((w + d)/max(|y|, w - d))/(4d)``.
        """
        y = np.asarray(x, dtype=np.float64) - 0.5 * (self.low + self.high)
        return np.asarray(0.5 + 0.5 * np.sign(y) * self._g(np.abs(y)))

    def _g(self, y: NDArray[np.float64]) -> NDArray[np.float64]:
        w, d = 0.5 * (self.high - self.low), self.d
        lo, hi = w - d, w + d
        if d == 0.0:
            return np.asarray(np.minimum(y / w, 1.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            inner = (y - lo + y * np.log(hi / np.maximum(y, lo))) / (2.0 * d)
            below = y * np.log(hi / lo) / (2.0 * d) if lo > 0.0 else np.zeros_like(y)
        return np.asarray(np.where(y >= hi, 1.0, np.where(y <= lo, below, inner)))

    def ppf(self, u: Any) -> NDArray[np.float64]:
        """Inverse of :meth:`cdf`: closed form up to ``|y| = w - d``, beyond it bisection.

        ``G`` is increasing on ``[w - d, w + d]``; 64 halvings of that interval give the
        quantile to rounding.
        """
        r = np.asarray(u, dtype=np.float64)
        w, d = 0.5 * (self.high - self.low), self.d
        lo, hi = w - d, w + d
        g = np.abs(2.0 * r - 1.0)  # G(|y|) of the quantile
        if d == 0.0:
            y = g * w
        else:
            glo = lo * math.log(hi / lo) / (2.0 * d) if lo > 0.0 else 0.0
            a = np.full(g.shape, lo)
            b = np.full(g.shape, hi)
            for _ in range(64):
                m = 0.5 * (a + b)
                below = self._g(m) < g
                a = np.where(below, m, a)
                b = np.where(below, b, m)
            y = np.where(g <= glo, g * (2.0 * d) / math.log(hi / lo) if lo > 0.0 else 0.0, a)
        return np.asarray(0.5 * (self.low + self.high) + np.sign(r - 0.5) * y)


@register_distribution("arcsine", "u_shaped")
@dataclass(frozen=True, eq=False)
class Arcsine(_Interval):
    """Arc sine (U-shaped) PDF U(a, b) (JCGM 101 §6.4.6).

    Parameters
    ----------
    low, high : float
        Limits ``a < b``.

    Notes
    -----
    Expectation ``(a + b)/2``, variance ``(b - a)²/8`` (§6.4.6.3). Sampling (§6.4.6.4):
    ``ξ = (a + b)/2 + (b - a)/2 · sin(2π r)``.

    Examples
    --------
    >>> Arcsine(-1, 1).std
    0.7071067811865475
    """

    @property
    def std(self) -> float:
        """Standard deviation ``(b - a)/√8``."""
        return (self.high - self.low) / math.sqrt(8.0)

    def sample(
        self, rng: np.random.Generator, n: int, *, normal_method: NormalMethod = "default"
    ) -> NDArray[np.float64]:
        """Draw ``n`` values, shape ``(n,)`` (§6.4.6.4)."""
        r = rng.random(_check_n(n))
        return self.mean + (0.5 * (self.high - self.low)) * np.sin((2.0 * np.pi) * r)

    def ppf(self, u: Any) -> NDArray[np.float64]:
        """``(a + b)/2 + (b - a)/2 · sin(π (u - 1/2))``.

        The inverse of ``F = 1/2 + arcsin((2x - a - b)/(b - a))/π``.
        """
        r = np.asarray(u, dtype=np.float64)
        return np.asarray(self.mean + (0.5 * (self.high - self.low)) * np.sin(np.pi * (r - 0.5)))


@register_distribution("t", "student_t")
@dataclass(frozen=True, eq=False)
class StudentT(Distribution):
    """Scaled and shifted t PDF t_ν(μ, s²) (JCGM 101 §6.4.9).

    Typically from ``n`` indications with mean ``x̄`` and standard deviation ``s``:
    ``df = n - 1``, ``loc = x̄``, ``scale = s/√n`` (§6.4.9.2).

    Parameters
    ----------
    df : float
        Degrees of freedom ν > 0 (need not be an integer).
    loc : float, default 0
        Location μ.
    scale : float, default 1
        Scale ``s > 0``.

    Notes
    -----
    Expectation μ for ν > 1 (NaN otherwise); variance ``ν s²/(ν - 2)`` for ν > 2
    (§6.4.9.3; ``inf`` otherwise). ``dof`` is ν. Sampling (§6.4.9.5): ``ξ = μ + s t``
    with ``t`` a draw from the standard t with ν degrees of freedom: the Generator's
    ``standard_t`` by default, or ``z / sqrt(χ²_ν/ν)`` with ``z`` a Box–Muller normal
    when ``normal_method="box-muller"``.

    Examples
    --------
    >>> d = StudentT(4, loc=1, scale=0.5)
    >>> d.dof, d.mean, d.std == 0.5 * math.sqrt(2)
    (4.0, 1.0, True)
    >>> str(d), str(StudentT(9))
    ('t(4, 1, 0.5)', 't(9)')
    """

    df: float
    loc: float = 0.0
    scale: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "df", _real("df", self.df, "t", positive=True))
        object.__setattr__(self, "loc", _real("loc", self.loc, "t"))
        object.__setattr__(self, "scale", _real("scale", self.scale, "t", positive=True))

    def _params(self) -> tuple[Any, ...]:
        if self.loc == 0.0 and self.scale == 1.0:
            return (self.df,)
        return (self.df, self.loc, self.scale)

    @property
    def mean(self) -> float:
        """Expectation μ (ν > 1), else NaN."""
        return self.loc if self.df > 1.0 else math.nan

    @property
    def std(self) -> float:
        """Standard deviation ``s sqrt(ν/(ν - 2))`` (ν > 2), else ``inf``."""
        if self.df <= 2.0:
            return math.inf
        return self.scale * math.sqrt(self.df / (self.df - 2.0))

    @property
    def dof(self) -> float:
        """ν."""
        return self.df

    def sample(
        self, rng: np.random.Generator, n: int, *, normal_method: NormalMethod = "default"
    ) -> NDArray[np.float64]:
        """Draw ``n`` values, shape ``(n,)`` (§6.4.9.5)."""
        n = _check_n(n)
        if normal_method == "default":
            t = rng.standard_t(self.df, n)
        else:
            z = standard_normal(rng, n, normal_method)
            chi2 = 2.0 * rng.standard_gamma(0.5 * self.df, n)
            t = z / np.sqrt(chi2 / self.df)
        return self.loc + self.scale * t

    def ppf(self, u: Any) -> NDArray[np.float64]:
        """``μ + s t_ν⁻¹(u)``."""
        from scipy.special import stdtrit

        return np.asarray(self.loc + self.scale * stdtrit(self.df, u), dtype=np.float64)


@register_distribution("exponential")
@dataclass(frozen=True, eq=False)
class Exponential(Distribution):
    """Exponential PDF Ex(1/x) for a non-negative quantity of known expectation (§6.4.10).

    Parameters
    ----------
    mean : float
        Expectation ``x > 0``.

    Notes
    -----
    Standard deviation ``x`` (§6.4.10.3); sampling ``ξ = -x ln r`` (§6.4.10.4), here by
    the Generator's standard exponential sampler.

    Examples
    --------
    >>> Exponential(2).std
    2.0
    """

    mean: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "mean", _real("mean", self.mean, "exponential", positive=True))

    @property
    def std(self) -> float:
        """Standard deviation, equal to the expectation."""
        return self.mean

    def sample(
        self, rng: np.random.Generator, n: int, *, normal_method: NormalMethod = "default"
    ) -> NDArray[np.float64]:
        """Draw ``n`` values, shape ``(n,)`` (§6.4.10.4)."""
        return self.mean * rng.standard_exponential(_check_n(n))

    def ppf(self, u: Any) -> NDArray[np.float64]:
        """``-x ln(1 - u)``."""
        return np.asarray(-self.mean * np.log1p(-np.asarray(u, dtype=np.float64)))


@register_distribution("gamma")
@dataclass(frozen=True, eq=False)
class Gamma(Distribution):
    """Gamma PDF with shape ``k`` and scale ``θ`` (JCGM 101 §6.4.11).

    JCGM 101 writes G(α, β) with rate β; here ``shape = α`` and ``scale = 1/β``. For a
    quantity estimated from an observed count ``q`` (§6.4.11.1), JCGM 101 assigns
    G(q + 1, 1): ``Gamma(q + 1, 1)``, expectation and variance ``q + 1``.

    Parameters
    ----------
    shape : float
        Shape ``k > 0``.
    scale : float
        Scale ``θ > 0``.

    Notes
    -----
    Expectation ``kθ``, variance ``kθ²`` (§6.4.11.3).

    Examples
    --------
    >>> g = Gamma(4, 0.5)
    >>> g.mean, g.std
    (2.0, 1.0)
    """

    shape: float
    scale: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "shape", _real("shape", self.shape, "gamma", positive=True))
        object.__setattr__(self, "scale", _real("scale", self.scale, "gamma", positive=True))

    @property
    def mean(self) -> float:
        """Expectation ``kθ``."""
        return self.shape * self.scale

    @property
    def std(self) -> float:
        """Standard deviation ``√k θ``."""
        return math.sqrt(self.shape) * self.scale

    def sample(
        self, rng: np.random.Generator, n: int, *, normal_method: NormalMethod = "default"
    ) -> NDArray[np.float64]:
        """Draw ``n`` values, shape ``(n,)`` (§6.4.11.4)."""
        return self.scale * rng.standard_gamma(self.shape, _check_n(n))

    def ppf(self, u: Any) -> NDArray[np.float64]:
        """``θ P⁻¹(k, u)``, ``P`` the regularised lower incomplete gamma function."""
        from scipy.special import gammaincinv

        return np.asarray(self.scale * gammaincinv(self.shape, u), dtype=np.float64)


# --------------------------------------------------------------------------- vector PDFs
def _vector(name: str, value: Any, dist: str) -> NDArray[np.float64]:
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise DistributionError(
            f"{dist}: expected a list of numbers, got {value!r}", field=name
        ) from None
    if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)):
        raise DistributionError(
            f"{dist}: expected a non-empty list of finite numbers, got {value!r}", field=name
        )
    arr.setflags(write=False)
    return arr


@register_distribution("mvnormal", "multivariate_normal")
@dataclass(frozen=True, eq=False)
class MultivariateNormal(Distribution):
    """Multivariate Gaussian PDF N(μ, V) (JCGM 101 §6.4.8).

    Parameters
    ----------
    mean : array_like, shape (k,)
        Expectation μ.
    cov : array_like, shape (k, k)
        Covariance matrix V: symmetric and positive semi-definite.

    Notes
    -----
    Sampling (§6.4.8.4): ``ξ = μ + Rᵀ z`` with ``RᵀR = V`` (Cholesky factor) and ``z``
    a vector of ``k`` standard normal draws. For a singular (semi-definite) V, where the
    Cholesky factor does not exist, the factor ``Q diag(sqrt(λ))`` of the eigen
    decomposition ``V = Q diag(λ) Qᵀ`` is used instead (§6.4.8.4 NOTE).

    Examples
    --------
    >>> d = MultivariateNormal([0, 1], [[4, 1], [1, 1]])
    >>> d.dim, d.std.tolist()
    (2, [2.0, 1.0])
    >>> str(d)
    'mvnormal([0, 1], [[4, 1], [1, 1]])'
    """

    mean: NDArray[np.float64]
    cov: NDArray[np.float64]
    _factor: NDArray[np.float64] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        mean = _vector("mean", self.mean, "mvnormal")
        k = mean.size
        try:
            cov = np.array(self.cov, dtype=np.float64)
        except (TypeError, ValueError):
            raise DistributionError(
                f"mvnormal: expected a {k}x{k} matrix of numbers, got {self.cov!r}", field="cov"
            ) from None
        if cov.shape != (k, k) or not np.all(np.isfinite(cov)):
            raise DistributionError(
                f"mvnormal: expected a {k}x{k} matrix of finite numbers (k = len(mean)), "
                f"got shape {cov.shape}",
                field="cov",
            )
        scale = float(np.max(np.abs(cov))) if cov.size else 0.0
        if not np.allclose(cov, cov.T, rtol=0.0, atol=1e-12 * max(scale, 1e-300)):
            raise DistributionError("mvnormal: expected a symmetric covariance", field="cov")
        cov = 0.5 * (cov + cov.T)
        try:
            factor = np.linalg.cholesky(cov)
        except np.linalg.LinAlgError:
            lam, q = np.linalg.eigh(cov)
            if lam.min() < -1e-10 * max(scale, 1e-300):
                raise DistributionError(
                    "mvnormal: expected a positive semi-definite covariance, smallest "
                    f"eigenvalue is {lam.min():.6g}",
                    field="cov",
                ) from None
            factor = q * np.sqrt(np.clip(lam, 0.0, None))
        cov.setflags(write=False)
        factor.setflags(write=False)
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "cov", cov)
        object.__setattr__(self, "_factor", factor)

    def __repr__(self) -> str:
        return f"MultivariateNormal(mean={self.mean.tolist()}, cov={self.cov.tolist()})"

    @property
    def std(self) -> NDArray[np.float64]:
        """Standard deviations ``sqrt(diag(V))``, shape ``(k,)``."""
        return np.sqrt(np.diag(self.cov))

    @property
    def dim(self) -> int:
        """``k``."""
        return int(self.mean.size)

    def sample(
        self, rng: np.random.Generator, n: int, *, normal_method: NormalMethod = "default"
    ) -> NDArray[np.float64]:
        """Draw ``n`` vectors, shape ``(n, k)`` (§6.4.8.4)."""
        z = standard_normal(rng, (_check_n(n), self.dim), normal_method)
        out = z @ self._factor.T
        out += self.mean
        return out

    @property
    def uniform_dims(self) -> int:
        """``k``: one coordinate per component."""
        return self.dim

    def from_uniform(self, u: NDArray[np.float64]) -> NDArray[np.float64]:
        """``μ + R^T z`` with ``z = Φ⁻¹(u)`` component by component (§6.4.8.4)."""
        from scipy.special import ndtri

        out = ndtri(u) @ self._factor.T
        out += self.mean
        return np.asarray(out)


@register_distribution("iid")
@dataclass(frozen=True, eq=False)
class IID(Distribution):
    """``k`` independent, identically distributed copies of a scalar PDF, as one input.

    A Monte Carlo input with many independent components of one PDF — the noise of each
    coordinate of every point a laser tracker or a touch probe measures — without a
    ``k × k`` covariance matrix and without ``k`` separately named inputs.

    Parameters
    ----------
    base : Distribution
        The scalar PDF of each component.
    k : int
        Number of components, ``k >= 1``.

    Notes
    -----
    ``sample(rng, n)`` draws ``n·k`` values of ``base`` from ``rng`` in one call and
    returns them as ``(n, k)`` in C order (trial by trial). An input of dimension ``k``
    is drawn in seed blocks of at most :data:`~mtmc.uncertainty.sampling.MAX_SEED_BLOCK_VALUES`
    numbers (see :func:`~mtmc.uncertainty.sampling.seed_block_trials`), so the memory of
    a run does not grow with ``k`` times a fixed number of trials.

    Examples
    --------
    >>> d = IID(Normal(0, 2), 3)
    >>> d.dim, d.std.tolist(), str(d)
    (3, [2.0, 2.0, 2.0], 'iid(normal(0, 2), 3)')
    >>> d.sample(np.random.default_rng(0), 4).shape
    (4, 3)
    """

    base: Distribution
    k: int

    def __post_init__(self) -> None:
        if not isinstance(self.base, Distribution):
            raise DistributionError(
                f"iid: expected a distribution as first parameter, got {self.base!r}",
                field="base",
            )
        if self.base.dim != 0 or isinstance(self.base, IID):
            raise DistributionError(
                f"iid: expected a scalar distribution, got {self.base}", field="base"
            )
        k: Any = self.k
        if isinstance(k, float) and k.is_integer():
            k = int(k)
        if isinstance(k, bool) or not isinstance(k, int | np.integer) or k < 1:
            raise DistributionError(
                f"iid: expected a whole number of components k >= 1, got {self.k!r}", field="k"
            )
        object.__setattr__(self, "k", int(k))

    def __repr__(self) -> str:
        return f"IID(base={self.base!r}, k={self.k})"

    @property
    def mean(self) -> NDArray[np.float64]:
        """The base mean repeated, shape ``(k,)``."""
        return np.full(self.k, float(self.base.mean))

    @property
    def std(self) -> NDArray[np.float64]:
        """The base standard deviation repeated, shape ``(k,)``."""
        return np.full(self.k, float(self.base.std))

    @property
    def dim(self) -> int:
        """``k``."""
        return self.k

    @property
    def dof(self) -> float:
        """The degrees of freedom of the base PDF."""
        return self.base.dof

    def sample(
        self, rng: np.random.Generator, n: int, *, normal_method: NormalMethod = "default"
    ) -> NDArray[np.float64]:
        """Draw ``n`` vectors of ``k`` independent values, shape ``(n, k)``."""
        n = _check_n(n)
        return self.base.sample(rng, n * self.k, normal_method=normal_method).reshape(n, self.k)

    @property
    def uniform_dims(self) -> int:
        """``k`` times those of the base PDF."""
        return self.k * self.base.uniform_dims

    def from_uniform(self, u: NDArray[np.float64]) -> NDArray[np.float64]:
        """Each component from its own ``base.uniform_dims`` coordinates."""
        n, s = u.shape[0], self.base.uniform_dims
        flat = self.base.from_uniform(np.ascontiguousarray(u).reshape(n * self.k, s))
        return flat.reshape(n, self.k)


@register_distribution("constant")
@dataclass(frozen=True, eq=False)
class Constant(Distribution):
    """A quantity known exactly: a scalar or a ``(k,)`` vector (zero uncertainty).

    Parameters
    ----------
    value : float or array_like, shape (k,)

    Examples
    --------
    >>> Constant(2.5).sample(np.random.default_rng(0), 3)
    array([2.5, 2.5, 2.5])
    >>> Constant([1, 2]).dim
    2
    """

    value: Any

    def __post_init__(self) -> None:
        if np.ndim(self.value) == 0:
            object.__setattr__(self, "value", _real("value", self.value, "constant"))
        else:
            object.__setattr__(self, "value", _vector("value", self.value, "constant"))

    def __repr__(self) -> str:
        v = self.value.tolist() if isinstance(self.value, np.ndarray) else self.value
        return f"Constant(value={v!r})"

    @property
    def mean(self) -> Any:
        """The value."""
        return self.value

    @property
    def std(self) -> Any:
        """Zero (or zeros, shape ``(k,)``)."""
        return 0.0 if self.dim == 0 else np.zeros(self.dim)

    @property
    def dim(self) -> int:
        """0 for a scalar value, ``k`` for a vector."""
        return 0 if np.ndim(self.value) == 0 else int(np.size(self.value))

    def sample(
        self, rng: np.random.Generator, n: int, *, normal_method: NormalMethod = "default"
    ) -> NDArray[np.float64]:
        """Return ``n`` copies of the value, shape ``(n,)`` or ``(n, k)``."""
        n = _check_n(n)
        out = np.empty((n,) if self.dim == 0 else (n, self.dim))
        out[...] = self.value
        return out

    @property
    def uniform_dims(self) -> int:
        """None: a constant takes no coordinate."""
        return 0

    def ppf(self, u: Any) -> NDArray[np.float64]:
        """The value, whatever ``u`` (a scalar constant)."""
        if self.dim:
            return super().ppf(u)
        return np.full(np.shape(u), float(self.value))

    def from_uniform(self, u: NDArray[np.float64]) -> NDArray[np.float64]:
        """``n`` copies of the value."""
        out = np.empty((u.shape[0],) if self.dim == 0 else (u.shape[0], self.dim))
        out[...] = self.value
        return out


# --------------------------------------------------------------------------- parsing
#: The most components a distribution written as text may have (``iid(d, k)``,
#: ``mvnormal``): the GUM holds a k × k covariance of each input, and a propagate study of
#: ``iid(normal(0, 1), 4096)`` (20 000 trials) peaked at 1.8 GB and took 38 s.
MAX_COMPONENTS = 4096

_TOKEN = re.compile(
    r"\s*(?:(?P<num>[+-]?\.?\d(?:[\w.]|(?<=[eE])[+-])*)"  # read by read_number
    r"|(?P<name>[A-Za-z_][A-Za-z0-9_]*)|(?P<punct>[()\[\],=]))"
)

_Token = tuple[str, str, int]  # kind ("num", "name", "punct", "end"), text, column


class _Reader:
    """Read the text of a distribution: Python's :mod:`ast` gives its tree, nothing is evaluated.

    The text is cut into tokens (numbers with their sign, names, ``( ) [ ] , =``) and their
    order checked, so that a text that is not a distribution is refused at the first token
    out of place, saying what was expected there. Python's parser
    (:func:`~mtmc.uncertainty.formula.parse_tree`, as for a model expression) then
    reads the structure, with each name written ``_`` and each number ``0`` so that it sees
    nothing but the structure, and the tree is read back into PDFs: a call is a PDF, a number
    the float of its text, a bracketed list a list.
    """

    def __init__(self, text: str, file: str | None, line: int | None, field: str | None):
        self.text = text
        self.file, self.line, self.field = file, line, field
        self.tokens: list[_Token] = []
        pos = 0
        while pos < len(text):
            if text[pos:].strip() == "":
                break
            m = _TOKEN.match(text, pos)
            if m is None or m.end() == pos:
                col = pos + len(text[pos:]) - len(text[pos:].lstrip()) + 1
                self.fail(f"unexpected character {text[col - 1]!r}", col)
            kind = m.lastgroup or ""
            self.tokens.append((kind, m.group(kind), m.start(kind) + 1))
            pos = m.end()
        self.at = {col: tok for _, tok, col in self.tokens}
        self.numbers = {
            col: read_number(tok, partial(self.error, column=col))
            for kind, tok, col in self.tokens
            if kind == "num"
        }

    def error(self, message: str, column: int | None = None) -> DistributionError:
        return DistributionError(
            f"{message} in {self.text.strip()!r}",
            file=self.file,
            line=self.line,
            column=column,
            field=self.field,
        )

    def fail(self, message: str, column: int | None = None) -> NoReturn:
        raise self.error(message, column)

    def _expected(self, what: str, tok: _Token) -> NoReturn:
        self.fail(
            f"expected {what}, got {'end of text' if tok[0] == 'end' else repr(tok[1])}", tok[2]
        )

    def check(self) -> None:
        """Refuse the first token out of place, saying what was expected there.

        The states name what the next token may be: ``name`` (the text's distribution),
        ``argument`` (after ``(``: a parameter or ``)``), ``positional`` (after ``,`` in a
        call: a parameter), ``item`` (after ``[``: a value or ``]``), ``value`` (a number, a
        list or a distribution), ``next`` (after a value: ``,``, the closing bracket, or
        the end of the text after the last one).
        """
        toks = [*self.tokens, ("end", "", len(self.text) + 1)]
        self.open: list[tuple[str, set[str]]] = []  # "(" with the keywords given, or "["
        steps = {
            "name": self._name,
            "argument": self._argument,
            "positional": self._positional,
            "item": self._item,
            "value": self._value,
            "next": self._next,
        }
        want, i = "name", 0
        while want != "done":
            want, i = steps[want](toks, i)

    def _call(self, toks: list[_Token], i: int) -> tuple[str, int]:
        _, text, col = toks[i]
        if text.lower() not in _REGISTRY:
            names = ", ".join(distribution_names())
            self.fail(f"unknown distribution {text!r}; expected one of {names}", col)
        if toks[i + 1][1] != "(":
            self._expected("'('", toks[i + 1])
        self.open.append(("(", set()))
        return "argument", i + 2

    def _name(self, toks: list[_Token], i: int) -> tuple[str, int]:
        if toks[i][0] != "name":
            self._expected("a distribution name", toks[i])
        return self._call(toks, i)

    def _value(self, toks: list[_Token], i: int) -> tuple[str, int]:
        kind, text, _ = toks[i]
        if kind == "name":
            return self._call(toks, i)
        if kind == "num":
            return "next", i + 1
        if text != "[":
            self._expected("a number or a list", toks[i])
        self.open.append(("[", set()))
        return "item", i + 1

    def _argument(self, toks: list[_Token], i: int) -> tuple[str, int]:
        if toks[i][1] == ")":
            self.open.pop()
            return "next", i + 1
        return self._positional(toks, i)

    def _positional(self, toks: list[_Token], i: int) -> tuple[str, int]:
        kind, text, col = toks[i]
        given = self.open[-1][1]
        if kind == "name" and toks[i + 1][1] == "=":
            if text in given:
                self.fail(f"parameter {text!r} given twice", col)
            given.add(text)
            return "value", i + 2
        if given:
            self.fail("positional parameter after a keyword parameter", col)
        return "value", i

    def _item(self, toks: list[_Token], i: int) -> tuple[str, int]:
        if toks[i][1] == "]":
            self.open.pop()
            return "next", i + 1
        return "value", i

    def _next(self, toks: list[_Token], i: int) -> tuple[str, int]:
        kind, text, col = toks[i]
        if not self.open:
            if kind != "end":
                self.fail(f"unexpected {text!r} after the closing ')'", col)
            return "done", i
        bracket = self.open[-1][0]
        close = ")" if bracket == "(" else "]"
        if text == "," and kind == "punct":
            return ("positional" if bracket == "(" else "value"), i + 1
        if text != close or kind != "punct":
            self._expected(f"',' or {close!r}", toks[i])
        self.open.pop()
        return "next", i + 1

    def read(self) -> Distribution:
        """The distribution the text writes (after :meth:`check`)."""
        self.check()
        skeleton = [" "] * len(self.text)
        for kind, tok, col in self.tokens:
            mark = {"name": "_" * len(tok), "num": "0".ljust(len(tok))}.get(kind, tok)
            skeleton[col - 1 : col - 1 + len(tok)] = mark
        flat = "".join(skeleton)
        start = len(flat) - len(flat.lstrip())

        def error(message: str, column: int | None = None, **_line: Any) -> MtmcError:
            at = None if column is None else start + column  # a column of the text as given
            return DistributionError(
                message, file=self.file, line=self.line, column=at, field=self.field
            )

        tree = parse_tree(flat.strip(), error, shown=self.text.strip())
        return self.distribution(cast(ast.Call, tree.body), start + 1)  # check(): a call

    def value(self, node: ast.expr, start: int) -> Any:
        """A tree node of the skeleton back as a PDF, a float or a list of them."""
        if isinstance(node, ast.Call):
            return self.distribution(node, start)
        if isinstance(node, ast.List):
            return [self.value(n, start) for n in node.elts]
        return self.numbers[start + node.col_offset]  # the number as written

    def distribution(self, node: ast.Call, start: int) -> Distribution:
        col = start + node.col_offset
        cls = _REGISTRY[self.at[col].lower()]
        args = [self.value(a, start) for a in node.args]
        kwargs = {self.at[start + k.col_offset]: self.value(k.value, start) for k in node.keywords}
        params = [f for f in dataclasses.fields(cast(Any, cls)) if f.init]
        names = [f.name for f in params]
        modifiers = {k: kwargs.pop(k) for k in list(kwargs) if k in _MODIFIERS and k not in names}
        required = [
            f.name
            for f in params
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
        ]
        nargs = len(args) + len(kwargs)
        arity = (
            str(len(names)) if len(required) == len(names) else f"{len(required)} to {len(names)}"
        )
        signature = f"{cls.name}({', '.join(names)})"
        if len(args) > len(names) or nargs < len(required):
            self.fail(f"{cls.name} takes {arity} parameters ({signature}), got {nargs}", col)
        for key in kwargs:
            if key not in names:
                self.fail(
                    f"{cls.name} has no parameter {key!r}; expected one of "
                    f"{', '.join([*names, *sorted(_MODIFIERS)])}",
                    col,
                )
            if names.index(key) < len(args):
                self.fail(f"parameter {key!r} given twice", col)
        missing = [r for r in required if r not in kwargs and names.index(r) >= len(args)]
        if missing:
            self.fail(f"{cls.name} is missing parameter(s) {', '.join(missing)} ({signature})", col)
        try:
            dist = cls(*args, **kwargs)
            for apply in dict.fromkeys(_MODIFIERS[k] for k in modifiers):
                given = {k: v for k, v in modifiers.items() if _MODIFIERS[k] is apply}
                dist = apply(dist, **given)
        except DistributionError as exc:
            raise DistributionError(
                f"{exc.message} in {self.text.strip()!r}",
                file=self.file,
                line=self.line,
                column=col,
                field=self.field if self.field is not None else exc.field,
            ) from None
        if dist.dim > MAX_COMPONENTS:
            self.fail(
                f"{cls.name}: expected at most {MAX_COMPONENTS} components, got {dist.dim} "
                "(the GUM holds a k × k covariance of a k-variate input)",
                col,
            )
        return dist


def parse_distribution(
    text: str,
    *,
    file: str | None = None,
    line: int | None = None,
    field: str | None = None,
) -> Distribution:
    """Read a distribution from its text form, e.g. ``"normal(0, 0.5)"``.

    Grammar: ``name(arg, ...)`` where each argument is a number or a bracketed list of
    numbers or lists, optionally given as ``param=value`` after the positional ones. The
    text is read by Python's parser (:mod:`ast`), as a model expression is, after its tokens
    are checked; nothing is evaluated.

    =====================================================  ===========================
    text                                                   PDF
    =====================================================  ===========================
    ``normal(mean, std)`` (``gaussian``)                   :class:`Normal`
    ``uniform(low, high)`` (``rectangular``)               :class:`Uniform`
    ``triangular(low, high[, mode])``                      :class:`Triangular`
    ``trapezoidal(low, high, beta)`` (``trapezoid``)       :class:`Trapezoidal`
    ``ctrap(low, high, d)`` (``curvilinear_trapezoid``)    :class:`CurvilinearTrapezoid`
    ``arcsine(low, high)`` (``u_shaped``)                  :class:`Arcsine`
    ``t(df[, loc, scale])`` (``student_t``)                :class:`StudentT`
    ``exponential(mean)``                                  :class:`Exponential`
    ``gamma(shape, scale)``                                :class:`Gamma`
    ``mvnormal([m1, ...], [[v11, ...], ...])``             :class:`MultivariateNormal`
    ``constant(value)``                                    :class:`Constant`
    ``iid(dist, k)``                                       :class:`IID`
    ``type_a([x1, x2, ...][, pooled_s=s, pooled_dof=ν])``  :class:`~mtmc.uncertainty.typea.TypeA`
    =====================================================  ===========================

    Any distribution's text may end with ``dof=ν`` or ``u_rel_u=r`` (the degrees of
    freedom of its standard uncertainty, given or as ``ν = ½ r⁻²`` from its relative
    uncertainty, JCGM 100 G.4.2): ``"normal(0, 1, dof=8)"``, ``"uniform(-1, 1,
    u_rel_u=0.25)"`` (:func:`~mtmc.uncertainty.typea.with_dof`).

    Parameters
    ----------
    text : str
        The text to parse (names are case-insensitive).
    file, line, field : optional
        Where the text came from; they are put in the error message.

    Returns
    -------
    Distribution

    Raises
    ------
    DistributionError
        Unknown name, wrong number of parameters, a bad token, or an invalid parameter
        value; the message names the column and, if given, the file, line and field.

    Examples
    --------
    >>> parse_distribution("t(9, loc=10, scale=0.1)")
    StudentT(df=9.0, loc=10.0, scale=0.1)
    >>> parse_distribution("normal(0)")
    Traceback (most recent call last):
    ...
    mtmc.errors.DistributionError: line 1, column 1: normal takes 2 parameters \
(normal(mean, std)), got 1 in 'normal(0)'
    """
    if not isinstance(text, str):
        raise DistributionError(
            f"expected the text of a distribution, got {type(text).__name__}",
            file=file,
            line=line,
            field=field,
        )
    return _Reader(text, file, 1 if line is None and file is None else line, field).read()


def as_distribution(obj: Any, *, field: str | None = None) -> Distribution:
    """Coerce an input specification to a :class:`Distribution`.

    Parameters
    ----------
    obj : Distribution, number, array_like or str
        A Distribution is returned as is; a number or a 1-D array becomes a
        :class:`Constant`; a string is parsed by :func:`parse_distribution`.
    field : str, optional
        Name of the input, put in error messages.

    Returns
    -------
    Distribution

    Raises
    ------
    DistributionError
        If ``obj`` is none of these, or does not parse.

    Examples
    --------
    >>> as_distribution(3)
    Constant(value=3.0)
    >>> as_distribution("rectangular(0, 2)")
    Uniform(low=0.0, high=2.0)
    """
    if isinstance(obj, Distribution):
        return obj
    if isinstance(obj, str):
        return parse_distribution(obj, field=field)
    if isinstance(obj, bool) or obj is None:
        raise DistributionError(
            f"expected a distribution, a number or a string, got {obj!r}", field=field
        )
    try:
        arr = np.asarray(obj, dtype=np.float64)
    except (TypeError, ValueError):
        raise DistributionError(
            f"expected a distribution, a number or a string, got {obj!r}", field=field
        ) from None
    if arr.ndim > 1:
        raise DistributionError(
            f"expected a number or a 1-D vector for a constant, got shape {arr.shape}",
            field=field,
        )
    try:
        return Constant(float(arr) if arr.ndim == 0 else arr)
    except DistributionError as exc:
        raise DistributionError(exc.message, field=field or exc.field) from None
