"""NC programs (ISO G-code, Heidenhain conversational), the points table, the time estimate."""

from __future__ import annotations

import csv
import math
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from mtmc.errors import InputError
from mtmc.verification.ncprogram import (
    NCSettings,
    estimate_time,
    heidenhain_program,
    iso_program,
    nc_from_dict,
    points_table,
    trapezoid_time,
    write_programs,
)
from mtmc.verification.workspace import MeasurementPlan, cloud, mesh

LO = np.array([0.0, 0.0, 0.0])
HI = np.array([2500.0, 1500.0, 1200.0])


def _plan(**kw: object) -> MeasurementPlan:
    rng = np.random.default_rng(np.random.SeedSequence(96))
    return MeasurementPlan(("X", "Y", "Z"), cloud(LO, HI, rng, step=[500, 500, 400]), **kw)  # type: ignore[arg-type]


def read_iso(text: str) -> tuple[np.ndarray, list[float], list[int]]:
    """A small G-code reader: modal absolute positions after each G01, dwells, stops.

    Returns the positions of the moves (K, 3), the dwell (s) following each move (0 if
    none) and the indices of the moves after which an M00 stops the program.
    """
    pos = {"X": math.nan, "Y": math.nan, "Z": math.nan}
    moves: list[list[float]] = []
    dwell: list[float] = []
    stops: list[int] = []
    assert text.startswith("%\nO")
    assert text.endswith("M30\n%\n")
    for line in text.splitlines():
        code = re.sub(r"\(.*?\)", "", line).strip()
        if not code or code == "%" or code.startswith("O"):
            continue
        words = dict((w[0], w[1:]) for w in code.split())
        if code.startswith("G01"):
            for a in "XYZ":
                if a in words:
                    assert "." in words[a]  # a decimal point: never least increments
                    pos[a] = float(words[a])
            moves.append([pos["X"], pos["Y"], pos["Z"]])
            dwell.append(0.0)
        elif code.startswith("G04"):
            assert dwell[-1] == 0.0
            dwell[-1] = int(words["P"]) / 1000.0 if "P" in words else float(words["X"])
        elif code.startswith("M00"):
            stops.append(len(moves) - 1)
    return np.array(moves), dwell, stops


def test_iso_program_parses_back_to_the_plan() -> None:
    plan = _plan(offsets=[[0, 0, 0], [0, 0, 100]], overshoot=[50, 25, 15], approach=[1, 1, -1])
    s = NCSettings(feed=2000.0, dwell=6.0, program=2016)
    text = iso_program(plan, s)
    assert text.splitlines()[1].startswith("O2016 (")
    assert "G21 G90 G94" in text
    assert text.count("F2000.0") == 1
    moves, dwell, stops = read_iso(text)
    np.testing.assert_allclose(moves, plan.moves, atol=5e-4)  # 3 decimals
    measured = np.array(dwell) > 0
    np.testing.assert_array_equal(measured, plan.move_point >= 0)
    assert set(np.array(dwell)[measured]) == {6.0}
    np.testing.assert_allclose(moves[measured], plan.measurement_positions, atol=5e-4)
    assert stops == [int(np.flatnonzero(plan.move_offset == 1)[0]) - 1]
    # the X dwell word, in seconds
    _moves_x, dwell_x, _ = read_iso(iso_program(plan, NCSettings(feed=2000.0, dwell_word="X")))
    np.testing.assert_array_equal(dwell_x, dwell)


def test_heidenhain_program_structure() -> None:
    plan = _plan(offsets=[[0, 0, 0], [0, 0, 100]])
    s = NCSettings(feed=1500.0, dwell=6.0, name="VERIF96")
    lines = heidenhain_program(plan, s).splitlines()
    assert [int(ln.split()[0]) for ln in lines] == list(range(len(lines)))
    body = [ln.split(" ", 1)[1] for ln in lines]
    assert body[0] == "BEGIN PGM VERIF96 MM"
    assert body[-1] == "END PGM VERIF96 MM"
    moves = [b for b in body if b.startswith("L ")]
    assert len(moves) == plan.moves.shape[0] == 192
    pos = {"X": math.nan, "Y": math.nan, "Z": math.nan}
    got = []
    for i, b in enumerate(body):
        if b.startswith("L "):
            assert b.endswith(" R0 F1500")
            for w in b.split()[1:-2]:
                assert w[1] in "+-"  # Heidenhain writes the sign
                pos[w[0]] = float(w[1:])
            got.append([pos["X"], pos["Y"], pos["Z"]])
            # the dwell cycle follows every measuring move
            assert body[i + 1] == "CYCL DEF 9.0 DWELL TIME"
            assert body[i + 2] == "CYCL DEF 9.1 DWELL 6"
    np.testing.assert_allclose(got, plan.moves, atol=5e-4)
    assert body.count("STOP") == 1
    assert body.count("CYCL DEF 9.0 DWELL TIME") == plan.n_measurements


