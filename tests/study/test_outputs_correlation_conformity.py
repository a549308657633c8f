"""``[correlation]`` and ``[conformity]`` beside ``[outputs]``: a gauge-block pair, two lengths.

Two gauge blocks ``a`` and ``b`` calibrated against one reference are correlated (r); the
pair wrung together gives ``L1 = a + b``, the one compared with the other ``L2 = a − b``.
For normal inputs the closed form is exact in the GUM and in the Monte Carlo:
``u²(L1,2) = u_a² + u_b² ± 2 r u_a u_b`` and ``cov(L1, L2) = u_a² − u_b²`` (JCGM 100 eq.
(13), JCGM 102 §6.2.1.3), and the probability of conformity of a normal output is
``Φ((T_U − y)/u) − Φ((T_L − y)/u)`` (JCGM 106 §7.2).
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from scipy.stats import norm

from mtmc.errors import InputError
from mtmc.study import load_result, loads_study, write_result

A, UA = 100.0002, 0.0003
B, UB = 50.0001, 0.0002
R = 0.6
M = 100_000
STUDY = f"""# a gauge-block pair
kind = "propagate"
title = "Two gauge blocks: wrung and compared"
unit = "mm"

[outputs]
L1 = "a + b"
L2 = "a - b"

[inputs]
a = "normal({A}, {UA})"
b = "normal({B}, {UB})"

[correlation]
pairs = [["a", "b", {R}]]

[conformity.L1]
lower = 149.9995
upper = 150.0009

[conformity.L2]  # one limit
upper = 50.0003

