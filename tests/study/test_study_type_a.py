"""Type A inputs and degrees of freedom in study files: round trip, result.json, report, errors.

References: the values of each input recomputed with NumPy and SciPy from the observations
the file gives (``scipy.stats.sem`` for s/√n), the GUM's ν_eff by the Welch–Satterthwaite
formula written out by hand (JCGM 100 eq. (G.2b)), and the library calls on the same
inputs (the study adds no arithmetic of its own: bit for bit).
"""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from mtmc import expression, gum, monte_carlo, parse_distribution, type_a
from mtmc.cli.main import main
from mtmc.errors import MtmcError
from mtmc.report import html
from mtmc.study import load_study, loads_study, write_result
from mtmc.study.observations import load_csv_column
from mtmc.uncertainty import AutocorrelationWarning

CSV = """\
# comparator readings (nm), taken in this order
run;x;y
1;10.1;5.0
2;10.3;5.2
3;10.2;
4;10.4;5.1
5;10.2;4.9
"""

STUDY = """\
kind = "propagate"
title = "Type A and degrees of freedom"
model = "x + y + p + z + w"
output = "l"
unit = "nm"

[inputs]
x = {data = "readings.csv", column = "x"}
y = {data = "readings.csv"}
p = {data = [215.0, 212.0, 218.0], pooled_s = 13, pooled_dof = 24}
z = {dist = "normal(0, 0.1)", u_rel_u = 0.25}
w = {dist = "uniform(-0.2, 0.2)", dof = 12}

[run]
trials = 20000
seed = 7
"""


@pytest.fixture
def study_dir(tmp_path: Path) -> Path:
    (tmp_path / "readings.csv").write_text(CSV, encoding="utf-8")
    (tmp_path / "s.toml").write_text(STUDY, encoding="utf-8")
    return tmp_path


def test_inputs_read_from_the_file_are_the_library_objects(study_dir):
    study = load_study(study_dir / "s.toml")
    x, y, p = (study.inputs[k] for k in "xyp")  # type: ignore[attr-defined]
    assert x == type_a([10.1, 10.3, 10.2, 10.4, 10.2])
    assert y == type_a([5.0, 5.2, 5.1, 4.9])  # the empty cell is no observation
    assert p == type_a([215.0, 212.0, 218.0], pooled_s=13, pooled_dof=24)
    assert study.inputs["z"] == parse_distribution("normal(0, 0.1, u_rel_u=0.25)")  # type: ignore[attr-defined]
    assert study.inputs["w"] == parse_distribution("uniform(-0.2, 0.2, dof=12)")  # type: ignore[attr-defined]


