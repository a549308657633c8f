"""Drawing a measurement graph: places as circles, transitions as boxes, markers as dots.

Stryczek (Table 1) draws places as ○, transitions as ▭, arcs as arrows and the markers of
M0 as ● inside their place: "a graphical character allowing for the easy assessment of
the model completeness and cohesion". :func:`to_dot` writes Graphviz DOT text;
:func:`draw` writes SVG (or PNG, PDF) with Matplotlib. Node positions come from the
graph (``pos``, e.g. the pixel coordinates of the assertion database) when every node
has one, else from the firing order: column ``2g + 1`` for the transitions of
generation ``g``, ``2g + 2`` for their outputs, column 0 for the marked places.
"""

from __future__ import annotations

from pathlib import Path

from mtmc.graph.model import check_graph
from mtmc.graph.structure import Graph, Plan

__all__ = ["layout", "graph_to_dot", "draw_graph"]

#: Size of the place and transition labels, pt: read at the drawing's own size (the
#: report draws it to the width of the page, and unscaled in a box that scrolls on request).
LABEL_PT = 7.0


def layout(plan: Plan) -> dict[str, tuple[float, float]]:
    """Positions of every place and transition (x to the right, y downwards).

    Parameters
    ----------
    plan : Plan
        A checked graph.

    Returns
    -------
    dict of str to (float, float)
        The node positions.
    """
    g = plan.graph
    nodes = [*plan.types, *(t.name for t in g.transitions)]
    given: dict[str, tuple[float, float]] = {}
    for p in g.places:
        if p.pos is not None:
            given[p.name] = (p.pos[0], p.pos[1])
    for t in g.transitions:
        if t.pos is not None:
            given[t.name] = (t.pos[0], t.pos[1])
    if all(n in given for n in nodes):
        return given
    col: dict[str, int] = {p: 0 for p in plan.types}
    for s in plan.steps:
        col[s.transition.name] = 2 * s.generation + 1
        col[s.transition.out] = 2 * s.generation + 2
    rows: dict[int, list[str]] = {}
    for n in nodes:
        rows.setdefault(col[n], []).append(n)
    pos = {}
    for c, names in rows.items():
        for i, n in enumerate(sorted(names)):
            pos[n] = (120.0 * c, 60.0 * i + (30.0 if c % 2 else 0.0))
    return pos


def _q(s: str) -> str:
    return '"' + s.replace('"', "'") + '"'


def graph_to_dot(graph: Graph | Plan) -> str:
    r"""The graph as Graphviz DOT text.

    Places are ``shape=circle`` labelled ``name`` and type (a marked place is drawn with a
    ``●``), transitions ``shape=box`` labelled ``name`` and op, arcs in input order.

    Parameters
    ----------
    graph : Graph or Plan
        The graph.

    Returns
    -------
    str
        DOT text (``dot -Tsvg`` renders it).

    Examples
    --------
    >>> from mtmc.graph.places import Place, Transition
    >>> g = Graph(places=(Place("a", "real", 1.0),),
    ...           transitions=(Transition("t1", "ratio", ("a", "a"), "b"),))
    >>> print(graph_to_dot(g).splitlines()[3])
      "a" [shape=circle, label="a\nreal\n●"];
    """
    plan = graph if isinstance(graph, Plan) else check_graph(graph)
    g = plan.graph
    marked = set(plan.marked)
    out = [f"digraph {_q(g.title or 'graph')} {{", "  rankdir=LR;", "  node [fontsize=10];"]
    nl = "\\n"  # DOT's line break inside a label
    for name, type_ in plan.types.items():
        dot = nl + "●" if name in marked else ""
        out.append(f'  {_q(name)} [shape=circle, label="{name}{nl}{type_}{dot}"];')
    for t in g.transitions:
        out.append(f'  {_q(t.name)} [shape=box, label="{t.name}{nl}{t.op}"];')
    for t in g.transitions:
        for i, p in enumerate(t.inputs, 1):
            lab = f" [label={i}]" if len(t.inputs) > 1 else ""
            out.append(f"  {_q(p)} -> {_q(t.name)}{lab};")
        out.append(f"  {_q(t.name)} -> {_q(t.out)};")
    out.append("}")
    return "\n".join(out) + "\n"


def draw_graph(graph: Graph | Plan, path: str | Path) -> None:
    """Draw the graph to a file with Matplotlib (format from the suffix: svg, png, pdf).

    Parameters
    ----------
    graph : Graph or Plan
        The graph.
    path : str or Path
        The output file.
    """
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle as CirclePatch
    from matplotlib.patches import FancyArrowPatch, Rectangle

    plan = graph if isinstance(graph, Plan) else check_graph(graph)
    g = plan.graph
    pos = layout(plan)
    xs = [p[0] for p in pos.values()]
    ys = [p[1] for p in pos.values()]
    w = max(xs) - min(xs) + 120.0
    h = max(ys) - min(ys) + 80.0
    fig = Figure(figsize=(max(4.0, w / 60.0), max(3.0, h / 60.0)))
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    ax.set_xlim(min(xs) - 60.0, max(xs) + 60.0)
    ax.set_ylim(max(ys) + 40.0, min(ys) - 40.0)
    ax.set_aspect("equal")
    ax.axis("off")
    r = 12.0
    marked = set(plan.marked)
    for t in g.transitions:
        for p in (*t.inputs, t.out):
            a, b = (pos[p], pos[t.name]) if p != t.out else (pos[t.name], pos[p])
            ax.add_patch(
                FancyArrowPatch(
                    a, b, arrowstyle="-|>", mutation_scale=8, shrinkA=13, shrinkB=13, lw=0.6
                )
            )
    for name, type_ in plan.types.items():
        x, y = pos[name]
        ax.add_patch(CirclePatch((x, y), r, fill=False, lw=0.8))
        if name in marked:
            ax.add_patch(CirclePatch((x, y), 3.0, color="black"))
        ax.text(x, y + r + 8.0, f"{name}\n{type_}", ha="center", va="top", fontsize=LABEL_PT)
    for t in g.transitions:
        x, y = pos[t.name]
        ax.add_patch(
            Rectangle((x - 6.0, y - 14.0), 12.0, 28.0, fill=True, fc="white", ec="black", lw=0.8)
        )
        ax.text(x, y - 18.0, f"{t.name}\n{t.op}", ha="center", va="bottom", fontsize=LABEL_PT)
    import matplotlib

    # no date in an SVG or PDF: the same graph draws the same file (a report's bytes)
    dated = Path(path).suffix.lower() not in (".svg", ".pdf")
    with matplotlib.rc_context({"svg.fonttype": "none"}):  # names stay text in the SVG
        fig.savefig(str(path), metadata=None if dated else {"Date": None})
