"""ISO 230-1 / ISO 230-7 names of geometric errors, and their meaning in the model.

Names follow ISO 230-1 (linear axes) and ISO 230-7 (rotary axes): ``E`` then the
direction of the error (X, Y, Z for a displacement, A, B, C for a rotation about x, y, z),
then, for a location or squareness error, ``0``, then the axis concerned:

================  ======================================================  ===========
kind              names (for axis K)                                      unit
================  ======================================================  ===========
component         ``EXK EYK EZK`` (positioning, straightness),            mm, rad
                  ``EAK EBK ECK`` (roll, pitch, yaw; or, for a rotary
                  axis, radial/axial/tilt/angular positioning motions),
                  functions of the position of K
squareness        ``EC0Y``, ``EB0Z``, ``EA0Z`` (linear axis K tilted      rad
                  about the named direction; the other references
                  ``EC0X``, ``EB0X``, ``EA0Y`` are accepted too)
location          rotary K: ``EX0C EY0C`` (position of the axis line),     mm, rad
                  ``EA0C EB0C`` (its orientation), and kin for A and B
tool              ``EXT EYT EZT`` (tool-point offset errors),             mm, rad
                  ``EAT EBT ECT`` (tool orientation)
part setup        ``EXP EYP EZP EAP EBP ECP`` (workpiece position and     mm, rad
                  orientation on its carrier)
================  ======================================================  ===========

Names may be written without the leading ``E`` (``X0C``, ``C0Y``), as controllers write
them. Every error term is, as in ISO 230-1, a motion of the tool relative to the
workpiece: a positive ``EXX`` moves the tool point by +EXX along x relative to the
workpiece whether X carries the tool or the part (see ``docs/conventions.md``).

Examples
--------
>>> normalise_error_name("x0c")
'EX0C'
>>> parse_error_name("EC0Y")
ErrorTerm(name='EC0Y', kind='squareness', axis='Y', direction=2, angular=True)
"""

from __future__ import annotations

from dataclasses import dataclass

from mtmc.errors import InputError
from mtmc.kinematics.topology import AXIS_DIRECTION, Topology, is_linear, is_rotary

__all__ = ["ErrorTerm", "normalise_error_name", "parse_error_name", "list_error_terms"]

_DIRS = "XYZ"
_ROTS = "ABC"


@dataclass(frozen=True)
class ErrorTerm:
    """One geometric error parameter.

    Parameters
    ----------
    name : str
        The ISO name with the leading ``E`` (``EXX``, ``EC0Y``, ``EX0C``, ``EZT``).
    kind : str
        ``"component"``, ``"squareness"``, ``"location"``, ``"tool"`` or ``"part"``.
    axis : str
        The axis letter, or ``"T"`` (tool) / ``"P"`` (part setup).
    direction : int
        0, 1, 2 for x, y, z: the direction of the displacement or the rotation axis.
    angular : bool
        True for a rotation (rad), False for a displacement (mm).
    """

    name: str
    kind: str
    axis: str
    direction: int
    angular: bool


def normalise_error_name(name: str) -> str:
    """Upper-case ``name`` and add the leading ``E`` when it is left out.

    Parameters
    ----------
    name : str
        ``EXX``, ``xx``, ``X0C``, ...

    Returns
    -------
    str
        The name with the leading ``E`` (not checked further; see :func:`parse_error_name`).

    Raises
    ------
    InputError
        If ``name`` is not a string.
    """
    if not isinstance(name, str):
        raise InputError(
            f"expected an error name such as 'EXX' or 'EC0Y', got {name!r}", field="name"
        )
    s = name.strip().upper()
    if not s.startswith("E"):
        s = "E" + s
    return s


