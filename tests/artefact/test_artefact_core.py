"""The artefact, the probing and the sphere fit (Wang, Cheung and Kong 2022, §2.3, Table 1)."""

from __future__ import annotations

import math
from itertools import combinations
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import least_squares

from mtmc.artefact import (
    distances,
    fit_points,
    fit_sensitivity,
    load_points,
    loads_artefact,
    patch_points,
    shipped_artefact,
)
from mtmc.errors import InputError
from mtmc.geometry import fit_sphere
from mtmc.uncertainty import monte_carlo
from mtmc.uncertainty.distributions import IID, Normal

ROOT = Path(__file__).resolve().parents[2]
# Table 1 of the paper (tests/reference/wang2022/table1.csv): the calibrated ball centres, mm
TABLE1 = [
    tuple(row)
    for row in np.loadtxt(
        Path(__file__).resolve().parents[1] / "reference" / "wang2022" / "table1.csv",
        delimiter=",",
        skiprows=1,
    ).tolist()
]
R = 9.997 / 2


def test_shipped_artefact_is_table1_and_examples_copy() -> None:
    a = shipped_artefact()
    assert a.names == ("1", "2", "3", "4", "5")
    assert a.centres.tolist() == [list(c) for c in TABLE1]
    assert a.centres[1, 1] == 0.864597  # printed with six decimals, kept as printed
    assert a.diameter == 9.997
    assert not a.centres.flags.writeable
    shipped = ROOT / "src/mtmc/data/artefacts/wang2022_five_ball.toml"
    example = ROOT / "examples/artefacts/wang2022_five_ball.toml"
    assert shipped.read_text() == example.read_text()


def test_distances_against_hand_computation() -> None:
    hand = [math.dist(p, q) for p, q in combinations(TABLE1, 2)]
    got = distances(shipped_artefact().centres)
    assert got.shape == (10,)
    np.testing.assert_allclose(got, hand, rtol=0, atol=1e-12)
    # batched: a leading trial axis
    batch = distances(np.stack([shipped_artefact().centres] * 3))
    np.testing.assert_array_equal(batch, np.stack([got] * 3))


def test_cmm_covariance_gives_the_stated_distance_uncertainty() -> None:
    a = shipped_artefact()
    V = a.centre_covariance()
    c = a.centres
    for k, (i, j) in enumerate(combinations(range(5), 2)):
        u = (c[i] - c[j]) / np.linalg.norm(c[i] - c[j])
        g = np.zeros(15)
        g[3 * i : 3 * i + 3], g[3 * j : 3 * j + 3] = u, -u
        L = np.linalg.norm(c[i] - c[j])
        expected = math.sqrt(0.25**2 + (L / 300.0) ** 2)  # um
        assert math.sqrt(g @ V @ g) * 1e3 == pytest.approx(expected, rel=1e-12)
        assert a.distance_uncertainty()[k] == pytest.approx(expected, rel=1e-12)
        assert expected <= a.length_uncertainty(L)  # quadrature <= printed linear sum
    assert np.all(np.linalg.eigvalsh(V) > 0)


def test_artefact_file_errors_name_file_line_field() -> None:
    text = (
        'name = "x"\ndiameter = 10.0\n[[ball]]\nname = "1"\ncentre = [1, 2]\n'
        '[[ball]]\nname = "2"\ncentre = [1, 2, 3]\n'
    )
    with pytest.raises(InputError) as e:
        loads_artefact(text, file="a.toml")
    assert (e.value.file, e.value.line, e.value.field) == ("a.toml", 5, "ball[0].centre")
    with pytest.raises(InputError) as e:
        loads_artefact(text.replace("diameter = 10.0", "").replace("[1, 2]", "[0, 0, 0]"), "b.toml")
    assert "diameter" in str(e.value)
    assert e.value.file == "b.toml"
    with pytest.raises(InputError) as e:
        loads_artefact("diameter = -1\n", file="c.toml")
    assert e.value.line == 1
    assert e.value.field == "diameter"


