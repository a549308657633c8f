"""Forward kinematics (the lowered column program) against the chain of homogeneous
4 x 4 matrices written out here pose by pose, for every kind of error value: constants,
one value per trial, shared and per-trial error functions of every family; small-angle and
exact rotations; offsets and pivots; several internal blocks."""

from __future__ import annotations

import numpy as np
import pytest

from mtmc.kinematics import (
    ChebyshevSeries,
    ConstantFunction,
    ErrorTable,
    FourierSeries,
    LegendreSeries,
    Machine,
    PolynomialFunction,
    _columns,
)

M = 150


def _T(v):
    T = np.eye(4)
    T[:3, 3] = v
    return T


def _R(e, exact):
    a, b, c = e
    R = np.eye(4)
    if exact:
        ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
        Rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
        Ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
        Rz = np.array([[cc, -sc, 0], [sc, cc, 0], [0, 0, 1]])
        R[:3, :3] = Rz @ Ry @ Rx
    else:
        R[:3, :3] += np.array([[0, -c, b], [c, 0, -a], [-b, a, 0]])
    return R


def _Rinv(e, exact):
    """The transpose (``R(e)^T`` of the model, also for the small-angle matrix)."""
    R = _R(e, exact)
    R[:3, :3] = R[:3, :3].T
    return R


def _rot(k, angle):
    R = np.eye(4)
    i, j = (k + 1) % 3, (k + 2) % 3
    R[i, i] = R[j, j] = np.cos(angle)
    R[i, j], R[j, i] = -np.sin(angle), np.sin(angle)
    return R


def reference_pose(machine: Machine, q: np.ndarray, errors: dict, exact: bool) -> np.ndarray:
    """W_T_tool = S_P^-1 A_1(q_1) ... A_n(q_n) S_T, one pose at a time (Machine's docstring)."""
    col = {a: i for i, a in enumerate(machine.axes)}
    out = np.empty((q.shape[0], 4, 4))
    for m in range(q.shape[0]):

        def val(name, ax=None, m=m):
            v = errors.get(name, 0.0)
            if callable(v):
                if v.coefficients.ndim == 2:
                    v = v.with_coefficients(v.coefficients[m])
                return float(v(np.array([q[m, col[ax]]]))[0])
            v = np.asarray(v, dtype=float)
            return float(v if v.ndim == 0 else v[m])

        def vec(names, ax=None, val=val):
            return np.array([0.0 if n is None else val(n, ax) for n in names])

        P = vec(["EXP", "EYP", "EZP"])
        chain = _Rinv(vec(["EAP", "EBP", "ECP"]), exact) @ _T(-(machine.workpiece + P))
        for ax in machine.topology.chain:
            k = "XYZABC".index(ax) % 3
            o = machine.pivots.get(ax, np.zeros(3))
            d = vec([f"E{c}{ax}" for c in "XYZ"], ax)
            eps = vec([f"E{c}{ax}" for c in "ABC"], ax)
            if ax in "XYZ":
                s = vec([None if j == k else f"E{'ABC'[j]}0{ax}" for j in range(3)])
                e = np.zeros(4)
                e[k] = 1.0
                direction = (_R(s, exact) @ e)[:3]
                A = _T(o) @ _T(q[m, col[ax]] * direction) @ _T(d) @ _R(eps, exact) @ _T(-o)
            else:
                d0 = vec([None if j == k else f"E{'XYZ'[j]}0{ax}" for j in range(3)])
                e0 = vec([f"E{'ABC'[j]}0{ax}" for j in range(3)])
                L = _T(d0) @ _R(e0, exact)
                Linv = _Rinv(e0, exact) @ _T(-d0)
                A = _T(o) @ L @ _T(d) @ _R(eps, exact) @ _rot(k, q[m, col[ax]]) @ Linv @ _T(-o)
            chain = chain @ A
        t = vec(["EXT", "EYT", "EZT"])
        out[m] = chain @ _T(machine.tool + t) @ _R(vec(["EAT", "EBT", "ECT"]), exact)
    return out


def _machine(spec: str) -> Machine:
    axes = [a for a in spec if a in "XYZABC"]
    return Machine.from_topology(
        spec,
        tool=(3.0, -7.0, -120.0),
        workpiece=(25.0, -40.0, 60.0),
        pivots={a: (11.0 * (i + 1), -9.0 * i, 4.0 * i - 30.0) for i, a in enumerate(axes)},
    )


