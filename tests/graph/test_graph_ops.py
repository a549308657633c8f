"""Ops registry, type binding and the rotary-axis construction (Stryczek eqs. 8-19)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mtmc.errors import DegenerateGeometryError, GraphError, InputError
from mtmc.geometry import Line
from mtmc.graph import ops


def rodrigues(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix about a unit axis (written here, independent of mtmc.geometry)."""
    k = axis / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def test_register_refuses_duplicates():
    v = ops.variants("middle")[0]
    with pytest.raises(GraphError, match="already has a variant"):
        ops.register(v)


def test_bind_by_input_types():
    assert ops.bind("point", ["x", "y", "z"]).output == "point"
    assert ops.bind("point", ["line", "plane"]).output == "point"
    assert ops.bind("middle", ["x", "x"]).output == "x"
    assert ops.bind("plane", ["point"] * 3).func is not ops.bind("plane", ["point"] * 5).func
    assert ops.bind("sphere", ["point"] * 5 + ["real"]).rest == "point"
    assert ops.bind("meas", [], output="z").output == "z"


def test_bind_errors_name_what_is_accepted():
    with pytest.raises(GraphError, match=r"op middle accepts no inputs of types \(x, y\)"):
        ops.bind("middle", ["x", "y"])
    with pytest.raises(GraphError, match="unknown op 'bogus'"):
        ops.bind("bogus", [])
    with pytest.raises(GraphError, match="4 or more point"):
        ops.bind("plane", ["point", "point"])


