"""Distances, r_max/r_avg, best-fit residuals and the gravity statistics against hand work."""

from __future__ import annotations

import math
from itertools import combinations
from pathlib import Path

import numpy as np
import pytest

from mtmc.artefact.analysis import analyse, rigid_fit_residuals
from mtmc.artefact.gravity import gravity_effect, load_gravity
from mtmc.errors import InputError

# Table 1 of the paper (tests/reference/wang2022/table1.csv): the calibrated ball centres, mm
TABLE1 = [
    tuple(row)
    for row in np.loadtxt(
        Path(__file__).resolve().parents[1] / "reference" / "wang2022" / "table1.csv",
        delimiter=",",
        skiprows=1,
    ).tolist()
]


def _hand_r(measured: list[tuple[float, float, float]]) -> tuple[float, float, list[float]]:
    r = [
        math.dist(measured[i], measured[j]) - math.dist(TABLE1[i], TABLE1[j])
        for i, j in combinations(range(5), 2)
    ]
    return max(abs(x) for x in r), sum(abs(x) for x in r) / len(r), r


def test_r_max_r_avg_against_hand_computation_on_table1() -> None:
    # measured centres: Table 1 with a few micrometres added by hand, one pose, one repetition
    shifts = [(1e-3, 0, 0), (0, -2e-3, 0), (0, 0, 3e-3), (-1.5e-3, 0.5e-3, 0), (0, 0, 0)]
    meas = [
        tuple(c + s for c, s in zip(p, d, strict=True)) for p, d in zip(TABLE1, shifts, strict=True)
    ]
    r_max, r_avg, r = _hand_r(meas)  # type: ignore[arg-type]
    m = np.array(meas)[None, None, None]  # (M=1, R=1, P=1, N=5, 3)
    pinv = np.zeros((18, 15))  # no setup errors identified: modelled = measured
    a = analyse(m, np.array(TABLE1), pinv, np.zeros((1, 5, 3, 3)))
    np.testing.assert_allclose(a.distance_error_measured[0, 0], r, rtol=0, atol=1e-12)
    assert a.r_max_measured[0, 0] == pytest.approx(r_max, abs=1e-12)
    assert a.r_avg_measured[0, 0] == pytest.approx(r_avg, abs=1e-12)
    np.testing.assert_array_equal(a.r_max_model, a.r_max_measured)
    assert round(r_max * 1e3, 1) == 2.2  # um, as Table 2 prints them
    assert not a.r_max_measured.flags.writeable


def test_rigid_fit_residuals_recover_a_pure_deformation() -> None:
    rng = np.random.default_rng(np.random.SeedSequence(4))
    ref = np.array(TABLE1)
    dev = rng.normal(0, 1e-3, ref.shape)
    dev -= dev.mean(axis=0)  # no translation part
    # remove the infinitesimal rotation part so that dev is the residual exactly (to 1e-12)
    A = np.zeros((15, 3))
    X = ref - ref.mean(axis=0)
    for i in range(5):
        A[3 * i : 3 * i + 3] = np.array(
            [[0, X[i, 2], -X[i, 1]], [-X[i, 2], 0, X[i, 0]], [X[i, 1], -X[i, 0], 0]]
        )
    w = np.linalg.lstsq(A, dev.reshape(-1), rcond=None)[0]
    dev = dev - (A @ w).reshape(5, 3)
    Rz = np.array([[np.cos(0.3), -np.sin(0.3), 0], [np.sin(0.3), np.cos(0.3), 0], [0, 0, 1]])
    moved = (ref + dev) @ Rz.T + [10.0, -5.0, 2.0]
    res = rigid_fit_residuals(moved, ref)
    np.testing.assert_allclose(res, dev, rtol=0, atol=1e-9)
    # batched over a leading axis = one at a time
    both = rigid_fit_residuals(np.stack([moved, ref + dev]), ref)
    np.testing.assert_allclose(both[0], res, atol=1e-13)
    np.testing.assert_allclose(both[1], res, atol=1e-9)


def test_setup_correction_and_volumetric_errors() -> None:
    """modelled = measured - dw + J_p dp, volumetric = modelled - calibrated."""
    rng = np.random.default_rng(np.random.SeedSequence(8))
    cal = np.array(TABLE1)
    m = cal + rng.normal(0, 1e-3, (2, 3, 5, 3))  # R = 2, P = 3
    Jp = rng.normal(size=(3, 5, 3, 3))
    pinv = rng.normal(size=(18, 90)) * 1e-2
    a = analyse(m[None], cal, pinv, Jp)
    E = (cal[None, None] - m).reshape(-1) @ pinv.T
    mean = m.mean(axis=0)
    modelled = mean - E[3:].reshape(5, 3)[None] + np.einsum("pnij,j->pni", Jp, E[:3])
    np.testing.assert_allclose(a.setup[0], E, atol=1e-15)
    np.testing.assert_allclose(a.modelled[0], modelled, atol=1e-14)
    np.testing.assert_allclose(a.volumetric[0], modelled - cal, atol=1e-14)


