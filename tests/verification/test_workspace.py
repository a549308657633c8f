"""Discretisation of the workspace: mesh, cloud (Aguado et al. 2016 eq. 18), diagonals, moves."""

from __future__ import annotations

import itertools
import tomllib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mtmc.errors import InputError
from mtmc.verification.workspace import (
    MeasurementPlan,
    axis_values,
    cloud,
    diagonals,
    mesh,
    workspace_from_dict,
)

LO = np.array([0.0, 0.0, 0.0])
HI = np.array([2500.0, 1500.0, 1200.0])


def test_aguado_2016_mesh_counts_and_bounds() -> None:
    # Aguado et al. 2016 §5: 500/500/400 mm -> 96 points, 100 mm -> 5408 points
    p96 = mesh(LO, HI, step=[500.0, 500.0, 400.0])
    p5408 = mesh(LO, HI, step=100.0)
    assert p96.shape == (96, 3)
    assert p5408.shape == (5408, 3)
    for p in (p96, p5408):
        np.testing.assert_array_equal(p.min(axis=0), LO)
        np.testing.assert_array_equal(p.max(axis=0), HI)
        assert np.unique(p, axis=0).shape[0] == p.shape[0]  # every node once
    # the nodes are exactly the product of the axis values
    expected = set(itertools.product(range(0, 2501, 500), range(0, 1501, 500), range(0, 1201, 400)))
    assert {tuple(int(v) for v in row) for row in p96} == expected


def test_counts_give_the_same_mesh_as_steps() -> None:
    a = mesh(LO, HI, step=[500.0, 500.0, 400.0])
    b = mesh(LO, HI, counts=[6, 4, 4])
    np.testing.assert_allclose(a, b, atol=1e-12)


@pytest.mark.parametrize("path", ["serpentine", "raster"])
@pytest.mark.parametrize("order", [[2, 1, 0], [0, 2, 1], [1, 0, 2]])
def test_motion_sequence(path: str, order: list[int]) -> None:
    p = mesh(LO, HI, counts=[3, 4, 5], order=order, path=path)
    dq = np.diff(p, axis=0)
    moving = np.abs(dq) > 0
    first, second, last = order
    # the first axis of the sequence moves between most pairs of points
    assert moving[:, first].sum() > moving[:, second].sum() > moving[:, last].sum()
    # the last axis moves only (counts - 1) times, monotonically
    assert moving[:, last].sum() == [3, 4, 5][last] - 1
    assert np.all(dq[:, last] >= 0)
    if path == "serpentine":
        # consecutive points differ by one step of one axis
        steps = (HI - LO) / (np.array([3, 4, 5]) - 1)
        n_moving = moving.sum(axis=1)
        assert np.all(n_moving == 1)
        np.testing.assert_allclose(np.abs(dq).sum(axis=1), steps[np.argmax(moving, axis=1)])
    else:
        # raster: the first axis always runs from start to end
        runs = p[:, first].reshape(-1, [3, 4, 5][first])
        assert np.all(np.diff(runs, axis=1) > 0)


def test_axis_values_errors() -> None:
    with pytest.raises(InputError, match="whole number of steps"):
        axis_values(0.0, 1000.0, step=300.0)
    with pytest.raises(InputError, match="step > 0"):
        axis_values(0.0, 1000.0, step=-1.0)
    with pytest.raises(InputError, match="either a step or a count"):
        axis_values(0.0, 1000.0)
    with pytest.raises(InputError, match="start <= end"):
        axis_values(10.0, 0.0, count=3)
    np.testing.assert_array_equal(axis_values(5.0, 5.0, step=1.0), [5.0])


def test_cloud_points_stay_in_their_cells_and_are_reproducible() -> None:
    step = np.array([500.0, 500.0, 400.0])
    base = mesh(LO, HI, step=step)

    def make(seed: int) -> np.ndarray:
        return cloud(LO, HI, np.random.default_rng(np.random.SeedSequence(seed)), step=step)

    c1, c2, c3 = make(7), make(7), make(8)
    np.testing.assert_array_equal(c1, c2)
    assert not np.array_equal(c1, c3)
    d = c1 - base
    assert np.all(np.abs(d) <= step / 2)  # inside the cell of its node
    on_edge = (base == LO) | (base == HI)
    assert np.all(d[on_edge] == 0.0)  # boundary coordinates stay (eq. 18: x_min < x < x_max)
    assert np.all(d[~on_edge] != 0.0)
    # the moves fill the cell: close to uniform on (-h/2, h/2) (sd h/sqrt(12))
    big = cloud(LO, HI, np.random.default_rng(np.random.SeedSequence(9)), step=100.0)
    dd = (big - mesh(LO, HI, step=100.0))[:, 0]
    dd = dd[dd != 0.0] / 100.0
    assert abs(dd.std() - 1 / np.sqrt(12)) < 0.01
    assert abs(dd.mean()) < 0.01
    # the direction of motion of the mesh is kept: along the first axis of the sequence
    # (Z) consecutive points of one pass are still in the same order
    same_pass = np.all(base[1:, :2] == base[:-1, :2], axis=1)
    assert np.all(np.sign(np.diff(c1[:, 2])[same_pass]) == np.sign(np.diff(base[:, 2])[same_pass]))


