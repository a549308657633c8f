"""The options every Monte Carlo command shares, and pointers to the command that reads a file."""

from __future__ import annotations

from pathlib import Path

import pytest

from mtmc.cli.main import main

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("flag", ["--no-progress", "--progress", "-q"])
def test_run_takes_progress_and_quiet(
    flag: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study = ROOT / "examples" / "studies" / "mass_calibration.toml"
    argv = ["run", str(study), "-n", "200", "-s", "1", "-o", str(tmp_path / "r"), flag]
    assert main(argv) == 0, capsys.readouterr().err
    out, err = capsys.readouterr()
    assert out.splitlines()[-1] == f"report: {tmp_path / 'r' / 'report.html'}"
    assert ("200/200 trials" in err) == (flag == "--progress")


@pytest.mark.parametrize(
    ("path", "pointer"),
    [
        ("examples/graphs/ball_centre.toml", "is a measurement graph: run it with mtmc graph run"),
        (
            "examples/artefacts/wang2022_five_ball.toml",
            'an artefact study names it (kind = "artefact"',
        ),
    ],
)
def test_run_on_a_file_that_is_no_study_names_its_reader(
    path: str, pointer: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["run", str(ROOT / path), "-o", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "missing kind" in err
    assert pointer in err
