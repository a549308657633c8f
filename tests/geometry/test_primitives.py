"""Tests of the batched primitives: shapes, coercion, broadcasting, indexing, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose, assert_array_equal

from mtmc.errors import DegenerateGeometryError, InputError
from mtmc.geometry import Circle, Line, Plane, Sphere
from mtmc.geometry.checks import check_frames, check_point_sets, check_scalars


def test_single_point_is_a_batch_of_one_and_direction_is_normalised() -> None:
    line = Line([1, 2, 3], [0, 0, 2])
    assert len(line) == 1
    assert line.point.dtype == np.float64
    assert_array_equal(line.point, [[1.0, 2.0, 3.0]])
    assert_array_equal(line.direction, [[0.0, 0.0, 1.0]])


def test_batch_of_one_broadcasts_against_batch_of_m() -> None:
    d = np.array([[1.0, 0, 0], [0, 3, 0], [0, 0, -2]])
    line = Line([5, 5, 5], d)
    assert len(line) == 3
    assert_array_equal(line.point, np.tile([5.0, 5, 5], (3, 1)))
    assert_array_equal(line.direction, [[1, 0, 0], [0, 1, 0], [0, 0, -1]])
    circ = Circle(np.zeros((4, 3)), [0, 0, 1], 2.0)
    assert len(circ) == 4
    assert circ.radius.shape == (4,)
    assert circ.normal.shape == (4, 3)


def test_plane_offset_is_eq_29() -> None:
    # D = -I x1 - J y1 - K z1 (Stryczek eq. 29) for the plane x + y + z = 1.
    plane = Plane([1, 0, 0], [1, 1, 1])
    assert_allclose(plane.offset, [-1 / math.sqrt(3)], rtol=1e-15)
    assert_allclose(plane.normal, [[1 / math.sqrt(3)] * 3], rtol=1e-15)


def test_line_at_and_circle_plane() -> None:
    line = Line([[0, 0, 0], [1, 1, 1]], [[1, 0, 0], [0, 0, 1]])
    assert_array_equal(line.at([2.0, -1.0]), [[2, 0, 0], [1, 1, 0]])
    circ = Circle([1, 2, 3], [0, 2, 0], 4.0)
    assert_array_equal(circ.plane.point, [[1, 2, 3]])
    assert_array_equal(circ.plane.normal, [[0, 1, 0]])


def test_indexing_gives_sub_batches() -> None:
    rng = np.random.default_rng(np.random.SeedSequence(11))
    s = Sphere(rng.normal(size=(6, 3)), rng.uniform(1, 2, size=6))
    one = s[2]
    assert len(one) == 1
    assert_array_equal(one.centre, s.centre[2:3])
    assert_array_equal(s[-1].radius, s.radius[5:6])
    assert len(s[1:4]) == 3
    mask = np.array([True, False, True, False, False, True])
    assert_array_equal(s[mask].centre, s.centre[mask])
    assert_array_equal(s[[0, 0]].radius, s.radius[[0, 0]])
    with pytest.raises(IndexError, match="trial index 6 out of range for a batch of 6"):
        s[6]


def test_bad_shape_names_field_and_shapes() -> None:
    with pytest.raises(
        InputError, match=r"field point: expected shape \(M, 3\) or \(3,\), got \(2, 2\)"
    ):
        Line(np.zeros((2, 2)), [0, 0, 1])
    with pytest.raises(InputError, match=r"field radius: expected shape \(M,\) or a number, got"):
        Sphere([0, 0, 0], np.ones((2, 2)))
    with pytest.raises(InputError, match="field normal: expected an array of real numbers"):
        Plane([0, 0, 0], "up")  # type: ignore[arg-type]


def test_batch_mismatch() -> None:
    with pytest.raises(
        InputError, match=r"field direction: expected 4 trials \(as in point\) or 1, got 3"
    ):
        Line(np.zeros((4, 3)), np.ones((3, 3)))


def test_zero_direction_is_degenerate_with_count() -> None:
    d = np.array([[1.0, 0, 0], [0, 0, 0], [0, 0, 0]])
    with pytest.raises(
        DegenerateGeometryError,
        match=r"field direction: the line direction has zero length in 2 of 3 trials "
        r"\(first: trial 1\); expected a non-zero line direction",
    ):
        Line(np.zeros((3, 3)), d)
    with pytest.raises(DegenerateGeometryError, match="the plane normal has zero length"):
        Plane([0, 0, 0], [0, 0, 0])


def test_negative_radius_refused_nan_propagates() -> None:
    with pytest.raises(
        InputError, match=r"field radius: expected a radius >= 0 mm, got -1.0 in 1 of 2"
    ):
        Sphere(np.zeros((2, 3)), [1.0, -1.0])
    # NaN propagates (it is not a negative radius)
    assert np.isnan(Circle([0, 0, 0], [0, 0, 1], math.nan).radius).all()
    assert np.isnan(Line([0, 0, 0], [math.nan, 0, 1]).direction).all()


def test_checkers() -> None:
    assert check_scalars(3).shape == (1,)
    assert check_frames(np.eye(4)).shape == (1, 4, 4)
    with pytest.raises(
        InputError, match=r"field frames: expected shape \(M, 4, 4\) or \(4, 4\), got \(3, 3\)"
    ):
        check_frames(np.eye(3))
    assert check_point_sets(np.zeros((5, 3))).shape == (1, 5, 3)
    with pytest.raises(
        InputError, match=r"expected shape \(M, n, 3\) or \(n, 3\), got \(2, 5, 2\)"
    ):
        check_point_sets(np.zeros((2, 5, 2)))
    bad = np.zeros((3, 4, 3))
    bad[2, 1, 0] = np.nan
    with pytest.raises(
        InputError, match=r"got NaN or infinity in 1 of 3 trials \(first: trial 2\)"
    ):
        check_point_sets(bad)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), m=st.integers(1, 12))
def test_getitem_matches_array_indexing(seed: int, m: int) -> None:
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    c = Circle(rng.normal(size=(m, 3)), rng.normal(size=(m, 3)), rng.uniform(0, 5, size=m))
    idx = rng.permutation(m)[: max(1, m // 2)]
    sub = c[idx]
    assert_array_equal(sub.centre, c.centre[idx])
    assert_array_equal(sub.normal, c.normal[idx])
    assert_array_equal(sub.radius, c.radius[idx])
    assert_allclose(np.linalg.norm(c.normal, axis=1), 1.0, rtol=1e-15)


def test_unit_rows_normalise_as_a_line_does() -> None:
    from mtmc.geometry.primitives import unit_rows

    rng = np.random.default_rng(3)
    v = rng.normal(size=(5000, 3)) * 10.0 ** rng.uniform(-6, 6, size=(5000, 1))
    v[0] = [0.0, 0.6, 0.8]  # unit already: kept as it is
    rows = unit_rows(np.ascontiguousarray(v.T), "direction", "line direction")
    assert_array_equal(rows.T, Line(np.zeros(3), v).direction)
    line = Line.of_unit(np.zeros((5000, 3)), np.ascontiguousarray(rows.T))
    assert not line.direction.flags.writeable
    with pytest.raises(DegenerateGeometryError, match="line direction has zero length"):
        unit_rows(np.zeros((3, 2)), "direction", "line direction")
