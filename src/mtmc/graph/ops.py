"""The transition ops of the measurement graph and their variants, bound by input types.

Stryczek names the transitions ``meas``, ``point``, ``line``, ``aline``, ``vector``,
``unit_v``, ``circle``, ``middle``, ``plane``, ``frame``, ``displace``, ``ratio``,
``project``, ``per_proj``: "a transition variant binding in a given node results from
the context in which it is placed in the model", i.e. from the types of its input
places. Here each op has one or more :class:`Variant`, each with the input types it
accepts and the output type it produces; :func:`bind` picks the variant matching the
types of a transition's inputs, or raises naming what the op accepts.

Every op function works on a whole batch: scalars ``(M,)``, points/vectors ``(M, 3)``,
lines/planes/circles/spheres as :mod:`mtmc.geometry` primitives, frames ``(M, 4, 4)``;
a constant input may be a batch of one and broadcasts. All geometry is done by
:mod:`mtmc.geometry`; this module only adds the rotary-axis construction of Stryczek
(eqs. 8-19), which has no counterpart there.

New ops register with :func:`register` (or the :func:`variant` decorator), which refuses
a second variant with the same name and input types.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import GraphError
from mtmc.geometry import constructions as gc
from mtmc.geometry import fits
from mtmc.geometry.checks import (
    RTOL,
    batch_size,
    broadcast_batch,
    check_points,
    check_scalars,
    degenerate,
)
from mtmc.geometry.primitives import Circle, Line, Plane, Sphere, squared_rows, unit_rows
from mtmc.geometry.vec import cross as _cross
from mtmc.graph.places import SCALAR_TYPES

__all__ = [
    "Variant",
    "register",
    "variant",
    "variants",
    "op_names",
    "bind",
    "rotary_axis",
    "OP_PARAMS",
    "PART_OF_INPUT",
]

#: Fields (besides ``name``, ``op``, ``in``, ``out``) each op accepts in a graph file.
OP_PARAMS: Mapping[str, tuple[str, ...]] = MappingProxyType(
    {"meas": ("at", "direction", "u_axis", "u_probe", "u_perp", "dist", "coordinate")}
)


@dataclass(frozen=True)
class Variant:
    """One variant of an op: the input types it accepts and the output type it makes.

    Parameters
    ----------
    op : str
        The op name.
    inputs : tuple of str
        Types of the leading inputs, in order.
    output : str
        Type of the output place.
    func : callable
        ``func(*values) -> value``, batched.
    rest : str, optional
        Type of a variable number of further inputs (``"point"`` for "four or more points").
    min_rest : int
        Least number of ``rest`` inputs.
    suffix : tuple of str
        Types of inputs after the ``rest`` ones (the radius of a known-radius sphere).
    doc : str
        One line saying what the variant computes.
    """

    op: str
    inputs: tuple[str, ...]
    output: str
    func: Callable[..., Any]
    rest: str | None = None
    min_rest: int = 0
    suffix: tuple[str, ...] = ()
    doc: str = ""

    def accepts(self, types: Sequence[str]) -> bool:
        """Whether this variant accepts inputs of ``types`` (in order)."""
        n_fixed = len(self.inputs) + len(self.suffix)
        if self.rest is None:
            return tuple(types) == self.inputs
        if len(types) < n_fixed + self.min_rest:
            return False
        head = tuple(types[: len(self.inputs)])
        tail = tuple(types[len(types) - len(self.suffix) :]) if self.suffix else ()
        middle = types[len(self.inputs) : len(types) - len(self.suffix)]
        return head == self.inputs and tail == self.suffix and all(t == self.rest for t in middle)

    def accepts_prefix(self, types: Sequence[str]) -> bool:
        """Whether some input list this variant accepts starts with ``types``.

        The test of an input added one at a time (an arc drawn in ``mtmc graph edit``):
        ``types`` may still grow into a list that :meth:`accepts`.
        """
        types = list(types)
        fixed = list(self.inputs)
        if len(types) <= len(fixed):
            return types == fixed[: len(types)]
        if types[: len(fixed)] != fixed or self.rest is None:
            return False
        tail = types[len(fixed) :]
        suffix = list(self.suffix)
        # the rest inputs, then possibly the start of the suffix (after min_rest of them)
        for cut in range(len(tail) + 1):
            head, end = tail[:cut], tail[cut:]
            if end and cut < self.min_rest:
                continue
            if all(t == self.rest for t in head) and end == suffix[: len(end)]:
                return True
        return False

    @property
    def max_inputs(self) -> float:
        """The most inputs this variant takes (``inf`` with ``rest`` inputs)."""
        return math.inf if self.rest is not None else len(self.inputs) + len(self.suffix)

    @property
    def signature(self) -> str:
        """The accepted input types in words, e.g. ``(point, point, point)``."""
        parts = list(self.inputs)
        if self.rest is not None:
            parts.append(f"{self.min_rest} or more {self.rest}")
        parts.extend(self.suffix)
        return "(" + ", ".join(parts) + ")"

    @property
    def key(self) -> tuple[Any, ...]:
        """What makes two variants of one op the same (refused by :func:`register`)."""
        return (self.op, self.inputs, self.rest, self.min_rest, self.suffix, self.output)


_REGISTRY: dict[str, list[Variant]] = {}


def register(v: Variant) -> Variant:
    """Add a variant to the registry.

    Parameters
    ----------
    v : Variant
        The variant.

    Returns
    -------
    Variant
        ``v``.

    Raises
    ------
    GraphError
        If a variant of the same op with the same input types is registered already.
    """
    for other in _REGISTRY.get(v.op, []):
        if other.key == v.key:
            raise GraphError(
                f"op {v.op} already has a variant for inputs {v.signature} -> {v.output}",
                field=v.op,
            )
    _REGISTRY.setdefault(v.op, []).append(v)
    return v


def variant(
    op: str,
    inputs: tuple[str, ...],
    output: str,
    *,
    rest: str | None = None,
    min_rest: int = 0,
    suffix: tuple[str, ...] = (),
    doc: str = "",
) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Register the decorated function as a variant of ``op`` (see :class:`Variant`).

    Parameters
    ----------
    op, inputs, output, rest, min_rest, suffix, doc
        As in :class:`Variant`.

    Returns
    -------
    callable
        A decorator returning the function unchanged.
    """

    def deco(func: Callable[..., Any]) -> Callable[..., Any]:
        register(
            Variant(
                op,
                inputs,
                output,
                func,
                rest,
                min_rest,
                suffix,
                doc or (func.__doc__ or "").strip().split("\n")[0],
            )
        )
        return func

    return deco


