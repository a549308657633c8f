"""Summaries of a Monte Carlo run (JCGM 101:2008 §7.5–7.7, JCGM 102:2011 §7.5–7.7).

A :class:`MonteCarloResult` holds the ``M`` model values of a run (``(M,)`` for a scalar
output, ``(M, d)`` for a vector output) with the seed that reproduces them, and computes
from them, on demand:

* the estimate ``y`` (the average of the values, JCGM 101 §7.6) and the standard
  uncertainty ``u(y)`` (their standard deviation with divisor ``M - 1``, JCGM 101 eq. (13);
  Stryczek eq. (5));
* the covariance matrix of a vector output (JCGM 102 §7.5, divisor ``M - 1``);
* probabilistically symmetric and shortest coverage intervals (JCGM 101 §7.7) from the
  sorted values, with ``q = pM`` if that is an integer and ``q = ⌊pM + ½⌋`` otherwise;
* an expanded uncertainty (half the length of a coverage interval);
* the hyperellipsoidal coverage region of a vector output (JCGM 102 §7.7.2);
* histogram data.

Examples
--------
>>> rng = np.random.default_rng(1)
>>> r = MonteCarloResult.from_samples(rng.normal(10.0, 2.0, 200_000), seed=1)
>>> round(r.estimate, 1), round(r.u, 1)
(10.0, 2.0)
>>> lo, hi = r.coverage_interval(0.95, "symmetric")
>>> round(lo, 0), round(hi, 0)
(6.0, 14.0)
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import InputError
from mtmc.uncertainty.checks import check_probability
from mtmc.uncertainty.sketch import QuantileSketch

if TYPE_CHECKING:
    from mtmc.uncertainty.decision import Conformity

__all__ = [
    "convergence",
    "MAX_COV_DIM",
    "CoverageEllipsoid",
    "Moments",
    "MonteCarloResults",
    "Histogram",
    "MonteCarloResult",
    "Trace",
    "coverage_indices",
    "min_trials",
    "require_trials",
]

IntervalKind = Literal["shortest", "symmetric"]


def _q_of(m: int, pf: float) -> int:
    """``q = pM`` if ``pM`` is an integer, else ``⌊pM + ½⌋`` (JCGM 101 §7.7.1)."""
    # pM is an integer exactly when round(pM) reproduces it (within rounding of p).
    pm = pf * m
    return int(round(pm) if abs(pm - round(pm)) <= 1e-9 * max(1.0, pm) else math.floor(pm + 0.5))


def coverage_indices(m: int, p: float) -> tuple[int, int]:
    """The numbers ``q`` and ``r`` of JCGM 101 §7.7.1–7.7.2 for ``M`` sorted values.

    Parameters
    ----------
    m : int
        Number of values ``M``.
    p : float
        Coverage probability, ``0 < p < 1``.

    Returns
    -------
    q, r : int
        ``q = pM`` if ``pM`` is an integer, else ``⌊pM + ½⌋``; ``r = (M - q)/2`` if that
        is an integer, else ``(M - q + 1)/2``. The probabilistically symmetric interval is
        ``[ỹ_r, ỹ_{r+q}]`` (1-based), any ``[ỹ_j, ỹ_{j+q}]`` is a ``100p %`` interval.

    Raises
    ------
    InputError
        If ``p`` is not in (0, 1) or ``M`` is too small (``q`` must be in ``1..M-1``).

    Examples
    --------
    >>> coverage_indices(10**6, 0.95)
    (950000, 25000)
    >>> coverage_indices(1001, 0.95)
    (951, 25)
    """
    pf = check_probability(p)
    q = _q_of(m, pf)
    if not 1 <= q <= m - 1:
        raise InputError(
            f"{m} values are too few for a {100 * pf:g} % coverage interval "
            f"(need q = pM between 1 and M - 1, got q = {q})",
            field="p",
        )
    r = (m - q) // 2 if (m - q) % 2 == 0 else (m - q + 1) // 2
    return int(q), int(max(r, 1))


def min_trials(p: float) -> int:
    """The fewest trials ``M`` whose coverage interval :func:`coverage_indices` can take.

    The shortest and the probabilistically symmetric ``100p %`` intervals both take
    ``q = pM`` (rounded) of ``M`` sorted values with ``1 <= q <= M - 1``: about
    ``M > 1/(2(1 - p))`` (and ``M >= 1/(2p)``); ``M = 11`` for ``p = 0.95``, ``M = 501``
    for ``p = 0.999``. This is the hard minimum of a run; JCGM 101 §7.2.2 recommends
    ``M >= 10⁴/(1 - p)`` for a reliable interval.

    Parameters
    ----------
    p : float
        Coverage probability, ``0 < p < 1``.

    Returns
    -------
    int
        At least 2.

    Examples
    --------
    >>> min_trials(0.95), min_trials(0.99), min_trials(0.5)
    (11, 51, 2)
    """
    pf = check_probability(p)
    m = max(2, math.floor(0.5 / min(pf, 1.0 - pf)) - 2)  # a few below the bound
    while True:  # up by at most a few steps: the rounding of q decides the last one
        if 1 <= _q_of(m, pf) <= m - 1:
            return m
        m += 1


def require_trials(m: int, p: float) -> None:
    """Refuse fewer trials than :func:`min_trials` for coverage probability ``p``.

    Parameters
    ----------
    m : int
        The number of trials ``M``.
    p : float
        Coverage probability, ``0 < p < 1``.

    Raises
    ------
    InputError
        At field ``trials``, stating the minimum and JCGM 101 §7.2.2's recommendation.

    Examples
    --------
    >>> require_trials(11, 0.95)
    >>> require_trials(10, 0.95)
    Traceback (most recent call last):
    ...
    mtmc.errors.InputError: field trials: expected at least 11 trials for a 95 % ... got 10
    """
    least = min_trials(p)
    if m < least:
        pf = float(p)
        raise InputError(
            f"expected at least {least} trials for a {100 * pf:g} % coverage interval "
            "(q = pM of the M sorted values must be 1 to M - 1; JCGM 101 §7.2.2 "
            f"recommends M >= {math.ceil(1e4 / (1.0 - pf) - 1e-6)}), got {m}",
            field="trials",
        )


def _constant_rows(xt: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Which rows of ``xt`` ``(d, n)`` hold one value ``n`` times (NaN never counts as one)."""
    out = np.zeros(xt.shape[0], dtype=bool)
    if xt.shape[1] == 0:
        return out
    # a row whose first and last values differ is not one value: the full look only at
    # the others (random values almost never tie: the check costs O(d), not O(d n))
    maybe = np.nonzero(xt[:, 0] == xt[:, -1])[0]
    if maybe.size:
        out[maybe] = (xt[maybe] == xt[maybe, :1]).all(axis=1)
    return out


