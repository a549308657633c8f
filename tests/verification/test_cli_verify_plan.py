"""``mtmc verify plan``: the CLI writes what the library computes; errors are one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from mtmc.cli.main import main
from mtmc.verification.ncprogram import NCSettings, estimate_time, iso_program
from mtmc.verification.workspace import MeasurementPlan, mesh

STUDY = """\
machine = "XFYZ"

[workspace]
distribution = "mesh"
sequence = "ZYX"
[workspace.X]
start = 0
end = 2500
step = 500
[workspace.Y]
start = 0
end = 1500
step = 500
[workspace.Z]
start = 0
end = 1200
step = 400

[nc]
format = ["iso", "heidenhain"]
feed = 2000
dwell = 6
acceleration = 500
output = "mesh96"
"""


def test_plan_writes_the_programs_and_the_estimate(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    study = tmp_path / "study.toml"
    study.write_text(STUDY)
    out = tmp_path / "out"
    out.mkdir()
    assert main(["verify", "plan", str(study), "-o", str(out), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    plan = MeasurementPlan(
        ("X", "Y", "Z"), mesh([0, 0, 0], [2500, 1500, 1200], step=[500, 500, 400]), kind="mesh"
    )
    settings = NCSettings(feed=2000.0, dwell=6.0, acceleration=500.0, output="mesh96")
    est = estimate_time(plan, settings)
    assert data["points"] == 96
    assert data["measurements"] == 96
    assert data["axes"] == ["X", "Y", "Z"]
    assert data["time"]["dwell_s"] == 576.0
    assert np.isclose(data["time"]["travel_s"], est.travel_s, rtol=1e-12)
    assert (out / "mesh96.nc").read_text() == iso_program(plan, settings)
    assert (out / "mesh96.h").read_text().startswith("0 BEGIN PGM MTMCVERIF MM\n")
    assert set(data["files"]) == {"iso", "heidenhain", "points"}
    assert main(["verify", "plan", str(study), "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "96 points (mesh, axes X Y Z)" in text
    assert "dwell 9.6 min" in text


def test_plan_errors_are_one_line(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    study = tmp_path / "study.toml"
    study.write_text(STUDY.replace("feed = 2000", "feed = 0"))
    assert main(["verify", "plan", str(study), "-o", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"mtmc: error: {study}:21: field nc.feed: expected a number > 0, got 0"]
    study.write_text(STUDY.replace('machine = "XFYZ"', 'machine = "XFYQ"'))
    assert main(["verify", "plan", str(study), "-o", str(tmp_path)]) == 2
    assert f"{study}:1: field machine:" in capsys.readouterr().err
    study.write_text(STUDY.replace('machine = "XFYZ"', 'machine = "CXFYZ"'))
    assert main(["verify", "plan", str(study), "-o", str(tmp_path)]) == 2
    assert "missing [workspace.C]" in capsys.readouterr().err
    study.write_text(STUDY)
    assert not list(tmp_path.glob("mesh96*"))


SHIPPED = Path(__file__).resolve().parents[2] / "examples" / "studies" / "aguado2016.toml"


def _boustrophedon(xs: list[float], ys: list[float], zs: list[float]) -> list[tuple[float, ...]]:
    """The Z-Y-X serpentine written out by hand: Z moves first, every other pass reversed."""
    out: list[tuple[float, ...]] = []
    for i, x in enumerate(xs):
        for j, y in enumerate(ys[::-1] if i % 2 else ys):
            column = zs[::-1] if (i * len(ys) + j) % 2 else zs
            out.extend((x, y, z) for z in column)
    return out


def _dwell_positions(
    blocks: list[str], words: dict[str, str], dwell: str
) -> list[tuple[float, ...]]:
    """The modal axis positions at each dwell of a program (axes left out keep their value)."""
    pos = {a: float("nan") for a in "XYZ"}
    seen = []
    for block in blocks:
        if dwell in block:
            seen.append(tuple(pos[a] for a in "XYZ"))
        elif block.startswith(words["move"]):
            for word in block.split()[1:]:
                if word[0] in pos:
                    pos[word[0]] = float(word[1:])
    return seen


def test_the_shipped_aguado2016_study_plans_its_96_point_mesh(
    tmp_path: Path, capsys, monkeypatch
) -> None:  # type: ignore[no-untyped-def]
    from mtmc.study import load_study

    monkeypatch.chdir(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    assert main(["verify", "plan", str(SHIPPED), "-o", str(out), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert (data["points"], data["measurements"], data["distribution"]) == (96, 96, "mesh")
    # 96 dwells of 6 s (the paper's stabilisation time) at the feed that gives its 25 min
    assert data["time"]["dwell_s"] == 96 * 6.0
    assert abs(data["time"]["total_s"] / 60.0 - 25.0) < 0.5
    names = ["aguado2016_mesh96.h", "aguado2016_mesh96.nc", "aguado2016_mesh96_points.csv"]
    assert sorted(p.name for p in out.iterdir()) == names  # no temporary left
    assert list(tmp_path.iterdir()) == [out]  # nothing beside the output folder

    expected = _boustrophedon(
        [0, 500, 1000, 1500, 2000, 2500], [0, 500, 1000, 1500], [0, 400, 800, 1200]
    )
    assert expected[0] == (0, 0, 0)
    assert expected[-1] == (2500, 0, 0)  # an even number of X passes ends on Y 0, Z 0

    iso = (out / "aguado2016_mesh96.nc").read_text().splitlines()
    g01 = [b for b in iso if b.startswith("G01")]
    assert len(g01) == 96
    assert g01[0] == "G01 X0.000 Y0.000 Z0.000 F2630.0"
    assert g01[-1] == "G01 Z0.000"  # modal: only the axis that moves
    assert g01[-2] == "G01 Z400.000"
    assert (iso[0], iso[1], iso[-2], iso[-1]) == (
        "%",
        "O2016 (MTMC VOLUMETRIC VERIFICATION)",
        "M30",
        "%",
    )
    assert "G21 G90 G94" in iso
    assert _dwell_positions(iso, {"move": "G01"}, "G04 P6000") == expected

    hh = [b.split(" ", 1)[1] for b in (out / "aguado2016_mesh96.h").read_text().splitlines()]
    assert (hh[0], hh[-1]) == ("BEGIN PGM AGUADO2016 MM", "END PGM AGUADO2016 MM")
    moves = [b for b in hh if b.startswith("L ")]
    assert (moves[0], moves[-1]) == ("L X+0.000 Y+0.000 Z+0.000 R0 F2630", "L Z+0.000 R0 F2630")
    assert _dwell_positions(hh, {"move": "L "}, "CYCL DEF 9.1 DWELL 6") == expected

    rows = (out / "aguado2016_mesh96_points.csv").read_text().splitlines()
    table = [r.split(",") for r in rows if not r.startswith("#")][1:]
    assert [tuple(float(v) for v in r[3:6]) for r in table] == expected
    # the plan measures the study's own point set [points.mesh96], in its order
    study = load_study(SHIPPED).study
    assert np.array_equal(study.points["mesh96"].q, np.array(expected, dtype=float))


def test_the_shipped_plan_leaves_old_programs_whole_when_a_write_fails(
    tmp_path: Path, capsys, monkeypatch
) -> None:  # type: ignore[no-untyped-def]
    import os

    old = tmp_path / "aguado2016_mesh96.h"
    old.write_text("old program")
    replace = os.replace

    def full_disk(src, dst):  # type: ignore[no-untyped-def]
        if str(dst).endswith(".h"):
            raise OSError(28, "No space left on device")
        replace(src, dst)

    monkeypatch.setattr(os, "replace", full_disk)
    assert main(["verify", "plan", str(SHIPPED), "-o", str(tmp_path)]) == 2
    assert "cannot write: No space left on device" in capsys.readouterr().err
    assert old.read_text() == "old program"
    assert sorted(p.name for p in tmp_path.iterdir()) == [old.name, "aguado2016_mesh96.nc"]
