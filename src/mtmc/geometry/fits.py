"""Batched orthogonal-distance least-squares fits: plane, line, circle, sphere.

Each fit takes ``M`` sets of ``n`` points, shape ``(M, n, 3)`` (a single set ``(n, 3)``
is a batch of one), and fits all ``M`` sets in one call: the trial axis is never looped
over in Python. The iterative fits (circle, sphere) loop over Gauss-Newton iterations
only, all trials together, and drop the trials that have converged from the following
iterations; each trial stops exactly as it would alone, so a batch gives bit-for-bit the
results of ``M`` separate calls.

The plane, line and sphere fits minimise the sum of squared *orthogonal* (geometric)
distances of the points to the feature; the circle in 3D does it in two steps (the plane,
then the circle in that plane), which is not the joint minimum of the 3D distances to the
circle when the points are off their plane:

- plane and line: the centroid and the eigenvectors of the scatter matrix
  ``S = sum_i (p_i - c)(p_i - c)^T`` (the plane's normal is the eigenvector of the
  smallest eigenvalue, the line's direction that of the largest); this is the exact
  total-least-squares solution, no iteration.
- circle in 3D: the best plane, the points expressed in that plane, the algebraic
  (Kåsa) circle as a start, then Gauss-Newton on the geometric distances
  ``rho_i - r`` (Gander, Golub & Strebel 1994, §3).
- sphere: the algebraic sphere as a start, then Gauss-Newton on ``|p_i - c| - r``
  (free radius) or on ``|p_i - c| - R`` with the radius ``R`` known (centre only: the
  ball-centre measurement with a calibrated ball of Stryczek and Wang, Cheung and Kong 2022).

The Gauss-Newton iterations of a trial stop when the step is below ``xtol`` times the
size of its point set, or when the steps stop shrinking at the rounding floor
(ill-conditioned data). Trials are processed in internal blocks of a few thousand, so
that the temporaries stay in the CPU cache; the results do not depend on the blocks.

Each :class:`FitResult` holds the fitted geometry, the residuals, their RMS, the degrees
of freedom and, for the iterative fits, the number of iterations and the covariance of
the fitted parameters ``s^2 (J^T J)^{-1}`` from the Jacobian ``J`` at the solution and
the residual variance ``s^2 = sum r_i^2 / dof``.

NaN policy: unlike the constructions, which let NaN propagate, the fits refuse
non-finite coordinates with an :class:`~mtmc.errors.InputError` naming the trials (an
iteration cannot converge on them).

Tolerances: degeneracy is tested on the eigenvalues ``l1 <= l2 <= l3`` of the scatter
matrix, relative, with :data:`mtmc.geometry.checks.RTOL` (``1e-10``): the eigenvalues
are only accurate to about ``eps * l3``, so the test is on eigenvalue ratios (e.g.
collinear points: ``l2 <= RTOL l3``, a ratio of the singular values of ``1e-5``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import ConvergenceError, InputError
from mtmc.geometry.checks import (
    RTOL,
    batch_size,
    check_point_sets,
    check_scalars,
    check_vectors,
    degenerate,
    in_batch,
)
from mtmc.geometry.primitives import Circle, Index, Line, Plane, Sphere, _index
from mtmc.geometry.vec import cross as _cross

__all__ = ["FitResult", "fit_circle", "fit_line", "fit_plane", "fit_sphere"]

XTOL: float = 1e-12
"""Default relative step tolerance of the Gauss-Newton iterations (see :func:`fit_sphere`)."""

MAX_ITERATIONS: int = 100
"""Default largest number of Gauss-Newton iterations."""


@dataclass(frozen=True, eq=False)
class FitResult:
    """The result of a batched least-squares fit.

    Attributes
    ----------
    geometry : Plane, Line, Circle or Sphere
        The fitted features, a batch of ``M``.
    residuals : ndarray, shape (M, n)
        The residual of each point, mm: the signed distance to the plane, the distance
        to the line (``>= 0``), the signed radial distance in the circle's plane
        (``rho_i - r``), the signed distance to the sphere (``|p_i - c| - r``).
    rms : ndarray, shape (M,)
        ``sqrt(mean(residuals**2))`` per trial, mm.
    dof : int
        Degrees of freedom of the residuals: ``n - 3`` (plane, circle, sphere of known
        radius), ``2n - 4`` (line: two residual components per point, four parameters),
        ``n - 4`` (sphere).
    covariance : ndarray, shape (M, k, k), or None
        Covariance of the fitted parameters, ``s^2 (J^T J)^{-1}``: circle ``(x, y, z, r)``
        (the centre's in-plane part only; the uncertainty of the plane itself is not
        included), sphere ``(x, y, z, r)``, sphere of known radius ``(x, y, z)``; in
        mm². NaN where ``dof == 0``. None for the plane and the line.
    iterations : ndarray of int, shape (M,), or None
        Gauss-Newton iterations each trial took (None for the closed-form fits).
    """

    geometry: Plane | Line | Circle | Sphere
    residuals: NDArray[np.float64]
    rms: NDArray[np.float64]
    dof: int
    covariance: NDArray[np.float64] | None = None
    iterations: NDArray[np.int64] | None = None

    def __len__(self) -> int:
        return int(self.residuals.shape[0])

    def __getitem__(self, idx: Index) -> FitResult:
        """The results of a sub-batch of trials (an integer keeps a batch of one)."""
        return FitResult(
            self.geometry[idx],
            _index(self.residuals, idx),
            _index(self.rms, idx),
            self.dof,
            None if self.covariance is None else _index(self.covariance, idx),
            None if self.iterations is None else _index(self.iterations, idx),
        )


Block = dict[str, NDArray[Any]]


def _block_size(n: int) -> int:
    """Trials per internal block: about 64 k coordinates, so the temporaries stay in cache."""
    return max(16, 65536 // max(n, 1))


def _run(fn: Callable[..., Block], m: int, n: int, **arrays: Any) -> Block:
    """Apply ``fn`` to consecutive blocks of trials and gather its per-trial outputs.

    Arrays with a leading size of ``m`` are cut into blocks; arrays with a leading size
    of 1 (a broadcast argument) and non-array arguments are passed whole. This loops
    over blocks of thousands of trials, not over trials: it keeps the temporaries of the
    vectorised arithmetic small enough to stay in the CPU cache (several times faster
    than one pass over ``M = 10^5`` trials at once). The arithmetic of each trial does
    not depend on the block it is in.
    """
    size = _block_size(n)
    out: Block = {}
    for start in range(0, m, size):
        stop = min(start + size, m)
        args = {
            key: (a[start:stop] if isinstance(a, np.ndarray) and a.shape[0] == m else a)
            for key, a in arrays.items()
        }
        res = fn(**args)
        if not out:
            out = {key: np.empty((m, *v.shape[1:]), dtype=v.dtype) for key, v in res.items()}
        for key, v in res.items():
            out[key][start:stop] = v
    return out


def _scatter(
    points: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Centroid, centred points and eigen-decomposition of the scatter matrix.

    Returns the centroid ``(B, 3)``, the centred points ``(B, n, 3)``, the eigenvalues
    ``(B, 3)`` ascending and the eigenvectors ``(B, 3, 3)`` (columns).
    """
    c = np.einsum("bni->bi", points) / points.shape[1]
    X = points - c[:, None, :]
    S = np.matmul(X.transpose(0, 2, 1), X)
    w, V = np.linalg.eigh(S)
    return c, X, w, V


