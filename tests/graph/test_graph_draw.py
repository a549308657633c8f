"""Drawing: DOT text and SVG."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from mtmc.graph import check_graph, load_graph
from mtmc.graph.draw import draw_graph, graph_to_dot, layout

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "graphs"


def test_dot_has_every_node_and_arc():
    g = load_graph(EXAMPLES / "ball_centre.toml")
    plan = check_graph(g)
    dot = graph_to_dot(g)
    assert dot.count("shape=circle") == len(plan.types)
    assert dot.count("shape=box") == len(g.transitions)
    arcs = sum(len(t.inputs) + 1 for t in g.transitions)
    assert dot.count(" -> ") == arcs
    assert '"neg_r1" [shape=circle, label="neg_r1\\nreal\\n●"]' in dot  # the marker


def test_layout_follows_firing_order():
    plan = check_graph(load_graph(EXAMPLES / "ball_centre.toml"))
    pos = layout(plan)
    for s in plan.steps:
        for p in s.transition.inputs:
            assert pos[p][0] < pos[s.transition.name][0] < pos[s.transition.out][0]


def test_svg(tmp_path):
    g = load_graph(EXAMPLES / "plane_3pt.toml")
    out = tmp_path / "g.svg"
    draw_graph(g, out)
    root = ET.parse(out).getroot()
    assert root.tag.endswith("svg")
    text = out.read_text()
    plan = check_graph(g)
    for name in (*plan.types, *(t.name for t in g.transitions)):
        assert f">{name}" in text, name


def test_the_reports_drawing_carries_no_date_and_is_the_same_twice():
    # the report embeds this drawing (report.plots.graph_svg, its ids salted): a
    # <dc:date> made the same report differ from one rendering to the next
    from mtmc.report.plots import graph_svg

    text = (EXAMPLES / "ball_centre.toml").read_text(encoding="utf-8")
    one = graph_svg(text, "ball_centre.toml")
    assert "dc:date" not in one
    assert one == graph_svg(text, "ball_centre.toml")
