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
        "unit",
        "estimate",
        "U",
        "k",
        "u",
        "p",
        "interval_kind",
        "shortest",
        "symmetric",
        "reported",
        "trials",
        "omitted",
        "seed",
        "run",
        "output",
        "gum",
        "validation",
    }
    assert got["unit"] == "1"
    assert got["interval_kind"] == "symmetric"
    lo, hi = mc.coverage_interval(0.95, kind="symmetric")
    assert got["U"] == 0.5 * (hi - lo)  # the same two floats, the same operation
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
        "U": g.coverage_factor() * g.u,
        "k": g.coverage_factor(),
        "u": g.u,
        "interval": list(g.coverage_interval()),
    }
    assert got["validation"] == {
        "d_low": v.d_low,
        "d_high": v.d_high,
        "delta": v.delta,
        "passed": v.passed,
        "verdict": got["validation"]["verdict"],
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
    ("argv", "fragment"),
    [
        # a = normal(10, 1) to the 200th power: finite values whose variance overflows
        (["propagate", "a**200", "-i", "a=normal(10,1)", "-n", "1000"], "error: field EXPR: "),
        # a 95 % interval takes q = round(pM) of M values with q <= M - 1: M >= 11
        (["propagate", "a", "-i", "a=normal(0, 1)", "--trials", "2"], "at least 11 trials"),
        (["propagate", "a", "-i", "a=normal(0, 1)", "-n", "10"], "--trials: expected at least 11"),
        (["propagate", "a", "-i", "a=normal(0, 1)", "-n", "50", "-p", "0.99"], "at least 51"),
    ],
)
def test_hostile_numbers_are_input_errors(argv, fragment, capsys):
    code, out, err = _run(argv, capsys)
    assert code == 2
    assert out == ""
    assert err.count("\n") == 1
    assert fragment in err


def test_the_fewest_trials_run(capsys):
    code, out, err = _run(["propagate", "a", "-i", "a=normal(0, 1)", "-n", "11", "--json"], capsys)
    assert code == 0, err
    assert json.loads(out)["trials"] == 11


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
    argv = [*ARGS, "--json"]
    if adaptive:  # --adaptive chooses the trials: not with --trials
        argv = [a for a in argv if a not in ("--trials", "50000")] + ["--adaptive"]
    code, quiet, quiet_err = _run(argv, capsys)
    assert code == 0
    assert quiet_err == ""
    code, loud, loud_err = _run([*argv, "--progress"], capsys)
    assert code == 0
    assert loud == quiet
    n = json.loads(loud)["trials"]
    assert f"{n}/{n} trials" in loud_err
    assert loud_err.count("\n") == 1


def test_adaptive_with_trials_is_refused(capsys):
    """--adaptive chooses the trials itself: -n beside it is refused, not ignored."""
    code, out, err = _run(
        ["propagate", "a", "-i", "a=normal(0,1)", "--adaptive", "-n", "5000"], capsys
    )
    assert code == 2
    assert out == ""
    assert err.strip() == (
        "mtmc: error: --adaptive chooses the number of trials itself (JCGM 101 §7.9); "
        "not with --trials"
    )


def test_output_named_as_its_input_is_refused(capsys):
    """An output named as an input is refused, as a study file's [outputs] is."""
    code, out, err = _run(["propagate", "a = a * 2", "-i", "a=normal(0,1)"], capsys)
    assert code == 2
    assert out == ""
    assert err.strip() == (
        "mtmc: error: field EXPR: output a has the name of an input; expected another name"
    )


@pytest.mark.parametrize(
    "expr", ["a * b + c", "y1 = a * b; y2 = b + c"], ids=["one output", "two outputs"]
)
def test_one_route_the_study_the_folder_and_mtmc_run(expr, tmp_path, capsys):
    """The command builds a propagate study and runs it through the study layer: its JSON,
    the study run by the library and `mtmc run` on the folder's study.toml agree to the bit
    (the same seeded draws and reductions)."""
    from mtmc.study import load_study

    argv = ["propagate", expr, *ARGS[2:], "--json", "-o", str(tmp_path / "a" / "b")]
    code, out, err = _run(argv, capsys)
    assert code == 0, err
    got = json.loads(out)
    folder = tmp_path / "a" / "b"  # created with its parent
    assert got["output"] == str(folder)
    assert (folder / "report.html").is_file()
    written = json.loads((folder / "result.json").read_text())
    library = load_study(folder / "study.toml").run()
    rows = got["outputs"].values() if "outputs" in got else [got]
    assert len(library.quantities) == len(written["quantities"]) == len(rows)
    for row, q, w in zip(rows, library.quantities, written["quantities"], strict=True):
        assert (row["estimate"], row["u"], row["U"]) == (q.mc.estimate, q.mc.u, q.mc.U)
        assert (w["monte_carlo"]["estimate"], w["monte_carlo"]["u"]) == (q.mc.estimate, q.mc.u)
        assert row["symmetric"] == list(q.mc.symmetric)
    assert library.seed == got["seed"] == 17
    code, out, err = _run(
        ["run", str(folder / "study.toml"), "-o", str(tmp_path / "r"), "--json"], capsys
    )
    assert code == 0, err
    again = json.loads(out)["quantities"]
    assert [(q["estimate"], q["u"]) for q in again] == [(r["estimate"], r["u"]) for r in rows]


def test_quiet_prints_trials_and_seed_only(capsys):
    code, out, err = _run([*ARGS, "-q"], capsys)
    assert code == 0, err
    assert out == "trials 50000  seed 17\n"
    assert err == ""
