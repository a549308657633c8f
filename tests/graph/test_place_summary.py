"""A place's summary: one type per attribute whatever the place type, values from NumPy.

The reference for every number is the mean and covariance that NumPy computes from the
kept samples of the place, flattened here by hand (not by the library's ``flatten``).
"""

from __future__ import annotations

import numpy as np
import pytest

from mtmc.errors import InputError
from mtmc.graph import loads_graph, run_graph
from mtmc.uncertainty.results import MonteCarloResult

M = 400

GRAPH = """
[probe]
u_axis = 0.0

[[place]]
name = "A"
type = "point"
value = [0.0, 0.0, 0.0]
u = 0.01

[[place]]
name = "B"
type = "point"
value = [10.0, 0.0, 0.0]
u = 0.01

[[place]]
name = "C"
type = "point"
value = [0.0, 10.0, 0.0]
u = 0.01

[[place]]
name = "P"
type = "point"
value = [3.0, 4.0, 5.0]
u = 0.01

[[transition]]
name = "t_d"
op = "distance"
in = ["P", "A"]
out = "d"

[[transition]]
name = "t_v"
op = "vector"
in = ["A", "P"]
out = "v"

[[transition]]
name = "t_ln"
op = "line"
in = ["A", "B"]
out = "ln"

[[transition]]
name = "t_pl"
op = "plane"
in = ["A", "B", "C"]
out = "pl"

[[transition]]
name = "t_ci"
op = "circle"
in = ["A", "B", "C"]
out = "ci"

[[transition]]
name = "t_sp"
op = "sphere"
in = ["A", "B", "C", "P"]
out = "sp"

[[transition]]
name = "t_fr"
op = "frame"
in = ["pl", "ln", "P"]
out = "fr"
"""

# place -> (type, parts and their number of components)
PLACES = {
    "d": ("real", (("value", 1),)),
    "P": ("point", (("value", 3),)),
    "v": ("vector", (("value", 3),)),
    "ln": ("line", (("point", 3), ("direction", 3))),
    "pl": ("plane", (("point", 3), ("normal", 3))),
    "ci": ("circle", (("centre", 3), ("normal", 3), ("radius", 1))),
    "sp": ("sphere", (("centre", 3), ("radius", 1))),
    "fr": ("frame", (("rotation", 9), ("translation", 3))),
}


def by_hand(value) -> np.ndarray:
    """The components of M place values as an (M, k) array, in the documented order."""
    if isinstance(value, np.ndarray):
        if value.ndim == 1:
            return value[:, None]
        if value.ndim == 3:  # frames: rotation row by row, then translation
            return np.hstack([value[:, :3, :3].reshape(len(value), 9), value[:, :3, 3]])
        return value
    cols = [
        getattr(value, a)
        for a in ("point", "centre", "direction", "normal", "radius")
        if hasattr(value, a)
    ]
    return np.hstack([c.reshape(len(c), -1) for c in cols])


@pytest.fixture(scope="module")
def runs():
    g = loads_graph(GRAPH)
    kept = run_graph(g, M, seed=3, outputs=list(PLACES), keep=list(PLACES))
    moments = run_graph(g, M, seed=3, outputs=list(PLACES))  # no samples: merged moments
    return kept, moments


@pytest.mark.parametrize("name", list(PLACES))
def test_every_attribute_has_one_type_and_the_documented_shape(runs, name):
    type_, parts = PLACES[name]
    k = sum(n for _, n in parts)
    for r in runs:
        s = r.places[name]
        assert s.type == type_
        assert s.parts == tuple(p for p, _ in parts)
        for arr, shape in ((s.estimate_vector, (k,)), (s.u_vector, (k,)), (s.cov, (k, k))):
            assert type(arr) is np.ndarray
            assert arr.dtype == np.float64
            assert arr.shape == shape
            assert not arr.flags.writeable
            with pytest.raises(ValueError, match="read-only"):
                arr[0] = 1.0
        if type_ == "real":
            assert type(s.estimate) is float
            assert type(s.u) is float
        else:
            for attr in ("estimate", "u"):
                with pytest.raises(InputError, match=f"{attr}_vector \\(shape \\({k},\\)\\)"):
                    getattr(s, attr)
        for part, j in parts:
            pr = s.part(part)
            assert type(pr) is MonteCarloResult
            assert pr.dim == (0 if j == 1 else j)
            assert pr.estimate_vector.shape == pr.u_vector.shape == (j,)
            assert pr.cov.shape == (j, j)
            assert not pr.estimate_vector.flags.writeable
            assert not pr.cov.flags.writeable
            assert pr.trials == M
            assert pr.seed == 3
            if j == 1:
                assert type(pr.estimate) is float
                assert type(pr.u) is float
            else:
                with pytest.raises(InputError, match="estimate_vector"):
                    _ = pr.estimate
        with pytest.raises(InputError, match="no part 'nope'"):
            s.part("nope")