[run]
trials = {M}
seed = 11
"""
LIMITS = {"L1": (149.9995, 150.0009), "L2": (-math.inf, 50.0003)}


@pytest.fixture(scope="module")
def pair():
    return loads_study(STUDY, file="pair.toml").run(samples=True)


def _closed_form() -> tuple[np.ndarray, np.ndarray]:
    y = np.array([A + B, A - B])
    cross = 2 * R * UA * UB
    cov = np.array([[UA**2 + UB**2 + cross, UA**2 - UB**2], [UA**2 - UB**2, UA**2 + UB**2 - cross]])
    return y, cov


def test_the_gum_of_the_two_lengths_is_the_closed_form(pair):
    y, cov = _closed_form()
    g = pair.extra["joint"]["gum"]
    # complex-step sensitivities of a linear model are exact; the rest is a few roundings
    assert np.allclose(g["estimate"], y, rtol=1e-15, atol=0)
    assert np.allclose(g["cov"], cov, rtol=1e-12, atol=0)
    for i, name in enumerate(("L1", "L2")):
        assert pair.quantity(name).gum.u == pytest.approx(math.sqrt(cov[i, i]), rel=1e-12)
    # the part of each u² that the cross term 2 r c_a c_b u_a u_b gives: +, then −
    by = {o["name"]: o for o in pair.extra["correlation"]["outputs"]}
    assert by["L1"]["gum_cross_variance"] == pytest.approx(2 * R * UA * UB, rel=1e-12)
    assert by["L2"]["gum_cross_variance"] == pytest.approx(-2 * R * UA * UB, rel=1e-12)
    assert by["L1"]["gum_cross_share"] == pytest.approx(2 * R * UA * UB / cov[0, 0], rel=1e-12)
    assert pair.extra["correlation"]["gum_cross_variance"] is None  # one per output instead


def test_the_monte_carlo_of_the_two_lengths_against_the_closed_form(pair):
    y, cov = _closed_form()
    mc = pair.extra["joint"]["monte_carlo"]
    # the Monte Carlo's noise: 4 standard errors of a mean, a standard deviation
    # (u/√(2M)) and a covariance (√((σ1²σ2² + c²)/M)) of M normal draws
    se_y = np.sqrt(np.diag(cov) / M)
    assert np.all(np.abs(np.array(mc["estimate"]) - y) < 4 * se_y)
    for i, name in enumerate(("L1", "L2")):
        u = math.sqrt(cov[i, i])
        assert pair.quantity(name).mc.u == pytest.approx(u, abs=4 * u / math.sqrt(2 * M))
    se_c = math.sqrt((cov[0, 0] * cov[1, 1] + cov[0, 1] ** 2) / M)
    assert abs(mc["cov"][0][1] - cov[0, 1]) < 4 * se_c
    # the correlation of the inputs is that of the copula (r realised within 4 se of r)
    realised = pair.extra["correlation"]["pairs"][0]["realised"]
    assert realised == pytest.approx(R, abs=4 * (1 - R**2) / math.sqrt(M))


def test_conformity_per_output_against_the_normal_cdf(pair):
    for name, (lo, hi) in LIMITS.items():
        q = pair.quantity(name)
        c = q.conformity
        assert c is not None
        assert (c["lower"], c["upper"]) == (None if lo == -math.inf else lo, hi)
        # the GUM's p_c of the normal output: the closed form at its y and u
        y, u = q.gum.estimate, q.gum.u
        exact = norm.cdf((hi - y) / u) - norm.cdf((lo - y) / u)
        assert c["gum_p_c"] == pytest.approx(exact, rel=1e-12)
        # the Monte Carlo's p_c: the fraction of the trials, within 4 binomial errors
        assert abs(c["p_c"] - exact) < 4 * math.sqrt(exact * (1 - exact) / M)
        assert c["p_c_error"] == pytest.approx(math.sqrt(c["p_c"] * (1 - c["p_c"]) / M))
        assert c["p_c"] == np.mean((pair.samples[name] >= lo) & (pair.samples[name] <= hi))


def test_each_output_is_the_study_of_it_alone_bit_for_bit(pair):
    one = STUDY.split("[outputs]")[0] + (
        'model = "a + b"\noutput = "L1"\n\n[inputs]' + STUDY.split("[inputs]")[1]
    )
    one = one.replace("[conformity.L1]", "[conformity]")
    one = one.split("[conformity.L2]")[0] + "[run]" + one.split("[run]")[1]
    alone = loads_study(one, file="one.toml").run(samples=True)
    assert np.array_equal(alone.samples["L1"], pair.samples["L1"])
    q, q1 = pair.quantity("L1"), alone.quantity("L1")
    assert (q.mc, q.conformity) == (q1.mc, q1.conformity)
    assert alone.extra["correlation"]["pairs"] == pair.extra["correlation"]["pairs"]


def test_the_result_folder_and_its_report_per_output(pair, tmp_path):
    out = write_result(pair, tmp_path / "pair", study_text=STUDY)
    back = load_result(out)
    for name in ("L1", "L2"):
        assert back.quantity(name).conformity == pair.quantity(name).conformity
    assert back.extra["correlation"] == json.loads(json.dumps(pair.extra["correlation"]))
    page = (out / "report.html").read_text(encoding="utf-8")
    assert len(re.findall(r'class="statement conformity"', page)) == 2
    assert "Tolerance interval [149.9995, 150.0009] mm" in page
    assert "Tolerance interval [—, 50.0003] mm" in page
    for k in range(2):
        assert f'data-key="correlation.outputs[{k}].gum_cross_variance"' in page


def _error(text: str) -> InputError:
    with pytest.raises(InputError) as info:
        loads_study(text, file="pair.toml")
    return info.value


def test_unknown_names_are_refused_as_in_a_study_of_one_output():
    # an input that is not one: the message of a study of one output, at its line
    bad = STUDY.replace('pairs = [["a", "b"', 'pairs = [["a", "c"')
    two = _error(bad)
    one_text = (
        'kind = "propagate"\nmodel = "a + b"\n\n\n\n\n\n\n[inputs]\n'
        + bad.split("[inputs]\n")[1].split("[conformity.L1]")[0]
    )
    one = _error(one_text)
    assert (
        (two.message, two.field)
        == (one.message, one.field)
        == (one.message, "correlation.pairs[0]")
    )
    assert two.line == bad.splitlines().index('pairs = [["a", "c", 0.6]]') + 1
    # an output that is not one
    e = _error(STUDY.replace("[conformity.L2]", "[conformity.L3]"))
    assert (e.field, e.message) == ("conformity.L3", "unknown output 'L3'; expected one of L1, L2")
    assert e.line == STUDY.splitlines().index("[conformity.L2]  # one limit") + 1
    # the limits of one output given for all
    e = _error(STUDY.replace("[conformity.L1]\n", "[conformity]\n").split("[conformity.L2]")[0])
    assert e.field == "conformity.lower"
    assert "a table of limits per output: [conformity.L1] lower = ..." in e.message
    # an output's table is read as the table of a study of one output, named by its path
    e = _error(STUDY.replace("upper = 150.0009", "upper = 149.9"))
    assert (e.field, e.message) == (
        "conformity.L1.upper",
        "expected upper > lower = 149.9995, got 149.9",
    )
    e = _error(STUDY.replace("upper = 50.0003", 'upper = 50.0003\nrule = "simple"\nguard = 0.5'))
    assert e.field == "conformity.L2.guard"
    e = _error(STUDY.replace("[conformity.L2]  # one limit\nupper = 50.0003", "[conformity.L2]"))
    assert e.field == "conformity.L2"
    assert "expected a tolerance limit" in e.message


def test_a_conformity_table_without_an_output_table_is_refused():
    head = STUDY.split("[conformity.L1]")[0]
    e = _error(head + "[conformity]\n\n[run]\ntrials = 20\n")
    assert e.field == "conformity"
    assert "a table of limits per output, e.g. [conformity.L1]" in e.message
    e = _error(head + "[conformity]\nL1 = 3\n")
    assert (e.field, e.message) == (
        "conformity.L1",
        "expected a table of limits for output L1, e.g. L1 = { upper = 1.0 }",
    )
