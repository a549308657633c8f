"""A drawing of the kinematic chain (the schematic of Aguado et al. 2016, Fig. 4), with Matplotlib.

The chain is drawn left to right as it is written, from the workpiece to the tool: the
workpiece, the part-side axes, the machine frame (a ground symbol), the tool-side axes,
the tool. A linear axis is a box with a double arrow along its direction; a rotary axis a
circle with a curved arrow. Part-side bodies are blue, tool-side bodies orange.

Examples
--------
>>> svg = draw_chain("XFYZ")
>>> svg.count('<g id="axis-') == 3 and '<g id="axis-X-linear-part">' in svg
True
"""

from __future__ import annotations

import io
from typing import Any

from mtmc.kinematics.machine import Machine
from mtmc.kinematics.topology import Topology, is_linear, parse_topology

__all__ = ["draw_chain"]

_PART = "#2b6cb0"
_TOOL = "#dd6b20"
_DIRS = {"X": "x", "Y": "y", "Z": "z", "U": "x", "V": "y", "W": "z", "A": "x", "B": "y", "C": "z"}


def draw_chain(spec: str | Topology | Machine, *, title: str | None = None) -> str:
    """Draw the kinematic chain of a machine as an SVG document.

    Parameters
    ----------
    spec : str, Topology or Machine
        The machine, its topology, or a topology string.
    title : str, optional
        A title line (default: the ISO 10791 string and Aguado's form).

    Returns
    -------
    str
        A standalone SVG document (Matplotlib, text kept as text, the same bytes for the
        same chain). The body of each axis is the element ``<g id="axis-L-KIND-SIDE">``,
        ``L`` its letter, ``KIND`` ``linear`` or ``rotary``, ``SIDE`` ``part`` or ``tool``,
        in chain order; the workpiece, the frame and the tool are ``<g id="workpiece">``,
        ``<g id="frame">`` and ``<g id="tool">``; each axis is labelled with its letter and
        "along x, part" (or "about z, tool", ...).

    Raises
    ------
    TopologyError
        If ``spec`` is a string that does not parse.
    """
    import matplotlib
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle, FancyArrowPatch, Polygon, Rectangle

    if isinstance(spec, Machine):
        topo = spec.topology
    elif isinstance(spec, Topology):
        topo = spec
    else:
        topo = parse_topology(spec)
    head = title if title is not None else f"{topo}  ({topo.aguado})"
    step, y, height = 110.0, 100.0, 190.0
    width = step * (len(topo.chain) + 3) + 40.0
    fig = Figure(figsize=(width / 72.0, height / 72.0))  # one unit of the axes, one pt
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    ax.set_xlim(0.0, width)
    ax.set_ylim(height, 0.0)
    ax.axis("off")
    ax.text(20.0, 24.0, head, fontsize=11.0)

    def text(x: float, yy: float, s: str, **kw: Any) -> None:
        ax.text(x, yy, s, ha="center", va="baseline", fontsize=kw.pop("fontsize", 10.0), **kw)

    def link(x0: float, x1: float) -> None:
        ax.plot([x0, x1], [y, y], color="#444", lw=1.5)

    x = 40.0
    ax.add_patch(
        Rectangle((x, y - 18.0), 60.0, 36.0, fc="#e2e8f0", ec=_PART, lw=1.5, gid="workpiece")
    )
    text(x + 30.0, y + 5.0, "workpiece")
    xs = x + 60.0
    x += step
    for side, axes in (("part", topo.part_axes), ("frame", ()), ("tool", topo.tool_axes)):
        if side == "frame":
            link(xs, x + 30.0)
            ground = [((x, y + 30.0), (x + 60.0, y + 30.0)), ((x + 30.0, y), (x + 30.0, y + 30.0))]
            ground += [((x + 6.0 + 12.0 * i, y + 30.0), (x + 12.0 * i, y + 40.0)) for i in range(5)]
            path = [p for seg in ground for p in (*seg, (float("nan"), float("nan")))]
            ax.plot(*zip(*path, strict=True), color="#000", lw=2.0, gid="frame")
            text(x + 30.0, y + 58.0, "frame")
            xs = x + 30.0
            x += step
            continue
        colour = _PART if side == "part" else _TOOL
        for name in axes:
            kind = "linear" if is_linear(name) else "rotary"
            cx = x + 30.0
            gid = f"axis-{name}-{kind}-{side}"
            if kind == "linear":
                link(xs, x)
                ax.add_patch(
                    Rectangle((x, y - 18.0), 60.0, 36.0, fc="white", ec=colour, lw=1.5, gid=gid)
                )
                a, b, style = (x + 10.0, y), (x + 50.0, y), "arc3"
                xs = x + 60.0
            else:
                link(xs, cx - 24.0)
                ax.add_patch(Circle((cx, y), 24.0, fc="white", ec=colour, lw=1.5, gid=gid))
                a, b, style = (cx - 12.0, y + 8.0), (cx + 12.0, y + 8.0), "arc3,rad=-1.1"
                xs = cx + 24.0
            arrows = "<|-|>" if kind == "linear" else "-|>"
            ax.add_patch(
                FancyArrowPatch(
                    a,
                    b,
                    arrowstyle=arrows,
                    connectionstyle=style,
                    mutation_scale=8.0,
                    color=colour,
                    lw=1.0,
                    shrinkA=0.0,
                    shrinkB=0.0,
                )
            )
            text(cx, y - 34.0, name, fontweight="bold")
            where = f"{'along' if kind == 'linear' else 'about'} {_DIRS[name]}, {side}"
            text(cx, y + 48.0, where, fontsize=8.5)
            x += step
    link(xs, x)
    tool = [(x, y - 18.0), (x + 40.0, y - 18.0), (x + 20.0, y + 22.0)]
    ax.add_patch(Polygon(tool, closed=True, fc="#fefcbf", ec=_TOOL, lw=1.5, gid="tool"))
    text(x + 20.0, y + 42.0, "tool")
    buf = io.StringIO()
    with matplotlib.rc_context({"svg.fonttype": "none", "svg.hashsalt": "chain"}):
        fig.savefig(buf, format="svg", metadata={"Date": None})
    return buf.getvalue()