def _plane_axes(
    X: NDArray[np.float64], V: NDArray[np.float64], orientation: NDArray[np.float64] | None
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Oriented normal, in-plane axes and in-plane coordinates of a fitted plane.

    Returns the normal ``(B, 3)``, the axes ``E = [e1 e2]`` ``(B, 3, 2)`` and the
    coordinates ``(2, B, n)`` of the centred points ``X`` in them, from the scatter
    matrix's eigenvectors ``V``.
    ``e1`` is the direction of largest spread and ``(e1, e2, normal)`` is right-handed.
    Without an ``orientation``, the normal points along Newell's vector
    ``sum_i x_i × x_{i+1}`` (indices cyclic) of the closed polygon through the points in
    their order; its component along the normal is, exactly, the in-plane sum
    ``sum_i (u_i v_{i+1} - v_i u_{i+1})`` (twice the signed area), which is what is
    computed. Where that reference vanishes, the normal's largest component is made
    positive.
    """
    n0 = V[:, :, 0]
    e1 = V[:, :, 2]
    E = np.stack([e1, _cross(n0, e1)], axis=2)
    U = np.matmul(X, E).transpose(2, 0, 1).copy()
    if orientation is None:
        u, v = U[0], U[1]
        area = np.einsum("bn,bn->b", u[:, :-1], v[:, 1:]) - np.einsum(
            "bn,bn->b", v[:, :-1], u[:, 1:]
        )
        area += u[:, -1] * v[:, 0] - v[:, -1] * u[:, 0]
        s = area
        scale = np.einsum("kbn,kbn->b", U, U)
    else:
        s = np.einsum("bi,bi->b", n0, orientation)
        scale = np.sqrt(np.einsum("bi,bi->b", orientation, orientation))
    big = np.take_along_axis(n0, np.abs(n0).argmax(axis=1)[:, None], axis=1)[:, 0]
    sign = np.where(np.abs(s) > RTOL * scale, np.sign(s), np.sign(big))
    E[:, :, 1] *= sign[:, None]
    U[1] *= sign[:, None]
    return n0 * sign[:, None], E, U


def _orient(v: NDArray[np.float64], ref: NDArray[np.float64]) -> NDArray[np.float64]:
    """Flip the unit vectors ``v`` so that ``v · ref > 0``.

    Where ``|v · ref| <= RTOL |ref|`` (no usable reference), the component of ``v``
    largest in magnitude is made positive instead.
    """
    s = np.einsum("bi,bi->b", v, ref)
    big = np.take_along_axis(v, np.abs(v).argmax(axis=1)[:, None], axis=1)[:, 0]
    scale = np.sqrt(np.einsum("bi,bi->b", ref, ref))
    sign = np.where(np.abs(s) > RTOL * scale, np.sign(s), np.sign(big))
    return v * sign[:, None]


def _orientation(orientation: npt.ArrayLike | None, m: int) -> NDArray[np.float64] | None:
    if orientation is None:
        return None
    ref = check_vectors(orientation, "orientation")
    batch_size(points=np.empty((m, 0)), orientation=ref)
    return ref


def _rms(r: NDArray[np.float64]) -> NDArray[np.float64]:
    rms: NDArray[np.float64] = np.sqrt(np.mean(r * r, axis=1))
    return rms


def _plane_block(P: NDArray[np.float64], orientation: NDArray[np.float64] | None) -> Block:
    c, X, w, V = _scatter(P)
    n = _plane_axes(X, V, orientation)[0]
    r = np.matmul(X, n[:, :, None])[:, :, 0]
    return {"c": c, "n": n, "r": r, "rms": _rms(r), "bad": ~(w[:, 1] > RTOL * w[:, 2])}


def fit_plane(points: npt.ArrayLike, *, orientation: npt.ArrayLike | None = None) -> FitResult:
    """Orthogonal-distance least-squares plane through ``M`` sets of points.

    The plane passes through the centroid ``c`` of each set; its normal is the
    eigenvector of the smallest eigenvalue of the scatter matrix
    ``S = sum_i (p_i - c)(p_i - c)^T``, which minimises ``sum_i (n · (p_i - c))^2``
    (the multi-point plane of Stryczek; for three points it is the plane of eqs. 20-29).

    Parameters
    ----------
    points : array_like, shape (M, n, 3) or (n, 3)
        The points, mm, ``n >= 3``.
    orientation : array_like, shape (M, 3) or (3,), optional
        A direction the normal is made to point along (``n · orientation > 0``), e.g.
        the nominal normal. By default the normal is right-handed with respect to the
        order of the points: it points along Newell's vector
        ``sum_i (p_i - c) × (p_{i+1} - c)`` of the closed polygon through them (for three
        points, the normal of :func:`~mtmc.geometry.plane_from_points`). Where that
        reference is perpendicular to the normal, the normal's largest component is made
        positive.

    Returns
    -------
    FitResult
        ``geometry`` a :class:`Plane` (point = centroid), ``residuals`` the signed
        distances ``n · (p_i - c)``, ``dof = n - 3``, no covariance.

    Raises
    ------
    DegenerateGeometryError
        Fewer than 3 points; collinear (or coincident) points, ``l2 <= RTOL l3``.
    InputError
        Bad shape, or non-finite coordinates.

    Examples
    --------
    >>> fit = fit_plane([[0, 0, 1], [1, 0, 1], [0, 1, 1], [1, 1, 1]])
    >>> fit.geometry.normal, fit.geometry.point, fit.rms
    (array([[0., 0., 1.]]), array([[0.5, 0.5, 1. ]]), array([0.]))
    """
    P = check_point_sets(points, min_points=3, what="a plane fit")
    m, n = P.shape[:2]
    o = _run(_plane_block, m, n, P=P, orientation=_orientation(orientation, m))
    degenerate(o["bad"], "the points are collinear", "points spanning a plane", "points")
    return FitResult(Plane(o["c"], o["n"]), o["r"], o["rms"], n - 3)


def _line_block(P: NDArray[np.float64], orientation: NDArray[np.float64] | None) -> Block:
    c, X, w, V = _scatter(P)
    n = P.shape[1]
    ref = X[:, -1, :] - X[:, 0, :] if orientation is None else orientation
    d = _orient(V[:, :, 2], ref)
    perp = X - np.matmul(X, d[:, :, None]) * d[:, None, :]
    r = np.sqrt(np.einsum("bni,bni->bn", perp, perp))
    scale = np.abs(P).max(axis=(1, 2))
    bad = ~(np.sqrt(np.maximum(w[:, 2], 0.0) / n) > RTOL * scale)
    return {"c": c, "d": d, "r": r, "rms": _rms(r), "bad": bad}


def fit_line(points: npt.ArrayLike, *, orientation: npt.ArrayLike | None = None) -> FitResult:
    """Orthogonal-distance least-squares line through ``M`` sets of points.

    The line passes through the centroid ``c``; its direction is the eigenvector of the
    largest eigenvalue of the scatter matrix, which minimises the sum of squared
    distances ``sum_i |(p_i - c) × d|^2``.

    Parameters
    ----------
    points : array_like, shape (M, n, 3) or (n, 3)
        The points, mm, ``n >= 2``.
    orientation : array_like, shape (M, 3) or (3,), optional
        A direction the line is made to point along (``d · orientation > 0``). By default
        it points from the first point towards the last (for two points, the direction
        of :func:`~mtmc.geometry.line_from_points`).

    Returns
    -------
    FitResult
        ``geometry`` a :class:`Line` (point = centroid), ``residuals`` the distances of
        the points to the line (``>= 0``), ``dof = 2n - 4``, no covariance.

    Raises
    ------
    DegenerateGeometryError
        Fewer than 2 points; all points coincide, ``sqrt(l3 / n) <= RTOL max|p_i|``.
    InputError
        Bad shape, or non-finite coordinates.

    Examples
    --------
    >>> fit = fit_line([[0, 0, 0], [1, 1, 0], [2, 2, 0]])
    >>> fit.geometry.direction * 2**0.5, fit.geometry.point
    (array([[1., 1., 0.]]), array([[1., 1., 0.]]))
    """
    P = check_point_sets(points, min_points=2, what="a line fit")
    m, n = P.shape[:2]
    o = _run(_line_block, m, n, P=P, orientation=_orientation(orientation, m))
    degenerate(o["bad"], "all the points coincide", "at least two distinct points", "points")
    return FitResult(Line(o["c"], o["d"]), o["r"], o["rms"], 2 * n - 4)


def _normal_equations(
    Xc: NDArray[np.float64],
    theta: NDArray[np.float64],
    radius: NDArray[np.float64] | None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Normal equations of the geometric circle or sphere fit.

    ``Xc`` holds the coordinates component-wise, shape ``(dim, B, n)``; ``theta`` the
    centre ``(B, dim)`` followed, when ``radius`` is None, by the radius. With
    ``rho_i = |x_i - a|``, ``u_i = (x_i - a) / rho_i`` and the residuals
    ``r_i = rho_i - r``, the Jacobian rows are ``[-u_i, -1]`` (``-u_i`` with the radius
    known), so ``J^T J = [[sum u u^T, sum u], [sum u^T, n]]`` and
    ``J^T r = [-sum u r, -sum r]``. Returns ``J^T J`` ``(B, k, k)``, ``J^T r`` ``(B, k)``
    and the residuals ``(B, n)``.
    """
    dim, b, n = Xc.shape
    free = radius is None
    k = dim + free
    D = Xc - theta[:, :dim].T[:, :, None]
    rho = np.sqrt(sum(D[i] * D[i] for i in range(dim)))
    U = D / rho
    r = rho - (theta[:, dim, None] if radius is None else radius[:, None])
    A = np.empty((b, k, k))
    g = np.empty((b, k))
    for i in range(dim):
        for j in range(i, dim):
            A[:, i, j] = A[:, j, i] = np.einsum("bn,bn->b", U[i], U[j])
        g[:, i] = -np.einsum("bn,bn->b", U[i], r)
    if free:
        A[:, dim, :dim] = A[:, :dim, dim] = U.sum(axis=2).T
        A[:, dim, dim] = n
        g[:, dim] = -r.sum(axis=1)
    return A, g, r


def _gauss_newton(
    Xc: NDArray[np.float64],
    theta: NDArray[np.float64],
    radius: NDArray[np.float64] | None,
    tol: NDArray[np.float64],
    max_iterations: int,
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.bool_]]:
    """Gauss-Newton for circles (``Xc`` of shape (2, B, n)) and spheres ((3, B, n)).

    Each iteration solves ``(J^T J) delta = -J^T r`` (see :func:`_normal_equations`)
    for every active trial and applies it. A trial stops, and is dropped from the
    following iterations, once ``max|delta| <= tol`` or the next step, extrapolated
    from the last two (``|delta_k|^2 / |delta_{k-1}|``), would be; or once a step below
    ``10^6 tol``
    is no smaller than the one before (the steps of a converging Gauss-Newton shrink
    geometrically until they reach the rounding floor of ill-conditioned data; that
    last step is then not applied). Returns the parameters, the iterations taken and
    the mask of the trials that did not converge.
    """
    theta = theta.copy()
    b = Xc.shape[1]
    iterations = np.zeros(b, dtype=np.int64)
    active = np.arange(b)
    Xa, ta, ra = Xc, tol, radius
    prev_step = np.full(b, np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        for it in range(1, max_iterations + 1):
            th = theta[active]
            A, g, _ = _normal_equations(Xa, th, ra)
            try:
                delta = -np.linalg.solve(A, g[:, :, None])[:, :, 0]
            except np.linalg.LinAlgError:
                delta = np.full_like(th, np.nan)
            step = np.abs(delta).max(axis=1)
            stalled = (step >= prev_step) & (step <= 1e6 * ta)
            theta[active] = np.where(stalled[:, None], th, th + delta)
            iterations[active] = it
            # the next step, extrapolated from the contraction of the last two
            contracting = (step < prev_step) & (prev_step < np.inf)
            small = (step <= ta) | (contracting & (step * step <= ta * prev_step))
            keep = ~(small | stalled)
            active = active[keep]
            if active.size == 0:
                break
            prev_step = step[keep]
            if not keep.all():
                Xa, ta = Xa[:, keep], ta[keep]
                if ra is not None and ra.shape[0] > 1:
                    ra = ra[keep]
    failed = np.zeros(b, dtype=np.bool_)
    failed[active] = True
    return theta, iterations, failed


def _solution(
    Xc: NDArray[np.float64],
    theta: NDArray[np.float64],
    radius: NDArray[np.float64] | None,
    dof: int,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Residuals ``(B, n)`` and covariance ``s^2 (J^T J)^{-1}`` ``(B, k, k)`` at ``theta``.

    ``s^2 = sum r^2 / dof``; the covariance is NaN where ``dof == 0``.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        A, _, r = _normal_equations(Xc, theta, radius)
    b, k = A.shape[:2]
    if dof <= 0:
        return r, np.full((b, k, k), np.nan)
    s2 = np.einsum("bn,bn->b", r, r) / dof
    return r, np.linalg.inv(A) * s2[:, None, None]


def _regular_polygon(n: int, dim: int) -> NDArray[np.float64]:
    """``n`` well-spread unit vectors in ``dim`` = 2 or 3 dimensions (none coplanar in 3D).

    Stands in for the points of degenerate trials, so that the rest of the block can
    be computed before the degenerate ones are reported.
    """
    k = np.arange(n) + 0.5
    if dim == 2:
        a = 2.0 * np.pi * k / n
        return np.stack([np.cos(a), np.sin(a)], axis=1)
    zc = 1.0 - 2.0 * k / n
    a = np.pi * (3.0 - np.sqrt(5.0)) * k
    s = np.sqrt(1.0 - zc * zc)
    return np.stack([s * np.cos(a), s * np.sin(a), zc], axis=1)


def _circle_block(
    P: NDArray[np.float64],
    orientation: NDArray[np.float64] | None,
    xtol: float,
    max_iterations: int,
) -> Block:
    c, X, w, V = _scatter(P)
    b, n = P.shape[:2]
    bad = ~(w[:, 1] > RTOL * w[:, 2])
    nrm, E, Uc = _plane_axes(X, V, orientation)  # Uc: (2, B, n) in-plane coordinates
    if bad.any():
        Uc[:, bad] = _regular_polygon(n, 2).T[:, None, :]
    u, v = Uc[0], Uc[1]
    # Kåsa: least squares of [u v 1] (2a, 2b, r^2 - a^2 - b^2) = u^2 + v^2, by its
    # normal equations (the coordinates are centred, so they are well conditioned).
    z = u * u + v * v
    A = np.empty((b, 3, 3))
    A[:, 0, 0] = np.einsum("bn,bn->b", u, u)
    A[:, 1, 1] = np.einsum("bn,bn->b", v, v)
    A[:, 0, 1] = A[:, 1, 0] = np.einsum("bn,bn->b", u, v)
    A[:, 0, 2] = A[:, 2, 0] = u.sum(axis=1)
    A[:, 1, 2] = A[:, 2, 1] = v.sum(axis=1)
    A[:, 2, 2] = n
    rhs = np.stack(
        [np.einsum("bn,bn->b", u, z), np.einsum("bn,bn->b", v, z), z.sum(axis=1)], axis=1
    )
    ab = 0.5 * np.linalg.solve(A, rhs[:, :, None])[:, :2, 0]
    r0 = np.sqrt((u - ab[:, 0, None]) ** 2 + (v - ab[:, 1, None]) ** 2).mean(axis=1)
    tol = xtol * np.sqrt(z.mean(axis=1))
    theta0 = np.concatenate([ab, r0[:, None]], axis=1)
    theta, its, failed = _gauss_newton(Uc, theta0, None, tol, max_iterations)
    r, cov2 = _solution(Uc, theta, None, n - 3)
    # (a, b, r) -> (x, y, z, r) with G = [[e1 e2 0], [0 0 1]], shape (B, 4, 3).
    G = np.zeros((b, 4, 3))
    G[:, :3, :2] = E
    G[:, 3, 2] = 1.0
    cov = np.matmul(np.matmul(G, cov2), G.transpose(0, 2, 1))
    centre = c + np.matmul(E, theta[:, :2, None])[:, :, 0]
    return {
        "centre": centre,
        "normal": nrm,
        "radius": theta[:, 2],
        "r": r,
        "rms": _rms(r),
        "cov": cov,
        "its": its,
        "bad": bad,
        "failed": failed & ~bad,
    }


def _check_iteration_args(xtol: float, max_iterations: int) -> None:
    if not (isinstance(xtol, int | float) and 0.0 < xtol < 1.0):
        raise InputError(
            f"expected a relative step tolerance 0 < xtol < 1, got {xtol!r}", field="xtol"
        )
    if not (isinstance(max_iterations, int | np.integer) and max_iterations >= 1):
        raise InputError(
            f"expected an integer max_iterations >= 1, got {max_iterations!r}",
            field="max_iterations",
        )


def _converged(failed: NDArray[np.bool_], what: str, max_iterations: int) -> None:
    if failed.any():
        raise ConvergenceError(
            f"{what} did not converge in {max_iterations} Gauss-Newton iterations "
            f"{in_batch(failed)}; expected "
            "points that determine the feature (a patch too small for its noise leaves "
            "the radius undetermined), or a larger max_iterations",
            field="points",
        )


def fit_circle(
    points: npt.ArrayLike,
    *,
    orientation: npt.ArrayLike | None = None,
    xtol: float = XTOL,
    max_iterations: int = MAX_ITERATIONS,
) -> FitResult:
    """Orthogonal-distance least-squares circle in 3D through ``M`` sets of points.

    Three steps, all trials together:

    1. the best plane (as :func:`fit_plane`), giving the normal ``n`` and two in-plane
       axes ``e1`` (the direction of largest spread) and ``e2 = n × e1``;
    2. the points in plane coordinates ``(u_i, v_i) = ((p_i - c) · e1, (p_i - c) · e2)``
       and the algebraic (Kåsa) circle, ``min sum (u^2 + v^2 + D u + E v + F)^2``, as a
       start (exact for three points);
    3. Gauss-Newton on the geometric distances ``rho_i - r``,
       ``rho_i = |(u_i, v_i) - (a, b)|``, to convergence (the geometric fit of Gander,
       Golub & Strebel 1994).

    Parameters
    ----------
    points : array_like, shape (M, n, 3) or (n, 3)
        The points, mm, ``n >= 3`` (planar data: give ``z = 0`` for a 2D fit).
    orientation : array_like, shape (M, 3) or (3,), optional
        A direction the circle's normal is made to point along; by default right-handed
        with respect to the order of the points (see :func:`fit_plane`).
    xtol : float
        Each trial stops when no parameter moves (or would move, extrapolating the
        last two steps) by more than ``xtol`` times the RMS distance of its points from
        their centroid; ``0 < xtol < 1``.
    max_iterations : int
        Largest number of Gauss-Newton iterations.

    Returns
    -------
    FitResult
        ``geometry`` a :class:`Circle`; ``residuals`` ``rho_i - r`` in the fitted plane
        (the out-of-plane distances are those of :func:`fit_plane`); ``dof = n - 3``;
        ``iterations``; ``covariance`` ``(M, 4, 4)`` of ``(x, y, z, r)`` from the
        in-plane fit (the uncertainty of the plane's orientation is not included).

    Raises
    ------
    DegenerateGeometryError
        Fewer than 3 points; collinear points (``l2 <= RTOL l3``).
    ConvergenceError
        If some trials have not converged in ``max_iterations``.
    InputError
        Bad shape, or non-finite coordinates.

    Examples
    --------
    The example of Gander, Golub & Strebel (1994):

    >>> xy = [[1, 7], [2, 6], [5, 8], [7, 7], [9, 5], [3, 7]]
    >>> fit = fit_circle([[x, y, 0.0] for x, y in xy])
    >>> print(fit.geometry.centre.round(4) + 0.0, fit.geometry.radius.round(4))
    [[4.7398 2.9835 0.    ]] [4.7142]
    """
    P = check_point_sets(points, min_points=3, what="a circle fit")
    _check_iteration_args(xtol, max_iterations)
    m, n = P.shape[:2]
    o = _run(
        _circle_block,
        m,
        n,
        P=P,
        orientation=_orientation(orientation, m),
        xtol=xtol,
        max_iterations=max_iterations,
    )
    degenerate(o["bad"], "the points are collinear", "points spanning a circle", "points")
    _converged(o["failed"], "the circle fit", max_iterations)
    circle = Circle(o["centre"], o["normal"], o["radius"])
    return FitResult(circle, o["r"], o["rms"], n - 3, o["cov"], o["its"])


def _sphere_block(
    P: NDArray[np.float64],
    R: NDArray[np.float64] | None,
    guess: NDArray[np.float64] | None,
    xtol: float,
    max_iterations: int,
) -> Block:
    b, n = P.shape[:2]
    c = np.einsum("bni->bi", P) / n
    X = P - c[:, None, :]
    z = np.einsum("bni,bni->bn", X, X)
    bad = np.zeros(b, dtype=np.bool_)
    if guess is not None:
        x0 = guess - c
    else:
        S = np.matmul(X.transpose(0, 2, 1), X)
        tr = np.trace(S, axis1=1, axis2=2)
        bad = ~(np.linalg.det(S) > RTOL * (tr / 3.0) ** 3)
        if bad.any():
            X[bad] = _regular_polygon(n, 3)
            z[bad] = 1.0
            S[bad] = np.matmul(X[bad].transpose(0, 2, 1), X[bad])
        # Algebraic sphere, centred data: S D = -sum_i x_i |x_i|^2, centre = -D / 2.
        x0 = 0.5 * np.linalg.solve(S, np.matmul(X.transpose(0, 2, 1), z[:, :, None]))[:, :, 0]
    if R is None:
        D0 = X - x0[:, None, :]
        r0 = np.sqrt(np.einsum("bni,bni->bn", D0, D0)).mean(axis=1)
        theta0 = np.concatenate([x0, r0[:, None]], axis=1)
    else:
        theta0 = np.ascontiguousarray(x0)
    tol = xtol * np.sqrt(z.mean(axis=1))
    Xc = np.ascontiguousarray(X.transpose(2, 0, 1))
    theta, its, failed = _gauss_newton(Xc, theta0, R, tol, max_iterations)
    rad = theta[:, 3] if R is None else np.broadcast_to(R, (b,))
    r, cov = _solution(Xc, theta, R, n - (4 if R is None else 3))
    return {
        "centre": c + theta[:, :3],
        "radius": rad,
        "r": r,
        "rms": _rms(r),
        "cov": cov,
        "its": its,
        "bad": bad,
        "failed": failed & ~bad,
    }


def fit_sphere(
    points: npt.ArrayLike,
    radius: npt.ArrayLike | None = None,
    *,
    centre_guess: npt.ArrayLike | None = None,
    xtol: float = XTOL,
    max_iterations: int = MAX_ITERATIONS,
) -> FitResult:
    """Orthogonal-distance least-squares sphere through ``M`` sets of points.

    With the points centred on their centroid (``x_i = p_i - c``), the algebraic sphere
    ``min sum (|x_i|^2 + D · x_i + G)^2`` gives the start: it solves
    ``S D = -sum_i x_i |x_i|^2`` with the scatter matrix ``S``, centre ``-D / 2``. Then
    Gauss-Newton on the geometric distances ``|x_i - a| - r`` (free radius, parameters
    ``(a, r)``) or ``|x_i - a| - R`` (known radius ``R``, parameters ``a``: the centre of
    a calibrated ball, Stryczek, Fig. 5-6; Wang, Cheung and Kong 2022, §2 probes 30 points on a
    6 mm × 6 mm patch of a 9.997 mm ball and fits its centre by least squares).

    Parameters
    ----------
    points : array_like, shape (M, n, 3) or (n, 3)
        The points, mm; ``n >= 4``, or ``n >= 3`` with a known radius and a
        ``centre_guess``.
    radius : array_like, shape (M,) or (), optional
        The known radius, mm (``> 0``); None fits it.
    centre_guess : array_like, shape (M, 3) or (3,), optional
        A start for the centre (e.g. the nominal one) instead of the algebraic sphere;
        with a known radius it also picks the side of the points the centre lies on.
    xtol : float
        Each trial stops when no parameter moves (or would move, extrapolating the
        last two steps) by more than ``xtol`` times the RMS distance of its points from
        their centroid; ``0 < xtol < 1``.
    max_iterations : int
        Largest number of Gauss-Newton iterations.

    Returns
    -------
    FitResult
        ``geometry`` a :class:`Sphere`; ``residuals`` ``|p_i - c| - r``; ``dof`` ``n - 4``
        (free) or ``n - 3`` (known radius); ``iterations``; ``covariance`` of
        ``(x, y, z, r)`` ``(M, 4, 4)`` or of the centre ``(M, 3, 3)``, mm².

    Raises
    ------
    DegenerateGeometryError
        Too few points ("a sphere fit needs at least 4 points, got 3"); coplanar points
        without a ``centre_guess`` (``det S <= RTOL (tr S / 3)^3``).
    ConvergenceError
        If some trials have not converged in ``max_iterations``.
    InputError
        Bad shape, non-finite coordinates, a radius not > 0.

    Examples
    --------
    >>> pts = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, -1]]
    >>> fit = fit_sphere(pts)
    >>> print(fit.geometry.centre.round(12) + 0.0, fit.geometry.radius)
    [[0. 0. 0.]] [1.]
    >>> fit_sphere(pts, radius=1.0).geometry.centre.round(12) + 0.0
    array([[0., 0., 0.]])
    """
    need = 3 if (radius is not None and centre_guess is not None) else 4
    P = check_point_sets(points, min_points=need, what="a sphere fit")
    _check_iteration_args(xtol, max_iterations)
    m, n = P.shape[:2]
    R = None
    if radius is not None:
        R = check_scalars(radius, "radius")
        batch_size(points=P, radius=R)
        if not (R > 0.0).all():
            bad = float(R[~(R > 0.0)][0])
            raise InputError(f"expected a radius > 0 mm, got {bad!r}", field="radius")
    guess = None
    if centre_guess is not None:
        guess = check_vectors(centre_guess, "centre_guess")
        batch_size(points=P, centre_guess=guess)
    o = _run(_sphere_block, m, n, P=P, R=R, guess=guess, xtol=xtol, max_iterations=max_iterations)
    degenerate(
        o["bad"],
        "the points are coplanar",
        "points not all in one plane (or a centre_guess)",
        "points",
    )
    _converged(o["failed"], "the sphere fit", max_iterations)
    return FitResult(
        Sphere(o["centre"], o["radius"]),
        o["r"],
        o["rms"],
        n - (4 if R is None else 3),
        o["cov"],
        o["its"],
    )
