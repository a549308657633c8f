"""Batched geometry of mtmc beside plain NumPy / SciPy references, timed side by side.

Fits on M = 10^5 sets of 30 points (plane, line, sphere with free and with known radius,
circle in 3D) and constructions on M = 10^6 (plane from three points, line-plane
intersection, circle through three points, 3-2-1 frame). Each is timed beside a
reference written here without mtmc:

* plane, line: batched SVD of the centred points (``np.linalg.svd`` on (M, 30, 3));
* sphere (free, known radius): ``scipy.optimize.least_squares`` (Levenberg-Marquardt,
  analytic Jacobian) one set at a time on the first 1000 sets, then three Gauss-Newton
  steps solved by QR (see :func:`polish`), the time scaled to M;
* circle: the plane by batched SVD, then ``least_squares`` (and :func:`polish`) of the
  in-plane circle one set at a time on the first 1000 sets, scaled;
* constructions: the textbook formulas with ``np.cross`` / ``np.einsum``, and for the
  circle through three points a different method (the batched 3 × 3 linear system of
  the circumcentre, ``np.linalg.solve``).

The agreement column is the largest difference between mtmc and the reference over the
sets compared (angles between normals or directions in rad, lengths in mm).

Usage: python benchmarks/bench_geometry.py [M_fits] [M_constructions] [repeats]
"""

from __future__ import annotations

import platform
import sys
import time

import numpy as np
from scipy.optimize import least_squares

from mtmc.geometry import (
    Line,
    Plane,
    circle_from_points,
    fit_circle,
    fit_line,
    fit_plane,
    fit_sphere,
    frame_from_plane_line_point,
    intersect_line_plane,
    plane_from_points,
)

N_POINTS = 30
SUBSET = 1000
NOISE = 0.001  # mm: 1 um on every coordinate
R_BALL = 12.7  # mm


