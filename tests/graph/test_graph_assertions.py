"""The assertion database of Stryczek (Table 1): import, export, errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mtmc.errors import GraphError, ParseError
from mtmc.graph import check_graph, load_graph, run_graph
from mtmc.graph.assertions import dumps_assertions, load_assertions, loads_assertions

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "graphs"

# The ball-centre graph of Stryczek, Fig. 6 written as Table 1 facts (typographic quotes as
# printed), with the probe extension: x1, x2, y1, y2, z1 probed, r1 the radius.
FIG6 = """
% Stryczek, Fig. 6: ball centre by 4 + 1 points
probe(0.002, 0.001, 0.0005).
p(1, 20, 20, „x”, -12.7, 0, 0).   p(2, 20, 60, „x”, 12.7, 0, 0).
p(3, 20, 100, „y”, 0, -12.7, 0).  p(4, 20, 140, „y”, 0, 12.7, 0).
p(5, 20, 180, „z”, 0, 0, 12.7).   p(6, 120, 220, „r”, -12.7, 0, 0).
p(7, 220, 40, „x”, 0, 0, 0).      p(8, 220, 120, „y”, 0, 0, 0).
p(9, 220, 200, „z”, 0, 0, 0).     p(10, 320, 120, „p”, 0, 0, 0).
t(1, 0, 20, meas). t(2, 0, 60, meas). t(3, 0, 100, meas). t(4, 0, 140, meas). t(5, 0, 180, meas).
t(6, 120, 40, middle). t(7, 120, 120, middle). t(8, 120, 200, displace). t(9, 270, 120, point).
tp(1, 1). tp(2, 2). tp(3, 3). tp(4, 4). tp(5, 5).
pt(1, 6). pt(2, 6). tp(6, 7).
pt(3, 7). pt(4, 7). tp(7, 8).
pt(5, 8). pt(6, 8). tp(8, 9).
pt(7, 9). pt(8, 9). pt(9, 9). tp(9, 10).
m(6). u(6, 0.0005).
"""


def test_fig6_reading():
    g = loads_assertions(FIG6, file="fig6.pl")
    plan = check_graph(g)
    assert plan.types["p10"] == "point"
    assert plan.types["p7"] == "x"
    t1 = g.transition("t1")
    assert t1.param("at") == (-12.7, 0.0, 0.0)  # the X, Y, Z of the meas output
    assert t1.param("direction") == (1.0, 0.0, 0.0)  # default for an x output
    assert g.transition("t9").inputs == ("p7", "p8", "p9")
    assert g.place("p6").value == -12.7
    assert g.place("p6").u == 0.0005
    assert g.place("p1").pos == (20.0, 20.0)
    assert plan.generations[0] == ("t1", "t2", "t3", "t4", "t5")


def test_fig6_gives_the_ball_centre_uncertainty():
    r = run_graph(loads_assertions(FIG6), 100_000, seed=3)
    u_dir = np.sqrt(0.002**2 + 0.001**2 + 0.0005**2)
    np.testing.assert_allclose(
        r.places["p10"].u_vector, [u_dir / np.sqrt(2)] * 2 + [np.hypot(u_dir, 0.0005)], rtol=0.012
    )


@pytest.mark.parametrize("name", ["ball_centre", "axis_c", "bcs_origin", "plane_lsq"])
def test_export_import_keeps_the_graph_and_its_numbers(name, tmp_path):
    g = load_graph(EXAMPLES / f"{name}.toml")
    text = dumps_assertions(g)
    path = tmp_path / f"{name}.pl"
    path.write_text(text)
    g2 = load_graph(path)
    assert dumps_assertions(g2) == text
    p1, p2 = check_graph(g), check_graph(g2)
    assert p1.types == p2.types
    assert [s.transition for s in p1.steps] == [s.transition for s in p2.steps]
    out = list(p1.types)[-1]
    a = run_graph(g, 500, seed=9, outputs=[out], keep=[out])
    b = run_graph(g2, 500, seed=9, outputs=[out], keep=[out])
    np.testing.assert_array_equal(a.places[out].estimate_vector, b.places[out].estimate_vector)


@pytest.mark.parametrize(
    ("text", "error", "line", "message"),
    [
        ("p(1, 0, 0, „x”, 1, 2, 3).\nq(1).", ParseError, 2, "unknown assertion 'q'"),
        ("p(1, 0, 0, „x”, 1, 2).", ParseError, 1, r"p\(...\) takes 7 arguments, got 6"),
        ("p(1, 0, 0, „x”, 1, 2, 3) $", ParseError, 1, "unexpected character"),
        (
            "p(1, 0, 0, „x”, 1, 2, 3).\nt(1, 0, 0, meas).\ntp(1, 1).\ntp(1, 2).",
            GraphError,
            4,
            "names place p2, which has no p",
        ),
        (
            "p(1, 0, 0, „x”, 1, 2, 3). p(2, 0, 0, „x”, 1, 2, 3).\n"
            "t(1, 0, 0, meas).\ntp(1, 1).\ntp(1, 2).",
            GraphError,
            2,
            "transition t1 has 2 output arcs",
        ),
        (
            "p(1, 0, 0, „x”, 1, 2, 3).\nt(1, 0, 0, meas).\ntp(1, 1).\npt(1, 7).",
            GraphError,
            4,
            "names transition t7, which has no t",
        ),
        (
            "p(1, 0, 0, „q”, 1, 2, 3).\nt(1, 0, 0, meas).\ntp(1, 1).",
            GraphError,
            1,
            "unknown type 'q'",
        ),
        (
            "p(1, 0, 0, „v”, 0, 0, 1). p(2, 0, 0, „unit”, 0, 0, 1).\nm(1). m(2).",
            GraphError,
            1,
            'the place type "unit" is now called "direction"',
        ),
    ],
)
def test_errors(text, error, line, message):
    with pytest.raises(error, match=message) as exc:
        loads_assertions(text, file="db.pl")
    assert exc.value.line == line
    assert str(exc.value).startswith(f"db.pl:{line}")


def test_missing_file(tmp_path):
    with pytest.raises(GraphError, match="cannot read"):
        load_assertions(tmp_path / "none.pl")


def test_type_code_v_is_a_direction_and_exports_as_v():
    text = (
        "p(1, 0, 0, „v”, 0, 0, 1). p(2, 0, 0, „p”, 1, 2, 3). p(3, 0, 0, „line”, 0, 0, 0).\n"
        "t(1, 0, 0, aline). pt(2, 1). pt(1, 1). tp(1, 3). m(1). m(2)."
    )
    g = loads_assertions(text)
    assert g.places[0].type == "direction"
    assert check_graph(g).types["p3"] == "line"
    again = loads_assertions(dumps_assertions(g))
    assert again.places == g.places
