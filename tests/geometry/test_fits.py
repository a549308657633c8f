"""Least-squares fits against published values, exact data, scipy, and one-at-a-time runs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose, assert_array_equal
from scipy.optimize import least_squares

from mtmc.errors import ConvergenceError, DegenerateGeometryError, InputError
from mtmc.geometry import (
    FitResult,
    circle_from_points,
    fit_circle,
    fit_line,
    fit_plane,
    fit_sphere,
    line_from_points,
    plane_from_points,
)

REFERENCE = Path(__file__).parent.parent / "reference" / "circle_ggs1994"
SEEDS = st.integers(0, 2**32 - 1)


def _rng(seed: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(seed))


def _rotations(rng: np.random.Generator, m: int) -> np.ndarray:
    """Random proper rotations (M, 3, 3), from the QR decomposition of Gaussian matrices."""
    q, r = np.linalg.qr(rng.normal(size=(m, 3, 3)))
    q = q * np.sign(np.diagonal(r, axis1=1, axis2=2))[:, None, :]
    q[np.linalg.det(q) < 0, :, 0] *= -1.0
    return q


def _ggs_points() -> np.ndarray:
    xy = np.loadtxt(REFERENCE / "points.csv", delimiter=",", skiprows=1)
    return np.column_stack([xy, np.zeros(len(xy))])


def _ggs_expected() -> dict[str, float]:
    values = {}
    for line in (REFERENCE / "expected_geometric_fit.txt").read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            key, value = line.split()
            values[key] = float(value)
    return values


def _sphere_points(
    rng: np.random.Generator,
    m: int,
    n: int,
    half_angle: float,
    radius: np.ndarray,
    centre: np.ndarray,
) -> np.ndarray:
    """Points on a spherical cap of the given half angle, in random orientations.

    The first four are the pole and three points 120° apart on the rim (or on the
    equator for caps wider than a hemisphere): a tetrahedron, never coplanar; the others
    are uniform on the cap. Four uniform points alone are
    sometimes coplanar to 1e-11 (e.g. seed 2325), which the fit rightly refuses.
    """
    cos_t = rng.uniform(np.cos(half_angle), 1.0, size=(m, n))
    phi = rng.uniform(0, 2 * np.pi, size=(m, n))
    if n >= 4:
        cos_t[:, 0] = 1.0
        cos_t[:, 1:4] = np.cos(min(half_angle, np.pi / 2))  # on the cap, never the antipode
        phi[:, 1:4] = phi[:, 1:2] + np.array([0.0, 2.0, 4.0]) * np.pi / 3
    sin_t = np.sqrt(1 - cos_t**2)
    local = np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t], axis=2)
    return centre[:, None, :] + radius[:, None, None] * np.einsum(
        "mij,mnj->mni", _rotations(rng, m), local
    )


def _wang2022_patch(radius: float) -> np.ndarray:
    """30 points on a 6 mm x 6 mm patch of a ball (Wang, Cheung and Kong 2022, §2), from +z."""
    x, y = np.meshgrid(np.linspace(-3, 3, 6), np.linspace(-3, 3, 5))
    x, y = x.ravel(), y.ravel()
    return np.column_stack([x, y, np.sqrt(radius**2 - x**2 - y**2)])


# --- the published example ------------------------------------------------------------------


def test_ggs1994_geometric_circle_fit_reproduces_published_values() -> None:
    expected = _ggs_expected()
    fit = fit_circle(_ggs_points())
    centre, radius = fit.geometry.centre[0], fit.geometry.radius[0]
    # published to 4 decimals: agree to half a unit of the last digit
    assert abs(centre[0] - expected["xc"]) <= 0.5e-4
    assert abs(centre[1] - expected["yc"]) <= 0.5e-4
    assert abs(radius - expected["r"]) <= 0.5e-4
    assert centre[2] == 0.0
    assert fit.dof == 3
    assert fit.iterations is not None
    assert 1 <= fit.iterations[0] < 30


def test_ggs1994_agrees_with_scipy_least_squares_and_is_pose_invariant() -> None:
    pts = _ggs_points()

    def resid(t: np.ndarray) -> np.ndarray:
        return np.hypot(pts[:, 0] - t[0], pts[:, 1] - t[1]) - t[2]

    ref = least_squares(resid, [5.0, 3.0, 5.0], xtol=1e-15, ftol=1e-15, gtol=1e-15).x
    fit = fit_circle(pts)
    theta = np.r_[fit.geometry.centre[0, :2], fit.geometry.radius]
    # This example converges slowly (large residuals): scipy stops ~1e-8 short of the
    # minimum, where its gradient is still ~1e-8; ours is converged to the rounding floor.
    assert_allclose(theta, ref, atol=1e-7)
    d = np.hypot(pts[:, 0] - theta[0], pts[:, 1] - theta[1])
    J = np.column_stack([-(pts[:, 0] - theta[0]) / d, -(pts[:, 1] - theta[1]) / d, -np.ones(6)])
    assert_allclose(J.T @ resid(theta), 0.0, atol=1e-12)  # first-order optimality
    assert_allclose(fit.residuals[0], resid(theta), atol=1e-12)
    ref = theta
    # the same points in 50 random poses in space
    rng = _rng(1994)
    R = _rotations(rng, 50)
    t = rng.normal(scale=100, size=(50, 3))
    moved = np.einsum("mij,nj->mni", R, pts) + t[:, None, :]
    fits = fit_circle(moved)
    assert_allclose(fits.geometry.radius, ref[2], atol=1e-9)
    assert_allclose(
        fits.geometry.centre, np.einsum("mij,j->mi", R, [ref[0], ref[1], 0]) + t, atol=1e-9
    )
    normal = R[:, :, 2] * np.sign(np.einsum("mi,mi->m", fits.geometry.normal, R[:, :, 2]))[:, None]
    assert_allclose(fits.geometry.normal, normal, atol=1e-12)


# --- exact points in random poses are recovered --------------------------------------------


@settings(max_examples=20, deadline=None)
@given(seed=SEEDS, n=st.integers(4, 40))
def test_exact_sphere_recovered(seed: int, n: int) -> None:
    rng = _rng(seed)
    m = 20
    centre = rng.normal(scale=100, size=(m, 3))
    radius = rng.uniform(1, 50, size=m)
    pts = _sphere_points(rng, m, n, rng.uniform(0.8, np.pi), radius, centre)
    fit = fit_sphere(pts)
    assert_allclose(fit.geometry.centre, centre, atol=1e-9)
    assert_allclose(fit.geometry.radius, radius, atol=1e-9)
    assert_allclose(fit.rms, 0.0, atol=1e-9)
    known = fit_sphere(pts, radius)
    assert_allclose(known.geometry.centre, centre, atol=1e-9)
    assert_array_equal(known.geometry.radius, radius)


@settings(max_examples=20, deadline=None)
@given(seed=SEEDS, n=st.integers(3, 40))
def test_exact_circle_recovered(seed: int, n: int) -> None:
    rng = _rng(seed)
    m = 20
    R = _rotations(rng, m)
    centre = rng.normal(scale=100, size=(m, 3))
    radius = rng.uniform(1, 50, size=m)
    # arcs of up to 2.5 rad with the points at least 0.01 rad apart (uniform draws
    # alone can put two of three points 1e-5 rad apart: a degenerate triangle, rightly
    # refused by the collinearity test l2 <= RTOL l3)
    angle = (
        rng.uniform(0, 2 * np.pi, size=(m, 1))
        + np.sort(rng.uniform(0, 2.5 - 0.01 * n, size=(m, n)), axis=1)
        + 0.01 * np.arange(n)
    )
    local = np.stack([np.cos(angle), np.sin(angle), np.zeros_like(angle)], axis=2)
    pts = centre[:, None, :] + radius[:, None, None] * np.einsum("mij,mnj->mni", R, local)
    fit = fit_circle(pts, orientation=R[:, :, 2])
    assert_allclose(fit.geometry.centre, centre, atol=1e-9)
    assert_allclose(fit.geometry.radius, radius, atol=1e-9)
    assert_allclose(fit.geometry.normal, R[:, :, 2], atol=1e-9)
    assert_allclose(fit.residuals, 0.0, atol=1e-9)


@settings(max_examples=20, deadline=None)
@given(seed=SEEDS, n=st.integers(3, 40))
def test_exact_plane_and_line_recovered(seed: int, n: int) -> None:
    rng = _rng(seed)
    m = 20
    R = _rotations(rng, m)
    origin = rng.normal(scale=100, size=(m, 3))
    local = rng.uniform(-20, 20, size=(m, n, 3))
    local[:, :, 2] = 0.0
    pts = origin[:, None, :] + np.einsum("mij,mnj->mni", R, local)
    fit = fit_plane(pts, orientation=R[:, :, 2])
    assert_allclose(fit.geometry.normal, R[:, :, 2], atol=1e-9)
    assert_allclose(np.einsum("mi,mi->m", fit.geometry.point - origin, R[:, :, 2]), 0.0, atol=1e-9)
    assert_allclose(fit.residuals, 0.0, atol=1e-9)
    local[:, :, 1] = 0.0
    pts = origin[:, None, :] + np.einsum("mij,mnj->mni", R, local)
    fit = fit_line(pts, orientation=R[:, :, 0])
    assert_allclose(fit.geometry.direction, R[:, :, 0], atol=1e-9)
    assert_allclose(fit.residuals, 0.0, atol=1e-9)
    assert fit.dof == 2 * n - 4


# --- hand-made plane and conventions -------------------------------------------------------


def test_plane_fit_of_a_hand_made_plane() -> None:
    # Points (±1, ±1, ±e) with the sign pattern x*y: S = diag(4, 4, 4 e^2), so the
    # best plane is z = 0 exactly, the residuals are ±e and rms = e. Then tilted.
    e = 0.01
    pts = np.array([[1, 1, e], [1, -1, -e], [-1, 1, -e], [-1, -1, e], [0, 0, 0]])
    fit = fit_plane(pts, orientation=[0, 0, 1])
    assert_allclose(fit.geometry.normal, [[0, 0, 1]], atol=1e-15)
    assert_allclose(fit.geometry.point, [[0, 0, 0]], atol=1e-15)
    assert_allclose(fit.residuals, [[e, -e, -e, e, 0]], atol=1e-15)
    assert_allclose(fit.rms, [e * np.sqrt(4 / 5)], rtol=1e-13)
    assert fit.dof == 2
    assert fit.covariance is None
    assert fit.iterations is None
    c, s = np.cos(0.3), np.sin(0.3)
    rot = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    tilted = fit_plane(pts @ rot.T + [10, 20, 30], orientation=[0, 0, 1])
    assert_allclose(tilted.geometry.normal, [rot[:, 2]], atol=1e-14)
    assert_allclose(tilted.geometry.point, [[10, 20, 30]], atol=1e-13)
    assert_allclose(tilted.residuals, fit.residuals, atol=1e-14)


def test_default_orientations_match_the_constructions() -> None:
    rng = _rng(5)
    a, b, c = rng.normal(size=(3, 10, 3))
    tri = np.stack([a, b, c], axis=1)
    assert_allclose(fit_plane(tri).geometry.normal, plane_from_points(a, b, c).normal, atol=1e-12)
    circ = circle_from_points(a, b, c)
    fit = fit_circle(tri)
    assert_allclose(fit.geometry.normal, circ.normal, atol=1e-12)
    assert_allclose(fit.geometry.centre, circ.centre, atol=1e-9)
    assert_allclose(fit.geometry.radius, circ.radius, atol=1e-9)
    assert np.isnan(fit.covariance).all()  # dof == 0
    assert_allclose(
        fit_line(tri[:, :2]).geometry.direction, line_from_points(a, b).direction, atol=1e-12
    )
    # an orientation flips the normal
    flipped = fit_plane(tri, orientation=-plane_from_points(a, b, c).normal)
    assert_allclose(flipped.geometry.normal, -plane_from_points(a, b, c).normal, atol=1e-12)
    assert_allclose(flipped.residuals, 0.0, atol=1e-12)


def test_known_radius_with_centre_guess_from_three_points() -> None:
    centre = np.array([1.0, 2.0, 3.0])
    d = np.array([[0.2, 0.1, 1], [-0.1, 0.3, 1], [0.0, -0.2, 1]])
    pts = centre + 4.0 * d / np.linalg.norm(d, axis=1)[:, None]
    fit = fit_sphere(pts, 4.0, centre_guess=centre + np.array([0.1, -0.1, 0.2]))
    assert_allclose(fit.geometry.centre, [centre], atol=1e-10)
    assert fit.dof == 0


# --- batch equals one at a time ------------------------------------------------------------


def _assert_same(batch: FitResult, one: FitResult, i: int) -> None:
    for name in ("point", "normal", "direction", "centre", "radius"):
        if hasattr(batch.geometry, name):
            assert_array_equal(getattr(one.geometry, name)[0], getattr(batch.geometry, name)[i])
    assert_array_equal(one.residuals[0], batch.residuals[i])
    assert_array_equal(one.rms[0], batch.rms[i])
    if batch.covariance is not None:
        assert one.covariance is not None
        assert_array_equal(one.covariance[0], batch.covariance[i])
    if batch.iterations is not None:
        assert one.iterations is not None
        assert one.iterations[0] == batch.iterations[i]


def test_batch_equals_one_at_a_time_for_noisy_points() -> None:
    rng = _rng(2024)
    m = 50
    sph = _sphere_points(rng, m, 30, 0.7, np.full(m, 5.0), rng.normal(size=(m, 3)))
    sph += rng.normal(scale=1e-3, size=sph.shape)
    angle = np.linspace(0, 5, 12)
    circ = np.stack([10 * np.cos(angle), 10 * np.sin(angle), np.zeros_like(angle)], axis=1)
    circ = circ + rng.normal(scale=0.01, size=(m, 12, 3))
    fits = {
        "sphere": (fit_sphere, sph, {}),
        "sphere, known radius": (fit_sphere, sph, {"radius": 5.0}),
        "circle": (fit_circle, circ, {}),
        "plane": (fit_plane, circ, {}),
        "line": (fit_line, sph, {}),
    }
    for fn, pts, kwargs in fits.values():
        batch = fn(pts, **kwargs)
        assert len(batch) == m
        _assert_same(batch, batch[7], 7)
        assert len(batch[3:9]) == 6
        for i in range(m):
            _assert_same(batch, fn(pts[i], **kwargs), i)


# --- against scipy.optimize.least_squares ---------------------------------------------------


def test_sphere_fit_agrees_with_scipy_least_squares() -> None:
    rng = _rng(3)
    radius = 9.997 / 2  # the calibrated fiducial of Wang, Cheung and Kong 2022
    m = 10
    centres = rng.normal(scale=50, size=(m, 3))
    pts = centres[:, None, :] + _wang2022_patch(radius) + rng.normal(scale=0.5e-3, size=(m, 30, 3))
    free = fit_sphere(pts)
    known = fit_sphere(pts, radius)
    for i in range(m):
        p = pts[i]
        ref = least_squares(
            lambda t, p=p: np.linalg.norm(p - t[:3], axis=1) - t[3],
            np.r_[p.mean(axis=0), 1.0],
            xtol=1e-15,
            ftol=1e-15,
            gtol=1e-15,
        ).x
        assert_allclose(free.geometry.centre[i], ref[:3], atol=1e-8)
        assert_allclose(free.geometry.radius[i], ref[3], atol=1e-8)
        ref = least_squares(
            lambda t, p=p: np.linalg.norm(p - t, axis=1) - radius,
            p.mean(axis=0),
            xtol=1e-15,
            ftol=1e-15,
            gtol=1e-15,
        ).x
        assert_allclose(known.geometry.centre[i], ref, atol=1e-8)


def test_sphere_covariance_matches_monte_carlo_spread() -> None:
    # Radial noise of sigma on the Wang, Cheung and Kong 2022 patch: the covariance s^2 (J^T J)^{-1}
    # averaged over trials must match the spread of the fitted parameters.
    rng = _rng(7)
    radius, sigma, m = 5.0, 1e-3, 4000
    nominal = _wang2022_patch(radius)
    normal = nominal / radius
    pts = nominal + rng.normal(scale=sigma, size=(m, 30, 1)) * normal
    for kwargs, k in (({}, 4), ({"radius": radius}, 3)):
        fit = fit_sphere(pts, **kwargs)
        assert fit.covariance is not None
        assert fit.covariance.shape == (m, k, k)
        params = np.column_stack([fit.geometry.centre, fit.geometry.radius])[:, :k]
        empirical = np.sqrt(np.diag(np.cov(params.T)))
        predicted = np.sqrt(np.diag(fit.covariance.mean(axis=0)))
        # the standard deviation estimated from 4000 trials is good to ~1.1 % (1 sigma)
        assert_allclose(empirical, predicted, rtol=0.05)
        bias = np.abs(params.mean(axis=0) - [0, 0, 0, radius][:k])
        assert np.all(bias <= 4 * predicted / np.sqrt(m))


def test_sphere_covariance_mean_is_closed_form_with_unbiased_variance() -> None:
    # For radial noise of sigma the linearised covariance of (centre, radius) is
    # sigma^2 (J^T J)^{-1}, J with rows (-n_i, -1) (n_i the unit normal at point i), or
    # (-n_i) with a known radius. Its estimate s^2 (J^T J)^{-1}, s^2 = sum r^2 / (n - k),
    # is unbiased only with the divisor n - k: the mean over M trials must match the
    # closed form within five standard errors of the mean of s^2 / sigma^2
    # (chi^2_{n-k} / (n - k), relative standard deviation sqrt(2 / ((n - k) M))).
    rng = _rng(17)
    radius, sigma, m = 5.0, 1e-3, 4000
    nominal = _wang2022_patch(radius)
    normal = nominal / radius
    pts = nominal + rng.normal(scale=sigma, size=(m, 30, 1)) * normal
    for kwargs, k in (({}, 4), ({"radius": radius}, 3)):
        fit = fit_sphere(pts, **kwargs)
        assert fit.covariance is not None
        assert fit.dof == 30 - k
        jac = np.column_stack([-normal, -np.ones(30)])[:, :k]
        exact = sigma**2 * np.linalg.inv(jac.T @ jac)
        scale = np.sqrt(np.outer(np.diag(exact), np.diag(exact)))
        gap = np.abs(fit.covariance.mean(axis=0) - exact) / scale
        rel_se = np.sqrt(2.0 / ((30 - k) * m))
        assert np.all(gap <= 5 * rel_se), gap


def test_circle_covariance_matches_monte_carlo_spread() -> None:
    rng = _rng(8)
    sigma, m = 0.01, 4000
    angle = np.linspace(0, 3, 10)
    nominal = np.stack([20 * np.cos(angle), 20 * np.sin(angle), np.zeros_like(angle)], axis=1)
    radial = nominal / 20
    pts = nominal + rng.normal(scale=sigma, size=(m, 10, 1)) * radial
    fit = fit_circle(pts, orientation=[0, 0, 1])
    assert fit.covariance is not None
    params = np.column_stack([fit.geometry.centre[:, :2], fit.geometry.radius])
    empirical = np.sqrt(np.diag(np.cov(params.T)))
    predicted = np.sqrt(np.diag(fit.covariance.mean(axis=0)))[[0, 1, 3]]
    assert_allclose(empirical, predicted, rtol=0.05)
    assert_allclose(fit.covariance[:, 2, :], 0.0, atol=1e-20)  # nothing out of plane


# --- degenerate and bad input --------------------------------------------------------------


def test_too_few_points() -> None:
    with pytest.raises(
        DegenerateGeometryError, match="field points: a sphere fit needs at least 4 points, got 3"
    ):
        fit_sphere(np.zeros((2, 3, 3)))
    with pytest.raises(DegenerateGeometryError, match="a plane fit needs at least 3 points, got 2"):
        fit_plane(np.zeros((2, 3)))
    with pytest.raises(
        DegenerateGeometryError, match="a circle fit needs at least 3 points, got 2"
    ):
        fit_circle(np.zeros((2, 3)))
    with pytest.raises(DegenerateGeometryError, match="a line fit needs at least 2 points, got 1"):
        fit_line(np.zeros((1, 3)))
    with pytest.raises(
        DegenerateGeometryError, match="a sphere fit needs at least 3 points, got 2"
    ):
        fit_sphere(np.ones((2, 3)), 1.0, centre_guess=[0, 0, 0])


def test_collinear_coplanar_coincident() -> None:
    good = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]])
    line = np.outer(np.arange(5.0), [1, 2, 3])
    batch = np.stack([good, line, good, line + 1])
    msg = r"field points: the points are collinear in 2 of 4 trials \(first: trial 1\)"
    with pytest.raises(DegenerateGeometryError, match=msg + "; expected points spanning a plane"):
        fit_plane(batch)
    with pytest.raises(DegenerateGeometryError, match=msg + "; expected points spanning a circle"):
        fit_circle(batch)
    flat = good.copy()
    flat[:, 2] = 0.0
    with pytest.raises(
        DegenerateGeometryError,
        match=r"the points are coplanar in 1 of 2 trials \(first: trial 0\); expected points not",
    ):
        fit_sphere(np.stack([flat, good]))
    same = np.tile([3.0, 4.0, 5.0], (4, 1))
    with pytest.raises(DegenerateGeometryError, match="all the points coincide in 1 of 2 trials"):
        fit_line(np.stack([good[:4], same]))


def test_no_convergence_and_bad_input() -> None:
    pts = _wang2022_patch(5.0) + _rng(1).normal(scale=1e-3, size=(30, 3))
    with pytest.raises(
        ConvergenceError,
        match=r"the sphere fit did not converge in 1 Gauss-Newton iterations in 1 of 1 trials",
    ):
        fit_sphere(pts, max_iterations=1)
    with pytest.raises(InputError, match=r"field radius: expected a radius > 0 mm, got -5.0"):
        fit_sphere(pts, -5.0)
    bad = np.tile(pts, (3, 1, 1))
    bad[1, 4, 2] = np.inf
    with pytest.raises(InputError, match=r"NaN or infinity in 1 of 3 trials \(first: trial 1\)"):
        fit_sphere(bad)
    with pytest.raises(
        InputError, match=r"field orientation: expected 3 trials \(as in points\) or 1, got 2"
    ):
        fit_plane(np.tile(pts, (3, 1, 1)), orientation=np.ones((2, 3)))
    with pytest.raises(
        InputError, match=r"field xtol: expected a relative step tolerance 0 < xtol < 1, got 0"
    ):
        fit_circle(pts, xtol=0)
    with pytest.raises(
        InputError, match=r"field max_iterations: expected an integer max_iterations >= 1, got 0"
    ):
        fit_sphere(pts, max_iterations=0)