def variants(op: str) -> tuple[Variant, ...]:
    """The registered variants of ``op`` (empty for an unknown op)."""
    return tuple(_REGISTRY.get(op, ()))


def op_names() -> tuple[str, ...]:
    """The names of all registered ops, sorted."""
    return tuple(sorted(_REGISTRY))


def bind(op: str, types: Sequence[str], *, output: str | None = None) -> Variant:
    """Bind the variant of ``op`` accepting inputs of ``types``.

    Parameters
    ----------
    op : str
        The op name.
    types : sequence of str
        Types of the input places, in order.
    output : str, optional
        The declared type of the output place; when given, only a variant producing it
        binds (``meas`` has one variant per output type).

    Returns
    -------
    Variant
        The bound variant.

    Raises
    ------
    GraphError
        If the op is unknown, or no variant accepts ``types`` (the message lists the
        accepted signatures).
    """
    if op not in _REGISTRY:
        raise GraphError(f"unknown op {op!r}; expected one of {', '.join(op_names())}", field="op")
    cands = [v for v in _REGISTRY[op] if v.accepts(types)]
    if not cands:
        sigs = "; ".join(sorted({v.signature for v in _REGISTRY[op]}))
        got = "(" + ", ".join(types) + ")"
        raise GraphError(f"op {op} accepts no inputs of types {got}; it accepts {sigs}", field="in")
    if output is not None:
        same = [v for v in cands if v.output == output]
        if not same:
            outs = ", ".join(sorted({v.output for v in cands}))
            raise GraphError(
                f"op {op} on inputs ({', '.join(types)}) makes {outs}, "
                f"but the output place is declared {output}",
                field="out",
            )
        return same[0]
    return cands[0]


# --------------------------------------------------------------------------------------
# meas: values come from the probe model (mtmc.graph.probe); registered here for binding.


