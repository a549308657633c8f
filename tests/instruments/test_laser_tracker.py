"""Laser tracker: pose, spherical coordinates, noise presets, visibility; multilateration."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mtmc.errors import InputError
from mtmc.geometry.transforms import rotation_x, rotation_y, rotation_z
from mtmc.instruments import (
    LaserTracker,
    TrackerLimits,
    TrackerNoise,
    cartesian,
    datum_frame,
    self_calibrate,
    spherical,
    spherical_jacobian,
    trilaterate,
    trilateration_covariance,
    visibility,
)
from mtmc.uncertainty import monte_carlo
from mtmc.uncertainty.distributions import IID, Normal


def test_euler_xyz_is_fixed_axes_x_then_y_then_z() -> None:
    a = np.radians([0.0339, 0.0343, 59.4652])
    lt = LaserTracker.from_euler([-863.527, 194.373, 677.782], a)
    assert np.allclose(
        lt.rotation, rotation_z(a[2]) @ rotation_y(a[1]) @ rotation_x(a[0]), atol=1e-15
    )
    assert np.allclose(lt.euler(), a, atol=1e-14)


def test_axis_angle_matches_rodrigues_matrix_of_aguado_2017_eq3() -> None:
    u = np.array([1.0, 2.0, 2.0]) / 3.0
    th = 0.7
    c, s = math.cos(th), math.sin(th)
    ux, uy, uz = u
    R = np.array(
        [
            [c + ux**2 * (1 - c), ux * uy * (1 - c) - uz * s, ux * uz * (1 - c) + uy * s],
            [ux * uy * (1 - c) + uz * s, c + uy**2 * (1 - c), uy * uz * (1 - c) - ux * s],
            [ux * uz * (1 - c) - uy * s, uy * uz * (1 - c) + ux * s, c + uz**2 * (1 - c)],
        ]
    )
    lt = LaserTracker.from_axis_angle([0, 0, 0], u, th)
    assert np.allclose(lt.rotation, R, atol=1e-15)


def test_points_round_trip_and_spherical_inverse() -> None:
    lt = LaserTracker.from_euler([100.0, -50.0, 20.0], [0.1, -0.2, 1.0])
    p = np.random.default_rng(np.random.SeedSequence(1)).uniform(-2000, 2000, (50, 3))
    assert np.allclose(lt.to_base(lt.to_tracker(p)), p, atol=1e-10)
    x = lt.to_tracker(p)
    assert np.allclose(cartesian(spherical(x)), x, atol=1e-10)
    assert np.allclose(np.linalg.norm(x, axis=1), spherical(x)[:, 0])


def test_spherical_jacobian_against_central_differences() -> None:
    s = np.array([[1500.0, 0.4, -0.3], [800.0, -2.0, 0.9]])
    J = spherical_jacobian(s)
    h = np.array([1e-3, 1e-7, 1e-7])
    fd = np.stack(
        [
            (cartesian(s + h[j] * np.eye(3)[j]) - cartesian(s - h[j] * np.eye(3)[j])) / (2 * h[j])
            for j in range(3)
        ],
        axis=-1,
    )
    assert np.allclose(J, fd, rtol=1e-8, atol=1e-8)


def test_noise_presets_and_mpe_conversion() -> None:
    n = TrackerNoise.aguado2017()
    assert n.u_range(1000.0) == pytest.approx(0.0048)
    assert (n.azimuth, n.elevation) == (24e-6, 24e-6)
    t = TrackerNoise.from_mpe(adm=(0.010, 0.3e-6), transverse=(0.015, 6e-6), conversion="typical")
    r = TrackerNoise.from_mpe(
        adm=(0.010, 0.3e-6), transverse=(0.015, 6e-6), conversion="rectangular"
    )
    assert t.radial_a == pytest.approx(0.005)
    assert r.radial_a == pytest.approx(0.010 / math.sqrt(3))
    # transverse u at 5 m: (15 µm + 6 µm/m · 5 m)/2 = 22.5 µm
    assert t.u_spherical(5000.0)[1] * 5000.0 == pytest.approx(0.0225)
    assert "MPE/2" in t.source
    assert "MPE/√3" in r.source
    # every field is the MPE term over the divisor, the range's and the angles' alike
    k = math.sqrt(3.0)
    assert (r.radial_a, r.radial_b) == (0.010 / k, 0.3e-6 / k)
    assert (r.azimuth, r.elevation, r.transverse_a) == (6e-6 / k, 6e-6 / k, 0.015 / k)
    assert r.source == "MPE/√3 (rectangular): ADM ±(10 µm + 0.3 µm/m), transverse ±(15 µm + 6 µm/m)"
    assert t.source == "MPE/2 (typical): ADM ±(10 µm + 0.3 µm/m), transverse ±(15 µm + 6 µm/m)"
    with pytest.raises(InputError, match="conversion"):
        TrackerNoise.from_mpe(adm=(0.01, 0.0), transverse=(0.01, 0.0), conversion="gauss")  # type: ignore[arg-type]


def test_noise_covariance_against_monte_carlo() -> None:
    """The linearised Cartesian covariance of a reading against the engine's Monte Carlo."""
    n = TrackerNoise.aguado2017()
    x = np.array([2500.0, 1200.0, -400.0])
    C = n.covariance(x)
    res = monte_carlo(lambda z: n.perturb(x, z), {"z": IID(Normal(0, 1), 3)}, trials=40_000, seed=5)
    assert np.allclose(res.cov, C, rtol=0.05, atol=0.03 * np.abs(C).max())