def test_round_trip_result_json_and_report(study_dir):
    study = load_study(study_dir / "s.toml")
    result = study.run()
    out = study_dir / "out"
    write_result(result, out, study_text=study.source.text)
    doc = json.loads((out / "result.json").read_text(encoding="utf-8"))
    rows = {x["name"]: x for x in doc["inputs"]}
    xs = np.array([10.1, 10.3, 10.2, 10.4, 10.2])
    ta = rows["x"]["type_a"]
    # NumPy/SciPy recomputation: the same sums, to a few units of the last place
    assert ta["n"] == 5
    assert ta["mean"] == pytest.approx(float(xs.mean()), rel=1e-15)
    assert ta["s"] == pytest.approx(float(np.std(xs, ddof=1)), rel=1e-14)
    assert ta["u"] == pytest.approx(float(stats.sem(xs)), rel=1e-14)
    assert rows["x"]["u"] == ta["u"]
    assert (ta["dof"], rows["x"]["dof"]) == (4.0, 4.0)
    assert ta["warning"] is None
    assert rows["p"]["type_a"]["u"] == pytest.approx(13 / math.sqrt(3), rel=1e-15)
    assert rows["p"]["dof"] == 24.0
    assert rows["z"]["dof"] == 8.0  # ½ · 0.25⁻² (JCGM 100 G.4.2)
    assert rows["z"]["u"] == 0.1
    assert rows["w"]["u"] == pytest.approx(0.4 / math.sqrt(12), rel=1e-15)
    assert rows["x"]["distribution"].startswith("t(4, ")
    # the budget's ν and the GUM's ν_eff against eq. (G.2b) by hand
    q = doc["quantities"][0]
    assert [b["dof"] for b in q["budget"]] == [4.0, 3.0, 24.0, 8.0, 12.0]
    u = np.array([rows[k]["u"] for k in "xypzw"])
    nu = np.array([4.0, 3.0, 24.0, 8.0, 12.0])
    hand = float(np.sum(u**2)) ** 2 / float(np.sum(u**4 / nu))
    assert q["gum"]["dof"] == pytest.approx(hand, rel=1e-12)
    assert q["gum"]["u"] == pytest.approx(math.sqrt(float(np.sum(u**2))), rel=1e-12)
    # the study adds nothing: the library on the same inputs gives the same bits
    model = expression("x + y + p + z + w")
    mc = monte_carlo(model, study.inputs, trials=20_000, seed=7)  # type: ignore[attr-defined]
    assert q["monte_carlo"]["u"] == mc.u
    assert q["gum"]["u"] == gum(model, study.inputs).u  # type: ignore[attr-defined]
    csv_text = (out / "budget.csv").read_text(encoding="utf-8")
    assert csv_text.splitlines()[0].endswith(",share,dof")
    # the report: the ν column of the budget and the Type A table
    page = (out / "report.html").read_text(encoding="utf-8")
    assert "ν of u(x)" in page
    assert "Type A evaluation from observations (JCGM 100 §4.2)" in page
    assert "with a pooled s<sub>p</sub> (§4.2.4)" in page  # input p is pooled
    assert 'data-key="inputs[0].type_a.r1"' in page
    assert 'data-key="quantities[0].budget[3].dof"' in page


def test_autocorrelated_observations_reach_the_report(tmp_path):
    drift = ", ".join(str(float(i)) for i in range(1, 17))
    text = STUDY.replace(
        "{data = [215.0, 212.0, 218.0], pooled_s = 13, pooled_dof = 24}", f"{{data = [{drift}]}}"
    )
    (tmp_path / "readings.csv").write_text(CSV, encoding="utf-8")
    with warnings.catch_warnings():
        warnings.simplefilter("error", AutocorrelationWarning)  # reported with the result
        study = loads_study(text, file="s.toml", folder=tmp_path)
        doc = study.run(trials=2000, seed=1).to_dict()
    assert doc["warnings"] == [f"input p: {study.inputs['p'].warning}"]  # type: ignore[attr-defined]
    assert "r1 = 0.812" in doc["warnings"][0]
    page = html(doc)
    assert page.count("serially correlated") == 2  # the summary and the Type A table


def test_cli_takes_type_a_and_dof_in_distribution_text(capsys):
    argv = ["propagate", "a + b", "-i", "a=type_a([1.0, 1.2, 1.1, 1.3])"]
    argv += ["-i", "b=normal(0, 0.05, dof=8)", "--gum", "--json", "--trials", "4000", "--seed", "2"]
    assert main(argv) == 0
    got = json.loads(capsys.readouterr().out)
    s = float(np.std([1.0, 1.2, 1.1, 1.3], ddof=1))
    u = math.sqrt(s**2 / 4 + 0.05**2)
    assert got["gum"]["u"] == pytest.approx(u, rel=1e-12)
    hand = u**4 / ((s / 2) ** 4 / 3 + 0.05**4 / 8)
    # k = t_95(ν_eff) with ν_eff truncated (JCGM 100 G.4.1 NOTE 1), by scipy
    assert got["gum"]["k"] == pytest.approx(float(stats.t.ppf(0.975, math.floor(hand))), rel=1e-12)