def _meas_placeholder(*_: Any) -> Any:  # pragma: no cover - meas is evaluated by probe
    raise RuntimeError("meas is evaluated by mtmc.graph.probe")


for _t in ("point", "x", "y", "z"):
    register(Variant("meas", (), _t, _meas_placeholder, doc=f"touch-probe measurement -> {_t}"))

# --------------------------------------------------------------------------------------
# point


@variant("point", ("x", "y", "z"), "point")
def _point_xyz(x: NDArray[np.float64], y: NDArray[np.float64], z: NDArray[np.float64]) -> Any:
    """The point of three coordinates."""
    m = max(np.size(x), np.size(y), np.size(z))
    out = np.empty((m, 3))
    out[:, 0], out[:, 1], out[:, 2] = x, y, z
    return out


@variant("point", ("line", "plane"), "point")
def _point_line_plane(line: Line, plane: Plane) -> Any:
    """The intersection of a line and a plane."""
    return gc.intersect_line_plane(line, plane)


@variant("point", ("plane", "line"), "point")
def _point_plane_line(plane: Plane, line: Line) -> Any:
    """The intersection of a plane and a line."""
    return gc.intersect_line_plane(line, plane)


@variant("point", ("circle",), "point")
def _point_circle(c: Circle) -> Any:
    """The centre of a circle."""
    return c.centre


@variant("point", ("line",), "point")
def _point_line(line: Line) -> Any:
    """The attachment point of a line (the circle centre of an ``axis``)."""
    return line.point


@variant("point", ("sphere",), "point")
def _point_sphere(s: Sphere) -> Any:
    """The centre of a sphere."""
    return s.centre


# --------------------------------------------------------------------------------------
# middle, vector, unit_v, displace, ratio


def _scalar_middle(a: Any, b: Any) -> Any:
    out = np.add(a, b)
    out *= 0.5
    return out


for _t in SCALAR_TYPES:
    register(Variant("middle", (_t, _t), _t, _scalar_middle, doc=f"the mean of two {_t}"))


@variant("middle", ("point", "point"), "point")
def _middle_points(a: Any, b: Any) -> Any:
    """The middle of two points."""
    return gc.middle(a, b)


@variant("vector", ("point", "point"), "vector")
def _vector(a: Any, b: Any) -> Any:
    """The vector b - a."""
    return gc.vector(a, b)


@variant("unit_v", ("vector",), "direction")
def _unit_v(v: Any) -> Any:
    """The unit vector of a vector."""
    return gc.unit_vector(v)


@variant("unit_v", ("line",), "direction")
def _unit_line(line: Line) -> Any:
    """The direction of a line (of an ``axis``: V_A, V_C of Stryczek, Fig. 13)."""
    return line.direction


@variant("unit_v", ("plane",), "direction")
def _unit_plane(plane: Plane) -> Any:
    """The normal of a plane."""
    return plane.normal


@variant("displace", ("point", "vector"), "point")
def _displace_pv(p: Any, v: Any) -> Any:
    """The point displaced by a vector, p + v."""
    return gc.displace(p, v)


@variant("displace", ("point", "direction", "real"), "point")
def _displace_pur(p: Any, d: Any, r: Any) -> Any:
    """The point displaced by r along a unit vector, p + r d."""
    v = np.multiply(np.atleast_1d(r)[:, None], d)  # d is a direction place: no rescaling
    pp = np.asarray(p)
    if pp.dtype == np.float64 and pp.shape == v.shape and v.ndim == 2 and v.shape[1] == 3:
        v += pp  # = p + v, in place
        return v
    return gc.displace(pp, v)


def _scalar_sum(a: Any, b: Any) -> Any:
    return np.asarray(a) + np.asarray(b)


for _t in SCALAR_TYPES:
    register(Variant("displace", (_t, "real"), _t, _scalar_sum, doc=f"the {_t} plus a real"))


@variant("ratio", ("vector", "real"), "vector")
def _ratio_vr(v: Any, r: Any) -> Any:
    """The vector times a real."""
    return np.asarray(v) * np.atleast_1d(r)[:, None]


@variant("ratio", ("real", "real"), "real")
def _ratio_rr(a: Any, b: Any) -> Any:
    """The product of two reals."""
    return np.asarray(a) * np.asarray(b)


# --------------------------------------------------------------------------------------
# distance, angle


