"""The papers' printed models, typed into the tests, against mtmc's chain."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from mtmc.kinematics import Machine, equation_of_motion, library_machine


def test_wang2022_wbzfxyct_eq16_and_jacobian_eq19() -> None:
    """Wang, Cheung and Kong 2022, eqs. (10), (14), (16), (19) on the wBZfXYCt machine.

    The paper moves each axis by its own coordinate; ISO 841 (mtmc) moves part-side axes
    by the negative: (x, y, z_s, b_s, c) of the paper = (x, y, -z, -b, c) of mtmc.
    """
    rng = np.random.default_rng(np.random.SeedSequence(3003))
    m = 50
    p = np.array([1.5, -2.0, 40.0])  # probe centre on C
    w = np.array([30.0, 20.0, 25.0])  # fiducial i on B
    mach = Machine.from_topology("wBZfXYCt", tool=p, workpiece=w)
    x, y, zs = rng.uniform(-50, 50, (3, m))
    bs, c = rng.uniform(-np.pi, np.pi, (2, m))
    q = np.column_stack([x, y, -zs, -bs, c])  # mtmc column order X Y Z B C
    RC = Rotation.from_euler("z", c[:, None]).as_matrix()
    RB = Rotation.from_euler("y", bs[:, None]).as_matrix()
    # eq. (16) with zero setup errors: delta_i = (x, y, -z) + R_C p - R_B w_i, in frame F
    delta = np.column_stack([x, y, -zs]) + RC @ p - RB @ w
    pW = mach.tool_position(q)  # the same vector seen in the fiducial (workpiece) frame
    np.testing.assert_allclose(np.einsum("mij,mj->mi", RB, pW), delta, atol=1e-12)
    # eq. (19): d delta / d Delta_p = R_C, d delta / d Delta_w = -R_B
    J = mach.jacobian(q, names=["EXT", "EYT", "EZT", "EXP", "EYP", "EZP"])
    JF = RB @ J
    np.testing.assert_allclose(JF[:, :, :3], RC, atol=1e-12)
    np.testing.assert_allclose(JF[:, :, 3:], -RB, atol=1e-12)


def test_aguado2017_xfyz_squareness_terms() -> None:
    """Aguado et al. 2017, eqs. (7)-(9): X = (-x + dxx, dyx, dzx), Y = (dxy - y Sxy, y + dyy, dzy),
    Z = (dxz - z Sxz, dyz - z Syz, z + dzz); with Sxy = EC0Y, Sxz = -EB0Z, Syz = EA0Z
    the first-order equation of motion carries exactly these terms."""
    eq = equation_of_motion(library_machine("xfyz"), errors=["EC0Y", "EB0Z", "EA0Z"])
    import sympy as sp

    x, y, z = eq.axis_symbols
    s = {str(v): v for v in eq.error_symbols}
    tx, ty, tz, wx, wy, wz = eq.offset_symbols
    pos = eq.position.subs({tx: 0, ty: 0, tz: 0, wx: 0, wy: 0, wz: 0})
    Sxy, Sxz, Syz = s["EC0Y"], -s["EB0Z"], s["EA0Z"]
    expected = sp.Matrix([x - y * Sxy - z * Sxz, y - z * Syz, z])
    assert sp.simplify(pos - expected) == sp.zeros(3, 1)
