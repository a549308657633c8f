"""Multilateration: points from the lengths measured by three or more tracker stations.

A tracker's interferometer or ADM measures lengths far better than its encoders measure
angles at long range (24 µrad is 120 µm at 5 m; 4 µm + 0.8 µm/m is 8 µm). Three or four
trackers, or one tracker moved to three or four stations, measuring the same reflector
positions give the points from the lengths alone:

``d_si = |P_i − C_s|``      (station ``s``, point ``i``).

With the stations known (three or more, not collinear with the point), each point
follows from its ``S`` lengths by Gauss–Newton. With four or more stations the station
positions themselves can be found from the same lengths (self-calibration): ``S·N``
equations for ``3N + 3S − 6`` unknowns (the six of a rigid motion are not observable
from lengths), so ``N >= (3S − 6)/(S − 3)`` points, e.g. ``N >= 6`` for ``S = 4``, and the
result is in the station datum frame: ``C_0`` at the origin, ``C_1`` on +x, ``C_2`` in the
xy plane with ``y > 0``. Three stations cannot self-calibrate from lengths only (``3N``
equations, ``3N + 3`` unknowns).

All solvers are batched: lengths ``(M, S, N)``, one problem per trial, solved in one pass
(the point blocks are eliminated by their 3 × 3 Schur complements).

Examples
--------
>>> import numpy as np
>>> C = np.array([[0.0, 0, 0], [3000, 0, 0], [0, 3000, 0], [0, 0, 2000]])
>>> P = np.array([[1000.0, 800.0, 500.0]])
>>> d = np.linalg.norm(P[None, :, :] - C[:, None, :], axis=-1)
>>> r = trilaterate(C, d[None], points0=[[900.0, 900.0, 400.0]])
>>> np.allclose(r.points, P, atol=1e-9), r.converged.tolist()
(True, [True])
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import DegenerateGeometryError, InputError

__all__ = [
    "Multilateration",
    "trilaterate",
    "self_calibrate",
    "datum_frame",
    "datum_pose",
    "trilateration_covariance",
]

_F = NDArray[np.float64]


@dataclass(frozen=True)
class Multilateration:
    """Result of :func:`trilaterate` or :func:`self_calibrate` (arrays read-only).

    Attributes
    ----------
    points : ndarray, shape (M, N, 3)
        mm.
    stations : ndarray, shape (M, S, 3)
        mm (the given stations for :func:`trilaterate`; the datum frame for
        :func:`self_calibrate`).
    rms : ndarray, shape (M,)
        Root mean square of the length residuals, mm.
    converged : ndarray of bool, shape (M,)
    iterations : int
    """

    points: _F
    stations: _F
    rms: _F
    converged: NDArray[np.bool_]
    iterations: int

    def __post_init__(self) -> None:
        for n in ("points", "stations", "rms", "converged"):
            getattr(self, n).setflags(write=False)


def _lengths(d: npt.ArrayLike, S: int | None = None) -> _F:
    a = np.asarray(d, dtype=np.float64)
    if a.ndim == 2:
        a = a[None]
    if a.ndim != 3 or (S is not None and a.shape[1] != S):
        raise InputError(
            f"expected lengths of shape (M, S, N){'' if S is None else f' with S = {S}'}, "
            f"got shape {a.shape}",
            field="lengths",
        )
    if not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise InputError("expected finite positive lengths", field="lengths")
    return a


def datum_pose(stations: npt.ArrayLike) -> tuple[_F, _F]:
    """The pose of the station datum frame of :func:`self_calibrate` in the stations' frame.

    Parameters
    ----------
    stations : array_like, shape (S, 3), S >= 3
        Station positions in some frame, mm.

    Returns
    -------
    rotation : ndarray, shape (3, 3)
        Columns: the datum axes in the given frame (``C_1 − C_0`` along x, ``C_2`` in
        the xy plane with ``y > 0``).
    origin : ndarray, shape (3,)
        ``C_0``: a datum-frame point ``p`` is ``rotation @ p + origin`` in the given frame.

    Raises
    ------
    InputError
        If stations 0 and 1 coincide or the first three are collinear.
    """
    C = np.asarray(stations, dtype=np.float64)
    ex = C[1] - C[0]
    if np.linalg.norm(ex) == 0:
        raise InputError("stations 0 and 1 coincide", field="stations")
    ex = ex / np.linalg.norm(ex)
    v = C[2] - C[0]
    ez = np.cross(ex, v)
    if np.linalg.norm(ez) < 1e-9 * np.linalg.norm(v):
        raise InputError("the first three stations are collinear", field="stations")
    ez /= np.linalg.norm(ez)
    return np.stack([ex, np.cross(ez, ex), ez], axis=1), C[0].copy()


def datum_frame(
    stations: npt.ArrayLike, points: npt.ArrayLike | None = None
) -> tuple[_F, _F | None]:
    """Express stations (and points) in the station datum frame of :func:`self_calibrate`.

    Parameters
    ----------
    stations : array_like, shape (S, 3), S >= 3
    points : array_like, shape (N, 3), optional

    Returns
    -------
    stations, points : ndarray
        ``C_0`` at the origin, ``C_1`` on +x, ``C_2`` in the xy plane with ``y > 0``.

    Raises
    ------
    InputError
        As :func:`datum_pose`: stations 0 and 1 coincide, or the first three are collinear.
    """
    C = np.asarray(stations, dtype=np.float64)
    R, origin = datum_pose(C)  # columns: datum axes in the given frame
    Cd = (C - origin) @ R
    Pd = None if points is None else (np.asarray(points, dtype=np.float64) - origin) @ R
    return Cd, Pd


def _check_stations(C: _F, solid: bool, field: str) -> None:
    """Refuse stations on one line (or, when ``solid``, on one plane).

    Raises
    ------
    DegenerateGeometryError
        Naming ``field``: the lengths from such stations do not fix a point (a circle or a
        mirror pair of solutions is as good).
    """
    pts = C.reshape(-1, *C.shape[-2:])[0]
    if not np.all(np.isfinite(pts)):
        raise InputError("expected finite station coordinates", field=field)
    s = np.linalg.svd(pts - pts.mean(axis=0), compute_uv=False)
    tiny = 1e-9 * max(float(s[0]), 1e-300)
    if s[1] <= tiny:
        raise DegenerateGeometryError("the stations lie on one line", field=field)
    if solid and s[2] <= tiny:
        raise DegenerateGeometryError(
            "the stations lie in one plane; expected four or more not in one plane", field=field
        )


def _singular(field: str) -> DegenerateGeometryError:
    return DegenerateGeometryError(
        "the stations and lengths do not fix the points (a singular system)", field=field
    )


def _linear_points(C: _F, d: _F) -> _F:
    """Linear trilateration (S >= 4 non-coplanar).

    ``2(C_s − C_0)·P = |C_s|² − |C_0|² − d_s² + d_0²``.
    """
    A = 2.0 * (C[:, 1:] - C[:, :1])  # (M, S-1, 3)
    c2 = np.sum(C * C, axis=-1)  # (M, S)
    b = (c2[:, 1:] - c2[:, :1])[:, :, None] - d[:, 1:, :] ** 2 + d[:, :1, :] ** 2  # (M, S-1, N)
    AtA = np.swapaxes(A, 1, 2) @ A
    return np.swapaxes(np.linalg.solve(AtA, np.swapaxes(A, 1, 2) @ b), 1, 2)  # (M, N, 3)


def _point_normal(P: _F, C: _F, d: _F) -> tuple[_F, _F, _F, _F]:
    """Residuals (M,S,N), unit vectors (M,S,N,3), point blocks H (M,N,3,3) and g (M,N,3)."""
    diff = P[:, None, :, :] - C[:, :, None, :]
    rng = np.linalg.norm(diff, axis=-1)
    e = diff / rng[..., None]
    r = rng - d
    H = np.einsum("msni,msnj->mnij", e, e)
    g = np.einsum("msni,msn->mni", e, r)
    return r, e, H, g


def _start_points(C: _F, d: _F, points0: npt.ArrayLike | None) -> _F:
    """The starting points of the Gauss–Newton iterations, ``(M, N, 3)``.

    Parameters
    ----------
    C : ndarray, shape (M, S, 3)
        Stations (known, or the approximate ones of :func:`self_calibrate`), mm.
    d : ndarray, shape (M, S, N)
        Lengths, mm.
    points0 : array_like, shape (N, 3) or (M, N, 3), optional
        Given starting points, copied for every trial; without them the linear solution
        (:func:`_linear_points`, S >= 4).

    Raises
    ------
    InputError
        For three stations without ``points0`` (two mirror-image solutions), or
        ``points0`` of a shape that is not ``(N, 3)`` or ``(M, N, 3)``.
    """
    m, _, n = d.shape
    if points0 is None:
        if C.shape[1] < 4:
            raise InputError(
                "three stations need starting points (mirror ambiguity)", field="points0"
            )
        return _linear_points(C, d)
    p0 = np.asarray(points0, dtype=np.float64)
    if p0.shape not in ((n, 3), (m, n, 3)):
        raise InputError(
            f"expected starting points of shape ({n}, 3) or ({m}, {n}, 3), got {p0.shape}",
            field="points0",
        )
    return np.broadcast_to(p0, (m, n, 3)).copy()


def _result(P: _F, C: _F, d: _F, done: NDArray[np.bool_], iterations: int) -> Multilateration:
    """The solution with the root mean square of its length residuals."""
    r = _point_normal(P, C, d)[0]
    rms = np.sqrt(np.mean(r * r, axis=(1, 2)))
    return Multilateration(P, C, rms, done, iterations)


def trilaterate(
    stations: npt.ArrayLike,
    lengths: npt.ArrayLike,
    *,
    points0: npt.ArrayLike | None = None,
    max_iter: int = 50,
    tol: float = 1e-12,
) -> Multilateration:
    """Points from the lengths of known stations, batched Gauss–Newton.

    Parameters
    ----------
    stations : array_like, shape (S, 3) or (M, S, 3), S >= 3
        Station positions, mm.
    lengths : array_like, shape (M, S, N) or (S, N)
        Measured lengths, mm.
    points0 : array_like, shape (N, 3) or (M, N, 3), optional
        Starting points (required for S = 3, which has a mirror ambiguity; by default the
        linear solution for S >= 4).
    max_iter : int
    tol : float
        Convergence when every step is below ``tol`` times the largest length.

    Returns
    -------
    Multilateration

    Raises
    ------
    InputError
        On bad shapes (``points0`` included), fewer than three stations, or S = 3 without
        ``points0``.
    """
    C = np.asarray(stations, dtype=np.float64)
    if C.ndim == 2:
        C = C[None]
    if C.ndim != 3 or C.shape[-1] != 3 or C.shape[1] < 3:
        raise InputError(
            f"expected (S, 3) stations with S >= 3, got shape {C.shape}", field="stations"
        )
    d = _lengths(lengths, C.shape[1])
    _check_stations(C, points0 is None and C.shape[1] >= 4, "stations")
    m = d.shape[0]
    C = np.broadcast_to(C, (m, *C.shape[1:]))
    scale = float(np.max(d))
    done = np.zeros(m, dtype=bool)
    it = 0
    try:
        P = _start_points(C, d, points0)
        for it in range(1, max_iter + 1):  # noqa: B007 - iterations, not trials
            _, _, H, g = _point_normal(P, C, d)
            step = -np.linalg.solve(H, g[..., None])[..., 0]
            P = P + step
            done = np.max(np.abs(step), axis=(1, 2)) <= tol * scale
            if np.all(done):
                break
    except np.linalg.LinAlgError:
        raise _singular("lengths") from None
    return _result(P, np.array(C), d, done, it)


def self_calibrate(
    lengths: npt.ArrayLike,
    stations0: npt.ArrayLike,
    *,
    points0: npt.ArrayLike | None = None,
    max_iter: int = 100,
    tol: float = 1e-12,
) -> Multilateration:
    """Stations and points from lengths only (S >= 4), batched Gauss–Newton with Schur complement.

    Parameters
    ----------
    lengths : array_like, shape (M, S, N) or (S, N)
        mm.
    stations0 : array_like, shape (S, 3)
        Approximate station positions (any frame), mm; they fix the starting values and
        which side of the plane of the first three stations the others lie.
    points0 : array_like, shape (N, 3), optional
        Starting points in the same frame (default: linear trilateration from
        ``stations0``).
    max_iter : int
    tol : float
        Convergence when every step is below ``tol`` times the largest length.

    Returns
    -------
    Multilateration
        Stations and points in the station datum frame (see :func:`datum_frame`).

    Raises
    ------
    InputError
        For S < 4, too few points (``S·N < 3N + 3S − 6``) or bad shapes (``points0``
        included).
    """
    C0 = np.asarray(stations0, dtype=np.float64)
    if C0.ndim != 2 or C0.shape[1] != 3:
        raise InputError(f"expected stations of shape (S, 3), got {C0.shape}", field="stations0")
    S = C0.shape[0]
    if S < 4:
        raise InputError(
            "self-calibration from lengths only needs at least four stations "
            f"(3 stations: 3N equations for 3N + 3 unknowns), got {S}",
            field="stations0",
        )
    d = _lengths(lengths, S)
    m, _, N = d.shape
    if S * N < 3 * N + 3 * S - 6:
        raise InputError(
            f"{S} stations need at least {-(-(3 * S - 6) // (S - 3))} points to "
            f"self-calibrate, got {N}",
            field="lengths",
        )
    _check_stations(C0, points0 is None, "stations0")
    try:
        P0 = _start_points(C0[None], d[:1], points0)[0]
    except np.linalg.LinAlgError:
        raise _singular("lengths") from None
    Cd, Pd = datum_frame(C0, P0)
    assert Pd is not None
    # free station coordinates in the datum: C1.x, C2.x, C2.y, then all of C3...
    free = [(1, 0), (2, 0), (2, 1)] + [(s, k) for s in range(3, S) for k in range(3)]
    k = len(free)
    sidx = np.array([f[0] for f in free])
    cidx = np.array([f[1] for f in free])
    C = np.broadcast_to(Cd, (m, S, 3)).copy()
    P = np.broadcast_to(Pd, (m, N, 3)).copy()
    scale = float(np.max(d))
    done = np.zeros(m, dtype=bool)
    it = 0
    try:
        for it in range(1, max_iter + 1):  # noqa: B007 - iterations, not trials
            r, e, Hpp, gp = _point_normal(P, C, d)
            # station Jacobian: dr_si/dC_s = -e_si; columns of the free coordinates
            Jc = np.zeros((m, S, N, k))
            for j in range(k):  # loop over the few station unknowns
                Jc[:, sidx[j], :, j] = -e[:, sidx[j], :, cidx[j]]
            Hcc = np.einsum("msnj,msnl->mjl", Jc, Jc)
            gc = np.einsum("msnj,msn->mj", Jc, r)
            Hpc = np.einsum("msni,msnj->mnij", e, Jc)  # (M, N, 3, k)
            Hpp_inv = np.linalg.inv(Hpp)
            X = Hpp_inv @ Hpc  # (M, N, 3, k)
            Sred = Hcc - np.einsum("mnij,mnil->mjl", Hpc, X)
            rhs = gc - np.einsum("mnil,mni->ml", X, gp)
            dc = -np.linalg.solve(Sred, rhs[..., None])[..., 0]
            dp = -(Hpp_inv @ gp[..., None])[..., 0] - np.einsum("mnil,ml->mni", X, dc)
            C[:, sidx, cidx] += dc
            P += dp
            step = np.maximum(np.max(np.abs(dc), axis=1), np.max(np.abs(dp), axis=(1, 2)))
            done = step <= tol * scale
            if np.all(done):
                break
    except np.linalg.LinAlgError:
        raise _singular("lengths") from None
    return _result(P, C, d, done, it)


def trilateration_covariance(
    stations: npt.ArrayLike, points: npt.ArrayLike, u_length: npt.ArrayLike
) -> _F:
    """Linearised covariance of multilaterated points with known stations.

    Parameters
    ----------
    stations : array_like, shape (S, 3)
    points : array_like, shape (N, 3)
    u_length : array_like, shape (S, N) or broadcastable
        Standard uncertainty of each length, mm.

    Returns
    -------
    ndarray, shape (N, 3, 3)
        ``(Eᵀ W E)⁻¹`` with ``E`` the unit vectors station → point and ``W = diag(u⁻²)``,
        mm² (GUM law of propagation through the Gauss–Newton solution).
    """
    C = np.asarray(stations, dtype=np.float64)
    P = np.asarray(points, dtype=np.float64)
    diff = P[None, :, :] - C[:, None, :]
    e = diff / np.linalg.norm(diff, axis=-1, keepdims=True)
    w = np.broadcast_to(np.asarray(u_length, dtype=np.float64), e.shape[:2]) ** -2.0
    H = np.einsum("sni,sn,snj->nij", e, w, e)
    return np.linalg.inv(H)
