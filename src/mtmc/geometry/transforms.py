"""Homogeneous transforms and rotations, batched.

Conventions (see ``docs/conventions.md``): right-handed frames; rotation matrices are
*active* (``R @ v`` rotates the vector ``v``, expressed in a fixed frame); vectors are
columns and transforms compose by *pre*-multiplication, so ``T_a2c = T_b2c @ T_a2b``.
A homogeneous transform (HTM) is the ``4 x 4`` matrix ``[[R, t], [0, 0, 0, 1]]``; applied
to a point ``p`` it gives ``R p + t``.

Every function accepts any number of leading (batch) axes: the trial axis comes first,
geometric axes last. An angle of shape ``(M,)`` gives rotations of shape ``(M, 3, 3)``; a
scalar gives one ``(3, 3)`` matrix. Angles are in radians, lengths in millimetres.

Examples
--------
>>> import numpy as np
>>> R = rotation_z(np.array([np.pi / 2]))
>>> np.round(R[0] @ np.array([1.0, 0.0, 0.0]), 12) + 0.0
array([0., 1., 0.])
>>> T = htm(R, np.array([[10.0, 0.0, 0.0]]))
>>> np.round(apply_htm(T, np.array([[1.0, 0.0, 0.0]])), 12) + 0.0
array([[10.,  1.,  0.]])
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import DegenerateGeometryError, InputError
from mtmc.geometry.checks import as_float, check_rotation_matrices

__all__ = [
    "rotation_x",
    "rotation_y",
    "rotation_z",
    "htm",
    "htm_inverse",
    "translation_htm",
    "small_angle_rotation",
    "small_angle_rotate",
    "rotate_about_axis",
    "matrix_from_euler",
    "euler_from_matrix",
    "matrix_from_axis_angle",
    "axis_angle_from_matrix",
    "matrix_from_rotation_vector",
    "rotation_vector_from_matrix",
    "cross_matrix",
    "quaternion_from_matrix",
    "apply_htm",
]

_AXIS_INDEX = {"x": 0, "y": 1, "z": 2}


def _check_trailing(arr: NDArray[np.float64], shape: tuple[int, ...], name: str) -> None:
    k = len(shape)
    if arr.ndim < k or arr.shape[arr.ndim - k :] != shape:
        want = "(..., " + ", ".join(str(s) for s in shape) + ")"
        raise InputError(f"expected an array of shape {want}, got shape {arr.shape}", field=name)


def rotate_about_axis(
    axis: int, angle: npt.ArrayLike, y: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Rotate vectors ``y`` about the coordinate axis ``axis`` by ``angle`` (active, exact).

    The matrix-free form of :func:`rotation_x` / :func:`rotation_y` / :func:`rotation_z`,
    which the kinematic chain applies to ``(M, K, 3)`` arrays of points.

    Parameters
    ----------
    axis : int
        0, 1 or 2 for x, y or z.
    angle : array_like
        Angles in rad, broadcasting against ``y[..., 0]`` (e.g. ``()`` or ``(M, 1)``).
    y : ndarray, shape (..., 3)
        The vectors.

    Returns
    -------
    ndarray, shape (..., 3)
        ``R(angle) y``, a new array.

    Examples
    --------
    >>> np.round(rotate_about_axis(2, np.pi / 2, np.array([1.0, 0.0, 0.0])), 12) + 0.0
    array([0., 1., 0.])
    """
    c, s = np.cos(angle), np.sin(angle)
    i, k = (axis + 1) % 3, (axis + 2) % 3
    out = (
        y.copy()
        if np.ndim(c) == 0
        else np.broadcast_to(y, np.broadcast_shapes(y.shape, (*np.shape(c), 3))).copy()
    )
    yi, yk = y[..., i], y[..., k]
    out[..., i] = c * yi - s * yk
    out[..., k] = s * yi + c * yk
    return out


def _as_matrix(columns: NDArray[np.float64]) -> NDArray[np.float64]:
    """The matrix whose column j is ``columns[..., j, :]`` (the image of e_j)."""
    return np.ascontiguousarray(np.swapaxes(columns, -1, -2))


