"""Frozen means frozen: results, primitives, machines and module tables refuse every write."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from mtmc.geometry import Circle, Line, Plane, Sphere
from mtmc.graph.assertions import TYPE_CODES
from mtmc.graph.ops import OP_PARAMS
from mtmc.graph.structure import LENGTH_UNITS
from mtmc.kinematics import Machine
from mtmc.kinematics.topology import AXIS_DIRECTION
from mtmc.uncertainty import Normal, gum
from mtmc.uncertainty.formula import ALLOWED_CONSTANTS, ALLOWED_FUNCTIONS


def _writes_refused(*arrays: np.ndarray) -> None:
    for a in arrays:
        assert isinstance(a, np.ndarray)
        with pytest.raises(ValueError, match="read-only"):
            a[...] = 0.0


def test_frozen_primitives_hold_read_only_copies() -> None:
    p, d = np.array([1.0, 2.0, 3.0]), np.array([0.0, 0.0, 1.0])
    line = Line(p, d)
    assert line.point is not p
    assert not np.shares_memory(line.point, p)
    p[0] = 99.0  # the caller's array stays writable and the line does not see the change
    assert line.point[0, 0] == 1.0
    batch = np.zeros((4, 3))
    plane = Plane(batch, [0, 0, 1])
    batch[:] = 5.0
    assert not plane.point.any()
    r = np.array([1.0, 2.0])
    circle, sphere = Circle(np.zeros((2, 3)), [0, 0, 1], r), Sphere(np.zeros(3), r)
    r[:] = -1.0
    assert sphere.radius.tolist() == [1.0, 2.0]
    _writes_refused(line.point, line.direction, plane.point, plane.normal)
    _writes_refused(circle.centre, circle.normal, circle.radius, sphere.centre, sphere.radius)
    _writes_refused(line[1:].point, sphere[0].radius)  # sub-batches too
    with pytest.raises(dataclasses.FrozenInstanceError):
        plane.normal = np.zeros((1, 3))  # type: ignore[misc]


def test_frozen_gum_result_and_budget() -> None:
    res = gum(
        lambda a, b: np.stack([a + b, a - b], axis=-1),
        {"a": Normal(1.0, 0.1), "b": Normal(2.0, 0.2)},
    )
    _writes_refused(res.estimate_vector, res.u_vector, res.dof_vector, res.cov)
    _writes_refused(res.sensitivities["a"], res.budget[0].sensitivity)
    with pytest.raises(TypeError):
        res.sensitivities["c"] = 1.0  # type: ignore[index]
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.cov = np.eye(2)  # type: ignore[misc]


def test_frozen_machine_pivots_are_a_copy_that_cannot_change() -> None:
    o = np.array([10.0, 0.0, 0.0])
    m = Machine.from_topology("wCXfYZt", pivots={"C": o}, travel={"X": (0.0, 100.0)})
    q = np.array([[1.0, 2.0, 3.0, 0.3]])
    before = m.tool_position(q)
    o[0] = 500.0  # the caller's array
    assert o.flags.writeable
    with pytest.raises(TypeError):
        m.pivots["X"] = np.zeros(3)  # type: ignore[index]
    with pytest.raises(TypeError):
        m.travel["Y"] = (0.0, 1.0)  # type: ignore[index]
    _writes_refused(m.pivots["C"], m.tool, m.workpiece, m.tool_axis)
    np.testing.assert_array_equal(m.tool_position(q), before)


@pytest.mark.parametrize(
    "table",
    [LENGTH_UNITS, TYPE_CODES, OP_PARAMS, AXIS_DIRECTION, ALLOWED_FUNCTIONS, ALLOWED_CONSTANTS],
    ids=["LENGTH_UNITS", "TYPE_CODES", "OP_PARAMS", "AXIS_DIRECTION", "FUNCTIONS", "CONSTANTS"],
)
def test_frozen_module_tables(table) -> None:
    key = next(iter(table))
    with pytest.raises(TypeError):
        table[key] = table[key]
    with pytest.raises(TypeError):
        del table[key]


def test_frozen_monte_carlo_result() -> None:
    from mtmc.uncertainty import monte_carlo

    res = monte_carlo(
        lambda a, b: np.stack([a + b, a - b], axis=-1),
        {"a": Normal(1.0, 0.1), "b": Normal(2.0, 0.2)},
        trials=200,
        seed=1,
    )
    _writes_refused(res.estimate_vector, res.u_vector, res.cov, res.samples)
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.samples = np.zeros((200, 2))  # type: ignore[misc]


def test_frozen_graph_plan() -> None:
    from pathlib import Path

    from mtmc.graph import load_graph
    from mtmc.graph.model import check_graph

    graph = Path(__file__).resolve().parents[1] / "examples" / "graphs" / "ball_centre.toml"
    plan = check_graph(load_graph(graph))
    name = next(iter(plan.types))
    with pytest.raises(TypeError):
        plan.types[name] = "point"  # type: ignore[index]
    with pytest.raises(TypeError):
        plan.producer["zz"] = "t"  # type: ignore[index]


def test_frozen_graph_result_and_place_summaries() -> None:
    from pathlib import Path

    from mtmc.graph import load_graph, run_graph

    graph = Path(__file__).resolve().parents[1] / "examples" / "graphs" / "axis_c.toml"
    r = run_graph(load_graph(graph), 50, seed=1, outputs=["axis_c", "p_c"], keep=["p_c", "axis_c"])
    with pytest.raises(TypeError):
        r.places["x"] = r.places["p_c"]  # type: ignore[index]
    with pytest.raises(TypeError):
        r.samples["x"] = np.zeros(3)  # type: ignore[index]
    with pytest.raises(TypeError):
        r.types["x"] = "point"  # type: ignore[index]
    _writes_refused(r.samples["p_c"], r.samples["axis_c"].direction)
    for s in r.places.values():
        _writes_refused(s.estimate_vector, s.u_vector, s.cov)
        for part in s.parts:
            pr = s.part(part)
            _writes_refused(pr.estimate_vector, pr.u_vector, pr.cov, pr.values)


def test_frozen_objects_pickle_and_stay_frozen() -> None:
    import pickle

    m = Machine.from_topology("wCXfYZt", pivots={"C": [10.0, 0.0, 0.0]})
    back = pickle.loads(pickle.dumps(m))
    np.testing.assert_array_equal(back.pivots["C"], [10.0, 0.0, 0.0])
    with pytest.raises(TypeError):
        back.pivots["X"] = np.zeros(3)  # type: ignore[index]
    res = pickle.loads(pickle.dumps(gum(lambda a: 2 * a, {"a": Normal(1.0, 0.1)})))
    assert res.sensitivities["a"] == pytest.approx(2.0)
    with pytest.raises(TypeError):
        res.sensitivities["b"] = 1.0  # type: ignore[index]
