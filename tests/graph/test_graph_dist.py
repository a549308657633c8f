"""``dist`` on places and probings: the law, its scaling from the file's units, direction
places.

References: the standard deviation of a uniform law, ``a/√3`` for ``uniform(-a, a)``; the
same graph written in mm and in µm (``units = "um"``, every length ×1000) gives the same
numbers in mm to rounding; a ``direction`` place (a unit vector) drawn as
``(e1, e2, 1 + e3)`` with ``e ~ N(0, σ²)`` and renormalised has ``E[z] = 1 - σ² + O(σ⁴)``
and ``u(z) = σ² + O(σ⁴)`` (to second order ``z = 1 - σ²(z1² + z2²)/2``, half a χ² with 2
degrees of freedom).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mtmc.errors import MtmcError
from mtmc.graph import loads_graph, run_graph

M = 20_000
SIGMA = 0.05


def _graph(units: str, s: float) -> str:
    """A place with a ``dist``, a probing with a ``dist``, a random direction; lengths ×s."""
    text = f'units = "{units}"\n[probe]\nu_axis = 0.0\nu_probe = 0.0\nu_perp = 0.0\n'
    text += (
        f'[[place]]\nname = "a"\ntype = "real"\nvalue = {10 * s}\n'
        f'dist = "uniform({-1 * s}, {1 * s})"\n'
    )
    text += (
        '[[place]]\nname = "n"\ntype = "direction"\nvalue = [0.0, 0.0, 1.0]\n'
        f'dist = "normal(0, {SIGMA})"\n'
    )
    return text + (
        f'[[transition]]\nname = "m"\nop = "meas"\nat = [{5 * s}, 0, 0]\ndirection = [1, 0, 0]\n'
        f'dist = "uniform({-0.002 * s}, {0.002 * s})"\nout = "p"\n'
    )


@pytest.fixture(scope="module")
def runs():
    return {u: run_graph(loads_graph(_graph(u, s)), M, seed=5) for u, s in (("mm", 1), ("um", 1e3))}


def test_place_and_probe_dist_follow_their_law(runs):
    r = runs["mm"]
    a, p = r.places["a"], r.places["p"]
    u_a = 1 / math.sqrt(3)
    assert a.estimate == pytest.approx(10.0, abs=4 * u_a / math.sqrt(M))
    assert a.u == pytest.approx(u_a, rel=4 / math.sqrt(2 * M))  # a uniform law: narrower
    u_p = 0.002 / math.sqrt(3)  # the probing error along x, nothing else
    np.testing.assert_allclose(p.estimate_vector, [5, 0, 0], atol=4 * u_p / math.sqrt(M))
    assert p.u_vector[0] == pytest.approx(u_p, rel=4 / math.sqrt(2 * M))
    assert p.u_vector[1] == p.u_vector[2] == 0.0


def test_a_um_file_scales_place_and_probe_dist_to_mm(runs):
    mm, um = runs["mm"], runs["um"]
    for name in ("a", "p", "n"):
        um_p, mm_p = um.places[name], mm.places[name]
        np.testing.assert_allclose(um_p.estimate_vector, mm_p.estimate_vector, rtol=1e-12)
        np.testing.assert_allclose(um_p.u_vector, mm_p.u_vector, rtol=1e-9)
    assert um.places["a"].u == pytest.approx(1 / math.sqrt(3), rel=0.05)  # in mm, not µm


def test_random_direction_places_are_renormalised(runs):
    n = runs["mm"].places["n"]
    s2 = SIGMA**2
    assert n.estimate_vector[2] == pytest.approx(1 - s2, abs=4 * s2 / math.sqrt(M) + 2 * s2**2)
    # the sample standard deviation of a χ² law (kurtosis 9): relative error √(8/4M)
    assert n.u_vector[2] == pytest.approx(s2, rel=4 * math.sqrt(2 / M) + 4 * s2)
    np.testing.assert_allclose(n.u_vector[:2], SIGMA, rtol=4 / math.sqrt(2 * M) + 2 * s2)


@pytest.mark.parametrize(
    ("units", "dist", "words"),
    [
        ("mm", "normal(0, 1e300)", "standard uncertainty of dist at most 1e+06 mm"),  # u = ∞
        ("mm", "uniform(-3e6, 3e6)", "standard uncertainty of dist at most 1e+06 mm"),
        ("um", "normal(2e9, 1)", "expectation of dist at most 1e+09 um"),
        ("mm", "t(1)", "got nan for 't(1)'"),  # Cauchy: no expectation, no u
    ],
)
def test_a_place_dist_has_the_limits_of_a_value_and_u(units, dist, words):
    text = f'units = "{units}"\n[[place]]\nname = "a"\ntype = "real"\n\ndist = "{dist}"\n'
    text += '[[transition]]\nname = "t"\nop = "ratio"\nin = ["a", "a"]\nout = "b"\n'
    with pytest.raises(MtmcError) as info:
        loads_graph(text, file="g.toml")
    err = info.value
    assert (err.file, err.line, err.field) == ("g.toml", 6, "dist")
    assert words in err.message
    # within the limit (as a u of 10⁶ mm is): accepted
    loads_graph(text.replace(dist, "normal(0, 1e6)" if units == "mm" else "normal(0, 1e9)"))
