"""Machine model and setup-error identification (Wang, Cheung and Kong 2022, eqs. 3-20)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from mtmc.artefact import (
    FiducialSetup,
    identify_setup,
    paper_jacobian,
    setup_error_names,
    shipped_artefact,
)
from mtmc.errors import InputError
from mtmc.kinematics import Machine

DEG = np.pi / 180
NINE = np.array([[b, c] for b in (0, 5, 10) for c in (0, 5, -5)]) * DEG
PROBE = np.array([30.0, -4.0, 50.0])


def _setup(topology: str = "wBZfXYCt") -> FiducialSetup:
    art = shipped_artefact().mounted([0.0, 0.0, 20.0])
    return FiducialSetup(Machine.from_topology(topology, tool=PROBE), art)


def test_commanded_positions_put_the_nominal_probe_on_each_ball() -> None:
    s = _setup()
    q = s.commanded(NINE)  # (9, 5, 3)
    assert q.shape == (9, 5, 3)
    full = np.concatenate([q, np.repeat(NINE[:, None, :], 5, axis=1)], axis=2).reshape(-1, 5)
    f = s.machine.tool_position(full).reshape(9, 5, 3)
    np.testing.assert_allclose(
        f, np.broadcast_to(s.artefact.mounted_centres(), f.shape), atol=1e-12
    )
    # eqs. 10 and 14 typed in (paper's b and z are mtmc's -b and -z): the probe centre
    # x + R_C p equals the fiducial z + R_B w in the frame F
    x, y, z = q[..., 0], q[..., 1], q[..., 2]
    b, c = -NINE[:, 0], NINE[:, 1]
    RC = Rotation.from_euler("z", c[:, None]).as_matrix()
    RB = Rotation.from_euler("y", b[:, None]).as_matrix()
    probe = np.stack([x, y, np.zeros_like(x)], -1) + np.einsum("pij,j->pi", RC, PROBE)[:, None]
    w = s.artefact.mounted_centres()
    fid = np.stack([0 * x, 0 * y, -z], -1) + np.einsum("pij,nj->pni", RB, w)
    np.testing.assert_allclose(probe, fid, atol=1e-12)


def test_paper_jacobian_is_the_w_frame_jacobian_rotated_by_RB() -> None:
    s = _setup()
    JW = s.setup_jacobian(NINE).reshape(9, 5, 3, 18)
    RB = Rotation.from_euler("y", -NINE[:, :1]).as_matrix()
    JF = np.einsum("pij,pnjk->pnik", RB, JW).reshape(-1, 18)
    Jp = paper_jacobian(-NINE[:, 0], NINE[:, 1], 5)
    np.testing.assert_allclose(JF, Jp, atol=1e-12)
    # eq. 19 as printed ends with I3 where eq. 16 gives R_C: different unless c = 0
    last = Jp.reshape(9, 5, 3, 18)[1, 4, :, :3]  # c = 5 deg, ball 5
    assert np.abs(last - np.eye(3)).max() > 0.08
    np.testing.assert_allclose(last, Rotation.from_euler("z", 5 * DEG).as_matrix(), atol=1e-15)


@pytest.mark.parametrize("topology", ["wBZfXYCt", "wCAXfYZt"])
def test_noise_free_setup_errors_recovered(topology: str) -> None:
    s = _setup(topology)
    rng = np.random.default_rng(np.random.SeedSequence(16))
    E = rng.normal(0, 3e-3, 18)  # mm
    meas = s.measure(NINE, setup=E)
    dF = (s.artefact.mounted_centres()[None] - meas.centres).reshape(-1)
    idn = identify_setup(s.setup_jacobian(NINE), dF, setup_error_names(s.artefact.names))
    assert idn.full_rank
    assert idn.rank == 18
    assert np.abs(idn.estimate - E).max() < 1e-9  # mm, i.e. 1e-6 um
    assert not idn.estimate.flags.writeable


def test_single_pose_rank_deficiency_and_its_combinations() -> None:
    s = _setup()
    names = setup_error_names(s.artefact.names)
    one = identify_setup(s.setup_jacobian(NINE[:1]), np.zeros(15), names)
    assert (one.rank, one.full_rank) == (15, False)
    assert s.setup_jacobian(NINE[:1]).shape == (15, 18)
    combos = one.unidentifiable()
    assert combos == [
        "+1·dpx +1·dw1x +1·dw2x +1·dw3x +1·dw4x +1·dw5x",
        "+1·dpy +1·dw1y +1·dw2y +1·dw3y +1·dw4y +1·dw5y",
        "+1·dpz +1·dw1z +1·dw2z +1·dw3z +1·dw4z +1·dw5z",
    ]
    assert np.isinf(one.u).all()
    # C alone (b = 0): the probe's z offset and a common z shift stay confounded
    conly = identify_setup(s.setup_jacobian(NINE[:3]), np.zeros(45), names)
    assert conly.rank == 17
    assert conly.unidentifiable() == ["+1·dpz +1·dw1z +1·dw2z +1·dw3z +1·dw4z +1·dw5z"]
    assert np.isfinite(conly.u[:2]).all()
    assert np.isinf(conly.u[2])
    # the nine-pose plan is full rank
    nine = identify_setup(s.setup_jacobian(NINE), np.zeros(135), names)
    assert nine.full_rank
    assert nine.null_space.shape == (0, 18)


def test_identification_covariance_against_explicit_formula() -> None:
    s = _setup()
    J = s.setup_jacobian(NINE)
    rng = np.random.default_rng(np.random.SeedSequence(2))
    sig = rng.uniform(0.1e-3, 0.3e-3, J.shape[0])
    idn = identify_setup(J, rng.normal(0, 1e-3, J.shape[0]), setup_error_names("12345"), sig**2)
    P = np.linalg.pinv(J)
    ref = P @ np.diag(sig**2) @ P.T
    np.testing.assert_allclose(idn.covariance, ref, rtol=0, atol=1e-9 * np.abs(ref).max())
    # with equal weights the LS covariance is s^2 (J^T J)^-1
    V = identify_setup(J, rng.normal(0, 1e-3, J.shape[0]), setup_error_names("12345"))
    s2 = float(V.residuals @ V.residuals) / (J.shape[0] - 18)
    ref = s2 * np.linalg.inv(J.T @ J)
    np.testing.assert_allclose(V.covariance, ref, rtol=0, atol=1e-9 * np.abs(ref).max())


def test_bad_input() -> None:
    s = _setup()
    with pytest.raises(InputError):
        s.measure(NINE, setup=np.zeros(5))
    with pytest.raises(InputError):
        s.measure(NINE, errors={"EXT": 1e-3})
    with pytest.raises(InputError):
        s.commanded(np.zeros((3, 3)))
    with pytest.raises(InputError):
        FiducialSetup(Machine.from_topology("wCAXfYt"), shipped_artefact())


def test_vectors_in_axes_are_moved_back_by_the_axis_map() -> None:
    """``Measurement.in_axes`` is the inverse of ``A``: ``A · in_axes(w) = w`` at each pose
    (a solve of well-conditioned 3 × 3 systems: 1e-12 of the mm size of w)."""
    meas = _setup().measure(NINE)
    w = np.random.default_rng(3).normal(size=meas.centres.shape)
    back = np.einsum("pij,pnj->pni", meas.axis_map, meas.in_axes(w))
    np.testing.assert_allclose(back, w, atol=1e-12)
