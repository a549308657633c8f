"""Broken study files: one line naming file, line and field; nothing runs, nothing is written."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from mtmc.cli.main import main
from mtmc.errors import MtmcError
from mtmc.study import load_study, loads_study, study_kinds

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "examples" / "studies"

GOOD_PROPAGATE = """\
kind = "propagate"
title = "sum"
model = "a + b"
output = "y"
unit = "mm"

[inputs]
a = "normal(1, 0.1)"
b = 2.0

[run]
trials = 1000
seed = 3
"""

# (replace this, with this, expected line, expected field, words in the message)
CASES = [
    (
        'kind = "propagate"',
        'kind = "spline"',
        1,
        "kind",
        "expected one of artefact, circular, graph, kinematics, positioning, propagate",
    ),
    ('kind = "propagate"', "kind = 3", 1, "kind", "expected a string"),
    ('kind = "propagate"\n', "", None, "kind", "missing kind"),
    ('model = "a + b"', 'model = "a + "', 3, "model", ""),
    ('model = "a + b"', 'model = "a + c"', 3, "model", "c have no input"),
    ('a = "normal(1, 0.1)"', 'a = "normal(1, -0.1)"', 8, "inputs.a", ">= 0"),
    ('a = "normal(1, 0.1)"', 'a = "normal(nan, 0.1)"', 8, "inputs.a", ""),
    ("b = 2.0", "b = nan", 9, "inputs.b", "finite"),
    ("b = 2.0", "b = [1, 2]", 9, "inputs.b", "expected a distribution text or a number"),
    ("b = 2.0", "b = 2.0\nc = 1.0", 10, "inputs.c", "not a variable of the model"),
    ("trials = 1000", 'trials = "many"', 12, "run.trials", "expected an integer"),
    ("trials = 1000", "trials = 1", 12, "run.trials", ">= 2"),
    ("trials = 1000", "trials = 1e4", 12, "run.trials", "expected an integer"),
    # a 95 % interval takes q = round(pM) of M sorted values with q <= M - 1: M >= 11
    ("trials = 1000", "trials = 2", 12, "run.trials", "expected at least 11 trials"),
    ("trials = 1000", "trials = 10", 12, "run.trials", "expected at least 11 trials"),
    ("trials = 1000", "trials = 50\np = 0.99", 12, "run.trials", "expected at least 51"),
    ("seed = 3", "seed = -1", 13, "run.seed", ">= 0"),
    ("seed = 3", "seed = 3\np = nan", 14, "run.p", "finite"),
    ("seed = 3", "seed = 3\np = 1.5", 14, "run.p", "in (0, 1)"),
    ("seed = 3", 'seed = 3\ninterval = "widest"', 14, "run.interval", "'shortest'"),
    ("seed = 3", "seed = 3\ncolour = 1", 14, "run.colour", "unknown key"),
    ('title = "sum"', 'title = "sum"\nauthor = "x"', 3, "author", "unknown key"),
    ('[inputs]\na = "normal(1, 0.1)"\nb = 2.0', "inputs = 3", 7, "inputs", "expected a table"),
    ('unit = "mm"', "unit = 1", 5, "unit", "expected a string"),
]


@pytest.mark.parametrize(("old", "new", "line", "field", "words"), CASES)
def test_broken_propagate_file_names_file_line_and_field(old, new, line, field, words):
    text = GOOD_PROPAGATE.replace(old, new, 1)
    assert text != GOOD_PROPAGATE
    with pytest.raises(MtmcError) as info:
        loads_study(text, file="broken.toml")
    err = info.value
    assert err.file == "broken.toml"
    assert err.line == line
    assert err.field == field
    assert words in err.message
    assert "\n" not in str(err)


def test_the_good_file_loads_and_runs():
    r = loads_study(GOOD_PROPAGATE, file="good.toml").run()
    assert r.quantity("y").mc.estimate == pytest.approx(3.0, abs=0.02)


GOOD_GRAPH = """\
kind = "graph"
graph = "{graph}"
outputs = ["d_ac"]