def test_load_csv_column_against_the_csv_module(tmp_path):
    f = tmp_path / "r.csv"
    f.write_text("a,b\n1, 2\n3,\n,4.5\n", encoding="utf-8")
    assert load_csv_column(f, "a").tolist() == [1.0, 3.0]
    assert load_csv_column(f, "B").tolist() == [2.0, 4.5]  # case ignored where not exact


# (replace this, with this, file (None: the study), line, field, words)
ERRORS = [
    (
        'x = {data = "readings.csv", column = "x"}',
        'x = {data = "readings.csv", column = "q"}',
        "readings.csv",
        2,
        "q",
        "no column 'q' in the header; it has run, x, y",
    ),
    (
        'x = {data = "readings.csv", column = "x"}',
        'x = {data = "missing.csv"}',
        None,
        8,
        "inputs.x.data",
        "expected an existing file",
    ),
    (
        'x = {data = "readings.csv", column = "x"}',
        "x = {data = [1.0]}",
        None,
        8,
        "inputs.x.data",
        "at least 2 observations",
    ),
    (
        'x = {data = "readings.csv", column = "x"}',
        "x = {data = []}",
        None,
        8,
        "inputs.x.data",
        "at least 2 observations",
    ),
    (
        'x = {data = "readings.csv", column = "x"}',
        "x = {data = [1.0, nan, 2.0]}",
        None,
        8,
        "inputs.x.data[1]",
        "expected a finite number",
    ),
    (
        'x = {data = "readings.csv", column = "x"}',
        'x = {data = [1.0, "a"]}',
        None,
        8,
        "inputs.x.data[1]",
        "expected a number",
    ),
    (
        'x = {data = "readings.csv", column = "x"}',
        "x = {data = [2.0, 2.0]}",
        None,
        8,
        "inputs.x.data",
        "all equal",
    ),
    (
        'x = {data = "readings.csv", column = "x"}',
        "x = {data = 3}",
        None,
        8,
        "inputs.x.data",
        "array of observations or the name of a CSV file",
    ),
    (
        'x = {data = "readings.csv", column = "x"}',
        'x = {column = "x"}',
        None,
        8,
        "inputs.x",
        "got neither",
    ),
    (
        'x = {data = "readings.csv", column = "x"}',
        'x = {data = [1.0, 2.0], dist = "normal(0, 1)"}',
        None,
        8,
        "inputs.x",
        "got both",
    ),
    (
        'x = {data = "readings.csv", column = "x"}',
        "x = {data = [1.0, 2.0], dof = 3}",
        None,
        8,
        "inputs.x.dof",
        "ν = n - 1",
    ),
    (
        'x = {data = "readings.csv", column = "x"}',
        'x = {data = [1.0, 2.0], column = "x"}',
        None,
        8,
        "inputs.x.column",
        "column goes with data",
    ),
    (
        'x = {data = "readings.csv", column = "x"}',
        "x = {data = [1.0, 2.0], colour = 3}",
        None,
        8,
        "inputs.x.colour",
        "unknown key 'colour'",
    ),
    (
        "pooled_s = 13, pooled_dof = 24",
        "pooled_s = 13",
        None,
        10,
        "inputs.p.pooled_s",
        "pooled_dof is missing",
    ),
    ("pooled_s = 13", "pooled_s = -13", None, 10, "inputs.p.pooled_s", "expected a number > 0"),
    ("pooled_dof = 24", "pooled_dof = 0", None, 10, "inputs.p.pooled_dof", "expected a number > 0"),
    ("u_rel_u = 0.25", "u_rel_u = 0", None, 11, "inputs.z.u_rel_u", "expected a number > 0"),
    ("u_rel_u = 0.25", "u_rel_u = 0.25, dof = 3", None, 11, "inputs.z.u_rel_u", "got both"),
    ("u_rel_u = 0.25", "pooled_s = 3", None, 11, "inputs.z.pooled_s", "goes with data"),
    ('"normal(0, 0.1)"', '"normal(0, -0.1)"', None, 11, "inputs.z.dist", ">= 0"),
    ('"normal(0, 0.1)"', '"t(3, 0, 0.1)"', None, 11, "inputs.z.u_rel_u", "already has ν = 3"),
    (
        '"uniform(-0.2, 0.2)", dof = 12',
        '"constant(1)", dof = 12',
        None,
        12,
        "inputs.w.dof",
        "zero standard deviation",
    ),
    (
        '"uniform(-0.2, 0.2)", dof = 12',
        '"uniform(-0.2, 0.2)", dof = "many"',
        None,
        12,
        "inputs.w.dof",
        "expected a number",
    ),
    (
        '"uniform(-0.2, 0.2)", dof = 12',
        '"uniform(-0.2, 0.2, dof=-1)"',
        None,
        12,
        "inputs.w.dist",
        "expected dof to be a finite number > 0",
    ),
]