def _exact_constants(xt: NDArray[np.float64], mean: NDArray[np.float64]) -> None:
    """Set ``mean`` (in place) to the value itself where a row of ``xt`` is one value.

    The sum of ``n`` copies of ``c`` divided by ``n`` can miss ``c`` by an ulp
    (``(0.1 + 0.1 + 0.1) / 3``); the deviations from it would then give a constant a
    ``u`` of 1e-17 instead of 0. A constant's mean is the constant, and its ``u`` 0.
    """
    const = _constant_rows(xt)
    if const.any():
        mean[const] = xt[const, 0]


@dataclass(frozen=True, eq=False)
class Histogram:
    """Histogram data of a scalar output: bin edges, density and counts (arrays read-only).

    The one histogram type: :meth:`MonteCarloResult.histogram` makes it, a study's
    quantity keeps it (``histogram`` of ``result.json``: the edges and the density) and
    the report draws it.

    Attributes
    ----------
    edges : ndarray, shape (nbins + 1,)
        Bin edges, in the unit of the output (empty where the values are one value).
    density : ndarray, shape (nbins,)
        ``counts / (M · width)``: an estimate of the PDF of the output.
    counts : ndarray of int, shape (nbins,), or None
        Values per bin; None where only the density is kept (a study's quantity, a
        histogram read back from ``result.json``).
    """

    edges: NDArray[np.float64]
    density: NDArray[np.float64]
    counts: NDArray[np.int64] | None = None

    def __post_init__(self) -> None:
        for name in ("edges", "density"):
            a = np.array(getattr(self, name), dtype=np.float64)
            a.setflags(write=False)
            object.__setattr__(self, name, a)
        if self.counts is not None:
            c = np.array(self.counts, dtype=np.int64)
            c.setflags(write=False)
            object.__setattr__(self, "counts", c)

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        assert isinstance(other, Histogram)
        same = np.array_equal(self.edges, other.edges) and np.array_equal(
            self.density, other.density
        )
        if self.counts is None or other.counts is None:
            return same and self.counts is other.counts
        return same and np.array_equal(self.counts, other.counts)

    __hash__ = None  # type: ignore[assignment]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (``histogram`` of a quantity): the edges and the density."""
        return {
            name: [float(x) if math.isfinite(x) else None for x in getattr(self, name).tolist()]
            for name in ("edges", "density")
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Histogram:
        """The histogram that :meth:`to_dict` wrote."""
        return cls(
            edges=np.array(d["edges"], dtype=np.float64),
            density=np.array(d["density"], dtype=np.float64),
        )


@dataclass(frozen=True)
class CoverageEllipsoid:
    """Hyperellipsoidal coverage region ``(η - y)ᵀ V⁻¹ (η - y) <= k²`` (JCGM 102 §7.7).

    Attributes
    ----------
    centre : ndarray, shape (d,)
        The estimate ``y``.
    cov : ndarray, shape (d, d)
        The covariance matrix ``V`` that shapes the region.
    k : float
        The scale (coverage factor) ``k_p``.
    p : float
        Coverage probability.
    method : str
        ``"mc"``: ``k²`` is the ``q``-th smallest of the ``M`` squared Mahalanobis
        distances of the values (JCGM 102 §7.7.2, ``q`` as in JCGM 101 §7.7.1);
        ``"chi2"``: ``k² = χ²_d(p)``, exact when the output is Gaussian (JCGM 102
        §6.5.2.3).
    semi_axes : ndarray, shape (d,)
        ``k sqrt(λ_i)`` for the eigenvalues ``λ_i`` of ``V`` (ascending).
    axes : ndarray, shape (d, d)
        Unit eigenvectors of ``V``, as columns in the order of ``semi_axes``.
    """

    centre: NDArray[np.float64]
    cov: NDArray[np.float64]
    k: float
    p: float
    method: str
    semi_axes: NDArray[np.float64] = field(repr=False)
    axes: NDArray[np.float64] = field(repr=False)

    def mahalanobis2(self, points: npt.ArrayLike) -> NDArray[np.float64]:
        """Squared Mahalanobis distances ``(η - y)ᵀ V⁻¹ (η - y)`` of ``(n, d)`` points.

        Parameters
        ----------
        points : array_like, shape (n, d)

        Returns
        -------
        ndarray, shape (n,)
        """
        pts = np.asarray(points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != self.centre.size:
            raise InputError(
                f"expected points of shape (n, {self.centre.size}), got {pts.shape}",
                field="points",
            )
        return _mahalanobis2(pts, self.centre, self.cov)

    def contains(self, points: npt.ArrayLike) -> NDArray[np.bool_]:
        """Whether each of ``(n, d)`` points lies in the region; shape ``(n,)``."""
        return self.mahalanobis2(points) <= self.k**2

    def boundary(self, n: int = 200) -> NDArray[np.float64]:
        """``n`` points on the boundary of a 2-D region (an ellipse), shape ``(n, 2)``.

        Raises
        ------
        InputError
            If the region is not two-dimensional.
        """
        if self.centre.size != 2:
            raise InputError(
                f"a boundary curve needs a 2-D region, this one has d = {self.centre.size}",
                field="d",
            )
        t = np.linspace(0.0, 2.0 * np.pi, n)
        circle = np.stack([np.cos(t), np.sin(t)], axis=1) * self.semi_axes
        return self.centre + circle @ self.axes.T


def _mahalanobis2(
    pts: NDArray[np.float64], centre: NDArray[np.float64], cov: NDArray[np.float64]
) -> NDArray[np.float64]:
    diff = pts - centre
    # Solve through the Cholesky factor: d² = |L⁻¹ (η - y)|².
    lam = np.linalg.eigvalsh(cov)
    try:
        if lam[0] <= 1e-12 * max(lam[-1], 0.0):
            raise np.linalg.LinAlgError
        chol = np.linalg.cholesky(cov)
    except np.linalg.LinAlgError:
        raise InputError(
            "the covariance matrix of the output is singular: no coverage ellipsoid "
            "(a component is constant or components are linearly dependent)",
            field="cov",
        ) from None
    w = np.linalg.solve(chol, diff.T)
    d2: NDArray[np.float64] = np.einsum("ij,ij->j", w, w)
    return d2


#: Vector outputs of up to this many components keep their full covariance when their
#: samples are not kept; wider ones keep the variances only.
MAX_COV_DIM: int = 256

#: Widest output whose second moments are dot products of rows in NumPy's own loops
#: (wider ones use a matrix product).
_DOT_DIM = 32

#: NumPy's ``einsum`` sums the dot product of two long rows in chunks of this many
#: values (its buffered iterator) and adds the chunks' sums in order; :func:`_row_dots`
#: does the same for many rows in one call.
_DOT_CHUNK = 8192


def _row_dots(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``Σ_m a[..., m] b[..., m]`` of the rows of two ``(..., n)`` arrays, all in one go.

    Each sum has the bits of ``np.einsum("m,m->", a_row, b_row)``: chunks of
    :data:`_DOT_CHUNK` values, each summed by einsum's kernel, added in order (a test
    compares the two). The rows must be contiguous (the arrays may be slices of a
    C-ordered array along the leading axes).
    """
    n = a.shape[-1]
    if n <= _DOT_CHUNK:
        out: NDArray[np.float64] = np.einsum("...m,...m->...", a, b)
        return out
    q = n // _DOT_CHUNK
    head = q * _DOT_CHUNK
    lead = a.shape[:-1]
    part = np.einsum(
        "...km,...km->...k",
        a[..., :head].reshape(*lead, q, _DOT_CHUNK),
        b[..., :head].reshape(*lead, q, _DOT_CHUNK),
    )
    acc: NDArray[np.float64] = part[..., 0].copy()
    for k in range(1, q):
        acc += part[..., k]
    if head < n:
        acc += np.einsum("...m,...m->...", a[..., head:], b[..., head:])
    return acc


@dataclass(frozen=True, eq=False)
class Trace:
    """The estimate and ``u`` of the first ``m`` trials of a run, for some ``m``.

    Streamed by the engine for a scalar output whose samples are not kept: the moments
    merged in trial order are read at the end of seed blocks spaced about evenly on a log
    scale, so the curve is the same bits whatever the workers.

    Attributes
    ----------
    m : ndarray of int
        Numbers of trials, ascending.
    estimate, u : ndarray
        Mean and standard deviation (divisor ``m - 1``) of the first ``m`` values.
    """

    m: NDArray[np.int64]
    estimate: NDArray[np.float64]
    u: NDArray[np.float64]

    def __post_init__(self) -> None:
        for a in (self.m, self.estimate, self.u):
            a.setflags(write=False)


@dataclass(frozen=True)
class Moments:
    """Count, mean and second central moments of a set of values, mergeable.

    Attributes
    ----------
    n : int
        Number of values.
    mean : ndarray, shape (d,)
        Their mean.
    m2 : ndarray, shape (d, d) or (d,)
        ``Σ (x - mean)(x - mean)ᵀ`` (the full matrix for ``d <= MAX_COV_DIM``, else its
        diagonal ``Σ (x - mean)²``).

    Notes
    -----
    Two sets merge exactly as Chan, Golub and LeVeque (1979) give it:
    ``n = nₐ + n_b``, ``δ = x̄_b - x̄ₐ``, ``x̄ = x̄ₐ + δ n_b/n``,
    ``M₂ = M₂ₐ + M₂_b + δδᵀ nₐn_b/n``. The Monte Carlo engine forms the moments of fixed
    blocks of trials and merges them in trial order, so the result does not depend on
    how the trials were cut into evaluation blocks or shared between workers.

    The moments of ``P`` outputs of one width over the same trials can be held side by
    side (:meth:`of_stack`: ``mean`` ``(P, d)``, ``m2`` ``(P, d, d)`` or ``(P, d)``);
    they merge in one call, with the bits of ``P`` separate merges, and
    :meth:`unstack` gives the moments of each.

    Examples
    --------
    >>> x = np.arange(10.0).reshape(5, 2)
    >>> m = Moments.of(x[:2]).merge(Moments.of(x[2:]))
    >>> bool(np.allclose(m.cov, np.cov(x, rowvar=False)))
    True
    """

    n: int
    mean: NDArray[np.float64]
    m2: NDArray[np.float64]

    def __post_init__(self) -> None:
        for name in ("mean", "m2"):
            arr = np.array(getattr(self, name), dtype=np.float64)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    @classmethod
    def of(cls, x: NDArray[np.float64]) -> Moments:
        """The moments of the rows of ``x``, shape ``(n, d)``."""
        return cls.of_columns(np.ascontiguousarray(np.asarray(x, dtype=np.float64).T))

    @classmethod
    def of_columns(cls, xt: NDArray[np.float64]) -> Moments:
        """The moments of the columns of ``xt``, shape ``(d, n)`` (one row per component).

        Row-wise reductions of a C-ordered ``(d, n)`` array are NumPy's fast pairwise
        sums; the same array gives the same bits.
        """
        n = int(xt.shape[1])
        d = xt.shape[0]
        if d <= _DOT_DIM:
            both = cls.of_stack([xt])
            return cls._new(n, both.mean[0], both.m2[0])
        mean = np.add.reduce(xt, axis=1)  # = xt.mean(axis=1), bit for bit
        mean /= n
        _exact_constants(xt, mean)
        dev = xt - mean[:, None]
        if d <= MAX_COV_DIM:
            m2 = dev @ dev.T
        else:
            m2 = np.einsum("ij,ij->i", dev, dev)
        return cls._new(n, mean, m2)

    @classmethod
    def of_stack(
        cls, xts: Sequence[NDArray[np.float64]], sums: NDArray[np.float64] | None = None
    ) -> Moments:
        """The moments of ``P`` sets of values of one width over the same trials, side by side.

        Parameters
        ----------
        xts : sequence of ndarray, each shape (d, n), C-ordered
            The values of each set, one row per component (as :meth:`of_columns`).
        sums : ndarray, shape (P, d), optional
            ``np.add.reduce(xts[p], axis=1)`` of each set, where already taken.

        Returns
        -------
        Moments
            ``mean`` of shape ``(P, d)``, ``m2`` ``(P, d, d)`` (``(P, d)`` for
            ``d > MAX_COV_DIM``): row ``p`` is ``of_columns(xts[p])`` bit for bit, the
            dot products of all sets made in a few calls (per offset ``s`` of the
            components, the products of components ``i`` and ``i + s`` of every set).
        """
        p = len(xts)
        d, n = xts[0].shape
        if d > _DOT_DIM:
            each = [cls.of_columns(x) for x in xts]
            return cls._new(n, np.stack([e.mean for e in each]), np.stack([e.m2 for e in each]))
        if sums is None:
            sums = np.empty((p, d))
            for i, x in enumerate(xts):
                np.add.reduce(x, axis=1, out=sums[i])  # = x.mean(axis=1) * n, bit for bit
        mean = sums / n
        dev = np.empty((p, d, n))
        for i, x in enumerate(xts):
            _exact_constants(x, mean[i])
            np.subtract(x, mean[i][:, None], out=dev[i])
        m2 = np.empty((p, d, d))
        flat = m2.reshape(p, d * d)
        for s in range(d):  # dot products of rows in NumPy's own loops: no BLAS threads
            v = _row_dots(dev[:, : d - s], dev[:, s:])
            # the s-th diagonals above and below: (i, i + s) and (i + s, i), i < d - s
            flat[:, s : s + (d - s) * (d + 1) : d + 1] = v
            flat[:, s * d : s * d + (d - s) * (d + 1) : d + 1] = v
        return cls._new(n, mean, m2)

    def unstack(self) -> list[Moments]:
        """The moments of each set of moments held side by side (:meth:`of_stack`)."""
        return [Moments._new(self.n, self.mean[i], self.m2[i]) for i in range(len(self.mean))]

    @classmethod
    def _new(cls, n: int, mean: NDArray[np.float64], m2: NDArray[np.float64]) -> Moments:
        """Moments of new float64 arrays that nothing else holds (made read-only, no copy)."""
        obj = object.__new__(cls)
        mean.setflags(write=False)
        m2.setflags(write=False)
        object.__setattr__(obj, "n", n)
        object.__setattr__(obj, "mean", mean)
        object.__setattr__(obj, "m2", m2)
        return obj

    def merge(self, other: Moments) -> Moments:
        """The moments of the union of both sets (of each pair, for moments side by side)."""
        if other.n == 0:
            return self
        if self.n == 0:
            return other
        n = self.n + other.n
        delta = other.mean - self.mean
        mean = self.mean + delta * (other.n / n)
        w = self.n * other.n / n
        if self.m2.ndim > self.mean.ndim:  # δδᵀ of each set
            corr = delta[..., :, None] * delta[..., None, :]
        else:
            corr = delta * delta
        corr *= w
        m2 = self.m2 + other.m2
        m2 += corr
        return Moments._new(n, mean, m2)

    @property
    def cov(self) -> NDArray[np.float64]:
        """Covariance with divisor ``n - 1``: ``(d, d)``, or the variances ``(d,)``."""
        return self.m2 / (self.n - 1)


def _fewer_bins(values: NDArray[np.float64], bins: int | str) -> int | str:
    """``bins``, or fewer where the range of the values holds fewer distinct doubles.

    Values within a few ulp of each other (an input ``uniform(1, 1.00000000000001)``: a
    range of 45 ulp) cannot be cut into 60 bins of distinct edges, and NumPy refuses
    ("Too many bins for data range"): the bins then are as many as the edges that
    ``linspace`` keeps distinct.
    """
    if not isinstance(bins, int) or values.size == 0:
        return bins
    lo, hi = float(np.min(values)), float(np.max(values))
    if not lo < hi:
        return bins
    ulp = float(np.spacing(max(abs(lo), abs(hi))))
    n = max(1, min(bins, int((hi - lo) / ulp)))
    while n > 1 and np.any(np.diff(np.linspace(lo, hi, n + 1)) <= 0.0):
        n -= 1
    return n


@dataclass(frozen=True)
class MonteCarloResult:
    """The values of a Monte Carlo run and their summaries (JCGM 101 §7.5–7.7).

    Attributes
    ----------
    samples : ndarray, shape (M,) or (M, d), or None
        The model values, in trial order (trials whose value was not finite are left out
        when the run used ``nan_policy="omit"``); ``None`` when the run did not keep
        them (then ``moments`` holds the estimate and covariance, and coverage
        intervals, histograms and ellipsoids are not available).
    trials : int
        Number of trials run (``M`` plus the omitted ones).
    seed : int or None
        The seed that reproduces the run (``None`` if the values came from elsewhere).
    adaptive : bool
        Whether the number of trials was chosen by the adaptive procedure (§7.9).
    blocks : int
        Number of blocks of ``block_trials`` trials of the adaptive procedure (``1`` for
        a fixed run).
    block_trials : int
        Trials per adaptive block (``trials`` for a fixed run).
    tolerance : float or None
        The numerical tolerance ``δ`` the adaptive procedure met (``None`` for a fixed
        run).
    omitted : int
        Trials whose model value was not finite and that were left out.
    normal_method : str
        How standard normal numbers were made (``"default"`` or ``"box-muller"``).
    sampling : str
        ``"random"`` (pseudo-random draws) or ``"sobol"`` (randomised quasi-Monte Carlo,
        see :mod:`mtmc.uncertainty.sampling`).
    moments : Moments or None
        Count, mean and second moments of the values, merged over fixed blocks of trials
        (only for a result whose samples were not kept).
    scalar : bool
        With ``samples=None``: whether the output is a scalar (``(M,)``) rather than a
        vector of one component (``(M, 1)``).
    sketch : QuantileSketch or None
        With ``samples=None``, for a scalar output: a mergeable quantile sketch of the
        values, from which coverage intervals are read (each endpoint within
        ``sketch.rank_error`` ranks of the exact order statistic; :attr:`rank_error`).
    trace : Trace or None
        With ``samples=None``, for a scalar output: the estimate and ``u`` of the first
        ``m`` trials at seed-block ends spaced about evenly on a log scale (the
        convergence curve of :meth:`convergence`, streamed).
    """

    samples: NDArray[np.float64] | None = field(repr=False)
    trials: int
    seed: int | None
    adaptive: bool = False
    blocks: int = 1
    block_trials: int = 0
    tolerance: float | None = None
    omitted: int = 0
    normal_method: str = "default"
    sampling: str = "random"
    moments: Moments | None = field(default=None, repr=False)
    scalar: bool = True
    sketch: QuantileSketch | None = field(default=None, repr=False)
    trace: Trace | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if self.block_trials == 0:
            object.__setattr__(self, "block_trials", int(self.trials))
        if self.samples is None:
            if self.moments is None or self.moments.n < 2:
                raise InputError(
                    "expected samples, or the moments of at least 2 values", field="samples"
                )
            if self.scalar and self.moments.mean.shape != (1,):
                raise InputError("a scalar result has moments of one component", field="scalar")
            return
        object.__setattr__(self, "moments", None)
        s = np.asarray(self.samples, dtype=np.float64)
        if s.ndim not in (1, 2) or s.shape[0] < 2:
            raise InputError(
                f"expected at least 2 values, shape (M,) or (M, d), got shape {s.shape}",
                field="samples",
            )
        bad = ~np.isfinite(s) if s.ndim == 1 else ~np.isfinite(s).all(axis=1)
        nbad = int(np.count_nonzero(bad))
        if nbad:
            raise InputError(
                f"{nbad} of {s.shape[0]} values are not finite (first at index "
                f"{int(np.argmax(bad))}); expected finite model values",
                field="samples",
            )
        if s is self.samples and s.flags.writeable:
            s = s.view()
        s.setflags(write=False)
        object.__setattr__(self, "samples", s)
        object.__setattr__(self, "scalar", s.ndim == 1)

    @classmethod
    def from_samples(
        cls, samples: npt.ArrayLike, *, seed: int | None, trials: int | None = None
    ) -> MonteCarloResult:
        """A result from given model values.

        Parameters
        ----------
        samples : array_like, shape (M,) or (M, d)
            Finite model values.
        seed : int or None
            The seed that produced them, if known.
        trials : int, optional
            Number of trials (default ``M``).

        Returns
        -------
        MonteCarloResult

        Raises
        ------
        InputError
            If there are fewer than 2 values, the shape is wrong or a value is not finite.
        """
        s = np.array(samples, dtype=np.float64)
        return cls(samples=s, trials=int(s.shape[0] if trials is None else trials), seed=seed)

    # ------------------------------------------------------------------ basic summaries
    @property
    def kept(self) -> bool:
        """Whether the samples were kept (else only their moments)."""
        return self.samples is not None

    @property
    def values(self) -> NDArray[np.float64]:
        """The samples, or an :class:`~mtmc.errors.InputError` if they were not kept."""
        if self.samples is None:
            raise InputError(
                "the samples of this output were not kept (run with keep=[...] or "
                "keep_samples=True); only its estimate, u and covariance are available",
                field="samples",
            )
        return self.samples

    @property
    def m(self) -> int:
        """Number of values ``M``."""
        if self.samples is None:
            assert self.moments is not None
            return self.moments.n
        return int(self.samples.shape[0])

    @property
    def dim(self) -> int:
        """0 for a scalar output, ``d`` for a vector output."""
        if self.samples is None:
            assert self.moments is not None
            return 0 if self.scalar else int(self.moments.mean.shape[0])
        return 0 if self.samples.ndim == 1 else int(self.samples.shape[1])

    @cached_property
    def estimate_vector(self) -> NDArray[np.float64]:
        """The estimate ``y`` of every component, read-only, shape ``(d,)`` (``(1,)`` for a scalar).

        The average of the values (JCGM 101 eq. (12), JCGM 102 §7.5).
        """
        if self.samples is None:
            assert self.moments is not None
            mean = np.array(self.moments.mean)
        else:
            mean = np.atleast_1d(self.samples.mean(axis=0))
            _exact_constants(np.atleast_2d(self.samples.T), mean)
        mean.setflags(write=False)
        return mean

    @cached_property
    def u_vector(self) -> NDArray[np.float64]:
        """Standard uncertainties of the components, read-only, ``(d,)`` (``(1,)`` for a scalar).

        The standard deviation of the values with divisor ``M - 1`` (JCGM 101 eq. (13),
        Stryczek eq. (5)).
        """
        if self.samples is None:
            assert self.moments is not None
            c = self.moments.cov
            sd = np.sqrt(np.clip(np.diag(c) if c.ndim == 2 else c, 0.0, None))
        else:
            sd = np.atleast_1d(self.samples.std(axis=0, ddof=1))
            sd[_constant_rows(np.atleast_2d(self.samples.T))] = 0.0
        sd.setflags(write=False)
        return sd

    @property
    def estimate(self) -> float:
        """The estimate ``y`` of a scalar output (JCGM 101 eq. (12)), a float.

        Raises
        ------
        InputError
            For a vector output: its estimate is :attr:`estimate_vector`.
        """
        self._require_scalar_value("estimate")
        return float(self.estimate_vector[0])

    @property
    def u(self) -> float:
        """Standard uncertainty ``u(y)`` of a scalar output (JCGM 101 eq. (13)), a float.

        Raises
        ------
        InputError
            For a vector output: its standard uncertainties are :attr:`u_vector`.
        """
        self._require_scalar_value("u")
        return float(self.u_vector[0])

    def _require_scalar_value(self, name: str) -> None:
        if self.dim != 0:
            raise InputError(
                f"{name} is the float of a scalar output; this one has d = {self.dim} "
                f"components: use {name}_vector (shape (d,)) or component(i)",
                field=name,
            )

    @cached_property
    def cov(self) -> NDArray[np.float64]:
        """Covariance matrix ``U_y`` with divisor ``M - 1`` (JCGM 102 eq. (21)), ``(d, d)``.

        For a scalar output, the ``(1, 1)`` matrix ``[[u²]]``. Read-only.
        """
        if self.samples is None:
            assert self.moments is not None
            c = self.moments.cov
            if c.ndim == 1:
                raise InputError(
                    f"the covariance of an output of {c.shape[0]} components is not kept "
                    f"when its samples are not (more than {MAX_COV_DIM}); u is available",
                    field="samples",
                )
            c = np.array(c)
        else:
            x = self.samples.reshape(self.m, -1)
            c = np.atleast_2d(np.cov(x, rowvar=False, ddof=1))
        c.setflags(write=False)
        return c

    @property
    def rank_error(self) -> int:
        """Bound on the rank error of the coverage-interval endpoints (0: exact)."""
        return 0 if self.sketch is None or self.samples is not None else self.sketch.rank_error

    @cached_property
    def _sorted(self) -> NDArray[np.float64]:
        self._require_scalar("coverage intervals")
        s = np.sort(self.values)
        s.setflags(write=False)
        return s

    def _require_scalar(self, what: str) -> None:
        if self.dim != 0:
            raise InputError(
                f"{what} need a scalar output; this one has d = {self.dim} "
                "(use component(i), or coverage_ellipsoid for a region)",
                field="samples",
            )

    def component(self, i: int) -> MonteCarloResult:
        """The scalar result of component ``i`` of a vector output.

        Parameters
        ----------
        i : int
            Index of the component, ``0 <= i < d``.

        Returns
        -------
        MonteCarloResult
            With ``samples`` of shape ``(M,)`` and the same run information.
        """
        if self.dim == 0:
            raise InputError("component() needs a vector output", field="samples")
        if not -self.dim <= i < self.dim:
            raise InputError(f"expected 0 <= i < {self.dim}, got {i}", field="i")
        moments = None
        if self.samples is None:
            assert self.moments is not None
            c = self.moments.m2
            moments = Moments(
                self.moments.n,
                self.moments.mean[i : i + 1],
                c[i : i + 1, i : i + 1] if c.ndim == 2 else c[i : i + 1],
            )
        return MonteCarloResult(
            samples=None if self.samples is None else self.samples[:, i],
            moments=moments,
            trials=self.trials,
            seed=self.seed,
            adaptive=self.adaptive,
            blocks=self.blocks,
            block_trials=self.block_trials,
            tolerance=self.tolerance,
            omitted=self.omitted,
            normal_method=self.normal_method,
            sampling=self.sampling,
        )

    # ------------------------------------------------------------------ intervals
    def coverage_interval(
        self, p: float = 0.95, kind: IntervalKind = "symmetric"
    ) -> tuple[float, float]:
        """A coverage interval for the output with coverage probability ``p``.

        Parameters
        ----------
        p : float, default 0.95
            Coverage probability.
        kind : {"symmetric", "shortest"}, default "symmetric"
            ``"symmetric"``: the probabilistically symmetric interval ``[ỹ_r, ỹ_{r+q}]``
            (JCGM 101 §7.7.2), the one JCGM 101 §8 compares with the GUM interval and
            the default everywhere in mtmc. ``"shortest"`` (on request):
            ``[ỹ_{r*}, ỹ_{r*+q}]`` with ``r*`` the ``r`` minimising ``ỹ_{r+q} - ỹ_r`` over
            ``r = 1..M-q`` (JCGM 101 §7.7.3; the first on ties). ``ỹ`` are the sorted
            values, indices 1-based, ``q``, ``r`` from :func:`coverage_indices`.

        Returns
        -------
        (float, float)
            ``(y_low, y_high)``.

        Raises
        ------
        InputError
            For a vector output, a bad ``p`` or ``kind``, or too few values.

        Examples
        --------
        >>> r = MonteCarloResult.from_samples(np.arange(1.0, 101.0), seed=None)
        >>> r.coverage_interval(0.9, "symmetric")
        (5.0, 95.0)
        """
        q, r = coverage_indices(self.m, p)
        if self.samples is None and self.sketch is not None and self.dim == 0:
            if kind == "symmetric":
                return self.sketch.value_at_rank(r), self.sketch.value_at_rank(r + q)
            if kind == "shortest":
                return self.sketch.shortest(q)
            raise InputError(f"expected 'shortest' or 'symmetric', got {kind!r}", field="kind")
        s = self._sorted
        if kind == "symmetric":
            return float(s[r - 1]), float(s[r - 1 + q])
        if kind == "shortest":
            widths = s[q:] - s[: self.m - q]
            j = int(np.argmin(widths))
            return float(s[j]), float(s[j + q])
        raise InputError(f"expected 'shortest' or 'symmetric', got {kind!r}", field="kind")

    def expanded_uncertainty(self, p: float = 0.95, kind: IntervalKind = "symmetric") -> float:
        """Half the length of the coverage interval: ``U_p = (y_high - y_low)/2``.

        JCGM 101 gives the interval itself; for a symmetric output PDF this half-length
        is the expanded uncertainty of JCGM 100 §6. Stryczek (p. 4) calls the whole
        length ``y_high - y_low`` "U" (4.321 µm for ``[-1.658, 2.663]``); mtmc follows
        the GUM and takes half of it.

        Parameters
        ----------
        p : float, default 0.95
        kind : {"symmetric", "shortest"}, default "symmetric"
            As :meth:`coverage_interval`.

        Returns
        -------
        float
        """
        lo, hi = self.coverage_interval(p, kind)
        return 0.5 * (hi - lo)

    def coverage_factor(self, p: float = 0.95, kind: IntervalKind = "symmetric") -> float:
        """The coverage factor ``k_p`` with ``U_p = k_p u(y)``: here ``U_p / u(y)``.

        The same quantity as :meth:`mtmc.uncertainty.propagation.GumResult.coverage_factor`, there
        the t-quantile of the GUM for ``ν_eff`` degrees of freedom, here implied by the
        Monte Carlo interval: for a Gaussian output the two agree.

        Parameters
        ----------
        p : float, default 0.95
        kind : {"symmetric", "shortest"}, default "symmetric"
            As :meth:`coverage_interval`.

        Returns
        -------
        float
        """
        self._require_scalar("a coverage factor")
        return self.expanded_uncertainty(p, kind) / self.u

    def histogram(self, bins: int | str = "auto") -> Histogram:
        """Histogram data of a scalar output (for the plots of Stryczek, Fig. 3–4).

        Parameters
        ----------
        bins : int or str, default "auto"
            As ``numpy.histogram``. Where the samples were not kept, an integer: the
            histogram is then that of the quantile sketch's weighted values, each bin's
            count within :attr:`rank_error` of the count of all values in it (twice that
            for a bin with two inner edges), its range that of the sketch's values.

        Returns
        -------
        Histogram
        """
        self._require_scalar("a histogram")
        if self.samples is None and self.sketch is not None:
            if not isinstance(bins, int):
                raise InputError(
                    "the samples were not kept: expected a number of bins for the histogram "
                    "of the quantile sketch",
                    field="bins",
                )
            vals, wts = self.sketch.weighted_values()
            c, edges = np.histogram(vals, bins=_fewer_bins(vals, bins), weights=wts)
            counts = np.rint(c).astype(np.int64)
            return Histogram(edges=edges, counts=counts, density=c / (self.m * np.diff(edges)))
        counts, edges = np.histogram(self.values, bins=_fewer_bins(self.values, bins))
        density = counts / (self.m * np.diff(edges))
        return Histogram(edges=edges, counts=counts.astype(np.int64), density=density)

    def convergence(
        self, points: int = 60
    ) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
        """The estimate and ``u`` of the first ``m`` trials, for ``m`` up to ``M``.

        From the kept samples (:func:`convergence`), or, where they were not kept, from
        the curve the engine streamed at seed-block ends (:attr:`trace`: ``m`` from one
        seed block of trials, ``points`` is then not used).

        Returns
        -------
        m : ndarray of int
        estimate, u : ndarray
        """
        self._require_scalar("a convergence curve")
        if self.samples is None:
            if self.trace is None:
                raise InputError(
                    "the samples of this output were not kept and no convergence curve was "
                    "streamed for it",
                    field="samples",
                )
            return self.trace.m, self.trace.estimate, self.trace.u
        return convergence(self.samples, points)

    # ------------------------------------------------------------------ vector outputs
    def coverage_ellipsoid(
        self, p: float = 0.95, method: Literal["mc", "chi2"] = "mc"
    ) -> CoverageEllipsoid:
        """Hyperellipsoidal coverage region of a vector output (JCGM 102 §7.7).

        The region is ``{η : (η - y)ᵀ U_y⁻¹ (η - y) <= k_p²}`` with ``y`` the estimate and
        ``U_y`` the covariance matrix of the values.

        Parameters
        ----------
        p : float, default 0.95
            Coverage probability.
        method : {"mc", "chi2"}
            ``"mc"`` (default, JCGM 102 §7.7.2): ``k_p²`` is the ``q``-th smallest of the
            ``M`` squared distances ``d_r² = (y_r - y)ᵀ U_y⁻¹ (y_r - y)``, ``q`` as in
            JCGM 101 §7.7.1, so that a fraction ``p`` of the values lies in the region,
            whatever the output PDF. ``"chi2"``: ``k_p² = χ²_d(p)``, the quantile of the
            chi-squared distribution with ``d`` degrees of freedom, valid for a Gaussian
            output (JCGM 102 §6.5.2.3).

        Returns
        -------
        CoverageEllipsoid

        Raises
        ------
        InputError
            For a scalar output, a singular covariance, a bad ``p`` or ``method``.
        """
        if self.dim == 0:
            raise InputError(
                "a coverage ellipsoid needs a vector output (M, d); use coverage_interval",
                field="samples",
            )
        pf = check_probability(p)
        centre = np.array(self.estimate_vector)
        cov = np.array(self.cov)
        if method == "mc":
            d2 = _mahalanobis2(self.values, centre, cov)
            q, _ = coverage_indices(self.m, pf)
            k2 = float(np.partition(d2, q - 1)[q - 1])
        elif method == "chi2":
            from scipy import stats  # imported here: scipy.stats costs ~0.5 s at import

            k2 = float(stats.chi2.ppf(pf, self.dim))
        else:
            raise InputError(f"expected 'mc' or 'chi2', got {method!r}", field="method")
        lam, vec = np.linalg.eigh(cov)
        k = math.sqrt(k2)
        return CoverageEllipsoid(
            centre=centre,
            cov=cov,
            k=k,
            p=pf,
            method=method,
            semi_axes=k * np.sqrt(np.clip(lam, 0.0, None)),
            axes=vec,
        )

    def summary(self, p: float = 0.95) -> dict[str, Any]:
        """The numbers a report shows, as plain Python values.

        Returns
        -------
        dict
            ``estimate``, ``u``, ``trials``, ``seed``, ``adaptive``, ``blocks``,
            ``tolerance``, ``omitted``; for a scalar output also ``p``,
            ``interval_shortest``, ``interval_symmetric`` and ``U`` (shortest); for a
            vector output ``cov``.
        """
        out: dict[str, Any] = {
            "estimate": self.estimate_vector.tolist() if self.dim else self.estimate,
            "u": self.u_vector.tolist() if self.dim else self.u,
            "trials": self.trials,
            "seed": self.seed,
            "adaptive": self.adaptive,
            "blocks": self.blocks,
            "tolerance": self.tolerance,
            "omitted": self.omitted,
        }
        if self.samples is None:
            out["kept"] = False
            if self.dim:
                out["cov"] = self.cov.tolist()
            elif self.sketch is not None:
                out["p"] = float(p)
                out["interval_shortest"] = list(self.coverage_interval(p, "shortest"))
                out["interval_symmetric"] = list(self.coverage_interval(p, "symmetric"))
                out["U"] = self.expanded_uncertainty(p, "shortest")
                out["rank_error"] = self.rank_error
        elif self.dim == 0:
            out["p"] = float(p)
            out["interval_shortest"] = list(self.coverage_interval(p, "shortest"))
            out["interval_symmetric"] = list(self.coverage_interval(p, "symmetric"))
            out["U"] = self.expanded_uncertainty(p, "shortest")
        else:
            out["cov"] = self.cov.tolist()
        return out

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

        :func:`mtmc.uncertainty.decision.conformity` of this result: ``p_c`` is the
        fraction of the values in ``[lower, upper]`` (or read from the sketch, or from
        the normal of ``estimate`` and ``u`` where neither was kept).

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


@dataclass(frozen=True, eq=False)
class MonteCarloResults(Mapping[str, MonteCarloResult]):
    """The results of one Monte Carlo run of a model with named outputs.

    A read-only mapping from output name to its :class:`MonteCarloResult` (samples kept,
    or their moments only), with the run's number of trials and seed. Every output comes
    from the same trials: their joint samples (where kept) are row-aligned.

    Attributes
    ----------
    outputs : mapping of str to MonteCarloResult
        The outputs, in the order the model returned them.
    trials : int
        Number of trials run.
    seed : int or None
        The seed that reproduces the run.
    omitted : int
        Trials left out because an output was not finite (``nan_policy="omit"``).

    Examples
    --------
    >>> from mtmc.uncertainty.montecarlo import monte_carlo
    >>> r = monte_carlo(lambda x: {"twice": 2 * x, "pair": np.stack([x, -x], axis=1)},
    ...                 {"x": "normal(1, 0.1)"}, trials=10_000, seed=1)
    >>> list(r), round(r["twice"].u, 2), r["pair"].dim
    (['twice', 'pair'], 0.2, 2)
    """

    outputs: Mapping[str, MonteCarloResult]
    trials: int
    seed: int | None
    omitted: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, "outputs", MappingProxyType(dict(self.outputs)))

    def __getitem__(self, name: str) -> MonteCarloResult:
        try:
            return self.outputs[name]
        except KeyError:
            raise InputError(
                f"the run has no output {name!r}; expected one of {', '.join(self.outputs)}",
                field=name,
            ) from None

    def __iter__(self) -> Iterator[str]:
        return iter(self.outputs)

    def __len__(self) -> int:
        return len(self.outputs)


#: Values summed at a time by :func:`convergence` (its memory, whatever ``M``).
CONVERGENCE_CHUNK: int = 1 << 20


def convergence(
    samples: npt.ArrayLike, points: int = 60
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
    """The estimate and ``u`` from the first ``m`` trials, for ``m`` up to ``M``.

    Parameters
    ----------
    samples : ndarray, shape (M,)
        Model values in trial order.
    points : int
        Number of values of ``m``, spaced evenly on a log scale from 10 (or 2) to ``M``.

    Returns
    -------
    m : ndarray of int, shape (n,)
    estimate, u : ndarray, shape (n,)
        Mean and standard deviation (divisor ``m - 1``, JCGM 101 eq. (13)) of the first
        ``m`` values. Running sums of the deviations from the first value's neighbourhood
        keep the cancellation small.

    Examples
    --------
    >>> m, est, u = convergence(np.arange(1.0, 101.0), points=3)
    >>> m.tolist(), est.tolist()
    ([10, 32, 100], [5.5, 16.5, 50.5])
    >>> bool(np.isclose(u[-1], np.arange(1.0, 101.0).std(ddof=1)))
    True
    """
    x = np.asarray(samples, dtype=np.float64)
    big_m = x.shape[0]
    start = min(10, big_m)
    m = np.unique(np.round(np.geomspace(max(start, 2), big_m, points)).astype(np.int64))
    shift = float(np.mean(x[: min(big_m, 100)]))
    # running sums in chunks, each chunk's cumsum starting from the carry of the one
    # before: the same additions in the same order as one cumsum of all M values (so the
    # same bits), in memory of a chunk rather than four arrays of M values
    s1 = np.empty(m.size)
    s2 = np.empty(m.size)
    carry = np.zeros(2)
    for lo in range(0, big_m, CONVERGENCE_CHUNK):
        hi = min(big_m, lo + CONVERGENCE_CHUNK)
        d = x[lo:hi] - shift
        c1 = np.cumsum(np.concatenate([carry[:1], d]))[1:]
        c2 = np.cumsum(np.concatenate([carry[1:], d * d]))[1:]
        at = (m > lo) & (m <= hi)
        s1[at] = c1[m[at] - 1 - lo]
        s2[at] = c2[m[at] - 1 - lo]
        carry = np.array([c1[-1], c2[-1]])
    est = shift + s1 / m
    var = np.clip((s2 - s1 * s1 / m) / (m - 1), 0.0, None)
    return m, est, np.sqrt(var)