def parse_error_name(name: str) -> ErrorTerm:
    """Parse an ISO 230 error name into an :class:`ErrorTerm` (no machine needed).

    Parameters
    ----------
    name : str
        An error name with or without the leading ``E``.

    Returns
    -------
    ErrorTerm

    Raises
    ------
    InputError
        If the name is not of the form ``E<dir><axis>``, ``E<dir>0<axis>``, ``E<dir>T``
        or ``E<dir>P``, or names a meaningless term (``EX0X``, ``EC0C``).
    """
    if not isinstance(name, str):
        raise InputError(f"expected an error name such as 'EXX', got {name!r}", field="errors")
    s = normalise_error_name(name)
    expected = (
        "expected an ISO 230 error name: E<X|Y|Z|A|B|C><axis> (component), "
        "E<A|B|C>0<linear axis> (squareness), E<X|Y|Z|A|B|C>0<rotary axis> (location), "
        "E<X|Y|Z|A|B|C>T (tool) or E<X|Y|Z|A|B|C>P (part setup)"
    )
    if len(s) not in (3, 4) or s[1] not in _DIRS + _ROTS:
        raise InputError(f"unknown error name {name!r}: {expected}", field=name)
    angular = s[1] in _ROTS
    direction = (_DIRS + _ROTS).index(s[1]) % 3
    if len(s) == 3:
        target = s[2]
        if target == "T":
            return ErrorTerm(s, "tool", "T", direction, angular)
        if target == "P":
            return ErrorTerm(s, "part", "P", direction, angular)
        if target in AXIS_DIRECTION:
            return ErrorTerm(s, "component", target, direction, angular)
        raise InputError(f"unknown error name {name!r}: {expected}", field=name)
    if s[2] != "0" or s[3] not in AXIS_DIRECTION:
        raise InputError(f"unknown error name {name!r}: {expected}", field=name)
    axis = s[3]
    if is_linear(axis):
        if not angular or direction == AXIS_DIRECTION[axis]:
            raise InputError(
                f"{name!r} is not a squareness error: for linear axis {axis} expected a "
                f"rotation about another direction, e.g. "
                f"E{_ROTS[(AXIS_DIRECTION[axis] + 1) % 3]}0{axis}",
                field=name,
            )
        return ErrorTerm(s, "squareness", axis, direction, True)
    if direction == AXIS_DIRECTION[axis]:
        raise InputError(
            f"{name!r} is not a location error of rotary axis {axis}: the location is "
            f"given by the two directions across the axis (the zero position belongs to "
            f"the component error E{_ROTS[AXIS_DIRECTION[axis]]}{axis})",
            field=name,
        )
    return ErrorTerm(s, "location", axis, direction, angular)


def list_error_terms(topology: Topology, *, which: str = "standard") -> tuple[ErrorTerm, ...]:
    """The error terms of a machine, in a fixed order.

    Parameters
    ----------
    topology : Topology
        The machine's axis chain.
    which : {"standard", "all"}
        ``"standard"``: an independent set: component errors of every axis (X, Y, Z, A, B,
        C order of errors), squareness with the ISO 230-1 references (``EC0Y``, ``EB0Z``,
        ``EA0Z``: an axis of larger direction index is tilted towards the one of smaller
        index), the four location errors of each rotary axis, tool and part setup errors.
        ``"all"`` adds the squareness terms of the other references (``EC0X`` ...).

    Returns
    -------
    tuple of ErrorTerm
        Order: components (axes in canonical order), squareness, location, tool, part.

    Raises
    ------
    InputError
        If ``which`` is not ``"standard"`` or ``"all"``.
    """
    if which not in ("standard", "all"):
        raise InputError(f"expected 'standard' or 'all', got {which!r}", field="which")
    out: list[ErrorTerm] = []
    for ax in topology.axes:
        for j, ch in enumerate(_DIRS + _ROTS):
            out.append(ErrorTerm(f"E{ch}{ax}", "component", ax, j % 3, j >= 3))
    out += _squareness_terms(topology, which)
    out += _location_terms(topology)
    for kind, tag in (("tool", "T"), ("part", "P")):
        for j, ch in enumerate(_DIRS + _ROTS):
            out.append(ErrorTerm(f"E{ch}{tag}", kind, tag, j % 3, j >= 3))
    return tuple(out)


def _squareness_terms(topology: Topology, which: str) -> list[ErrorTerm]:
    """The squareness terms of the linear axes (see `list_error_terms` for ``which``)."""
    out: list[ErrorTerm] = []
    lin = topology.linear_axes
    primary = [a for a in lin if a in "XYZ"]
    for ax in lin:
        d = AXIS_DIRECTION[ax]
        refs: list[int] = []
        for other in primary:
            e = AXIS_DIRECTION[other]
            if other == ax or e == d:
                continue
            if which == "all" or ax not in "XYZ" or e < d:
                refs.append(e)
        for e in sorted(set(refs)):
            r = 3 - d - e
            out.append(ErrorTerm(f"E{_ROTS[r]}0{ax}", "squareness", ax, r, True))
    return out


def _location_terms(topology: Topology) -> list[ErrorTerm]:
    """The four location terms of each rotary axis: two offsets, then two tilts."""
    out: list[ErrorTerm] = []
    for ax in topology.rotary_axes:
        d = AXIS_DIRECTION[ax]
        for j in range(3):
            if j != d:
                out.append(ErrorTerm(f"E{_DIRS[j]}0{ax}", "location", ax, j, False))
        for j in range(3):
            if j != d:
                out.append(ErrorTerm(f"E{_ROTS[j]}0{ax}", "location", ax, j, True))
    return out


def _check_term_for(topology: Topology, term: ErrorTerm) -> None:
    if term.kind in ("tool", "part"):
        return
    if term.axis not in topology.chain:
        raise InputError(
            f"error {term.name} refers to axis {term.axis}, which machine {topology} does "
            f"not have (axes: {' '.join(topology.axes)})",
            field=term.name,
        )
    if term.kind == "location" and not is_rotary(term.axis):  # pragma: no cover
        raise InputError(f"{term.name}: location errors are for rotary axes", field=term.name)
