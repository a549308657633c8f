"""``mtmc propagate --sensitivity``: the JSON holds the library's Monte Carlo budget and
Sobol indices for the same seed; the text prints their table; a bad N is named."""

from __future__ import annotations

import json

from mtmc import expression, gum, parse_distribution
from mtmc.cli.main import main
from mtmc.uncertainty import monte_carlo_budget, sobol_indices

ARGS = ["propagate", "a * b + c", "-i", "a=normal(2, 0.1)", "-i", "b=uniform(2.5, 3.5)"]
ARGS += ["-i", "c=t(8, 0, 0.05)", "--trials", "20000", "--seed", "17", "--sensitivity"]
ARGS += ["--sensitivity-trials", "32768"]


def test_json_holds_the_library_budget_and_indices(capsys):
    assert main([*ARGS, "--json"]) == 0
    got = json.loads(capsys.readouterr().out)["sensitivity"]
    model = expression("a * b + c")
    inputs = {
        "a": parse_distribution("normal(2, 0.1)"),
        "b": parse_distribution("uniform(2.5, 3.5)"),
        "c": parse_distribution("t(8, 0, 0.05)"),
    }
    s = sobol_indices(model, inputs, trials=32768, seed=17)
    b = monte_carlo_budget(
        model, inputs, trials=32768, seed=17, gum=gum(model, inputs), sampling="sobol"
    )
    # the same seed and N: the same bits
    assert [x["first"] for x in got["sobol"]["indices"]] == [e.first for e in s.entries]
    assert [x["total"] for x in got["sobol"]["indices"]] == [e.total for e in s.entries]
    assert [x["u"] for x in got["budget"]] == [e.u for e in b.entries]
    # c enters linearly; its t PDF has the standard deviation 0.05 · sqrt(8/6), which the
    # budget compares with, not the GUM's u = s/√n = 0.05 (JCGM 101 §6.4.9)
    line = got["budget"][2]
    assert line["gum_contribution"] == 0.05
    assert abs(line["linear_reference"] - 0.05 * (8 / 6) ** 0.5) < 1e-15
    assert got["nonlinear"] == []


def test_text_prints_the_table(capsys):
    assert main(ARGS) == 0
    out = capsys.readouterr().out
    assert "Sobol indices" in out
    assert "S_Ti" in out
    for name in ("a", "b", "c", "sum"):
        assert f"│ {name} " in out


def test_bad_trials_are_named(capsys):
    argv = [a if a != "32768" else "40000" for a in ARGS]
    assert main(argv) != 0
    err = capsys.readouterr().err
    assert "--sensitivity-trials" in err
    assert "multiple of 16384" in err