def _odr_longdouble(P: np.ndarray, radius: float | None) -> np.ndarray:
    """Independent Gauss-Newton on |p - c| - r in extended precision (np.longdouble)."""
    X = P.astype(np.longdouble)
    c = X.mean(axis=0) - np.array([0, 0, 1], dtype=np.longdouble)  # below a top patch
    r = np.longdouble(radius) if radius is not None else np.longdouble(R)
    for _ in range(60):
        D = X - c
        rho = np.sqrt((D * D).sum(axis=1))
        res = rho - r
        J = np.concatenate([-(D / rho[:, None]), -np.ones((len(X), 1), np.longdouble)], axis=1)
        if radius is not None:
            J = J[:, :3]
        # normal equations solved by hand in longdouble (3x3 or 4x4 Gaussian elimination)
        A = J.T @ J
        g = -(J.T @ res)
        n = A.shape[0]
        M = np.concatenate([A, g[:, None]], axis=1)
        for i in range(n):
            M[i] /= M[i, i]
            for k in range(n):
                if k != i:
                    M[k] -= M[k, i] * M[i]
        step = M[:, -1]
        c = c + step[:3]
        if radius is None:
            r = r + step[3]
    return np.asarray(c, dtype=np.float64)


def test_sphere_fit_is_orthogonal_distance_against_high_precision() -> None:
    rng = np.random.default_rng(np.random.SeedSequence(31))
    P = patch_points([1.0, -2.0, 3.0], R) + rng.normal(0, 2e-3, (30, 3))  # exaggerated noise
    for radius in (None, R):
        got = fit_sphere(P, radius).geometry.centre[0]  # type: ignore[union-attr]
        ref = _odr_longdouble(P, radius)
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-10)
        # scipy least_squares at tight tolerance, a second method
        if radius is None:
            sol = least_squares(
                lambda t: np.linalg.norm(P - t[:3], axis=1) - t[3],
                np.r_[ref + 0.01, R],
                xtol=1e-15,
                ftol=1e-15,
                gtol=1e-15,
            ).x[:3]
        else:
            sol = least_squares(
                lambda t: np.linalg.norm(P - t, axis=1) - R,
                ref + 0.01,
                xtol=1e-15,
                ftol=1e-15,
                gtol=1e-15,
            ).x
        np.testing.assert_allclose(got, sol, rtol=0, atol=1e-9)
    # the algebraic fit alone is measurably different: the test can tell them apart
    X = P - P.mean(axis=0)
    z = (X * X).sum(axis=1)
    alg = 0.5 * np.linalg.solve(X.T @ X, X.T @ z) + P.mean(axis=0)
    assert np.abs(alg - _odr_longdouble(P, None)).max() > 1e-6


@pytest.mark.parametrize("radius", [None, R])
def test_thirty_exact_points_give_the_centre_to_1e9_mm(radius: float | None) -> None:
    centre = np.array([59.31108, -0.25560, 14.99509])
    for axis in ([0, 0, 1], [1, 0, 0], [0.3, -0.5, 0.8]):
        P = patch_points(centre, R, axis)
        assert P.shape == (30, 3)
        span = P.max(axis=0) - P.min(axis=0)
        assert sorted(span)[1] == pytest.approx(5.0, abs=0.1) or max(span) < 6.1
        f = fit_points(P, radius)
        np.testing.assert_allclose(f.centre, centre, rtol=0, atol=1e-9)
        assert f.rms < 1e-9
        assert f.n == 30