def _elementary(angle: npt.ArrayLike, axis: int) -> NDArray[np.float64]:
    a = as_float(angle, "angle")
    return _as_matrix(rotate_about_axis(axis, a[..., None], np.eye(3)))


def rotation_x(angle: npt.ArrayLike) -> NDArray[np.float64]:
    """Active rotation about the x axis.

    Parameters
    ----------
    angle : array_like, shape (...,)
        Rotation angle in rad, positive counter-clockwise looking down +x (right-hand rule).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``[[1, 0, 0], [0, c, -s], [0, s, c]]`` with ``c = cos(angle)``, ``s = sin(angle)``.

    Examples
    --------
    >>> np.round(rotation_x(np.pi / 2) @ [0.0, 1.0, 0.0], 12) + 0.0
    array([0., 0., 1.])
    """
    return _elementary(angle, 0)


def rotation_y(angle: npt.ArrayLike) -> NDArray[np.float64]:
    """Active rotation about the y axis.

    Parameters
    ----------
    angle : array_like, shape (...,)
        Rotation angle in rad (right-hand rule about +y).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``[[c, 0, s], [0, 1, 0], [-s, 0, c]]``.

    Examples
    --------
    >>> np.round(rotation_y(np.pi / 2) @ [0.0, 0.0, 1.0], 12) + 0.0
    array([1., 0., 0.])
    """
    return _elementary(angle, 1)


def rotation_z(angle: npt.ArrayLike) -> NDArray[np.float64]:
    """Active rotation about the z axis.

    Parameters
    ----------
    angle : array_like, shape (...,)
        Rotation angle in rad (right-hand rule about +z).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``[[c, -s, 0], [s, c, 0], [0, 0, 1]]``.

    Examples
    --------
    >>> np.round(rotation_z(np.pi / 2) @ [1.0, 0.0, 0.0], 12) + 0.0
    array([0., 1., 0.])
    """
    return _elementary(angle, 2)


def htm(rotation: npt.ArrayLike, translation: npt.ArrayLike) -> NDArray[np.float64]:
    """Homogeneous transform from a rotation and a translation.

    Parameters
    ----------
    rotation : array_like, shape (..., 3, 3)
        Rotation matrices (not checked for orthogonality: small-angle error matrices are
        accepted as they are).
    translation : array_like, shape (..., 3)
        Translations in mm. The batch shapes of both arguments broadcast.

    Returns
    -------
    ndarray, shape (..., 4, 4)
        ``[[R, t], [0, 0, 0, 1]]``, mapping ``p`` to ``R p + t``.

    Raises
    ------
    InputError
        If the trailing shapes are not ``(3, 3)`` and ``(3,)``.
    """
    R = as_float(rotation, "rotation")
    t = as_float(translation, "translation")
    _check_trailing(R, (3, 3), "rotation")
    _check_trailing(t, (3,), "translation")
    batch = np.broadcast_shapes(R.shape[:-2], t.shape[:-1])
    out = np.zeros((*batch, 4, 4))
    out[..., :3, :3] = R
    out[..., :3, 3] = t
    out[..., 3, 3] = 1.0
    return out


def translation_htm(translation: npt.ArrayLike) -> NDArray[np.float64]:
    """Pure translation as a homogeneous transform.

    Parameters
    ----------
    translation : array_like, shape (..., 3)
        Translation in mm.

    Returns
    -------
    ndarray, shape (..., 4, 4)
        ``[[I, t], [0, 0, 0, 1]]``.
    """
    t = as_float(translation, "translation")
    _check_trailing(t, (3,), "translation")
    return htm(np.eye(3), t)


