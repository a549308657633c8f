"""Forward kinematics with errors: nominal chains, single errors against hand-derived
first-order formulas, batch against one-at-a-time, analytic Jacobian against finite
differences, and small-angle against exact rotations."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from mtmc.errors import InputError
from mtmc.kinematics import (
    LegendreSeries,
    Machine,
    PolynomialFunction,
    library_entries,
    library_machine,
)

AXIS_VEC = {
    "X": (1, 0, 0),
    "Y": (0, 1, 0),
    "Z": (0, 0, 1),
    "U": (1, 0, 0),
    "V": (0, 1, 0),
    "W": (0, 0, 1),
    "A": (1, 0, 0),
    "B": (0, 1, 0),
    "C": (0, 0, 1),
}


def _rng(k: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(k))


def _random_q(machine: Machine, m: int, rng: np.random.Generator) -> np.ndarray:
    cols = []
    for ax in machine.axes:
        if ax in "ABC":
            cols.append(rng.uniform(-np.pi, np.pi, m))
        else:
            cols.append(rng.uniform(-500.0, 500.0, m))
    return np.stack(cols, axis=1)


def _physical_reference(machine: Machine, q: np.ndarray) -> np.ndarray:
    """Nominal tool position, one trial at a time, from the physical motions.

    Written from the physical picture, not from mtmc's relative chain: each part-side axis
    moves its carriage by -q (ISO 841: the command is the tool relative to the part) about
    its pivot, each tool-side axis by +q; the tool position in the workpiece frame is
    inv(F_T_W) @ F_T_tool with F the machine frame.
    """
    topo = machine.topology
    out = np.empty((q.shape[0], 3))
    for m in range(q.shape[0]):
        pos = dict(zip(machine.axes, q[m], strict=True))

        def motion(ax: str, sign: float, pos: dict[str, float] = pos) -> np.ndarray:
            T = np.eye(4)
            v = np.array(AXIS_VEC[ax], dtype=float)
            o = machine.pivots.get(ax, np.zeros(3))
            if ax in "ABC":
                R = Rotation.from_rotvec(sign * pos[ax] * v).as_matrix()
                T[:3, :3] = R
                T[:3, 3] = o - R @ o
            else:
                T[:3, 3] = sign * pos[ax] * v
            return T

        F_T_W = np.eye(4)
        for ax in reversed(topo.part_axes):  # from the frame out to the workpiece
            F_T_W = F_T_W @ motion(ax, -1.0)
        Tw = np.eye(4)
        Tw[:3, 3] = machine.workpiece
        F_T_W = F_T_W @ Tw
        F_T_tool = np.eye(4)
        for ax in topo.tool_axes:
            F_T_tool = F_T_tool @ motion(ax, +1.0)
        tip = F_T_tool @ np.append(machine.tool, 1.0)
        out[m] = (np.linalg.inv(F_T_W) @ tip)[:3]
    return out


@pytest.mark.parametrize("entry", library_entries(), ids=lambda e: e.name)
def test_zero_errors_give_nominal_for_every_library_machine(entry) -> None:  # type: ignore[no-untyped-def]
    machine = entry.machine
    rng = _rng(1)
    q = _random_q(machine, 200, rng)
    p = machine.tool_position(q)
    np.testing.assert_allclose(p, _physical_reference(machine, q), atol=1e-9)
    # rotary axes at zero and no offsets: the commanded linear coordinates, both sides
    bare = Machine.from_topology(machine.topology)
    q0 = q.copy()
    q0[:, [i for i, a in enumerate(bare.axes) if a in "ABC"]] = 0.0
    lin = {a: q0[:, i] for i, a in enumerate(bare.axes)}
    expected = np.zeros((200, 3))
    for a, v in lin.items():
        if a not in "ABC":
            expected += np.outer(v, AXIS_VEC[a])
    np.testing.assert_allclose(bare.tool_position(q0), expected, atol=1e-9)
    # the dict form of q gives the same numbers
    np.testing.assert_array_equal(bare.tool_position(lin), bare.tool_position(q0))


def test_pivots_and_offsets_follow_the_physical_chain() -> None:
    m = Machine.from_topology(
        "wCAYfXZBt",
        tool=(1.0, 2.0, -150.0),
        workpiece=(10.0, -5.0, 20.0),
        pivots={"C": (30.0, 40.0, 0.0), "A": (0.0, 25.0, -60.0), "B": (0.0, 0.0, 120.0)},
    )
    q = _random_q(m, 100, _rng(2))
    np.testing.assert_allclose(m.tool_position(q), _physical_reference(m, q), atol=1e-9)


def test_table_table_closed_form() -> None:
    # wCAXfYZt, no offsets: p_W = Rz(c) Rx(a) (x, y, z)
    m = library_machine("table-table")
    q = _random_q(m, 50, _rng(3))
    x, y, z, a, c = q.T
    ref = Rotation.from_euler("xz", np.stack([a, c], axis=1)).apply(np.stack([x, y, z], axis=1))
    np.testing.assert_allclose(m.tool_position(q), ref, atol=1e-9)
    # the tool axis (+z of the spindle) in the table frame
    dref = Rotation.from_euler("xz", np.stack([a, c], axis=1)).apply([0.0, 0.0, 1.0])
    np.testing.assert_allclose(m.tool_direction(q), dref, atol=1e-12)
    T = m.pose(q)
    np.testing.assert_allclose(T[:, :3, 3], m.tool_position(q), atol=1e-12)
    np.testing.assert_allclose(T[:, :3, 2], dref, atol=1e-12)


# --- single errors against hand-derived first-order formulas --------------------------

LIN_CASES = ["XFYZ", "FXYZ", "XYFZ", "ZYXF"]


@pytest.mark.parametrize("spec", LIN_CASES)
def test_squareness_errors(spec: str) -> None:
    m = Machine.from_topology(spec)
    q = _random_q(m, 20, _rng(4))
    x, y, z = q.T
    e = 2e-5
    p0 = m.tool_position(q)
    d = m.tool_position(q, {"EC0Y": e}) - p0
    np.testing.assert_allclose(d, np.stack([-y * e, 0 * y, 0 * y], 1), atol=1e-12)
    d = m.tool_position(q, {"EB0Z": e}) - p0
    np.testing.assert_allclose(d, np.stack([z * e, 0 * z, 0 * z], 1), atol=1e-12)
    d = m.tool_position(q, {"A0Z": e}) - p0
    np.testing.assert_allclose(d, np.stack([0 * z, -z * e, 0 * z], 1), atol=1e-12)
    # the other reference: X tilted about z towards +y
    d = m.tool_position(q, {"EC0X": e}) - p0
    np.testing.assert_allclose(d, np.stack([0 * x, x * e, 0 * x], 1), atol=1e-12)


@pytest.mark.parametrize("spec", LIN_CASES)
def test_linear_component_errors_and_abbe(spec: str) -> None:
    t = np.array([5.0, -3.0, -120.0])
    o = np.array([0.0, 50.0, 20.0])
    m = Machine.from_topology(spec, tool=t, pivots={"X": o})
    q = _random_q(m, 20, _rng(5))
    _, y, z = q.T
    p0 = m.tool_position(q)
    # positioning and straightness: the same sign whichever side X is on
    d = m.tool_position(q, {"EXX": 1e-3, "EYX": -2e-3, "EZX": 3e-3}) - p0
    np.testing.assert_allclose(d, np.tile([1e-3, -2e-3, 3e-3], (20, 1)), atol=1e-12)
    # angular errors of X act about X's reference point o on what X carries (the axes
    # after X in the chain towards the tool, and the tool): delta = eps x (r - o)
    eps = np.array([3e-6, -4e-6, 5e-6])
    chain = m.topology.chain
    after = chain[chain.index("X") + 1 :]
    r = np.tile(t, (20, 1)).astype(float)
    for ax, v in (("Y", y), ("Z", z)):
        if ax in after:
            r += np.outer(v, AXIS_VEC[ax])
    before = chain[: chain.index("X")]
    d = m.tool_position(q, {"EAX": eps[0], "EBX": eps[1], "ECX": eps[2]}) - p0
    np.testing.assert_allclose(d, np.cross(eps, r - o), atol=1e-12)
    assert before or after  # the chain has axes on at least one side of X


@pytest.mark.parametrize(("spec", "tool"), [("wCAXfYZt", (0, 0, 0)), ("wfXYZCAt", (20, 10, -150))])
def test_rotary_location_errors(spec: str, tool: tuple[float, float, float]) -> None:
    m = Machine.from_topology(spec, tool=tool)
    q = _random_q(m, 30, _rng(6))
    q[:, m.axes.index("A")] = 0.0
    c = q[:, m.axes.index("C")]
    Rz = Rotation.from_euler("z", c[:, None]).as_matrix()
    lin = q[:, :3]
    # the point fed into C's transform: the part-side C sees (x, y, z) + tool; the
    # tool-side C sees the tool offset only
    v = lin + np.asarray(tool) if m.topology.side("C") == "part" else np.tile(tool, (30, 1))
    p0 = m.tool_position(q)
    e = np.array([0.01, -0.02, 0.0])
    d = m.tool_position(q, {"EX0C": e[0], "EY0C": e[1]}) - p0
    np.testing.assert_allclose(d, e - np.einsum("mij,j->mi", Rz, e), atol=1e-12)
    eps = np.array([2e-5, -3e-5, 0.0])
    d = m.tool_position(q, {"EA0C": eps[0], "EB0C": eps[1]}) - p0
    Rv = np.einsum("mij,mj->mi", Rz, v)
    ref = np.cross(eps, Rv) - np.einsum("mij,mj->mi", Rz, np.cross(eps, v))
    # first order: the neglected term is eps x (R (eps x v)), at most |eps|^2 |v|
    bound = np.sum(eps**2) * np.max(np.linalg.norm(v, axis=1))
    np.testing.assert_allclose(d, ref, rtol=0, atol=bound)
    assert np.max(np.abs(d - ref)) > 0.0
    # location errors do nothing at C = 0 (exactly with exact rotations; the small-angle
    # L L^T = I - [eps]x^2 leaves a second-order residue)
    q[:, m.axes.index("C")] = 0.0
    loc = {"EX0C": 0.01, "EA0C": 1e-4}
    np.testing.assert_allclose(m.tool_position(q, loc, exact=True), m.tool_position(q), atol=1e-12)
    np.testing.assert_allclose(m.tool_position(q, loc), m.tool_position(q), atol=1e-8 * 1000)


@pytest.mark.parametrize("spec", ["wCAXfYZt", "wfXYZCAt", "wBZfXYCt"])
def test_rotary_component_errors(spec: str) -> None:
    m = Machine.from_topology(spec, tool=(3.0, 4.0, -50.0))
    q = _random_q(m, 30, _rng(7))
    p0 = m.tool_position(q)
    # ECC is an angular positioning error: to first order it equals moving C by ECC
    e = 1e-6
    qc = q.copy()
    qc[:, m.axes.index("C")] += e
    np.testing.assert_allclose(
        m.tool_position(q, {"ECC": e}) - p0, m.tool_position(qc) - p0, rtol=0, atol=2e-9
    )
    # EXC, EYC, EZC shift the next body in the non-rotating frame of C: for a machine
    # whose only body before C in the chain is the workpiece, the shift is seen as is
    if m.topology.chain[0] == "C":
        d = m.tool_position(q, {"EXC": 1e-3, "EZC": -2e-3}) - p0
        np.testing.assert_allclose(d, np.tile([1e-3, 0.0, -2e-3], (30, 1)), atol=1e-12)


def test_tool_and_setup_errors() -> None:
    m = Machine.from_topology("XFYZ", tool=(0, 0, -100.0), workpiece=(200.0, 100.0, 50.0))
    q = _random_q(m, 10, _rng(8))
    p0 = m.tool_position(q)
    np.testing.assert_allclose(p0, q + np.array([0, 0, -100.0]) - [200.0, 100.0, 50.0], atol=1e-12)
    d = m.tool_position(q, {"EXT": 1e-3, "EZT": 2e-3}) - p0
    np.testing.assert_allclose(d, np.tile([1e-3, 0, 2e-3], (10, 1)), atol=1e-12)
    # the workpiece placed +EXP along x: the tool is -EXP relative to it
    d = m.tool_position(q, {"EXP": 1e-3}) - p0
    np.testing.assert_allclose(d, np.tile([-1e-3, 0, 0], (10, 1)), atol=1e-12)
    # the workpiece rotated by ECP about its origin: the tool, seen from it, by -ECP
    d = m.tool_position(q, {"ECP": 1e-5}) - p0
    np.testing.assert_allclose(d, -np.cross([0, 0, 1e-5], p0), atol=1e-12)
    # a tool tilt changes the tool axis, not the tool point
    np.testing.assert_allclose(m.tool_position(q, {"EAT": 1e-4}), p0, atol=1e-12)
    np.testing.assert_allclose(m.tool_direction(q, {"EAT": 1e-4}), np.tile([0, -1e-4, 1], (10, 1)))


# --- batches ----------------------------------------------------------------------------


def _random_errors(machine: Machine, rng: np.random.Generator, m: int | None) -> dict:
    shape = () if m is None else (m,)
    out = {}
    for name in machine.error_names:
        term = machine.error_term(name)
        scale = 5e-5 if term.angular else 5e-3
        out[name] = rng.normal(scale=scale, size=shape)
    return out


@pytest.mark.parametrize("name", ["table-head", "wbzfxyct", "xfyz"])
def test_batch_equals_one_at_a_time(name: str) -> None:
    mach = library_machine(name)
    rng = _rng(9)
    m = 25
    q = _random_q(mach, m, rng)
    errs = _random_errors(mach, rng, m)
    ax0 = mach.axes[0]
    errs[f"EX{ax0}"] = PolynomialFunction(rng.normal(size=(m, 4)) * [1e-3, 1e-6, 1e-9, 1e-12])
    for exact in (False, True):
        batch = mach.tool_position(q, errs, exact=exact)
        pose = mach.pose(q, errs, exact=exact)
        for i in range(m):
            one = {k: (v[i] if isinstance(v, np.ndarray) else None) for k, v in errs.items()}
            one[f"EX{ax0}"] = PolynomialFunction(errs[f"EX{ax0}"].coefficients[i])
            np.testing.assert_allclose(
                mach.tool_position(q[i], one, exact=exact)[0], batch[i], rtol=0, atol=1e-11
            )
            np.testing.assert_allclose(mach.pose(q[i], one, exact=exact)[0], pose[i], atol=1e-11)


def test_trial_axis_on_errors_only_broadcasts_q() -> None:
    mach = library_machine("xfyz")
    v = np.linspace(-1e-3, 1e-3, 7)
    p = mach.tool_position([[100.0, 200.0, 300.0]], {"EXX": v})
    assert p.shape == (7, 3)
    np.testing.assert_allclose(p[:, 0], 100.0 + v)


def test_exact_pose_is_rigid_and_small_angle_first_order() -> None:
    mach = library_machine("table-table")
    rng = _rng(10)
    q = _random_q(mach, 40, rng)
    errs = _random_errors(mach, rng, None)
    T = mach.pose(q, errs, exact=True)
    R = T[:, :3, :3]
    np.testing.assert_allclose(
        R @ np.swapaxes(R, 1, 2), np.broadcast_to(np.eye(3), R.shape), atol=1e-14
    )
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-14)


# --- Jacobian -----------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["table-table", "head-head", "table-head", "wbzfxyct", "zyxf"])
@pytest.mark.parametrize("exact", [False, True])
def test_analytic_jacobian_matches_central_differences(name: str, exact: bool) -> None:
    base = library_machine(name)
    mach = Machine.from_topology(
        base.topology,
        tool=(12.0, -7.0, -180.0),
        workpiece=(40.0, 30.0, 25.0),
        pivots={ax: (10.0, -20.0, 30.0) for ax in base.axes},
    )
    rng = _rng(11)
    q = _random_q(mach, 6, rng)
    errs = _random_errors(mach, rng, 6)
    names = mach.accepted_error_names
    J = mach.jacobian(q, errs, names=names, exact=exact)
    assert J.shape == (6, 3, len(names))
    for k, n in enumerate(names):
        h = 1e-7 if mach.error_term(n).angular else 1e-5
        up = dict(errs)
        dn = dict(errs)
        up[n] = errs.get(n, 0.0) + h
        dn[n] = errs.get(n, 0.0) - h
        fd = (mach.tool_position(q, up, exact=exact) - mach.tool_position(q, dn, exact=exact)) / (
            2 * h
        )
        scale = 1.0 if not mach.error_term(n).angular else 1000.0
        np.testing.assert_allclose(J[:, :, k], fd, atol=2e-6 * scale, err_msg=n)


@pytest.mark.parametrize("name", ["table-table", "head-head", "table-head", "wbzfxyct", "xfyz"])
@pytest.mark.parametrize("exact", [False, True])
def test_jacobian_transpose_is_the_jacobian_times_a_vector(name: str, exact: bool) -> None:
    # reverse mode against the forward-mode Jacobian (itself tested against central
    # differences above), per-trial and constant errors, rotary and linear axes
    base = library_machine(name)
    mach = Machine.from_topology(
        base.topology,
        tool=(12.0, -7.0, -180.0),
        workpiece=(40.0, 30.0, 25.0),
        pivots={ax: (10.0, -20.0, 30.0) for ax in base.axes},
    )
    rng = _rng(13)
    q = _random_q(mach, 9, rng)
    errs = _random_errors(mach, rng, 9)
    names = mach.accepted_error_names
    w = rng.normal(size=(9, 3))
    ref = np.einsum("mce,mc->me", mach.jacobian(q, errs, names=names, exact=exact), w)
    got = mach.jacobian_transpose(q, errs, w, names=names, exact=exact)
    # the same products summed in another order: rounding of terms up to about |J||w|,
    # with lever arms of 10³ mm, 10⁻¹³ of the largest entry
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-13 * np.abs(ref).max())
    with pytest.raises(InputError, match="shape"):
        mach.jacobian_transpose(q, errs, w[:3], names=names)


def test_jacobian_chains_to_coefficients() -> None:
    # d p / d c_k of a Legendre series = J[:, :, EXX] * P_k(t)
    mach = library_machine("xfyz")
    q = _random_q(mach, 5, _rng(12))
    f = LegendreSeries([1e-3, 2e-3, -1e-3], low=-500.0, high=500.0)
    J = mach.jacobian(q, {"EYX": f}, names=["EYX"])
    B = f.basis(q[:, 0])
    h = 1e-3  # the position is linear in a straightness error: no truncation error
    for k in range(3):
        dc = np.zeros(3)
        dc[k] = h
        fd = (
            mach.tool_position(q, {"EYX": f.with_coefficients(f.coefficients + dc)})
            - mach.tool_position(q, {"EYX": f.with_coefficients(f.coefficients - dc)})
        ) / (2 * h)
        np.testing.assert_allclose(J[:, :, 0] * B[:, k, None], fd, atol=1e-9)


# --- small-angle vs exact, random topologies -----------------------------------------------


@st.composite
def topologies(draw: st.DrawFn) -> str:
    lin = draw(st.lists(st.sampled_from("XYZUVW"), min_size=1, max_size=4, unique=True))
    rot = draw(st.lists(st.sampled_from("ABC"), min_size=0, max_size=3, unique=True))
    axes = draw(st.permutations(lin + rot))
    k = draw(st.integers(0, len(axes)))
    return "w" + "".join(axes[:k]) + "f" + "".join(axes[k:]) + "t"


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(spec=topologies(), seed=st.integers(0, 2**32 - 1), frac=st.floats(0.1, 1.0))
def test_small_angle_and_exact_agree_to_second_order(spec: str, seed: int, frac: float) -> None:
    mach = Machine.from_topology(spec, tool=(10.0, -20.0, -100.0))
    rng = _rng(seed)
    q = _random_q(mach, 8, rng)
    names = [n for n in mach.accepted_error_names if rng.random() < frac]
    errs = {}
    for n in names:
        term = mach.error_term(n)
        errs[n] = rng.normal(scale=1e-4 if term.angular else 1e-2)

    def gap(s: float) -> float:
        scaled = {k: s * v for k, v in errs.items()}
        return float(
            np.max(
                np.abs(mach.tool_position(q, scaled) - mach.tool_position(q, scaled, exact=True))
            )
        )

    g1, g2 = gap(1.0), gap(0.5)
    first = float(np.max(np.abs(mach.tool_position(q, errs) - mach.tool_position(q))))
    # the gap is second order: halving every error quarters it, and it is far below
    # the first-order effect of the errors
    if g1 > 1e-10:
        assert 0.2 < g2 / g1 < 0.3
    assert g1 <= 1e-2 * max(first, 1e-9)


# --- input errors -----------------------------------------------------------------------------


def test_bad_inputs_are_named() -> None:
    mach = library_machine("xfyz")
    with pytest.raises(
        InputError, match=r"field q: expected axis positions of shape \(M, 3\) in the order X Y Z"
    ):
        mach.tool_position(np.zeros((4, 5)))
    with pytest.raises(InputError, match="no position for axis Z"):
        mach.tool_position({"X": [0.0], "Y": [0.0]})
    with pytest.raises(InputError, match="unknown axis 'C'"):
        mach.tool_position({"X": [0.0], "Y": [0.0], "Z": [0.0], "C": [0.0]})
    with pytest.raises(
        InputError, match="error EX0C refers to axis C, which machine wXfYZt does not have"
    ):
        mach.tool_position([[0.0, 0.0, 0.0]], {"X0C": 1e-3})
    with pytest.raises(InputError, match="field EC0Y: EC0Y is a squareness error, a constant"):
        mach.tool_position([[0.0, 0.0, 0.0]], {"EC0Y": PolynomialFunction([0.0, 1.0])})
    with pytest.raises(InputError, match="error EXX given twice"):
        mach.tool_position([[0.0, 0.0, 0.0]], {"EXX": 1.0, "XX": 2.0})
    with pytest.raises(InputError, match="the trial axes do not match"):
        mach.tool_position(np.zeros((4, 3)), {"EXX": np.zeros(3)})
    with pytest.raises(InputError, match="field tool: expected 3 finite numbers"):
        Machine.from_topology("XFYZ", tool=(0.0, 1.0))
    with pytest.raises(InputError, match="no machine 'nope' in the library: expected one of xfyz"):
        library_machine("nope")


def test_head_head_closed_form() -> None:
    # wfXYZCAt: the fork head carries A on C; tool point t below the A axis:
    # p = (x, y, z) + Rz(c) Rx(a) t, tool axis Rz(c) Rx(a) e_z
    m = library_machine("head-head")
    q = _random_q(m, 50, _rng(13))
    x, y, z, a, c = q.T
    R = Rotation.from_euler("xz", np.stack([a, c], axis=1))
    np.testing.assert_allclose(
        m.tool_position(q), np.stack([x, y, z], 1) + R.apply(m.tool.copy()), atol=1e-9
    )
    np.testing.assert_allclose(m.tool_direction(q), R.apply([0.0, 0.0, 1.0]), atol=1e-12)
    np.testing.assert_allclose(m.pose(q)[:, :3, :3], R.as_matrix(), atol=1e-12)