def test_points_table_matches_the_program(tmp_path: Path) -> None:
    plan = _plan(offsets=[[0, 0, 0], [10, 0, 100]])
    s = NCSettings(feed=2000.0, dialects=("iso", "heidenhain"), output="v96")
    files = write_programs(plan, s, tmp_path)
    assert sorted(p.name for p in files.values()) == ["v96.h", "v96.nc", "v96_points.csv"]
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temp files left
    rows = list(
        csv.reader(
            line for line in files["points"].read_text().splitlines() if not line.startswith("#")
        )
    )
    assert rows[0] == [
        "measurement",
        "point",
        "offset",
        "X",
        "Y",
        "Z",
        "offset_x",
        "offset_y",
        "offset_z",
    ]
    table = np.array(rows[1:], dtype=float)
    assert table.shape == (192, 9)
    np.testing.assert_array_equal(table[:, 0], np.arange(1, 193))
    np.testing.assert_array_equal(table[:, 1], np.tile(np.arange(1, 97), 2))
    np.testing.assert_array_equal(table[:, 2], np.repeat([1, 2], 96))
    moves, dwell, _ = read_iso(files["iso"].read_text())
    np.testing.assert_allclose(table[:, 3:6], moves[np.array(dwell) > 0], atol=0)
    np.testing.assert_array_equal(table[96:, 6:], np.tile([10.0, 0.0, 100.0], (96, 1)))
    assert points_table(plan) != points_table(plan, s)  # the programs are named with settings


def test_trapezoid_formula() -> None:
    v, a = 2000.0 / 60.0, 500.0
    # cruise: d/v + v/a; triangle: 2 sqrt(d/a); continuous at d = v^2/a
    assert float(trapezoid_time(400.0, v, a)) == pytest.approx(400.0 / v + v / a, rel=1e-15)
    assert float(trapezoid_time(1.0, v, a)) == pytest.approx(2.0 * math.sqrt(1.0 / a), rel=1e-15)
    d0 = v * v / a
    assert float(trapezoid_time(d0 * (1 - 1e-12), v, a)) == pytest.approx(
        float(trapezoid_time(d0, v, a)), rel=1e-9
    )
    # by integration of the velocity profile
    t_end = float(trapezoid_time(400.0, v, a))
    t = np.linspace(0.0, t_end, 200_001)
    vel = np.minimum(np.minimum(a * t, v), a * (t_end - t))
    assert np.trapezoid(vel, t) == pytest.approx(400.0, rel=1e-6)
    with pytest.raises(InputError):
        trapezoid_time(1.0, 0.0, a)


def test_time_of_the_96_point_mesh_by_hand() -> None:
    # serpentine Z, Y, X: 24 columns of 3 Z moves of 400 mm, 18 Y moves and 5 X moves of 500 mm
    plan = MeasurementPlan(("X", "Y", "Z"), mesh(LO, HI, step=[500, 500, 400]))
    F, a, dwell = 2000.0, 500.0, 6.0
    v = F / 60.0
    hand = 72 * (400.0 / v + v / a) + 23 * (500.0 / v + v / a)
    est = estimate_time(plan, NCSettings(feed=F, dwell=dwell, acceleration=a))
    assert est.n_moves == 95
    assert est.path_length_mm == pytest.approx(40300.0)
    assert est.travel_s == pytest.approx(hand, rel=1e-12)
    assert est.dwell_s == 96 * 6.0
    assert est.total_s == pytest.approx(576.0 + hand, rel=1e-12)
    # Aguado et al. 2016 give 25 min for the 96 points at 6 s dwell: dwell alone is 9.6
    # min, so about 15.4 min of travel, which this path makes at about 2630 mm/min
    est25 = estimate_time(plan, NCSettings(feed=2630.0, dwell=dwell, acceleration=a))
    assert est25.total_s / 60.0 == pytest.approx(25.0, abs=0.5)


def test_time_of_the_5408_point_mesh() -> None:
    # Aguado et al. 2016: 5408 points at 6 s "approximately 9 hours" of measuring
    plan = MeasurementPlan(("X", "Y", "Z"), mesh(LO, HI, step=100.0))
    est = estimate_time(plan, NCSettings(feed=2000.0, dwell=6.0, acceleration=500.0))
    assert est.n_measurements == 5408
    assert est.dwell_s == 32448.0
    assert est.dwell_s / 3600.0 == pytest.approx(9.0, abs=0.02)
    # 5407 moves of 100 mm: 100/v + v/a each
    v = 2000.0 / 60.0
    assert est.travel_s == pytest.approx(5407 * (100.0 / v + v / 500.0), rel=1e-12)
    assert est.to_dict()["total_h"] == pytest.approx((32448.0 + est.travel_s) / 3600.0)