def htm_inverse(T: npt.ArrayLike) -> NDArray[np.float64]:
    """Inverse of rigid homogeneous transforms.

    Parameters
    ----------
    T : array_like, shape (..., 4, 4)
        Rigid transforms ``[[R, t], [0, 1]]`` with orthonormal ``R``.

    Returns
    -------
    ndarray, shape (..., 4, 4)
        ``[[R^T, -R^T t], [0, 1]]``. For a transform whose ``R`` is not orthonormal (a
        small-angle error matrix) use :func:`numpy.linalg.inv` instead.

    Raises
    ------
    InputError
        If the trailing shape is not ``(4, 4)``.
    """
    A = as_float(T, "T")
    _check_trailing(A, (4, 4), "T")
    Rt = np.swapaxes(A[..., :3, :3], -1, -2)
    t = A[..., :3, 3]
    return htm(Rt, -np.einsum("...ij,...j->...i", Rt, t))


def small_angle_rotation(
    ea: npt.ArrayLike, eb: npt.ArrayLike, ec: npt.ArrayLike
) -> NDArray[np.float64]:
    """First-order rotation matrix for small angles about x, y and z.

    Parameters
    ----------
    ea, eb, ec : array_like, shape (...,)
        Small rotations in rad about x, y and z (ISO 230-1 ``EA``, ``EB``, ``EC``); the
        three broadcast together.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``I + [e]x = [[1, -ec, eb], [ec, 1, -ea], [-eb, ea, 1]]``, the first-order
        expansion of any sequence of the three elementary rotations.

    Notes
    -----
    Aguado et al. 2016, eq. (12) prints the transpose,
    ``[[1, EC, -EB], [-EC, 1, EA], [EB, -EA, 1]]``:
    that matrix changes the coordinates of a point into a frame rotated by the errors
    (passive form). mtmc uses active rotations throughout; the transposed (passive) form
    is ``small_angle_rotation(-ea, -eb, -ec)``. See ``docs/conventions.md``.

    Examples
    --------
    >>> small_angle_rotation(0.0, 0.0, 1e-3)
    array([[ 1.   , -0.001,  0.   ],
           [ 0.001,  1.   ,  0.   ],
           [ 0.   ,  0.   ,  1.   ]])
    """
    a, b, c = np.broadcast_arrays(as_float(ea, "ea"), as_float(eb, "eb"), as_float(ec, "ec"))
    return _as_matrix(small_angle_rotate(a[..., None], b[..., None], c[..., None], np.eye(3)))


def small_angle_rotate(
    ea: npt.ArrayLike,
    eb: npt.ArrayLike,
    ec: npt.ArrayLike,
    y: NDArray[np.float64],
    *,
    sign: float = 1.0,
) -> NDArray[np.float64]:
    """Apply the first-order rotation ``I + sign [e]x`` to vectors: ``y + sign (e × y)``.

    The one implementation of the small-angle convention of mtmc: :func:`small_angle_rotation`
    is this applied to the unit vectors, the kinematic chain applies it to points, and the
    symbolic chain (:mod:`mtmc.kinematics.symbolic`) writes the same matrix.

    Parameters
    ----------
    ea, eb, ec : array_like
        Small rotations in rad about x, y and z, broadcasting against ``y[..., 0]``.
    y : ndarray, shape (..., 3)
        The vectors.
    sign : float
        +1 for ``I + [e]x``; -1 for its transpose ``I - [e]x`` (the passive form, and the
        first-order inverse).

    Returns
    -------
    ndarray, shape (..., 3)
        A new array.

    Examples
    --------
    >>> small_angle_rotate(0.0, 0.0, 1e-3, np.array([1.0, 0.0, 0.0]))
    array([1.   , 0.001, 0.   ])
    """
    a, b, c = (np.asarray(v, dtype=np.float64) for v in (ea, eb, ec))
    yx, yy, yz = y[..., 0], y[..., 1], y[..., 2]
    out = np.empty(
        np.broadcast_shapes(y.shape, (*np.shape(a), 3), (*np.shape(b), 3), (*np.shape(c), 3))
    )
    out[..., 0] = yx + sign * (b * yz - c * yy)
    out[..., 1] = yy + sign * (c * yx - a * yz)
    out[..., 2] = yz + sign * (a * yy - b * yx)
    return out


