"""The values of places as flat arrays of components, and the values of marked places.

Every place type has a fixed layout of components (:data:`PARTS`): :func:`flatten` turns a
batched value into an ``(m, k)`` array and :func:`unflatten` back; the running sums of a
graph run (:mod:`mtmc.graph.run`) and the nominal check (:mod:`mtmc.graph.nominal`) both
work on this layout. :func:`marked_value` is the value of a marked (input) place for a
batch of drawn samples.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mtmc.errors import InputError
from mtmc.geometry.constructions import normal_plane_basis
from mtmc.geometry.primitives import Circle, Line, Plane, Sphere
from mtmc.graph.places import SCALAR_TYPES, VECTOR_TYPES, Place

__all__ = ["PARTS", "flatten", "marked_value", "normal_plane_parts", "place_factor", "unflatten"]

#: Parts of each place type in the flat layout used for the running sums: (name, size).
PARTS: dict[str, tuple[tuple[str, int], ...]] = {
    "x": (("value", 1),),
    "y": (("value", 1),),
    "z": (("value", 1),),
    "real": (("value", 1),),
    "point": (("value", 3),),
    "vector": (("value", 3),),
    "direction": (("value", 3),),
    "line": (("point", 3), ("direction", 3)),
    "plane": (("point", 3), ("normal", 3)),
    "circle": (("centre", 3), ("normal", 3), ("radius", 1)),
    "sphere": (("centre", 3), ("radius", 1)),
    "frame": (("rotation", 9), ("translation", 3)),
}


def flatten(type_: str, value: Any, m: int) -> NDArray[np.float64]:
    """The components of a place value as an ``(m, k)`` array (layout of :data:`PARTS`).

    Parameters
    ----------
    type_ : str
        The place type.
    value : ndarray or primitive
        The batched value (``(m,)``, ``(m, 3)``, a Line/Plane/Circle/Sphere, ``(m, 4, 4)``).
    m : int
        Trials in the batch (a batch of one broadcasts).

    Returns
    -------
    ndarray, shape (m, k)
        A new array (never a view of ``value``; stored component by component, so it
        is the transpose of a C-contiguous ``(k, m)`` array). ``k`` = 1 (scalar), 3
        (point, vector, direction), 6 (line: point, direction; plane: point, normal), 7
        (circle: centre, normal, radius), 4 (sphere: centre, radius), 12 (frame:
        rotation row by row, translation).
    """
    return _rows(_cols(type_, value, m), m).T


def _cols(type_: str, value: Any, m: int) -> list[Any]:
    """The parts of a place value as ``(m, j)`` arrays (or batches of one)."""
    if type_ in SCALAR_TYPES:
        cols = [np.broadcast_to(np.asarray(value, dtype=np.float64).reshape(-1), (m,))[:, None]]
    elif type_ in VECTOR_TYPES:
        cols = [np.broadcast_to(np.asarray(value, dtype=np.float64).reshape(-1, 3), (m, 3))]
    elif isinstance(value, Line):
        cols = [value.point, value.direction]
    elif isinstance(value, Plane):
        cols = [value.point, value.normal]
    elif isinstance(value, Circle):
        cols = [value.centre, value.normal, value.radius[:, None]]
    elif isinstance(value, Sphere):
        cols = [value.centre, value.radius[:, None]]
    elif type_ == "frame":
        t = np.asarray(value, dtype=np.float64).reshape(-1, 4, 4)
        cols = [t[:, :3, :3].reshape(-1, 9), t[:, :3, 3]]
    else:  # pragma: no cover - every type is handled above
        raise TypeError(f"cannot flatten a {type_}")
    return cols


def _rows(cols: list[Any], m: int) -> NDArray[np.float64]:
    """The columns ``cols`` (each ``(m, j)`` or a batch of one) as a new ``(k, m)`` array."""
    out = np.empty((sum(c.shape[1] for c in cols), m))
    i = 0
    for c in cols:
        out[i : i + c.shape[1]] = np.asarray(c).T
        i += c.shape[1]
    return out


def place_factor(p: Place, factor: float) -> float:
    """The factor from a place's value as written to the library's mm and rad."""
    if p.type == "direction" or p.unit == "1" or p.unit == "rad":
        return 1.0
    if p.unit == "deg":
        return math.pi / 180.0
    return factor


def marked_value(p: Place, factor: float, samples: Mapping[str, Any]) -> Any:
    """The value of a marked place: ``(m,)``/``(m, 3)`` if random, a batch of one if constant."""
    f = place_factor(p, factor)
    vec = p.type in VECTOR_TYPES
    if vec:
        base = np.asarray(p.value if p.value is not None else (0.0, 0.0, 0.0)) * f
        if p.name + ".x" not in samples:
            return base.reshape(1, 3)
        cols = [np.asarray(samples[f"{p.name}.{c}"], dtype=np.float64) for c in "xyz"]
        val = np.stack(cols, axis=1)
        if p.dist is not None:
            val = base + f * val
        if p.type == "direction":
            val = val / np.linalg.norm(val, axis=1)[:, None]
        return val
    base_s = (p.value if isinstance(p.value, float) else 0.0) * f
    if p.name not in samples:
        return np.full(1, base_s)
    if p.dist is not None:
        return base_s + f * np.asarray(samples[p.name])
    return np.asarray(samples[p.name])


def unflatten(type_: str, flat: NDArray[np.float64]) -> Any:
    """A place value from its components, the inverse of :func:`flatten`.

    Parameters
    ----------
    type_ : str
        The place type.
    flat : ndarray, shape (M,) or (M, k)
        The components in the layout of :data:`PARTS`.

    Returns
    -------
    ndarray or primitive
        ``(M,)`` for scalars, ``(M, 3)`` for points, vectors and directions, a
        Line/Plane/Circle/Sphere, or ``(M, 4, 4)`` frames.
    """
    x = np.asarray(flat, dtype=np.float64)
    x = x.reshape(x.shape[0], -1)
    if type_ in SCALAR_TYPES:
        return x[:, 0].copy()
    if type_ in VECTOR_TYPES:
        return x.copy()
    if type_ == "line":
        return Line(x[:, 0:3], x[:, 3:6])
    if type_ == "plane":
        return Plane(x[:, 0:3], x[:, 3:6])
    if type_ == "circle":
        return Circle(x[:, 0:3], x[:, 3:6], x[:, 6])
    if type_ == "sphere":
        return Sphere(x[:, 0:3], x[:, 3])
    if type_ == "frame":
        t = np.zeros((x.shape[0], 4, 4))
        t[:, :3, :3] = x[:, :9].reshape(-1, 3, 3)
        t[:, :3, 3] = x[:, 9:12]
        t[:, 3, 3] = 1.0
        return t
    raise InputError(f"unknown place type {type_!r}", field="type")  # pragma: no cover


def normal_plane_parts(
    type_: str, flat: NDArray[np.float64]
) -> tuple[tuple[str, NDArray[np.float64]], ...]:
    """The parts of a direction, line or circle in the plane normal to its mean axis.

    The coverage regions of such a place (JCGM 102 §7.7) are ellipses in the plane
    normal to the mean of its direction ``d̄`` (its normal for a circle), with the basis
    ``(e1, e2)`` of :func:`~mtmc.geometry.constructions.normal_plane_basis`: the point
    (centre) of a line (circle) as ``(p·e1, p·e2)``, where it crosses that plane up to
    its along-axis part, and the direction (normal) as ``(d·e1, d·e2)``, its tilt in rad
    to first order. A direction has its tilt only.

    Parameters
    ----------
    type_ : str
        The place type; other types have no such parts.
    flat : ndarray, shape (m, k)
        Values in the layout of :data:`PARTS` (:func:`flatten`).

    Returns
    -------
    tuple of (str, ndarray of shape (m, 2))
        ``(part, values)``: ``("point", …), ("direction", …)`` of a line,
        ``("centre", …), ("normal", …)`` of a circle, ``(("value", …),)`` of a
        direction, ``()`` for any other type.
    """
    v = np.asarray(flat, dtype=np.float64)
    if type_ == "direction":
        return (("value", v[:, 0:3] @ normal_plane_basis(v[:, 0:3].mean(axis=0))),)
    if type_ not in ("line", "circle"):
        return ()
    (first, _), (second, _) = PARTS[type_][:2]
    basis = normal_plane_basis(v[:, 3:6].mean(axis=0))
    return ((first, v[:, 0:3] @ basis), (second, v[:, 3:6] @ basis))
