"""Aguado's equations written out by hand against mtmc's chain with the mapped errors.

Aguado et al. 2017, eqs. (1), (6)-(9): the XFYZ machine. Aguado et al. 2016, eqs. (3),
(9)-(12): the ZYXF machine. The error vectors and matrices (2017 eqs. 6-9, 2016 eqs. 9-12)
are typed as printed; the two chains are not. 2017 eq. 1 prints "+ Y - Z" after the
bracket of R_y; typed here is our reading "+ Y - X" (the part-side X, which the printed
line does not contain elsewhere), with the laser-tracker transform set to the identity.
2016 eq. 3 prints T_t = R(z)(R(y)(R(z) T_p + X) + Y) + z; typed here is our reconstruction
T_t = R(z)(R(y)(R(x) T_p + X) + Y) + Z (the inner R(z) read as R(x), the lower-case z as
the vector Z of eq. 11). Both are evaluated with exact matrix inverses and compared with
``Machine.tool_position`` given :func:`iso_errors_from_aguado`. The two agree to first
order in the errors: the tolerance is well above the second-order terms (ε² L, ε δ) and
well below the first-order ones the mapping is about (k ε, the lever of the pivot).
"""

from __future__ import annotations

import numpy as np
import pytest

from mtmc.errors import InputError, TopologyError
from mtmc.kinematics import Machine, Topology, iso_errors_from_aguado

Q = np.array(
    [[0.0, 0.0, 0.0], [800.0, 300.0, 150.0], [1500.0, -400.0, 600.0], [-200.0, 900.0, -350.0]]
)
TOOL = np.array([12.0, -7.0, 180.0])


def _errors(seed: int, names: list[str]) -> dict[str, float]:
    rng = np.random.default_rng(seed)
    out = {}
    for n in names:
        scale = 5e-3 if n[0] == "d" else 2e-5  # mm for δ, rad for ε and S
        out[n] = float(rng.uniform(-1, 1) * scale)
    return out


def _names(axes: str, squareness: list[str]) -> list[str]:
    return [f"{p}{c}{k}" for k in axes for p in "de" for c in "xyz"] + squareness


def _r_active(e: np.ndarray) -> np.ndarray:
    """Aguado et al. 2017, eq. (6)."""
    ex, ey, ez = e
    return np.array([[1, -ez, ey], [ez, 1, -ex], [-ey, ex, 1]])


def _r_passive(e: np.ndarray) -> np.ndarray:
    """Aguado et al. 2016, eq. (12): [[1, ECK, -EBK], [-ECK, 1, EAK], [EBK, -EAK, 1]]."""
    ea, eb, ec = e
    return np.array([[1, ec, -eb], [-ec, 1, ea], [eb, -ea, 1]])


def _vec(err: dict[str, float], p: str, k: str) -> np.ndarray:
    return np.array([err.get(f"{p}{c}{k}", 0.0) for c in "xyz"])


def _xfyz_by_hand(q: np.ndarray, err: dict[str, float]) -> np.ndarray:
    """Aguado et al. 2017, eq. (1) with eqs. (5)-(9), R_LT = I and T_LT = 0."""
    x, y, z = q
    dx, dy, dz = (_vec(err, "d", k) for k in "xyz")
    X = np.array([-x + dx[0], dx[1], dx[2]])  # eq. 7
    Y = np.array([dy[0] - y * err["Sxy"], y + dy[1], dy[2]])  # eq. 8
    Z = np.array([dz[0] - z * err["Sxz"], dz[1] - z * err["Syz"], z + dz[2]])  # eq. 9
    rx, ry, rz = (_r_active(_vec(err, "e", k)) for k in "xyz")
    return np.linalg.solve(rx, ry @ (rz @ TOOL + Z) + Y - X)  # eq. 1, "- X" for its "- Z"


def _zyxf_by_hand(q: np.ndarray, err: dict[str, float]) -> np.ndarray:
    """Aguado et al. 2016, eq. (3) solved for T_p, with eqs. (9)-(12); Z moves the part."""
    x, y, z = q
    dx, dy, dz = (_vec(err, "d", k) for k in "xyz")
    X = np.array([-x + dx[0], -x * err["Syx"] + dx[1], -x * err["Szx"] + dx[2]])  # eq. 9
    Y = np.array([dy[0], -y + dy[1], -y * err["Szy"] + dy[2]])  # eq. 10
    Z = np.array([dz[0], dz[1], -z + dz[2]])  # eq. 11, the part-side sign
    rx, ry, rz = (_r_passive(_vec(err, "e", k)) for k in "xyz")
    # eq. (3) as reconstructed (printed: R(z)(R(y)(R(z) T_p + X) + Y) + z):
    # T_t = R(z)(R(y)(R(x) T_p + X) + Y) + Z, the tool T_t fixed on the frame
    return np.linalg.solve(rx, np.linalg.solve(ry, np.linalg.solve(rz, TOOL - Z) - Y) - X)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_xfyz_reproduces_aguado_2017_eqs_1_to_9(seed):
    err = _errors(seed, _names("xyz", ["Sxy", "Sxz", "Syz"]))
    want = np.array([_xfyz_by_hand(q, err) for q in Q])
    machine = Machine.from_topology("XFYZ", tool=TOOL)
    got = machine.tool_position(Q, iso_errors_from_aguado("XFYZ", Q, err))
    np.testing.assert_allclose(got, want, rtol=0, atol=5e-6)
    # the pivot term matters: without the lever x·ε of the part-side X the error is
    # first order (here up to ~1500 mm × 2e-5 rad)
    naive = dict(iso_errors_from_aguado("XFYZ", Q, {k: v for k, v in err.items()}))
    naive["EYX"] = np.full(len(Q), -err["dyx"])
    naive["EZX"] = np.full(len(Q), -err["dzx"])
    off = np.abs(machine.tool_position(Q, naive) - want).max()
    assert off > 1e-3


@pytest.mark.parametrize("seed", [4, 5, 6])
def test_zyxf_reproduces_aguado_2016_eqs_3_and_9_to_12(seed):
    err = _errors(seed, _names("xyz", ["Syx", "Szx", "Szy"]))
    want = np.array([_zyxf_by_hand(q, err) for q in Q])
    iso = iso_errors_from_aguado("ZYXF", Q, err, rotation="passive")
    machine = Machine.from_topology("ZYXF", tool=TOOL)
    assert str(machine.topology) == "wXYZft"
    np.testing.assert_allclose(machine.tool_position(Q, iso), want, rtol=0, atol=5e-6)
    # the other reading of ZYXF (Z carrying the part, X on the frame) is not this machine
    other = Machine(Topology(part_axes=("Z", "Y", "X"), tool_axes=()), tool=TOOL)
    iso_other = iso_errors_from_aguado(other.topology, Q, err, rotation="passive")
    assert np.abs(other.tool_position(Q, iso_other) - want).max() > 1e-3


def test_nominal_positions_without_errors():
    for spec in ("XFYZ", "ZYXF"):
        machine = Machine.from_topology(spec, tool=TOOL)
        got = machine.tool_position(Q, iso_errors_from_aguado(spec, Q, {}))
        np.testing.assert_allclose(got, Q + TOOL, atol=1e-12)


def test_mapping_refuses_unknown_names_and_rotary_axes():
    with pytest.raises(InputError, match="unknown coefficient 'EXX'"):
        iso_errors_from_aguado("XFYZ", Q, {"EXX": 1.0})
    with pytest.raises(TopologyError, match="linear axes"):
        iso_errors_from_aguado("wCfXYZt", np.zeros((1, 4)), {})