@pytest.mark.parametrize(("old", "new", "file", "line", "field", "words"), ERRORS)
def test_errors_name_file_line_and_field(study_dir, old, new, file, line, field, words):
    text = STUDY.replace(old, new, 1)
    assert text != STUDY
    with pytest.raises(MtmcError) as info:
        loads_study(text, file="s.toml", folder=study_dir)
    err = info.value
    want_file = "s.toml" if file is None else str(study_dir / file)
    assert (err.file, err.line, err.field) == (want_file, line, field)
    assert words in err.message
    assert "\n" not in str(err)


@pytest.mark.parametrize(
    ("csv", "line", "words"),
    [
        ("run,x\n1,10.1\n2,abc\n", 3, "exponent: -1.5e-3), got 'abc'"),
        ("run,x\n1,10.1\n2,nan\n", 3, "exponent: -1.5e-3), got 'nan'"),
        ("run,x\n1,10.1\n2,1_0\n", 3, "exponent: -1.5e-3), got '1_0'"),
        ("run,x\n1,10.1\n2,\uff11\n", 3, "exponent: -1.5e-3), got '\uff11'"),
        ("run,x\n1,10.1\n2\n", 3, "expected 2 or more fields"),
        ("run,x\n1,10.1\n", None, "has 1 value; input x needs at least 2"),
        ("# nothing\n\n", None, "expected a header line"),
        (b"run,x\n1,10.1\n2,\xff\n", 3, "UTF-8"),
    ],
)
def test_csv_errors_name_the_csv_file_line_and_column(study_dir, csv, line, words):
    f = study_dir / "readings.csv"
    if isinstance(csv, bytes):
        f.write_bytes(csv)
    else:
        f.write_text(csv, encoding="utf-8")
    text = STUDY.replace('y = {data = "readings.csv"}\n', "")
    text = text.replace("x + y + p", "x + p")
    with pytest.raises(MtmcError) as info:
        loads_study(text, file="s.toml", folder=study_dir)
    err = info.value
    assert err.file == str(f)
    assert err.line == line
    assert words in str(err)
    if "header" not in words and "UTF-8" not in words:
        assert err.field == "x"


def test_shipped_example_is_the_docs_worked_example():
    """examples/studies/bore_type_a.toml: the GUM of docs/type-a.md (u = 0.002289 mm,
    ν_eff = 12.78, k = t_95(12) = 2.179) and the Monte Carlo of the same inputs in Python."""
    root = Path(__file__).resolve().parents[2]
    study = load_study(root / "examples" / "studies" / "bore_type_a.toml")
    doc = study.run(trials=20_000).to_dict()
    q = doc["quantities"][0]
    assert round(q["gum"]["u"], 6) == 0.002289
    assert round(q["gum"]["dof"], 2) == 12.78
    assert q["gum"]["k"] == pytest.approx(float(stats.t.ppf(0.975, 12)), rel=1e-12)
    mc = monte_carlo(expression("x + b + r"), study.inputs, trials=20_000, seed=1)  # type: ignore[attr-defined]
    assert q["monte_carlo"]["u"] == mc.u
