"""Tests of mtmc.geometry.transforms against scipy's Rotation and closed forms."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from mtmc.errors import DegenerateGeometryError, InputError
from mtmc.geometry.transforms import (
    apply_htm,
    axis_angle_from_matrix,
    cross_matrix,
    euler_from_matrix,
    htm,
    htm_inverse,
    matrix_from_axis_angle,
    matrix_from_euler,
    matrix_from_rotation_vector,
    quaternion_from_matrix,
    rotate_about_axis,
    rotation_vector_from_matrix,
    rotation_x,
    rotation_y,
    rotation_z,
    small_angle_rotate,
    small_angle_rotation,
    translation_htm,
)

SEQS = [a + b + c for a in "xyz" for b in "xyz" for c in "xyz" if a != b and b != c]
ALL_SEQS = SEQS + [s.upper() for s in SEQS]


def _random_rotations(rng: np.random.Generator, m: int) -> np.ndarray:
    return Rotation.random(m, random_state=rng).as_matrix()


def test_elementary_rotations_match_scipy() -> None:
    a = np.linspace(-3.0, 3.0, 13)
    for fn, ax in ((rotation_x, "x"), (rotation_y, "y"), (rotation_z, "z")):
        np.testing.assert_allclose(
            fn(a), Rotation.from_euler(ax, a[:, None]).as_matrix(), atol=1e-15
        )
    assert rotation_x(0.3).shape == (3, 3)
    assert rotation_z(np.zeros((2, 5))).shape == (2, 5, 3, 3)


@pytest.mark.parametrize("seq", ALL_SEQS)
def test_matrix_from_euler_matches_scipy(seq: str) -> None:
    rng = np.random.default_rng(np.random.SeedSequence(11))
    ang = rng.uniform(-np.pi, np.pi, size=(200, 3))
    np.testing.assert_allclose(
        matrix_from_euler(ang, seq), Rotation.from_euler(seq, ang).as_matrix(), atol=1e-14
    )


@pytest.mark.parametrize("seq", ALL_SEQS)
def test_euler_round_trip_batched(seq: str) -> None:
    rng = np.random.default_rng(np.random.SeedSequence(12))
    R = _random_rotations(rng, 500)
    ang = euler_from_matrix(R, seq)
    np.testing.assert_allclose(matrix_from_euler(ang, seq), R, atol=1e-12)
    # same angles as scipy away from gimbal lock
    np.testing.assert_allclose(ang, Rotation.from_matrix(R).as_euler(seq), atol=1e-9)


@pytest.mark.parametrize("seq", ["xyz", "ZYX", "zxz", "XZX"])
def test_euler_gimbal_lock(seq: str) -> None:
    proper = seq[0].lower() == seq[2].lower()
    mids = [0.0, np.pi] if proper else [np.pi / 2, -np.pi / 2]
    for mid in mids:
        ang = np.array([[0.4, mid, 0.0], [-1.0, mid, 0.0]])
        if not seq.islower():
            ang = np.array([[0.0, mid, 0.4], [0.0, mid, -1.0]])
        R = matrix_from_euler(ang, seq)
        back = euler_from_matrix(R, seq)
        np.testing.assert_allclose(matrix_from_euler(back, seq), R, atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3),
    st.floats(0.0, np.pi),
)
def test_axis_angle_round_trip(axis: list[float], angle: float) -> None:
    n = np.array(axis)
    if np.linalg.norm(n) < 1e-3:
        n = np.array([0.0, 0.0, 1.0])
    R = matrix_from_axis_angle(n, angle)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-14)
    np.testing.assert_allclose(
        R, Rotation.from_rotvec(n / np.linalg.norm(n) * angle).as_matrix(), atol=1e-14
    )
    ax, th = axis_angle_from_matrix(R)
    np.testing.assert_allclose(matrix_from_axis_angle(ax, th), R, atol=1e-12)
    assert 0.0 <= th <= np.pi + 1e-15


def test_axis_angle_batched_and_near_pi() -> None:
    rng = np.random.default_rng(np.random.SeedSequence(13))
    n = rng.normal(size=(1000, 3))
    th = rng.uniform(0.0, np.pi, size=1000)
    th[:10] = np.pi - 1e-12
    th[10:20] = 1e-12
    R = matrix_from_axis_angle(n, th)
    ax, th2 = axis_angle_from_matrix(R)
    np.testing.assert_allclose(th2, th, atol=1e-9)
    np.testing.assert_allclose(matrix_from_axis_angle(ax, th2), R, atol=1e-12)
    # zero angle: axis (0, 0, 1) by convention
    ax0, th0 = axis_angle_from_matrix(np.eye(3))
    np.testing.assert_array_equal(ax0, [0.0, 0.0, 1.0])
    assert th0 == 0.0


def test_rotation_vector_maps_match_scipy_and_invert_each_other() -> None:
    rng = np.random.default_rng(np.random.SeedSequence(17))
    phi = rng.normal(size=(500, 3))
    phi /= np.maximum(1.0, np.linalg.norm(phi, axis=-1, keepdims=True) / 3.0)  # below pi
    phi[:5] = 0.0
    phi[5:200] *= 10.0 ** rng.uniform(-9.0, -3.0, size=(195, 1))
    R = matrix_from_rotation_vector(phi)
    np.testing.assert_allclose(R, Rotation.from_rotvec(phi).as_matrix(), atol=1e-15)
    np.testing.assert_array_equal(R[:5], np.broadcast_to(np.eye(3), (5, 3, 3)))
    np.testing.assert_allclose(rotation_vector_from_matrix(R), phi, rtol=1e-9, atol=1e-15)
    # below 1e-4 rad the series: no step between it and the closed form at the switch
    below, above = matrix_from_rotation_vector([[1e-4 * (1.0 - 1e-12), 0.0, 0.0], [1e-4, 0, 0]])
    np.testing.assert_allclose(below, above, atol=1e-16)


def test_cross_matrix_is_the_cross_product() -> None:
    rng = np.random.default_rng(np.random.SeedSequence(19))
    v, u = rng.normal(size=(2, 40, 3))
    K = cross_matrix(v)
    np.testing.assert_allclose(np.einsum("mij,mj->mi", K, u), np.cross(v, u), atol=1e-15)
    np.testing.assert_array_equal(K, -np.swapaxes(K, -1, -2))


def test_quaternion_matches_scipy() -> None:
    rng = np.random.default_rng(np.random.SeedSequence(14))
    R = _random_rotations(rng, 1000)
    q = quaternion_from_matrix(R)
    ref = Rotation.from_matrix(R).as_quat()  # scalar last
    ref = np.concatenate([ref[:, 3:], ref[:, :3]], axis=1)
    ref = np.where(ref[:, :1] < 0, -ref, ref)
    np.testing.assert_allclose(q, ref, atol=1e-14)


def test_htm_inverse_and_apply() -> None:
    rng = np.random.default_rng(np.random.SeedSequence(15))
    R = _random_rotations(rng, 100)
    t = rng.normal(scale=100.0, size=(100, 3))
    T = htm(R, t)
    np.testing.assert_allclose(htm_inverse(T) @ T, np.broadcast_to(np.eye(4), T.shape), atol=1e-12)
    np.testing.assert_allclose(htm_inverse(T), np.linalg.inv(T), atol=1e-12)
    p = rng.normal(size=(100, 3))
    np.testing.assert_allclose(apply_htm(T, p), np.einsum("mij,mj->mi", R, p) + t, atol=1e-12)
    # one at a time equals the batch
    for m in (0, 17, 99):
        np.testing.assert_allclose(apply_htm(T[m], p[m]), apply_htm(T, p)[m], atol=1e-13)
    # sets of points per trial
    pts = rng.normal(size=(100, 7, 3))
    out = apply_htm(T, pts)
    assert out.shape == (100, 7, 3)
    np.testing.assert_allclose(out[5], pts[5] @ R[5].T + t[5], atol=1e-12)
    np.testing.assert_allclose(
        apply_htm(translation_htm([1.0, 2.0, 3.0]), pts[0]), pts[0] + [1, 2, 3]
    )


def test_small_angle_rotation_is_first_order() -> None:
    e = np.array([[2e-5, -3e-5, 4e-5]])
    S = small_angle_rotation(e[:, 0], e[:, 1], e[:, 2])
    for seq, ang in (("xyz", e), ("XYZ", e), ("zyx", e[:, ::-1]), ("ZYX", e[:, ::-1])):
        exact = matrix_from_euler(ang, seq)
        # difference is second order: |e|^2 ~ 3e-9
        assert np.max(np.abs(S - exact)) < 2.0 * np.sum(e**2)
    # S^T S = I + O(e^2)
    assert np.max(np.abs(S[0].T @ S[0] - np.eye(3))) < 2.0 * np.sum(e**2)
    # Aguado et al. 2016, eq. 12 prints the transpose (passive form)
    ea, eb, ec = 1e-4, 2e-4, 3e-4
    eq12 = np.array([[1, ec, -eb], [-ec, 1, ea], [eb, -ea, 1]])
    np.testing.assert_array_equal(small_angle_rotation(ea, eb, ec).T, eq12)


def test_not_a_rotation_is_refused_by_every_conversion() -> None:
    reflection = np.diag([1.0, 1.0, -1.0])
    twice = 2.0 * np.eye(3)
    sheared = np.eye(3)
    sheared[0, 1] = 1e-6
    for f in (
        quaternion_from_matrix,
        axis_angle_from_matrix,
        lambda r: euler_from_matrix(r, "xyz"),
    ):
        with pytest.raises(InputError, match=r"field R: .*got a reflection \(det -1\)"):
            f(reflection)
        with pytest.raises(InputError, match=r"field R: .*RᵀR − I\| <= 1e-09\), got one with 3"):
            f(twice)
        with pytest.raises(InputError, match=r"1e-06 in 1 of 2 matrices \(first: matrix 1\)"):
            f(np.stack([np.eye(3), sheared]))
        with pytest.raises(InputError, match="field R"):
            f(np.full((3, 3), np.nan))
    # a product of many exact rotations stays far inside the tolerance
    rng = np.random.default_rng(np.random.SeedSequence(11))
    R = np.linalg.multi_dot(list(_random_rotations(rng, 200)))
    ref = np.roll(Rotation.from_matrix(R).as_quat(), 1)  # scalar first
    np.testing.assert_allclose(quaternion_from_matrix(R), ref * np.sign(ref[0]), atol=1e-12)


def test_matrix_free_rotations_equal_the_matrices() -> None:
    rng = np.random.default_rng(np.random.SeedSequence(12))
    y = rng.normal(size=(5, 4, 3))
    ang = rng.uniform(-np.pi, np.pi, size=(5, 1))
    for axis, rot in enumerate((rotation_x, rotation_y, rotation_z)):
        R = rot(ang[:, 0])
        np.testing.assert_allclose(
            rotate_about_axis(axis, ang, y), np.einsum("mij,mkj->mki", R, y), atol=1e-14
        )
    e = rng.normal(scale=1e-4, size=(5, 1, 3))
    S = small_angle_rotation(e[:, 0, 0], e[:, 0, 1], e[:, 0, 2])
    for sign, M in ((1.0, S), (-1.0, np.swapaxes(S, -1, -2))):
        np.testing.assert_allclose(
            small_angle_rotate(e[..., 0], e[..., 1], e[..., 2], y, sign=sign),
            np.einsum("mij,mkj->mki", M, y),
            atol=1e-15,
        )


def test_bad_input_messages() -> None:
    with pytest.raises(InputError, match=r"field seq: .*three axis letters"):
        matrix_from_euler([0, 0, 0], "xy")
    with pytest.raises(InputError, match="all lower case"):
        matrix_from_euler([0, 0, 0], "xYz")
    with pytest.raises(InputError, match="consecutive axes"):
        matrix_from_euler([0, 0, 0], "xxz")
    with pytest.raises(InputError, match=r"field angles: expected an array of shape \(\.\.\., 3\)"):
        matrix_from_euler([0, 0], "xyz")
    with pytest.raises(InputError, match=r"field T: .*\(\.\.\., 4, 4\), got shape \(3, 3\)"):
        htm_inverse(np.eye(3))
    with pytest.raises(DegenerateGeometryError, match="zero-length rotation axis"):
        matrix_from_axis_angle([[0.0, 0.0, 0.0]], [1.0])
    with pytest.raises(InputError, match="field points"):
        apply_htm(np.eye(4), np.zeros((2, 2, 2, 3)))


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.floats(-np.pi, np.pi), min_size=3, max_size=3),
    st.lists(st.floats(-1e3, 1e3), min_size=3, max_size=3),
    st.sampled_from(ALL_SEQS),
)
def test_inverse_property(angles: list[float], t: list[float], seq: str) -> None:
    T = htm(matrix_from_euler(angles, seq), t)
    np.testing.assert_allclose(htm_inverse(T) @ T, np.eye(4), atol=1e-12)
    np.testing.assert_allclose(T @ htm_inverse(T), np.eye(4), atol=1e-12)
    p = np.array([1.0, -2.0, 3.0])
    np.testing.assert_allclose(apply_htm(htm_inverse(T), apply_htm(T, p)), p, atol=1e-9)
