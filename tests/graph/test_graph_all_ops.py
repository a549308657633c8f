"""Every op variant through a graph of exact constants, against values worked by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mtmc.errors import DegenerateGeometryError
from mtmc.graph import check_graph, loads_graph, run_graph
from mtmc.graph.ops import op_names, variants

POINTS = {
    "A": (0, 0, 0),
    "B": (10, 0, 0),
    "C": (0, 10, 0),
    "D": (0, 0, 10),
    "P": (3, 4, 5),
    "K1": (5, 0, 0),
    "K2": (0, 5, 0),
    "K3": (-5, 0, 0),
    "K4": (0, -5, 0),
    "S1": (4, 2, 3),
    "S2": (1, 5, 3),
    "S3": (1, 2, 6),
    "S4": (-2, 2, 3),
    "S5": (1, -1, 3),
}
# (op, inputs, out) with the expected flattened value (None: checked separately)
STEPS = [
    ("plane", ["A", "B", "C"], "pl_z", None),
    ("plane", ["A", "B", "D"], "pl_y", None),
    ("plane", ["A", "B", "E", "C"], "pl_lsq", None),
    ("plane", ["P", "ez"], "pl_pn", None),
    ("project", ["P", "pl_z"], "proj", [3, 4, 0]),
    ("distance", ["P", "pl_z"], "d_pl", [5]),
    ("line", ["A", "B"], "ln_ab", [0, 0, 0, 1, 0, 0]),
    ("line", ["pl_z", "pl_y"], "ln_pp", None),
    ("line", ["P", "ez"], "ln_pu", [3, 4, 5, 0, 0, 1]),
    ("aline", ["P", "ez"], "ax", [3, 4, 5, 0, 0, 1]),
    ("per_proj", ["P", "ln_ab"], "foot", [3, 0, 0]),
    ("distance", ["P", "ln_ab"], "d_ln", [math.sqrt(41)]),
    ("distance", ["P", "A"], "d_pp", [math.sqrt(50)]),
    ("vector", ["A", "P"], "v_ap", [3, 4, 5]),
    ("unit_v", ["v_ap"], "u_ap", list(np.array([3, 4, 5]) / math.sqrt(50))),
    ("unit_v", ["pl_z"], "u_pl", [0, 0, 1]),
    ("unit_v", ["ln_ab"], "u_ln", [1, 0, 0]),
    ("ratio", ["v_ap", "two"], "v2", [6, 8, 10]),
    ("ratio", ["two", "two"], "four", [4]),
    ("vector", ["A", "B"], "v_ab", [10, 0, 0]),
    ("vector", ["A", "C"], "v_ac", [0, 10, 0]),
    ("angle", ["v_ab", "v_ac"], "ang_vv", [math.pi / 2]),
    ("angle", ["u_ln", "v_ap"], "ang_uv", [math.acos(3 / math.sqrt(50))]),
    ("angle", ["v_ap", "ez"], "ang_vu", [math.acos(5 / math.sqrt(50))]),
    ("angle", ["u_ln", "ez"], "ang_uu", [math.pi / 2]),
    ("point", ["ax", "pl_z"], "x_lp", [3, 4, 0]),
    ("point", ["pl_z", "ax"], "x_pl", [3, 4, 0]),
    ("point", ["ln_ab"], "pt_ln", [0, 0, 0]),
    ("middle", ["A", "B"], "mid", [5, 0, 0]),
    ("displace", ["P", "v_ab"], "dp_v", [13, 4, 5]),
    ("displace", ["P", "ez", "two"], "dp_u", [3, 4, 7]),
    ("displace", ["two", "two"], "dp_r", [4]),
    ("circle", ["K1", "K2", "K3"], "c3", [0, 0, 0, 0, 0, 1, 5]),
    ("circle", ["K1", "K2", "K3", "K4"], "c4", [0, 0, 0, 0, 0, 1, 5]),
    ("point", ["c3"], "c3_centre", [0, 0, 0]),
    ("sphere", ["S1", "S2", "S3", "S4", "S5"], "sph", [1, 2, 3, 3]),
    ("sphere", ["S1", "S2", "S3", "S4", "S5", "three"], "sph_r", [1, 2, 3, 3]),
    ("point", ["sph"], "sph_centre", [1, 2, 3]),
    ("frame", ["pl_z", "ln_ab", "P"], "fr", None),
    ("axis", ["K1", "K2", "K4"], "axis3", [0, 0, 0, 0, 0, 1]),
]


def build() -> str:
    out = ["[probe]\nu_axis = 0.0\n"]
    pts = dict(POINTS, E=(10, 10, 0))
    for name, v in pts.items():
        out.append(f'[[place]]\nname = "{name}"\ntype = "point"\nvalue = {list(map(float, v))}\n')
    out.append('[[place]]\nname = "ez"\ntype = "direction"\nvalue = [0.0, 0.0, 1.0]\n')
    out.append('[[place]]\nname = "two"\ntype = "real"\nvalue = 2.0\nunit = "1"\n')
    out.append('[[place]]\nname = "three"\ntype = "real"\nvalue = 3.0\n')
    for i, (op, ins, o, _) in enumerate(STEPS):
        out.append(
            f'[[transition]]\nname = "t{i}"\nop = "{op}"\nin = {ins}\nout = "{o}"\n'.replace(
                "'", '"'
            )
        )
    out.append(
        '[[transition]]\nname = "m"\nop = "meas"\nat = [1.0, 2.0, 3.0]\n'
        'direction = [0, 0, -1]\nout = "mp"\n'
    )
    return "\n".join(out)


def test_every_op_is_exercised():
    used = {op for op, *_ in STEPS} | {"meas"}
    assert used == set(op_names())
    n_variants = sum(len(variants(op)) for op in op_names())
    assert n_variants >= 40


def test_values_by_hand():
    g = loads_graph(build())
    plan = check_graph(g)
    r = run_graph(g, 3, seed=1)
    for _op, _ins, o, want in STEPS:
        if want is not None:
            np.testing.assert_allclose(r.places[o].estimate_vector, want, atol=1e-12, err_msg=o)
            np.testing.assert_allclose(r.places[o].cov, 0.0, atol=1e-20, err_msg=o)
    np.testing.assert_allclose(r.places["mp"].estimate_vector, [1, 2, 3])
    assert plan.types["c4"] == "circle"
    assert plan.types["fr"] == "frame"
    pl = r.places
    np.testing.assert_allclose(pl["pl_z"].part("normal").estimate_vector, [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(
        pl["pl_y"].part("normal").estimate_vector, [0, -1, 0], atol=1e-15
    )  # AB x AD
    np.testing.assert_allclose(pl["pl_lsq"].part("normal").estimate_vector, [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(pl["pl_lsq"].part("point").estimate_vector, [5, 5, 0], atol=1e-12)
    np.testing.assert_allclose(pl["pl_pn"].part("point").estimate_vector, [3, 4, 5], atol=1e-15)
    d = pl["ln_pp"].part("direction").estimate_vector
    np.testing.assert_allclose(abs(d[0]), 1.0, atol=1e-15)  # the x axis, either sense
    np.testing.assert_allclose(pl["ln_pp"].part("point").estimate_vector[1:], [0, 0], atol=1e-12)
    # frame (3-2-1): z = plane normal, x = line direction, origin on the line AB (the x
    # axis) level with P = (3, 4, 5): (3, 0, 0)
    rot = pl["fr"].part("rotation").estimate_vector.reshape(3, 3)
    np.testing.assert_allclose(rot, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(pl["fr"].part("translation").estimate_vector, [3, 0, 0], atol=1e-12)


def test_degenerate_construction_names_the_transition():
    text = build().replace(
        'in = ["K1", "K2", "K3"]\nout = "c3"', 'in = ["K1", "K3", "A"]\nout = "c3"'
    )
    # refused on reading, before any trial: the nominal configuration is degenerate
    with pytest.raises(
        DegenerateGeometryError,
        match=r"deg.toml:\d+: field in: transition t32 \(circle\): at the nominal values",
    ):
        loads_graph(text, file="deg.toml")
    g = loads_graph(text, file="deg.toml", validate=False)
    with pytest.raises(
        DegenerateGeometryError, match=r"deg.toml:\d+: .*transition t32 \(circle\): "
    ):
        run_graph(g, 2, seed=1)