def _parse_seq(seq: str) -> tuple[list[int], bool]:
    """Return (axis indices in the order applied, extrinsic?)."""
    if not isinstance(seq, str) or len(seq) != 3:
        raise InputError(
            f"expected an Euler sequence of three axis letters such as 'xyz' (extrinsic) or "
            f"'ZYX' (intrinsic), got {seq!r}",
            field="seq",
        )
    if seq.islower() == seq.isupper() or seq.lower().strip("xyz") != "":
        raise InputError(
            f"expected three letters from x, y, z, all lower case (extrinsic) or all upper "
            f"case (intrinsic), got {seq!r}",
            field="seq",
        )
    idx = [_AXIS_INDEX[ch] for ch in seq.lower()]
    if idx[0] == idx[1] or idx[1] == idx[2]:
        raise InputError(
            f"expected consecutive axes to differ in the Euler sequence, got {seq!r}",
            field="seq",
        )
    return idx, seq.islower()


def matrix_from_euler(angles: npt.ArrayLike, seq: str) -> NDArray[np.float64]:
    """Rotation matrix from three Euler angles.

    Parameters
    ----------
    angles : array_like, shape (..., 3)
        The three angles in rad, in the order of ``seq``.
    seq : str
        Three axis letters. Lower case (``"xyz"``) means *extrinsic* rotations about the
        fixed axes, applied in the order written: ``R = R_3(a3) R_2(a2) R_1(a1)``. Upper
        case (``"XYZ"``) means *intrinsic* rotations about the moving axes:
        ``R = R_1(a1) R_2(a2) R_3(a3)``. This is the convention of
        :class:`scipy.spatial.transform.Rotation`. Proper Euler (``"zxz"``) and
        Tait–Bryan (``"xyz"``) sequences are both accepted.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Raises
    ------
    InputError
        If ``seq`` is not a valid sequence or ``angles`` does not end in 3.

    Examples
    --------
    >>> R = matrix_from_euler([0.1, 0.2, 0.3], "xyz")
    >>> np.allclose(R, rotation_z(0.3) @ rotation_y(0.2) @ rotation_x(0.1))
    True
    """
    idx, extrinsic = _parse_seq(seq)
    a = as_float(angles, "angles")
    _check_trailing(a, (3,), "angles")
    mats = [_elementary(a[..., k], idx[k]) for k in range(3)]
    if extrinsic:
        return mats[2] @ mats[1] @ mats[0]
    return mats[0] @ mats[1] @ mats[2]


def quaternion_from_matrix(R: npt.ArrayLike) -> NDArray[np.float64]:
    """Unit quaternion ``(w, x, y, z)`` of rotation matrices, with ``w >= 0``.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrices.

    Returns
    -------
    ndarray, shape (..., 4)
        Scalar-first unit quaternions. Computed by Shepperd's method: the largest of
        ``1 + tr R``, ``1 + 2 R_ii - tr R`` gives the pivot component, so the result is
        accurate for every angle including pi.

    Raises
    ------
    InputError
        If the trailing shape is not ``(3, 3)`` or a matrix is not a rotation (a
        reflection, or ``max |RᵀR − I| > ORTHO_TOL = 1e-9``; see
        :func:`mtmc.geometry.checks.check_rotation_matrices`).
    """
    M = check_rotation_matrices(R, "R")
    tr = M[..., 0, 0] + M[..., 1, 1] + M[..., 2, 2]
    cand = np.stack([tr, M[..., 0, 0], M[..., 1, 1], M[..., 2, 2]], axis=-1)
    pivot = np.argmax(cand, axis=-1)
    q = np.empty((*M.shape[:-2], 4))
    # pivot w
    w4 = np.stack(
        [
            1.0 + tr,
            M[..., 2, 1] - M[..., 1, 2],
            M[..., 0, 2] - M[..., 2, 0],
            M[..., 1, 0] - M[..., 0, 1],
        ],
        axis=-1,
    )
    x4 = np.stack(
        [
            M[..., 2, 1] - M[..., 1, 2],
            1.0 + 2.0 * M[..., 0, 0] - tr,
            M[..., 0, 1] + M[..., 1, 0],
            M[..., 0, 2] + M[..., 2, 0],
        ],
        axis=-1,
    )
    y4 = np.stack(
        [
            M[..., 0, 2] - M[..., 2, 0],
            M[..., 0, 1] + M[..., 1, 0],
            1.0 + 2.0 * M[..., 1, 1] - tr,
            M[..., 1, 2] + M[..., 2, 1],
        ],
        axis=-1,
    )
    z4 = np.stack(
        [
            M[..., 1, 0] - M[..., 0, 1],
            M[..., 0, 2] + M[..., 2, 0],
            M[..., 1, 2] + M[..., 2, 1],
            1.0 + 2.0 * M[..., 2, 2] - tr,
        ],
        axis=-1,
    )
    allq = np.stack([w4, x4, y4, z4], axis=-2)  # (..., 4 pivots, 4 comps)
    q = np.take_along_axis(allq, pivot[..., None, None], axis=-2)[..., 0, :]
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    out: NDArray[np.float64] = np.where(q[..., :1] < 0.0, -q, q)
    return out


