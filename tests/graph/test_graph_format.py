"""TOML graph files: round trip, validation errors with file, line and field."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mtmc.errors import GraphError, InputError, ParseError
from mtmc.graph import check_graph, dumps_graph, load_graph, loads_graph
from mtmc.graph.places import Place, Transition

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "graphs"
NAMES = ["ball_centre", "plane_3pt", "plane_lsq", "axis_a", "axis_c", "bcs_origin"]

HEAD = """title = "t"
[probe]
u_axis = 0.002
"""


def meas(name: str, out: str, coord: str = "x") -> str:
    return f"""
[[transition]]
name = "{name}"
op = "meas"
coordinate = "{coord}"
at = [0.0, 0.0, 0.0]
direction = [1.0, 0.0, 0.0]
out = "{out}"
"""


@pytest.mark.parametrize("name", NAMES)
def test_examples_round_trip(name):
    g = load_graph(EXAMPLES / f"{name}.toml")
    assert loads_graph(dumps_graph(g)) == g
    assert dumps_graph(loads_graph(dumps_graph(g))) == dumps_graph(g)


@settings(max_examples=30, deadline=None)
@given(
    values=st.lists(st.floats(-1e3, 1e3, allow_nan=False), min_size=2, max_size=5),
    u=st.floats(0, 1),
    units=st.sampled_from(["mm", "um"]),
)
def test_round_trip_property(values, u, units):
    places = tuple(Place(f"r{i}", "real", v, u=u) for i, v in enumerate(values))
    trans = tuple(
        Transition(f"t{i}", "displace", (f"r{i}", f"r{i + 1}"), f"s{i}")
        for i in range(len(values) - 1)
    )
    from mtmc.graph.structure import Graph

    g = Graph(places, trans, title='a "quoted" title', units=units)
    assert loads_graph(dumps_graph(g)) == g


def test_implicit_output_types():
    g = loads_graph(
        HEAD
        + meas("m1", "a")
        + meas("m2", "b")
        + """
[[transition]]
name = "t3"
op = "middle"
in = ["a", "b"]
out = "c"
[[transition]]
name = "m4"
op = "meas"
at = [1.0, 2.0, 3.0]
direction = [0.0, 0.0, -1.0]
out = "p"
"""
    )
    plan = check_graph(g)
    assert plan.types == {"a": "x", "b": "x", "c": "x", "p": "point"}
    assert plan.generations == (("m1", "m2", "m4"), ("t3",))


@pytest.mark.parametrize(
    ("text", "line", "message"),
    [
        (
            HEAD
            + meas("m1", "a")
            + '\n[[transition]]\nname = "t2"\nop = "frobnicate"\nin = ["a"]\nout = "b"\n',
            15,
            "field op: transition t2: unknown op 'frobnicate'",
        ),
        (
            HEAD + meas("m1", "a") + meas("m2", "a"),
            19,
            "field out: transition m2: place a is already produced by m1",
        ),
        (
            HEAD
            + meas("m1", "a")
            + '\n[[transition]]\nname = "t2"\nop = "middle"\nin = ["a", "q"]\nout = "b"\n',
            16,
            "input place q is not declared and no transition produces it",
        ),
        (
            HEAD
            + meas("m1", "a")
            + '\n[[transition]]\nname = "t2"\nop = "middle"\nin = ["a", "m1"]\nout = "b"\n',
            16,
            "m1 is a transition; the graph is bipartite",
        ),
        (
            HEAD
            + meas("m1", "a")
            + '\n[[transition]]\nname = "t2"\nop = "unit_v"\nin = ["a"]\nout = "b"\n',
            16,
            r"op unit_v accepts no inputs of types \(x\)",
        ),
        (
            HEAD + meas("m1", "a").replace('coordinate = "x"', "speed = 3"),
            8,
            "field speed: transition m1: unknown field 'speed'",
        ),
        (
            HEAD
            + '\n[[place]]\nname = "r"\ntype = "real"\nvalue = 1.0\ncolour = "red"\n'
            + meas("m1", "a"),
            9,
            "field colour: place r: unknown key 'colour'",
        ),
        (
            HEAD + '\n[[place]]\nname = "r"\ntype = "reel"\nvalue = 1.0\n' + meas("m1", "a"),
            7,
            "unknown type 'reel'",
        ),
        (
            HEAD
            + '\n[[place]]\nname = "r"\ntype = "real"\nvalue = 1.0\nu = -2\n'
            + meas("m1", "a"),
            9,
            "u must be >= 0",
        ),
        (HEAD + "colour = 3\n", 4, "field colour: probe: unknown key 'colour'"),
        ("colour = 3\n" + HEAD, 1, "field colour: unknown key 'colour'"),
        (
            HEAD + meas("m1", "a").replace('out = "a"', 'out = ["a", "b"]'),
            11,
            "out must be one place name",
        ),
    ],
)
def test_errors_name_file_line_field(text, line, message):
    with pytest.raises(GraphError, match=message) as exc:
        loads_graph(text, file="g.toml")
    assert exc.value.file == "g.toml"
    assert exc.value.line == line, str(exc.value)
    assert str(exc.value).startswith(f"g.toml:{line}:")


def test_cycle_is_reported():
    text = (
        HEAD
        + """
