"""Error generation functions (Aguado et al. 2016, §4.3): an error's value along an axis's travel.

Each function is a frozen value object; calling it on a batch of axis positions ``q`` of
shape ``(M,)`` returns the error values ``(M,)`` (mm for a displacement, rad for a
rotation). All of them are linear in their coefficients, ``f(q) = basis(q) @ c``, which
gives the derivative of an error with respect to its coefficients for identification.

Coefficients may carry a trial axis: ``coefficients`` of shape ``(n,)`` are shared by all
trials, shape ``(M, n)`` gives trial m its own function (a Monte Carlo over error
coefficients in one call).

- :class:`ConstantFunction` — ``c0``.
- :class:`PolynomialFunction` — ``c0 + c1 q + c2 q^2 + ...`` (q in mm or rad).
- :class:`LegendreSeries` — ``sum c_k P_k(t)``, ``t`` the position mapped from the travel
  ``[low, high]`` onto ``[-1, 1]``.
- :class:`ChebyshevSeries` — ``sum c_k T_k(t)``, same mapping.
- :class:`FourierSeries` — ``a0 + sum_k (a_k cos kq + b_k sin kq)``, for rotary axes.
- :class:`ErrorTable` — linear interpolation in a measured error map (optionally periodic).

Examples
--------
>>> import numpy as np
>>> f = LegendreSeries([0.0, 0.002, 0.001], low=0.0, high=1000.0)
>>> np.round(f(np.array([0.0, 500.0, 1000.0])), 6)
array([-0.001 , -0.0005,  0.003 ])
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.polynomial import chebyshev, legendre
from numpy.typing import NDArray

from mtmc.errors import InputError

__all__ = [
    "ErrorFunction",
    "ConstantFunction",
    "PolynomialFunction",
    "LegendreSeries",
    "ChebyshevSeries",
    "FourierSeries",
    "ErrorTable",
]


def _coeffs(c: npt.ArrayLike, name: str) -> NDArray[np.float64]:
    arr = np.asarray(c, dtype=np.float64)
    if arr.ndim == 0:
        arr = arr[None]
    if arr.ndim not in (1, 2) or arr.shape[-1] == 0:
        raise InputError(
            f"expected coefficients of shape (n,) or (M, n) with n >= 1, got shape {arr.shape}",
            field=name,
        )
    if not np.all(np.isfinite(arr)):
        raise InputError("expected finite coefficients", field=name)
    arr.setflags(write=False)
    return arr


def _positions(q: npt.ArrayLike) -> NDArray[np.float64]:
    arr = np.asarray(q, dtype=np.float64)
    if arr.ndim > 1:
        raise InputError(f"expected axis positions of shape (M,), got shape {arr.shape}", field="q")
    return arr


class ErrorFunction(ABC):
    """An error as a function of an axis position, linear in its coefficients.

    Subclasses are frozen dataclasses with a ``coefficients`` array of shape ``(n,)`` or
    ``(M, n)``.
    """

    coefficients: NDArray[np.float64]

    @property
    def n_coefficients(self) -> int:
        """Number of coefficients ``n``."""
        return int(self.coefficients.shape[-1])

    @abstractmethod
    def basis(self, q: npt.ArrayLike) -> NDArray[np.float64]:
        """Basis functions at the positions.

        Parameters
        ----------
        q : array_like, shape (M,)
            Axis positions (mm or rad).

        Returns
        -------
        ndarray, shape (M, n)
            ``d f(q) / d c_k``.
        """

    def with_coefficients(self, coefficients: npt.ArrayLike) -> ErrorFunction:
        """The same kind of function with other coefficients (shape ``(n,)`` or ``(M, n)``).

        Parameters
        ----------
        coefficients : array_like
            New coefficients, same ``n``.

        Returns
        -------
        ErrorFunction

        Raises
        ------
        InputError
            If the number of coefficients differs.
        """
        c = _coeffs(coefficients, "coefficients")
        if c.shape[-1] != self.n_coefficients:
            raise InputError(
                f"expected {self.n_coefficients} coefficients, got {c.shape[-1]}",
                field="coefficients",
            )
        return _replace(self, c)

    def __eq__(self, other: object) -> bool:
        """Same kind of function, same settings, equal coefficients."""
        import dataclasses

        if type(self) is not type(other):
            return NotImplemented
        return all(
            np.array_equal(getattr(self, f.name), getattr(other, f.name))
            for f in dataclasses.fields(self)  # type: ignore[arg-type]
        )

    __hash__ = None  # type: ignore[assignment]

    def __call__(self, q: npt.ArrayLike) -> NDArray[np.float64]:
        """Evaluate at axis positions ``q`` of shape ``(M,)``; returns ``(M,)``."""
        B = self.basis(q)
        out: NDArray[np.float64] = np.einsum("...k,...k->...", B, self.coefficients)
        return out


def _replace(obj: Any, c: NDArray[np.float64]) -> ErrorFunction:
    import dataclasses

    out: ErrorFunction = dataclasses.replace(obj, coefficients=c)
    return out


@dataclass(frozen=True, eq=False)
class ConstantFunction(ErrorFunction):
    """A constant error ``c0``.

    Parameters
    ----------
    coefficients : array_like, shape (1,) or (M, 1), or a scalar
        The value (mm or rad).
    """

    coefficients: NDArray[np.float64]

    def __post_init__(self) -> None:
        object.__setattr__(self, "coefficients", _coeffs(self.coefficients, "coefficients"))
        if self.coefficients.shape[-1] != 1:
            raise InputError("expected one coefficient", field="coefficients")

    def basis(self, q: npt.ArrayLike) -> NDArray[np.float64]:
        """``ones((M, 1))``."""
        x = _positions(q)
        return np.ones((*x.shape, 1))


@dataclass(frozen=True, eq=False)
class PolynomialFunction(ErrorFunction):
    """A plain power series ``sum_k c_k q^k``.

    Parameters
    ----------
    coefficients : array_like, shape (n,) or (M, n)
        ``c_0 ... c_{n-1}``; ``c_k`` in error units per mm^k (or rad^k).
    """

    coefficients: NDArray[np.float64]

    def __post_init__(self) -> None:
        object.__setattr__(self, "coefficients", _coeffs(self.coefficients, "coefficients"))

    def __call__(self, q: npt.ArrayLike) -> NDArray[np.float64]:
        """Evaluate by Horner's scheme at ``q`` of shape ``(M,)``; returns ``(M,)``."""
        x = _positions(q)
        c = self.coefficients
        out = np.broadcast_to(c[..., -1], np.broadcast_shapes(x.shape, c.shape[:-1])).copy()
        for k in range(self.n_coefficients - 2, -1, -1):
            out *= x
            out += c[..., k]
        return out

    def basis(self, q: npt.ArrayLike) -> NDArray[np.float64]:
        """Powers ``q^k``, shape ``(M, n)``."""
        x = _positions(q)
        return np.power.outer(x, np.arange(self.n_coefficients, dtype=np.float64))


