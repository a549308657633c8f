"""Constructions against hand-worked closed forms, and their geometric properties."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose, assert_array_equal

from mtmc.errors import DegenerateGeometryError, InputError
from mtmc.geometry import (
    Line,
    Plane,
    angle_between,
    circle_from_points,
    displace,
    distance_point_line,
    distance_point_plane,
    distance_point_point,
    foot_on_line,
    frame_from_plane_line_point,
    intersect_line_plane,
    line_from_planes,
    line_from_point_direction,
    line_from_points,
    middle,
    plane_from_point_normal,
    plane_from_points,
    project_point_plane,
    unit_vector,
    vector,
)

SEEDS = st.integers(0, 2**32 - 1)
M = 16


def _rng(seed: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(seed))


def _points(rng: np.random.Generator, k: int = 1) -> np.ndarray:
    return rng.normal(scale=50.0, size=(k, M, 3)) if k > 1 else rng.normal(scale=50.0, size=(M, 3))


# --- closed forms, worked by hand ---------------------------------------------------------


def test_middle_vector_unit_displace() -> None:
    assert_array_equal(middle([1, 2, 3], [3, 6, 9]), [[2, 4, 6]])
    assert_array_equal(vector([1, 2, 3], [3, 6, 9]), [[2, 4, 6]])
    assert_allclose(unit_vector([[3, 4, 12], [0, -2, 0]]), [[3 / 13, 4 / 13, 12 / 13], [0, -1, 0]])
    assert_array_equal(displace([1, 1, 1], [[0, 0, 2], [1, 0, 0]]), [[1, 1, 3], [2, 1, 1]])
    # a displacement by a constant along a direction (Stryczek's r_2 above the table)
    assert_allclose(displace([1, 1, 1], [0, 0, 7], length=[2.5]), [[1, 1, 3.5]])


def test_plane_from_points_eqs_20_to_29_with_eq_22_corrected() -> None:
    p1, p2, p3 = [1.0, 0, 0], [0.0, 1, 0], [0.0, 0, 1]
    plane = plane_from_points(p1, p2, p3)
    assert_allclose(plane.normal, [[1 / math.sqrt(3)] * 3], rtol=1e-15)
    assert_allclose(plane.offset, [-1 / math.sqrt(3)], rtol=1e-15)  # eq. 29
    # The components as printed: a = V12, b = V13.
    a = np.subtract(p2, p1)
    b = np.subtract(p3, p1)
    i0 = a[1] * b[2] - b[1] * a[2]  # eq. 21
    j0_printed = a[0] * b[2] - b[0] * a[2]  # eq. 22 as printed
    k0 = a[0] * b[1] - b[0] * a[1]  # eq. 23
    printed = np.array([i0, j0_printed, k0])
    assert abs(printed @ a) > 1.0  # the printed J_0 gives a vector not normal to V12
    corrected = np.array([i0, -j0_printed, k0])
    assert_allclose(corrected @ a, 0.0, atol=0)
    assert_allclose(plane.normal[0], corrected / np.linalg.norm(corrected), rtol=1e-15)


def test_line_plane_intersection_by_hand() -> None:
    # x = (1, 2, 3) + t (1, 1, 1)/sqrt(3) meets z = 0 at t = -3 sqrt(3): (-2, -1, 0).
    x = intersect_line_plane(Line([1, 2, 3], [1, 1, 1]), Plane([7, 7, 0], [0, 0, -1]))
    assert_allclose(x, [[-2, -1, 0]], atol=1e-14)


def test_line_from_planes_by_hand() -> None:
    # x + y + z = 3 and x - y = 0: direction (1, 1, 1) × (1, -1, 0) = (1, 1, -2).
    line = line_from_planes(Plane([1, 1, 1], [1, 1, 1]), Plane([0, 0, 0], [1, -1, 0]))
    assert_allclose(line.direction, [np.array([1, 1, -2]) / math.sqrt(6)], rtol=1e-15)
    p = line.point[0]
    assert_allclose([p.sum(), p[0] - p[1]], [3, 0], atol=1e-14)
    # the point closest to the midpoint x0 = (0.5, 0.5, 0.5) of the planes' points:
    # (1, 1, 1) is on the line and (1, 1, 1) - x0 = (0.5, 0.5, 0.5) is normal to (1, 1, -2).
    assert_allclose(p, [1, 1, 1], atol=1e-14)


def test_projections_and_distances_by_hand() -> None:
    plane = Plane([0, 0, 2], [0, 0, 1])
    assert_array_equal(project_point_plane([[3, 4, 7]], plane), [[3, 4, 2]])
    assert_array_equal(distance_point_plane([[3, 4, 7], [0, 0, -1]], plane), [5, -3])
    axis = Line([0, 0, 5], [0, 0, -3])
    assert_array_equal(foot_on_line([1, 1, 9], axis), [[0, 0, 9]])
    assert_allclose(distance_point_line([1, 1, 9], axis), [math.sqrt(2)], rtol=1e-15)
    assert_array_equal(distance_point_point([1, 2, 3], [4, 6, 15]), [13])


def test_angle_between_exact_and_nearly_parallel() -> None:
    assert_allclose(
        angle_between([1, 0, 0], [[1, 1, 0], [0, 0, 5], [-2, 0, 0]]), [np.pi / 4, np.pi / 2, np.pi]
    )
    # 1 nrad: arccos of the dot product would give 0 or ~1.5e-8; atan2 keeps every digit.
    assert_allclose(angle_between([1, 0, 0], [1, 1e-9, 0]), [1e-9], rtol=1e-12)


def test_circle_from_points_tilted_by_hand() -> None:
    # circle of radius 5 about (1, 2, 3) in the plane with normal (0, 0.6, 0.8)
    n = np.array([0, 0.6, 0.8])
    e1 = np.array([1.0, 0, 0])
    e2 = np.cross(n, e1)
    c = np.array([1.0, 2, 3])
    pts = [c + 5 * (math.cos(t) * e1 + math.sin(t) * e2) for t in (0.1, 2.0, 4.0)]
    circ = circle_from_points(*pts)
    assert_allclose(circ.centre, [c], atol=1e-13)
    assert_allclose(circ.radius, [5.0], rtol=1e-14)
    assert_allclose(circ.normal, [n], atol=1e-15)  # counter-clockwise about n


def test_line_constructors() -> None:
    line = line_from_points([1, 1, 1], [1, 1, -3])
    assert_array_equal(line.point, [[1, 1, 1]])
    assert_array_equal(line.direction, [[0, 0, -1]])
    line = line_from_point_direction([0, 0, 0], [2, 0, 0])
    assert_array_equal(line.direction, [[1, 0, 0]])
    plane = plane_from_point_normal([0, 0, 1], [0, 3, 4])
    assert_allclose(plane.normal, [[0, 0.6, 0.8]])


def test_frame_by_hand() -> None:
    # plane z = 1; the line through 0 along (0, 1, 1) projects to the y direction through
    # (0, 0, 1); the point (5, 6, 7) fixes the origin along it: (0, 6, 1)
    T = frame_from_plane_line_point(
        Plane([0, 0, 1], [0, 0, 1]), Line([0, 0, 0], [0, 1, 1]), [5, 6, 7]
    )
    expected = np.array([[0, -1, 0, 0], [1, 0, 0, 6], [0, 0, 1, 1], [0, 0, 0, 1.0]])
    assert_allclose(T[0], expected, atol=1e-15)


def test_frame_is_3_2_1_by_hand() -> None:
    # plane z = 0, then the line y = 5 along x, then the point (7, 0, 0): the origin is
    # where the plane x = 7 (through the point, across the line) cuts the line: (7, 5, 0)
    T = frame_from_plane_line_point(
        Plane([0, 0, 0], [0, 0, 1]), Line([-3, 5, 0], [1, 0, 0]), [7, 0, 0]
    )
    expected = np.array([[1, 0, 0, 7], [0, 1, 0, 5], [0, 0, 1, 0], [0, 0, 0, 1.0]])
    assert_allclose(T[0], expected, atol=1e-15)


# --- broadcasting and input errors --------------------------------------------------------


def test_single_point_broadcasts_against_batch() -> None:
    rng = _rng(3)
    b = rng.normal(size=(5, 3))
    a = np.array([1.0, -2.0, 0.5])
    assert_array_equal(middle(a, b), middle(np.tile(a, (5, 1)), b))
    assert_array_equal(distance_point_point(a, b), distance_point_point(np.tile(a, (5, 1)), b))
    plane = Plane(a, [0, 0, 1])
    assert project_point_plane(b, plane).shape == (5, 3)


def test_batch_size_mismatch_is_named() -> None:
    with pytest.raises(InputError, match=r"field b: expected 4 trials \(as in a\) or 1, got 3"):
        middle(np.zeros((4, 3)), np.zeros((3, 3)))
    with pytest.raises(InputError, match=r"field plane: expected 2 trials \(as in p\) or 1, got 3"):
        project_point_plane(np.zeros((2, 3)), Plane(np.zeros((3, 3)), [0, 0, 1]))


# --- degenerate input ---------------------------------------------------------------------


def test_zero_vector() -> None:
    with pytest.raises(
        DegenerateGeometryError,
        match=r"field v: the vector has zero length in 1 of 2 trials \(first: trial 0\); "
        "expected a non-zero vector",
    ):
        unit_vector([[0, 0, 0], [1, 0, 0]])
    with pytest.raises(DegenerateGeometryError, match="field u: the vector has zero length"):
        angle_between([0, 0, 0], [1, 0, 0])
    with pytest.raises(DegenerateGeometryError, match="the vector has zero length"):
        displace([0, 0, 0], [0, 0, 0], length=1.0)


def test_coincident_points_for_a_line() -> None:
    a = np.array([[100.0, 0, 0], [1, 2, 3], [5, 5, 5]])
    b = a + np.array([[1e-7, 0, 0], [0, 0, 0], [0, 0, 1e-12]])
    # trial 0 is 1e-9 relative (distinct), trials 1 and 2 coincide (<= 1e-10 relative)
    with pytest.raises(
        DegenerateGeometryError,
        match=r"field b: the two points coincide in 2 of 3 trials \(first: trial 1\); "
        "expected two distinct points",
    ):
        line_from_points(a, b)
    line_from_points(a[:1], b[:1])
    with pytest.raises(DegenerateGeometryError, match="in 1 of 1 trials"):
        line_from_points(a[:1], a[:1] + np.array([1e-9, 0, 0]))


def test_collinear_points_for_a_plane_and_a_circle() -> None:
    a = np.zeros((3, 3))
    b = np.array([[1.0, 0, 0], [1, 1, 1], [1, 0, 0]])
    c = np.array([[2.0, 0, 0], [0, 1, 0], [-3, 0, 1e-12]])
    msg = r"field c: the three points are collinear in 2 of 3 trials \(first: trial 0\)"
    with pytest.raises(
        DegenerateGeometryError, match=msg + "; expected three non-collinear points"
    ):
        plane_from_points(a, b, c)
    with pytest.raises(DegenerateGeometryError, match=msg):
        circle_from_points(a, b, c)


def test_line_parallel_to_plane() -> None:
    plane = Plane([0, 0, 0], [0, 0, 1])
    lines = Line(np.zeros((2, 3)), [[1, 0, 1], [1, 1, 1e-11]])
    with pytest.raises(
        DegenerateGeometryError,
        match=r"field line: the line is parallel to the plane in 1 of 2 trials \(first: trial 1\)",
    ):
        intersect_line_plane(lines, plane)


def test_parallel_planes() -> None:
    with pytest.raises(
        DegenerateGeometryError,
        match=r"field p2: the two planes are parallel in 1 of 1 trials .*expected two non-parallel",
    ):
        line_from_planes(Plane([0, 0, 0], [0, 0, 1]), Plane([0, 0, 5], [0, 0, -2]))


def test_frame_with_line_perpendicular_to_plane() -> None:
    with pytest.raises(DegenerateGeometryError, match="the line is perpendicular to the plane"):
        frame_from_plane_line_point(
            Plane([0, 0, 0], [0, 0, 1]), Line([1, 1, 1], [0, 0, 1]), [0, 0, 0]
        )


def test_nan_propagates_without_a_degenerate_error() -> None:
    a = np.array([[0.0, 0, 0], [np.nan, 0, 0]])
    plane = plane_from_points(a, [1, 0, 0], [0, 1, 0])
    assert_array_equal(plane.normal[0], [0, 0, 1])
    assert np.isnan(plane.normal[1]).all()
    assert np.isnan(unit_vector(a[1])).all()
    assert np.isnan(intersect_line_plane(Line(a, [0, 0, 1]), plane)[1]).all()


# --- properties ---------------------------------------------------------------------------


@settings(max_examples=40, deadline=None)
@given(seed=SEEDS)
def test_projection_lies_on_plane_and_offset_is_along_normal(seed: int) -> None:
    rng = _rng(seed)
    p, q = _points(rng, 2)
    plane = Plane(q, rng.normal(size=(M, 3)))
    x = project_point_plane(p, plane)
    assert_allclose(distance_point_plane(x, plane), 0.0, atol=1e-12)
    offset = p - x
    assert_allclose(np.cross(offset, plane.normal), 0.0, atol=1e-12)
    assert_allclose(
        np.linalg.norm(offset, axis=1), np.abs(distance_point_plane(p, plane)), atol=1e-12
    )


@settings(max_examples=40, deadline=None)
@given(seed=SEEDS)
def test_foot_of_perpendicular_makes_a_right_angle(seed: int) -> None:
    rng = _rng(seed)
    p, q = _points(rng, 2)
    line = Line(q, rng.normal(size=(M, 3)))
    f = foot_on_line(p, line)
    assert_allclose(np.einsum("mi,mi->m", p - f, line.direction), 0.0, atol=1e-11)
    assert_allclose(distance_point_line(f, line), 0.0, atol=1e-12)
    assert_allclose(
        distance_point_line(p, line), distance_point_point(p, f), rtol=1e-12, atol=1e-12
    )


@settings(max_examples=40, deadline=None)
@given(seed=SEEDS)
def test_distances_symmetric_and_triangle_inequality(seed: int) -> None:
    a, b, c = _points(_rng(seed), 3)
    assert_array_equal(distance_point_point(a, b), distance_point_point(b, a))
    assert np.all(
        distance_point_point(a, c)
        <= distance_point_point(a, b) + distance_point_point(b, c) + 1e-12
    )
    assert_allclose(angle_between(a, b), angle_between(b, a), rtol=0, atol=0)


@settings(max_examples=40, deadline=None)
@given(seed=SEEDS)
def test_intersections_lie_on_both_features(seed: int) -> None:
    rng = _rng(seed)
    a, b, c = _points(rng, 3)
    plane = plane_from_points(a, b, c)
    for x in (a, b, c):
        assert_allclose(distance_point_plane(x, plane), 0.0, atol=1e-10)
    line = Line(_points(rng), rng.normal(size=(M, 3)))
    x = intersect_line_plane(line, plane)
    assert_allclose(distance_point_plane(x, plane), 0.0, atol=1e-9)
    assert_allclose(distance_point_line(x, line), 0.0, atol=1e-9)
    other = Plane(_points(rng), rng.normal(size=(M, 3)))
    both = line_from_planes(plane, other)
    assert_allclose(distance_point_plane(both.point, plane), 0.0, atol=1e-10)
    assert_allclose(distance_point_plane(both.point, other), 0.0, atol=1e-10)
    assert_allclose(np.einsum("mi,mi->m", both.direction, plane.normal), 0.0, atol=1e-14)
    assert_allclose(np.einsum("mi,mi->m", both.direction, other.normal), 0.0, atol=1e-14)


@settings(max_examples=40, deadline=None)
@given(seed=SEEDS)
def test_circle_through_three_points(seed: int) -> None:
    a, b, c = _points(_rng(seed), 3)
    circ = circle_from_points(a, b, c)
    for x in (a, b, c):
        assert_allclose(distance_point_point(x, circ.centre), circ.radius, rtol=1e-10)
    assert_allclose(distance_point_plane(circ.centre, plane_from_points(a, b, c)), 0.0, atol=1e-10)
    assert_allclose(circ.normal, plane_from_points(a, b, c).normal, atol=1e-13)


@settings(max_examples=40, deadline=None)
@given(seed=SEEDS)
def test_frame_is_a_proper_rigid_transform_with_the_documented_axes(seed: int) -> None:
    rng = _rng(seed)
    plane = Plane(_points(rng), rng.normal(size=(M, 3)))
    line = Line(_points(rng), rng.normal(size=(M, 3)))
    point = _points(rng)
    T = frame_from_plane_line_point(plane, line, point)
    R = T[:, :3, :3]
    # x is the normalised projection of the line direction on the plane: its rounding
    # error, and so that of R^T R, grows like eps / sin(angle between line and normal)
    # (seed 290 draws sin = 0.026 and gives 1.8e-14); the bound is 9 eps / sin.
    sin = np.linalg.norm(np.cross(line.direction, plane.normal), axis=1)
    ortho = np.abs(np.matmul(R.transpose(0, 2, 1), R) - np.eye(3)).max(axis=(1, 2))
    assert np.all(ortho <= 2e-15 / sin), ortho * sin
    assert_allclose(np.linalg.det(R), 1.0, rtol=1e-14)
    assert_array_equal(T[:, 3, :], np.broadcast_to([0, 0, 0, 1.0], (M, 4)))
    assert_allclose(R[:, :, 2], plane.normal, atol=1e-15)
    d = line.direction
    proj = d - np.einsum("mi,mi->m", d, plane.normal)[:, None] * plane.normal
    x_ref = proj / np.linalg.norm(proj, axis=1)[:, None]
    assert np.all(np.abs(R[:, :, 0] - x_ref).max(axis=1) <= 4e-15 / sin)
    # the origin by a second method: the intersection of three planes, solved per trial:
    # the datum plane, the plane through the point across x, and the plane that holds the
    # line and the normal (so the projected line)
    n, x = plane.normal, x_ref
    a_mat = np.stack([n, x, np.cross(n, d)], axis=1)
    rhs = np.stack(
        [
            np.einsum("mi,mi->m", n, plane.point),
            np.einsum("mi,mi->m", x, point),
            np.einsum("mi,mi->m", np.cross(n, d), line.point),
        ],
        axis=1,
    )
    origin = np.linalg.solve(a_mat, rhs[..., None])[..., 0]
    err = np.abs(T[:, :3, 3] - origin).max(axis=1)
    assert np.all(err <= 1e-11 / sin), err * sin
    # the point, expressed in the new frame, has x = 0 (level with the origin)
    local = np.einsum("mji,mj->mi", R, point - T[:, :3, 3])
    assert_allclose(local[:, 0], 0.0, atol=1e-11)


@settings(max_examples=20, deadline=None)
@given(seed=SEEDS)
def test_batch_equals_one_at_a_time(seed: int) -> None:
    rng = _rng(seed)
    a, b, c = _points(rng, 3)
    batch = circle_from_points(a, b, c)
    frames = frame_from_plane_line_point(plane_from_points(a, b, c), line_from_points(a, c), b)
    for i in range(M):
        one = circle_from_points(a[i], b[i], c[i])
        assert_array_equal(one.centre[0], batch.centre[i])
        assert_array_equal(one.radius[0], batch.radius[i])
        f = frame_from_plane_line_point(
            plane_from_points(a[i], b[i], c[i]), line_from_points(a[i], c[i]), b[i]
        )
        assert_array_equal(f[0], frames[i])
