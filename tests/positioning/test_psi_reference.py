"""A published positioning test: the Paul Scherrer Institute's acceptance report (ecmccfg, 2023).

``tests/reference/iso230_2/psi_ecmccfg_mcu1025.csv`` (provenance in
``tests/reference/README.md``): 5 targets × 5 runs × 2 directions of a linear axis against its
encoder. The report prints, in mm, B 0.04649, M 0.036, R 0.23036, A 0.23036 and E 0.05405.
"""

from __future__ import annotations

import hashlib
import json
from decimal import ROUND_HALF_EVEN, Decimal
from pathlib import Path

import numpy as np
import pytest

from mtmc.cli.main import main
from mtmc.positioning import evaluate, grubbs_critical, load_positioning_csv, outliers

DATA = Path(__file__).resolve().parents[1] / "reference" / "iso230_2" / "psi_ecmccfg_mcu1025.csv"
SHA256 = "20745378568d839cb835f08eebd41fa3d50aad20e793ea082e6e3545625f7efe"

#: The printed values in mm, as text: their digits are the comparison's resolution.
PRINTED = {"B": "0.04649", "M": "0.036", "R": "0.23036", "A": "0.23036", "E": "0.05405"}


def _to_printed_digits(value_um: float, printed: str) -> str:
    """A value in µm as mm, rounded to the decimals of the printed text."""
    places = Decimal(printed)
    return str(Decimal(repr(value_um / 1000.0)).quantize(places, rounding=ROUND_HALF_EVEN))


def _e_readings(x: np.ndarray) -> dict[str, float]:
    """E by each reading a script might take, from the deviations (m, n, 2) in µm."""
    mean = x.mean(axis=1)  # (m, 2): x̄_i↑, x̄_i↓
    without_run_1 = x[:, 1:, :].mean(axis=1)
    return {
        # ISO 230-2: max over both directions of the means minus their min
        "E, ISO 230-2's definition": float(mean.max() - mean.min()),
        "E↑ (positive direction only)": float(np.ptp(mean[:, 0])),
        "E↓ (negative direction only)": float(np.ptp(mean[:, 1])),
        "max(E↑, E↓)": float(max(np.ptp(mean[:, 0]), np.ptp(mean[:, 1]))),
        "E without run 1": float(without_run_1.max() - without_run_1.min()),
        "range of the individual readings": float(x.max() - x.min()),
        "M (the bidirectional means x̄_i)": float(np.ptp(mean.mean(axis=1))),
    }


def test_the_file_is_the_published_one():
    assert hashlib.sha256(DATA.read_bytes()).hexdigest() == SHA256
    t = load_positioning_csv(DATA)
    assert (t.m, t.n, t.unit) == (5, 5, "um")
    assert t.targets.tolist() == [15.0, 25.2, 35.4, 45.6, 55.8]