def best(fn, repeats):
    """Best wall time of ``repeats`` calls, and the last result."""
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def frame_axes(n):
    """Two unit vectors perpendicular to each row of ``n`` and to each other."""
    helper = np.where(np.abs(n[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    e1 = unit(np.cross(n, helper))
    return e1, np.cross(n, e1)


def angle(a, b):
    """Angle between the lines of ``a`` and ``b`` (sign ignored), rad."""
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.abs(np.sum(a * b, axis=-1)))


# ---------------------------------------------------------------- data


def plane_sets(rng, m):
    n = unit(np.array([0.0, 0.0, 1.0]) + rng.normal(0.0, 0.05, (m, 3)))
    e1, e2 = frame_axes(n)
    c = rng.uniform(-100.0, 100.0, (m, 3))
    uv = rng.uniform(-50.0, 50.0, (m, N_POINTS, 2))
    pts = c[:, None] + uv[..., :1] * e1[:, None] + uv[..., 1:] * e2[:, None]
    return pts + rng.normal(0.0, NOISE, pts.shape)


def line_sets(rng, m):
    d = unit(rng.normal(size=(m, 3)))
    c = rng.uniform(-100.0, 100.0, (m, 3))
    t = rng.uniform(-50.0, 50.0, (m, N_POINTS, 1))
    pts = c[:, None] + t * d[:, None]
    return pts + rng.normal(0.0, NOISE, pts.shape)


def sphere_sets(rng, m):
    """Points on a 60-degree cap of a ball (as probed from above), radial noise."""
    c = rng.uniform(-10.0, 10.0, (m, 3))
    theta = np.arccos(rng.uniform(np.cos(np.pi / 3), 1.0, (m, N_POINTS)))
    phi = rng.uniform(0.0, 2.0 * np.pi, (m, N_POINTS))
    d = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)
    r = R_BALL + rng.normal(0.0, NOISE, (m, N_POINTS, 1))
    return c[:, None] + r * d


def circle_sets(rng, m):
    n = unit(np.array([0.0, 0.0, 1.0]) + rng.normal(0.0, 0.2, (m, 3)))
    e1, e2 = frame_axes(n)
    c = rng.uniform(-100.0, 100.0, (m, 3))
    phi = rng.uniform(0.0, 2.0 * np.pi, (m, N_POINTS, 1))
    r = 25.0 + rng.normal(0.0, NOISE, (m, N_POINTS, 1))
    pts = c[:, None] + r * (np.cos(phi) * e1[:, None] + np.sin(phi) * e2[:, None])
    return pts + rng.normal(0.0, NOISE, (m, N_POINTS, 1)) * n[:, None]


# ---------------------------------------------------------------- references


def ref_plane(P):
    c = P.mean(axis=1)
    _, _, vt = np.linalg.svd(P - c[:, None], full_matrices=False)
    return c, vt[:, -1]


def ref_line(P):
    c = P.mean(axis=1)
    _, _, vt = np.linalg.svd(P - c[:, None], full_matrices=False)
    return c, vt[:, 0]


def _sphere_res(x, P, radius):
    d = P - x[:3]
    return np.sqrt(np.sum(d * d, axis=1)) - (x[3] if radius is None else radius)


def _sphere_jac(x, P, radius):
    d = P - x[:3]
    rho = np.sqrt(np.sum(d * d, axis=1))
    J = -d / rho[:, None]
    return J if radius is not None else np.column_stack([J, -np.ones(len(P))])


def polish(fun, jac, x, args, steps=3):
    """A few Gauss-Newton steps solved by QR (``lstsq``) after ``least_squares``.

    MINPACK's LM stops on its ``ftol`` test once the sum of squares changes by less than
    the rounding of the residuals, which on a 60-degree cap leaves the centre about 2 nm
    short of the stationary point (gradient ~1e-9); these steps take it there.
    """
    for _ in range(steps):
        x = x + np.linalg.lstsq(jac(x, *args), -fun(x, *args), rcond=None)[0]
    return x


def ref_sphere(P, radius=None):
    """One least_squares per set (then :func:`polish`); start: the centroid pushed back."""
    out = np.empty((len(P), 4))
    for i, pts in enumerate(P):
        c0 = pts.mean(axis=0) - np.array([0.0, 0.0, 0.5 * R_BALL])
        r0 = np.linalg.norm(pts - c0, axis=1).mean()
        x0 = np.append(c0, r0) if radius is None else c0
        sol = least_squares(
            _sphere_res,
            x0,
            jac=_sphere_jac,
            args=(pts, radius),
            method="lm",
            xtol=1e-15,
            ftol=1e-15,
            gtol=1e-15,
        )
        x = polish(_sphere_res, _sphere_jac, sol.x, (pts, radius))
        out[i, :3] = x[:3]
        out[i, 3] = x[3] if radius is None else radius
    return out


def _circle_res(x, uv):
    return np.hypot(uv[:, 0] - x[0], uv[:, 1] - x[1]) - x[2]


def _circle_jac(x, uv):
    du, dv = uv[:, 0] - x[0], uv[:, 1] - x[1]
    rho = np.hypot(du, dv)
    return np.column_stack([-du / rho, -dv / rho, -np.ones(len(uv))])


def ref_circle(P):
    """Plane by batched SVD, then one in-plane least_squares circle per set."""
    c, n = ref_plane(P)
    e1, e2 = frame_axes(n)
    X = P - c[:, None]
    U = np.stack([np.einsum("mni,mi->mn", X, e1), np.einsum("mni,mi->mn", X, e2)], axis=-1)
    out = np.empty((len(P), 4))
    for i, uv in enumerate(U):
        x0 = np.append(uv.mean(axis=0), np.hypot(*(uv - uv.mean(axis=0)).T).mean())
        sol = least_squares(
            _circle_res,
            x0,
            jac=_circle_jac,
            args=(uv,),
            method="lm",
            xtol=1e-15,
            ftol=1e-15,
            gtol=1e-15,
        )
        x = polish(_circle_res, _circle_jac, sol.x, (uv,))
        out[i, :3] = c[i] + x[0] * e1[i] + x[1] * e2[i]
        out[i, 3] = x[2]
    return out


def ref_plane3(a, b, c):
    n = np.cross(b - a, c - a)
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def ref_intersect(l0, d, p0, n):
    t = np.einsum("mi,mi->m", p0 - l0, n) / np.einsum("mi,mi->m", d, n)
    return l0 + t[:, None] * d


def ref_circumcentre(a, b, c):
    """Centre from 2(b-a)·x = |b|²-|a|², 2(c-a)·x = |c|²-|a|², w·x = w·a (3 × 3 solve)."""
    w = np.cross(b - a, c - a)
    A = np.stack([2.0 * (b - a), 2.0 * (c - a), w], axis=1)
    rhs = np.stack(
        [
            np.einsum("mi,mi->m", b, b) - np.einsum("mi,mi->m", a, a),
            np.einsum("mi,mi->m", c, c) - np.einsum("mi,mi->m", a, a),
            np.einsum("mi,mi->m", w, a),
        ],
        axis=1,
    )
    centre = np.linalg.solve(A, rhs[..., None])[..., 0]
    return centre, np.linalg.norm(a - centre, axis=1)


def ref_frame(p0, n, d, q):
    x = d - np.einsum("mi,mi->m", d, n)[:, None] * n
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    y = np.cross(n, x)
    o = q - np.einsum("mi,mi->m", q - p0, n)[:, None] * n
    T = np.zeros((len(n), 4, 4))
    T[:, :3, :3] = np.stack([x, y, n], axis=2)
    T[:, :3, 3] = o
    T[:, 3, 3] = 1.0
    return T


# ---------------------------------------------------------------- main


def main() -> None:
    m_fit = int(float(sys.argv[1])) if len(sys.argv) > 1 else 100_000
    m_con = int(float(sys.argv[2])) if len(sys.argv) > 2 else 1_000_000
    repeats = int(sys.argv[3]) if len(sys.argv) > 3 else 3
    rng = np.random.default_rng(np.random.SeedSequence(20261121))
    sub = min(SUBSET, m_fit)
    rows = []

    def row(case, m, t_mtmc, t_ref, ref_name, agree):
        rows.append((case, m, t_mtmc, t_ref, ref_name, agree))
        print(f"  done: {case}", file=sys.stderr, flush=True)

    # fits, M sets of 30 points
    P = plane_sets(rng, m_fit)
    t1, fit = best(lambda: fit_plane(P), repeats)
    t2, (c_ref, n_ref) = best(lambda: ref_plane(P), repeats)
    g = fit.geometry
    agree = (
        f"normal {angle(g.normal, n_ref).max():.1e} rad, "
        f"point {np.abs(g.point - c_ref).max():.1e} mm"
    )
    row("fit_plane", m_fit, t1, t2, "batched SVD", agree)

    P = line_sets(rng, m_fit)
    t1, fit = best(lambda: fit_line(P), repeats)
    t2, (c_ref, d_ref) = best(lambda: ref_line(P), repeats)
    g = fit.geometry
    agree = (
        f"direction {angle(g.direction, d_ref).max():.1e} rad, "
        f"point {np.abs(g.point - c_ref).max():.1e} mm"
    )
    row("fit_line", m_fit, t1, t2, "batched SVD", agree)

    P = sphere_sets(rng, m_fit)
    t1, fit = best(lambda: fit_sphere(P), repeats)
    t2, ref = best(lambda: ref_sphere(P[:sub]), 1)
    g = fit.geometry
    agree = (
        f"centre {np.abs(g.centre[:sub] - ref[:, :3]).max():.1e} mm, "
        f"radius {np.abs(g.radius[:sub] - ref[:, 3]).max():.1e} mm"
    )
    row(
        "fit_sphere (free radius)",
        m_fit,
        t1,
        t2 * m_fit / sub,
        "least_squares + QR GN, scaled",
        agree,
    )

    t1, fit = best(lambda: fit_sphere(P, R_BALL), repeats)
    t2, ref = best(lambda: ref_sphere(P[:sub], R_BALL), 1)
    agree = f"centre {np.abs(fit.geometry.centre[:sub] - ref[:, :3]).max():.1e} mm"
    row(
        "fit_sphere (known radius)",
        m_fit,
        t1,
        t2 * m_fit / sub,
        "least_squares + QR GN, scaled",
        agree,
    )

    P = circle_sets(rng, m_fit)
    t1, fit = best(lambda: fit_circle(P), repeats)
    t2, ref = best(lambda: ref_circle(P[:sub]), 1)
    g = fit.geometry
    agree = (
        f"centre {np.abs(g.centre[:sub] - ref[:, :3]).max():.1e} mm, "
        f"radius {np.abs(g.radius[:sub] - ref[:, 3]).max():.1e} mm"
    )
    row("fit_circle", m_fit, t1, t2 * m_fit / sub, "SVD, least_squares + QR GN, sc.", agree)

    # constructions, M single features
    a = rng.uniform(-100.0, 100.0, (m_con, 3))
    b = rng.uniform(-100.0, 100.0, (m_con, 3))
    c = rng.uniform(-100.0, 100.0, (m_con, 3))
    t1, pl = best(lambda: plane_from_points(a, b, c), repeats)
    t2, n_ref = best(lambda: ref_plane3(a, b, c), repeats)
    row(
        "plane_from_points",
        m_con,
        t1,
        t2,
        "np.cross",
        f"normal {np.abs(pl.normal - n_ref).max():.1e}",
    )

    d = unit(rng.normal(size=(m_con, 3)))
    n = unit(d + rng.normal(size=(m_con, 3)))  # not parallel to the plane
    line, plane = Line(a, d), Plane(b, n)
    t1, x = best(lambda: intersect_line_plane(line, plane), repeats)
    t2, x_ref = best(lambda: ref_intersect(a, d, b, n), repeats)
    row(
        "intersect_line_plane",
        m_con,
        t1,
        t2,
        "einsum formula",
        f"point {np.abs(x - x_ref).max() / np.abs(x_ref).max():.1e} (relative)",
    )

    t1, circ = best(lambda: circle_from_points(a, b, c), repeats)
    t2, (ctr_ref, r_ref) = best(lambda: ref_circumcentre(a, b, c), repeats)
    scale = np.maximum(r_ref, 1.0)
    row(
        "circle_from_points",
        m_con,
        t1,
        t2,
        "3x3 np.linalg.solve",
        f"centre {(np.abs(circ.centre - ctr_ref).max(axis=1) / scale).max():.1e}, "
        f"radius {(np.abs(circ.radius - r_ref) / scale).max():.1e} (relative)",
    )

    d_frame = unit(rng.normal(size=(m_con, 3)))
    t1, T = best(lambda: frame_from_plane_line_point(plane, Line(a, d_frame), c), repeats)
    t2, T_ref = best(lambda: ref_frame(b, n, d_frame, c), repeats)
    rot = np.abs(T[:, :3, :3] - T_ref[:, :3, :3]).max()
    row(
        "frame_from_plane_line_point",
        m_con,
        t1,
        t2,
        "np.cross, stacked",
        f"rotation {rot:.1e}, origin {np.abs(T[:, :3, 3] - T_ref[:, :3, 3]).max():.1e} mm",
    )

    print(
        f"mtmc geometry, {N_POINTS} points per fit set, best of {repeats} "
        f"(SciPy references: {sub} sets, scaled to M), Python {platform.python_version()}, "
        f"NumPy {np.__version__}"
    )
    head = (
        f"{'case':<30}{'M':>9}{'mtmc s':>9}{'ref s':>9}{'ref/mtmc':>9}  {'reference':<33}agreement"
    )
    print(head)
    for case, m, t_m, t_r, ref_name, agree in rows:
        print(f"{case:<30}{m:>9.0e}{t_m:>9.3f}{t_r:>9.3f}{t_r / t_m:>9.2f}  {ref_name:<33}{agree}")


if __name__ == "__main__":
    main()
