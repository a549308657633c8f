"""Every kind records its inputs one way: the u the GUM takes, ν, and the PDF's own sd.

A t input (JCGM 101 §6.4.9) of scale s and ν degrees of freedom: the GUM takes u = s with
ν (JCGM 100 §4.2), the Monte Carlo draws a PDF of standard deviation s·√(ν/(ν − 2)). The
input table of a kinematics or graph study says what a propagate study says.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from mtmc.study import loads_study

STUDIES = Path(__file__).resolve().parents[2] / "examples" / "studies"


def test_a_t_error_of_a_kinematics_study_is_recorded_with_its_scale_and_dof():
    text = (STUDIES / "five_axis.toml").read_text(encoding="utf-8")
    old = 'EX0C = "normal(0, 0.003)"'
    assert text.count(old) == 1
    study = loads_study(text.replace(old, 'EX0C = "t(4, 0, 0.003)"'), folder=STUDIES)
    result = study.run(trials=2000, seed=3)
    (x,) = [x for x in result.inputs if x["name"] == "EX0C"]
    assert x["u"] == 0.003
    assert x["dof"] == 4.0
    assert x["sd"] == pytest.approx(0.003 * math.sqrt(2.0), rel=1e-15)
    assert x["unit"] == "mm"
    (b,) = [b for b in result.quantity("pose1.x").budget if b.name == "EX0C"]
    assert b.u == x["u"]  # the budget's u(x) is the recorded u
    (y,) = [x for x in result.inputs if x["name"] == "EY0C"]
    assert (y["u"], y["dof"], "sd" in y) == (0.003, math.inf, False)


def test_a_graph_study_records_its_inputs_as_the_other_kinds():
    study = loads_study((STUDIES / "axis_c.toml").read_text(encoding="utf-8"), folder=STUDIES)
    result = study.run(trials=2000, seed=3)
    assert result.inputs
    for x in result.inputs:
        assert set(x) >= {"name", "distribution", "estimate", "u", "dof"}
        assert x["dof"] == math.inf  # normal inputs: u exactly known
