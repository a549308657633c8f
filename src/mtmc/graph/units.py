"""The physical dimension of each part of a place: a length, an angle, or a number.

A graph file states its length unit once (``units = "mm"`` or ``"um"``) and marked real
places may say ``unit = "1"``, ``"rad"`` or ``"deg"``; the dimension of a produced place
follows from the op that produces it. Reports and the CLI use this to print every value
in the file's unit (a place written in deg in deg), and the library's results stay in mm
and rad.
"""

from __future__ import annotations

import math

from mtmc.graph.structure import Plan

__all__ = ["file_unit", "place_dimension", "unit_of"]

#: The parts of each place type that are lengths (the others are unit vectors, rotation
#: matrices, or the value of a scalar place, whose dimension follows its producer).
_LENGTH_PARTS = frozenset({"point", "centre", "radius", "translation"})


def _marked(plan: Plan, name: str) -> tuple[int, int]:
    """The dimension a place's ``unit`` says (none: a length)."""
    place = plan.graph.place(name)
    unit = place.unit if place is not None else None
    if unit == "1":
        return (0, 0)
    if unit in ("rad", "deg"):
        return (0, 1)
    return (1, 0)


def _rule(plan: Plan, name: str) -> tuple[int, int] | tuple[str, tuple[str, ...]]:
    """A place's dimension where it is known at once, else (op, the inputs it follows)."""
    type_ = plan.types[name]
    if type_ in ("x", "y", "z", "point"):
        return (1, 0)
    if type_ == "direction":
        return (0, 0)
    if name not in plan.producer:
        return _marked(plan, name)
    t = plan.graph.transition(plan.producer[name])
    assert t is not None
    if t.op == "angle":
        return (0, 1)
    if t.op == "ratio":
        return ("ratio", tuple(t.inputs[:2]))
    if t.op in ("middle", "displace") and t.inputs:
        return ("same", (t.inputs[0],))
    return (1, 0)  # distance, vector, meas and the rest: lengths


def _scalar_dimension(plan: Plan, name: str) -> tuple[int, int]:
    """Dimension of the value of an x/y/z/real/vector place: (power of length, of angle).

    A marked place says it (``unit``: none = a length, ``1``, ``rad``/``deg``); a produced
    one follows its op: ``distance`` and ``vector`` give lengths, ``angle`` radians,
    ``ratio`` the product of its inputs' dimensions, ``middle`` and ``displace`` the
    dimension of their first input; ``meas`` and the coordinates of points are lengths.
    Walked with a stack of its own, not recursion: a chain of thousands of
    ``displace`` transitions is as good as a short one. A place met again on the way (a
    cycle, which a checked graph has not) counts as marked. What it finds is kept in
    ``plan.dimensions``, for the next place asked.
    """
    memo = plan.dimensions
    stack, path = [name], set()
    while stack:
        n = stack[-1]
        if n in memo:
            stack.pop()
            continue
        rule = _rule(plan, n)
        if isinstance(rule[0], int):
            memo[n] = rule
        else:
            op, inputs = rule
            path.add(n)
            pending = [p for p in inputs if p not in memo and p not in path]
            if pending:
                stack.append(pending[0])
                continue
            dims = [memo.get(p) or _marked(plan, p) for p in inputs]
            memo[n] = (
                (dims[0][0] + dims[1][0], dims[0][1] + dims[1][1]) if op == "ratio" else dims[0]
            )
        stack.pop()
        path.discard(n)
    return memo[name]


def place_dimension(plan: Plan, name: str, part: str = "value") -> tuple[int, int]:
    """The dimension of one part of a place, as (power of length, power of angle).

    Parameters
    ----------
    plan : Plan
        A checked graph (:func:`mtmc.graph.check_graph`).
    name : str
        The place.
    part : str
        ``"value"`` for x/y/z/real/point/vector/direction places, else a part of a compound place
        (``"point"``, ``"direction"``, ``"normal"``, ``"centre"``, ``"radius"``,
        ``"rotation"``, ``"translation"``).

    Returns
    -------
    tuple of int
        ``(1, 0)`` a length, ``(0, 1)`` an angle, ``(0, 0)`` a number (a direction's
        components), ``(2, 0)`` an area (a ratio of two lengths' product), and so on.

    Examples
    --------
    >>> from mtmc.graph.places import Place, Transition
    >>> from mtmc.graph.model import check_graph
    >>> from mtmc.graph.structure import Graph
    >>> g = Graph(
    ...     places=(Place("a", "point", [0, 0, 0]), Place("b", "point", [1, 0, 0])),
    ...     transitions=(Transition("t", "distance", ("a", "b"), "d"),),
    ... )
    >>> place_dimension(check_graph(g), "d"), place_dimension(check_graph(g), "a", "value")
    ((1, 0), (1, 0))
    """
    if part == "value":
        return _scalar_dimension(plan, name)
    return (1 if part in _LENGTH_PARTS else 0, 0)


def unit_of(dimension: tuple[int, int], length_unit: str = "mm") -> str:
    """The unit of a dimension (power of length, power of angle), as reports print it.

    Parameters
    ----------
    dimension : tuple of int
        As :func:`place_dimension` gives it.
    length_unit : str
        The unit of length (``"mm"``, or a graph file's ``units``); angles are in rad.

    Returns
    -------
    str
        ``"mm"``, ``"rad"``, ``"mm^2"``, ``"mm·rad"``; ``"1"`` for a number.

    Examples
    --------
    >>> unit_of((1, 0)), unit_of((2, 0), "um"), unit_of((1, -1)), unit_of((0, 0))
    ('mm', 'um^2', 'mm·rad^-1', '1')
    """
    length, angle = dimension
    names = []
    if length:
        names.append(length_unit + (f"^{length}" if length != 1 else ""))
    if angle:
        names.append("rad" + (f"^{angle}" if angle != 1 else ""))
    return "·".join(names) or "1"


def file_unit(plan: Plan, name: str, part: str = "value") -> tuple[float, str]:
    """How a part of a place is shown in the graph file's unit: the divisor and the unit.

    The library's values are in mm and rad; a graph written in ``um`` shows a length as
    the value divided by ``factor`` (1e-3 mm per µm), an area by ``factor²``, an angle as
    it is. The command line and the workbench print every value through this.

    Returns
    -------
    scale : float
        ``factor ** (power of length)``: divide a library value by it; ``π/180`` for a
        marked place written in degrees.
    unit : str
        :func:`unit_of` the dimension, in the file's unit of length; ``"deg"`` for a
        marked place written in degrees, so that ``alpha = 30 deg`` shows as 30 deg.
    """
    place = plan.graph.place(name)
    if part == "value" and place is not None and place.unit == "deg":
        return math.pi / 180.0, "deg"
    length, angle = place_dimension(plan, name, part)
    return plan.graph.factor**length, unit_of((length, angle), plan.graph.units)