@settings(max_examples=40, deadline=None)
@given(
    axis=st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda a: np.linalg.norm(a) > 0.2),
    centre=st.tuples(*[st.floats(-500, 500)] * 3),
    start=st.tuples(*[st.floats(-200, 200)] * 3),
    alpha=st.floats(0.2, 2.8),
)
def test_rotary_axis_recovers_a_known_axis(axis, centre, start, alpha):
    """Rotate a point about a known axis by 0, +alpha, -alpha; recover the axis exactly."""
    a = np.asarray(axis) / np.linalg.norm(axis)
    c = np.asarray(centre)
    r0 = np.asarray(start) - np.dot(start, a) * a  # radial offset, perpendicular to a
    if np.linalg.norm(r0) < 10:
        r0 = np.cross(a, [1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.cross(a, [0.0, 1.0, 0.0])
        r0 *= 50 / np.linalg.norm(r0)
    p1 = c + r0
    p2 = c + rodrigues(a, alpha) @ r0
    p3 = c + rodrigues(a, -alpha) @ r0
    for line in (ops.rotary_axis(p1, p2, p3, alpha), ops.rotary_axis(p1, p2, p3)):
        np.testing.assert_allclose(line.direction[0], a, atol=1e-9)
        # the located point is the circle centre: the point of the axis in the ball's plane
        np.testing.assert_allclose(line.point[0], c, atol=1e-7 * (1 + np.abs(c).max()))


def test_rotary_axis_batch_equals_one_at_a_time():
    rng = np.random.default_rng(5)
    m = 50
    p = [rng.normal(size=(m, 3)) * 0.01 + q for q in ([100, 0, 0], [0, 100, 0], [0, -100, 0])]
    alpha = np.full(m, np.pi / 2)
    batch = ops.rotary_axis(*p, alpha)
    for i in range(0, m, 7):
        one = ops.rotary_axis(p[0][i], p[1][i], p[2][i], alpha[i])
        np.testing.assert_array_equal(one.point[0], batch.point[i])
        np.testing.assert_array_equal(one.direction[0], batch.direction[i])


def test_rotary_axis_on_rows_is_the_line_of_its_centre_and_normal():
    """Eqs. 8-27 written on (M, 3) arrays, as a Line normalises: the same bits."""
    rng = np.random.default_rng(6)
    m, al = 3000, np.pi / 3
    p1, p2, p3 = (
        rng.normal(size=(m, 3)) * 0.002 + q for q in ([150, 0, 40], [75, 130, 40], [75, -130, 40])
    )
    w = (p2 + p3) * 0.5 - p1
    r = np.sqrt(np.einsum("mi,mi->m", p3 - p2, p3 - p2)) * 0.5
    r = r / (np.sqrt(np.einsum("mi,mi->m", w, w)) * np.sin(al))
    ab, ac = p2 - p1, p3 - p1
    normal = np.stack(
        [
            ab[:, 1] * ac[:, 2] - ab[:, 2] * ac[:, 1],
            ab[:, 2] * ac[:, 0] - ab[:, 0] * ac[:, 2],
            ab[:, 0] * ac[:, 1] - ab[:, 1] * ac[:, 0],
        ],
        axis=1,
    )
    line = ops.rotary_axis(p1, p2, p3, al)
    np.testing.assert_array_equal(line.direction, Line(p1, normal).direction)
    np.testing.assert_allclose(line.point, p1 + w * r[:, None], rtol=0, atol=1e-12)


def test_rotary_axis_paper_steps():
    """Eqs. 8-19 on numbers: P1 at 0, P2 at +60 deg, P3 at -60 deg about z, R = 150."""
    al = np.pi / 3
    p1, p2, p3 = (150, 0, 40), (75, 150 * np.sin(al), 40), (75, -150 * np.sin(al), 40)
    line = ops.rotary_axis(p1, p2, p3, al)
    # eqs. 8-12: P4 = (75, 0, 40), |P3 P4| = 150 sin 60, R = 150; eqs. 13-19: P0 = P1 - 150 x
    np.testing.assert_allclose(line.point[0], [0, 0, 40], atol=1e-12)
    np.testing.assert_allclose(line.direction[0], [0, 0, 1], atol=1e-15)


def test_rotary_axis_degenerate():
    with pytest.raises(DegenerateGeometryError):
        ops.rotary_axis([0, 0, 0], [1, 0, 0], [2, 0, 0])
    with pytest.raises(DegenerateGeometryError, match="alpha"):
        ops.rotary_axis([1, 0, 0], [0, 1, 0], [0, -1, 0], 0.0)


def test_rotary_axis_checks_shapes_and_uses_relative_tolerances():
    with pytest.raises(
        InputError, match=r"field p2: expected shape \(M, 3\) or \(3,\), got \(2,\)"
    ):
        ops.rotary_axis([1, 0, 0], [0, 1], [0, -1, 0])
    with pytest.raises(InputError, match=r"field p3: expected 4 trials \(as in p1\) or 1, got 2"):
        ops.rotary_axis(np.ones((4, 3)), [0, 1, 0], np.ones((2, 3)))
    with pytest.raises(InputError, match=r"field alpha: expected shape \(M,\) or a number"):
        ops.rotary_axis([1, 0, 0], [0, 1, 0], [0, -1, 0], np.ones((2, 2)))
    # the same circle at any scale: 1e-9 mm is as good as 1e9 mm
    al = np.pi / 3
    for scale in (1e-9, 1.0, 1e9):
        p = scale * np.array(
            [[1.0, 0, 0], [np.cos(al), np.sin(al), 0], [np.cos(al), -np.sin(al), 0]]
        )
        line = ops.rotary_axis(*p, al)
        np.testing.assert_allclose(line.point[0], [0, 0, 0], atol=1e-12 * scale)
        np.testing.assert_allclose(line.direction[0], [0, 0, 1], atol=1e-12)
    # collinear to 1e-12 of the chord lengths, at any scale: refused, naming the trial
    for scale in (1e-9, 1e9):
        p = scale * np.array([[0, 0, 0], [1, 1e-12, 0], [2, 0, 0]])
        with pytest.raises(DegenerateGeometryError, match=r"collinear in 1 of 1 trials"):
            ops.rotary_axis(*p)


def test_rotary_axis_broadcasts_constants_against_a_batch():
    """Constant ball centres (a batch of one) with a random angle, and the reverse."""
    al = np.pi / 3
    p = [(150, 0, 40), (75, 150 * np.sin(al), 40), (75, -150 * np.sin(al), 40)]
    alphas = np.full(4, al)
    line = ops.rotary_axis(*p, alphas)
    assert line.point.shape == (4, 3)
    np.testing.assert_allclose(line.point, [[0, 0, 40]] * 4, atol=1e-12)
    batch = np.repeat(np.asarray(p[0], dtype=float)[None], 4, axis=0)
    line2 = ops.rotary_axis(batch, p[1], p[2], al)
    np.testing.assert_allclose(line2.point, line.point, atol=1e-12)


def test_a_direction_place_is_a_unit_vector_with_or_without_u():
    """displace(point, direction, r) moves by r whatever the length typed for the direction."""
    from mtmc.graph import loads_graph, run_graph
    from mtmc.graph.places import Place

    assert Place("d", "direction", (0.0, 0.0, 2.0)).value == (0.0, 0.0, 1.0)
    assert Place("d", "direction", (3.0, 0.0, 4.0)).value == (0.6, 0.0, 0.8)
    unit = (0.6, 0.0, 0.8)  # |unit| = 1 to 1e-16: kept bit for bit
    assert Place("d", "direction", unit).value == unit

    def graph(u: str) -> str:
        return (
            'title = "t"\n[[place]]\nname = "p"\ntype = "point"\nvalue = [1.0, 2.0, 3.0]\n'
            f'[[place]]\nname = "d"\ntype = "direction"\nvalue = [0.0, 0.0, 2.0]\n{u}'
            '[[place]]\nname = "r"\ntype = "real"\nvalue = 5.0\n'
            '[[transition]]\nname = "t"\nop = "displace"\nin = ["p", "d", "r"]\nout = "q"\n'
        )

    for u in ("", "u = 1e-9\n"):
        r = run_graph(loads_graph(graph(u)), 100, seed=1)
        np.testing.assert_allclose(r.places["q"].estimate_vector, [1, 2, 8], atol=1e-7)
        np.testing.assert_allclose(r.places["d"].estimate_vector, [0, 0, 1], atol=1e-8)


def test_accepts_prefix_is_being_the_start_of_an_accepted_list() -> None:
    """Second method: every input list of up to 6 types that a variant accepts, written
    out, and their prefixes; ``accepts_prefix`` says yes to exactly those (the rule the
    workbench asks as an arc is drawn), and ``max_inputs`` is the longest list."""
    import itertools

    for op in ops.op_names():
        for v in ops.variants(op):
            # the variant's own types and one it never takes
            alphabet = sorted({*v.inputs, *v.suffix, *([v.rest] if v.rest else []), "frame?"})
            accepted = [
                c for n in range(7) for c in itertools.product(alphabet, repeat=n) if v.accepts(c)
            ]
            prefixes = {c[:i] for c in accepted for i in range(len(c) + 1)}
            for n in range(6):
                for c in itertools.product(alphabet, repeat=n):
                    assert v.accepts_prefix(c) == (c in prefixes), (v.signature, c)
            longest = max(len(c) for c in accepted)
            assert v.max_inputs == (math.inf if v.rest else longest)
