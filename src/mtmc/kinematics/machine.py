"""Forward kinematics of a machine tool with ISO 230 geometric errors, batched.

The model
---------
The pose of the tool relative to the workpiece is a product of homogeneous transforms
read along the chain from the workpiece to the tool (``docs/conventions.md``)::

    W_T_tool = S_P^-1 . A_1(q_1) . A_2(q_2) ... A_n(q_n) . S_T

- ``S_P = T(w + d_P) R(e_P)``: the workpiece on its carrier (offset ``w``, setup errors
  ``EXP EYP EZP`` / ``EAP EBP ECP``), so ``S_P^-1 = R(e_P)^T T(-(w + d_P))``.
- Each axis contributes ``A_k``, the *relative* motion of the next body (towards the
  tool) seen from the previous one (towards the workpiece), always with the nominal
  motion ``+q`` (ISO 841: a command is the motion of the tool relative to the
  workpiece). A physical part-side axis moves its carriage by ``-q``; ``A_k`` is the
  inverse of that motion, so both sides share one formula. With ``o`` the axis's pivot
  (reference point) in the previous body's frame:

  - linear K (direction ``e``): ``A = T(o) T(q R(s) e) T(d) R(eps) T(-o)``, with
    ``d = (EXK, EYK, EZK)(q)``, ``eps = (EAK, EBK, ECK)(q)`` and ``s`` the squareness
    angles of K (``EC0Y`` etc.);
  - rotary K (about ``e``): ``A = T(o) L T(d) R(eps) Rot_e(q) L^-1 T(-o)``, with the
    location ``L = T(d0) R(eps0)`` (``EX0C EY0C``, ``EA0C EB0C``), ``L^-1 = R(eps0)^T
    T(-d0)``, and the component error motions ``d = (EXC, EYC, EZC)(q)``,
    ``eps = (EAC, EBC, ECC)(q)`` expressed in the non-rotating frame.
- ``S_T = T(t + d_T) R(e_T)``: the tool point ``t`` on the last tool-side body, with
  ``EXT EYT EZT`` / ``EAT EBT ECT``.

``R(a, b, c)`` is the small-angle matrix ``I + [e]x`` of Aguado et al. 2016, eq. (12) (transposed,
see :func:`mtmc.geometry.transforms.small_angle_rotation`) by default, or with ``exact=True``
the rotation ``Rz(c) Ry(b) Rx(a)``. Every error is a motion of the tool relative to the
workpiece, so with zero errors and offsets and the rotary axes at zero the tool point is
at the commanded linear coordinates whichever of part or tool an axis moves.

Implementation: the chain is applied to the tool point (and, for the pose, to three
directions) from the tool to the workpiece, never as a product of ``(M, 4, 4)`` matrices
and never with a loop over trials. :meth:`Machine.tool_position`, :meth:`Machine.pose` and
:meth:`Machine.tool_direction` lower the factors once per call into a short program on
coordinate rows (:mod:`mtmc.kinematics._columns`): constant factors multiplied out into
one affine map, the error functions of an axis evaluated together, internal blocks of a
few thousand poses with reused buffers. :meth:`Machine.jacobian` applies the factors one
by one on ``(M, k, 3)`` arrays. Factors whose errors are all absent are skipped.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import InputError
from mtmc.frozen import frozen_mapping
from mtmc.geometry.transforms import rotate_about_axis, small_angle_rotate
from mtmc.kinematics import _columns as _cols
from mtmc.kinematics.error_terms import (
    ErrorTerm,
    _check_term_for,
    list_error_terms,
    parse_error_name,
)
from mtmc.kinematics.functions import ErrorFunction
from mtmc.kinematics.topology import AXIS_DIRECTION, Topology, is_linear, parse_topology

__all__ = ["Machine"]

_DIRS = "XYZ"
_ROTS = "ABC"
_F = NDArray[np.float64]
Values = dict[str, Any]


# ----------------------------------------------------------------------------------------
# element-wise vector helpers on arrays (..., 3)


def _col(v: Any) -> Any:
    """A value () or (M,) as something that broadcasts against (M, K)."""
    a = np.asarray(v, dtype=np.float64)
    return a[..., None] if a.ndim else a


def _cross_axis(j: int, y: _F) -> _F:
    """``e_j x y`` for y (..., 3)."""
    out = np.zeros_like(y)
    i, k = (j + 1) % 3, (j + 2) % 3
    out[..., i] = -y[..., k]
    out[..., k] = y[..., i]
    return out


# ----------------------------------------------------------------------------------------
# factors of the chain


class _Factor:
    """One elementary transform of the chain; applied to points and directions."""

    names: tuple[str, ...] = ()
    #: Whether the factor turns directions (its linear part is not the identity).
    turns: bool = True

    def active(self, vals: Values) -> bool:
        return True

    def apply(self, y: _F, is_point: _F, vals: Values, q: _F, exact: bool) -> _F:
        raise NotImplementedError

    def partials(self, y: _F, vals: Values, q: _F, exact: bool) -> list[tuple[str, _F]]:
        return []

    def lower(self, present: Mapping[str, Any], exact: bool) -> list[_cols.Op]:
        """The operations (:mod:`mtmc.kinematics._columns`) of this factor.

        Only the errors in ``present`` appear; ``exact`` selects the rotations.
        """
        raise NotImplementedError


def _rotation_ops(
    names: Sequence[str], present: Mapping[str, Any], exact: bool, transpose: bool
) -> list[_cols.Op]:
    """``R(a, b, c)`` (or its transpose) of the present named angles, as operations."""
    if not any(n in present for n in names):
        return []
    if not exact:
        a, b, c = (n if n in present else None for n in names)
        return [_cols.SmallRotation((a, b, c), -1.0 if transpose else 1.0)]
    order, sign = ((2, 1, 0), -1.0) if transpose else ((0, 1, 2), 1.0)
    return [_cols.AxisRotation(j, names[j], sign) for j in order if names[j] in present]


class _Translate(_Factor):
    """``y + sign * (const + (v_x, v_y, v_z))`` on points; v named errors."""

    turns = False

    def __init__(self, const: _F | None, names: tuple[str | None, ...], sign: float) -> None:
        self.const = None if const is None or not np.any(const) else const
        self.slot = names
        self.names = tuple(n for n in names if n is not None)
        self.sign = sign

    def active(self, vals: Values) -> bool:
        return self.const is not None or any(n in vals for n in self.names)

    def apply(self, y: _F, is_point: _F, vals: Values, q: _F, exact: bool) -> _F:
        comps: list[Any] = []
        for j in range(3):
            n = self.slot[j]
            v: Any = 0.0 if self.const is None else self.const[j]
            if n is not None and n in vals:
                v = v + _col(vals[n])
            comps.append(np.broadcast_to(v, np.shape(v)))
        shape = np.broadcast_shapes(*(np.shape(c) for c in comps))
        t = np.empty((*shape, 3))
        for j in range(3):
            t[..., j] = comps[j]
        return y + self.sign * t * is_point[:, None]

    def lower(self, present: Mapping[str, Any], exact: bool) -> list[_cols.Op]:
        ops: list[_cols.Op] = []
        if self.const is not None:
            ops.append(_cols.Affine(np.eye(3), self.sign * self.const))
        terms = tuple(
            ((self.sign, n),) if n is not None and n in present else () for n in self.slot
        )
        if any(terms):
            ops.append(_cols.Translate(terms))
        return ops

    def partials(self, y: _F, vals: Values, q: _F, exact: bool) -> list[tuple[str, _F]]:
        out = []
        for j in range(3):
            n = self.slot[j]
            if n is not None:
                v = np.zeros_like(y)
                v[..., j] = self.sign
                out.append((n, v))
        return out


class _ErrorRotation(_Factor):
    """``R(a, b, c)`` (or its transpose) of three named small angles."""

    def __init__(self, names: tuple[str, str, str], transpose: bool) -> None:
        self.names = names
        self.transpose = transpose

    def active(self, vals: Values) -> bool:
        return any(n in vals for n in self.names)

    def lower(self, present: Mapping[str, Any], exact: bool) -> list[_cols.Op]:
        return _rotation_ops(self.names, present, exact, self.transpose)

    def _angles(self, vals: Values) -> tuple[Any, Any, Any]:
        a, b, c = (_col(vals[n]) if n in vals else 0.0 for n in self.names)
        return a, b, c

    def apply(self, y: _F, is_point: _F, vals: Values, q: _F, exact: bool) -> _F:
        e = self._angles(vals)
        if not exact:
            return small_angle_rotate(*e, y, sign=-1.0 if self.transpose else 1.0)
        if self.transpose:
            for j in (2, 1, 0):
                y = rotate_about_axis(j, -e[j], y)
            return y
        for j in (0, 1, 2):
            y = rotate_about_axis(j, e[j], y)
        return y

    def partials(self, y: _F, vals: Values, q: _F, exact: bool) -> list[tuple[str, _F]]:
        sign = -1.0 if self.transpose else 1.0
        if not exact:
            return [(self.names[j], sign * _cross_axis(j, y)) for j in range(3)]
        e = self._angles(vals)
        out: list[tuple[str, _F]] = []
        order = (2, 1, 0) if self.transpose else (0, 1, 2)
        for j in order:
            # derivative w.r.t. the j-th angle: rotations before j, then G_j, then after
            z = y
            for i in order:
                z = rotate_about_axis(i, sign * e[i], z)
                if i == j:
                    z = sign * _cross_axis(j, z)
            out.append((self.names[j], z))
        return out


class _AxisRotation(_Factor):
    """Nominal rotation of a rotary axis by its position ``q[:, col]``."""

    def __init__(self, direction: int, col: int) -> None:
        self.direction = direction
        self.col = col

    def apply(self, y: _F, is_point: _F, vals: Values, q: _F, exact: bool) -> _F:
        return rotate_about_axis(self.direction, q[:, self.col, None], y)

    def lower(self, present: Mapping[str, Any], exact: bool) -> list[_cols.Op]:
        return [_cols.AxisRotation(self.direction, f"q:{self.col}", 1.0)]


class _LinearMotion(_Factor):
    """Nominal translation ``q R(s) e`` of a linear axis, ``s`` its squareness angles."""

    turns = False

    def __init__(self, direction: int, col: int, squareness: tuple[tuple[str, int], ...]) -> None:
        self.direction = direction
        self.col = col
        self.sq = squareness
        self.names = tuple(n for n, _ in squareness)

    def lower(self, present: Mapping[str, Any], exact: bool) -> list[_cols.Op]:
        names = ["", "", ""]
        for n, j in self.sq:
            names[j] = n
        rot = _rotation_ops(names, present, exact, transpose=False)
        return [_cols.LinearMotion(f"q:{self.col}", self.direction, rot)]

    def _dir(self, vals: Values, exact: bool) -> _F:
        e = np.zeros(3)
        e[self.direction] = 1.0
        ang: list[Any] = [0.0, 0.0, 0.0]
        for n, j in self.sq:
            if n in vals:
                ang[j] = np.asarray(vals[n], dtype=np.float64)
        shape = np.broadcast_shapes(*(np.shape(a) for a in ang))
        d = np.broadcast_to(e, (*shape, 3)).copy()
        if not exact:
            return small_angle_rotate(ang[0], ang[1], ang[2], d)
        for j in (0, 1, 2):
            d = rotate_about_axis(j, ang[j], d)
        return d

    def apply(self, y: _F, is_point: _F, vals: Values, q: _F, exact: bool) -> _F:
        d = self._dir(vals, exact)  # (3,) or (M, 3)
        t = q[:, self.col, None] * d
        return y + t[:, None, :] * is_point[:, None]

    def partials(self, y: _F, vals: Values, q: _F, exact: bool) -> list[tuple[str, _F]]:
        out = []
        qq = q[:, self.col, None]  # (M, 1)
        ang: list[Any] = [0.0, 0.0, 0.0]
        for n, j in self.sq:
            if n in vals:
                ang[j] = np.asarray(vals[n], dtype=np.float64)
        e = np.zeros(3)
        e[self.direction] = 1.0
        for n, j in self.sq:
            if not exact:
                v: _F = _cross_axis(j, e)
            else:
                v = np.broadcast_to(e, (*np.broadcast_shapes(*(np.shape(a) for a in ang)), 3))
                for i in (0, 1, 2):
                    v = rotate_about_axis(i, ang[i], v)
                    if i == j:
                        v = _cross_axis(j, v)
            out.append((n, np.broadcast_to((qq * v)[:, None, :], y.shape).copy()))
        return out


# ----------------------------------------------------------------------------------------


def _vec3(v: npt.ArrayLike, name: str) -> _F:
    a = np.array(v, dtype=np.float64)  # a copy: the caller's array stays theirs, writable
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise InputError(f"expected 3 finite numbers (mm), got {v!r}", field=name)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class Machine:
    """A machine tool: topology, nominal offsets, and the error model around them.

    Parameters
    ----------
    topology : Topology
        The axis chain (see :func:`mtmc.kinematics.parse_topology`).
    tool : ndarray, shape (3,)
        Tool point in the frame of the last tool-side body (or of the frame when no axis
        carries the tool), mm. Default zero.
    workpiece : ndarray, shape (3,)
        Origin of the workpiece frame in the frame of the last part-side body, mm.
    pivots : mapping of str to ndarray (3,)
        Per axis: for a rotary axis, a point of its nominal axis line; for a linear axis,
        the reference point about which its angular errors act. In the frame of the
        previous body in the chain, mm. Default: the origin. Copied on construction into
        a read-only mapping of read-only arrays: the chain compiled from it cannot drift.
    travel : mapping of str to (float, float)
        Optional travel of each axis (mm or rad), used by the library and the drawing;
        copied into a read-only mapping.
    tool_axis : ndarray, shape (3,)
        Direction of the tool axis in the tool frame (default +z).
    name : str
        A label.

    Notes
    -----
    Machines compare by identity (they hold arrays); compare ``topology``, ``tool`` ...
    to compare two configurations.

    Examples
    --------
    >>> m = Machine.from_topology("wCAXfYZt")
    >>> m.axes
    ('X', 'Y', 'Z', 'A', 'C')
    >>> m.tool_position([[10.0, 20.0, 30.0, 0.0, 0.0]])
    array([[10., 20., 30.]])
    """

    topology: Topology
    tool: _F = field(default_factory=lambda: np.zeros(3))
    workpiece: _F = field(default_factory=lambda: np.zeros(3))
    pivots: Mapping[str, _F] = field(default_factory=dict)
    travel: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    tool_axis: _F = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    name: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "tool", _vec3(self.tool, "tool"))
        object.__setattr__(self, "workpiece", _vec3(self.workpiece, "workpiece"))
        object.__setattr__(self, "tool_axis", _vec3(self.tool_axis, "tool_axis"))
        piv = {}
        for ax, p in dict(self.pivots).items():
            if ax not in self.topology.chain:
                raise InputError(
                    f"pivot given for axis {ax!r}, which machine {self.topology} does not have",
                    field="pivots",
                )
            piv[ax] = _vec3(p, f"pivots.{ax}")
        object.__setattr__(self, "pivots", frozen_mapping(piv))
        trav = {}
        for ax, lim in dict(self.travel).items():
            if ax not in self.topology.chain:
                raise InputError(
                    f"travel given for axis {ax!r}, which machine {self.topology} does not have",
                    field="travel",
                )
            lo, hi = (float(v) for v in lim)
            if not hi > lo:
                raise InputError(f"expected low < high, got {lim!r}", field=f"travel.{ax}")
            trav[ax] = (lo, hi)
        object.__setattr__(self, "travel", frozen_mapping(trav))
        object.__setattr__(self, "_factors", self._build())
        terms = list_error_terms(self.topology, which="all")
        object.__setattr__(self, "_terms", {t.name: t for t in terms})

    # -- construction -------------------------------------------------------------------

    @classmethod
    def from_topology(
        cls,
        spec: str | Topology,
        *,
        tool: npt.ArrayLike = (0.0, 0.0, 0.0),
        workpiece: npt.ArrayLike = (0.0, 0.0, 0.0),
        pivots: Mapping[str, npt.ArrayLike] | None = None,
        travel: Mapping[str, tuple[float, float]] | None = None,
        tool_axis: npt.ArrayLike = (0.0, 0.0, 1.0),
        name: str = "",
    ) -> Machine:
        """Build a machine from a topology string.

        Parameters
        ----------
        spec : str or Topology
            ``wCBXfYZt`` (ISO 10791 style) or ``XFYZ`` (Aguado's notation).
        tool, workpiece, pivots, travel, tool_axis, name
            As for :class:`Machine`.

        Returns
        -------
        Machine

        Raises
        ------
        TopologyError
            If ``spec`` does not parse.
        InputError
            On a malformed offset, or a pivot/travel for an axis the machine lacks.
        """
        topo = spec if isinstance(spec, Topology) else parse_topology(spec)
        return cls(
            topology=topo,
            tool=np.asarray(tool, dtype=np.float64),
            workpiece=np.asarray(workpiece, dtype=np.float64),
            pivots={k: np.asarray(v, dtype=np.float64) for k, v in (pivots or {}).items()},
            travel=dict(travel or {}),
            tool_axis=np.asarray(tool_axis, dtype=np.float64),
            name=name,
        )

    @property
    def axes(self) -> tuple[str, ...]:
        """Axis letters in the column order of ``q`` (X Y Z U V W A B C order)."""
        return self.topology.axes

    @property
    def n_axes(self) -> int:
        """Number of axes."""
        return len(self.axes)

    @property
    def error_names(self) -> tuple[str, ...]:
        """The standard (independent) error names, in the order of the Jacobian columns."""
        return tuple(t.name for t in list_error_terms(self.topology, which="standard"))

    @property
    def accepted_error_names(self) -> tuple[str, ...]:
        """Every error name this machine accepts (adds the other squareness references)."""
        return tuple(t.name for t in list_error_terms(self.topology, which="all"))

    def error_term(self, name: str) -> ErrorTerm:
        """The :class:`ErrorTerm` of ``name`` (with or without the leading ``E``).

        Parameters
        ----------
        name : str
            An error name.

        Returns
        -------
        ErrorTerm

        Raises
        ------
        InputError
            If the name is not an ISO 230 name or refers to an axis the machine lacks.
        """
        term = parse_error_name(name)
        _check_term_for(self.topology, term)
        return term

    def _build(self) -> list[_Factor]:
        topo = self.topology
        cols = {ax: i for i, ax in enumerate(topo.axes)}
        fs: list[_Factor] = []
        fs.append(_ErrorRotation(("EAP", "EBP", "ECP"), transpose=True))
        fs.append(_Translate(self.workpiece, ("EXP", "EYP", "EZP"), -1.0))
        for ax in topo.chain:
            d = AXIS_DIRECTION[ax]
            o = self.pivots.get(ax)
            fs.append(_Translate(o, (None, None, None), 1.0))
            comp_t = tuple(f"E{c}{ax}" for c in _DIRS)
            comp_r: tuple[str, str, str] = (f"EA{ax}", f"EB{ax}", f"EC{ax}")
            if is_linear(ax):
                sq = tuple((f"E{_ROTS[j]}0{ax}", j) for j in range(3) if j != d)
                fs.append(_LinearMotion(d, cols[ax], sq))
                fs.append(_Translate(None, comp_t, 1.0))
                fs.append(_ErrorRotation(comp_r, transpose=False))
            else:
                loc_t = tuple(None if j == d else f"E{_DIRS[j]}0{ax}" for j in range(3))
                loc_r = tuple(f"E{_ROTS[j]}0{ax}" for j in range(3))
                fs.append(_Translate(None, loc_t, 1.0))
                fs.append(_ErrorRotation(loc_r, transpose=False))  # type: ignore[arg-type]
                fs.append(_Translate(None, comp_t, 1.0))
                fs.append(_ErrorRotation(comp_r, transpose=False))
                fs.append(_AxisRotation(d, cols[ax]))
                fs.append(_ErrorRotation(loc_r, transpose=True))  # type: ignore[arg-type]
                fs.append(_Translate(None, loc_t, -1.0))
            fs.append(_Translate(None if o is None else -o, (None, None, None), 1.0))
        fs.append(_Translate(self.tool, ("EXT", "EYT", "EZT"), 1.0))
        fs.append(_ErrorRotation(("EAT", "EBT", "ECT"), transpose=False))
        return fs

    # -- inputs -------------------------------------------------------------------------

    def positions(self, q: npt.ArrayLike | Mapping[str, npt.ArrayLike]) -> _F:
        """Axis positions checked and stacked as an array ``(M, n_axes)`` in ``axes`` order.

        Parameters
        ----------
        q : array_like, shape (M, n_axes) or (n_axes,), or mapping of str to array_like (M,)
            Positions, mm for linear axes and rad for rotary ones; a mapping gives one
            array per axis letter.

        Returns
        -------
        ndarray, shape (M, n_axes)

        Raises
        ------
        InputError
            If an axis is unknown or missing, a shape is wrong, or a value is not finite.
        """
        if isinstance(q, Mapping):
            unknown = [k for k in q if k not in self.axes]
            if unknown:
                raise InputError(
                    f"unknown axis {unknown[0]!r}: machine {self.topology} has axes "
                    f"{' '.join(self.axes)}",
                    field="q",
                )
            missing = [a for a in self.axes if a not in q]
            if missing:
                raise InputError(
                    f"no position for axis {missing[0]}: expected one array per axis "
                    f"({' '.join(self.axes)})",
                    field="q",
                )
            arrs = [np.atleast_1d(np.asarray(q[a], dtype=np.float64)) for a in self.axes]
            if any(a.ndim != 1 for a in arrs):
                raise InputError("expected each axis position of shape (M,)", field="q")
            arr = np.stack(np.broadcast_arrays(*arrs), axis=1)
        else:
            arr = np.asarray(q, dtype=np.float64)
            if arr.ndim == 1:
                arr = arr[None, :]
            if arr.ndim != 2 or arr.shape[1] != self.n_axes:
                raise InputError(
                    f"expected axis positions of shape (M, {self.n_axes}) in the order "
                    f"{' '.join(self.axes)}, got shape {arr.shape}",
                    field="q",
                )
        if not np.all(np.isfinite(arr)):
            raise InputError("expected finite axis positions", field="q")
        return arr

    def error_values(
        self, q: npt.ArrayLike | Mapping[str, npt.ArrayLike], errors: Mapping[str, Any] | None
    ) -> dict[str, Any]:
        """Evaluate each error at the axis positions.

        Parameters
        ----------
        q : array_like, shape (M, n_axes), or mapping axis -> (M,)
            Axis positions (mm, rad).
        errors : mapping of str to float, array (M,) or ErrorFunction
            Errors by ISO name (with or without ``E``). A component error may be an
            :class:`~mtmc.kinematics.functions.ErrorFunction` of its axis's position;
            every other error is a constant (a number, or an array ``(M,)`` for one
            value per trial).

        Returns
        -------
        dict of str to ndarray
            Normalised name -> value, shape ``()`` or ``(M,)``.

        Raises
        ------
        InputError
            On an unknown name, a name given twice, an error function for a constant
            term, or a value of the wrong shape.
        """
        qa = self.positions(q)
        return self._values(qa, errors)

    def _inputs(self, errors: Mapping[str, Any] | None) -> dict[str, Any]:
        """Check the errors; normalised name -> array () or (M,), or ErrorFunction."""
        out: dict[str, Any] = {}
        for raw, val in (errors or {}).items():
            term = self.error_term(raw)
            if term.name in out:
                raise InputError(f"error {term.name} given twice", field=raw)
            if isinstance(val, ErrorFunction):
                if term.kind != "component":
                    raise InputError(
                        f"{term.name} is a {term.kind} error, a constant: expected a number "
                        "or an array (M,), not a function of position",
                        field=raw,
                    )
                out[term.name] = val
                continue
            try:
                v = np.asarray(val, dtype=np.float64)
            except (TypeError, ValueError) as exc:
                raise InputError(
                    f"expected a number, an array (M,) or an error function, got {val!r}",
                    field=raw,
                ) from exc
            if v.ndim > 1:
                raise InputError(
                    f"expected a number or an array of shape (M,), got shape {v.shape}",
                    field=raw,
                )
            if not np.all(np.isfinite(v)):
                raise InputError("expected finite error values", field=raw)
            out[term.name] = v
        return out

    def _values(self, qa: _F, errors: Mapping[str, Any] | None) -> dict[str, Any]:
        out = self._inputs(errors)
        cols = {ax: i for i, ax in enumerate(self.axes)}
        for name, val in out.items():
            if isinstance(val, ErrorFunction):
                v = np.asarray(val(qa[:, cols[self.error_term(name).axis]]), dtype=np.float64)
                if not np.all(np.isfinite(v)):
                    raise InputError("expected finite error values", field=name)
                out[name] = v
        return out

    def _batch(self, qa: _F, vals: Mapping[str, Any]) -> int:
        shapes = [
            (qa.shape[0],),
            *(
                np.broadcast_shapes((qa.shape[0],), v.coefficients.shape[:-1])
                if isinstance(v, ErrorFunction) and v.coefficients.ndim == 2
                else (() if isinstance(v, ErrorFunction) else np.shape(v))
                for v in vals.values()
            ),
        ]
        try:
            (m,) = np.broadcast_shapes(*shapes) or (1,)
        except ValueError as exc:
            raise InputError(
                f"the trial axes do not match: q has {qa.shape[0]} rows, errors have shapes "
                f"{sorted({s for s in shapes[1:]})}",
                field="errors",
            ) from exc
        return int(m)

    # -- forward kinematics -------------------------------------------------------------

    def _run(
        self,
        q: npt.ArrayLike | Mapping[str, npt.ArrayLike],
        errors: Mapping[str, Any] | None,
        exact: bool,
        start: list[list[float]],
        points: tuple[bool, ...],
    ) -> _F:
        """The chain applied to the vectors ``start`` (points or directions): (M, n, 3).

        In blocks of :data:`~mtmc.kinematics._columns.BLOCK` poses, each coordinate a
        column, the chain lowered once into operations with the constant factors
        multiplied out (:mod:`mtmc.kinematics._columns`).
        """
        qa = self.positions(q)
        vals = self._inputs(errors)
        m = self._batch(qa, vals)
        # constant sources are floats, the others arrays (M,) or functions of a position
        const: dict[str, Any] = {}
        arrays: dict[str, _F] = {}
        funcs: dict[str, tuple[str, ErrorFunction]] = {}
        qcols: dict[str, int] = {}
        for i in range(self.n_axes):
            if qa.shape[0] == 1:
                const[f"q:{i}"] = float(qa[0, i])
            else:
                qcols[f"q:{i}"] = i
        cols = {ax: i for i, ax in enumerate(self.axes)}
        for name, v in vals.items():
            if isinstance(v, ErrorFunction):
                if v.coefficients.ndim == 2 and v.coefficients.shape[0] == 1:
                    v = v.with_coefficients(v.coefficients[0])
                funcs[name] = (f"q:{cols[self.error_term(name).axis]}", v)
            elif v.size == 1:
                const[name] = float(v.reshape(()))
            else:
                arrays[name] = v
        ops: list[_cols.Op] = []
        for f in reversed(self._factors):  # type: ignore[attr-defined]
            ops.extend(f.lower(vals, exact))
        prog = _cols.Program(ops, start, points, const, arrays, qcols, funcs)
        y = prog.run(qa, m)
        if funcs and not np.isfinite(y.sum()):
            self._values(qa, errors)  # names the error function that overflowed
        return y

    def tool_position(
        self,
        q: npt.ArrayLike | Mapping[str, npt.ArrayLike],
        errors: Mapping[str, Any] | None = None,
        *,
        exact: bool = False,
    ) -> NDArray[np.float64]:
        """Position of the tool point in the workpiece frame.

        Parameters
        ----------
        q : array_like, shape (M, n_axes), or mapping axis letter -> array (M,)
            Commanded axis positions in the order of :attr:`axes` (mm; rad for rotary).
        errors : mapping, optional
            ISO name -> number, array ``(M,)`` (one value per trial) or error function
            (component errors). Missing errors are zero. See :meth:`error_values`.
        exact : bool
            Exact rotations ``Rz(c) Ry(b) Rx(a)`` for the error angles instead of the
            small-angle matrices (Aguado et al. 2016, eq. 12).

        Returns
        -------
        ndarray, shape (M, 3)
            mm. ``M`` is the broadcast of the rows of ``q`` and the trial axes of errors.

        Raises
        ------
        InputError
            On a bad ``q`` or error (see :meth:`error_values`).
        """
        return self._run(q, errors, exact, [[0.0, 0.0, 0.0]], (True,))[:, 0, :]

    def pose(
        self,
        q: npt.ArrayLike | Mapping[str, npt.ArrayLike],
        errors: Mapping[str, Any] | None = None,
        *,
        exact: bool = False,
    ) -> NDArray[np.float64]:
        """Pose of the tool frame in the workpiece frame.

        Parameters
        ----------
        q, errors, exact
            As for :meth:`tool_position`.

        Returns
        -------
        ndarray, shape (M, 4, 4)
            ``W_T_tool``; its translation is :meth:`tool_position`. With small-angle error
            matrices the rotation block is orthonormal only to first order.
        """
        start = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        y = self._run(q, errors, exact, start, (True, False, False, False))
        out = np.zeros((y.shape[0], 4, 4))
        out[:, :3, :3] = np.swapaxes(y[:, 1:, :], 1, 2)
        out[:, :3, 3] = y[:, 0, :]
        out[:, 3, 3] = 1.0
        return out

    def tool_direction(
        self,
        q: npt.ArrayLike | Mapping[str, npt.ArrayLike],
        errors: Mapping[str, Any] | None = None,
        *,
        exact: bool = False,
    ) -> NDArray[np.float64]:
        """Direction of the tool axis in the workpiece frame.

        Parameters
        ----------
        q, errors, exact
            As for :meth:`tool_position`.

        Returns
        -------
        ndarray, shape (M, 3)
            The image of :attr:`tool_axis` (unit to first order with small angles).
        """
        y = self._run(q, errors, exact, [[float(v) for v in self.tool_axis]], (False,))
        return y[:, 0, :]

    def jacobian(
        self,
        q: npt.ArrayLike | Mapping[str, npt.ArrayLike],
        errors: Mapping[str, Any] | None = None,
        *,
        names: tuple[str, ...] | list[str] | None = None,
        exact: bool = False,
    ) -> NDArray[np.float64]:
        """Jacobian of the tool position with respect to error values, analytic, batched.

        Parameters
        ----------
        q, errors, exact
            As for :meth:`tool_position`; the Jacobian is taken at these errors.
        names : sequence of str, optional
            The error names of the columns (default :attr:`error_names`).

        Returns
        -------
        ndarray, shape (M, 3, len(names))
            ``d p / d e`` for each error value ``e`` at the pose (for a component error,
            its value at the axis position; chain with
            :meth:`~mtmc.kinematics.functions.ErrorFunction.basis` for coefficients).

        Raises
        ------
        InputError
            On an unknown name or bad input.

        Notes
        -----
        One pass from the tool to the workpiece: before each factor ``F`` the partial
        derivatives ``dF(y)/de`` of its parameters are taken at the current point ``y``,
        and every derivative column collected so far is carried through the linear part
        of the remaining factors. Exact for the small-angle model and for ``exact=True``
        (the derivatives of ``Rz Ry Rx`` are written out).
        """
        cols_names = (
            self.error_names if names is None else tuple(self.error_term(n).name for n in names)
        )
        qa = self.positions(q)
        vals = self._values(qa, errors)
        m = self._batch(qa, vals)
        if qa.shape[0] != m:
            qa = np.broadcast_to(qa, (m, qa.shape[1]))
        index = {n: i for i, n in enumerate(cols_names)}
        y = np.zeros((m, 1, 3))
        V = np.zeros((m, 0, 3))
        owners: list[int] = []
        one = np.ones(1)
        for f in reversed(self._factors):  # type: ignore[attr-defined]
            new = [(index[n], v) for n, v in f.partials(y, vals, qa, exact) if n in index]
            if f.active(vals):
                if V.shape[1]:
                    V = f.apply(V, np.zeros(V.shape[1]), vals, qa, exact)
                y = f.apply(y, one, vals, qa, exact)
            if new:
                V = np.concatenate([V, *(np.broadcast_to(v, (m, 1, 3)) for _, v in new)], axis=1)
                owners.extend(i for i, _ in new)
        J = np.zeros((m, 3, len(cols_names)))
        for col, i in enumerate(owners):  # loop over parameters, not trials
            J[:, :, i] += V[:, col, :]
        return J

    def jacobian_transpose(
        self,
        q: npt.ArrayLike | Mapping[str, npt.ArrayLike],
        errors: Mapping[str, Any] | None,
        w: npt.ArrayLike,
        *,
        names: tuple[str, ...] | list[str] | None = None,
        exact: bool = False,
    ) -> NDArray[np.float64]:
        """``Jᵀ w`` at every pose: the Jacobian of :meth:`jacobian` times one vector each.

        Parameters
        ----------
        q, errors, exact
            As for :meth:`jacobian`.
        w : array_like, shape (M, 3)
            One vector per pose (mm, workpiece frame), e.g. the residual of a fit.
        names : sequence of str, optional
            The error names (default :attr:`error_names`).

        Returns
        -------
        ndarray, shape (M, len(names))
            ``Σ_c J[:, c, e] w[:, c]``: the gradient of ``w · p`` with respect to each error
            value, equal to ``einsum("mce,mc->me", jacobian(...), w)`` to rounding.

        Raises
        ------
        InputError
            On an unknown name or bad input, or ``w`` of another shape.

        Notes
        -----
        Reverse mode: the pass from the tool to the workpiece keeps, at each factor, the
        partial derivatives of its parameters and its linear part (the images of the unit
        vectors; none for a factor that only translates); a pass back carries ``w``
        through the transposed linear parts and meets each partial derivative once. Its
        cost is that of four vectors through the chain, where :meth:`jacobian` carries
        one per error.
        """
        cols_names = (
            self.error_names if names is None else tuple(self.error_term(n).name for n in names)
        )
        qa = self.positions(q)
        vals = self._values(qa, errors)
        m = self._batch(qa, vals)
        if qa.shape[0] != m:
            qa = np.broadcast_to(qa, (m, qa.shape[1]))
        lam = np.asarray(w, dtype=np.float64)
        if lam.shape != (m, 3):
            raise InputError(f"expected w of shape ({m}, 3), got {lam.shape}", field="w")
        index = {n: i for i, n in enumerate(cols_names)}
        y = np.zeros((m, 1, 3))
        one = np.ones(1)
        unit = np.broadcast_to(np.eye(3), (m, 3, 3))
        tape: list[tuple[list[tuple[int, _F]], _F | None]] = []
        for f in reversed(self._factors):  # type: ignore[attr-defined]
            new = [
                (index[n], np.broadcast_to(v, (m, 1, 3))[:, 0, :])
                for n, v in f.partials(y, vals, qa, exact)
                if n in index
            ]
            images = None
            if f.active(vals):
                if f.turns:
                    images = f.apply(unit, np.zeros(3), vals, qa, exact)  # row c: L e_c
                y = f.apply(y, one, vals, qa, exact)
            tape.append((new, images))
        g = np.zeros((m, len(cols_names)))
        for new, images in reversed(tape):  # from the workpiece back to the tool
            for i, v in new:
                g[:, i] += np.einsum("mc,mc->m", v, lam)
            if images is not None:
                lam = np.einsum("mci,mi->mc", images, lam)  # Lᵀ w
        return g
