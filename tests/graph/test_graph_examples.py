"""The shipped example graphs against closed forms, a plain-NumPy Monte Carlo, and the GUM.

Tolerances: the relative standard deviation of a Monte Carlo standard uncertainty from M
normal-ish trials is about 1/sqrt(2M) (0.22 % at M = 10^5, 0.5 % at M = 2·10^4); each
tolerance below is at least five of those (two independent runs compared: sqrt 2 more).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from mtmc.graph import graph_model, load_graph, run_graph
from mtmc.uncertainty import gum, validate

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "graphs"
U1, U2, U3 = 0.002, 0.001, 0.0005  # the [probe] of every example
U_DIR = math.sqrt(U1**2 + U2**2 + U3**2)  # Stryczek eq. 1, along the probing direction
U_R1 = 0.0005  # u of the ball radius
R_BALL = 12.7


def test_ball_centre_closed_form():
    r = run_graph(load_graph(EXAMPLES / "ball_centre.toml"), 100_000, seed=11)
    p = r.places["p"]
    # cx = (x1 + x2)/2 with each coordinate N(., u_dir^2): u = u_dir / sqrt 2
    np.testing.assert_allclose(p.u_vector[:2], U_DIR / math.sqrt(2), rtol=0.012)
    # cz = z1 - r1: u = sqrt(u_dir^2 + u_r1^2)
    np.testing.assert_allclose(p.u_vector[2], math.hypot(U_DIR, U_R1), rtol=0.012)
    np.testing.assert_allclose(p.estimate_vector, 0.0, atol=5 * U_DIR / math.sqrt(100_000))
    assert abs(p.cov[0, 1]) < 5 * U_DIR**2 / 2 / math.sqrt(100_000)


def test_ball_centre_box_muller():
    """The same closed form with normals made by Box-Muller (Stryczek eq. 6)."""
    g = load_graph(EXAMPLES / "ball_centre.toml")
    r = run_graph(g, 100_000, seed=11, normal_method="box-muller", outputs=["p"])
    np.testing.assert_allclose(r.places["p"].u_vector[:2], U_DIR / math.sqrt(2), rtol=0.012)
    d = run_graph(g, 1000, seed=11, outputs=["p"])
    assert not np.array_equal(r.places["p"].estimate_vector, d.places["p"].estimate_vector)


def test_plane_3pt_closed_form():
    """Normal of the plane through (0,0), (a,0), (0,b): n ~ (-(e2-e1)/a, -(e3-e1)/b, 1)."""
    r = run_graph(load_graph(EXAMPLES / "plane_3pt.toml"), 100_000, seed=12)
    n = r.places["normal"]
    np.testing.assert_allclose(
        n.u_vector[:2], [math.sqrt(2) * U_DIR / 100, math.sqrt(2) * U_DIR / 80], rtol=0.012
    )
    np.testing.assert_allclose(n.estimate_vector, [0, 0, 1], atol=1e-6)
    # the plane's point is the first probed point: u1 in x and y, u_dir along z
    pt = r.places["plane"].part("point")
    np.testing.assert_allclose(pt.u_vector, [U1, U1, U_DIR], rtol=0.012)


def test_plane_lsq_closed_form():
    """Least-squares plane: u(slope) = u_dir / sqrt(sum (x - mean x)^2), u(z) = u_dir / sqrt n."""
    r = run_graph(load_graph(EXAMPLES / "plane_lsq.toml"), 100_000, seed=13)
    x = np.array([0, 50, 100, 100, 100, 50, 0, 0.0])
    y = np.array([0, 0, 0, 40, 80, 80, 80, 40.0])
    want = [
        U_DIR / np.sqrt(((x - x.mean()) ** 2).sum()),
        U_DIR / np.sqrt(((y - y.mean()) ** 2).sum()),
    ]
    np.testing.assert_allclose(r.places["normal"].u_vector[:2], want, rtol=0.012)
    pt = r.places["plane"].part("point")
    np.testing.assert_allclose(pt.u_vector[2], U_DIR / math.sqrt(8), rtol=0.012)
    np.testing.assert_allclose(pt.estimate_vector, [50, 40, 0], atol=1e-4)


def ball_centres(rng, m, centres, dr):
    """Plain NumPy: ball centres by 4 + 1 points; dr is the shared error of r1."""
    out = []
    for c in centres:
        e = rng.normal(0.0, U_DIR, size=(m, 5))
        out.append(
            np.column_stack(
                [c[0] + e[:, :2].mean(1), c[1] + e[:, 2:4].mean(1), c[2] + e[:, 4] + dr]
            )
        )
    return out


def paper_axis(p1, p2, p3, alpha):
    """Stryczek eqs. 8-19 (eq. 14 read as X4 - X1) and eqs. 20-27 (eq. 22 sign corrected)."""
    p4 = (p2 + p3) / 2
    big_r = np.linalg.norm(p3 - p4, axis=1) / np.sin(alpha)
    v1 = (p4 - p1) / np.linalg.norm(p4 - p1, axis=1)[:, None]
    a, b = p2 - p1, p3 - p1
    n = np.column_stack(
        [
            a[:, 1] * b[:, 2] - b[:, 1] * a[:, 2],
            a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
            a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1],
        ]
    )
    return p1 + big_r[:, None] * v1, n / np.linalg.norm(n, axis=1)[:, None]


def circumcentre(p1, p2, p3):
    """Circle centre by solving 2(Pi - P1)·c = |Pi|^2 - |P1|^2, n·c = n·P1 per trial."""
    n = np.cross(p2 - p1, p3 - p1)
    A = np.stack([2 * (p2 - p1), 2 * (p3 - p1), n], axis=1)
    rhs = np.column_stack(
        [(p2**2).sum(1) - (p1**2).sum(1), (p3**2).sum(1) - (p1**2).sum(1), (n * p1).sum(1)]
    )
    return np.linalg.solve(A, rhs[..., None])[..., 0], n / np.linalg.norm(n, axis=1)[:, None]


def positions(axis, p0, alpha):
    c, s = math.cos(alpha), math.sin(alpha)
    x, y, z = p0
    if axis == "z":
        return [(x, y, z), (c * x - s * y, s * x + c * y, z), (c * x + s * y, -s * x + c * y, z)]
    return [(x, y, z), (x, c * y - s * z, s * y + c * z), (x, c * y + s * z, -s * y + c * z)]


M = 20_000


@pytest.mark.parametrize("with_alpha", [True, False])
def test_axis_c_against_plain_numpy(with_alpha):
    g = load_graph(EXAMPLES / "axis_c.toml")
    if not with_alpha:  # the 3-point variant: circle through the three centres
        t = g.transition("t_axis_c")
        new = dataclasses.replace(t, inputs=t.inputs[:3])
        g = dataclasses.replace(g, transitions=tuple(new if x is t else x for x in g.transitions))
    r = run_graph(g, M, seed=21)
    rng = np.random.default_rng(99)
    alpha = math.radians(60)
    dr = rng.normal(0, U_R1, M)
    p1, p2, p3 = ball_centres(rng, M, positions("z", (150.0, 0.0, 40.0), alpha), dr)
    centre, n = paper_axis(p1, p2, p3, alpha) if with_alpha else circumcentre(p1, p2, p3)
    line = r.places["axis_c"]
    est_p, u_p = line.part("point").estimate_vector, line.part("point").u_vector
    u_d = line.part("direction").u_vector
    np.testing.assert_allclose(u_p, centre.std(0, ddof=1), rtol=0.04)
    np.testing.assert_allclose(u_d[:2], n[:, :2].std(0, ddof=1), rtol=0.04)
    np.testing.assert_allclose(est_p, [0, 0, 40], atol=4 * u_p.max() / math.sqrt(M))
    # P_C on the table: P0 - (40 + e_r2) v_C
    pc = centre + (-40 + rng.normal(0, 0.001, M))[:, None] * n
    np.testing.assert_allclose(r.places["p_c"].u_vector, pc.std(0, ddof=1), rtol=0.04)


def bcs_plain(rng, m):
    dr = rng.normal(0, U_R1, m)
    a_pts = ball_centres(rng, m, positions("x", (0.0, 0.0, 120.0), math.radians(30)), dr)
    c_pts = ball_centres(rng, m, positions("z", (150.0, 0.0, -10.0), math.radians(60)), dr)
    pa, va = paper_axis(*a_pts, math.radians(30))
    pc0, vc = paper_axis(*c_pts, math.radians(60))
    pc = pc0 + (-40 + rng.normal(0, 0.001, m))[:, None] * vc
    po = (
        pa + ((pc - pa) * va).sum(1)[:, None] * va
    )  # eq. 30: plane through P_C normal to A, met by A
    return np.linalg.norm(pc - po, axis=1), po


def test_axis_a_against_plain_numpy():
    r = run_graph(load_graph(EXAMPLES / "axis_a.toml"), M, seed=22)
    rng = np.random.default_rng(98)
    dr = rng.normal(0, U_R1, M)
    pts = ball_centres(rng, M, positions("x", (0.0, 0.0, 120.0), math.radians(30)), dr)
    centre, n = paper_axis(*pts, math.radians(30))
    np.testing.assert_allclose(
        r.places["axis_a"].part("point").u_vector, centre.std(0, ddof=1), rtol=0.04
    )
    np.testing.assert_allclose(r.places["v_a"].u_vector[1:], n[:, 1:].std(0, ddof=1), rtol=0.04)


def test_bcs_origin_against_plain_numpy():
    r = run_graph(load_graph(EXAMPLES / "bcs_origin.toml"), M, seed=23, keep=["d_ac"])
    d, po = bcs_plain(np.random.default_rng(97), M)
    np.testing.assert_allclose(r.places["d_ac"].u, d.std(ddof=1), rtol=0.04)
    np.testing.assert_allclose(r.places["p_o"].u_vector, po.std(0, ddof=1), rtol=0.04)
    np.testing.assert_allclose(r.places["d_ac"].estimate, 50.0, atol=4 * d.std() / math.sqrt(M))
    # the kept samples give the same summary as the running sums
    res = r.result("d_ac")
    np.testing.assert_allclose(res.u, r.places["d_ac"].u, rtol=1e-9)


def test_bcs_origin_gum_agrees_with_mc():
    """JCGM 101 §8: the GUM interval of d_AC validated by MC (the model is near-linear)."""
    g = load_graph(EXAMPLES / "bcs_origin.toml")
    model, inputs = graph_model(g, "d_ac")
    gr = gum(model, inputs)
    r = run_graph(g, 200_000, seed=24, outputs=["d_ac"], keep=["d_ac"])
    mc = r.result("d_ac")
    v = validate(gr, mc, ndig=2)
    assert v.passed, v
    np.testing.assert_allclose(gr.u, mc.u, rtol=0.01)


def test_block_size_does_not_change_the_numbers():
    g = load_graph(EXAMPLES / "axis_c.toml")
    a = run_graph(g, 5000, seed=31, keep=["p_c", "c1_x1"], outputs=["p_c"], block_size=5000)
    b = run_graph(g, 5000, seed=31, keep=["p_c", "c1_x1"], outputs=["p_c"], block_size=777)
    np.testing.assert_array_equal(a.samples["p_c"], b.samples["p_c"])
    np.testing.assert_array_equal(a.samples["c1_x1"], b.samples["c1_x1"])
    np.testing.assert_allclose(a.places["p_c"].cov, b.places["p_c"].cov, rtol=1e-9)
    c = run_graph(g, 5000, seed=32, keep=["p_c"], outputs=["p_c"])
    assert not np.array_equal(a.samples["p_c"], c.samples["p_c"])


def test_micrometre_file_gives_the_same_result_in_mm():
    text = (EXAMPLES / "ball_centre.toml").read_text()
    g_mm = load_graph(EXAMPLES / "ball_centre.toml")
    from mtmc.graph import loads_graph

    um = text.replace('units = "mm"', 'units = "um"')
    um = um.replace("u_axis = 0.002", "u_axis = 2.0").replace("u_probe = 0.001", "u_probe = 1.0")
    um = um.replace("u_perp = 0.0005", "u_perp = 0.5").replace("u = 0.0005", "u = 0.5")
    um = um.replace("-12.7", "-12700.0").replace("12.7", "12700.0")
    a = run_graph(g_mm, 2000, seed=5, outputs=["p"])
    b = run_graph(loads_graph(um), 2000, seed=5, outputs=["p"])
    np.testing.assert_allclose(
        b.places["p"].estimate_vector, a.places["p"].estimate_vector, atol=1e-12
    )
    np.testing.assert_allclose(b.places["p"].u_vector, a.places["p"].u_vector, rtol=1e-9)
