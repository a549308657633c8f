"""``mtmc propagate`` in-process: the JSON equals the library's own result for the same
seed; bad input exits non-zero with a one-line message naming the culprit."""

from __future__ import annotations

import json

import pytest

from mtmc import expression, gum, monte_carlo, parse_distribution, validate
from mtmc.cli.main import main

ARGS = ["propagate", "a * b + c", "-i", "a=normal(2, 0.1)", "-i", "b=uniform(2.5, 3.5)"]
ARGS += ["-i", "c=t(8, 0, 0.05)", "--trials", "50000", "--seed", "17"]


def _run(argv, capsys):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def test_json_equals_library_result(capsys):
    code, out, err = _run([*ARGS, "--json", "--gum"], capsys)
    assert code == 0, err
    assert len(out.strip().splitlines()) == 1
    got = json.loads(out)
    expr = expression("a * b + c")
    inputs = {
        "a": parse_distribution("normal(2, 0.1)"),
        "b": parse_distribution("uniform(2.5, 3.5)"),
        "c": parse_distribution("t(8, 0, 0.05)"),
    }
    mc = monte_carlo(expr, inputs, trials=50_000, seed=17)
    g = gum(expr, inputs)
    v = validate(g, mc)
    assert set(got) == {
        "estimate",
        "u",
        "p",
        "shortest",
        "symmetric",
        "trials",
        "omitted",
        "seed",
        "gum",
        "validation",
    }
    assert got["estimate"] == mc.estimate
    assert got["u"] == mc.u
    assert got["p"] == 0.95
    assert got["shortest"] == list(mc.coverage_interval(0.95, kind="shortest"))
    assert got["symmetric"] == list(mc.coverage_interval(0.95, kind="symmetric"))
    assert got["trials"] == 50_000
    assert got["seed"] == 17
    assert got["omitted"] == mc.omitted == 0
    assert got["gum"] == {
        "estimate": g.estimate,
        "u": g.u,
        "k": g.coverage_factor(),
        "interval": list(g.coverage_interval()),
    }
    assert got["validation"] == {
        "d_low": v.d_low,
        "d_high": v.d_high,
        "delta": v.delta,
        "passed": v.passed,
    }


def test_json_without_gum_has_no_gum_keys_and_p_is_used(capsys):
    code, out, _ = _run([*ARGS, "--json", "-p", "0.9"], capsys)
    assert code == 0
    got = json.loads(out)
    assert "gum" not in got
    assert "validation" not in got
    assert got["p"] == 0.9
    mc = monte_carlo(
        expression("a * b + c"),
        {"a": "normal(2, 0.1)", "b": "uniform(2.5, 3.5)", "c": "t(8, 0, 0.05)"},
        trials=50_000,
        seed=17,
    )
    assert got["shortest"] == list(mc.coverage_interval(0.9, kind="shortest"))


def test_seed_none_is_recorded_and_reproduces(capsys):
    code, out, _ = _run(
        ["propagate", "x", "-i", "x=normal(0, 1)", "--trials", "1000", "--json"], capsys
    )
    assert code == 0
    first = json.loads(out)
    assert isinstance(first["seed"], int)
    argv = ["propagate", "x", "-i", "x=normal(0, 1)", "--trials", "1000", "--json"]
    code, out, _ = _run([*argv, "--seed", str(first["seed"])], capsys)
    assert json.loads(out) == first


def test_adaptive_run(capsys):
    code, out, _ = _run(
        [
            "propagate",
            "x + y",
            "-i",
            "x=normal(0, 1)",
            "-i",
            "y=normal(0, 1)",
            "--adaptive",
            "--seed",
            "5",
            "--json",
        ],
        capsys,
    )
    assert code == 0
    got = json.loads(out)
    mc = monte_carlo(
        expression("x + y"), {"x": "normal(0, 1)", "y": "normal(0, 1)"}, seed=5, adaptive=True
    )
    assert got["trials"] == mc.trials
    assert got["u"] == mc.u


def test_table_output(capsys):
    code, out, _ = _run([*ARGS, "--gum"], capsys)
    assert code == 0
    mc = monte_carlo(
        expression("a * b + c"),
        {"a": "normal(2, 0.1)", "b": "uniform(2.5, 3.5)", "c": "t(8, 0, 0.05)"},
        trials=50_000,
        seed=17,
    )
    assert "Monte Carlo (JCGM 101): a * b + c" in out
    assert f"{mc.estimate:.6g}" in out
    assert f"{mc.u:.6g}" in out
    assert "GUM validated" in out
    assert "50000" in out
    assert "17" in out


@pytest.mark.parametrize(
    ("argv", "fragments"),
    [
        (["propagate", "a * b", "-i", "a=normal(0, 1)"], ["variable(s) b", "no -i"]),
        (
            ["propagate", "a", "-i", "a=normal(0, 1)", "-i", "zz=normal(0, 1)"],
            ["input(s) zz not in the expression"],
        ),
        (["propagate", "a.real", "-i", "a=normal(0, 1)"], ["attribute access", "column 1"]),
        (["propagate", "a +", "-i", "a=normal(0, 1)"], ["syntax error"]),
        (["propagate", "a", "-i", "a=normel(0, 1)"], ["field -i a", "unknown distribution"]),
        (["propagate", "a", "-i", "a=normal(0)"], ["field -i a"]),
        # an option names itself, not a "line 1" of no file; the column stays
        (
            ["propagate", "a", "-i", "a=normal(0,,1)"],
            ["error: field -i a: expected a number", "'normal(0,,1)' (column 10)"],
        ),
        (["propagate", "a", "-i", "a"], ["expected NAME=DISTRIBUTION"]),
        (["propagate", "a", "-i", "a=normal(0,1)", "-i", "a=normal(0,1)"], ["more than once"]),
        (["propagate", "a", "-i", "a=normal(0, 1)", "-p", "1.5"], ["0 < p < 1"]),
        (["propagate", "a", "-i", "a=normal(0, 1)", "--trials", "1"], ["trials"]),
    ],
)
def test_errors_exit_non_zero_with_one_line(argv, fragments, capsys):
    code, out, err = _run(argv, capsys)
    assert code != 0
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("mtmc: error: ")
    for fragment in fragments:
        assert fragment in lines[0]


@pytest.mark.parametrize("adaptive", [False, True])
def test_progress_bar_on_stderr_only(adaptive, capsys):
    argv = [*ARGS, "--json"] + (["--adaptive"] if adaptive else [])
    code, quiet, quiet_err = _run(argv, capsys)
    assert code == 0
    assert quiet_err == ""
    code, loud, loud_err = _run([*argv, "--progress"], capsys)
    assert code == 0
    assert loud == quiet
    n = json.loads(loud)["trials"]
    assert f"{n}/{n} trials" in loud_err
    assert loud_err.count("\n") == 1
