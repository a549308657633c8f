"""Places, transitions and probe defaults: the small frozen objects a graph is made of.

A measurement graph (Stryczek, eq. 7) is the ordered four G = (Π, T, E, M): places Π,
transitions T, arcs E (here: each transition's ``inputs`` and ``out``) and markers M (here:
the places that carry a value, ``u`` or ``dist`` are marked from the start, the set M0).
These classes hold what a graph file says, validated field by field in ``__post_init__``;
the meaning (type binding, firing order) lives in :mod:`mtmc.graph.model`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mtmc.errors import GraphError

__all__ = [
    "PLACE_TYPES",
    "COORDINATE_TYPES",
    "SCALAR_TYPES",
    "VALUE_TYPES",
    "VECTOR_TYPES",
    "PLACE_UNITS",
    "MAX_MAGNITUDE",
    "finite_number",
    "Place",
    "Transition",
    "ProbeDefaults",
]

#: The typed places of the graph. ``x``, ``y``, ``z``: one measured coordinate;
#: ``real``: a scalar; ``point``, ``vector``: 3-vectors; ``direction``: a unit vector (a
#: directional versor ``I, J, K`` of Stryczek); ``line``, ``plane``, ``circle``, ``sphere``:
#: derived features; ``frame``: a 4×4 homogeneous transform.
PLACE_TYPES: tuple[str, ...] = (
    "x",
    "y",
    "z",
    "real",
    "point",
    "vector",
    "direction",
    "line",
    "plane",
    "circle",
    "sphere",
    "frame",
)
#: The coordinate types, whose value is one coordinate of a probed point.
COORDINATE_TYPES: tuple[str, ...] = ("x", "y", "z")
#: The types whose value is one number: a coordinate or a real.
SCALAR_TYPES: tuple[str, ...] = (*COORDINATE_TYPES, "real")
#: The types whose value is a 3-vector ``(x, y, z)``.
VECTOR_TYPES: tuple[str, ...] = ("point", "vector", "direction")
#: The types a place may carry a value for (the others are built by transitions).
VALUE_TYPES: tuple[str, ...] = (*SCALAR_TYPES, *VECTOR_TYPES)
#: Units a place may declare: ``None`` (a length in the file's units), ``"1"``
#: (dimensionless), or an angle (``"rad"``, ``"deg"``).
PLACE_UNITS: tuple[str, ...] = ("1", "rad", "deg")

_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def _check_name(name: object, what: str, line: int | None) -> None:
    if not isinstance(name, str) or not _NAME.match(name):
        raise GraphError(
            f"{what} name must be an identifier (letters, digits, _), got {name!r}",
            line=line,
            field="name",
        )


#: The largest magnitude of a number in a graph file, in the file's units: 10¹² mm is a
#: million kilometres. Geometry squares lengths and sums squares, and the probe model sums
#: squared uncertainties; a number near the float64 limit (1e308) would overflow there.
MAX_MAGNITUDE: float = 1e12


def _finite(value: object, what: str, field_name: str, line: int | None) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise GraphError(f"{what}: expected a number, got {value!r}", line=line, field=field_name)
    try:
        x = float(value)
    except OverflowError:  # an integer beyond the float range
        x = math.inf
    if not math.isfinite(x) or abs(x) > MAX_MAGNITUDE:
        raise GraphError(
            f"{what}: expected a finite number of magnitude at most {MAX_MAGNITUDE:g}, "
            f"got {value!r}",
            line=line,
            field=field_name,
        )
    return x


def finite_number(value: object, what: str, field_name: str, line: int | None) -> float:
    """A number of a graph file as a float, or a :class:`GraphError` naming the field.

    Parameters
    ----------
    value : object
        What the file gives.
    what : str
        The place or transition (``"transition m1"``), for the message.
    field_name : str
        The field.
    line : int or None
        Its line.

    Returns
    -------
    float
        The number.

    Raises
    ------
    GraphError
        If ``value`` is not a number (a boolean is not), is not finite, or is larger in
        magnitude than :data:`MAX_MAGNITUDE`.
    """
    return _finite(value, what, field_name, line)


def _vector3(value: object, what: str, field_name: str, line: int | None) -> tuple[float, ...]:
    if not isinstance(value, list | tuple) or len(value) != 3:
        raise GraphError(
            f"{what}: expected a list of 3 numbers, got {value!r}", line=line, field=field_name
        )
    return tuple(_finite(v, what, field_name, line) for v in value)


@dataclass(frozen=True)
class Place:
    """A place of the graph: a typed quantity, marked from the start if it has a value.

    Parameters
    ----------
    name : str
        Identifier, unique in the graph.
    type : str
        One of :data:`PLACE_TYPES`.
    value : float or tuple of 3 floats, optional
        Nominal value (scalar for ``x``/``y``/``z``/``real``, 3 numbers for ``point``,
        ``vector``, ``direction``). In the file's length unit, or in ``unit``. A
        ``direction`` is divided by its length on construction (``[0, 0, 2]`` is
        ``[0, 0, 1]``), so that every op that takes it, ``displace`` by ``r`` along it
        included, sees a unit vector, with or without ``u``.
    u : float or tuple of 3 floats, optional
        Standard uncertainty: the place is ``value + N(0, u²)`` (each coordinate
        independently for 3-vectors; a ``direction`` is renormalised). A ``point``,
        ``vector`` or ``direction`` place may give one per coordinate, ``(u_x, u_y, u_z)``,
        as Stryczek's point place does (Table 1); :meth:`coordinate_u` gives the three in
        either case. Requires ``value``.
    dist : str, optional
        A distribution (``"uniform(-1e-3, 1e-3)"``) of the deviation added to ``value``
        (``value`` defaults to 0, so without it ``dist`` is the quantity itself).
        Exclusive with ``u``.
    unit : str, optional
        ``"1"`` (dimensionless), ``"rad"`` or ``"deg"``; default: a length in the file's unit.
    pos : tuple of 2 floats, optional
        Position of the node on a drawing (the assertion database's pixel ``x, y``).
    line : int, optional
        Line in the source file (not part of equality).

    Raises
    ------
    GraphError
        On an unknown type (``"unit"``, the former name of ``direction``, is refused
        with a message saying so), a malformed value, a negative ``u``, or ``u`` with
        ``dist``.
    """

    name: str
    type: str
    value: float | tuple[float, ...] | None = None
    # float, or a tuple of 3 floats (per coordinate); Any for the callers that read a float
    u: Any = None
    dist: str | None = None
    unit: str | None = None
    pos: tuple[float, float] | None = None
    line: int | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        _check_name(self.name, "place", self.line)
        what = f"place {self.name}"
        if self.type == "unit":
            raise GraphError(
                f'{what}: the place type "unit" is now called "direction" (a unit vector); '
                'write type = "direction"',
                line=self.line,
                field="type",
            )
        if self.type not in PLACE_TYPES:
            raise GraphError(
                f"{what}: unknown type {self.type!r}; expected one of {', '.join(PLACE_TYPES)}",
                line=self.line,
                field="type",
            )
        marked = self.value is not None or self.u is not None or self.dist is not None
        if marked and self.type not in VALUE_TYPES:
            raise GraphError(
                f"{what}: a place of type {self.type} cannot carry a value; "
                "build it with a transition",
                line=self.line,
                field="value",
            )
        self._check_value(what)
        self._check_u(what)
        self._check_dist_unit_pos(what)

    def _check_value(self, what: str) -> None:
        if self.value is not None:
            if self.type in VECTOR_TYPES:
                vec = _vector3(self.value, what, "value", self.line)
                if self.type == "direction":
                    norm = math.hypot(*vec)
                    if norm == 0.0:
                        raise GraphError(
                            f"{what}: a direction (a unit vector) cannot be zero",
                            line=self.line,
                            field="value",
                        )
                    if abs(norm - 1.0) > 1e-15:  # a unit vector (to 1e-15) is kept as it is
                        vec = tuple(c / norm for c in vec)
                object.__setattr__(self, "value", vec)
            else:
                object.__setattr__(self, "value", _finite(self.value, what, "value", self.line))

    def _check_u(self, what: str) -> None:
        if self.u is not None:
            u: float | tuple[float, ...]
            if isinstance(self.u, list | tuple):
                if self.type not in VECTOR_TYPES:
                    raise GraphError(
                        f"{what}: one u per coordinate needs a point, vector or direction place; "
                        f"a {self.type} place takes one number",
                        line=self.line,
                        field="u",
                    )
                u = _vector3(self.u, what, "u", self.line)
                low = min(u)
            else:
                u = low = _finite(self.u, what, "u", self.line)
            if low < 0:
                raise GraphError(
                    f"{what}: u must be >= 0, got {self.u!r}", line=self.line, field="u"
                )
            if self.value is None:
                raise GraphError(
                    f"{what}: u needs a nominal value (add value = ...)", line=self.line, field="u"
                )
            object.__setattr__(self, "u", u)

    def _check_dist_unit_pos(self, what: str) -> None:
        if self.dist is not None:
            if not isinstance(self.dist, str):
                raise GraphError(f"{what}: dist must be a string", line=self.line, field="dist")
            if self.u is not None:
                raise GraphError(
                    f"{what}: give either u or dist, not both", line=self.line, field="dist"
                )
        if self.unit is not None:
            if self.unit not in PLACE_UNITS:
                raise GraphError(
                    f"{what}: unknown unit {self.unit!r}; expected one of {', '.join(PLACE_UNITS)}"
                    " (lengths use the file's units)",
                    line=self.line,
                    field="unit",
                )
            if self.type != "real":
                raise GraphError(
                    f"{what}: only a real place may set unit", line=self.line, field="unit"
                )
        if self.pos is not None:
            if not isinstance(self.pos, list | tuple) or len(self.pos) != 2:
                raise GraphError(f"{what}: pos must be 2 numbers", line=self.line, field="pos")
            object.__setattr__(
                self, "pos", tuple(_finite(v, what, "pos", self.line) for v in self.pos)
            )

    @property
    def marked(self) -> bool:
        """Whether the place is marked from the start (carries a value, u or dist)."""
        return self.value is not None or self.u is not None or self.dist is not None

    def coordinate_u(self, factor: float = 1.0) -> NDArray[np.float64]:
        """The standard uncertainty of each coordinate of the place, ``(3,)``.

        ``(u, u, u)`` for one ``u``, ``(u_x, u_y, u_z)`` when given per coordinate, zeros
        without ``u``; for a scalar place the three are its one ``u``.

        Parameters
        ----------
        factor : float
            The place's unit in mm (or rad): the file's length unit, 1e-3 for µm.

        Returns
        -------
        ndarray, shape (3,)
            ``u · factor`` per coordinate (x, y, z), read-only.

        Examples
        --------
        >>> Place("p", "point", (1.0, 2.0, 3.0), u=(1.0, 2.0, 0.0)).coordinate_u(1e-3)
        array([0.001, 0.002, 0.   ])
        >>> Place("p", "point", (1.0, 2.0, 3.0), u=0.5).coordinate_u()
        array([0.5, 0.5, 0.5])
        """
        u = self.u if self.u is not None else 0.0
        out = np.broadcast_to(np.asarray(u, dtype=np.float64) * factor, (3,)).copy()
        out.flags.writeable = False
        return out


def _freeze(value: Any) -> Any:
    if isinstance(value, list | tuple):
        return tuple(_freeze(v) for v in value)
    return value


@dataclass(frozen=True)
class Transition:
    """A transition of the graph: an op applied to input places, writing one output place.

    Parameters
    ----------
    name : str
        Identifier, unique in the graph.
    op : str
        The op name (``meas``, ``point``, ``middle``, ...); its variant binds later by the
        types of the inputs (:mod:`mtmc.graph.ops`).
    inputs : tuple of str
        Input places, in order (the input arcs ``pt(p, t)``).
    out : str
        Output place (the output arc ``tp(t, p)``).
    params : tuple of (str, value) pairs
        Op fields other than ``name``/``op``/``in``/``out``, sorted by key (e.g. ``at``,
        ``direction``, ``u_probe`` of ``meas``). Lists are stored as tuples.
    pos : tuple of 2 floats, optional
        Position on a drawing.
    line : int, optional
        Line in the source file (not part of equality).
    param_lines : tuple of (str, int) pairs
        Line of each field in the source file (not part of equality).
    """

    name: str
    op: str
    inputs: tuple[str, ...]
    out: str
    params: tuple[tuple[str, Any], ...] = ()
    pos: tuple[float, float] | None = None
    line: int | None = field(default=None, compare=False, repr=False)
    param_lines: tuple[tuple[str, int], ...] = field(default=(), compare=False, repr=False)

    def __post_init__(self) -> None:
        _check_name(self.name, "transition", self.line)
        what = f"transition {self.name}"
        if not isinstance(self.op, str) or not self.op:
            raise GraphError(f"{what}: op must be a name", line=self.line, field="op")
        if isinstance(self.inputs, str) or not isinstance(self.inputs, list | tuple):
            raise GraphError(
                f"{what}: in must be a list of place names, got {self.inputs!r}",
                line=self.field_line("in"),
                field="in",
            )
        for p in self.inputs:
            if not isinstance(p, str) or not _NAME.match(p):
                raise GraphError(
                    f"{what}: input {p!r} is not a place name",
                    line=self.field_line("in"),
                    field="in",
                )
        object.__setattr__(self, "inputs", tuple(self.inputs))
        if not isinstance(self.out, str) or not _NAME.match(self.out):
            raise GraphError(
                f"{what}: out must be one place name, got {self.out!r}",
                line=self.field_line("out"),
                field="out",
            )
        params = dict(self.params)
        if len(params) != len(self.params):
            raise GraphError(f"{what}: a field is given twice", line=self.line)
        object.__setattr__(
            self, "params", tuple(sorted((str(k), _freeze(v)) for k, v in params.items()))
        )
        if self.pos is not None:
            if not isinstance(self.pos, list | tuple) or len(self.pos) != 2:
                raise GraphError(
                    f"{what}: pos must be 2 numbers, got {self.pos!r}",
                    line=self.field_line("pos"),
                    field="pos",
                )
            object.__setattr__(
                self,
                "pos",
                tuple(_finite(v, what, "pos", self.field_line("pos")) for v in self.pos),
            )

    def param(self, key: str, default: Any = None) -> Any:
        """Return the field ``key`` of the transition, or ``default``."""
        for k, v in self.params:
            if k == key:
                return v
        return default

    def field_line(self, key: str) -> int | None:
        """Return the source line of field ``key`` (the entry's line if unknown)."""
        for k, n in self.param_lines:
            if k == key:
                return n
        return self.line


@dataclass(frozen=True)
class ProbeDefaults:
    """Standard uncertainties of the touch-probe model (Stryczek, eq. 1), in the file's units.

    Parameters
    ----------
    u_axis : float
        u1, the axis position uncertainty, on every coordinate of a probed point.
    u_probe : float
        u2, the probe's own uncertainty, along the probing direction.
    u_perp : float
        u3, from the non-perpendicularity of the probing movement, along the direction.

    Notes
    -----
    Along the probing direction the three combine as u = √(u1² + u2² + u3²). Stryczek
    prints eq. 1 garbled (``m = a·b ∫ ρ θ dh``); its text states this root sum of squares.
    """

    u_axis: float = 0.0
    u_probe: float = 0.0
    u_perp: float = 0.0
    line: int | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        for key in ("u_axis", "u_probe", "u_perp"):
            v = _finite(getattr(self, key), "probe", key, self.line)
            if v < 0:
                raise GraphError(f"probe: {key} must be >= 0, got {v!r}", line=self.line, field=key)
            object.__setattr__(self, key, v)
