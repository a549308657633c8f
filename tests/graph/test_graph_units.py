"""place_dimension: the dimension of each place, worked out by hand for small graphs."""

from mtmc.graph.model import check_graph
from mtmc.graph.toml_format import loads_graph
from mtmc.graph.units import place_dimension

TEXT = """
title = "dimensions"
[[place]]
name = "a"
type = "point"
value = [0, 0, 0]
[[place]]
name = "b"
type = "point"
value = [3, 4, 0]
[[place]]
name = "c"
type = "point"
value = [0, 5, 0]
[[place]]
name = "k"
type = "real"
value = 2.0
unit = "1"
[[place]]
name = "phi"
type = "real"
value = 30.0
unit = "deg"
[[transition]]
name = "t_ab"
op = "vector"
in = ["a", "b"]
out = "ab"
[[transition]]
name = "t_ac"
op = "vector"
in = ["a", "c"]
out = "ac"
[[transition]]
name = "t_d"
op = "distance"
in = ["a", "b"]
out = "d"
[[transition]]
name = "t_dd"
op = "ratio"
in = ["d", "d"]
out = "area"
[[transition]]
name = "t_dk"
op = "ratio"
in = ["d", "k"]
out = "twice_d"
[[transition]]
name = "t_ang"
op = "angle"
in = ["ab", "ac"]
out = "theta"
[[transition]]
name = "t_sum"
op = "displace"
in = ["phi", "theta"]
out = "phi_plus"
[[transition]]
name = "t_u"
op = "unit_v"
in = ["ab"]
out = "u_ab"
[[transition]]
name = "t_line"
op = "aline"
in = ["a", "u_ab"]
out = "l"
"""


def test_dimensions_follow_the_ops():
    plan = check_graph(loads_graph(TEXT))
    expected = {
        ("a", "value"): (1, 0),  # a point: coordinates are lengths
        ("ab", "value"): (1, 0),  # vector b - a
        ("d", "value"): (1, 0),  # distance
        ("area", "value"): (2, 0),  # length x length
        ("twice_d", "value"): (1, 0),  # length x number
        ("k", "value"): (0, 0),  # declared unit = "1"
        ("phi", "value"): (0, 1),  # declared in degrees: an angle
        ("theta", "value"): (0, 1),  # angle op
        ("phi_plus", "value"): (0, 1),  # displace keeps its first input's dimension
        ("u_ab", "value"): (0, 0),  # unit vector: numbers
        ("l", "point"): (1, 0),
        ("l", "direction"): (0, 0),
    }
    got = {key: place_dimension(plan, *key) for key in expected}
    assert got == expected


def test_a_place_written_in_degrees_is_shown_in_degrees():
    # file_unit: phi is written "30 deg" and shown so; a produced angle (theta) in rad,
    # a length in the file's unit. Reference: the numbers as written in TEXT.
    import math

    import pytest

    from mtmc.graph.units import file_unit

    plan = check_graph(loads_graph(TEXT))
    scale, unit = file_unit(plan, "phi")
    assert unit == "deg"
    # two roundings (to rad on reading, back to deg on showing): an ulp or two of 30
    assert math.radians(30.0) / scale == pytest.approx(30.0, rel=1e-15)
    assert file_unit(plan, "theta") == (1.0, "rad")
    assert file_unit(plan, "phi_plus") == (1.0, "rad")
    assert file_unit(plan, "d") == (1.0, "mm")


def test_graph_run_prints_a_constant_as_written():
    # `graph run`: alpha_a = 30 deg (axis_a.toml) printed as 30 deg with u 0, not
    # 0.523599 rad. Reference: the graph file's own value.
    from pathlib import Path

    from typer.testing import CliRunner

    from mtmc.cli.main import app

    graph = Path(__file__).parents[2] / "examples" / "graphs" / "axis_a.toml"
    args = ["graph", "run", str(graph), "-n", "200", "-s", "1", "--place", "alpha_a"]
    out = CliRunner().invoke(app, args, terminal_width=120)
    assert out.exit_code == 0, out.output
    row = next(line for line in out.output.splitlines() if "alpha_a" in line)
    cells = [c.strip() for c in row.strip("│ ").split("│")]
    assert cells[-3:] == ["30", "0", "deg"], row