def test_B_M_R_A_as_printed_through_the_library_and_the_command_line(capsys):
    params = evaluate(load_positioning_csv(DATA))
    assert main(["positioning", "evaluate", str(DATA), "-n", "2000", "-s", "1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)["parameters"]
    for sym in ("B", "M", "R", "A"):
        lib = float(getattr(params, sym))
        # the printed digits are the tolerance: both routes round to the printed text
        assert _to_printed_digits(lib, PRINTED[sym]) == PRINTED[sym], sym
        # the command line's estimate is the library's (the definition on the readings)
        assert out[sym]["estimate"] == pytest.approx(lib, rel=1e-15, abs=1e-12), sym
        assert _to_printed_digits(out[sym]["estimate"], PRINTED[sym]) == PRINTED[sym]


def test_the_printed_E_is_E_of_the_negative_direction_not_the_definition(capsys):
    t = load_positioning_csv(DATA)
    params = evaluate(t)
    got = _e_readings(t.deviations)
    # what each reading gives, µm (docs/positioning.md prints the same table)
    expected = {
        "E, ISO 230-2's definition": 70.08764354,
        "E↑ (positive direction only)": 57.2660174,
        "E↓ (negative direction only)": 54.0546685,
        "max(E↑, E↓)": 57.2660174,
        "E without run 1": 71.372113,
        "range of the individual readings": 135.4428479,
        "M (the bidirectional means x̄_i)": 35.99823204,
    }
    for name, value in expected.items():
        # the file's deviations carry 7 decimals of µm: the means of 5 of them are exact
        # to 1e-7 µm, and the sums to a few ulp of 100 µm
        assert got[name] == pytest.approx(value, abs=1e-7), name
    matches = [n for n, v in got.items() if _to_printed_digits(v, PRINTED["E"]) == PRINTED["E"]]
    assert matches == ["E↓ (negative direction only)"]
    # mtmc keeps the definition: E is 70.09 µm, and E↓ is its own parameter
    assert float(params.E) == pytest.approx(expected["E, ISO 230-2's definition"], abs=1e-7)
    assert float(params.E_down) == got["E↓ (negative direction only)"]
    assert main(["positioning", "evaluate", str(DATA), "-n", "2000", "-s", "1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)["parameters"]
    assert _to_printed_digits(out["E_down"]["estimate"], PRINTED["E"]) == PRINTED["E"]
    assert _to_printed_digits(out["E"]["estimate"], "0.00001") == "0.07009"


def test_run_1_at_15_mm_is_flagged_by_grubbs_and_kept():
    # ASTM E178 (Grubbs 1969), n = 5: 1.715 at the two-sided 5 % level (one-sided 2.5 %)
    assert grubbs_critical(5) == pytest.approx(1.715, abs=5e-4)
    t = load_positioning_csv(DATA)
    found = outliers(t)
    assert [(o.target, o.direction, o.run) for o in found] == [(15.0, 0, 1), (25.2, 0, 1)]
    first = found[0]
    assert first.deviation == pytest.approx(100.3467144, abs=1e-7)
    # G by hand: |x - x̄| / s over the five runs at 15 mm ↑
    runs = t.deviations[0, :, 0]
    g = abs(runs[0] - runs.mean()) / runs.std(ddof=1)
    assert first.G == pytest.approx(g, rel=1e-14)
    assert "ISO 230-2 keeps every run" in first.text("mm", "µm")
    # kept: the parameters are those of all five runs
    assert float(evaluate(t).A) == pytest.approx(230.36435366, abs=1e-7)


def test_the_warning_reaches_the_terminal_and_the_json(capsys):
    argv = ["positioning", "evaluate", str(DATA), "-n", "2000", "-s", "1"]
    assert main(argv) == 0
    # on stderr, as every command warns, and under -q too
    err = capsys.readouterr().err
    assert "mtmc: warning: run 1 at P = 15 mm ↑ reads 100.347 µm" in err
    assert main([*argv, "-q"]) == 0
    assert "mtmc: warning: run 1 at P = 15 mm ↑ reads 100.347 µm" in capsys.readouterr().err
    assert main([*argv, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert len(out["warnings"]) == 2
    assert "Grubbs' test" in out["warnings"][0]


def test_mtmc_run_of_a_study_of_the_file_warns_as_positioning_evaluate(tmp_path, capsys):
    # one reading of a result's warnings (StudyResult.warnings): the study's own and its
    # kind's, here the positioning test's outliers, printed by StudyOptions.run for both
    argv = ["-n", "2000", "-s", "1", "-q", "--plots", "0"]
    assert main(["positioning", "evaluate", str(DATA), *argv]) == 0
    evaluated = capsys.readouterr()
    study = tmp_path / "psi.toml"
    study.write_text(f'kind = "positioning"\ntitle = "PSI"\ndata = "{DATA.as_posix()}"\n')
    assert main(["run", str(study), *argv, "-o", str(tmp_path / "r")]) == 0
    ran = capsys.readouterr()
    lines = [line for line in ran.err.splitlines() if line.startswith("mtmc: warning: ")]
    assert len(lines) == 2
    assert "Grubbs' test" in lines[0]
    assert ran.err == evaluated.err
    assert ran.out.splitlines()[0] == evaluated.out.splitlines()[0] == "trials 2000  seed 1"
    as_json = ["-n", "2000", "-s", "1", "--json", "--plots", "0", "-o", str(tmp_path / "j")]
    assert main(["run", str(study), *as_json]) == 0
    assert json.loads(capsys.readouterr().out)["warnings"] == [
        line.removeprefix("mtmc: warning: ") for line in lines
    ]


def test_the_report_and_the_notes_of_the_psi_test(tmp_path, capsys):
    out = tmp_path / "psi"
    argv = ["positioning", "evaluate", str(DATA), "-n", "4000", "-s", "2", "-o", str(out)]
    assert main(argv) == 0
    text = capsys.readouterr().out
    page = (out / "report.html").read_text(encoding="utf-8")
    assert "Runs far from the others (kept)" in page
    assert "run 1 at P = 15 mm ↑ reads 100.347 µm" in page
    assert "U covers: instrument and environment not evaluated" in page
    # R↑ on the readings alone: "not evaluated" with its reason, never a bare U = 0
    assert "R_up = 230.364 µm, U not evaluated: R_up is a function of" in page
    assert "R_up = 230.364 µm, U = 0" not in page
    # one symbol for the micrometre in every note (the near-tie note of E↑ names a gap)
    doc = json.loads((out / "result.json").read_text(encoding="utf-8"))
    notes = doc["positioning"]["notes"]
    assert any("comes within" in n for n in notes)
    for n in notes:
        assert " um" not in n, n
    assert " um " not in text
