"""Machine topology strings: ISO 10791 style (``wCBXfYZt``) and Aguado's (``XFYZ``).

A topology lists the axes of a machine as a chain from the workpiece to the tool, with
the machine frame (bed) somewhere in between. Axes written left of the frame carry the
workpiece, axes right of it carry the tool:

- ISO 10791 style: ``w`` (workpiece), the part-side axes, ``f`` (frame), the tool-side
  axes, ``t`` (tool); the letters run from the workpiece to the tool. In ``wCBXfYZt``
  the workpiece sits on C, C on B, B on X, X on the frame; Y sits on the frame, Z on Y,
  the tool on Z.
- Aguado's notation (Aguado et al. 2017; Aguado et al. 2016): no ``w`` and ``t``, ``F``
  for the frame, and the letters of each side run **from the frame outwards**: the
  part-side letters from the frame to the part, the tool-side ones from the frame to
  the tool. ``XFYZ`` is ``wXfYZt`` (X moves the part, Y and Z the tool); ``ZYXF`` is
  ``wXYZft``, a knee-type mill (Z on the frame carries Y, Y carries X, X the part).
  Aguado et al. 2016, eq. (3), ``T_t = R(z)(R(y)(R(x) T_p + X) + Y) + Z``, nests the
  part ``T_p`` in X first and Z last, and its eqs. (9)-(11) give X the squareness terms
  to Y and Z and Y the one to Z, Z none: Z is the reference axis on the frame.

Axis letters: linear X, Y, Z and the secondary linear U, V, W (parallel to X, Y, Z);
rotary A, B, C about x, y, z (ISO 841).

Examples
--------
>>> t = parse_topology("XFYZ")
>>> t.part_axes, t.tool_axes, t.axes
(('X',), ('Y', 'Z'), ('X', 'Y', 'Z'))
>>> str(parse_topology("wBZfXYCt"))
'wBZfXYCt'
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

from mtmc.errors import TopologyError

__all__ = [
    "LINEAR_AXES",
    "ROTARY_AXES",
    "AXIS_DIRECTION",
    "Topology",
    "parse_topology",
    "is_linear",
    "is_rotary",
]

LINEAR_AXES = ("X", "Y", "Z", "U", "V", "W")
ROTARY_AXES = ("A", "B", "C")
#: Index (0 = x, 1 = y, 2 = z) of the direction of motion or rotation of each axis letter.
AXIS_DIRECTION: Mapping[str, int] = MappingProxyType(
    {"X": 0, "Y": 1, "Z": 2, "U": 0, "V": 1, "W": 2, "A": 0, "B": 1, "C": 2}
)
_CANONICAL = LINEAR_AXES + ROTARY_AXES


def is_linear(axis: str) -> bool:
    """Whether ``axis`` is a linear axis letter (X, Y, Z, U, V, W)."""
    return axis in LINEAR_AXES


def is_rotary(axis: str) -> bool:
    """Whether ``axis`` is a rotary axis letter (A, B, C)."""
    return axis in ROTARY_AXES


@dataclass(frozen=True)
class Topology:
    """The axis chain of a machine tool.

    Parameters
    ----------
    part_axes : tuple of str
        Axes carrying the workpiece, in chain order from the workpiece to the frame (the
        order written in the string).
    tool_axes : tuple of str
        Axes carrying the tool, in chain order from the frame to the tool.

    Attributes
    ----------
    axes : tuple of str
        All axes in canonical order (X, Y, Z, U, V, W, A, B, C): the column order of the
        axis positions ``q``.
    chain : tuple of str
        All axes in chain order from the workpiece to the tool.

    Raises
    ------
    TopologyError
        If an axis letter is unknown or repeated, or there are no axes.
    """

    part_axes: tuple[str, ...]
    tool_axes: tuple[str, ...]

    def __post_init__(self) -> None:
        seen: set[str] = set()
        for ax in (*self.part_axes, *self.tool_axes):
            if ax not in _CANONICAL:
                raise TopologyError(
                    f"unknown axis letter {ax!r}: expected one of X Y Z U V W (linear) or "
                    "A B C (rotary)",
                    field="topology",
                )
            if ax in seen:
                raise TopologyError(
                    f"axis {ax!r} appears twice: each axis may appear once", field="topology"
                )
            seen.add(ax)
        if not seen:
            raise TopologyError("no axes: expected at least one axis letter", field="topology")

    @property
    def chain(self) -> tuple[str, ...]:
        """All axes from the workpiece to the tool."""
        return (*self.part_axes, *self.tool_axes)

    @property
    def axes(self) -> tuple[str, ...]:
        """All axes in canonical order X, Y, Z, U, V, W, A, B, C."""
        return tuple(a for a in _CANONICAL if a in self.chain)

    @property
    def linear_axes(self) -> tuple[str, ...]:
        """The linear axes, canonical order."""
        return tuple(a for a in self.axes if is_linear(a))

    @property
    def rotary_axes(self) -> tuple[str, ...]:
        """The rotary axes, canonical order."""
        return tuple(a for a in self.axes if is_rotary(a))

    def side(self, axis: str) -> str:
        """``"part"`` or ``"tool"``: which side of the frame ``axis`` is on."""
        if axis in self.part_axes:
            return "part"
        if axis in self.tool_axes:
            return "tool"
        raise TopologyError(f"axis {axis!r} is not in {self}", field="axis")

    def __str__(self) -> str:
        return "w" + "".join(self.part_axes) + "f" + "".join(self.tool_axes) + "t"

    @property
    def aguado(self) -> str:
        """The same topology in Aguado's notation (``XFYZ``; ``wXYZft`` is ``ZYXF``)."""
        return "".join(reversed(self.part_axes)) + "F" + "".join(self.tool_axes)


