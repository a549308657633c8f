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
    assert main(["verify", "plan", str(study), "-o", str(tmp_path / "nope")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert not list(tmp_path.glob("mesh96*"))