def test_fit_covariance_against_monte_carlo() -> None:
    """The fit's covariance s^2 (J^T J)^-1 and its linear map K against MC of the fit."""
    P0 = patch_points([0.0, 0.0, 0.0], R)
    sigma = np.array([0.36, 0.41, 0.25]) * 1e-3  # per axis, mm

    def model(e: np.ndarray) -> np.ndarray:
        pts = P0 + e.reshape(-1, 30, 3) * sigma
        return fit_sphere(pts, np.full(len(e), R)).geometry.centre  # type: ignore[union-attr]

    res = monte_carlo(model, {"e": IID(Normal(0, 1), 90)}, trials=4000, seed=2022)
    K = fit_sensitivity(P0, [0.0, 0.0, 0.0])[0]
    V_lin = K @ np.diag(np.tile(sigma**2, 30)) @ K.T
    # variances within MC tolerance (4000 trials: relative sd of a variance ~ 2.2 %)
    np.testing.assert_allclose(np.diag(res.cov), np.diag(V_lin), rtol=0.12)
    # the fit's own covariance assumes isotropic noise: compare with isotropic MC
    iso = 0.35e-3

    def model_iso(e: np.ndarray) -> np.ndarray:
        pts = P0 + e.reshape(-1, 30, 3) * iso
        return fit_sphere(pts, np.full(len(e), R)).geometry.centre  # type: ignore[union-attr]

    res2 = monte_carlo(model_iso, {"e": IID(Normal(0, 1), 90)}, trials=4000, seed=7)
    f = fit_sphere(P0 + np.random.default_rng(3).normal(0, iso, (30, 3)), R)
    assert f.covariance is not None
    np.testing.assert_allclose(np.diag(res2.cov), np.diag(f.covariance[0]), rtol=0.35)
    Kf = fit_sensitivity(P0, [0.0, 0.0, 0.0])[0]
    np.testing.assert_allclose(np.diag(res2.cov), np.diag(Kf @ Kf.T) * iso**2, rtol=0.12)


def test_linear_map_matches_the_converged_fit() -> None:
    rng = np.random.default_rng(np.random.SeedSequence(5))
    P0 = patch_points([1.0, 2.0, 3.0], R)
    eps = rng.normal(0, 0.4e-3, (200, 30, 3))
    for free in (False, True):
        K = fit_sensitivity(P0, [1.0, 2.0, 3.0], free)[0]
        lin = np.array([1.0, 2.0, 3.0]) + eps.reshape(200, 90) @ K.T
        fit = fit_sphere(P0 + eps, None if free else np.full(200, R))
        full = fit.geometry.centre  # type: ignore[union-attr]
        # second order in the noise, amplified by the cap's conditioning: measured
        # 2e-7 mm (known radius) and 2e-6 mm (free), ~0.1 % of the centre's u
        assert np.abs(lin - full).max() < (1e-6 if not free else 1e-5)


def test_load_points_csv_units_header_and_partial_cap(tmp_path: Path) -> None:
    rng = np.random.default_rng(np.random.SeedSequence(11))
    # a real-scan-like partial cap: 5000 points within 25 degrees of the pole, in metres
    n = 5000
    th = np.arccos(1 - rng.uniform(0, 1 - math.cos(math.radians(25)), n))
    ph = rng.uniform(0, 2 * np.pi, n)
    c = np.array([10.0, -20.0, 5.0])
    pts = c + R * np.column_stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)])
    pts += rng.normal(0, 0.2e-3, pts.shape)
    f = tmp_path / "scan.csv"
    f.write_text(
        "x,y,z\n" + "\n".join(f"{x / 1e3!r},{y / 1e3!r},{z / 1e3!r}" for x, y, z in pts.tolist())
    )
    P = load_points(f, "m")
    np.testing.assert_allclose(P, pts, rtol=1e-15, atol=1e-12)
    fit = fit_points(P)
    assert abs(fit.radius - R) < 5e-4
    assert np.abs(np.array(fit.centre) - c).max() < 5e-4
    assert fit.u_radius > 0
    assert fit.n == n
    g = tmp_path / "plain.csv"
    g.write_text("\n".join(f"{x!r} {y!r} {z!r}" for x, y, z in (pts[:10] * 1e3).tolist()))
    np.testing.assert_allclose(load_points(g, "um"), pts[:10], rtol=1e-12)
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y,z\n1,2,3\n1,2\n")
    with pytest.raises(InputError) as e:
        load_points(bad)
    assert e.value.line == 3
    assert e.value.file == str(bad)
    with pytest.raises(InputError):
        load_points(g, "inch")