def test_gravity_against_hand_computation(tmp_path: Path) -> None:
    # three repetitions in H and V, two in O, two balls, mm
    rows = [
        ("H", "1", 10.0, 0.0, 5.0),
        ("H", "1", 10.0002, 0.0, 5.0),
        ("H", "1", 9.9998, 0.0, 5.0),
        ("H", "2", -10.0, 1.0, 6.0),
        ("H", "2", -10.0, 1.0, 6.0),
        ("H", "2", -10.0, 1.0, 6.0),
        ("V", "1", 10.001, 0.0, 5.002),
        ("V", "1", 10.001, 0.0, 5.002),
        ("V", "1", 10.001, 0.0, 5.002),
        ("V", "2", -10.0, 0.9985, 6.0),
        ("V", "2", -10.0, 0.9985, 6.0),
        ("V", "2", -10.0, 0.9985, 6.0),
        ("O", "1", 10.0, 0.0003, 5.0),
        ("O", "1", 10.0, 0.0001, 5.0),
        ("O", "2", -10.0, 1.0, 5.9996),
        ("O", "2", -10.0, 1.0, 5.9994),
    ]
    g = gravity_effect(rows)
    assert g.orientations == ("O", "V")
    assert g.balls == ("1", "2")
    # by hand, um: V-H ball 1 (1, 0, 2), ball 2 (0, -1.5, 0)
    # O-H ball 1 (0, 0.2, 0), ball 2 (0, 0, -0.5)
    np.testing.assert_allclose(g.delta[1] * 1e3, [[1, 0, 2], [0, -1.5, 0]], atol=1e-9)
    np.testing.assert_allclose(g.delta[0] * 1e3, [[0, 0.2, 0], [0, 0, -0.5]], atol=1e-9)
    np.testing.assert_allclose(g.delta_d[1] * 1e3, [math.sqrt(5), 1.5], atol=1e-9)
    np.testing.assert_allclose(g.mean_abs[1] * 1e3, [0.5, 0.75, 1.0], atol=1e-9)
    assert g.mean_d[1] * 1e3 == pytest.approx((math.sqrt(5) + 1.5) / 2, abs=1e-9)
    assert g.mean_d[0] * 1e3 == pytest.approx(0.35, abs=1e-9)
    f = tmp_path / "g.csv"
    f.write_text("orientation,ball,x,y,z\n" + "\n".join(",".join(map(str, r)) for r in rows))
    np.testing.assert_array_equal(load_gravity(f).delta, g.delta)
    bad = tmp_path / "bad.csv"
    bad.write_text("orientation,ball,x,y,z\nH,1,0,0,0\nX,1,0,0,0\n")
    with pytest.raises(InputError) as e:
        load_gravity(bad)
    assert e.value.line == 3
    with pytest.raises(InputError):
        gravity_effect([("H", "1", 0, 0, 0), ("V", "2", 0, 0, 0)])


def test_best_rotation_newton_polar_against_the_svd() -> None:
    from mtmc.artefact.analysis import _kabsch_svd, best_rotation
    from mtmc.geometry.transforms import matrix_from_euler

    rng = np.random.default_rng(np.random.SeedSequence(31))
    B = 500
    Y = rng.normal(size=(B, 5, 3)) * np.array([60.0, 30.0, 5.0])
    R = np.asarray(matrix_from_euler(rng.normal(size=(B, 3)), "zyx")).reshape(B, 3, 3)
    X = np.einsum("bji,bnj->bni", R, Y) + rng.normal(size=(B, 5, 3)) * 1e-3
    X[: B // 2] = Y[: B // 2] + rng.normal(size=(B // 2, 5, 3)) * 1e-3  # near the identity
    H = np.swapaxes(X - X.mean(1, keepdims=True), -1, -2) @ (Y - Y.mean(1, keepdims=True))
    H[:3, :, 2] *= -1.0  # det H < 0: a reflection would fit better, the SVD path
    H[3] = 0.0  # singular
    got, ref = best_rotation(H), _kabsch_svd(H)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12)
    np.testing.assert_allclose(
        got @ np.swapaxes(got, -1, -2), np.broadcast_to(np.eye(3), H.shape), atol=1e-14
    )
    np.testing.assert_allclose(np.linalg.det(got), 1.0, rtol=0, atol=1e-13)
    # batched over any leading axes = one matrix at a time
    one = np.stack([best_rotation(h) for h in H[:20]])
    np.testing.assert_allclose(
        best_rotation(H[:20].reshape(4, 5, 3, 3)).reshape(20, 3, 3), one, rtol=0, atol=1e-15
    )
