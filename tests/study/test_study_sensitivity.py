"""The ``[sensitivity]`` table of a propagate study: read with file, line and field in its
errors; run into ``result.json`` with the same numbers as the engine's functions; shown
in the report beside the GUM budget, with the sentence that says where the two differ."""

from __future__ import annotations

from pathlib import Path

import pytest

from mtmc.errors import MtmcError
from mtmc.report import html
from mtmc.study import load_study, loads_study
from mtmc.uncertainty import gum, monte_carlo_budget, sobol_indices

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "examples" / "studies"

LINEAR = """\
kind = "propagate"
title = "linear"
model = "2 * a - b"
output = "y"
unit = "mm"

[inputs]
a = "normal(1, 0.1)"
b = "uniform(-0.2, 0.2)"

[run]
trials = 1000
seed = 3

[sensitivity]
trials = 32768
sampling = "random"
"""


@pytest.fixture(scope="module")
def mass():
    study = load_study(STUDIES / "mass_calibration.toml")
    return study, study.run(trials=2000, seed=5)


def test_the_record_is_the_engine_functions_bit_for_bit(mass):
    study, result = mass
    rec = result.to_dict()["sensitivity"]
    assert rec["trials"] == study.sensitivity.trials == 131072
    assert rec["sampling"] == "sobol"
    # a second route to the same numbers: the engine's functions with the run's seed
    s = sobol_indices(study.model, study.inputs, trials=131072, seed=5)
    g = gum(study.model, study.inputs)
    b = monte_carlo_budget(
        study.model, study.inputs, trials=131072, seed=5, gum=g, sampling="sobol"
    )
    assert [x["first"] for x in rec["sobol"]["indices"]] == [e.first for e in s.entries]
    assert [x["total_se"] for x in rec["sobol"]["indices"]] == [e.total_se for e in s.entries]
    assert [x["u"] for x in rec["budget"]] == [e.u for e in b.entries]
    assert rec["sobol"]["first_sum"] == s.first_sum
    assert rec["u_gum"] == g.u
    assert rec["u_mc"] == result.quantities[0].mc.u


def test_the_mass_calibration_shows_its_second_order_term(mass):
    # JCGM 101 §9.3: u = 0.054 mg by the GUM, 0.075 mg by Monte Carlo; the difference is
    # the interaction of ρ_a and ρ_w (Σ S_i = 0.51, closed form in
    # tests/uncertainty/test_sensitivity.py), while each input alone acts linearly
    _, result = mass
    rec = result.to_dict()["sensitivity"]
    assert rec["interacting"] == ["rho_a", "rho_w"]
    assert rec["nonlinear"] == []
    assert rec["sobol"]["additive"] is False
    assert 0.50 < rec["sobol"]["first_sum"] < 0.52
    page = html(result.to_dict())
    assert "comes from interactions of <code>rho_a</code> and <code>rho_w</code>" in page
    assert "0.075 mg by Monte Carlo against 0.054 mg by the GUM" in page
    assert "each input varied alone acts linearly" in page


def test_a_linear_study_agrees_and_says_so():
    result = loads_study(LINEAR).run()
    rec = result.to_dict()["sensitivity"]
    assert rec["nonlinear"] == []
    assert rec["interacting"] == []
    assert rec["sobol"]["additive"] is True
    assert rec["batches"] == 2
    page = html(result.to_dict())
    assert "The Monte Carlo budget agrees with the GUM's" in page


def test_a_curved_model_is_named_not_linear():
    # Y = X², X ~ N(0.5, 1): alone, u = sqrt(4μ²σ² + 2σ⁴) = 1.73 against the GUM's |2μ|σ = 1
    # with 8 seed blocks (2 could not tell: agreement_factor(2) = 254 standard errors)
    text = LINEAR.replace('"2 * a - b"', '"a ** 2 + b"').replace("normal(1, 0.1)", "normal(0.5, 1)")
    text = text.replace("trials = 32768", "trials = 131072")
    rec = loads_study(text).run().to_dict()
    assert rec["sensitivity"]["nonlinear"] == ["a"]
    page = html(rec)
    assert "for <code>a</code>: the model is not linear in this input over its PDF" in page
    assert '<a href="#sensitivity">' in page


def test_a_study_without_the_table_has_no_record():
    text = LINEAR.split("[sensitivity]")[0]
    study = loads_study(text)
    assert study.sensitivity is None
    assert "sensitivity" not in study.run().to_dict()
    assert 'id="sensitivity"' not in html(study.run().to_dict())


@pytest.mark.parametrize(
    ("old", "new", "line", "field", "words"),
    [
        ("trials = 32768\n", "trials = 40000\n", 16, "sensitivity.trials", "multiple of 16384"),
        ("trials = 32768\n", "trials = 16384\n", 16, "sensitivity.trials", ">= 32768"),
        ("trials = 32768\n", "trials = 2.5\n", 16, "sensitivity.trials", "expected an integer"),
        ('sampling = "random"', 'sampling = "lhs"', 17, "sensitivity.sampling", "'sobol'"),
        ('sampling = "random"', "sampling = 1\nseed = 4", 18, "sensitivity.seed", "unknown key"),
    ],
)
def test_errors_name_file_line_and_field(old, new, line, field, words):
    with pytest.raises(MtmcError) as exc:
        loads_study(LINEAR.replace(old, new), file="s.toml")
    e = exc.value
    assert (e.file, e.line, e.field) == ("s.toml", line, field), e
    assert words in e.message


def test_a_sensitivity_that_is_not_a_table_is_named():
    text = LINEAR.split("[sensitivity]")[0].replace(
        'unit = "mm"\n', 'unit = "mm"\nsensitivity = 3\n'
    )
    with pytest.raises(MtmcError) as exc:
        loads_study(text, file="s.toml")
    assert (exc.value.line, exc.value.field) == (6, "sensitivity")
    assert "expected a table" in exc.value.message


def test_sensitivity_with_correlated_inputs_is_refused():
    # the Sobol decomposition of V(Y) into shares of single inputs needs independent inputs
    text = LINEAR + '\n[correlation]\npairs = [["a", "b", 0.5]]\n'
    with pytest.raises(MtmcError) as exc:
        loads_study(text, file="s.toml")
    assert (exc.value.line, exc.value.field) == (15, "sensitivity")
    assert "independent inputs" in exc.value.message