def test_cloud_needs_a_generator() -> None:
    with pytest.raises(InputError, match="Generator"):
        cloud(LO, HI, 7, step=500.0)  # type: ignore[arg-type]
    with pytest.raises(InputError, match="fraction"):
        cloud(LO, HI, np.random.default_rng(1), step=500.0, fraction=0.6)


def test_diagonals_lie_on_the_diagonals() -> None:
    n = 11
    body = diagonals(LO, HI, n)
    assert body.shape == (4 * n, 3)
    for line in body.reshape(4, n, 3):
        a, b = line[0], line[-1]
        # opposite corners: every coordinate at one end of its interval, all flipped
        assert np.all((a == LO) | (a == HI))
        assert np.all(a + b == LO + HI)
        t = np.linspace(0, 1, n)[:, None]
        np.testing.assert_allclose(line, a + t * (b - a), atol=1e-9)
    # the four body diagonals are distinct and cross at the centre
    corners = {tuple(line[0]) for line in body.reshape(4, n, 3)}
    assert len(corners) == 4
    np.testing.assert_allclose(body.reshape(4, n, 3)[:, n // 2], np.tile((LO + HI) / 2, (4, 1)))
    face = diagonals(LO, HI, n, which="face")
    assert face.shape == (12 * n, 3)
    for line in face.reshape(12, n, 3):
        a, b = line[0], line[-1]
        fixed = a == b
        assert fixed.sum() == 1  # one axis stays: the line lies in a face
        j = int(np.flatnonzero(fixed)[0])
        assert a[j] in (LO[j], HI[j])
        cross = np.cross(line - a, b - a)
        np.testing.assert_allclose(cross, 0.0, atol=1e-6)
    assert len({(tuple(ln[0]), tuple(ln[-1])) for ln in face.reshape(12, n, 3)}) == 12


def test_diagonals_with_a_fixed_axis() -> None:
    d = diagonals([0, 0, 50], [400, 400, 50], 5)
    assert d.shape == (10, 3)
    assert np.all(d[:, 2] == 50)
    with pytest.raises(InputError, match="face diagonals need at least 3"):
        diagonals([0, 0, 50], [400, 400, 50], 5, which="face")


def test_unidirectional_approach_with_overshoot() -> None:
    pts = mesh([0, 0], [20, 10], counts=[3, 2], order=[0, 1])  # X serpentine, Y slow
    plan = MeasurementPlan(("X", "Y"), pts, overshoot=[2.0, 1.0], approach=[1, -1])
    moves, target = plan.moves, plan.move_point
    # every point is reached once, in order
    np.testing.assert_array_equal(target[target >= 0], np.arange(pts.shape[0]))
    np.testing.assert_array_equal(moves[target >= 0], pts)
    # the last motion of each axis before each point is in its direction of approach
    for j, direction in enumerate((1, -1)):
        for i in np.flatnonzero(target >= 0):
            prev = moves[:i, j]
            moved = np.flatnonzero(prev != moves[i, j])
            assert moved.size, "the first point is pre-positioned"
            last_from = prev[moved[-1]]
            assert np.sign(moves[i, j] - last_from) == direction
            # the axis comes either from the previous point or from the overshoot position
            assert last_from in (moves[i, j] - direction * [2.0, 1.0][j], *pts[:, j])
    # two offsets: the path is repeated, the offset index follows the passes
    two = MeasurementPlan(("X", "Y"), pts, offsets=[[0, 0, 0], [0, 0, 100]])
    assert two.n_measurements == 12
    assert two.moves.shape == (12, 2)
    np.testing.assert_array_equal(two.move_offset, [0] * 6 + [1] * 6)
    np.testing.assert_array_equal(two.measurement_offsets[6:], np.tile([0, 0, 100.0], (6, 1)))


def test_plan_validation() -> None:
    with pytest.raises(InputError, match="needs an overshoot"):
        MeasurementPlan(("X",), [[0.0]], approach=[1])
    with pytest.raises(InputError, match=r"shape \(n, 2\)"):
        MeasurementPlan(("X", "Y"), [[0.0]])
    with pytest.raises(InputError, match="overshoots >= 0"):
        MeasurementPlan(("X",), [[0.0]], overshoot=[-1.0], approach=[1])
    plan = MeasurementPlan(("X",), [[0.0], [1.0]])
    with pytest.raises(ValueError, match="read-only"):
        plan.points[0, 0] = 3.0


STUDY = """\
[workspace]
distribution = "cloud"
sequence = "ZYX"
seed = 2016
offsets = [[0, 0, 0], [0, 0, 150]]
[workspace.X]
start = 0
end = 2500
step = 500
overshoot = 50
approach = "+"
[workspace.Y]
start = 0
end = 1500
count = 4
[workspace.Z]
start = 0
end = 1200
step = 400
"""


def test_workspace_table() -> None:
    plan = workspace_from_dict(tomllib.loads(STUDY), "s.toml", text=STUDY, machine_axes="XYZ")
    assert plan.axes == ("X", "Y", "Z")
    assert plan.kind == "cloud"
    assert plan.seed == 2016
    assert plan.n_points == 96
    assert plan.n_measurements == 192
    rng = np.random.default_rng(np.random.SeedSequence(2016))
    np.testing.assert_array_equal(plan.points, cloud(LO, HI, rng, counts=[6, 4, 4]))


@pytest.mark.parametrize(
    ("edit", "line", "field", "message"),
    [
        (("step = 500", "step = 300"), 9, "workspace.X.step", "whole number of steps"),
        (("count = 4", "count = 1"), 15, "workspace.Y.count", ">= 2"),
        (('sequence = "ZYX"', 'sequence = "ZY"'), 3, "workspace.sequence", "each axis"),
        (("seed = 2016", "seed = -1"), 4, "workspace.seed", ">= 0"),
        (('approach = "+"', 'approach = "up"'), 11, "workspace.X.approach", "expected one of"),
        (("overshoot = 50", "overshoot = 0"), 11, "workspace.X.approach", "overshoot > 0"),
        (("[workspace.Z]", "[workspace.Q]"), 16, "workspace.Q", "unknown key"),
        (
            ("offsets = [[0, 0, 0], [0, 0, 150]]", "offsets = [[0, 0]]"),
            5,
            "workspace.offsets",
            "[x, y, z]",
        ),
    ],
)
def test_workspace_errors_name_line_and_field(
    edit: tuple[str, str], line: int, field: str, message: str
) -> None:
    text = STUDY.replace(*edit)
    with pytest.raises(InputError, match=message) as info:
        workspace_from_dict(tomllib.loads(text), "s.toml", text=text, machine_axes="XYZ")
    err = info.value
    assert (err.file, err.line, err.field) == ("s.toml", line, field)


def test_workspace_axes_of_the_machine() -> None:
    text = STUDY
    with pytest.raises(InputError, match="missing") as info:
        workspace_from_dict(tomllib.loads(text), "s.toml", text=text, machine_axes="XYZC")
    assert info.value.line == 1
    with pytest.raises(InputError, match="not an axis of the machine") as info:
        workspace_from_dict(tomllib.loads(text), "s.toml", text=text, machine_axes="XY")
    assert info.value.line == 16


@given(
    counts=st.lists(st.integers(1, 5), min_size=1, max_size=4),
    data=st.data(),
)
@settings(max_examples=60, deadline=None)
def test_serpentine_visits_every_node_once_one_step_at_a_time(counts: list[int], data) -> None:  # type: ignore[no-untyped-def]
    d = len(counts)
    order = data.draw(st.permutations(range(d)))
    hi = np.array([float(c - 1) for c in counts])  # unit steps; a count of 1 is a fixed axis
    p = mesh(np.zeros(d), hi, counts=counts, order=order)
    assert p.shape == (int(np.prod(counts)), d)
    assert np.unique(p, axis=0).shape[0] == p.shape[0]
    if p.shape[0] > 1:
        dq = np.abs(np.diff(p, axis=0))
        np.testing.assert_array_equal(dq.sum(axis=1), 1.0)  # one axis, one step