[run]
trials = 500

[sweep]
output = "d_ac"

[sweep.vary]
"probe.u_probe" = "0.001:0.002:2"
"""

GRAPH_CASES = [
    ('outputs = ["d_ac"]', 'outputs = ["nowhere"]', 3, "outputs", "has no place 'nowhere'"),
    ('outputs = ["d_ac"]', 'outputs = "d_ac"', 3, "outputs", "array of strings"),
    ('outputs = ["d_ac"]', "", None, "outputs", "missing outputs"),
    ('graph = "{graph}"', 'graph = "missing.toml"', 2, "graph", "expected an existing file"),
    ('output = "d_ac"', 'output = "p_o"', 9, "sweep.output", "scalar place"),
    ('"probe.u_probe"', '"probe.u_nothing"', 12, "sweep.vary.probe.u_nothing", "u_axis"),
    ('"0.001:0.002:2"', '"0.001:0.002"', 12, "sweep.vary.probe.u_probe", "LOW:HIGH:N"),
    ('"0.001:0.002:2"', "[0.001, -0.002]", 12, "sweep.vary.probe.u_probe", ">= 0"),
    ('"0.001:0.002:2"', "[0.001, nan]", 12, "sweep.vary.probe.u_probe", "finite"),
]


@pytest.mark.parametrize(("old", "new", "line", "field", "words"), GRAPH_CASES)
def test_broken_graph_file_names_file_line_and_field(old, new, line, field, words):
    graph = (ROOT / "examples" / "graphs" / "bcs_origin.toml").as_posix()
    good = GOOD_GRAPH.replace("{graph}", graph)
    text = good.replace(old.replace("{graph}", graph), new, 1)
    assert text != good
    with pytest.raises(MtmcError) as info:
        loads_study(text, file="g.toml", folder=ROOT)
    err = info.value
    assert (err.file, err.line, err.field) == ("g.toml", line, field)
    assert words in err.message


BAD_VALUES = ['"junk"', "nan", "-1", "-1.5", "[]", "{}", "true", "1e400", '["a", 1]']


def _fuzzed(text: str):
    """Every key line of a valid study with its value replaced by each bad value."""
    lines = text.splitlines()
    for i, raw in enumerate(lines):
        m = re.match(r'^(\s*[A-Za-z_"][A-Za-z0-9_."]*\s*=\s*)(.*)$', raw)
        if not m:
            continue
        for bad in BAD_VALUES:
            yield i + 1, "\n".join([*lines[:i], m.group(1) + bad, *lines[i + 1 :]]) + "\n"


@pytest.mark.parametrize("name", ["mass_calibration", "bcs_origin"])
def test_fuzzed_shipped_studies_fail_on_the_line_changed(name):
    path = STUDIES / f"{name}.toml"
    text = path.read_text(encoding="utf-8")
    errors: list[tuple[int, MtmcError]] = []
    for line, broken in _fuzzed(text):
        try:
            study = loads_study(broken, file=path.name, folder=path.parent)
        except MtmcError as exc:
            errors.append((line, exc))
        else:  # still valid (a title of "junk"): it must then run
            assert study.title
    assert len(errors) > 40
    for line, exc in errors:
        assert exc.file == path.name, (line, exc)
        assert exc.line == line, (exc, line)
        assert exc.field, exc
        assert "\n" not in str(exc)


def test_unknown_kind_lists_the_known_ones():
    with pytest.raises(MtmcError, match="expected one of " + ", ".join(study_kinds())):
        loads_study('kind = "nope"\n', file="k.toml")


def test_not_toml_gives_line_and_column():
    with pytest.raises(MtmcError) as info:
        loads_study('kind = "graph"\nx = = 3\n', file="t.toml")
    assert (info.value.file, info.value.line) == ("t.toml", 2)


def test_the_fewest_trials_of_a_coverage_interval_run():
    # q = round(0.95 M) <= M - 1 first holds at M = 11 (q = 10), at M = 51 for p = 0.99
    for p, least in ((0.95, 11), (0.99, 51)):
        text = GOOD_PROPAGATE.replace("trials = 1000", f"trials = {least}\np = {p}")
        r = loads_study(text, file="good.toml").run()
        assert r.trials == least
        lo, hi = r.quantities[0].mc.coverage_interval
        assert lo < hi


# a = normal(10, 1) reaches 10**200 and beyond: every value is finite, their variance is not
OVERFLOW = GOOD_PROPAGATE.replace('model = "a + b"', 'model = "a**200 + b"').replace(
    'a = "normal(1, 0.1)"', 'a = "normal(10, 1)"'
)


@pytest.mark.parametrize(
    ("power", "words"),
    [
        (200, "finite in every trial but its standard uncertainty overflows float64"),
        (400, "not finite (NaN or inf) in 1000 of 1000 trials"),
    ],
)
def test_a_model_that_overflows_is_one_error_at_its_line(power, words):
    assert math.isfinite(10.0**200)
    assert math.isinf(10.0**200 * 10.0**200)  # its square: a variance overflows
    text = OVERFLOW.replace("a**200", f"a**{power}")
    with pytest.raises(MtmcError) as info:
        loads_study(text, file="big.toml").run()
    err = info.value
    assert (err.file, err.line, err.field) == ("big.toml", 3, "model")
    assert words in err.message


def test_cli_names_the_model_line_of_a_study_that_overflows(tmp_path, capsys):
    study = tmp_path / "big.toml"
    study.write_text(OVERFLOW, encoding="utf-8")
    out = tmp_path / "out"
    assert main(["run", str(study), "-o", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith(f"mtmc: error: {study}:3: field model: ")
    assert not out.exists()


@pytest.mark.parametrize(("old", "new"), [(c[0], c[1]) for c in CASES[:8]])
def test_cli_prints_one_line_and_leaves_no_folder(tmp_path, capsys, old, new):
    study = tmp_path / "broken.toml"
    study.write_text(GOOD_PROPAGATE.replace(old, new, 1), encoding="utf-8")
    out = tmp_path / "out"
    assert main(["run", str(study), "-o", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith(f"mtmc: error: {study}:")
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["broken.toml"]


def test_missing_file(tmp_path):
    with pytest.raises(MtmcError, match="cannot read the study file"):
        load_study(tmp_path / "none.toml")


KIN = """\
kind = "kinematics"
machine = "table-table"
poses = [[0.0, 0.0, 0.0, -30.0, 0.0]]