@pytest.mark.parametrize("name", list(PLACES))
def test_values_are_the_mean_and_covariance_of_the_kept_samples(runs, name):
    kept, moments = runs
    x = by_hand(kept.samples[name])
    mean, cov = x.mean(axis=0), np.atleast_2d(np.cov(x, rowvar=False, ddof=1))
    u = np.sqrt(np.diag(cov))
    scale = np.abs(x).max()  # the numbers: rounding of sums of M values of this size
    atol_m, atol_c = 1e-13 * scale, 1e-13 * scale**2
    for r in (kept, moments):
        s = r.places[name]
        np.testing.assert_allclose(s.estimate_vector, mean, rtol=1e-13, atol=atol_m)
        np.testing.assert_allclose(s.cov, cov, rtol=1e-10, atol=atol_c)
        np.testing.assert_allclose(s.u_vector, u, rtol=1e-10, atol=1e-12)
        if s.type == "real":
            assert s.estimate == pytest.approx(mean[0], rel=1e-13)
            assert s.u == pytest.approx(u[0], rel=1e-10)
        i = 0
        for part, j in PLACES[name][1]:
            pr = s.part(part)
            sl = slice(i, i + j)
            np.testing.assert_allclose(pr.estimate_vector, mean[sl], rtol=1e-13, atol=atol_m)
            np.testing.assert_allclose(pr.u_vector, u[sl], rtol=1e-10, atol=1e-12)
            np.testing.assert_allclose(pr.cov, cov[sl, sl], rtol=1e-10, atol=atol_c)
            assert pr.kept == (r is kept)
            if r is kept:  # the part's own samples, for intervals and histograms
                np.testing.assert_array_equal(pr.values.reshape(M, -1), x[:, sl])
            i += j
        assert i == x.shape[1]


def test_a_scalar_part_gives_coverage_intervals_when_kept(runs):
    kept, _ = runs
    radius = kept.places["sp"].part("radius")
    x = by_hand(kept.samples["sp"])[:, 3]
    lo, hi = radius.coverage_interval(0.9)
    s = np.sort(x)
    # JCGM 101 §7.7.2: the symmetric interval is [y_(r), y_(r+q)], q = pM, r = (M - q)/2
    assert (lo, hi) == (s[19], s[19 + 360])


def test_json_layout(runs):
    kept, _ = runs
    d = kept.to_dict()["places"]
    assert d["d"] == {
        "type": "real",
        "estimate": kept.places["d"].estimate,
        "u": kept.places["d"].u,
    }
    assert set(d["P"]) == {"type", "estimate", "u", "cov"}
    np.testing.assert_array_equal(d["P"]["cov"], kept.places["P"].cov)
    assert set(d["ci"]) == {"type", "centre", "normal", "radius"}
    assert isinstance(d["ci"]["radius"]["u"], float)
    rot = kept.places["fr"].part("rotation")
    np.testing.assert_array_equal(
        d["fr"]["rotation"]["estimate"], rot.estimate_vector.reshape(3, 3)
    )
    assert np.shape(d["fr"]["translation"]["u"]) == (3,)


def test_normal_plane_parts_of_a_line_circle_and_direction() -> None:
    """Closed form: in the plane normal to the mean axis, the point of a line keeps its
    distance from the axis through the origin and the direction its sine of tilt,
    whatever the axis (``|p|² − (p·d̄)²`` and ``|d|² − (d·d̄)²``; compared absolutely, to
    a few roundings of ``|p|² ≈ 50`` and of ``|d|² = 1``, the differences cancelling)."""
    from scipy.spatial.transform import Rotation

    from mtmc.graph.values import normal_plane_parts

    rng = np.random.default_rng(5)
    m = 400
    tilt = rng.normal(0.0, 1e-3, size=(m, 2))
    d = np.column_stack([tilt, np.ones(m)])
    d /= np.linalg.norm(d, axis=1)[:, None]
    p = np.column_stack([rng.normal(0.0, [2e-3, 5e-3], size=(m, 2)), rng.normal(7.0, 1.0, m)])
    rot = Rotation.from_euler("xyz", [0.3, -1.1, 2.0]).as_matrix()
    p, d = p @ rot.T, d @ rot.T
    axis = d.mean(axis=0) / np.linalg.norm(d.mean(axis=0))
    (n1, a), (n2, b) = normal_plane_parts("line", np.column_stack([p, d]))
    assert (n1, n2) == ("point", "direction")
    assert a.shape == b.shape == (m, 2)
    np.testing.assert_allclose(np.sum(a**2, axis=1), np.sum(p**2, 1) - (p @ axis) ** 2, atol=1e-13)
    np.testing.assert_allclose(np.sum(b**2, axis=1), 1.0 - (d @ axis) ** 2, atol=1e-15)
    circle = np.column_stack([p, d, np.full(m, 3.0)])
    assert [n for n, _ in normal_plane_parts("circle", circle)] == ["centre", "normal"]
    ((n3, c),) = normal_plane_parts("direction", d)
    np.testing.assert_array_equal(c, b)
    assert n3 == "value"
    assert normal_plane_parts("point", p) == ()
