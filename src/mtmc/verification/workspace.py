"""Discretisation of a machine's workspace into verification points, and the path through them.

The workspace of a volumetric verification is a box of axis positions, one interval per
axis. It is discretised (Aguado et al. 2016, §4.2) as

- a **mesh**: every combination of equally spaced values per axis (:func:`mesh`);
- a **cloud**: the mesh with each inner coordinate moved by a random amount inside its
  cell, Aguado et al. 2016 eq. 18 (:func:`cloud`);
- **diagonals**: points along the body diagonals of the box and, optionally, the
  diagonals of its faces, as in the ISO 230-6 diagonal tests (:func:`diagonals`).

A mesh or a cloud is visited in a *motion sequence*: the first axis named moves first
(fastest), the last one moves least. On a ``"serpentine"`` path each pass of an axis runs
back over the previous one (no long return moves); on a ``"raster"`` path every pass runs in
the same direction. :class:`MeasurementPlan` then adds the *direction of approach*: an axis
with a unidirectional approach and an overshoot arrives at every point moving in the same
direction, going past the point by the overshoot first where the path would arrive from
the other side, so that the backlash of the axis is the same at every point. A plan may be
measured with several reflector (tool) offsets: the whole path is repeated once per offset.

Points are axis positions in mm (rad for a rotary axis), shape ``(n, n_axes)``, columns in
the axis order of the machine (:attr:`mtmc.kinematics.Topology.axes`: ``XFYZ`` gives X, Y, Z).

Examples
--------
>>> p = mesh([0.0, 0.0, 0.0], [2500.0, 1500.0, 1200.0], step=[500.0, 500.0, 400.0])
>>> p.shape
(96, 3)
>>> p[:5]
array([[   0.,    0.,    0.],
       [   0.,    0.,  400.],
       [   0.,    0.,  800.],
       [   0.,    0., 1200.],
       [   0.,  500., 1200.]])
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.document import MAX_MM, Fields, Source, finite
from mtmc.errors import InputError
from mtmc.frozen import frozen_array
from mtmc.kinematics.topology import AXIS_DIRECTION, is_rotary

__all__ = [
    "DISTRIBUTIONS",
    "MeasurementPlan",
    "axis_values",
    "cloud",
    "diagonals",
    "mesh",
    "read_workspace",
    "workspace_from_dict",
]

#: The kinds of discretisation (Aguado et al. 2016 §4.2: mesh 0, cloud 1, diagonals 2).
DISTRIBUTIONS = ("mesh", "cloud", "diagonals")
_PATHS = ("serpentine", "raster")
_APPROACH = {"+": 1, "-": -1, "none": 0}
_TOL = 1e-9


def _box(start: npt.ArrayLike, end: npt.ArrayLike) -> tuple[NDArray[np.float64], ...]:
    lo = np.atleast_1d(np.asarray(start, dtype=np.float64))
    hi = np.atleast_1d(np.asarray(end, dtype=np.float64))
    if lo.ndim != 1 or lo.shape != hi.shape:
        raise InputError(
            f"expected start and end of the same shape (n_axes,), got {lo.shape} and {hi.shape}",
            field="start",
        )
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        raise InputError("expected finite start and end positions", field="start")
    bad = np.flatnonzero(hi < lo)
    if bad.size:
        i = int(bad[0])
        raise InputError(
            f"axis {i}: expected start <= end, got start={lo[i]:g}, end={hi[i]:g}", field="end"
        )
    return lo, hi


#: The most positions one axis of a mesh, and the whole mesh, may have.
MAX_POSITIONS = 100_000


def axis_values(
    start: float, end: float, *, step: float | None = None, count: int | None = None
) -> NDArray[np.float64]:
    """The equally spaced positions of one axis, ``start`` and ``end`` included.

    Parameters
    ----------
    start, end : float
        The interval of the axis (mm or rad), ``start <= end``; ``start == end`` gives the
        one position ``start`` (a fixed axis).
    step : float, optional
        The distance between consecutive positions, > 0; ``end - start`` must be a whole
        number of steps (relative tolerance 1e-9).
    count : int, optional
        The number of positions instead of a step (>= 2, or 1 for a fixed axis).

    Returns
    -------
    ndarray, shape (k,)
        Increasing positions.

    Raises
    ------
    InputError
        If neither or both of ``step`` and ``count`` are given, if the step is not
        positive or does not divide the interval, or if the count does not fit.

    Examples
    --------
    >>> axis_values(0.0, 1200.0, step=400.0)
    array([   0.,  400.,  800., 1200.])
    >>> axis_values(0.0, 1.0, count=3)
    array([0. , 0.5, 1. ])
    """
    lo, hi = (float(v[0]) for v in _box([start], [end]))
    span = hi - lo
    if (step is None) == (count is None):
        raise InputError("expected either a step or a count, not both or neither", field="step")
    if span == 0.0:
        if count is not None and count != 1:
            raise InputError(
                f"start == end ({lo:g}): a fixed axis has one position, got count {count}",
                field="count",
            )
        return np.array([lo])
    if count is not None:
        if isinstance(count, bool) or int(count) != count or count < 2:
            raise InputError(f"expected a count >= 2 for start < end, got {count!r}", field="count")
        if count > MAX_POSITIONS:
            raise InputError(f"expected a count <= {MAX_POSITIONS}, got {count!r}", field="count")
        return np.linspace(lo, hi, int(count))
    assert step is not None
    if not (np.isfinite(step) and step > 0):
        raise InputError(f"expected a step > 0, got {step!r}", field="step")
    k = span / step
    if not k <= MAX_POSITIONS:
        raise InputError(
            f"a step of {step:g} gives {k:.3g} positions from {lo:g} to {hi:g}; "
            f"expected at most {MAX_POSITIONS}",
            field="step",
        )
    n = round(k)
    if n < 1 or abs(k - n) > _TOL * max(1.0, k):
        raise InputError(
            f"the interval {lo:g} .. {hi:g} is not a whole number of steps of {step:g} "
            f"({k:.6g} steps); choose another step or give a count",
            field="step",
        )
    return np.linspace(lo, hi, n + 1)


def _grid(
    start: npt.ArrayLike,
    end: npt.ArrayLike,
    step: npt.ArrayLike | None,
    counts: npt.ArrayLike | None,
) -> list[NDArray[np.float64]]:
    lo, hi = _box(start, end)
    d = lo.size
    if (step is None) == (counts is None):
        raise InputError("expected either step or counts, not both or neither", field="step")
    if step is not None:
        st = np.broadcast_to(np.asarray(step, dtype=np.float64), (d,))
        return _bounded([axis_values(lo[i], hi[i], step=float(st[i])) for i in range(d)])
    cn = np.broadcast_to(np.asarray(counts), (d,))
    out = []
    for i in range(d):
        c = cn[i]
        if not (np.issubdtype(np.asarray(c).dtype, np.integer) or float(c).is_integer()):
            raise InputError(f"axis {i}: expected an integer count, got {c!r}", field="counts")
        out.append(axis_values(lo[i], hi[i], count=1 if lo[i] == hi[i] else int(c)))
    return _bounded(out)


def _bounded(axes: list[NDArray[np.float64]]) -> list[NDArray[np.float64]]:
    """The positions of the axes, if their mesh has at most :data:`MAX_POSITIONS` points."""
    n = math.prod(a.size for a in axes)
    if n > MAX_POSITIONS:
        raise InputError(f"the mesh has {n} points; expected at most {MAX_POSITIONS}", field="step")
    return axes


def _order(d: int, order: Sequence[int] | None) -> list[int]:
    if order is None:
        return list(range(d - 1, -1, -1))
    seq = [int(i) for i in order]
    if sorted(seq) != list(range(d)):
        raise InputError(
            f"expected the motion sequence to name each of the {d} axes once, got {list(order)}",
            field="sequence",
        )
    return seq


def _sequence_index(counts: Sequence[int], order: list[int], path: str) -> NDArray[np.intp]:
    """Grid index ``(n, d)`` of every mesh node, in the order they are visited.

    ``order[0]`` is the axis that moves first (fastest). On a serpentine path the index of
    an axis runs backwards on every other pass of the axes moving less, which is the
    boustrophedon (reflected mixed-radix Gray) order.
    """
    if path not in _PATHS:
        raise InputError(f"expected path 'serpentine' or 'raster', got {path!r}", field="path")
    d = len(counts)
    n = int(np.prod(counts))
    slow_to_fast = order[::-1]
    sizes = [int(counts[a]) for a in slow_to_fast]
    # digits of the visiting rank in mixed radix, slowest axis first
    ranks = np.arange(n)
    digits = np.empty((n, d), dtype=np.intp)
    rem = ranks.copy()
    for j in range(d - 1, -1, -1):
        digits[:, j] = rem % sizes[j]
        rem //= sizes[j]
    if path == "serpentine":
        # the pass an axis is on is numbered by the (unreflected) digits of the slower
        # axes; odd passes run backwards (a reflected mixed-radix Gray code)
        passes = np.zeros(n, dtype=np.intp)
        for j in range(d):
            original = digits[:, j].copy()
            flip = passes % 2 == 1
            digits[flip, j] = sizes[j] - 1 - digits[flip, j]
            passes = passes * sizes[j] + original
    index = np.empty((n, d), dtype=np.intp)
    for j, a in enumerate(slow_to_fast):
        index[:, a] = digits[:, j]
    return index


def _mesh_points(
    values: list[NDArray[np.float64]], order: Sequence[int] | None, path: str
) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """The mesh of the per-axis ``values`` in visiting order, and its grid index (n, d)."""
    index = _sequence_index([v.size for v in values], _order(len(values), order), path)
    pts = np.stack([values[a][index[:, a]] for a in range(len(values))], axis=1)
    return pts, index


def _perturb(
    pts: NDArray[np.float64],
    values: list[NDArray[np.float64]],
    index: NDArray[np.intp],
    rng: np.random.Generator,
    fraction: float,
) -> NDArray[np.float64]:
    """Aguado et al. 2016 eq. 18: inner coordinates moved by U(-fraction, fraction) steps."""
    sizes = np.array([v.size for v in values])
    h = np.array([v[1] - v[0] if v.size > 1 else 0.0 for v in values])
    inner = (index > 0) & (index < sizes - 1)
    u = rng.uniform(-fraction, fraction, size=pts.shape)
    return pts + np.where(inner, u * h, 0.0)


def mesh(
    start: npt.ArrayLike,
    end: npt.ArrayLike,
    *,
    step: npt.ArrayLike | None = None,
    counts: npt.ArrayLike | None = None,
    order: Sequence[int] | None = None,
    path: str = "serpentine",
) -> NDArray[np.float64]:
    """A mesh of points over an axis box, in the order of a motion sequence.

    Parameters
    ----------
    start, end : array_like, shape (n_axes,)
        The box (mm or rad), ``start <= end`` per axis; an axis with ``start == end`` is
        fixed at that position.
    step : array_like, shape (n_axes,) or scalar, optional
        The spacing per axis (it must divide each interval), or
    counts : array_like of int, shape (n_axes,) or scalar, optional
        the number of positions per axis.
    order : sequence of int, optional
        The motion sequence: column indices from the axis that moves first (fastest) to
        the one that moves last. Default: the last column first (``Z``, then ``Y``, then
        ``X`` for X, Y, Z).
    path : {"serpentine", "raster"}
        Serpentine: every other pass of an axis runs backwards, so consecutive points are
        one step apart. Raster: every pass runs from ``start`` to ``end``.

    Returns
    -------
    ndarray, shape (n, n_axes)
        The points in the order they are measured; ``n`` is the product of the numbers
        of positions per axis.

    Raises
    ------
    InputError
        On an empty or reversed interval, a step that does not divide it, a bad count, an
        order that is not a permutation of the columns or an unknown path.

    Examples
    --------
    >>> mesh([0, 0], [1, 2], counts=[2, 3], order=[0, 1])
    array([[0., 0.],
           [1., 0.],
           [1., 1.],
           [0., 1.],
           [0., 2.],
           [1., 2.]])
    """
    return _mesh_points(_grid(start, end, step, counts), order, path)[0]


def cloud(
    start: npt.ArrayLike,
    end: npt.ArrayLike,
    rng: np.random.Generator,
    *,
    step: npt.ArrayLike | None = None,
    counts: npt.ArrayLike | None = None,
    order: Sequence[int] | None = None,
    path: str = "serpentine",
    fraction: float = 0.5,
) -> NDArray[np.float64]:
    """A cloud of points: a mesh with each inner coordinate moved inside its cell.

    Aguado et al. 2016 eq. 18, ``x_cloud = x_mesh ± rand(interval(x))`` for
    ``x_min < x < x_max``: every coordinate of a point that is not on the boundary of
    the box along that axis is moved by ``u · h``, ``u ~ U(-fraction, +fraction)``
    independently per point and per axis, ``h`` the mesh step of the axis. The boundary
    coordinates stay, so the cloud spans the same box. With ``fraction <= 0.5`` a point
    never leaves the cell of its mesh node (the interval of half a step either side) and
    consecutive points along an axis keep the order of the mesh, so the cloud is visited
    with the same directions of motion as the mesh.

    Parameters
    ----------
    start, end, step, counts, order, path
        The mesh, as :func:`mesh`.
    rng : numpy.random.Generator
        The source of the random moves (made from a ``SeedSequence`` by the caller); the
        same generator state gives the same cloud.
    fraction : float
        Half-width of the move in steps, ``0 < fraction <= 0.5``.

    Returns
    -------
    ndarray, shape (n, n_axes)
        The points, in the mesh's order.

    Raises
    ------
    InputError
        As :func:`mesh`; on a fraction outside ``(0, 0.5]``; if ``rng`` is not a Generator.

    Examples
    --------
    >>> rng = np.random.default_rng(np.random.SeedSequence(1))
    >>> c = cloud([0, 0, 0], [2500, 1500, 1200], rng, step=[500, 500, 400])
    >>> c.shape, bool(np.all((c >= 0) & (c <= [2500, 1500, 1200])))
    ((96, 3), True)
    """
    if not isinstance(rng, np.random.Generator):
        raise InputError(
            "expected a numpy.random.Generator (made from a SeedSequence)", field="rng"
        )
    if not (np.isfinite(fraction) and 0.0 < fraction <= 0.5):
        raise InputError(f"expected 0 < fraction <= 0.5, got {fraction!r}", field="fraction")
    values = _grid(start, end, step, counts)
    pts, index = _mesh_points(values, order, path)
    return _perturb(pts, values, index, rng, fraction)


def diagonals(
    start: npt.ArrayLike, end: npt.ArrayLike, n_points: int, *, which: str = "body"
) -> NDArray[np.float64]:
    """Points along the diagonals of an axis box (ISO 230-6 diagonal tests).

    Body diagonals join opposite corners of the box: ``2**(d-1)`` of them for ``d``
    axes of non-zero length (four in 3-D), each from the corner at ``start`` on the first
    such axis to the opposite one. Face diagonals join opposite corners of each face: for
    every pair of moving axes, the two diagonals of the rectangle they span on each of
    the faces (the other axes at their start and at their end), twelve in 3-D. Each
    diagonal carries ``n_points`` equally spaced points, its two ends included; diagonals
    follow one another, each run from its first corner to its second.

    Parameters
    ----------
    start, end : array_like, shape (n_axes,)
        The box; fixed axes (``start == end``) are left out of the diagonals.
    n_points : int
        Points per diagonal, >= 2.
    which : {"body", "face", "all"}
        The body diagonals, the face diagonals, or both (body first).

    Returns
    -------
    ndarray, shape (n_diagonals * n_points, n_axes)

    Raises
    ------
    InputError
        On a bad box, fewer than 2 points, fewer than two moving axes (fewer than three
        for face diagonals) or an unknown ``which``.

    Examples
    --------
    >>> d = diagonals([0, 0, 0], [2, 2, 2], 3)
    >>> d[:3]
    array([[0., 0., 0.],
           [1., 1., 1.],
           [2., 2., 2.]])
    >>> diagonals([0, 0, 0], [2, 2, 2], 3, which="all").shape
    (48, 3)
    """
    lo, hi = _box(start, end)
    if which not in ("body", "face", "all"):
        raise InputError(f"expected 'body', 'face' or 'all', got {which!r}", field="diagonals")
    if isinstance(n_points, bool) or int(n_points) != n_points or n_points < 2:
        raise InputError(
            f"expected at least 2 points per diagonal, got {n_points!r}", field="points"
        )
    moving = [i for i in range(lo.size) if hi[i] > lo[i]]
    k = len(moving)
    need = 3 if which == "face" else 2
    if k < need:
        raise InputError(
            f"{which} diagonals need at least {need} axes with start < end, got {k}",
            field="diagonals",
        )
    ends: list[tuple[NDArray[np.float64], NDArray[np.float64]]] = []
    if which in ("body", "all"):
        # corners with the first moving axis at its start; the diagonal ends at the mirror
        for bits in range(2 ** (k - 1)):
            a, b = lo.copy(), lo.copy()
            for j, ax in enumerate(moving):
                low_side = j == 0 or not (bits >> (j - 1)) & 1
                a[ax], b[ax] = (lo[ax], hi[ax]) if low_side else (hi[ax], lo[ax])
            ends.append((a, b))
    if which in ("face", "all") and k >= 3:
        for p in range(k):
            for q in range(p + 1, k):
                u, v = moving[p], moving[q]
                rest = [ax for ax in moving if ax not in (u, v)]
                for level in range(2 ** len(rest)):
                    base = lo.copy()
                    for j, ax in enumerate(rest):
                        base[ax] = hi[ax] if (level >> j) & 1 else lo[ax]
                    for flip in (False, True):
                        a, b = base.copy(), base.copy()
                        a[u], b[u] = lo[u], hi[u]
                        a[v], b[v] = (hi[v], lo[v]) if flip else (lo[v], hi[v])
                        ends.append((a, b))
    t = np.linspace(0.0, 1.0, int(n_points))[:, None]
    A = np.stack([e[0] for e in ends])
    B = np.stack([e[1] for e in ends])
    pts = A[:, None, :] + t[None, :, :] * (B - A)[:, None, :]
    return pts.reshape(-1, lo.size)


def _approach_moves(
    points: NDArray[np.float64], overshoot: NDArray[np.float64], approach: NDArray[np.int_]
) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """Commanded positions (K, d) and the point each reaches (-1: a pre-positioning move)."""
    n, d = points.shape
    prev = np.vstack([np.full((1, d), np.nan), points[:-1]])
    delta = points - prev
    # an axis with a direction of approach is pre-positioned before the first point, and
    # wherever the path would reach the point moving the other way
    needs = (approach != 0) & (np.isnan(delta) | (np.sign(delta) == -approach))
    pre = np.where(needs, points - approach * overshoot, points)
    extra = needs.any(axis=1)
    counts = 1 + extra.astype(np.intp)
    moves = np.empty((int(counts.sum()), d))
    target = np.empty(moves.shape[0], dtype=np.intp)
    last = np.cumsum(counts) - 1
    moves[last] = points
    target[last] = np.arange(n)
    first = last[extra] - 1
    moves[first] = pre[extra]
    target[first] = -1
    return moves, target


@dataclass(frozen=True)
class MeasurementPlan:
    """The verification points of a machine and the moves of the machine through them.

    Parameters
    ----------
    axes : tuple of str
        The axis letters of the columns (the machine's axis order, e.g. X, Y, Z).
    points : array_like, shape (n, n_axes)
        Nominal axis positions of the verification points in the order they are measured
        (mm; rad for a rotary axis).
    offsets : array_like, shape (k, 3), optional
        Reflector (tool) offsets from the tool reference point, mm, in the tool frame;
        the path is measured once per offset. Default one zero offset.
    overshoot : array_like, shape (n_axes,) or scalar, optional
        Distance by which an axis with a direction of approach goes past a point before
        approaching it (mm or rad), >= 0. Default 0.
    approach : sequence of {+1, -1, 0}, optional
        Per axis: arrive at every point moving in the + direction, in the - direction,
        or either way (0, no overshoot). Default 0 for all. An axis with a direction
        needs an overshoot > 0, and an overshoot needs a direction.
    kind : str
        ``"mesh"``, ``"cloud"``, ``"diagonals"`` or ``"points"`` (given by hand).
    seed : int, optional
        The seed of a cloud, recorded with the plan.

    Attributes
    ----------
    moves : ndarray, shape (K, n_axes)
        Every commanded position, in order: for each offset, the path through all the
        points with the pre-positioning (overshoot) moves inserted.
    move_point : ndarray of int, shape (K,)
        The index into :attr:`points` a move reaches, or -1 for a pre-positioning move
        (no measurement there).
    move_offset : ndarray of int, shape (K,)
        The index into :attr:`offsets` of the pass a move belongs to.

    Raises
    ------
    InputError
        On shapes that do not agree, non-finite values, a negative overshoot, a
        direction without overshoot or the reverse, or no points.

    Examples
    --------
    >>> plan = MeasurementPlan(("X",), [[0.0], [10.0], [5.0]], overshoot=[2.0], approach=[1])
    >>> plan.moves.ravel()
    array([-2.,  0., 10.,  3.,  5.])
    >>> plan.move_point
    array([-1,  0,  1, -1,  2])
    """

    axes: tuple[str, ...]
    points: NDArray[np.float64]
    offsets: NDArray[np.float64] = field(default_factory=lambda: np.zeros((1, 3)))
    overshoot: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    approach: tuple[int, ...] = ()
    kind: str = "points"
    seed: int | None = None
    moves: NDArray[np.float64] = field(init=False, repr=False)
    move_point: NDArray[np.intp] = field(init=False, repr=False)
    move_offset: NDArray[np.intp] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        axes = tuple(str(a) for a in self.axes)
        d = len(axes)
        if d == 0 or len(set(axes)) != d:
            raise InputError(f"expected distinct axis letters, got {axes}", field="axes")
        pts = np.asarray(self.points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != d or pts.shape[0] == 0:
            raise InputError(
                f"expected points of shape (n, {d}) with n >= 1 for axes {' '.join(axes)}, "
                f"got shape {pts.shape}",
                field="points",
            )
        if not np.all(np.isfinite(pts)):
            raise InputError("expected finite point coordinates", field="points")
        off = np.asarray(self.offsets, dtype=np.float64)
        if off.ndim == 1:
            off = off[None, :]
        if off.ndim != 2 or off.shape[1] != 3 or off.shape[0] == 0 or not np.all(np.isfinite(off)):
            raise InputError(
                f"expected finite offsets of shape (k, 3) with k >= 1, got shape {off.shape}",
                field="offsets",
            )
        ov = np.asarray(self.overshoot, dtype=np.float64)
        ov = np.zeros(d) if ov.size == 0 else np.broadcast_to(ov, (d,)).astype(np.float64)
        if not np.all(np.isfinite(ov)) or np.any(ov < 0):
            raise InputError(f"expected overshoots >= 0, got {ov.tolist()}", field="overshoot")
        ap = tuple(int(a) for a in self.approach) if len(self.approach) else (0,) * d
        if len(ap) != d or any(a not in (-1, 0, 1) for a in ap):
            raise InputError(
                f"expected one direction of approach (+1, -1 or 0) per axis, got {ap}",
                field="approach",
            )
        for i, ax in enumerate(axes):
            if (ap[i] != 0) != (ov[i] > 0):
                raise InputError(
                    f"axis {ax}: a direction of approach needs an overshoot > 0 and an "
                    f"overshoot needs a direction, got approach {ap[i]:+d}, overshoot "
                    f"{ov[i]:g}",
                    field=f"{ax}.overshoot",
                )
        if self.kind not in (*DISTRIBUTIONS, "points"):
            raise InputError(f"unknown kind {self.kind!r}", field="kind")
        k = off.shape[0]
        moves, target = _approach_moves(np.tile(pts, (k, 1)), ov, np.asarray(ap))
        n = pts.shape[0]
        offset_index = np.full(target.shape, -1, dtype=np.intp)
        hit = target >= 0
        offset_index[hit] = target[hit] // n
        # a pre-positioning move belongs to the pass of the point it prepares
        offset_index = _fill_back(offset_index)
        target = np.where(hit, target % n, -1)
        object.__setattr__(self, "axes", axes)
        object.__setattr__(self, "points", frozen_array(pts))
        object.__setattr__(self, "offsets", frozen_array(off))
        object.__setattr__(self, "overshoot", frozen_array(ov))
        object.__setattr__(self, "approach", ap)
        object.__setattr__(self, "moves", frozen_array(moves))
        object.__setattr__(self, "move_point", frozen_array(target))
        object.__setattr__(self, "move_offset", frozen_array(offset_index))

    @property
    def n_points(self) -> int:
        """Number of verification points ``n``."""
        return int(self.points.shape[0])

    @property
    def n_offsets(self) -> int:
        """Number of reflector offsets ``k``."""
        return int(self.offsets.shape[0])

    @property
    def n_measurements(self) -> int:
        """Number of measurements ``n * k`` (each point once per offset)."""
        return self.n_points * self.n_offsets

    @property
    def measurement_positions(self) -> NDArray[np.float64]:
        """Axis positions of the measurements in measuring order, shape ``(n * k, n_axes)``."""
        return np.tile(self.points, (self.n_offsets, 1))

    @property
    def measurement_offsets(self) -> NDArray[np.float64]:
        """Reflector offset of each measurement, shape ``(n * k, 3)``, mm."""
        return np.repeat(self.offsets, self.n_points, axis=0)


def _fill_back(idx: NDArray[np.intp]) -> NDArray[np.intp]:
    """Replace each -1 by the next non-negative entry (the last entry is never -1)."""
    out = idx.copy()
    pos = np.where(out >= 0, np.arange(out.size), out.size)
    nxt = np.minimum.accumulate(pos[::-1])[::-1]
    return out[np.minimum(nxt, out.size - 1)]


# ---------------------------------------------------------------------------------------
# The [workspace] table of a study file

_WS_KEYS = (
    "distribution",
    "sequence",
    "path",
    "seed",
    "fraction",
    "diagonals",
    "points",
    "offsets",
)
_AXIS_KEYS = ("start", "end", "step", "count", "overshoot", "approach")


def read_workspace(ws: Fields, machine_axes: Sequence[str] | None = None) -> MeasurementPlan:
    """Read a ``[workspace]`` table of a study file into a :class:`MeasurementPlan`.

    The table (``docs/verification-planning.md``)::

        [workspace]
        distribution = "mesh"     # "mesh", "cloud" or "diagonals"
        sequence = "ZYX"          # the axis that moves first, then the next, ...
        path = "serpentine"       # or "raster"
        seed = 2016               # cloud: the seed of its random moves (required)
        fraction = 0.5            # cloud: half-width of the moves, in steps
        diagonals = "body"        # diagonals: "body", "face" or "all"
        points = 10               # diagonals: points per diagonal
        offsets = [[0, 0, 0]]     # reflector offsets, mm (the path is repeated per offset)
        [workspace.X]
        start = 0                 # mm (deg for a rotary axis)
        end = 2500
        step = 500                # or count = 6 (mesh and cloud)
        overshoot = 50            # mm (deg), with approach
        approach = "+"            # "+", "-" or "none" (default)

    Parameters
    ----------
    ws : mtmc.document.Fields
        The table (it knows its file and the line of each key).
    machine_axes : sequence of str, optional
        The machine's axes in its order (``Machine.axes``): every one needs a table, and
        the columns follow this order. Without it, the axis tables given, in the
        canonical order X Y Z U V W A B C.

    Returns
    -------
    MeasurementPlan
        Positions in mm (rad for a rotary axis).

    Raises
    ------
    InputError
        Naming the file, the line and the field: an unknown key, a missing or wrong
        value, an axis the machine does not have or an axis of the machine left out.
    """
    axes = _workspace_axes(ws, machine_axes)
    dist = ws.text("distribution", "mesh", choices=DISTRIBUTIONS)
    d = len(axes)
    start, end = np.zeros(d), np.zeros(d)
    values: list[NDArray[np.float64]] = []
    overshoot, approach = np.zeros(d), [0] * d
    for i, a in enumerate(axes):
        start[i], end[i], grid, overshoot[i], approach[i] = _read_axis(ws, a, dist)
        values.append(grid)
    order = _read_sequence(ws, axes)
    path = ws.text("path", "serpentine", choices=_PATHS)
    offsets = _read_offsets(ws)
    pts, seed = _workspace_points(ws, dist, start, end, values, order, path)
    return MeasurementPlan(
        axes,
        pts,
        offsets=offsets,
        overshoot=overshoot,
        approach=tuple(approach),
        kind=dist,
        seed=seed,
    )


def _workspace_axes(ws: Fields, machine_axes: Sequence[str] | None) -> tuple[str, ...]:
    """The axes of the plan: the machine's (each with its table), else the tables given."""
    axis_names = [k for k in ws.data if k not in _WS_KEYS]
    for k in axis_names:
        if k not in AXIS_DIRECTION or not isinstance(ws.data[k], dict):
            raise ws.error(
                f"unknown key {k!r}; expected one of {', '.join(_WS_KEYS)} or an axis table "
                "such as [workspace.X]",
                k,
            )
    if machine_axes is None:
        axes = tuple(a for a in AXIS_DIRECTION if a in axis_names)
        if not axes:
            raise ws.error("expected at least one axis table such as [workspace.X]")
        return axes
    axes = tuple(machine_axes)
    for k in axis_names:
        if k not in axes:
            raise ws.error(f"axis {k} is not an axis of the machine ({' '.join(axes)})", k)
    for a in axes:
        if a not in axis_names:
            raise ws.error(
                f"missing [{'.'.join(map(str, ws.path))}.{a}]: every axis of the machine "
                f"needs start and end (start = end for an axis that stays put)"
            )
    return axes


def _read_axis(
    ws: Fields, a: str, dist: str
) -> tuple[float, float, NDArray[np.float64], float, int]:
    """One ``[workspace.A]`` table: start, end, the positions, overshoot, approach (mm/rad)."""
    t = ws.table(a)
    assert t is not None
    t.only(_AXIS_KEYS)
    scale = np.pi / 180.0 if is_rotary(a) else 1.0
    lo = t.number("start") * scale
    hi = t.number("end") * scale
    if hi < lo:
        raise t.error(f"expected end >= start ({t.data['start']!r})", "end")
    if dist != "diagonals" and hi > lo:
        grid = _axis_grid(t, lo, hi, scale)
    else:
        grid = np.array([lo])
        for key in ("step", "count"):
            if t.has(key):
                why = "a diagonal" if dist == "diagonals" else "a fixed axis (start = end)"
                raise t.error(f"{key} has no meaning for {why}", key)
    overshoot = t.number("overshoot", 0.0, low=0.0) * scale
    approach = _APPROACH[t.text("approach", "none", choices=tuple(_APPROACH))]
    if (approach != 0) != (overshoot > 0):
        key = "approach" if t.has("approach") else "overshoot"
        raise t.error(
            "a direction of approach needs an overshoot > 0, and an overshoot needs an "
            'approach of "+" or "-"',
            key,
        )
    return lo, hi, grid, overshoot, approach


def _axis_grid(t: Fields, lo: float, hi: float, scale: float) -> NDArray[np.float64]:
    """The positions of a moving axis from its ``step`` or ``count``."""
    if t.has("step") == t.has("count"):
        raise t.error("expected either step or count (not both)", "step")
    key = "step" if t.has("step") else "count"
    try:
        if key == "step":
            step = t.number("step", low=0.0, open_low=True) * scale
            return axis_values(lo, hi, step=step)
        count = t.integer("count", minimum=2)
        return axis_values(lo, hi, count=count)
    except InputError as exc:
        if exc.file is not None:
            raise
        raise t.error(exc.message, key) from None


def _read_sequence(ws: Fields, axes: tuple[str, ...]) -> list[int]:
    """The order the axes move in (``sequence``), as indices into ``axes``."""
    seq_text = ws.text("sequence", "".join(axes[::-1]))
    seq_letters = [c for c in seq_text.upper() if not c.isspace()]
    if sorted(seq_letters) != sorted(axes):
        raise ws.error(
            f"expected the sequence to name each axis ({' '.join(axes)}) once, got {seq_text!r}",
            "sequence",
        )
    return [axes.index(c) for c in seq_letters]


def _workspace_points(
    ws: Fields,
    dist: str,
    start: NDArray[np.float64],
    end: NDArray[np.float64],
    values: list[NDArray[np.float64]],
    order: list[int],
    path: str,
) -> tuple[NDArray[np.float64], int | None]:
    """The points of the distribution and the seed of a cloud (keys of the others refused)."""
    if dist == "diagonals":
        for key in ("seed", "fraction"):
            if ws.has(key):
                raise ws.error(f"{key} is for a cloud, not for diagonals", key)
        which = ws.text("diagonals", "body", choices=("body", "face", "all"))
        n_points = ws.integer("points", minimum=2)
        try:
            return diagonals(start, end, n_points, which=which), None
        except InputError as exc:
            raise ws.error(exc.message, "diagonals") from None
    for key in ("diagonals", "points"):
        if ws.has(key):
            raise ws.error(f"{key} is for distribution = 'diagonals'", key)
    pts, index = _mesh_points(values, order, path)
    if dist == "cloud":
        seed = ws.integer("seed", minimum=0)
        frac = ws.number("fraction", 0.5, low=0.0, high=0.5, open_low=True)
        rng = np.random.default_rng(np.random.SeedSequence(seed))
        return _perturb(pts, values, index, rng, frac), seed
    if ws.has("seed") or ws.has("fraction"):
        key = "seed" if ws.has("seed") else "fraction"
        raise ws.error(f"{key} is for distribution = 'cloud'", key)
    return pts, None


def _read_offsets(ws: Fields) -> NDArray[np.float64]:
    raw = ws.data.get("offsets", [[0.0, 0.0, 0.0]])
    ok = (
        isinstance(raw, list)
        and len(raw) > 0
        and all(
            isinstance(r, list)
            and len(r) == 3
            and all(finite(v) is not None and abs(v) <= MAX_MM for v in r)
            for r in raw
        )
    )
    if not ok:
        raise ws.error(
            f"expected an array of [x, y, z] offsets in mm, each at most {MAX_MM:g} in size, "
            f"e.g. [[0, 0, 0], [0, 0, 100]], got {raw!r:.80}",
            "offsets",
        )
    return np.asarray(raw, dtype=np.float64)


def workspace_from_dict(
    data: dict[str, Any],
    file: str = "<study>",
    *,
    text: str | None = None,
    machine_axes: Sequence[str] | None = None,
) -> MeasurementPlan:
    """Read a ``[workspace]`` table given as a dict (see :func:`read_workspace`).

    Parameters
    ----------
    data : dict
        The parsed TOML of the whole study (with a ``workspace`` table).
    file : str
        The file name for the messages.
    text : str, optional
        The TOML text, for the line numbers in the messages
        (:func:`mtmc.graph.toml_format.key_lines`); without it messages name no line.
    machine_axes : sequence of str, optional
        As :func:`read_workspace`.

    Returns
    -------
    MeasurementPlan

    Raises
    ------
    InputError
        As :func:`read_workspace`; if there is no ``[workspace]`` table.

    Examples
    --------
    >>> import tomllib
    >>> text = '''
    ... [workspace]
    ... [workspace.X]
    ... start = 0
    ... end = 100
    ... step = 50
    ... '''
    >>> workspace_from_dict(tomllib.loads(text), text=text).points.ravel()
    array([  0.,  50., 100.])
    """
    top = Fields(Source.from_text(text or "", file), data)
    ws = top.table("workspace")
    assert ws is not None
    return read_workspace(ws, machine_axes)
