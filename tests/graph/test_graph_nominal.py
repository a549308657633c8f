"""The nominal configuration checked before a run: degenerate constructions, conditioning, α."""

from __future__ import annotations

import math
import re
import warnings
from pathlib import Path

import pytest

from mtmc.cli.main import main
from mtmc.errors import DegenerateGeometryError, GraphError
from mtmc.graph import loads_graph
from mtmc.graph.model import check_graph
from mtmc.graph.nominal import ConditioningWarning, check_nominal

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "graphs"
PLANE = (EXAMPLES / "plane_3pt.toml").read_text()


def _plane(p3: str) -> str:
    return PLANE.replace("at = [0.0, 80.0, 0.0]", f"at = {p3}")


def test_collinear_points_into_plane_are_refused_by_name_before_running():
    text = _plane("[50.0, 0.0, 0.0]")  # on the line of m1 and m2; the probe has noise
    with pytest.raises(DegenerateGeometryError) as exc:
        loads_graph(text, file="p.toml")
    e = exc.value
    assert e.file == "p.toml"
    assert e.field == "in"
    assert text.splitlines()[e.line - 1] == 'in = ["p1", "p2", "p3"]'
    assert "transition t_plane (plane): at the nominal values" in str(e)
    assert "collinear" in str(e)
    assert "trials" not in str(e)


def test_identical_points_into_circle_are_refused_by_name(tmp_path):
    text = _plane("[0.0, 0.0, 0.0]").replace('op = "plane"', 'op = "circle"')
    text = text.replace("at = [100.0, 0.0, 0.0]", "at = [0.0, 0.0, 0.0]")
    text = text.split('[[transition]]\nname = "t_normal"')[0]
    f = tmp_path / "c.toml"
    f.write_text(text)
    assert main(["graph", "run", str(f), "-n", "100", "--seed", "1"]) == 2


def test_cli_prints_one_line_for_a_degenerate_nominal(tmp_path, capsys):
    f = tmp_path / "p.toml"
    f.write_text(_plane("[50.0, 0.0, 0.0]"))
    assert main(["graph", "check", str(f)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert re.match(r"mtmc: error: .*p\.toml:\d+: field in: transition t_plane \(plane\)", err)


def test_condition_number_of_a_thin_triangle_against_its_closed_form():
    # a = 0, b = (L, 0, 0), c = (L/2, e, 0): tilting c by dz turns the normal by dz/e,
    # the largest derivative; the size is the RMS distance of a, b, c from their centroid.
    length, e = 100.0, 0.01
    text = _plane(f"[{length / 2}, {e}, 0.0]")
    with pytest.warns(ConditioningWarning, match=r"transition t_plane \(plane\) is badly"):
        plan = check_graph(loads_graph(text, file="p.toml", validate=False))
    size = math.sqrt(length**2 / 6 + 2 * e**2 / 9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConditioningWarning)
        kappa = check_nominal(plan).condition["t_plane"]
    assert kappa == pytest.approx(size / e, rel=1e-4)
    assert len(plan.warnings) == 1
    assert plan.warnings[0].startswith("p.toml:")


def test_examples_are_well_conditioned_and_differences_have_condition_one():
    for f in sorted(EXAMPLES.glob("*.toml")):
        with warnings.catch_warnings():
            warnings.simplefilter("error", ConditioningWarning)
            plan = check_graph(loads_graph(f.read_text(), file=f.name, validate=False))
        assert plan.warnings == ()
    plan = check_graph(loads_graph((EXAMPLES / "bcs_origin.toml").read_text(), validate=False))
    cond = check_nominal(plan).condition
    vector_ops = [s.transition.name for s in plan.steps if s.transition.op == "vector"]
    assert vector_ops
    assert all(cond[n] == pytest.approx(1.0, rel=1e-6) for n in vector_ops)


def test_axis_angle_typed_in_radians_in_a_degree_place_is_refused(tmp_path, capsys):
    text = (EXAMPLES / "axis_c.toml").read_text()
    bad = text.replace('value = 60.0\nunit = "deg"', 'value = 1.0471975512\nunit = "deg"')
    assert bad != text
    with pytest.raises(GraphError, match=r"transition t_axis_c \(axis\): the angle alpha_c"):
        loads_graph(bad, file="axis_c.toml")
    f = tmp_path / "axis_c.toml"
    f.write_text(bad)
    assert main(["graph", "run", str(f), "-n", "10", "--seed", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "60" in err
    assert "alpha_c" in err


def test_axis_angle_within_the_tolerance_passes():
    # 0.5° off the angle of the ball positions is within the check's tolerance: the graph
    # is read, checked without a message, and carries the typed angle
    text = (EXAMPLES / "axis_c.toml").read_text()
    ok = text.replace('value = 60.0\nunit = "deg"', 'value = 60.5\nunit = "deg"')
    assert ok != text
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        graph = loads_graph(ok, file="axis_c.toml")
        plan = check_graph(graph)
    assert plan.warnings == ()
    assert graph.place("alpha_c").value == pytest.approx(60.5)
