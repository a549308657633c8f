"""The touch-probe model of meas (Stryczek eq. 1) against its closed-form covariance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mtmc.errors import GraphError
from mtmc.graph import loads_graph, run_graph

M = 100_000


def graph(direction, extra="", out_type=None):
    decl = f'\n[[place]]\nname = "q"\ntype = "{out_type}"\n' if out_type else ""
    return loads_graph(f"""
[probe]
u_axis = 0.002
u_probe = 0.003
u_perp = 0.001
{decl}
[[transition]]
name = "m1"
op = "meas"
at = [10.0, 20.0, 30.0]
direction = {direction}
out = "q"
{extra}
""")


def test_oblique_direction_covariance():
    """e ~ N(0, u1^2 I + (u2^2 + u3^2) d d^T) for a unit direction d."""
    d = np.array([1.0, 2.0, -2.0]) / 3.0
    r = run_graph(graph("[1.0, 2.0, -2.0]"), M, seed=1)
    want = 0.002**2 * np.eye(3) + (0.003**2 + 0.001**2) * np.outer(d, d)
    cov = r.places["q"].cov
    # the sample covariance's entries have sd about sqrt((C_ii C_jj + C_ij^2) / M)
    sd = np.sqrt((np.outer(np.diag(want), np.diag(want)) + want**2) / M)
    assert np.all(np.abs(cov - want) < 5 * sd)
    np.testing.assert_allclose(
        r.places["q"].estimate_vector, [10, 20, 30], atol=5 * 0.004 / math.sqrt(M)
    )
    # along d: u = sqrt(u1^2 + u2^2 + u3^2) (Stryczek eq. 1)
    np.testing.assert_allclose(
        math.sqrt(d @ cov @ d), math.sqrt(0.002**2 + 0.003**2 + 0.001**2), rtol=0.012
    )


@pytest.mark.parametrize(("coord", "i"), [("x", 0), ("y", 1), ("z", 2)])
def test_coordinate_output(coord, i):
    d = np.array([0.0, 0.6, 0.8])
    r = run_graph(graph("[0.0, 0.6, 0.8]", f'coordinate = "{coord}"'), M, seed=2)
    want = math.sqrt(0.002**2 + (0.003**2 + 0.001**2) * d[i] ** 2)
    np.testing.assert_allclose(r.places["q"].u, want, rtol=0.012)
    assert r.types["q"] == coord


def test_axis_aligned_point_uses_diagonal_covariance():
    r = run_graph(graph("[0.0, 0.0, -1.0]"), M, seed=3)
    u = r.places["q"].u_vector
    np.testing.assert_allclose(
        u, [0.002, 0.002, math.sqrt(0.002**2 + 0.003**2 + 0.001**2)], rtol=0.012
    )


def test_dist_along_direction():
    """dist replaces the along-direction normal: uniform(-a, a) has u = a / sqrt 3."""
    r = run_graph(
        graph("[1.0, 0.0, 0.0]", 'dist = "uniform(-0.006, 0.006)"'), M, seed=4, keep=["q"]
    )
    u = r.places["q"].u_vector
    np.testing.assert_allclose(u, [math.sqrt(0.002**2 + 0.006**2 / 3), 0.002, 0.002], rtol=0.012)
    # the transition's u_axis overrides [probe]
    r2 = run_graph(
        graph("[1.0, 0.0, 0.0]", "u_axis = 0.0\nu_probe = 0.0\nu_perp = 0.0"), 10, seed=4
    )
    np.testing.assert_array_equal(r2.places["q"].u_vector, 0.0)


def test_bad_meas_fields():
    # checked when the file is read, naming the line of the field
    with pytest.raises(GraphError, match="probing direction is zero") as exc:
        graph("[0.0, 0.0, 0.0]")
    assert (exc.value.field, exc.value.line) == ("direction", 11)
    with pytest.raises(GraphError, match=r"line 13: field dist: transition m1: .*frob"):
        graph("[1.0, 0.0, 0.0]", 'dist = "frob(1)"')
    with pytest.raises(
        GraphError, match=r"line 13: field u_probe: .*u_probe must be a number >= 0"
    ):
        graph("[1.0, 0.0, 0.0]", "u_probe = -1.0")
    with pytest.raises(GraphError, match="meas needs at"):
        loads_graph('[[transition]]\nname = "m"\nop = "meas"\ndirection = [1, 0, 0]\nout = "q"\n')
