"""Sweeps over a graph and the surrogate of Stryczek eq. 31 (general form)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mtmc.errors import GraphError, InputError
from mtmc.graph import load_graph, run_graph
from mtmc.graph.sweep import apply_setting, fit_surrogate, parse_range, sweep_graph

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "graphs"


def test_fit_surrogate_recovers_exact_coefficients():
    s1, s2 = np.meshgrid(np.linspace(1, 5, 5), np.linspace(0.5, 3, 4))
    sig = np.column_stack([s1.ravel(), s2.ravel()])
    u = np.sqrt(0.25 + 0.7 * sig[:, 0] ** 2 + 2.5 * sig[:, 1] ** 2)
    fit = fit_surrogate(sig, u, names=["a", "b"])
    np.testing.assert_allclose(fit.coefficients, [0.7, 2.5], rtol=1e-10)
    np.testing.assert_allclose(fit.c0, 0.25, rtol=1e-9)
    assert fit.max_rel_error < 1e-12
    np.testing.assert_allclose(fit.predict(sig), u, rtol=1e-12)
    # Stryczek's eq. 31 is this form with c_i = 0.05999^2 / 845 and 0.05999^2 / 868, no c0
    paper = np.sqrt(0.05999**2 * (sig[:, 0] ** 2 / 845 + sig[:, 1] ** 2 / 868))
    fit31 = fit_surrogate(sig, paper, intercept=False)
    np.testing.assert_allclose(fit31.coefficients, [0.05999**2 / 845, 0.05999**2 / 868], rtol=1e-10)
    # the fitted quantity is the standard uncertainty u (Stryczek's U), not an expanded one
    assert fit.formula() == "u = sqrt(0.25 + 0.7*a^2 + 2.5*b^2)"


def test_fit_surrogate_errors():
    with pytest.raises(InputError, match="every u must be > 0"):
        fit_surrogate([[1.0], [2.0]], [1.0, 0.0])
    with pytest.raises(InputError, match="cannot fit 3 coefficients"):
        fit_surrogate([[1.0, 2.0], [2.0, 1.0]], [1.0, 2.0])


def test_parse_range():
    np.testing.assert_allclose(parse_range("1:3:3"), [1, 2, 3])
    np.testing.assert_allclose(parse_range("1,4"), [1, 4])
    with pytest.raises(InputError, match="LOW:HIGH:N"):
        parse_range("1:2", field="probe.u_axis")


def test_fig14_grid_and_surrogate():
    """Stryczek, Fig. 14: 25 points x 1000 trials of the A-C distance; eq. 31 form within 5 %."""
    g = load_graph(EXAMPLES / "bcs_origin.toml")
    grid = {
        "probe.u_probe": np.linspace(0.001, 0.005, 5),
        "probe.u_axis": np.linspace(0.001, 0.005, 5),
    }
    res = sweep_graph(g, grid, "d_ac", trials=1000, seed=14)
    assert res.grid.shape == (25, 2)
    assert res.u.shape == (25,)
    fit = res.fit()
    assert fit.max_rel_error <= 0.05
    # each grid point is an ordinary run with the same seed
    one = apply_setting(apply_setting(g, "probe.u_probe", 0.003), "probe.u_axis", 0.005)
    r = run_graph(one, 1000, seed=14, outputs=["d_ac"])
    np.testing.assert_allclose(res.u[2 * 5 + 4], r.places["d_ac"].u, rtol=1e-12)
    # u grows with both sigmas
    assert np.all(np.diff(res.u.reshape(5, 5), axis=0) > 0)
    assert np.all(np.diff(res.u.reshape(5, 5), axis=1) > 0)
    csv = res.to_csv(fit).splitlines()
    assert csv[0] == "probe.u_probe,probe.u_axis,d_ac_estimate,d_ac_u,u_surrogate,rel_error"
    assert len(csv) == 26


def test_surrogate_coefficient_matches_the_closed_form():
    """Ball centre: u(cx)^2 = (u1^2 + u2^2 + u3^2) / 2, so c(u_probe) = c(u_axis) = 1/2."""
    g = load_graph(EXAMPLES / "ball_centre.toml")
    res = sweep_graph(
        g,
        {"probe.u_probe": [0.001, 0.003, 0.005], "probe.u_axis": [0.001, 0.004]},
        "cx",
        trials=20_000,
        seed=3,
    )
    fit = res.fit()
    # every grid point runs with the same seed and the probe draws each coordinate of an
    # axis-aligned probing as one normal (mtmc.graph.probe), so u(cx)² = K (u1² + u2² + u3²)/2
    # with one sample factor K = s²/σ² for the whole grid (u3 = u_perp = 0.0005 mm is not
    # swept: c0 = K u3²/2): the surrogate is exact, its coefficients are equal, and each
    # is K/2 with K within five relative standard errors of a sample variance,
    # √(2/(M - 1)), of 1.
    np.testing.assert_allclose(fit.coefficients[0], fit.coefficients[1], rtol=1e-9)
    assert fit.max_rel_error < 1e-9
    tol = 5 * np.sqrt(2 / (20_000 - 1))
    np.testing.assert_allclose(fit.coefficients, [0.5, 0.5], rtol=tol)
    np.testing.assert_allclose(fit.c0 / 0.0005**2, fit.coefficients[0], rtol=1e-6)


def test_apply_setting_and_sweep_errors():
    g = load_graph(EXAMPLES / "ball_centre.toml")
    assert apply_setting(g, "neg_r1.u", 0.1).place("neg_r1").u == 0.1
    assert apply_setting(g, "m1.u_probe", 0.1).transition("m1").param("u_probe") == 0.1
    with pytest.raises(InputError, match="neither probe, a place nor a transition"):
        apply_setting(g, "zz.u", 1.0)
    with pytest.raises(InputError, match="probe has no field 'u_x'"):
        apply_setting(g, "probe.u_x", 1.0)
    with pytest.raises(GraphError, match="needs a scalar output place"):
        sweep_graph(g, {"probe.u_axis": [0.001]}, "p", trials=10, seed=1)


def test_point_groups_are_consecutive_larger_first_and_end_as_one_point_a_task():
    import heapq
    import math

    from mtmc.graph.sweep import SWEEP_TASKS_PER_WORKER, _point_groups

    assert [len(g) for g in _point_groups(25, 2)] == [4, 3, 3, 3, 3, 3, 3, 3]
    assert _point_groups(0, 2) == []
    for n in range(1, 121):
        for w in range(1, 17):
            groups = _point_groups(n, w)
            assert [i for g in groups for i in g] == list(range(n))
            sizes = [len(g) for g in groups]
            assert len(sizes) == min(n, SWEEP_TASKS_PER_WORKER * w)
            assert sizes == sorted(sizes, reverse=True)
            assert sizes[0] - sizes[-1] <= 1
            # w workers of equal speed, each taking the next task when it is free, end
            # within ceil(n / w) points: what one point a task gives
            free = [0] * w
            for s in sizes:
                heapq.heappush(free, heapq.heappop(free) + s)
            assert max(free) == math.ceil(n / w), (n, w)


@pytest.mark.parametrize("executor", ["thread", "process"])
def test_a_sweep_in_groups_of_points_on_workers_gives_the_bits_of_one_process(executor):
    # 7 grid points on 2 workers would be 7 tasks of one point; with 2 tasks a worker they
    # are 4 tasks of 2, 2, 2 and 1 points, whose results come back point by point
    from unittest import mock

    from mtmc.graph import sweep as sweep_mod

    g = load_graph(EXAMPLES / "bcs_origin.toml")
    vary = {"probe.u_probe": np.linspace(0.001, 0.004, 7)}
    plain = sweep_graph(g, vary, "d_ac", trials=600, seed=9)
    seen: list[int] = []
    with mock.patch.object(sweep_mod, "SWEEP_TASKS_PER_WORKER", 2):
        assert [len(x) for x in sweep_mod._point_groups(7, 2)] == [2, 2, 2, 1]
        res = sweep_graph(
            g,
            vary,
            "d_ac",
            trials=600,
            seed=9,
            workers=2,
            executor=executor,
            progress=lambda done, _total: seen.append(done),
        )
    np.testing.assert_array_equal(res.u, plain.u)
    np.testing.assert_array_equal(res.estimate, plain.estimate)
    assert seen == [600 * (i + 1) for i in range(7)]
