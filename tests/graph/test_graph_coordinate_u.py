"""Stryczek's point place with one u per coordinate, and the r place with three numbers."""

from __future__ import annotations

import numpy as np
import pytest

from mtmc.errors import GraphError, ParseError
from mtmc.graph import loads_graph
from mtmc.graph.assertions import dumps_assertions, loads_assertions
from mtmc.graph.places import Place
from mtmc.graph.toml_format import dumps_graph

TOML = """
units = "um"
[[place]]
name = "a"
type = "point"
value = [1.0, 2.0, 3.0]
u = [0.5, 2.0, 0.0]

[[place]]
name = "b"
type = "point"
value = [4.0, 6.0, 3.0]
u = 1.5

[[transition]]
name = "t1"
op = "vector"
in = ["a", "b"]
out = "ab"
"""


def test_toml_point_takes_one_u_per_coordinate():
    g = loads_graph(TOML, file="g.toml")
    a, b = g.place("a"), g.place("b")
    assert a is not None
    assert b is not None
    assert a.u == (0.5, 2.0, 0.0)
    np.testing.assert_array_equal(a.coordinate_u(g.factor), [0.5e-3, 2.0e-3, 0.0])
    np.testing.assert_array_equal(b.coordinate_u(g.factor), [1.5e-3] * 3)
    assert not a.coordinate_u().flags.writeable


def test_coordinate_u_round_trips_through_both_formats():
    g = loads_graph(TOML)
    assert loads_graph(dumps_graph(g)) == g
    text = dumps_assertions(g)
    assert "u(a, 0.5, 2.0, 0.0)." in text
    assert loads_assertions(text).place("a").u == (0.5, 2.0, 0.0)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ("u = [0.5, 2.0]", "expected a list of 3 numbers"),
        ("u = [0.5, -2.0, 0.0]", "u must be >= 0"),
    ],
)
def test_bad_coordinate_u_names_the_field(change, message):
    with pytest.raises(GraphError, match=message) as exc:
        loads_graph(TOML.replace("u = [0.5, 2.0, 0.0]", change), file="g.toml")
    assert exc.value.field == "u"
    assert exc.value.line == 7


def test_a_scalar_place_takes_one_u():
    with pytest.raises(GraphError, match="one u per coordinate needs a point"):
        Place("r", "real", 1.0, u=(1.0, 2.0, 3.0))


FACTS = """
p(1, 0, 0, "p", 10, 20, 30). m(1).
p(2, 0, 0, "r", {r}). m(2).
p(3, 0, 0, "{out}", 0, 0, 0).
t(1, 0, 0, displace). pt(1, 1). pt(2, 1). tp(1, 3).
u(1, 0.001, 0.002, 0.003).
"""


def test_r_place_reads_all_three_numbers():
    g = loads_assertions(FACTS.format(r="1.5, -2, 0.25", out="p"), file="f.pl")
    r = g.place("p2")
    assert r is not None
    assert r.type == "vector"
    assert r.value == (1.5, -2.0, 0.25)
    assert g.place("p1").u == (0.001, 0.002, 0.003)
    assert g.place("p1").coordinate_u().tolist() == [0.001, 0.002, 0.003]


def test_r_place_with_one_number_is_a_real():
    g = loads_assertions(FACTS.format(r="2.5, 0, 0", out="p"), file="f.pl", validate=False)
    assert g.place("p2").type == "real"
    assert g.place("p2").value == 2.5


def test_u_fact_with_two_numbers_is_refused_with_its_line():
    with pytest.raises(ParseError, match=r"u\(\.\.\.\) takes 2 or 4 arguments, got 3"):
        loads_assertions(FACTS.format(r="1, 0, 0", out="p") + "u(2, 1, 2).\n", file="f.pl")