def _errors(machine: Machine, rng: np.random.Generator) -> dict:
    """Every standard error; the component ones cycle through every kind of value."""
    out: dict = {}
    for i, name in enumerate(machine.error_names):
        term = machine.error_term(name)
        s = 4e-5 if term.angular else 4e-3
        if term.kind != "component":
            out[name] = rng.normal(scale=s) if i % 2 else rng.normal(scale=s, size=M)
            continue
        rotary = term.axis in "ABC"
        L = 3.0 if rotary else 500.0
        lo, hi = (-4.0, 4.0) if rotary else (-600.0, 600.0)
        kind = i % 8
        if kind == 0:
            out[name] = PolynomialFunction(rng.normal(size=4) * s / L ** np.arange(4))
        elif kind == 1:
            out[name] = PolynomialFunction(rng.normal(size=(M, 3)) * s / L ** np.arange(3))
        elif kind == 2:
            out[name] = LegendreSeries(rng.normal(size=4) * s, low=lo, high=hi)
        elif kind == 3:
            out[name] = ChebyshevSeries(rng.normal(size=3) * s, low=lo, high=hi)
        elif kind == 4 and rotary:
            out[name] = FourierSeries(rng.normal(size=5) * s)
        elif kind == 4:
            out[name] = ErrorTable(np.linspace(lo, hi, 7), rng.normal(size=7) * s)
        elif kind == 5:
            out[name] = ConstantFunction(rng.normal() * s)
        elif kind == 6:
            out[name] = rng.normal(scale=s, size=M)
        else:
            out[name] = float(rng.normal(scale=s))
    # a second polynomial of the first kind on each axis, so that groups hold several
    for name in machine.error_names:
        term = machine.error_term(name)
        if term.kind == "component" and term.angular and not isinstance(out[name], np.ndarray):
            L = 3.0 if term.axis in "ABC" else 500.0
            out[name] = PolynomialFunction(rng.normal(size=4) * 4e-5 / L ** np.arange(4))
    return out


def _q(machine: Machine, rng: np.random.Generator) -> np.ndarray:
    return np.stack(
        [
            rng.uniform(-np.pi, np.pi, M) if a in "ABC" else rng.uniform(-300.0, 300.0, M)
            for a in machine.axes
        ],
        axis=1,
    )


@pytest.mark.parametrize("exact", [False, True])
@pytest.mark.parametrize("spec", ["wCAXfYZt", "wCAYfXZBt", "wXfYZt", "wBZfXYCt"])
def test_fast_chain_equals_matrix_product(spec, exact, monkeypatch):
    monkeypatch.setattr(_columns, "BLOCK", 64)  # three full internal blocks and a partial one
    rng = np.random.default_rng(np.random.SeedSequence(20260412))
    machine = _machine(spec)
    q = _q(machine, rng)
    errors = _errors(machine, rng)
    ref = reference_pose(machine, q, errors, exact)
    p = machine.tool_position(q, errors, exact=exact)
    np.testing.assert_allclose(p, ref[:, :3, 3], rtol=0, atol=1e-12)
    np.testing.assert_allclose(machine.pose(q, errors, exact=exact), ref, rtol=0, atol=1e-12)
    d = machine.tool_direction(q, errors, exact=exact)
    np.testing.assert_allclose(d, ref[:, :3, :3] @ machine.tool_axis, rtol=0, atol=1e-12)
    # the translation of the pose is the tool position, number for number
    np.testing.assert_array_equal(machine.pose(q, errors, exact=exact)[:, :3, 3], p)
    # the block length does not change the numbers beyond rounding
    monkeypatch.setattr(_columns, "BLOCK", 4096)
    np.testing.assert_allclose(machine.tool_position(q, errors, exact=exact), p, atol=1e-12)


def test_one_pose_many_trials_and_constant_errors():
    # q of one row broadcast against errors with a trial axis: the positions are constants
    rng = np.random.default_rng(5)
    machine = _machine("wCAXfYZt")
    errors = _errors(machine, rng)
    errors = {k: v for k, v in errors.items() if not callable(v) or v.coefficients.ndim == 1}
    q1 = _q(machine, rng)[:1]
    p = machine.tool_position(q1, errors)
    assert p.shape == (M, 3)
    ref = reference_pose(machine, np.repeat(q1, M, axis=0), errors, exact=False)
    np.testing.assert_allclose(p, ref[:, :3, 3], rtol=0, atol=1e-12)
    # no per-trial value at all: one pose, every source a constant
    const = {k: v for k, v in errors.items() if not isinstance(v, np.ndarray)}
    ref1 = reference_pose(machine, q1, const, exact=False)
    np.testing.assert_allclose(machine.tool_position(q1, const), ref1[:, :3, 3], atol=1e-12)


def test_cos_sin_from_the_half_angle_tangent():
    a = np.concatenate(
        [
            np.linspace(-40.0, 40.0, 100_001),
            np.pi * np.arange(-9, 10),
            np.nextafter(np.pi, 0) * np.array([-1.0, 1.0]),
            [0.0, -0.0, 1e-300, 1e-8],
        ]
    )
    c, s = _columns.cos_sin(a)
    np.testing.assert_allclose(c, np.cos(a), rtol=0, atol=2e-15)
    np.testing.assert_allclose(s, np.sin(a), rtol=0, atol=2e-15)
    assert np.all(np.isfinite(c))
    assert np.all(np.isfinite(s))