def test_noise_at_fixed_points_is_perturb_of_every_trial_bit_for_bit() -> None:
    """The spherical coordinates of fixed points, computed once, give perturb's very bits.

    Reference: the formula of Aguado et al. 2016 eqs. 22–24 written out here with NumPy on
    the points repeated for every trial (what perturb did for every block of trials).
    """
    from mtmc.instruments.laser_tracker import NoiseAt

    n = TrackerNoise.from_mpe(adm=(0.010, 0.3e-6), transverse=(0.015, 6e-6), conversion="typical")
    rng = np.random.default_rng(np.random.SeedSequence(8))
    x = rng.uniform(-3000.0, 3000.0, size=(57, 3))
    z = rng.normal(size=(11, 57, 3))
    xx = np.broadcast_to(x, z.shape)
    h = np.hypot(xx[..., 0], xx[..., 1])
    L = np.sqrt(h * h + xx[..., 2] ** 2)
    az, el = np.arctan2(xx[..., 1], xx[..., 0]), np.arctan2(xx[..., 2], h)
    uL = n.radial_a + n.radial_b * L
    ua, ue = n.azimuth + n.transverse_a / L, n.elevation + n.transverse_a / L
    L2, az2, el2 = L + uL * z[..., 0], az + ua * z[..., 1], el + ue * z[..., 2]
    ref = np.stack(
        [L2 * np.cos(el2) * np.cos(az2), L2 * np.cos(el2) * np.sin(az2), L2 * np.sin(el2)],
        axis=-1,
    )
    at = n.at(x)
    assert isinstance(at, NoiseAt)
    assert at.spherical.shape == (57, 3)
    assert not at.spherical.flags.writeable
    assert not at.u.flags.writeable
    np.testing.assert_array_equal(at.perturb(z), ref)
    np.testing.assert_array_equal(n.perturb(xx, z), ref)
    with pytest.raises(InputError, match="one shape"):
        NoiseAt(at.spherical, at.u[:3])


def test_visibility_names_failing_points_and_limits() -> None:
    lt = LaserTracker.from_euler([-1000.0, 0.0, 500.0], [0.0, 0.0, 0.0])
    pts = np.array([[0.0, 0.0, 0.0], [400.0, 0.0, 0.0], [0.0, 3000.0, 0.0], [0.0, 0.0, 2500.0]])
    rep = visibility(
        lt, pts, TrackerLimits(acceptance=(0.0, math.radians(30.0)), height=(0.0, 400.0))
    )
    assert not rep.ok
    which = {(f.point, f.limit) for f in rep.failures}
    assert which == {(-1, "height"), (2, "acceptance"), (3, "acceptance"), (3, "elevation")} or (
        which >= {(-1, "height"), (2, "acceptance"), (3, "acceptance")}
    )
    assert "point 2: acceptance" in rep.text()
    assert "tracker height 500.0 mm" in rep.text()
    ok = visibility(lt, pts[:2], TrackerLimits())
    assert ok.ok
    assert ok.text() == "all points visible"


def _geometry() -> tuple[np.ndarray, np.ndarray]:
    C = np.array([[0.0, 0, 0], [4000, 0, 100], [0, 3500, -100], [3800, 3600, 900]])
    P = np.random.default_rng(np.random.SeedSequence(2)).uniform(
        [500, 500, 0], [3000, 3000, 1200], (10, 3)
    )
    return C, P


def test_multilateration_recovers_exact_points_noise_free() -> None:
    C, P = _geometry()
    d = np.linalg.norm(P[None] - C[:, None], axis=-1)
    r = trilaterate(C, d)
    assert np.abs(r.points[0] - P).max() < 1e-9
    assert r.converged.all()
    r3 = trilaterate(C[:3], d[:3], points0=P + 5.0)
    assert np.abs(r3.points[0] - P).max() < 1e-9
    start = C + np.random.default_rng(np.random.SeedSequence(4)).normal(0, 3.0, C.shape)
    sc = self_calibrate(np.stack([d, d, d]), start)
    Cd, Pd = datum_frame(C, P)
    assert sc.converged.all()
    assert np.abs(sc.stations - Cd).max() < 1e-8
    assert np.abs(sc.points - Pd).max() < 1e-8


