"""A drawing of the kinematic chain as SVG (the schematic of Aguado et al. 2016, Fig. 4).

The chain is drawn left to right as it is written, from the workpiece to the tool: the
workpiece, the part-side axes, the machine frame (a ground symbol), the tool-side axes,
the tool. A linear axis is a box with a double arrow along its direction; a rotary axis a
circle with a curved arrow. Part-side bodies are blue, tool-side bodies orange.

Examples
--------
>>> svg = draw_chain("XFYZ")
>>> svg.startswith("<svg") and svg.count('class="axis') == 3
True
"""

from __future__ import annotations

from html import escape

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
        A standalone SVG document; each body is a ``<g>`` element with
        ``class="axis linear|rotary part|tool"`` and ``data-axis`` set to its letter, in
        chain order.

    Raises
    ------
    TopologyError
        If ``spec`` is a string that does not parse.
    """
    if isinstance(spec, Machine):
        topo = spec.topology
    elif isinstance(spec, Topology):
        topo = spec
    else:
        topo = parse_topology(spec)
    head = title if title is not None else f"{topo}  ({topo.aguado})"
    step = 110
    n = len(topo.chain) + 3
    width = step * n + 40
    height = 190
    y = 100
    items: list[str] = []
    x = 40

    def link(x0: float, x1: float) -> None:
        items.append(
            f'<line x1="{x0}" y1="{y}" x2="{x1}" y2="{y}" stroke="#444" stroke-width="2"/>'
        )

    # workpiece
    items.append(
        f'<g class="end workpiece"><rect x="{x}" y="{y - 18}" width="60" height="36" '
        f'fill="#e2e8f0" stroke="{_PART}" stroke-width="2"/>'
        f'<text x="{x + 30}" y="{y + 5}" text-anchor="middle">workpiece</text></g>'
    )
    xs = x + 60
    x += step
    for side, axes in (("part", topo.part_axes), ("frame", ()), ("tool", topo.tool_axes)):
        if side == "frame":
            link(xs, x + 30)
            items.append(
                f'<g class="frame"><line x1="{x}" y1="{y + 30}" x2="{x + 60}" y2="{y + 30}" '
                f'stroke="#000" stroke-width="3"/>'
                + "".join(
                    f'<line x1="{x + 6 + 12 * i}" y1="{y + 30}" x2="{x + 12 * i}" '
                    f'y2="{y + 40}" stroke="#000"/>'
                    for i in range(5)
                )
                + f'<line x1="{x + 30}" y1="{y}" x2="{x + 30}" y2="{y + 30}" stroke="#000" '
                f'stroke-width="3"/><text x="{x + 30}" y="{y + 58}" text-anchor="middle">'
                "frame</text></g>"
            )
            xs = x + 30
            x += step
            continue
        colour = _PART if side == "part" else _TOOL
        for ax in axes:
            kind = "linear" if is_linear(ax) else "rotary"
            cx = x + 30
            link(xs, x if kind == "linear" else cx - 24)
            label = f'<text x="{cx}" y="{y - 34}" text-anchor="middle" font-weight="bold">'
            label += f"{ax}</text>"
            sub = f'<text x="{cx}" y="{y + 48}" text-anchor="middle" font-size="11">'
            sub += f"{'along' if kind == 'linear' else 'about'} {_DIRS[ax]}, {side}</text>"
            if kind == "linear":
                body = (
                    f'<rect x="{x}" y="{y - 18}" width="60" height="36" fill="white" '
                    f'stroke="{colour}" stroke-width="2"/>'
                    f'<line x1="{x + 10}" y1="{y}" x2="{x + 50}" y2="{y}" stroke="{colour}" '
                    f'marker-start="url(#arrow)" marker-end="url(#arrow)"/>'
                )
                xs = x + 60
            else:
                body = (
                    f'<circle cx="{cx}" cy="{y}" r="24" fill="white" stroke="{colour}" '
                    f'stroke-width="2"/><path d="M {cx - 12} {y + 8} A 14 14 0 1 1 {cx + 12} '
                    f'{y + 8}" fill="none" stroke="{colour}" marker-end="url(#arrow)"/>'
                )
                xs = cx + 24
            items.append(f'<g class="axis {kind} {side}" data-axis="{ax}">{body}{label}{sub}</g>')
            x += step
    link(xs, x)
    items.append(
        f'<g class="end tool"><polygon points="{x},{y - 18} {x + 40},{y - 18} {x + 20},{y + 22}" '
        f'fill="#fefcbf" stroke="{_TOOL}" stroke-width="2"/>'
        f'<text x="{x + 20}" y="{y + 42}" text-anchor="middle">tool</text></g>'
    )
    defs = (
        '<defs><marker id="arrow" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="6" '
        'markerHeight="6" orient="auto-start-reverse"><path d="M 0 0 L 10 5 L 0 10 z" '
        'fill="#444"/></marker></defs>'
    )
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
        f'viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="13">'
        f"{defs}<title>{escape(head, quote=False)}</title>"
        f'<text x="20" y="24" font-size="15">{escape(head, quote=False)}</text>'
        + "".join(items)
        + "</svg>"
    )
