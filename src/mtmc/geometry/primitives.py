"""Batched geometric primitives: lines, planes, circles and spheres.

Each primitive is a small frozen dataclass holding a whole batch of ``M`` trials, the
trial axis first, like :class:`scipy.spatial.transform.Rotation`: ``len(line)`` is
``M`` and ``line[i]`` or ``line[2:5]`` is a sub-batch (an integer index keeps a batch
of one). Shapes are checked and values coerced to float64 on construction; a single
``(3,)`` point or a plain number is a batch of one, and a batch of one broadcasts
against a batch of ``M`` (e.g. one fixed line point with ``M`` sampled directions).

The arrays of a primitive are read-only, and never the caller's: an array passed in is
copied unless it is read-only already (a primitive's own, when a sub-batch is taken).
Directions and normals are normalised to unit length on construction; a zero-length
one raises :class:`mtmc.errors.DegenerateGeometryError`. NaN values are not refused: they
propagate (a Monte Carlo trial that went wrong upstream stays visible as NaN).

Units: lengths in mm.

Examples
--------
>>> import numpy as np
>>> plane = Plane(point=[0, 0, 1], normal=[0, 0, 2])
>>> len(plane), plane.normal
(1, array([[0., 0., 1.]]))
>>> plane.offset
array([-1.])
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import InputError
from mtmc.geometry.checks import (
    batch_size,
    broadcast_batch,
    check_points,
    check_scalars,
    check_vectors,
    degenerate,
    in_batch,
)

__all__ = ["Circle", "Line", "Plane", "Sphere"]

Index = int | slice | npt.NDArray[np.intp] | npt.NDArray[np.bool_] | list[int]


def _normalised(v: NDArray[np.float64], name: str, what: str) -> NDArray[np.float64]:
    norm = np.sqrt(np.einsum("mi,mi->m", v, v))
    degenerate(norm <= 0.0, f"the {what} has zero length", f"a non-zero {what}", name)
    # Vectors already of unit length (to 1e-15) are kept as they are, so that a
    # primitive rebuilt from another's arrays (a sub-batch) holds the same numbers.
    return v / np.where(np.abs(norm - 1.0) <= 1e-15, 1.0, norm)[:, None]


def unit_rows(
    v: NDArray[np.float64], name: str, what: str, sq: NDArray[np.float64] | None = None
) -> NDArray[np.float64]:
    """Normalise the columns of a ``(3, M)`` array of coordinate rows, in place.

    The rows counterpart of the normalisation of a primitive's direction, bit for bit:
    ``|v|² = (x² + z²) + y²`` (the order in which NumPy's ``einsum`` sums the three
    products of an ``(M, 3)`` row on x86-64; a test compares the two), and vectors
    already of unit length (to 1e-15) kept as they are.

    Parameters
    ----------
    v : ndarray, shape (3, M)
        The vectors, one row per coordinate (overwritten by the unit vectors).
    name, what : str
        The field and the thing, for the error (``"direction"``, ``"line direction"``).
    sq : ndarray, shape (M,), optional
        ``|v|²`` summed in that order (:func:`squared_rows`), where already formed
        (overwritten).

    Returns
    -------
    ndarray, shape (3, M)
        ``v``, now of unit columns.

    Raises
    ------
    DegenerateGeometryError
        If a vector has zero length.
    """
    sq = squared_rows(v) if sq is None else sq
    norm = np.sqrt(sq, out=sq)
    degenerate(norm <= 0.0, f"the {what} has zero length", f"a non-zero {what}", name)
    unit = np.subtract(norm, 1.0)
    unit = np.abs(unit, out=unit) <= 1e-15
    if unit.any():  # kept as they are
        norm[unit] = 1.0
    v /= norm
    return v


def squared_rows(
    v: NDArray[np.float64], order: tuple[int, int, int] = (0, 2, 1)
) -> NDArray[np.float64]:
    """``|v|²`` of each column of a ``(3, M)`` array, the squares added in ``order``.

    The default, ``(x² + z²) + y²``, is the order of :func:`unit_rows`.
    """
    i, j, k = order
    sq: NDArray[np.float64] = v[i] * v[i]
    tmp = v[j] * v[j]
    sq += tmp
    sq += np.multiply(v[k], v[k], out=tmp)
    return sq


def _index(arr: NDArray[Any], idx: Any) -> NDArray[Any]:
    if isinstance(idx, int | np.integer):
        m = arr.shape[0]
        if not -m <= int(idx) < m:
            raise IndexError(f"trial index {idx} out of range for a batch of {m}")
        i = int(idx) % m
        return arr[i : i + 1]
    out: NDArray[Any] = arr[idx]
    return out


def _own(arr: NDArray[np.float64], given: Any) -> NDArray[np.float64]:
    """``arr``, copied if it shares memory with ``given``, a writable array of the caller.

    A read-only array (a primitive's own, when a sub-batch is taken) is kept without a copy.
    """
    if isinstance(given, np.ndarray) and given.flags.writeable and np.may_share_memory(arr, given):
        return arr.copy()
    return arr


def _set(obj: object, **values: NDArray[np.float64]) -> None:
    for key, value in values.items():
        if value.flags.writeable:
            value = value.view()
            value.flags.writeable = False
        object.__setattr__(obj, key, value)


def _check_radius(r: NDArray[np.float64], name: str) -> None:
    bad = r < 0.0
    if bad.any():
        raise InputError(
            f"expected a radius >= 0 mm, got {float(r[np.argmax(bad)])!r} {in_batch(bad)}",
            field=name,
        )


def _set_point_and_unit(obj: Line | Plane, name: str, what: str) -> None:
    """Check ``obj.point`` and the vector ``obj.<name>``, normalise it, broadcast both."""
    p = _own(check_points(obj.point, "point"), obj.point)
    v = check_vectors(getattr(obj, name), name)
    m = batch_size(point=p, **{name: v})
    _set(obj, point=broadcast_batch(m, p), **{name: broadcast_batch(m, _normalised(v, name, what))})


@dataclass(frozen=True, eq=False)
class Line:
    """A batch of ``M`` straight lines, each a point and a unit direction.

    Parameters
    ----------
    point : array_like, shape (M, 3) or (3,)
        A point on each line, mm.
    direction : array_like, shape (M, 3) or (3,)
        The direction of each line; normalised to unit length on construction.

    Raises
    ------
    InputError
        If a shape is wrong or the batch sizes differ (other than 1 against ``M``).
    DegenerateGeometryError
        If a direction has zero length.
    """

    point: NDArray[np.float64]
    direction: NDArray[np.float64]

    def __post_init__(self) -> None:
        _set_point_and_unit(self, "direction", "line direction")

    @classmethod
    def of_unit(cls, point: NDArray[np.float64], direction: NDArray[np.float64]) -> Line:
        """The lines of new ``(M, 3)`` float64 arrays, ``direction`` already of unit length.

        For a construction that made its arrays itself and normalised the directions as
        the constructor does (:func:`unit_rows`): they are kept as they are (made
        read-only), with neither checks nor copies.
        """
        obj = object.__new__(cls)
        _set(obj, point=point, direction=direction)
        return obj

    def __len__(self) -> int:
        return int(self.point.shape[0])

    def __getitem__(self, idx: Index) -> Line:
        return Line(_index(self.point, idx), _index(self.direction, idx))

    def at(self, t: npt.ArrayLike) -> NDArray[np.float64]:
        """The points ``point + t * direction`` of the lines.

        Parameters
        ----------
        t : array_like, shape (M,) or ()
            The signed distance along each line, mm.

        Returns
        -------
        ndarray, shape (M, 3)
            The points, mm.
        """
        tt = check_scalars(t, "t")
        return self.point + tt[:, None] * self.direction


@dataclass(frozen=True, eq=False)
class Plane:
    """A batch of ``M`` planes, each a point and a unit normal.

    The plane is ``{x : normal · (x - point) = 0}``, or in the form of Stryczek's eq. 28,
    ``I x + J y + K z + D = 0`` with ``(I, J, K) = normal`` and ``D = offset``.

    Parameters
    ----------
    point : array_like, shape (M, 3) or (3,)
        A point on each plane, mm.
    normal : array_like, shape (M, 3) or (3,)
        The normal of each plane; normalised to unit length on construction.

    Raises
    ------
    InputError
        If a shape is wrong or the batch sizes differ.
    DegenerateGeometryError
        If a normal has zero length.
    """

    point: NDArray[np.float64]
    normal: NDArray[np.float64]

    def __post_init__(self) -> None:
        _set_point_and_unit(self, "normal", "plane normal")

    def __len__(self) -> int:
        return int(self.point.shape[0])

    def __getitem__(self, idx: Index) -> Plane:
        return Plane(_index(self.point, idx), _index(self.normal, idx))

    @property
    def offset(self) -> NDArray[np.float64]:
        """``D = -normal · point`` of the plane equation ``n · x + D = 0`` (eq. 29), shape (M,)."""
        d: NDArray[np.float64] = -np.einsum("mi,mi->m", self.normal, self.point)
        return d


@dataclass(frozen=True, eq=False)
class Circle:
    """A batch of ``M`` circles in space: centre, unit normal of their plane, radius.

    Parameters
    ----------
    centre : array_like, shape (M, 3) or (3,)
        The centres, mm.
    normal : array_like, shape (M, 3) or (3,)
        The normals of the circles' planes; normalised on construction.
    radius : array_like, shape (M,) or ()
        The radii, mm, ``>= 0``.

    Raises
    ------
    InputError
        If a shape is wrong, the batch sizes differ, or a radius is negative.
    DegenerateGeometryError
        If a normal has zero length.
    """

    centre: NDArray[np.float64]
    normal: NDArray[np.float64]
    radius: NDArray[np.float64]

    def __post_init__(self) -> None:
        c = _own(check_points(self.centre, "centre"), self.centre)
        n = check_vectors(self.normal, "normal")
        r = _own(check_scalars(self.radius, "radius"), self.radius)
        _check_radius(r, "radius")
        m = batch_size(centre=c, normal=n, radius=r)
        _set(
            self,
            centre=broadcast_batch(m, c),
            normal=broadcast_batch(m, _normalised(n, "normal", "circle normal")),
            radius=broadcast_batch(m, r),
        )

    def __len__(self) -> int:
        return int(self.centre.shape[0])

    def __getitem__(self, idx: Index) -> Circle:
        return Circle(_index(self.centre, idx), _index(self.normal, idx), _index(self.radius, idx))

    @property
    def plane(self) -> Plane:
        """The plane of each circle (through the centre, with the circle's normal)."""
        return Plane(self.centre, self.normal)


@dataclass(frozen=True, eq=False)
class Sphere:
    """A batch of ``M`` spheres: centre and radius.

    Parameters
    ----------
    centre : array_like, shape (M, 3) or (3,)
        The centres, mm.
    radius : array_like, shape (M,) or ()
        The radii, mm, ``>= 0``.

    Raises
    ------
    InputError
        If a shape is wrong, the batch sizes differ, or a radius is negative.
    """

    centre: NDArray[np.float64]
    radius: NDArray[np.float64]

    def __post_init__(self) -> None:
        c = _own(check_points(self.centre, "centre"), self.centre)
        r = _own(check_scalars(self.radius, "radius"), self.radius)
        _check_radius(r, "radius")
        m = batch_size(centre=c, radius=r)
        _set(self, centre=broadcast_batch(m, c), radius=broadcast_batch(m, r))

    def __len__(self) -> int:
        return int(self.centre.shape[0])

    def __getitem__(self, idx: Index) -> Sphere:
        return Sphere(_index(self.centre, idx), _index(self.radius, idx))
