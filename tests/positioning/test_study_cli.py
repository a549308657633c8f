"""The study kind, the CLI and the report: one route, the same numbers, errors with lines."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

import mtmc
from mtmc.cli.main import main
from mtmc.errors import InputError
from mtmc.positioning import SYMBOLS, UncertaintyModel, evaluate_uncertainty, load_positioning_csv
from mtmc.report import html
from mtmc.study import load_study, loads_study, write_result
from mtmc.study.positioning import PositioningStudy, summary
from mtmc.verification import load_compensation

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "examples" / "studies" / "positioning_x.toml"
DATA = ROOT / "examples" / "studies" / "positioning_x.csv"
M = 3000


def test_shipped_copies_are_the_examples():
    for name in ("positioning_x.toml", "positioning_x.csv"):
        pkg = ROOT / "src" / "mtmc" / "data" / "studies" / name
        assert pkg.read_bytes() == (ROOT / "examples" / "studies" / name).read_bytes()


def test_shipped_study_is_a_1_m_axis_with_5_runs_at_11_targets():
    s = load_study(STUDY)
    assert isinstance(s, PositioningStudy)
    assert (s.test.m, s.test.n) == (11, 5)
    assert s.test.targets[-1] - s.test.targets[0] == 1000.0


def test_api_study_and_cli_give_the_same_numbers(capsys):
    s = load_study(STUDY)
    result = s.run(trials=M, seed=4)
    assert [q.name for q in result.quantities] == list(SYMBOLS)
    assert {q.unit for q in result.quantities} == {"µm"}
    # the library called directly
    res = evaluate_uncertainty(s.test, s.model, M, seed=4)
    for i, q in enumerate(result.quantities):
        assert q.mc.estimate == float(np.mean(res.mc.samples[:, i]))
        assert q.gum.u == res.gum_result(q.name).u
    # the command line, with the study's model applied to the same file
    argv = ["positioning", "evaluate", str(DATA), "--study", str(STUDY), "-n", str(M)]
    assert main([*argv, "--seed", "4", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out == json.loads(json.dumps(summary(result)))
    assert set(out["parameters"]) == set(SYMBOLS)
    for sym in SYMBOLS:
        assert set(out["parameters"][sym]) >= {"estimate", "U"}
    assert out["unit"] == "µm"
    assert set(out["conformity"]) == {"A", "E", "M", "R", "B"}


def test_mtmc_run_writes_the_report_with_the_plot_and_the_notes(tmp_path):
    out = tmp_path / "posx"
    assert main(["run", str(STUDY), "-o", str(out), "-n", str(M), "-q"]) == 0
    doc = json.loads((out / "result.json").read_text(encoding="utf-8"))
    assert doc["kind"] == "positioning"
    assert doc["positioning"]["notes"]
    page = (out / "report.html").read_text(encoding="utf-8")
    assert 'data-plot="positioning"' in page
    assert "Where the GUM and the Monte Carlo disagree" in page
    for name in ("parameters", "targets", "compensation", "compensation_residual"):
        assert (out / f"{name}.csv").is_file()
    # the decisions are the engine's (JCGM 106), on the quantities, as every kind gives them
    got = mtmc.load_result(out)
    decided = {q.name: q.conformity for q in got.quantities if q.conformity is not None}
    assert set(decided) == {"A", "E", "M", "R", "B"}
    for name, c in decided.items():
        q = got.quantity(name)
        assert c["rule"] == "guarded"
        assert c["guard_band"] == q.mc.U  # guard_band = "U": each parameter's U
        assert c["acceptance"] == [None, c["upper"] - q.mc.U]
        assert c["estimate"] == next(r[3] for r in doc_rows(doc) if r[0] == name)
        assert c["decision"] in ("conforms", "does not conform")
        assert set(c) >= {"p_c", "gum_p_c", "gum_basis", "consumer_risk", "producer_risk"}
    assert "Conformity (JCGM 106)" in page


def doc_rows(doc):
    """The rows of the parameters table of a result.json."""
    return next(t["rows"] for t in doc["tables"] if t["name"] == "parameters")


def test_report_says_when_the_monte_carlo_of_A_differs(tmp_path):
    # a flat axis: A is a maximum over tied targets (see test_uncertainty)
    rng = np.random.default_rng(4)
    rows = ["target,run,direction,deviation"]
    for i, p in enumerate(np.linspace(0, 700, 8)):
        for j in range(5):
            for d in "+-":
                rows.append(f"{p},{j + 1},{d},{0.5 * rng.standard_normal():.4f}")
        del i
    data = tmp_path / "flat.csv"
    data.write_text("\n".join(rows) + "\n", encoding="utf-8")
    s = loads_study(
        'kind = "positioning"\ndata = "flat.csv"\n[run]\ntrials = 20000\nseed = 2\n',
        file="flat.toml",
        folder=tmp_path,
    )
    result = s.run()
    a = result.quantity("A")
    assert a.validation.verdict == "not validated"
    page = html(result.to_dict())
    assert "A: the GUM is not validated by the Monte Carlo" in page


def test_cli_table_compensation_and_result_folder(tmp_path, capsys):
    comp = tmp_path / "pitch.isg"
    out = tmp_path / "res"
    argv = ["positioning", "evaluate", str(DATA), "-n", "2000", "--seed", "1"]
    assert main([*argv, "--compensation", str(comp), "--sign", "correction", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "B_mean" in text
    assert f"report: {out / 'report.html'}" in text
    table = load_compensation(comp, "isg")
    assert table.sign == "correction"
    assert table.curve("EXX").positions.size == 11
    assert (out / "result.json").is_file()


def test_cli_columns_units_and_errors(tmp_path, capsys):
    data = tmp_path / "vendor.csv"
    text = DATA.read_text(encoding="utf-8").replace(
        "target,run,direction,deviation", "Pos,Run,Dir,Err"
    )
    data.write_text(text, encoding="utf-8")
    cols = "target=Pos,run=Run,direction=Dir,deviation=Err"
    argv = ["positioning", "evaluate", str(data), "--columns", cols, "-n", "500", "--json"]
    assert main([*argv, "--type-a", "none", "--seed", "1", "--study", str(STUDY)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["type_a"] == "none"
    assert main([*argv, "--type-a", "none"]) == 2  # nothing uncertain left
    assert "no uncertain input" in capsys.readouterr().err
    assert main(["positioning", "evaluate", str(data), "--columns", "target"]) == 2
    assert "OURS=THEIRS" in capsys.readouterr().err
    assert main(["positioning", "evaluate", str(data)]) == 2
    err = capsys.readouterr().err
    assert "vendor.csv:" in err
    assert "no column 'target'" in err
    other = ROOT / "examples" / "studies" / "mass_calibration.toml"
    assert main(["positioning", "evaluate", str(DATA), "--study", str(other)]) == 2
    assert "expected a positioning study" in capsys.readouterr().err


def _edit(tmp_path: Path, old: str, new: str) -> Path:
    text = STUDY.read_text(encoding="utf-8")
    assert old in text
    path = tmp_path / "s.toml"
    path.write_text(text.replace(old, new), encoding="utf-8")
    (tmp_path / "positioning_x.csv").write_bytes(DATA.read_bytes())
    return path


@pytest.mark.parametrize(
    ("old", "new", "field", "match"),
    [
        ("humidity_pct =", "humidty_pct =", "environment.humidty_pct", "unknown key"),
        ('"normal(1008.2, 0.5)"', '"normal(1008.2, -0.5)"', "environment.air_pressure_hPa", ">= 0"),
        ('"normal(1008.2, 0.5)"', "true", "environment.air_pressure_hPa", "distribution"),
        ('type_a = "means"', 'type_a = "all"', "uncertainty.type_a", "expected one of"),
        ('units = "mm,um"', 'units = "mm,arcsec"', "units", "TARGET,DEVIATION"),
        ("A = 20.0", "Q = 20.0", "tolerances.Q", "unknown key"),
        ('guard_band = "U"', 'guard_band = "2U"', "tolerances.guard_band", "expected one of"),
        ('data = "positioning_x.csv"', 'data = "none.csv"', "data", "existing file"),
        ("dead_path_mm = 60.0", "dead_path_mm = -1.0", "instrument.dead_path_mm", ">= 0"),
        ('drift = "uniform(-1.0, 1.0)"', "drift = inf", "environment.drift", "finite"),
        ('equation = "ciddor"', 'equation = "x"', "instrument.equation", "one of"),
    ],
)
def test_study_errors_name_the_line_and_field(tmp_path, old, new, field, match):
    path = _edit(tmp_path, old, new)
    with pytest.raises(InputError, match=match) as exc:
        load_study(path)
    assert exc.value.field == field
    line = next(k for k, t in enumerate(path.read_text().splitlines(), 1) if new in t)
    assert exc.value.line == line


def test_model_errors_are_placed_in_the_study(tmp_path):
    # air given in part: the model refuses it, the study names the key that is there
    path = _edit(tmp_path, 'humidity_pct = "normal(42, 4)"', "")
    with pytest.raises(InputError, match="together") as exc:
        load_study(path)
    assert exc.value.field == "environment.air_temperature_C"


def test_dead_path_without_air_and_a_bad_csv(tmp_path):
    text = STUDY.read_text(encoding="utf-8")
    for key in ("air_temperature_C", "air_pressure_hPa", "humidity_pct"):
        text = "\n".join(t for t in text.splitlines() if not t.startswith(key))
    path = tmp_path / "s.toml"
    path.write_text(text, encoding="utf-8")
    (tmp_path / "positioning_x.csv").write_bytes(DATA.read_bytes())
    with pytest.raises(InputError, match="dead path needs the air") as exc:
        load_study(path)
    assert exc.value.field == "instrument.dead_path_mm"
    study = _edit(tmp_path, "", "")
    bad = DATA.read_text(encoding="utf-8").replace("98.5,1,+,0.583", "98.5,1,+,?")
    (tmp_path / "positioning_x.csv").write_text(bad, encoding="utf-8")
    with pytest.raises(InputError, match="finite number") as exc:
        load_study(study)
    assert exc.value.file.endswith("positioning_x.csv")


def test_columns_and_a_numeric_guard_band(tmp_path):
    path = _edit(tmp_path, 'guard_band = "U"', 'guard_band = 0.5\n[columns]\ndeviation = "Err"')
    csv = tmp_path / "positioning_x.csv"
    csv.write_text(
        DATA.read_text(encoding="utf-8").replace("direction,deviation", "direction,Err"),
        encoding="utf-8",
    )
    s = load_study(path)
    assert s.guard_band == 0.5
    assert s.test.m == 11


def test_samples_kept_on_request():
    s = load_study(STUDY)
    result = s.run(trials=500, seed=1, samples=True)
    assert result.samples["A"].shape == (500,)


def test_the_study_result_folder_writes(tmp_path):
    s = load_study(STUDY)
    res = s.run(trials=500, seed=1)
    out = write_result(res, tmp_path / "o", study_text=s.source.text)
    assert (out / "report.html").is_file()
    assert load_positioning_csv(DATA).m == 11
    assert isinstance(s.model, UncertaintyModel)


def test_parameters_of_the_readings_alone_are_one_value_not_validated(capsys):
    # the Type A evaluation of the readings alone: the ranges R↑ and R↓ are those of the
    # readings in every trial, one value: the Monte Carlo's u is exactly 0 (it was the
    # rounding of the mean's arithmetic, 4.4e-16 µm at 3.05 µm, before a constant's mean
    # was taken as the constant), and the GUM's is 0: nothing to compare by JCGM 101 §8
    assert main(["positioning", "evaluate", str(DATA), "-n", "50000", "-s", "7", "--json"]) == 0
    params = json.loads(capsys.readouterr().out)["parameters"]
    for name in ("R_up", "R_down"):
        p = params[name]
        assert p["gum"]["u"] == 0.0
        assert p["u"] <= 16 * np.finfo(float).eps * p["estimate"]
        assert (p["verdict"], p["validated"]) == ("not applicable", None), name
        # its U covers nothing: said so, with the reason, never a bare 0
        assert p["covers"].startswith(f"not evaluated: {name} is a function of the standard")
    assert params["R_up"]["u"] == 0.0  # one value in every trial: its u, exactly
    assert (params["A"]["verdict"], params["A"]["validated"]) == ("not validated", False)


def test_terminal_json_and_report_give_one_estimate_and_say_what_U_covers(tmp_path, capsys):
    from mtmc.uncertainty.tolerance import round_to_uncertainty

    out_dir = tmp_path / "res"
    argv = ["positioning", "evaluate", str(DATA), "--study", str(STUDY), "-n", "4000", "-s", "3"]
    assert main([*argv, "-o", str(out_dir)]) == 0
    text = capsys.readouterr().out
    assert main([*argv, "--json"]) == 0
    js = json.loads(capsys.readouterr().out)
    page = (out_dir / "report.html").read_text(encoding="utf-8")
    readings = evaluate_uncertainty(load_positioning_csv(DATA), UncertaintyModel(), 10)
    for sym in SYMBOLS:
        p = js["parameters"][sym]
        rep = p["reported"]
        # the headline is the definition on the readings (the shipped model corrects
        # nothing on average: the readings' value to the rounding of the corrections)
        assert p["estimate"] == pytest.approx(p["readings"], abs=1e-9)
        assert p["estimate"] == pytest.approx(readings.estimate(sym), abs=1e-9)
        assert p["mc_mean"] != p["estimate"]
        # rounded to the digits of its U (JCGM 100 §7.2.6), the same text everywhere
        assert (rep["estimate"], rep["U"]) == round_to_uncertainty(p["estimate"], p["U"])
        assert re.search(rf"^\s+{sym}\s+{re.escape(rep['estimate'])}\s", text, re.M), sym
        assert f"{sym} = {rep['estimate']} µm, U = {rep['U']} µm" in page
        assert p["covers"] == "instrument and environment + scatter of the means" or (
            sym in ("R_up", "R_down") and p["covers"] == "instrument and environment"
        )
    line = js["covers"]
    assert line.startswith("U covers: instrument and environment (air_temperature")
    assert "scatter of s not evaluated (type_a = 'means')" in line
    assert line in text
    assert line.replace("'", "&#39;") in page
    # the decisions (JCGM 106, the engine's rule) in the terminal as in the JSON
    for sym, c in js["conformity"].items():
        assert f"conformity of {sym} (JCGM 106): {c['text']}" in text
        assert c["estimate"] == js["parameters"][sym]["estimate"]


def test_estimates_in_mm_are_printed_to_the_digits_of_their_U(tmp_path, capsys):
    # the shipped readings in mm: U is a few 1e-4 mm, so the estimate carries as many
    # decimals (not a fixed 3, which printed A = 0.008 beside U = 0.00054)
    rows = DATA.read_text(encoding="utf-8").splitlines()
    head = next(i for i, r in enumerate(rows) if r.startswith("target"))
    mm = rows[: head + 1]
    for r in rows[head + 1 :]:
        t, run, d, x = r.split(",")
        mm.append(f"{t},{run},{d},{float(x) / 1000.0!r}")
    data = tmp_path / "mm.csv"
    data.write_text("\n".join(mm) + "\n", encoding="utf-8")
    argv = ["positioning", "evaluate", str(data), "--units", "mm,mm", "-n", "3000", "-s", "1"]
    assert main([*argv, "--json"]) == 0
    js = json.loads(capsys.readouterr().out)
    a = js["parameters"]["A"]
    assert a["U"] < 1e-3
    decimals = len(a["reported"]["U"].partition(".")[2])
    assert decimals >= 4
    assert len(a["reported"]["estimate"].partition(".")[2]) == decimals
    assert main(argv) == 0
    assert re.search(rf"A\s+{re.escape(a['reported']['estimate'])}\s", capsys.readouterr().out)


def test_direction_words_from_the_study_and_the_command_line(tmp_path, capsys):
    text = DATA.read_text(encoding="utf-8").replace(",+,", ",Hin,").replace(",-,", ",Rueck,")
    data = tmp_path / "positioning_x.csv"
    data.write_text(text, encoding="utf-8")
    argv = ["positioning", "evaluate", str(data), "-n", "500", "-s", "1", "--json"]
    assert main(argv) == 2
    assert "expected a direction, got 'Hin'" in capsys.readouterr().err
    assert main([*argv, "--directions", "Hin=up,Rueck=down"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert main(["positioning", "evaluate", str(DATA), "-n", "500", "-s", "1", "--json"]) == 0
    assert got["parameters"] == json.loads(capsys.readouterr().out)["parameters"]
    study = _edit(tmp_path, "[run]", '[directions]\nHin = "up"\nRueck = "down"\n\n[run]')
    data.write_text(text, encoding="utf-8")  # _edit copied the shipped CSV over it
    assert load_study(study).test.deviations.tolist() == load_study(STUDY).test.deviations.tolist()
    bad = _edit(tmp_path, "[run]", '[directions]\nHin = "sideways"\n\n[run]')
    with pytest.raises(InputError, match="sideways") as exc:
        load_study(bad)
    assert exc.value.field == "directions.Hin"