def euler_from_matrix(R: npt.ArrayLike, seq: str) -> NDArray[np.float64]:
    """Euler angles of rotation matrices, the inverse of :func:`matrix_from_euler`.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrices.
    seq : str
        As in :func:`matrix_from_euler` (lower case extrinsic, upper case intrinsic).

    Returns
    -------
    ndarray, shape (..., 3)
        Angles in rad. The first and third lie in ``[-pi, pi]``; the second in
        ``[0, pi]`` for proper Euler sequences and ``[-pi/2, pi/2]`` for Tait–Bryan ones.
        At gimbal lock (second angle 0 or pi, resp. +-pi/2) the third angle is set to 0.

    Raises
    ------
    InputError
        If ``seq`` is not a valid sequence, or ``R`` is not of shape (..., 3, 3) or not a
        rotation (as for :func:`quaternion_from_matrix`).

    Notes
    -----
    Computed from the quaternion of ``R`` by the direct general method of Bernardes and
    Viollet (PLoS ONE 17(11), 2022), valid for all twelve sequences.

    Examples
    --------
    >>> R = matrix_from_euler([0.1, -0.2, 0.3], "ZYX")
    >>> np.round(euler_from_matrix(R, "ZYX"), 12)
    array([ 0.1, -0.2,  0.3])
    """
    idx, extrinsic = _parse_seq(seq)
    q = quaternion_from_matrix(R)
    if not extrinsic:
        idx = idx[::-1]
    i, j, k = idx
    proper = i == k
    if proper:
        k = 3 - i - j
    eps = (i - j) * (j - k) * (k - i) / 2.0
    w = q[..., 0]
    qi, qj, qk = q[..., 1 + i], q[..., 1 + j], q[..., 1 + k]
    if proper:
        a, b, c, d = w, qi, qj, qk * eps
    else:
        a, b, c, d = w - qj, qi + qk * eps, qj + w, qk * eps - qi
    t2 = 2.0 * np.arctan2(np.hypot(c, d), np.hypot(a, b))
    tp = np.arctan2(b, a)
    tm = np.arctan2(d, c)
    tol = 1e-7
    lock0 = np.abs(t2) <= tol
    lockpi = np.abs(t2 - np.pi) <= tol
    t1 = np.where(lock0, 2.0 * tp, np.where(lockpi, -2.0 * tm, tp - tm))
    t3 = np.where(lock0 | lockpi, 0.0, tp + tm)
    if not proper:
        t3 = eps * t3
        t2 = t2 - np.pi / 2.0
    t1 = (t1 + np.pi) % (2.0 * np.pi) - np.pi
    t3 = (t3 + np.pi) % (2.0 * np.pi) - np.pi
    out = np.stack([t1, t2, t3], axis=-1)
    if not extrinsic:
        out = out[..., ::-1]
    return np.ascontiguousarray(out)


