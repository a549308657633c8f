"""Input checkers for the batched geometry functions.

Each ``check_*`` helper coerces its argument to a ``float64`` array with the trial axis
first (without a copy when it already is one) and raises :class:`mtmc.errors.InputError`
naming the argument, the expected shape and the received one. :func:`batch_size` and
:func:`broadcast_batch` make arguments with a batch of 1 (a single point given as
``(3,)`` or ``(1, 3)``) broadcast against a batch of ``M``. :func:`degenerate` raises
:class:`mtmc.errors.DegenerateGeometryError` naming the case and how many trials of the
batch are affected.

The geometry functions and the measurement graph's ops check their arguments with these
helpers, so that one kind of input is always checked one way, with one message.

Tolerance
---------
Degeneracy is decided with the relative tolerance :data:`RTOL` (``1e-10``): a
construction is degenerate when a quantity that must be non-zero (a cross product, a
projected length, a singular value) is at most ``RTOL`` times the natural scale of its
inputs (the product of the vector lengths, the largest singular value, ...). Each
function states its scale in its docstring.
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import DegenerateGeometryError, InputError

__all__ = [
    "ORTHO_TOL",
    "RTOL",
    "as_float",
    "batch_size",
    "broadcast_batch",
    "check_frames",
    "check_point_sets",
    "check_points",
    "check_rotation_matrices",
    "check_scalars",
    "check_vectors",
    "degenerate",
    "in_batch",
    "IN_BATCH",
]

RTOL: float = 1e-10
"""Relative tolerance below which a construction is declared degenerate."""

ORTHO_TOL: float = 1e-9
"""Largest element of ``|RᵀR − I|`` of a matrix accepted as a rotation matrix.

