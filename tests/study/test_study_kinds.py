"""Each shipped study runs, and its numbers are those of the library call it wraps."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import chi2

from mtmc import (
    expression,
    graph_model,
    gum,
    load_graph,
    monte_carlo,
    parse_distribution,
    run_graph,
    sweep_graph,
    validate,
)
from mtmc.geometry.constructions import normal_plane_basis
from mtmc.study import load_study
from mtmc.uncertainty.propagation import endpoint_std_error
from mtmc.uncertainty.results import convergence

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "examples" / "studies"
GRAPHS = ROOT / "examples" / "graphs"
M = 20_000
SEED = 7


def _mc_tol(m: int, n_sigma: float = 4.0) -> float:
    """n_sigma relative standard errors of a Monte Carlo standard deviation."""
    return n_sigma / math.sqrt(2.0 * (m - 1))


@pytest.fixture(scope="module")
def results():
    out = {}
    for name in ("mass_calibration", "ball_centre", "axis_c", "axis_a", "bcs_origin"):
        out[name] = load_study(STUDIES / f"{name}.toml").run(trials=M, seed=SEED)
    return out


def test_mass_calibration_is_monte_carlo_and_gum_of_the_model(results):
    r = results["mass_calibration"]
    q = r.quantity("dm")
    model = expression("(m_rc + dm_rc) * (1 + (rho_a - 1.2) * (1 / rho_w - 1 / rho_r)) - 100000")
    inputs = {
        "m_rc": parse_distribution("normal(100000.000, 0.050)"),
        "dm_rc": parse_distribution("normal(1.234, 0.020)"),
        "rho_a": parse_distribution("uniform(1.10, 1.30)"),
        "rho_w": parse_distribution("uniform(7000, 9000)"),
        "rho_r": parse_distribution("uniform(7950, 8050)"),
    }
    mc = monte_carlo(model, inputs, trials=M, seed=SEED)
    assert q.mc.estimate == mc.estimate
    assert q.mc.u == mc.u
    assert q.mc.shortest == mc.coverage_interval(0.95, "shortest")
    assert q.mc.symmetric == mc.coverage_interval(0.95, "symmetric")
    # the study file asks for the shortest interval: U is its half-length
    assert q.mc.interval == "shortest"
    lo, hi = mc.coverage_interval(0.95, "shortest")
    assert q.mc.U == 0.5 * (hi - lo) != mc.expanded_uncertainty(0.95, "symmetric")
    g = gum(model, inputs)
    assert q.gum.u == g.u
    assert q.gum.k == g.coverage_factor()
    v = validate(g, mc, p=0.95, kind="shortest")
    assert q.validation.d_low == v.d_low
    assert q.validation.kind == "shortest"
    # JCGM 101 Table 7: u(δm) = 0.0754 mg by MC, 0.0539 mg by the GUM
    assert q.mc.u == pytest.approx(0.0754, rel=_mc_tol(M))
    assert q.gum.u == pytest.approx(0.0539, abs=5e-5)
    shares = [b.share for b in q.budget]
    assert sum(shares) == pytest.approx(1.0, abs=1e-12)
    assert [b.name for b in q.budget] == list(inputs)


def test_graph_study_is_monte_carlo_of_graph_model_and_equals_run_graph(results):
    r = results["bcs_origin"]
    g = load_graph(GRAPHS / "bcs_origin.toml")
    model, inputs = graph_model(g, "d_ac")
    mc = monte_carlo(model, inputs, trials=M, seed=SEED)
    q = r.quantity("d_ac")
    assert q.mc.u == mc.u
    assert q.mc.estimate == mc.estimate
    # no [run] interval: U is half the probabilistically symmetric interval, as the API's
    lo, hi = mc.coverage_interval(0.95, "symmetric")
    assert q.mc.interval == "symmetric"
    assert q.mc.U == 0.5 * (hi - lo) == mc.expanded_uncertainty(0.95)
    assert q.mc.k == q.mc.U / mc.u
    # a second route: the graph's own batched run draws the same trials
    res = run_graph(g, M, SEED, outputs=["d_ac", "p_o"])
    assert q.mc.u == pytest.approx(res.places["d_ac"].u, rel=1e-9)
    np.testing.assert_allclose(
        [r.quantity(f"p_o.{c}").mc.u for c in "xyz"], res.places["p_o"].u_vector, rtol=1e-9
    )
    # the GUM of the component models beside Monte Carlo
    assert q.gum.u == pytest.approx(gum(model, inputs).u, rel=1e-12)
    assert q.mc.u == pytest.approx(q.gum.u, rel=_mc_tol(M))
    for quant in r.quantities:
        assert sum(b.share for b in quant.budget) == pytest.approx(1.0, abs=1e-9)


def test_ball_centre_against_the_closed_form_of_the_probe_model(results):
    r = results["ball_centre"]
    # u_dir = sqrt(2² + 1² + 0.5²) µm on each probed coordinate, u(r1) = 0.5 µm
    u_dir = math.sqrt(2.0**2 + 1.0**2 + 0.5**2) * 1e-3
    closed = [u_dir / math.sqrt(2.0), u_dir / math.sqrt(2.0), math.hypot(u_dir, 0.5e-3)]
    for c, u in zip("xyz", closed, strict=True):
        q = r.quantity(f"p.{c}")
        assert q.unit == "mm"
        assert q.gum.u == pytest.approx(u, rel=1e-6)
        assert q.mc.u == pytest.approx(u, rel=_mc_tol(M))
    assert {reg.name for reg in r.regions} == {"p: x, y", "p: x, z", "p: y, z"}


@pytest.mark.parametrize("name", ["axis_c", "axis_a"])
def test_axis_regions_against_the_gaussian_ellipse(results, name):
    r = results[name]
    g = load_graph(GRAPHS / f"{name}.toml")
    res = run_graph(g, M, SEED, outputs=[name], keep=[name])
    direction = res.places[name].part("direction").estimate_vector
    cov = res.places[name].part("point").cov
    reg = r.regions[0]
    assert reg.name.startswith(f"{name}: point")
    # the plane of the region is normal to the axis: its covariance is the projection
    samples = res.samples[name].point
    basis = np.linalg.svd(np.eye(3) - np.outer(direction, direction) / (direction @ direction))[0]
    plane = basis[:, :2]
    lam_ref = np.linalg.eigvalsh(plane.T @ cov @ plane)
    np.testing.assert_allclose(np.sort(np.linalg.eigvalsh(reg.cov)), lam_ref, rtol=1e-6)
    assert reg.k_chi2 == pytest.approx(math.sqrt(chi2.ppf(0.95, 2)), rel=1e-12)
    assert reg.k == pytest.approx(reg.k_chi2, rel=0.03)
    # in the region's own basis of that plane, a fraction p of the trials lies inside
    own = normal_plane_basis(direction)
    assert np.allclose(own.T @ own, np.eye(2))
    assert np.allclose(own.T @ direction, 0.0)
    dev = samples @ own - samples.mean(0) @ own
    inside = np.einsum("ij,jk,ik->i", dev, np.linalg.inv(reg.cov), dev)
    assert np.mean(inside <= reg.k**2) == pytest.approx(0.95, abs=1e-3)
    # direction: the component along the axis moves to second order only
    comps = [r.quantity(f"{name}.direction.{c}") for c in "xyz"]
    along = int(np.argmax(np.abs(direction)))
    assert comps[along].gum.u < 1e-3 * max(c.mc.u for c in comps)


def test_sweep_is_the_library_sweep_with_its_surrogate(results):
    sw = results["bcs_origin"].extra["sweep"]
    g = load_graph(GRAPHS / "bcs_origin.toml")
    vals = np.linspace(0.001, 0.005, 5)
    ref = sweep_graph(
        g, {"probe.u_probe": vals, "probe.u_axis": vals}, "d_ac", trials=1000, seed=SEED
    )
    np.testing.assert_array_equal(sw["u"], ref.u)
    fit = ref.fit(intercept=True)
    np.testing.assert_allclose(sw["surrogate"]["coefficients"], fit.coefficients, rtol=1e-12)
    assert sw["surrogate"]["max_rel_error"] <= 0.05  # Stryczek: at most 5 %
    assert len(results["bcs_origin"].tables[0].rows) == 25
    # the surface the report draws is the study's: u = sqrt(c0 + c_p s_p^2 + c_m s_m^2)
    # over the box of the grid, written out here from the fitted constants
    a, b = (np.asarray(x) for x in sw["surface"]["axes"])
    np.testing.assert_allclose(a, np.linspace(0.001, 0.005, 30), rtol=1e-12)
    c0, (cp, cm) = fit.c0, fit.coefficients
    want = np.sqrt(c0 + cp * a[:, None] ** 2 + cm * b[None, :] ** 2)
    np.testing.assert_allclose(sw["surface"]["u"], want, rtol=1e-12)


def test_convergence_movement_over_the_last_half_against_direct_std(results):
    r = results["mass_calibration"]
    q = r.quantity("dm")
    cv = q.convergence
    # an independent recomputation: the standard deviation of the first m values for
    # every m of the curve in the last half, from the model values of the same run
    model = expression("(m_rc + dm_rc) * (1 + (rho_a - 1.2) * (1 / rho_w - 1 / rho_r)) - 100000")
    inputs = {
        "m_rc": "normal(100000.000, 0.050)",
        "dm_rc": "normal(1.234, 0.020)",
        "rho_a": "uniform(1.10, 1.30)",
        "rho_w": "uniform(7000, 9000)",
        "rho_r": "uniform(7950, 8050)",
    }
    y = np.asarray(monte_carlo(model, inputs, trials=M, seed=SEED).samples)
    ms = [m for m in cv.m if m >= M / 2]
    u = [y[:m].std(ddof=1) for m in ms]
    e = [y[:m].mean() for m in ms]
    assert cv.last_half_u == pytest.approx(max(u) - min(u), rel=1e-6, abs=1e-12)
    assert cv.last_half_estimate == pytest.approx(max(e) - min(e), rel=1e-6, abs=1e-12)
    # u = 0.075 mg: two significant digits give δ = 0.0005 mg (JCGM 101 §7.9.2)
    assert cv.delta == 0.0005
    assert cv.ndig == 2


def test_convergence_against_direct_means():
    x = np.random.default_rng(1).normal(3.0, 0.1, 5000)
    m, est, u = convergence(x, points=7)
    for mi, e, s in zip(m, est, u, strict=True):
        assert e == pytest.approx(x[:mi].mean(), rel=1e-13)
        assert s == pytest.approx(x[:mi].std(ddof=1), rel=1e-9)


def test_endpoint_std_error_against_replicated_runs():
    rng = np.random.default_rng(3)
    m = 2000
    lows = np.sort(rng.normal(0.0, 1.0, (400, m)), axis=1)[:, int(0.025 * m)]
    assert lows.std(ddof=1) == pytest.approx(endpoint_std_error(1.0, m, 0.95), rel=0.15)


def test_result_is_frozen_and_reproducible(results):
    r = results["ball_centre"]
    with pytest.raises(AttributeError):
        r.seed = 3  # type: ignore[misc]
    again = load_study(STUDIES / "ball_centre.toml").run(trials=M, seed=SEED)
    assert again.to_dict() == r.to_dict()
    assert r.regions[0].scatter.flags.writeable is False


def test_package_studies_are_the_examples():
    import mtmc

    packaged = Path(mtmc.__file__).parent / "data" / "studies"
    names = sorted(p.name for p in STUDIES.glob("*.toml"))
    assert names == sorted(p.name for p in packaged.glob("*.toml"))
    for n in names:
        assert (packaged / n).read_text() == (STUDIES / n).read_text(), n


def _fd_jacobian(machine, q, names, h=1e-7):
    cols = []
    for n in names:
        plus = machine.tool_position(q, {n: h})
        minus = machine.tool_position(q, {n: -h})
        cols.append((plus - minus)[0] / (2 * h))
    return np.stack(cols, axis=1)  # (3, N)


def test_kinematics_study_against_finite_differences_and_own_sampling():
    from mtmc import library_machine

    study = load_study(STUDIES / "five_axis.toml")
    r = study.run(trials=M, seed=SEED)
    machine = library_machine("table-table")
    names = list(study.errors)
    u_e = np.array([study.errors[n].std for n in names])
    poses = study.poses
    assert poses.shape == (4, 5)
    assert poses[0, 3] == pytest.approx(math.radians(-30.0))
    rng = np.random.default_rng(np.random.SeedSequence(2024))
    m = 20_000
    own = {}
    for n in names:
        d = study.errors[n]
        if str(d).startswith("normal"):
            own[n] = rng.normal(0.0, d.std, m)
        else:
            half = d.std * math.sqrt(3.0)
            own[n] = rng.uniform(-half, half, m)
    for i, q in enumerate(poses):
        J = _fd_jacobian(machine, q, names)
        u_fd = np.sqrt((J**2) @ (u_e**2))
        u_own = machine.tool_position(q, own).std(axis=0, ddof=1)
        for j, c in enumerate("xyz"):
            quant = r.quantity(f"pose{i + 1}.{c}")
            # the GUM by differentiation of the model against finite differences
            assert quant.gum.u == pytest.approx(u_fd[j], rel=1e-5)
            # Monte Carlo against draws made here with another generator
            assert quant.mc.u == pytest.approx(u_own[j], rel=_mc_tol(M) + _mc_tol(m))
            assert quant.gum.estimate == pytest.approx(machine.tool_position(q)[0, j])
    # pose 1, x: rectangular tilts dominate, the MC interval is narrower than the GUM's
    q1x = r.quantity("pose1.x")
    assert q1x.mc.k < 1.93 < q1x.gum.k
    assert r.tables[0].rows[0] == (1, 150.0, 0.0, -100.0, -30.0, 0.0)