def matrix_from_axis_angle(axis: npt.ArrayLike, angle: npt.ArrayLike) -> NDArray[np.float64]:
    """Rotation matrix from an axis and an angle (Rodrigues' formula).

    Parameters
    ----------
    axis : array_like, shape (..., 3)
        Rotation axis; normalised here, must not be zero.
    angle : array_like, shape (...,)
        Rotation angle in rad (right-hand rule about ``axis``). Batch shapes broadcast.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``R = I + sin(theta) K + (1 - cos(theta)) K^2`` with ``K = [n]x`` the cross-product
        matrix of the unit axis ``n``.

    Raises
    ------
    DegenerateGeometryError
        If an axis has zero length.
    InputError
        If ``axis`` does not end in 3.

    Examples
    --------
    >>> np.allclose(matrix_from_axis_angle([0, 0, 2.0], 0.3), rotation_z(0.3))
    True
    """
    n = as_float(axis, "axis")
    _check_trailing(n, (3,), "axis")
    th = as_float(angle, "angle")
    norm = np.linalg.norm(n, axis=-1, keepdims=True)
    if np.any(norm == 0.0):
        raise DegenerateGeometryError(
            "zero-length rotation axis: expected a non-zero vector", field="axis"
        )
    K = cross_matrix(n / norm)
    s = np.sin(th)[..., None, None]
    c = np.cos(th)[..., None, None]
    out: NDArray[np.float64] = np.eye(3) + s * K + (1.0 - c) * (K @ K)
    return out


def matrix_from_rotation_vector(phi: npt.ArrayLike) -> NDArray[np.float64]:
    """Rotation matrices of rotation vectors (the exponential map ``Exp(φ)``, Rodrigues).

    Parameters
    ----------
    phi : array_like, shape (..., 3)
        Rotation vectors (rad): the axis times the angle; zero gives the identity.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``R = I + a K + b K^2`` with ``K = [φ]x``, ``θ = |φ|``, ``a = sin(θ) / θ`` and
        ``b = (1 - cos(θ)) / θ^2``; below ``θ = 1e-4`` rad ``a`` and ``b`` are their series
        ``1 - θ²/6`` and ``1/2 - θ²/24``, so the map is exact at zero and smooth about it
        (the parametrisation of small rotations that a least-squares fit steps through).

    See Also
    --------
    rotation_vector_from_matrix : the inverse (the logarithmic map).
    matrix_from_axis_angle : the same rotation from a unit axis and an angle.

    Examples
    --------
    >>> np.allclose(matrix_from_rotation_vector([0.0, 0.0, 0.3]), rotation_z(0.3))
    True
    >>> matrix_from_rotation_vector([0.0, 0.0, 0.0])
    array([[1., 0., 0.],
           [0., 1., 0.],
           [0., 0., 1.]])
    """
    p = np.asarray(phi, dtype=np.float64)
    th2 = np.sum(p * p, axis=-1)
    th = np.sqrt(th2)
    small = th < 1e-4
    ths = np.where(small, 1.0, th)
    a = np.where(small, 1.0 - th2 / 6.0, np.sin(ths) / ths)
    b = np.where(small, 0.5 - th2 / 24.0, (1.0 - np.cos(ths)) / (ths * ths))
    K = cross_matrix(p)
    eye = np.broadcast_to(np.eye(3), K.shape)
    out: NDArray[np.float64] = eye + a[..., None, None] * K + b[..., None, None] * (K @ K)
    return out


def rotation_vector_from_matrix(R: npt.ArrayLike) -> NDArray[np.float64]:
    """Rotation vectors (axis times angle, rad) of rotation matrices, the logarithmic map.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrices.

    Returns
    -------
    ndarray, shape (..., 3)
        ``φ = θ n`` from :func:`axis_angle_from_matrix`, ``θ`` in ``[0, pi]``; the inverse of
        :func:`matrix_from_rotation_vector` for ``|φ| < pi``.

    Raises
    ------
    InputError
        As for :func:`axis_angle_from_matrix`.

    Examples
    --------
    >>> np.round(rotation_vector_from_matrix(rotation_x(0.25)), 12) + 0.0
    array([0.25, 0.  , 0.  ])
    """
    ax, ang = axis_angle_from_matrix(np.asarray(R, dtype=np.float64))
    return np.asarray(ax) * np.asarray(ang)[..., None]


