"""The symbolic equation of motion against the numerical HTM path."""

from __future__ import annotations

import numpy as np
import pytest

from mtmc.kinematics import Machine, equation_of_motion, library_machine


def _setup(name: str, seed: int, m: int = 40):
    base = library_machine(name)
    mach = Machine.from_topology(
        base.topology,
        tool=(3.0, -4.0, -120.0),
        workpiece=(15.0, 25.0, 35.0),
        pivots={ax: (5.0, -10.0, 20.0) for ax in base.axes},
    )
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    q = np.stack(
        [
            rng.uniform(-np.pi, np.pi, m) if ax in "ABC" else rng.uniform(-400, 400, m)
            for ax in mach.axes
        ],
        axis=1,
    )
    errs = {
        n: rng.normal(scale=5e-5 if mach.error_term(n).angular else 5e-3, size=m)
        for n in mach.error_names
    }
    return mach, q, errs


@pytest.mark.parametrize("name", ["xfyz", "zyxf", "table-table", "wbzfxyct"])
def test_first_order_equation_is_nominal_plus_jacobian(name: str) -> None:
    mach, q, errs = _setup(name, 1)
    eq = equation_of_motion(mach, first_order=True)
    f = eq.compile()
    J0 = mach.jacobian(q)  # at zero errors, columns in machine.error_names order
    e = np.stack([errs[n] for n in mach.error_names], axis=1)
    ref = mach.tool_position(q) + np.einsum("mij,mj->mi", J0, e)
    np.testing.assert_allclose(f(q, errs), ref, rtol=0, atol=1e-10)

    # and it differs from the full model by second-order terms only: halving the errors
    # quarters the gap
    def gap(s: float) -> float:
        e2 = {k: s * v for k, v in errs.items()}
        return float(np.max(np.abs(f(q, e2) - mach.tool_position(q, e2))))

    assert 0.2 < gap(0.5) / gap(1.0) < 0.3


@pytest.mark.parametrize("topology", ["XFYZ", "FXYZ"])
def test_first_order_equation_is_the_full_one_truncated(topology: str) -> None:
    # the first-order product carries v0 + sum e_k v_k through the chain; the full product
    # expanded with every error scaled by eps, and cut after eps^1, must be the same
    # expression (a three-axis machine, where the full product is small)
    import sympy as sp

    mach = Machine.from_topology(topology)
    full = equation_of_motion(mach)
    lin = equation_of_motion(mach, first_order=True)
    eps = sp.Symbol("eps")
    scale = {e: eps * e for e in full.error_symbols}
    for a, b in zip(full.position, lin.position, strict=True):
        e = sp.expand(a.xreplace(scale))
        cut = e.coeff(eps, 0) + e.coeff(eps, 1)
        assert sp.expand(cut - b) == 0


@pytest.mark.parametrize(
    ("name", "subset"),
    [
        ("xfyz", None),
        ("fxyz", None),
        ("table-table", ["EXX", "EC0Y", "EB0Z", "ECX", "EX0C", "EA0C", "EYA", "EBC", "ECC", "EZT"]),
        ("table-head", ["EY0C", "EB0C", "EXB", "EAB", "EA0Z", "EXP", "EBP", "EZZ"]),
    ],
)
def test_full_equation_compiled_equals_htm_path(name: str, subset: list[str] | None) -> None:
    mach, q, errs = _setup(name, 2)
    if subset is not None:
        errs = {k: errs[k] for k in subset}
    eq = equation_of_motion(mach, errors=list(errs))
    f = eq.compile()
    np.testing.assert_allclose(f(q, errs), mach.tool_position(q, errs), rtol=0, atol=1e-9)
    # zero errors: the nominal chain
    np.testing.assert_allclose(f(q), mach.tool_position(q), rtol=0, atol=1e-9)


def test_text_and_latex() -> None:
    eq = equation_of_motion(Machine.from_topology("XFYZ"), first_order=True)
    lines = eq.text().splitlines()
    assert [ln[:6] for ln in lines] == ["x_W = ", "y_W = ", "z_W = "]
    # squareness EC0Y with Y travel enters x as -EC0Y*y (ISO 230-1 sign)
    assert "- EC0Y*y" in lines[0] or lines[0].startswith("x_W = -EC0Y*y")
    tex = eq.latex()
    assert tex.startswith("\\begin{aligned}")
    assert "x_W &=" in tex
    assert "EC0Y" in tex
    assert [str(s) for s in eq.axis_symbols] == ["x", "y", "z"]


def test_symbolic_rotations_are_the_numeric_ones() -> None:
    import sympy as sp

    from mtmc.geometry import rotation_x, rotation_y, rotation_z, small_angle_rotation
    from mtmc.kinematics.symbolic import axis_rotation_matrix, small_angle_matrix

    e = (2e-4, -3e-4, 5e-4)
    S = small_angle_rotation(*e)
    for transpose, want in ((False, S), (True, S.T)):
        got = np.array(small_angle_matrix(*map(sp.Float, e), transpose=transpose), dtype=float)
        np.testing.assert_array_equal(got[:3, :3], want)
        np.testing.assert_array_equal(got[3], [0, 0, 0, 1])
    for axis, rot in enumerate((rotation_x, rotation_y, rotation_z)):
        got = np.array(axis_rotation_matrix(axis, sp.Float(0.7)), dtype=float)
        np.testing.assert_allclose(got[:3, :3], rot(0.7), rtol=0, atol=1e-15)