def _mapped(x: NDArray[np.float64], low: float, high: float) -> NDArray[np.float64]:
    return (2.0 * x - (low + high)) / (high - low)


def _check_range(low: float, high: float) -> None:
    if not (np.isfinite(low) and np.isfinite(high) and high > low):
        raise InputError(f"expected low < high, got low={low}, high={high}", field="low")


@dataclass(frozen=True, eq=False)
class _TravelSeries(ErrorFunction):
    """A series of polynomials in ``t``, the position mapped from the travel onto [-1, 1]."""

    coefficients: NDArray[np.float64]
    low: float = -1.0
    high: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "coefficients", _coeffs(self.coefficients, "coefficients"))
        _check_range(self.low, self.high)

    def _basis(
        self,
        q: npt.ArrayLike,
        vander: Callable[[NDArray[np.float64], int], NDArray[np.floating[Any]]],
    ) -> NDArray[np.float64]:
        """The pseudo-Vandermonde matrix of ``vander`` at ``t``, shape ``(M, n)``."""
        t = _mapped(_positions(q), self.low, self.high)
        B = vander(t, self.n_coefficients - 1).astype(np.float64, copy=False)
        return B.reshape(*t.shape, self.n_coefficients)


@dataclass(frozen=True, eq=False)
class LegendreSeries(_TravelSeries):
    """A Legendre series over the axis travel.

    ``f(q) = sum_k c_k P_k(t)``, ``t = (2 q - low - high) / (high - low)``, with the
    three-term recurrence ``(k + 1) P_{k+1} = (2k + 1) t P_k - k P_{k-1}``.

    Parameters
    ----------
    coefficients : array_like, shape (n,) or (M, n)
        ``c_0 ... c_{n-1}`` in error units.
    low, high : float
        The travel of the axis (mm or rad).
    """

    def basis(self, q: npt.ArrayLike) -> NDArray[np.float64]:
        """``P_k(t)``, shape ``(M, n)`` (NumPy's ``legvander``)."""
        return self._basis(q, legendre.legvander)