@variant("distance", ("point", "point"), "real")
def _dist_pp(a: Any, b: Any) -> Any:
    """The distance between two points."""
    return gc.distance_point_point(a, b)


@variant("distance", ("point", "line"), "real")
def _dist_pl(p: Any, line: Line) -> Any:
    """The distance of a point from a line."""
    return gc.distance_point_line(p, line)


@variant("distance", ("point", "plane"), "real")
def _dist_ppl(p: Any, plane: Plane) -> Any:
    """The signed distance of a point from a plane (along its normal)."""
    return gc.distance_point_plane(p, plane)


def _angle(u: Any, v: Any) -> Any:
    return gc.angle_between(u, v)


for _a in ("vector", "direction"):
    for _b in ("vector", "direction"):
        register(
            Variant("angle", (_a, _b), "real", _angle, doc="the angle between two directions, rad")
        )

# --------------------------------------------------------------------------------------
# line, aline, plane, circle, sphere, project, per_proj, frame


@variant("line", ("point", "point"), "line")
def _line_pp(a: Any, b: Any) -> Any:
    """The line through two points, directed from the first to the second."""
    return gc.line_from_points(a, b)


@variant("line", ("plane", "plane"), "line")
def _line_planes(p1: Plane, p2: Plane) -> Any:
    """The intersection line of two planes."""
    return gc.line_from_planes(p1, p2)


@variant("line", ("point", "direction"), "line")
def _line_pu(p: Any, d: Any) -> Any:
    """The line through a point along a unit vector."""
    return gc.line_from_point_direction(p, d)


@variant("aline", ("point", "direction"), "line")
def _aline(p: Any, d: Any) -> Any:
    """The line through a point along a unit vector (an axis)."""
    return gc.line_from_point_direction(p, d)


@variant("plane", ("point", "point", "point"), "plane")
def _plane_3(a: Any, b: Any, c: Any) -> Any:
    """The plane through three points, normal (b - a) x (c - a) (Stryczek eqs. 20-29)."""
    return gc.plane_from_points(a, b, c)


@variant("plane", ("point", "direction"), "plane")
def _plane_pn(p: Any, n: Any) -> Any:
    """The plane through a point with a unit normal."""
    return gc.plane_from_point_normal(p, n)


def _stack(points: Sequence[Any]) -> NDArray[np.float64]:
    arrs = np.broadcast_arrays(*[np.atleast_2d(np.asarray(p, dtype=np.float64)) for p in points])
    return np.stack(arrs, axis=1)


@variant("plane", (), "plane", rest="point", min_rest=4)
def _plane_lsq(*points: Any) -> Any:
    """The least-squares (orthogonal distance) plane of four or more points."""
    return fits.fit_plane(_stack(points)).geometry


@variant("circle", ("point", "point", "point"), "circle")
def _circle_3(a: Any, b: Any, c: Any) -> Any:
    """The circle through three points."""
    return gc.circle_from_points(a, b, c)


@variant("circle", (), "circle", rest="point", min_rest=4)
def _circle_lsq(*points: Any) -> Any:
    """The least-squares circle (in its least-squares plane) of four or more points."""
    return fits.fit_circle(_stack(points)).geometry


@variant("sphere", (), "sphere", rest="point", min_rest=4)
def _sphere_lsq(*points: Any) -> Any:
    """The least-squares sphere of four or more points."""
    return fits.fit_sphere(_stack(points)).geometry


@variant("sphere", (), "sphere", rest="point", min_rest=4, suffix=("real",))
def _sphere_known(*args: Any) -> Any:
    """The least-squares sphere of known radius (the last input) through four or more points."""
    *points, r = args
    return fits.fit_sphere(_stack(points), radius=np.atleast_1d(r)).geometry


@variant("project", ("point", "plane"), "point")
def _project(p: Any, plane: Plane) -> Any:
    """The orthogonal projection of a point on a plane."""
    return gc.project_point_plane(p, plane)


@variant("per_proj", ("point", "line"), "point")
def _per_proj(p: Any, line: Line) -> Any:
    """The foot of the perpendicular from a point to a line."""
    return gc.foot_on_line(p, line)


@variant("frame", ("plane", "line", "point"), "frame")
def _frame(plane: Plane, line: Line, p: Any) -> Any:
    """The frame of a plane (z), a line (x) and a point (origin)."""
    return gc.frame_from_plane_line_point(plane, line, p)