def _noisy_lengths() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Stations, points, three trials of lengths with 5 µm noise ``(3, 4, 10)``, a rough start."""
    C, P = _geometry()
    d = np.linalg.norm(P[None] - C[:, None], axis=-1)
    dn = d[None] + np.random.default_rng(np.random.SeedSequence(11)).normal(
        0.0, 0.005, (3, *d.shape)
    )
    start = C + np.random.default_rng(np.random.SeedSequence(4)).normal(0, 3.0, C.shape)
    return C, P, dn, start


def test_multilateration_batch_equals_one_trial_at_a_time() -> None:
    C, P, dn, start = _noisy_lengths()
    batch = (
        trilaterate(C, dn),
        trilaterate(C[:3], dn[:, :3], points0=P + 5.0),
        self_calibrate(dn, start),
        self_calibrate(dn, start, points0=P + 2.0),
    )
    for i in range(dn.shape[0]):
        alone = (
            trilaterate(C, dn[i]),
            trilaterate(C[:3], dn[i, :3], points0=P + 5.0),
            self_calibrate(dn[i], start),
            self_calibrate(dn[i], start, points0=P + 2.0),
        )
        for b, a in zip(batch, alone, strict=True):
            np.testing.assert_allclose(a.points[0], b.points[i], rtol=1e-12, atol=1e-9)
            np.testing.assert_allclose(a.stations[0], b.stations[i], rtol=1e-12, atol=1e-9)
            np.testing.assert_allclose(a.rms[0], b.rms[i], rtol=1e-9, atol=1e-12)


def test_multilateration_numbers_are_those_recorded() -> None:
    """The solvers' results on noisy lengths, as recorded (the starting points and the
    residuals of trilaterate and self_calibrate share one implementation since)."""
    C, P, dn, start = _noisy_lengths()
    r = trilaterate(C, dn)
    r3 = trilaterate(C[:3], dn[:, :3], points0=P + 5.0)
    sc = self_calibrate(dn, start)
    sc0 = self_calibrate(dn, start, points0=P + 2.0)
    recorded = [
        (r.points[2, 7], [1777.6564129465762, 2728.013143138636, 930.6968953022441]),
        (r.rms, [0.0015284656622243204, 0.0025124726541563493, 0.002466551376672751]),
        (r3.points[1, 4], [1581.5703933048235, 2173.240072467479, 507.35789242042944]),
        (sc.stations[2, 3], [3821.266908308998, 3575.609961490162, 907.2071887460563]),
        (sc.points[0, 9], [2236.8162156880794, 765.7328371142886, 91.55191181438717]),
        (sc.rms, [0.0008689712907278235, 0.0014023060264021505, 0.0018681506047810627]),
        (sc0.points[1, 0], [1178.1061472401495, 1218.6182697480085, 983.1461880325887]),
        (sc0.rms, [0.0008689712907319536, 0.0014023060263023417, 0.0018681506047473885]),
    ]
    for got, want in recorded:
        np.testing.assert_allclose(got, want, rtol=1e-9)
    assert np.all(r3.rms < 1e-9)  # three stations: the lengths are met exactly
    assert (r.iterations, r3.iterations, sc.iterations, sc0.iterations) == (3, 4, 5, 4)


def test_multilateration_starting_points_of_a_wrong_shape() -> None:
    C, P, dn, start = _noisy_lengths()
    with pytest.raises(InputError, match=r"starting points of shape \(10, 3\)") as info:
        trilaterate(C, dn, points0=P[:4])
    assert info.value.field == "points0"
    with pytest.raises(InputError, match="mirror ambiguity"):
        trilaterate(C[:3], dn[:, :3])
    with pytest.raises(InputError, match="starting points of shape"):
        self_calibrate(dn, start, points0=P[:, :2])


def test_self_calibration_needs_four_stations_and_enough_points() -> None:
    C, P = _geometry()
    d = np.linalg.norm(P[None] - C[:, None], axis=-1)
    with pytest.raises(InputError, match="at least four stations"):
        self_calibrate(d[:3], C[:3])
    with pytest.raises(InputError, match="need at least 6 points"):
        self_calibrate(d[:, :5], C)


def test_multilateration_beats_one_tracker_at_long_range() -> None:
    """At ~5 m, 24 µrad is ~120 µm across the beam; four lengths of 4 µm + 0.8 µm/m give < 15 µm."""
    C = np.array([[0.0, 0, 0], [6000, 0, 3000], [0, 6000, 3000], [6000, 6000, 0]])
    P = np.array([[3000.0, 3000.0, 600.0]])
    n = TrackerNoise.aguado2017()
    L = np.linalg.norm(P[None] - C[:, None], axis=-1)  # (4, 1)
    cov_multi = trilateration_covariance(C, P, n.u_range(L))
    lt = LaserTracker(np.eye(3), C[0], n)
    cov_single = lt.point_covariance(P)
    u_multi = math.sqrt(np.trace(cov_multi[0]))
    u_single = math.sqrt(np.trace(cov_single[0]))
    assert u_multi < 0.015 < 0.1 < u_single

    # and by Monte Carlo through the engine: lengths with noise, solved by trilateration
    def model(z: np.ndarray) -> np.ndarray:
        d = L[None] + n.u_range(L)[None] * z.reshape(-1, 4, 1)
        return trilaterate(C, d, points0=P).points[:, 0, :]

    res = monte_carlo(model, {"z": IID(Normal(0, 1), 4)}, trials=4000, seed=9)
    assert math.sqrt(np.trace(res.cov)) == pytest.approx(u_multi, rel=0.06)