[errors]
EX0C = "normal(0, 0.003)"
"""

KIN_CASES = [
    ('machine = "table-table"', 'machine = "lathe"', 2, "machine", "table-table"),
    ("-30.0, 0.0]]", "-30.0]]", 3, "poses", "expected 5 numbers (X, Y, Z, A, C)"),
    ("-30.0, 0.0]]", "-30.0, nan]]", 3, "poses", "pose 1: expected a finite number"),
    ("poses = [[0.0, 0.0, 0.0, -30.0, 0.0]]", "poses = []", 3, "poses", "array of poses"),
    ('EX0C = "normal(0, 0.003)"', 'EQ9Z = "normal(0, 0.003)"', 6, "errors.EQ9Z", "EX0C"),
    ('EX0C = "normal(0, 0.003)"', 'EX0C = "normal(0, -0.003)"', 6, "errors.EX0C", ">= 0"),
    ('machine = "table-table"', 'machine = "table-table"\nangles = "grad"', 3, "angles", "deg"),
]


@pytest.mark.parametrize(("old", "new", "line", "field", "words"), KIN_CASES)
def test_broken_kinematics_file_names_file_line_and_field(old, new, line, field, words):
    text = KIN.replace(old, new, 1)
    assert text != KIN
    with pytest.raises(MtmcError) as info:
        loads_study(text, file="k.toml")
    err = info.value
    assert (err.file, err.line, err.field) == ("k.toml", line, field)
    assert words in err.message