def parse_topology(spec: str) -> Topology:
    """Parse a topology string in ISO 10791 style or Aguado's notation.

    Parameters
    ----------
    spec : str
        ``wCBXfYZt`` (workpiece ``w``, frame ``f``, tool ``t``) or ``XFYZ`` (frame ``F``).
        Spaces are ignored.

    Returns
    -------
    Topology

    Raises
    ------
    TopologyError
        On an empty string, a missing or repeated frame marker, ``w`` without ``t`` (or
        the reverse), an unknown or repeated axis letter.

    Examples
    --------
    >>> parse_topology("wCBXfYZt").chain
    ('C', 'B', 'X', 'Y', 'Z')
    >>> parse_topology("ZYXF").part_axes  # from the workpiece: X carries it, Z is on the frame
    ('X', 'Y', 'Z')
    >>> str(parse_topology("ZYXF"))
    'wXYZft'
    """
    if not isinstance(spec, str):
        raise TopologyError(f"expected a topology string, got {spec!r}", field="topology")
    s = "".join(spec.split())
    where = f"topology {spec!r}"
    if not s:
        raise TopologyError("empty topology: expected e.g. 'wCBXfYZt' or 'XFYZ'", field="topology")
    has_w, has_t = s.startswith("w"), s.endswith("t")
    if has_w != has_t:
        raise TopologyError(
            f"{where}: expected both 'w' (workpiece, first) and 't' (tool, last), or neither",
            field="topology",
        )
    if has_w:
        s = s[1:-1]
    nframe = s.count("f") + s.count("F")
    if nframe == 0:
        raise TopologyError(
            f"{where}: no frame: expected exactly one 'f' (or 'F') between the part-side "
            "and the tool-side axes",
            field="topology",
        )
    if nframe > 1:
        raise TopologyError(
            f"{where}: two frames: expected exactly one 'f' (or 'F')", field="topology"
        )
    for i, ch in enumerate(s):
        if ch not in "fF" and ch not in _CANONICAL:
            raise TopologyError(
                f"{where}: unknown letter {ch!r} at position {i + 1 + has_w}: expected axis "
                "letters X Y Z U V W A B C, one frame 'f', and optionally 'w' ... 't'",
                field="topology",
            )
    k = s.index("f") if "f" in s else s.index("F")
    part = tuple(s[:k])
    if not has_w:  # Aguado's notation: the part-side letters run from the frame to the part
        part = part[::-1]
    return Topology(part_axes=part, tool_axes=tuple(s[k + 1 :]))