def cross_matrix(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """The cross-product (skew-symmetric) matrices ``[v]x`` of vectors: ``[v]x u = v × u``.

    Parameters
    ----------
    v : ndarray, shape (..., 3)
        The vectors.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``[[0, -v_z, v_y], [v_z, 0, -v_x], [-v_y, v_x, 0]]``.

    Examples
    --------
    >>> cross_matrix(np.array([1.0, 2.0, 3.0])) @ np.array([0.0, 0.0, 1.0])
    array([ 2., -1.,  0.])
    """
    K = np.zeros((*v.shape[:-1], 3, 3))
    K[..., 0, 1], K[..., 0, 2] = -v[..., 2], v[..., 1]
    K[..., 1, 0], K[..., 1, 2] = v[..., 2], -v[..., 0]
    K[..., 2, 0], K[..., 2, 1] = -v[..., 1], v[..., 0]
    return K


def axis_angle_from_matrix(
    R: npt.ArrayLike,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Axis and angle of rotation matrices, the inverse of :func:`matrix_from_axis_angle`.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrices.

    Returns
    -------
    axis : ndarray, shape (..., 3)
        Unit axis; ``(0, 0, 1)`` where the angle is zero (any axis would do).
    angle : ndarray, shape (...,)
        Angle in rad in ``[0, pi]``.

    Raises
    ------
    InputError
        If the trailing shape is not ``(3, 3)`` or a matrix is not a rotation (as for
        :func:`quaternion_from_matrix`).

    Notes
    -----
    From the quaternion ``(w, v)`` with ``w >= 0``: ``angle = 2 atan2(|v|, w)``,
    ``axis = v / |v|``; accurate near 0 and near pi, unlike ``acos((tr R - 1) / 2)``.

    Examples
    --------
    >>> ax, th = axis_angle_from_matrix(rotation_x(0.25))
    >>> np.round(ax, 12) + 0.0, np.round(th, 12)
    (array([1., 0., 0.]), np.float64(0.25))
    """
    q = quaternion_from_matrix(R)
    v = q[..., 1:]
    s = np.linalg.norm(v, axis=-1)
    angle = 2.0 * np.arctan2(s, q[..., 0])
    safe = np.where(s > 0.0, s, 1.0)[..., None]
    axis = np.where((s > 0.0)[..., None], v / safe, np.array([0.0, 0.0, 1.0]))
    return axis, angle


def apply_htm(T: npt.ArrayLike, points: npt.ArrayLike) -> NDArray[np.float64]:
    """Apply homogeneous transforms to points.

    Parameters
    ----------
    T : array_like, shape (..., 4, 4)
        Transforms.
    points : array_like, shape (..., 3) or (..., n, 3)
        Points in mm. If ``points.ndim == T.ndim - 1`` each transform maps the point of
        the same batch index (``T (M, 4, 4)`` with ``points (M, 3)``); if
        ``points.ndim == T.ndim`` each transform maps a set of ``n`` points
        (``T (M, 4, 4)`` with ``points (M, n, 3)``, or one ``T (4, 4)`` with ``(n, 3)``).
        Batch shapes broadcast.

    Returns
    -------
    ndarray
        ``R p + t`` with the shape of the broadcast points.

    Raises
    ------
    InputError
        If the trailing shapes are not ``(4, 4)`` and ``(3,)``, or the ranks do not fit.
    """
    A = as_float(T, "T")
    p = as_float(points, "points")
    _check_trailing(A, (4, 4), "T")
    _check_trailing(p, (3,), "points")
    R = A[..., :3, :3]
    t = A[..., :3, 3]
    if p.ndim == A.ndim - 1:
        out: NDArray[np.float64] = np.einsum("...ij,...j->...i", R, p) + t
        return out
    if p.ndim == A.ndim:
        out = np.einsum("...ij,...nj->...ni", R, p) + t[..., None, :]
        return out
    raise InputError(
        f"expected points of shape (..., 3) matching T's batch or (..., n, 3), got points "
        f"{p.shape} with T {A.shape}",
        field="points",
    )