Products of a few hundred rotations in float64 stay near 1e-13; a first-order (small-angle)
matrix ``I + [e]x`` misses by ``|e|²`` and passes for angles below about 3e-5 rad.
"""


def in_batch(mask: npt.ArrayLike, items: str = "trials", item: str = "trial") -> str:
    """Where the set entries of ``mask``, shape ``(M,)``, are: the words of a batch's error.

    Every refusal of some trials of a batch says it so: how many, of how many, the first.

    Examples
    --------
    >>> in_batch(np.array([False, True, True]))
    'in 2 of 3 trials (first: trial 1)'
    >>> in_batch(np.array([True]), "matrices", "matrix")
    'in 1 of 1 matrices (first: matrix 0)'
    """
    m = np.asarray(mask, dtype=np.bool_).ravel()
    bad = np.flatnonzero(m)
    return f"in {bad.size} of {m.size} {items} (first: {item} {bad[0]})"


#: The words :func:`in_batch` writes, as a pattern: a message about one case (the nominal
#: values of a graph) leaves them out.
IN_BATCH = re.compile(r" in \d+ of \d+ \w+ \(first: \w+ \d+\)")


def _shape_text(shape: tuple[int, ...]) -> str:
    return "(" + ", ".join(str(s) for s in shape) + (",)" if len(shape) == 1 else ")")


def as_float(x: npt.ArrayLike, name: str) -> NDArray[np.float64]:
    """``x`` as a float64 array (no copy when it already is one), any shape.

    Raises
    ------
    InputError
        If ``x`` is not numeric, naming the field ``name``.
    """
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(
            f"expected an array of real numbers, got {type(x).__name__} ({exc})", field=name
        ) from None
    return arr


def check_points(x: npt.ArrayLike, name: str = "points") -> NDArray[np.float64]:
    """Coerce a batch of 3D points (or vectors) to a float64 array of shape ``(M, 3)``.

    Parameters
    ----------
    x : array_like, shape (M, 3) or (3,)
        The points; a single point ``(3,)`` becomes a batch of one, ``(1, 3)``.
    name : str
        The argument name used in the error message.

    Returns
    -------
    ndarray, shape (M, 3)
        The points as float64 (no copy when ``x`` already is a float64 array).

    Raises
    ------
    InputError
        If ``x`` is not numeric or does not have shape ``(M, 3)`` or ``(3,)``.

    Examples
    --------
    >>> check_points([1, 2, 3]).shape
    (1, 3)
    >>> check_points([[1, 2]], name="a")
    Traceback (most recent call last):
    ...
    mtmc.errors.InputError: field a: expected shape (M, 3) or (3,), got (1, 2)
    """
    arr = as_float(x, name)
    if arr.ndim == 1 and arr.shape[0] == 3:
        return arr.reshape(1, 3)
    if arr.ndim == 2 and arr.shape[1] == 3:
        return arr
    raise InputError(f"expected shape (M, 3) or (3,), got {_shape_text(arr.shape)}", field=name)


def check_vectors(x: npt.ArrayLike, name: str = "vectors") -> NDArray[np.float64]:
    """Coerce a batch of 3D vectors to ``(M, 3)`` float64; same rules as :func:`check_points`.

    Parameters
    ----------
    x : array_like, shape (M, 3) or (3,)
        The vectors.
    name : str
        The argument name used in the error message.

    Returns
    -------
    ndarray, shape (M, 3)
        The vectors as float64.

    Raises
    ------
    InputError
        If ``x`` does not have shape ``(M, 3)`` or ``(3,)``.
    """
    return check_points(x, name)


def check_scalars(x: npt.ArrayLike, name: str = "values") -> NDArray[np.float64]:
    """Coerce a batch of scalars to a float64 array of shape ``(M,)``.

    Parameters
    ----------
    x : array_like, shape (M,) or ()
        The values; a plain number becomes a batch of one, ``(1,)``.
    name : str
        The argument name used in the error message.

    Returns
    -------
    ndarray, shape (M,)
        The values as float64.

    Raises
    ------
    InputError
        If ``x`` is not numeric or not 0- or 1-dimensional.

    Examples
    --------
    >>> check_scalars(2.5)
    array([2.5])
    """
    arr = as_float(x, name)
    if arr.ndim == 0:
        return arr.reshape(1)
    if arr.ndim == 1:
        return arr
    raise InputError(f"expected shape (M,) or a number, got {_shape_text(arr.shape)}", field=name)


def check_rotation_matrices(x: npt.ArrayLike, name: str = "R") -> NDArray[np.float64]:
    """Coerce rotation matrices to float64 of shape ``(..., 3, 3)`` and refuse the others.

    A rotation matrix is orthogonal with determinant +1. A reflection (determinant -1) or
    a matrix that is not orthogonal has no rotation angles, axis or quaternion: it is
    refused rather than turned into a rotation it is not.

    Parameters
    ----------
    x : array_like, shape (..., 3, 3)
        The matrices.
    name : str
        The argument name used in the error message.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The matrices as float64.

    Raises
    ------
    InputError
        If the trailing shape is not ``(3, 3)``, a matrix is not orthogonal
        (``max |RᵀR − I| > ORTHO_TOL``, NaN included), or it is a reflection (``det R < 0``).

    Examples
    --------
    >>> check_rotation_matrices(np.diag([1.0, 1.0, -1.0]))
    Traceback (most recent call last):
    ...
    mtmc.errors.InputError: field R: expected a rotation matrix (det +1), got a reflection ...
    """
    arr = as_float(x, name)
    if arr.ndim < 2 or arr.shape[-2:] != (3, 3):
        raise InputError(f"expected shape (..., 3, 3), got {_shape_text(arr.shape)}", field=name)
    flat = arr.reshape(-1, 3, 3)
    err = np.abs(np.swapaxes(flat, -1, -2) @ flat - np.eye(3)).max(axis=(-2, -1))
    bad = ~(err <= ORTHO_TOL)
    if bad.any():
        raise InputError(
            f"expected a rotation matrix (max |RᵀR − I| <= {ORTHO_TOL:g}), got one with "
            f"{float(err[np.argmax(bad)]):.3g} {in_batch(bad, 'matrices', 'matrix')}",
            field=name,
        )
    refl = np.linalg.det(flat) < 0.0
    if refl.any():
        raise InputError(
            "expected a rotation matrix (det +1), got a reflection (det -1) "
            + in_batch(refl, "matrices", "matrix"),
            field=name,
        )
    return arr


def check_point_sets(
    x: npt.ArrayLike, name: str = "points", *, min_points: int = 1, what: str = "the fit"
) -> NDArray[np.float64]:
    """Coerce a batch of point sets to float64 of shape ``(M, n, 3)`` and check ``n``.

    Parameters
    ----------
    x : array_like, shape (M, n, 3) or (n, 3)
        ``M`` sets of ``n`` points each; a single set ``(n, 3)`` becomes ``(1, n, 3)``.
    name : str
        The argument name used in the error message.
    min_points : int
        The least number of points per set, ``n >= min_points``.
    what : str
        What needs the points, for the message (``"a sphere fit"``).

    Returns
    -------
    ndarray, shape (M, n, 3)
        The point sets as float64.

    Raises
    ------
    InputError
        If the shape is wrong or some coordinates are not finite (NaN or infinite
        coordinates are refused, not propagated).
    DegenerateGeometryError
        If ``n < min_points``.

    Examples
    --------
    >>> check_point_sets([[0, 0, 0], [1, 0, 0], [0, 1, 0]], min_points=4, what="a sphere fit")
    Traceback (most recent call last):
    ...
    mtmc.errors.DegenerateGeometryError: field points: a sphere fit needs at least 4 points, got 3
    """
    arr = as_float(x, name)
    if arr.ndim == 2 and arr.shape[1] == 3:
        arr = arr.reshape(1, *arr.shape)
    if arr.ndim != 3 or arr.shape[2] != 3:
        raise InputError(
            f"expected shape (M, n, 3) or (n, 3), got {_shape_text(arr.shape)}", field=name
        )
    n = arr.shape[1]
    if n < min_points:
        raise DegenerateGeometryError(
            f"{what} needs at least {min_points} points, got {n}", field=name
        )
    finite = np.isfinite(arr).all(axis=(1, 2))
    if not finite.all():
        raise InputError(
            f"expected finite coordinates, got NaN or infinity {in_batch(~finite)}", field=name
        )
    return arr


def check_frames(x: npt.ArrayLike, name: str = "frames") -> NDArray[np.float64]:
    """Coerce a batch of homogeneous transforms to float64 of shape ``(M, 4, 4)``.

    Parameters
    ----------
    x : array_like, shape (M, 4, 4) or (4, 4)
        The frames; a single ``(4, 4)`` matrix becomes ``(1, 4, 4)``.
    name : str
        The argument name used in the error message.

    Returns
    -------
    ndarray, shape (M, 4, 4)
        The frames as float64.

    Raises
    ------
    InputError
        If the shape is wrong.
    """
    arr = as_float(x, name)
    if arr.shape == (4, 4):
        return arr.reshape(1, 4, 4)
    if arr.ndim == 3 and arr.shape[1:] == (4, 4):
        return arr
    raise InputError(
        f"expected shape (M, 4, 4) or (4, 4), got {_shape_text(arr.shape)}", field=name
    )


def batch_size(**arrays: NDArray[Any]) -> int:
    """The common batch size of arrays whose leading axis is the trial.

    A batch of 1 broadcasts against any other; two different sizes above 1 do not.

    Parameters
    ----------
    **arrays : ndarray
        The arrays, by argument name (the names appear in the error message).

    Returns
    -------
    int
        The largest leading size ``M``.

    Raises
    ------
    InputError
        If two arrays have different batch sizes, neither of them 1.

    Examples
    --------
    >>> import numpy as np
    >>> batch_size(a=np.zeros((1, 3)), b=np.zeros((5, 3)))
    5
    """
    m = 1
    first = ""
    for key, arr in arrays.items():
        k = arr.shape[0]
        if k == 1:
            continue
        if m == 1:
            m, first = k, key
        elif k != m:
            raise InputError(
                f"expected {m} trials (as in {first}) or 1, got {k}",
                field=key,
            )
    return m


def broadcast_batch(m: int, arr: NDArray[np.float64]) -> NDArray[np.float64]:
    """Broadcast an array with a batch of 1 to a batch of ``m`` (a read-only view).

    Parameters
    ----------
    m : int
        The batch size wanted.
    arr : ndarray, shape (1, ...) or (m, ...)
        The array.

    Returns
    -------
    ndarray, shape (m, ...)
        ``arr`` itself when it already has ``m`` trials, else a broadcast view.
    """
    if arr.shape[0] == m:
        return arr
    return np.broadcast_to(arr, (m, *arr.shape[1:]))


def degenerate(mask: NDArray[np.bool_], case: str, expected: str, field: str | None = None) -> None:
    """Raise :class:`DegenerateGeometryError` when any trial of ``mask`` is set.

    Parameters
    ----------
    mask : ndarray of bool, shape (M,)
        True for the degenerate trials.
    case : str
        The degenerate case, in words (``"the three points are collinear"``).
    expected : str
        What was expected instead (``"three non-collinear points"``).
    field : str, optional
        The argument name.

    Raises
    ------
    DegenerateGeometryError
        ``"<case> in k of M trials (first: trial i); expected <expected>"``.

    Examples
    --------
    >>> import numpy as np
    >>> try:
    ...     degenerate(np.array([False, True]), "the vector has zero length", "a vector")
    ... except DegenerateGeometryError as exc:
    ...     print(exc)
    the vector has zero length in 1 of 2 trials (first: trial 1); expected a vector
    """
    if mask.any():
        raise DegenerateGeometryError(f"{case} {in_batch(mask)}; expected {expected}", field=field)