[[place]]
name = "r"
type = "real"
value = 1.0
[[transition]]
name = "t1"
op = "displace"
in = ["r", "b"]
out = "a"
[[transition]]
name = "t2"
op = "displace"
in = ["a", "r"]
out = "b"
"""
    )
    with pytest.raises(GraphError, match="cycle through t1, t2") as exc:
        loads_graph(text, file="c.toml")
    assert exc.value.line == 9  # the [[transition]] header of t1


def test_marked_place_cannot_be_produced():
    text = HEAD + '\n[[place]]\nname = "a"\ntype = "x"\nvalue = 1.0\n' + meas("m1", "a")
    with pytest.raises(GraphError, match="marked from the start"):
        loads_graph(text)


def test_declared_type_must_match_variant():
    text = HEAD + '\n[[place]]\nname = "a"\ntype = "y"\n' + meas("m1", "a")
    with pytest.raises(GraphError, match="coordinate = 'x' but place a is declared y"):
        loads_graph(text)


def test_not_toml():
    with pytest.raises(ParseError, match="not valid TOML") as exc:
        loads_graph('title = "x"\n[[place]\n', file="bad.toml")
    assert exc.value.line == 2


def test_missing_file(tmp_path):
    # an unreadable file is an input error (as for every file mtmc reads), not a graph error
    with pytest.raises(InputError, match="cannot read the graph file"):
        load_graph(tmp_path / "nope.toml")


def test_the_former_place_type_unit_is_refused_with_its_new_name(tmp_path):
    """``type = "unit"`` (the former name of ``direction``): file, line, field, the new name."""
    path = tmp_path / "old.toml"
    path.write_text(
        HEAD
        + '\n[[place]]\nname = "n"\ntype = "unit"\nvalue = [0.0, 0.0, 1.0]\n'
        + meas("m1", "a"),
        encoding="utf-8",
    )
    with pytest.raises(GraphError) as exc:
        load_graph(path)
    assert exc.value.file == "old.toml"
    assert exc.value.line == 7  # the line of the type key
    assert exc.value.field == "type"
    message = str(exc.value)
    assert message.startswith("old.toml:7:")
    assert 'the place type "unit" is now called "direction" (a unit vector)' in message
    assert 'write type = "direction"' in message
    with pytest.raises(GraphError, match='now called "direction"'):
        Place("n", "unit", (0.0, 0.0, 1.0))


def test_a_direction_place_and_unit_v_output_are_directions():
    g = loads_graph(
        HEAD
        + '\n[[place]]\nname = "n"\ntype = "direction"\nvalue = [0.0, 0.0, 2.0]\n'
        + '\n[[place]]\nname = "v"\ntype = "vector"\nvalue = [3.0, 0.0, 4.0]\n'
        + '\n[[transition]]\nname = "t1"\nop = "unit_v"\nin = ["v"]\nout = "d"\n'
        + '\n[[transition]]\nname = "t2"\nop = "angle"\nin = ["n", "d"]\nout = "a"\n'
    )
    plan = check_graph(g)
    assert plan.types["n"] == plan.types["d"] == "direction"
    assert plan.types["a"] == "real"
    assert dumps_graph(g).count('type = "direction"') == 1
