"""``mtmc propagate --correlate``: the JSON equals the library's result for the same seed
and correlation; bad options exit non-zero with one line naming the option."""

from __future__ import annotations

import json

import pytest

from mtmc import expression, gum, monte_carlo, parse_distribution
from mtmc.cli.main import main

ARGS = ["propagate", "a - b", "-i", "a=normal(10, 0.002)", "-i", "b=uniform(4.99, 5.01)"]
ARGS += ["--trials", "20000", "--seed", "5", "--correlate", "a,b,0.7", "--json", "--gum"]


@pytest.mark.parametrize(("copula", "engine"), [("gaussian", "gaussian"), ("t:4", ("t", 4))])
def test_json_equals_library_result_with_correlation(copula, engine, capsys):
    assert main([*ARGS, "--copula", copula]) == 0
    got = json.loads(capsys.readouterr().out)
    inputs = {
        "a": parse_distribution("normal(10, 0.002)"),
        "b": parse_distribution("uniform(4.99, 5.01)"),
    }
    corr = {("a", "b"): 0.7}
    mc = monte_carlo(expression("a - b"), inputs, 20000, 5, correlation=corr, copula=engine)
    # our own seeded draws and reductions: equal to the bit
    assert got["u"] == mc.u
    assert got["estimate"] == mc.estimate
    assert got["gum"]["u"] == gum(expression("a - b"), inputs, correlation=corr).u
    assert [(x["a"], x["b"], x["r"]) for x in got["correlation"]["pairs"]] == [("a", "b", 0.7)]
    expected = {"kind": "gaussian"} if copula == "gaussian" else {"kind": "t", "dof": 4.0}
    assert got["correlation"]["copula"] == expected


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        (["--correlate", "a,b"], "field --correlate: expected A,B,R"),
        (["--copula", "t"], "field --copula: expected 'gaussian' or 't:DOF'"),
        (["--copula", "t:1e-3"], "field copula.dof: expected 0.1 <= dof < inf"),
        (["--correlate", "a,q,0.5"], "field --correlate: 'q' is not an input"),
        (["--correlate", "a,b,1.5"], "field --correlate: expected a coefficient in [-1, 1]"),
        (["--sensitivity"], "field --correlate: --sensitivity varies each input alone"),
    ],
)
def test_bad_correlation_options_exit_with_one_line(extra, words, capsys):
    assert main([*ARGS, *extra]) != 0
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert words in err