def test_time_models_path_and_axes() -> None:
    plan = MeasurementPlan(("X", "Y"), [[0.0, 0.0], [300.0, 400.0], [300.0, 401.0]])
    F, a = 3000.0, 200.0
    v = F / 60.0
    path = estimate_time(plan, NCSettings(feed=F, dwell=0.0, acceleration=a))
    t_tri = 2 * math.sqrt(1.0 / a)
    assert path.travel_s == pytest.approx(500.0 / v + v / a + t_tri)
    axes = estimate_time(
        plan,
        NCSettings(
            feed=F,
            dwell=0.0,
            acceleration=a,
            time_model="axes",
            axis_feed={"X": 6000.0},
            axis_acceleration={"Y": 100.0},
        ),
    )
    tx = 300.0 / 100.0 + 100.0 / a  # X at 6000 mm/min
    ty = 400.0 / v + v / 100.0  # Y at the feed, 100 mm/s²
    assert axes.travel_s == pytest.approx(max(tx, ty) + 2 * math.sqrt(1.0 / 100.0))
    rot = MeasurementPlan(("X", "C"), [[0.0, 0.0], [10.0, 1.0]])
    with pytest.raises(InputError, match="rotary axis C moves"):
        estimate_time(rot, NCSettings(feed=F))
    with pytest.raises(InputError, match="rotary axis C needs its own feed") as info:
        estimate_time(rot, NCSettings(feed=F, time_model="axes"))
    assert info.value.field == "axis_feed.C"
    # C at 2 rad/s (120 rad/min), 10 rad/s²: the X move (10 mm) is the slower one
    both = NCSettings(
        feed=F,
        time_model="axes",
        axis_feed={"C": 120.0},
        axis_acceleration={"C": 10.0},
        acceleration=a,
    )
    tx, tc = float(trapezoid_time(10.0, v, a)), float(trapezoid_time(1.0, 2.0, 10.0))
    assert estimate_time(rot, both).travel_s == pytest.approx(max(tx, tc))
    # a rotary axis that stays put is allowed in the path model
    still = MeasurementPlan(("X", "C"), [[0.0, 0.5], [300.0, 0.5]])
    assert estimate_time(still, NCSettings(feed=F, acceleration=a)).travel_s == pytest.approx(
        300.0 / v + v / a
    )


@pytest.mark.parametrize(
    ("kw", "field"),
    [
        ({"feed": 0.0}, "feed"),
        ({"feed": -5.0}, "feed"),
        ({"feed": math.nan}, "feed"),
        ({"feed": 100.0, "dwell": -1.0}, "dwell"),
        ({"feed": 100.0, "acceleration": 0.0}, "acceleration"),
        ({"feed": 100.0, "dwell_word": "Q"}, "dwell_word"),
        ({"feed": 100.0, "program": 0}, "program"),
        ({"feed": 100.0, "name": "MY PROG"}, "name"),
        ({"feed": 100.0, "dialects": ("iso", "fanuc")}, "format"),
        ({"feed": 100.0, "time_model": "fast"}, "time_model"),
    ],
)
def test_settings_validation(kw: dict[str, object], field: str) -> None:
    with pytest.raises(InputError) as info:
        NCSettings(**kw)  # type: ignore[arg-type]
    assert info.value.field == field


NC = """\
[nc]
format = ["iso", "heidenhain"]
feed = 2000
dwell = 6
dwell_word = "X"
program = 96
acceleration = 400
time_model = "axes"
[nc.axis_feed]
X = 10000
"""


def test_nc_table() -> None:
    s = nc_from_dict(tomllib.loads(NC), "s.toml", text=NC, axes=("X", "Y", "Z"))
    assert s.dialects == ("iso", "heidenhain")
    assert s.dwell_word == "X"
    assert s.program == 96
    assert s.axis_feed == {"X": 10000.0}
    assert s.acceleration == 400.0


@pytest.mark.parametrize(
    ("edit", "line", "field"),
    [
        (("feed = 2000", "feed = 0"), 3, "nc.feed"),
        (("dwell = 6", "dwell = -6"), 4, "nc.dwell"),
        (('dwell_word = "X"', 'dwell_word = "Q"'), 5, "nc.dwell_word"),
        (("program = 96", "program = 10000"), 6, "nc.program"),
        (('format = ["iso", "heidenhain"]', 'format = "siemens"'), 2, "nc.format"),
        (("X = 10000", "C = 10000"), 10, "nc.axis_feed.C"),
        (("acceleration = 400", "accel = 400"), 7, "nc.accel"),
    ],
)
def test_nc_errors_name_line_and_field(edit: tuple[str, str], line: int, field: str) -> None:
    text = NC.replace(*edit)
    with pytest.raises(InputError) as info:
        nc_from_dict(tomllib.loads(text), "s.toml", text=text, axes=("X", "Y", "Z"))
    assert (info.value.file, info.value.line, info.value.field) == ("s.toml", line, field)
