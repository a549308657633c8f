"""Reading a measured trace; `mtmc circle evaluate` prints what the library computes."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from mtmc.circular import (
    AxisEffects,
    circular_parameters,
    design,
    identify,
    load_circular_csv,
    loads_circular_csv,
    simulate_circle,
)
from mtmc.circular.data import parse_units
from mtmc.cli.main import main
from mtmc.errors import InputError
from mtmc.kinematics import Machine

R = 100.0
STEP = 2.0  # degrees


def _trace(tmp_path: Path, rng: np.random.Generator) -> tuple[Path, dict[str, np.ndarray]]:
    """A trace of XFYZ with a squareness and backlash, exported with an overrun of 10°."""
    m = Machine.from_topology("XFYZ")
    deg = np.arange(-10.0, 370.0, STEP)
    t = np.radians(np.arange(0.0, 360.0, STEP))
    eff = AxisEffects(backlash={"X": 0.004, "Y": 0.002}, lag={"X": 5e-4})
    rows = ["Angle;Dir;Error"]
    devs = {}
    for d, word in ((1, "counter"), (-1, "clockwise")):
        dev = simulate_circle(m, t, radius=R, direction=d, errors={"EC0Y": 3e-5}, effects=eff)[0]
        dev = dev + rng.normal(0, 2e-4, dev.size)
        devs[word] = dev
        for a in deg:  # the overrun arcs repeat the trace: they are left out
            rows.append(f"{a:g};{word};{dev[round(a / STEP) % t.size] * 1e3:.6f}")
    p = tmp_path / "trace.csv"
    p.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return p, devs


def test_reader_keeps_one_turn(tmp_path: Path) -> None:
    p, devs = _trace(tmp_path, np.random.default_rng(1))
    tr = load_circular_csv(
        p,
        columns={"angle": "Angle", "direction": "Dir", "deviation": "error"},
        directions={"counter": "ccw"},
    )
    assert tr.theta_ccw is not None
    assert tr.ccw is not None
    np.testing.assert_allclose(tr.theta_ccw, np.radians(np.arange(0.0, 360.0, STEP)))
    # written with 6 decimals of µm: read back to 5e-10 mm
    np.testing.assert_allclose(tr.ccw, devs["counter"], atol=6e-10)
    assert tr.cw is not None
    np.testing.assert_allclose(tr.cw, devs["clockwise"], atol=6e-10)


def test_reader_errors_name_file_line_and_column() -> None:
    ok = "angle,direction,deviation\n0,ccw,1\n90,ccw,2\n180,ccw,3\n270,ccw,4\n"
    assert loads_circular_csv(ok).ccw is not None
    with pytest.raises(InputError, match=r"f.csv:3: field deviation: expected a finite number"):
        loads_circular_csv(ok.replace("90,ccw,2", "90,ccw,x"), "f.csv")
    with pytest.raises(InputError, match=r"f.csv:4: field direction: expected a direction"):
        loads_circular_csv(ok.replace("180,ccw", "180,left"), "f.csv")
    with pytest.raises(InputError, match=r"f.csv:1: field angle: no column 'angle'"):
        loads_circular_csv(ok.replace("angle,", "theta,"), "f.csv")
    with pytest.raises(InputError, match=r"f.csv:5: a second reading at 180 deg ccw"):
        loads_circular_csv(ok.replace("270,ccw", "180,ccw"), "f.csv")
    with pytest.raises(InputError, match="at least 4 readings ccw"):
        loads_circular_csv("angle,direction,deviation\n0,ccw,1\n")
    with pytest.raises(InputError, match="units"):
        parse_units("deg,inch")
    assert parse_units("rad,mm") == ("rad", "mm")


def test_cli_evaluate_json(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    p, devs = _trace(tmp_path, np.random.default_rng(2))
    argv = ["circle", "evaluate", str(p), "--radius", str(R), "--json", "-n", "2000"]
    argv += ["--columns", "angle=Angle,direction=Dir,deviation=Error", "--seed", "5"]
    argv += ["--directions", "counter=ccw"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    t = np.radians(np.arange(0.0, 360.0, STEP))
    # the parameters: those of the trace as written (6 decimals of µm)
    ref = circular_parameters(theta_ccw=t, ccw=devs["counter"], theta_cw=t, cw=devs["clockwise"])
    for sym in ("F_max", "F_min", "G_lsc", "G_mz", "H", "G_b"):
        assert out["parameters"][sym]["estimate"] == pytest.approx(ref[sym][0] * 1e3, abs=1e-5)
        assert out["parameters"][sym]["unit"] == "µm"
        assert out["parameters"][sym]["U"] > 0
    # the errors: the identification of the trace, in µm and µrad
    des = design(radius=R, theta_ccw=t, theta_cw=t)
    ident = identify(des, np.concatenate([devs["counter"], devs["clockwise"]]))
    sq = out["errors"]["squareness"]
    assert sq["unit"] == "µrad"
    assert sq["estimate"] == pytest.approx(ident.value("squareness")[0] * 1e6, abs=1e-3)
    # 30 µrad injected, recovered within its U
    assert abs(sq["estimate"] - 30.0) < sq["U"]
    assert abs(out["errors"]["backlash_x"]["estimate"] - 4.0) < out["errors"]["backlash_x"]["U"]
    assert any("servo" not in n for n in out["notes"])


def test_cli_errors(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    bad = tmp_path / "bad.csv"
    bad.write_text("angle,direction,deviation\n0,ccw,1\n90,sideways,2\n", encoding="utf-8")
    assert main(["circle", "evaluate", str(bad), "--radius", "100"]) == 2
    err = capsys.readouterr().err
    assert "bad.csv:3: field direction" in err
    assert main(["circle", "evaluate", str(bad), "--radius", "100", "--directions", "x"]) == 2
    assert "--directions" in capsys.readouterr().err


def test_cli_evaluate_table(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # the table of mtmc run: y and U as the report and result.json round them (before, a
    # table of its own: the GUM's estimate to 4 digits, U to 2, "U (MC, 95 %)" whatever p)
    from mtmc.study import load_result

    monkeypatch.setenv("COLUMNS", "200")
    p, _ = _trace(tmp_path, np.random.default_rng(3))
    argv = ["circle", "evaluate", str(p), "--radius", str(R), "-n", "500", "--seed", "1"]
    argv += ["--columns", "angle=Angle,direction=Dir,deviation=Error"]
    argv += ["--directions", "counter=ccw", "--units", "deg,um", "-o", str(tmp_path / "r")]
    assert main([*argv, "--plots", "0"]) == 0
    out = capsys.readouterr().out
    assert "U (k, p = 95 %)" in out
    assert "note: radius" in out
    rows = {line.split("│")[1].strip(): line for line in out.splitlines() if line.count("│") > 3}
    result = load_result(tmp_path / "r")
    assert sorted(rows) == sorted(q.name for q in result.quantities)
    for q in result.quantities:
        cells = [c.strip() for c in rows[q.name].split("│")[1:-1]]
        assert cells[1:4] == [q.reported.estimate, f"{q.reported.U} (k = {q.mc.k:.3f})", q.unit]


def test_cli_evaluate_is_a_study_with_the_shared_options(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    """circle evaluate runs the circular study of the trace: its folder reruns to the bit."""
    from mtmc.study import load_result, load_study

    p, _ = _trace(tmp_path, np.random.default_rng(4))
    study = tmp_path / "s.toml"
    study.write_text(
        'kind = "circular"\ncolumns = {angle = "Angle", direction = "Dir", deviation = "Error"}\n'
        'directions = {counter = "ccw"}\n'
        f"[path]\nradius = {R}\npoints = 8\n[errors]\nsquareness = 1e-5\n"
        '[ballbar]\nlength_error = "normal(0, 0.0005)"\n'
        "[conformity.G_lsc]\nupper = 50\n[run]\ntrials = 300\nseed = 9\n",
        encoding="utf-8",
    )
    out_dir = tmp_path / "res"
    argv = ["circle", "evaluate", str(p), "--study", str(study), "--json", "-o", str(out_dir)]
    assert main([*argv, "-w", "2"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert (doc["trials"], doc["seed"]) == (300, 9)  # the study's [run]
    assert doc["parameters"]["G_lsc"]["conformity"]["decision"] == "conforms"
    assert "length_error" in {x["name"] for x in load_result(out_dir).inputs}  # its [ballbar]
    # the folder holds the trace and a study that names it: it reruns to the same numbers
    assert any((out_dir / "inputs").iterdir())
    again = load_study(out_dir / "study.toml").run()
    first = load_result(out_dir)
    for a, b in zip(first.quantities, again.quantities, strict=True):
        assert (a.mc.estimate, a.mc.U) == (b.mc.estimate, b.mc.U), a.name
    # without --radius and without a study: one line naming the option
    assert main(["circle", "evaluate", str(p)]) == 2
    assert "--radius" in capsys.readouterr().err


def test_reader_more_errors(tmp_path: Path) -> None:
    ok = "angle,direction,deviation\n0,ccw,1\n90,ccw,2\n180,ccw,3\n270,ccw,4\n"
    # the deviations of both paths, CCW first, in mm (µm in the file)
    np.testing.assert_allclose(loads_circular_csv(ok).deviation, [0.001, 0.002, 0.003, 0.004])
    with pytest.raises(InputError, match=r"directions\.left"):
        loads_circular_csv(ok, directions={"left": "up"})
    with pytest.raises(InputError, match="unknown column 'theta'"):
        loads_circular_csv(ok, columns={"theta": "Angle"})
    with pytest.raises(InputError, match="has none"):
        loads_circular_csv("# only a comment\n")
    with pytest.raises(InputError, match=r"f.csv:3: expected 3 fields, got 2"):
        loads_circular_csv(ok.replace("90,ccw,2", "90,ccw"), "f.csv")
    with pytest.raises(
        InputError,
        match=r"at least 4 readings cw within one turn, got 0 \(2 left out as overrun arcs\)",
    ):
        loads_circular_csv(ok + "360,cw,1\n-5,cw,2\n")
    with pytest.raises(InputError, match="cannot read the file"):
        load_circular_csv(tmp_path / "absent.csv")


@pytest.mark.parametrize(
    ("row", "field", "words"),
    [
        ("90,ccw,1_0", "deviation", "digits 0-9"),  # Python's float would take it
        ("90,ccw,nan", "deviation", "digits 0-9"),
        ("90,ccw,1e400", "deviation", "at most 1.8e+308"),
        ("90,ccw,2e9", "deviation", "at most 1e+09 in size"),  # µm: a kilometre
        ("1e5,ccw,2", "angle", "at most 3600 in size"),  # deg: ten turns
        ("٩٠,ccw,2", "angle", "digits 0-9"),  # Arabic-Indic digits
    ],
)
def test_reader_reads_numbers_as_every_csv_reader_does(row: str, field: str, words: str) -> None:
    """One number rule for the readings of ISO 230-2 and of ISO 230-4 (mtmc.csvtable)."""
    ok = "Angle,Dir,Error\n0,ccw,1\n90,ccw,2\n180,ccw,3\n270,ccw,4\n"
    mapped = {"angle": "Angle", "direction": "Dir", "deviation": "Error"}
    bad = ok.replace("90,ccw,2", row)
    name = mapped[field]
    with pytest.raises(InputError, match=rf"f\.csv:3: field {name}: expected .*{re.escape(words)}"):
        loads_circular_csv(bad, "f.csv", columns=mapped)


def _arc(angles: np.ndarray, direction: str) -> str:
    """A trace whose deviation is a function of the angle modulo 360°: 2 cos θ + sin 3θ µm."""
    t = np.radians(angles)
    dev = 2 * np.cos(t) + np.sin(3 * t)
    rows = [f"{a:.10g},{direction},{d:.15g}" for a, d in zip(angles, dev, strict=True)]
    return "angle,direction,deviation\n" + "\n".join(rows) + "\n"


ARC_STEP = 2.5
TURN = np.arange(0.0, 360.0, ARC_STEP)  # the evaluated turn, 144 readings
WANT = 1e-3 * (2 * np.cos(np.radians(TURN)) + np.sin(3 * np.radians(TURN)))


@pytest.mark.parametrize(
    ("angles", "direction", "overrun", "left"),
    [
        # a clockwise path exported through negative angles, 0 down to -357.5°
        (-TURN, "cw", None, 0),
        # the closing reading at 360°, the first point read again
        (np.arange(0.0, 360.0 + ARC_STEP, ARC_STEP), "ccw", None, 1),
        # overrun arcs of 45° at each end, the default reading of equal arcs
        (np.arange(-45.0, 405.0 + ARC_STEP, ARC_STEP), "ccw", None, 37),
        (np.arange(45.0, -405.0 - ARC_STEP, -ARC_STEP), "cw", None, 37),
        # an overrun of 10° at the start of travel and 30° after
        (np.arange(-10.0, 390.0, ARC_STEP), "ccw", 10.0, 16),
        (np.arange(10.0, -390.0, -ARC_STEP), "cw", 10.0, 16),
    ],
)
def test_the_overrun_arcs_are_read_and_left_out(angles, direction, overrun, left) -> None:
    """The evaluated turn is the same 144 readings whichever way the export writes it."""
    t = loads_circular_csv(_arc(angles, direction), "o.csv", overrun=overrun)
    theta = getattr(t, f"theta_{direction}")
    np.testing.assert_allclose(np.degrees(theta), TURN, atol=1e-9)
    # the deviations are those of their angle: 1e-15 mm, the rounding of 15 digits
    np.testing.assert_allclose(getattr(t, direction), WANT, atol=1e-15)
    assert t.overrun == ({direction: left} if left else {})


def test_an_overrun_out_of_range_or_a_repeat_within_the_turn_is_refused() -> None:
    text = _arc(TURN, "ccw")
    for bad in (-1.0, 360.0, float("nan")):
        with pytest.raises(InputError, match=r"overrun arc in \[0, 360\)") as err:
            loads_circular_csv(text, overrun=bad)
        assert err.value.field == "overrun"
    # within one turn an angle is read once: a repeat names both lines
    twice = _arc(np.array([-10.0, 10.0, 100.0, 200.0, 100.0, 300.0]), "ccw")
    with pytest.raises(InputError, match="second reading at 100 deg ccw") as err:
        loads_circular_csv(twice, "t.csv", overrun=20.0)
    assert err.value.line == 6
    assert "line 4" in str(err.value)
