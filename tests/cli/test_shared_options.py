"""The options every Monte Carlo command shares, and pointers to the command that reads a file."""

from __future__ import annotations

import json
import math
import re
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


def test_an_unknown_point_set_names_the_study_file_and_the_option(
    capsys: pytest.CaptureFixture[str],
) -> None:
    study = ROOT / "examples" / "studies" / "aguado2017.toml"
    assert main(["verify", "simulate", str(study), "--points", "nope", "-n", "2"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (f"mtmc: error: {study}: field --points: no point set 'nope'; the study has mesh")


def test_verify_plan_creates_its_output_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study = ROOT / "examples" / "studies" / "aguado2016.toml"
    out = tmp_path / "a" / "b"  # neither exists, as run -o creates its folder
    assert main(["verify", "plan", str(study), "-o", str(out), "--json"]) == 0
    files = json.loads(capsys.readouterr().out)["files"]
    assert files
    assert all(Path(f).parent == out and Path(f).is_file() for f in files.values())


def _two_poses(tmp_path: Path) -> Path:
    """The shipped artefact study (Wang, Cheung and Kong 2022) at two of its nine poses.

    22 quantities where the shipped study has 36: its report draws 44 plots, not 72.
    """
    text = (ROOT / "examples" / "studies" / "wang2022.toml").read_text(encoding="utf-8")
    text, n = re.subn(r"(?m)^poses_deg = .*$", "poses_deg = [[0, 0], [-10, 5]]", text)
    assert n == 1
    path = tmp_path / "wang2022_two_poses.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_artefact_simulate_runs_the_study_as_run_does_and_writes_its_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One route: `artefact simulate -o` writes the numbers of the study the library runs
    (which `mtmc run` is), the trials left out and the blocks come from the study's run
    record, the JSON names µm."""
    from mtmc.study import load_study

    study = str(_two_poses(tmp_path))
    a = tmp_path / "a" / "sim"
    argv = ["artefact", "simulate", study, "-n", "40", "-s", "2", "-o", str(a), "--json"]
    assert main(argv) == 0, capsys.readouterr().err
    got = json.loads(capsys.readouterr().out)
    assert got["unit"] == "µm"
    assert got["output"] == str(a)
    assert got["run"] == {
        "adaptive": False,
        "trials": 40,
        "omitted": 0,
        "nan_policy": "raise",
        "ndig": 2,
    }
    one = json.loads((a / "result.json").read_text())
    two = json.loads(json.dumps(load_study(study).run(trials=40, seed=2).to_dict()))
    # the same seeded draws and reductions: equal to the bit
    assert one["quantities"] == two["quantities"]
    assert (a / "report.html").is_file()
    by_name = {q["name"]: q["monte_carlo"] for q in one["quantities"]}
    # the quantity's u is reduced from the samples again (MonteCarloResult), the table's
    # by the engine: the same values summed in another order, so to a few ulp
    assert by_name["setup.dpx"]["u"] == pytest.approx(got["setup_errors"]["dpx"]["u"], rel=1e-14)
    assert main([*argv[:-1], "--no-gum"]) == 2
    assert "not with --no-gum" in capsys.readouterr().err


def _trace(tmp_path: Path) -> Path:
    """A circular trace of 36 points a direction: a centre offset of 2 µm along x."""
    rows = [
        f"{a},{d},{2 * math.cos(math.radians(a)):.6f}"
        for d in ("ccw", "cw")
        for a in range(0, 360, 10)
    ]
    p = tmp_path / "trace.csv"
    p.write_text("angle,direction,deviation\n" + "\n".join(rows) + "\n", encoding="utf-8")
    return p


@pytest.mark.parametrize(
    "argv",
    [
        ["circle", "simulate", "examples/studies/circle_c_axis.toml"],
        ["circle", "evaluate", "TRACE", "--radius", "150"],
        [
            "positioning",
            "evaluate",
            "examples/studies/positioning_x.csv",
            "--study",
            "examples/studies/positioning_x.toml",
        ],
        ["artefact", "simulate", "ARTEFACT"],
    ],
    ids=lambda a: " ".join(a[:2]),
)
def test_every_study_command_takes_quiet(
    argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """-q means what it means to mtmc run: no table, no bar; the trials and seed, how the
    run went, the JCGM 106 decisions and the report."""
    argv = [str(_trace(tmp_path)) if a == "TRACE" else a for a in argv]
    argv = [str(_two_poses(tmp_path)) if a == "ARTEFACT" else a for a in argv]
    argv = [str(ROOT / a) if a.startswith("examples/") else a for a in argv]
    out_dir = tmp_path / "r"
    # the report without histograms (--plots 0): what -q prints does not depend on them,
    # and they were 22 of the 25 s of these four runs
    same = ["-n", "40", "-s", "3", "-q", "--progress", "--plots", "0"]
    assert main([*argv, *same, "-o", str(out_dir)]) == 0
    out, err = capsys.readouterr()
    lines = out.splitlines()
    assert lines[0] == "trials 40  seed 3"
    assert lines[-1] == f"report: {out_dir / 'report.html'}"
    assert "trials" not in err  # -q turns the bar off, --progress or not
    # between them a decision for each output with [conformity] (the shipped circular and
    # positioning studies have some), in the order of result.json, with what it decided
    doc = json.loads((out_dir / "result.json").read_text(encoding="utf-8"))
    decided = [(q["name"], q["conformity"]) for q in doc["quantities"] if q.get("conformity")]
    assert len(lines) == len(decided) + 2
    for line, (name, c) in zip(lines[1:-1], decided, strict=True):
        assert line.startswith(f"conformity of {name} (JCGM 106): {c['text']}; {name} = ")
    # and mtmc run of the same study file prints the same lines
    study = next((a for a in argv if a.endswith(".toml")), None)
    if study is not None:
        assert main(["run", study, *same, "-o", str(tmp_path / "run")]) == 0
        assert capsys.readouterr().out.splitlines()[:-1] == lines[:-1]


#: One command line of each command that writes a result folder with a report (``-o``);
#: TRACE and ARTEFACT are written by the test.
REPORT_COMMANDS = {
    "run": ["run", "examples/studies/ball_centre.toml"],
    "propagate": ["propagate", "a * b", "-i", "a=normal(2, 0.1)", "-i", "b=normal(3, 0.2)"],
    "artefact simulate": ["artefact", "simulate", "ARTEFACT"],
    "verify simulate": ["verify", "simulate", "examples/studies/aguado2017.toml"],
    "positioning evaluate": [
        "positioning",
        "evaluate",
        "examples/studies/positioning_x.csv",
        "--study",
        "examples/studies/positioning_x.toml",
    ],
    "circle simulate": ["circle", "simulate", "examples/studies/circle_c_axis.toml"],
    "circle evaluate": ["circle", "evaluate", "TRACE", "--radius", "150"],
}


@pytest.mark.parametrize("name", sorted(REPORT_COMMANDS))
def test_every_command_that_writes_a_report_takes_plots(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """--plots N|all means what it means to mtmc report: the first N quantities drawn."""
    argv = REPORT_COMMANDS[name]
    argv = [str(_trace(tmp_path)) if a == "TRACE" else a for a in argv]
    argv = [str(_two_poses(tmp_path)) if a == "ARTEFACT" else a for a in argv]
    argv = [str(ROOT / a) if a.startswith("examples/") else a for a in argv]
    out_dir = tmp_path / "r"
    # a bad count: one line, exit 2, before anything runs or is written
    assert main([*argv, "-n", "20", "-s", "3", "-o", str(out_dir), "--plots", "some"]) == 2
    err = capsys.readouterr().err
    assert err == "mtmc: error: --plots: expected a whole number >= 0 or 'all', got 'some'\n"
    assert not out_dir.exists()
    assert main([*argv, "-n", "20", "-s", "3", "-o", str(out_dir), "-q", "--plots", "1"]) == 0
    capsys.readouterr()
    n = len(json.loads((out_dir / "result.json").read_text(encoding="utf-8"))["quantities"])
    page = (out_dir / "report.html").read_text(encoding="utf-8")
    drawn = 1 if n else 0
    assert page.count('data-plot="histogram:') == drawn, name
    assert page.count('class="unplotted"') == n - drawn, name