@dataclass(frozen=True, eq=False)
class ChebyshevSeries(_TravelSeries):
    """A Chebyshev series (first kind) over the axis travel.

    ``f(q) = sum_k c_k T_k(t)``, ``t`` as for :class:`LegendreSeries`,
    ``T_{k+1} = 2 t T_k - T_{k-1}``.

    Parameters
    ----------
    coefficients : array_like, shape (n,) or (M, n)
        ``c_0 ... c_{n-1}``.
    low, high : float
        The travel of the axis.
    """

    def basis(self, q: npt.ArrayLike) -> NDArray[np.float64]:
        """``T_k(t)``, shape ``(M, n)`` (NumPy's ``chebvander``)."""
        return self._basis(q, chebyshev.chebvander)


@dataclass(frozen=True, eq=False)
class FourierSeries(ErrorFunction):
    """A Fourier series in the angle of a rotary axis.

    ``f(q) = a0 + sum_{k=1..K} (a_k cos(k q) + b_k sin(k q))``, ``q`` in rad.

    Parameters
    ----------
    coefficients : array_like, shape (1 + 2K,) or (M, 1 + 2K)
        ``[a0, a1, b1, a2, b2, ...]``.
    """

    coefficients: NDArray[np.float64]

    def __post_init__(self) -> None:
        object.__setattr__(self, "coefficients", _coeffs(self.coefficients, "coefficients"))
        if self.coefficients.shape[-1] % 2 != 1:
            raise InputError(
                "expected an odd number of coefficients [a0, a1, b1, a2, b2, ...], got "
                f"{self.coefficients.shape[-1]}",
                field="coefficients",
            )

    @property
    def order(self) -> int:
        """The highest harmonic K."""
        return (self.n_coefficients - 1) // 2

    def basis(self, q: npt.ArrayLike) -> NDArray[np.float64]:
        """``[1, cos q, sin q, cos 2q, sin 2q, ...]``, shape ``(M, 1 + 2K)``."""
        x = _positions(q)
        out = np.empty((*x.shape, self.n_coefficients))
        out[..., 0] = 1.0
        for k in range(1, self.order + 1):
            out[..., 2 * k - 1] = np.cos(k * x)
            out[..., 2 * k] = np.sin(k * x)
        return out


@dataclass(frozen=True, eq=False)
class ErrorTable(ErrorFunction):
    """A measured error map, interpolated linearly between its positions.

    Parameters
    ----------
    positions : array_like, shape (n,)
        Strictly increasing axis positions (mm or rad).
    coefficients : array_like, shape (n,) or (M, n)
        Error values at the positions (the coefficients of the hat-function basis).
    period : float, optional
        For a rotary axis: positions are taken modulo ``period`` (e.g. ``2 pi``) from
        ``positions[0]``, and the map wraps from the last position to the first.

    Raises
    ------
    InputError
        On non-increasing positions, mismatched lengths, and (when evaluating) a position
        outside ``[positions[0], positions[-1]]`` on a table without period.
    """

    positions: NDArray[np.float64]
    coefficients: NDArray[np.float64]
    period: float | None = field(default=None)

    def __post_init__(self) -> None:
        p = np.asarray(self.positions, dtype=np.float64)
        c = _coeffs(self.coefficients, "coefficients")
        if p.ndim != 1 or p.size < 2 or not np.all(np.diff(p) > 0):
            raise InputError(
                "expected at least two strictly increasing positions", field="positions"
            )
        if c.shape[-1] != p.size:
            raise InputError(
                f"expected {p.size} values (one per position), got {c.shape[-1]}",
                field="coefficients",
            )
        if self.period is not None and not p[-1] < p[0] + self.period:
            raise InputError("expected the positions to span less than one period", field="period")
        p.setflags(write=False)
        object.__setattr__(self, "positions", p)
        object.__setattr__(self, "coefficients", c)

    def basis(self, q: npt.ArrayLike) -> NDArray[np.float64]:
        """Hat functions (linear interpolation weights), shape ``(M, n)``."""
        x = _positions(q)
        p = self.positions
        if self.period is not None:
            x = p[0] + np.mod(x - p[0], self.period)
            p = np.append(p, p[0] + self.period)
        elif np.any((x < p[0]) | (x > p[-1])):
            bad = x[(x < p[0]) | (x > p[-1])].ravel()[0]
            raise InputError(
                f"axis position {bad} outside the table's range [{p[0]}, {p[-1]}]", field="q"
            )
        i = np.clip(np.searchsorted(p, x, side="right") - 1, 0, p.size - 2)
        w = (x - p[i]) / (p[i + 1] - p[i])
        out = np.zeros((*x.shape, p.size))
        np.put_along_axis(out, i[..., None], (1.0 - w)[..., None], axis=-1)
        np.put_along_axis(out, (i + 1)[..., None], w[..., None], axis=-1)
        if self.period is not None:
            out[..., 0] += out[..., -1]
            out = out[..., :-1]
        return out