# --------------------------------------------------------------------------------------
# axis: Stryczek eqs. 8-19


def _sq(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """``|v|² = (x² + y²) + z²`` column by column of a ``(3, M)`` array of coordinate rows."""
    return squared_rows(v, (0, 1, 2))


def _cross_rows(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a × b`` of ``(3, M)`` arrays of coordinate rows (contiguous rows: no strides)."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    np.multiply(a[1], b[2], out=out[0])
    out[0] -= a[2] * b[1]
    np.multiply(a[2], b[0], out=out[1])
    out[1] -= a[0] * b[2]
    np.multiply(a[0], b[1], out=out[2])
    out[2] -= a[1] * b[0]
    return out


def rotary_axis(
    p1: npt.ArrayLike,
    p2: npt.ArrayLike,
    p3: npt.ArrayLike,
    alpha: npt.ArrayLike | None = None,
) -> Line:
    r"""Locate a rotary axis from three positions of a ball centre (Stryczek eqs. 8-27).

    A ball fixed on the rotary table is measured at the axis angles 0, +α and −α; its
    centres ``P1`` (at 0), ``P2`` (at +α) and ``P3`` (at −α) lie on a circle of radius
    ``R`` about the axis, in a plane normal to it. The axis is the line through that
    circle's centre ``P0`` along its normal.

    Direction (Stryczek eqs. 20-27): the unit normal of the plane of the three points,

    .. math:: \mathbf a = \frac{(P_2 - P_1)\times(P_3 - P_1)}{|(P_2 - P_1)\times(P_3 - P_1)|},

    which points along the axis about which ``P1`` turns into ``P2`` by +α (right-hand
    rule), i.e. ``P3 → P1 → P2`` in the order of increasing angle. Stryczek prints the
    y-component of the cross product (his eq. 22) as ``a_x b_z − b_x a_z``; the cofactor
    of his determinant (20) is ``a_z b_x − a_x b_z``, which is what is computed.

    Location with α given (Stryczek eqs. 8-19). With ``u`` the unit vector from ``P0``
    to ``P1``, the positions are ``P1 = P0 + R u`` and ``P2, P3 = P0 + R (cos α u ±
    sin α w)`` (``w`` in the plane, normal to ``u``), so

    - ``P4 = (P2 + P3)/2 = P0 + R cos α u`` (eqs. 8-10): on the radius through ``P1``;
    - ``|P3 P4| = |P3 − P2|/2 = R |sin α|`` (eq. 11, which prints only this right-hand
      side), hence ``R = |P3 P4| / |sin α|`` (eq. 12, where Stryczek writes ``sin α``
      for his 0 < α < π);
    - ``P4 − P1 = −R (1 − cos α) u``: the unit vector ``v = (P4 − P1)/|P1 P4|`` (eqs.
      13-16) is ``−u`` for every α that is not a multiple of 2π (also for α > π/2, where
      ``P4`` lies beyond ``P0``). Stryczek prints eq. 14 as ``I0 = (X4 − X3)/|P1 P4|``;
      by eqs. 15-16 and this construction it is ``(X4 − X1)/|P1 P4|``;
    - ``P0 = P1 + R v`` (eqs. 17-19).

    Only ``|sin α|`` enters, so α, −α, π − α and α + 2kπ give the same point: the
    method takes ``R`` from the chord and the angle, and ``|P1 P4|`` only through the
    unit vector ``v``. ``P0`` lies in the plane of the three points.

    Location without α: the centre of the circle through the three points
    (:func:`mtmc.geometry.circle_from_points`), which needs no assumption on the angles.
    With exact data both give the same axis; with noisy data the first uses the known
    angle and the symmetric placement, as Stryczek does, and the two differ by an amount
    of the order of the noise.

    Parameters
    ----------
    p1, p2, p3 : array_like, shape (M, 3) or (3,)
        Ball centres at the angles 0, +α and −α, mm. A batch of one broadcasts.
    alpha : array_like, shape (M,) or (), optional
        The angle α, rad; not a multiple of π (Stryczek: 0 < α < π).

    Returns
    -------
    Line
        The axis, a batch of ``M``: ``point`` the circle centre ``P0``, shape ``(M, 3)``,
        mm; ``direction`` the unit vector ``a``, shape ``(M, 3)``.

    Raises
    ------
    InputError
        If a point is not of shape ``(M, 3)`` or ``(3,)``, ``alpha`` not of shape ``(M,)``
        or ``()``, or the batch sizes differ (other than 1 against ``M``).
    DegenerateGeometryError
        With the relative tolerance :data:`mtmc.geometry.checks.RTOL` (``1e-10``): if the
        three points are collinear (``|(P2 − P1) × (P3 − P1)| <= RTOL |P2 − P1| |P3 − P1|``,
        field ``axis``), ``P1`` coincides with ``P4`` (``|P4 − P1| <= RTOL max(|P2 − P1|,
        |P3 − P1|)``, field ``axis``), or ``|sin α| <= RTOL`` (α a multiple of π, field
        ``alpha``). The message says in how many trials and the first one. NaN
        coordinates or angles are not refused: they propagate to the axis of their trial
        (as in :mod:`mtmc.geometry`), so that a run with ``nan_policy="omit"`` can drop it.

    Notes
    -----
    Sign of the direction on a machine. ISO 841 commands the motion of the tool relative
    to the workpiece: a rotary table (an axis that carries the workpiece) commanded to
    +α turns the ball by −α about the +C axis. Centres measured at the commanded
    0, +α, −α then give ``direction = −e_C``; the line, and ``P0``, are the same.

    ISO 230-7 location errors. For an axis C of nominal direction +z through the point
    ``o`` (:class:`mtmc.kinematics.Machine`, ``L = T(EX0C, EY0C, 0) R(EA0C, EB0C)``), with
    ``a`` oriented along +z: the line meets the plane ``z = o_z`` at
    ``(o_x + EX0C, o_y + EY0C, o_z)``, and, with exact rotations, ``a = Ry(EB0C) Rx(EA0C)
    e_z = (sin EB0C cos EA0C, −sin EA0C, cos EB0C cos EA0C)``; to first order (and with
    the default small-angle rotations) ``EA0C = −a_y`` and ``EB0C = a_x`` (rad,
    right-hand rule about x and y).

    First-order sensitivities of the variant with α, at the exact configuration, in the
    frame of the circle (x along ``u``, z along ``a``, ``c = cos α``, ``s = sin α``,
    ``δ`` a deviation of a coordinate):

    .. math::
        \delta P_{0x} &= \delta x_1 - (\delta y_2 - \delta y_3) / (2 s), \\
        \delta P_{0y} &= \delta y_1 + ((\delta y_2 + \delta y_3)/2 - \delta y_1) / (1 - c), \\
        \delta P_{0z} &= \delta z_1 + ((\delta z_2 + \delta z_3)/2 - \delta z_1) / (1 - c), \\
        \delta a_x &= -(\delta z_1 - (\delta z_2 + \delta z_3)/2) / (R (1 - c)), \qquad
        \delta a_y = -(\delta z_2 - \delta z_3) / (2 R s).

    A deviation of ``P4 − P1`` normal to ``u`` moves ``P0`` ``1/(1 − c)`` times as far:
    2 times at α = 60°, 7.5 times at α = 30°. (A test compares these with central
    differences and with the sensitivities of :func:`mtmc.uncertainty.gum`.)

    Examples
    --------
    >>> import numpy as np
    >>> a = np.pi / 4
    >>> p = [[10, 0, 5], [10 * np.cos(a), 10 * np.sin(a), 5], [10 * np.cos(a), -10 * np.sin(a), 5]]
    >>> ax = rotary_axis(*p, alpha=a)
    >>> np.round(ax.point, 12) + 0.0, np.round(ax.direction, 12) + 0.0
    (array([[0., 0., 5.]]), array([[0., 0., 1.]]))
    """
    a, b, c = (check_points(v, k) for v, k in ((p1, "p1"), (p2, "p2"), (p3, "p3")))
    al = None if alpha is None else check_scalars(alpha, "alpha")
    m = batch_size(p1=a, p2=b, p3=c, **({} if al is None else {"alpha": al}))
    a, b, c = (broadcast_batch(m, v) for v in (a, b, c))
    if al is None:
        ab, ac = b - a, c - a
        normal = _cross(ab, ac)  # eqs. 20-24; Line() normalises it (eqs. 25-27)
        _check_collinear(_sq(ab.T), _sq(ac.T), _sq(normal.T))
        return Line(gc.circle_from_points(a, b, c).centre, normal)
    # the coordinates as contiguous rows, (3, M): column arithmetic without strides (the
    # first operation on each point reads its columns, so no transposed copy is made)
    ra, rb, rc = a.T, b.T, c.T
    ab, ac = np.subtract(rb, ra, order="C"), np.subtract(rc, ra, order="C")
    n = _cross_rows(ab, ac)  # eqs. 20-24; Line() normalises it (eqs. 25-27)
    sab, sac, sn = _sq(ab), _sq(ac), squared_rows(n)
    _check_collinear(sab, sac, sn)
    s = np.sin(al)
    np.abs(s, out=s)  # |sin(alpha)|: R > 0 whatever the sign of alpha (eq. 12)
    bad = s <= RTOL  # NaN is not caught: it propagates, as in mtmc.geometry
    degenerate(
        bad,
        "sin(alpha) is 0: alpha is a multiple of pi, so P2 and P3 coincide",
        "0 < |alpha| < pi",
        "alpha",
    )
    # P4 - P1 = (P2 + P3)/2 - P1, eqs. 8-10 and 13 (in place: fewer temporaries)
    w = np.add(rb, rc, order="C")
    w *= 0.5
    w -= ra
    half_chord = _sq(np.subtract(rc, rb, order="C"))  # |P3 P4| = |P3 - P2| / 2, eq. 11
    np.sqrt(half_chord, out=half_chord)
    half_chord *= 0.5
    length = _sq(w)  # |P1 P4|, eq. 13
    np.sqrt(length, out=length)
    np.maximum(sab, sac, out=sab)
    sab *= RTOL**2
    bad = length * length <= sab
    degenerate(
        bad,
        "P1 coincides with P4, the middle of P2 and P3",
        "P1 away from the chord P2 P3",
        "axis",
    )
    # eq. 12: R = |P3 P4| / |sin(alpha)|; eqs. 14-19: P0 = P1 + R (P4 - P1) / |P1 P4|
    length *= s
    half_chord /= length
    w *= half_chord
    w += ra
    unit_rows(n, "direction", "line direction", sn)  # eqs. 25-27, as Line() normalises
    # back to (M, 3) rows, C-ordered like any other batch (the same bits as one at a time)
    return Line.of_unit(_columns(w), _columns(n))


def _columns(rows: NDArray[np.float64]) -> NDArray[np.float64]:
    """The ``(3, M)`` coordinate rows as a new C-ordered ``(M, 3)`` array (column by column)."""
    out = np.empty((rows.shape[1], 3))
    out[:, 0], out[:, 1], out[:, 2] = rows
    return out


def _check_collinear(
    sab: NDArray[np.float64], sac: NDArray[np.float64], sn: NDArray[np.float64]
) -> None:
    """Refuse collinear ball centres: ``|n|² <= RTOL² |P2 - P1|² |P3 - P1|²``."""
    bound = RTOL**2 * sab
    bound *= sac
    bad = sn <= bound  # NaN is not caught: it propagates, as in mtmc.geometry
    degenerate(
        bad,
        "the three ball centres are collinear",
        "three ball centres on a circle",
        "axis",
    )


@variant("axis", ("point", "point", "point"), "line")
def _axis3(a: Any, b: Any, c: Any) -> Any:
    """The rotary axis through the circle of three ball centres."""
    return rotary_axis(a, b, c)


@variant("axis", ("point", "point", "point", "real"), "line")
def _axis4(a: Any, b: Any, c: Any, alpha: Any) -> Any:
    """The rotary axis from ball centres at 0, +alpha, -alpha (Stryczek eqs. 8-19)."""
    return rotary_axis(a, b, c, alpha)


#: Variants whose value is a part of their one input's value, the very array the input
#: holds (by the part's name in :data:`mtmc.graph.run.PARTS`): a run that summarises
#: both places reads the summary of such a place from its input's.
PART_OF_INPUT: Mapping[Callable[..., Any], str] = MappingProxyType(
    {
        _point_line: "point",
        _point_circle: "centre",
        _point_sphere: "centre",
        _unit_line: "direction",
        _unit_plane: "normal",
    }
)
