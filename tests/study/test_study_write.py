"""The result folder: its files, provenance, and that a failed or killed run leaves none."""

from __future__ import annotations

import hashlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import mtmc
from mtmc.cli.main import main
from mtmc.errors import InputError
from mtmc.study import load_study, write_result

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "examples" / "studies"


def test_cli_run_writes_the_folder_the_library_computes(tmp_path, capsys):
    study = STUDIES / "mass_calibration.toml"
    out = tmp_path / "mass"
    argv = ["run", str(study), "-o", str(out), "--trials", "5000", "--seed", "11", "--samples"]
    assert main(argv) == 0
    printed = capsys.readouterr().out.strip().splitlines()
    assert printed[-1] == f"report: {out / 'report.html'}"
    names = sorted(p.name for p in out.iterdir())
    assert names == [
        "budget.csv",
        "provenance.json",
        "quantities.csv",
        "report.html",
        "result.json",
        "samples",
        "study.toml",
    ]
    result = json.loads((out / "result.json").read_text(encoding="utf-8"))
    lib = load_study(study).run(trials=5000, seed=11, samples=True)
    assert result == json.loads(json.dumps(lib.to_dict()))
    np.testing.assert_array_equal(np.load(out / "samples" / "dm.npy"), lib.samples["dm"])
    # the table printed is the library's rounding
    q = lib.quantity("dm")
    assert any(q.reported.estimate in ln and q.reported.U in ln for ln in printed)
    prov = json.loads((out / "provenance.json").read_text(encoding="utf-8"))
    assert prov["mtmc_version"] == mtmc.__version__
    assert prov["seed"] == 11
    assert prov["seed_entropy"] == str(np.random.SeedSequence(11).entropy)
    assert prov["study_sha256"] == hashlib.sha256(study.read_bytes()).hexdigest()
    assert prov["command_line"] == ["mtmc", *argv]
    assert prov["started"] <= prov["finished"]
    assert prov["libraries"]["numpy"] == np.__version__
    assert (out / "study.toml").read_text() == study.read_text()
    csv_lines = (out / "quantities.csv").read_text().splitlines()
    assert csv_lines[0].startswith("quantity,unit,estimate,u,U")
    assert float(csv_lines[1].split(",")[3]) == q.mc.u


def test_report_command_renders_again(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["run", str(STUDIES / "ball_centre.toml"), "-o", str(out), "-n", "2000", "-q"]) == 0
    (out / "report.html").unlink()
    assert main(["report", str(out)]) == 0
    assert (out / "report.html").is_file()
    assert main(["report", str(tmp_path)]) == 2
    assert "no result.json" in capsys.readouterr().err


def test_a_run_without_seed_records_the_fresh_one():
    r = load_study(STUDIES / "ball_centre.toml")
    a = r.run(trials=1000, seed=None)
    b = r.run(trials=1000, seed=a.seed)
    assert a.to_dict() == b.to_dict()


def test_failure_while_writing_leaves_nothing(tmp_path, monkeypatch):
    import importlib

    report = importlib.import_module("mtmc.report")

    result = load_study(STUDIES / "ball_centre.toml").run(trials=1000, seed=1)

    def boom(_folder, **_options):
        raise RuntimeError("disk full")

    monkeypatch.setattr(report, "render", boom)
    with pytest.raises(RuntimeError):
        write_result(result, tmp_path / "out")
    assert list(tmp_path.iterdir()) == []


def test_an_old_result_is_replaced_and_other_folders_are_refused(tmp_path):
    result = load_study(STUDIES / "ball_centre.toml").run(trials=1000, seed=1)
    out = write_result(result, tmp_path / "out", report=False)
    (out / "stale.txt").write_text("old")
    write_result(result, out, report=False)
    assert not (out / "stale.txt").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]
    other = tmp_path / "docs"
    other.mkdir()
    (other / "notes.txt").write_text("keep")
    with pytest.raises(InputError, match="not a result folder"):
        write_result(result, other)
    assert (other / "notes.txt").read_text() == "keep"


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGKILL])
def test_a_killed_run_leaves_no_result(tmp_path, sig):
    out = tmp_path / "big"
    cmd = [sys.executable, "-m", "mtmc.cli.main", "run", str(STUDIES / "mass_calibration.toml")]
    cmd += ["-o", str(out), "--trials", "100000000", "--quiet"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    time.sleep(3.0)
    assert proc.poll() is None, proc.communicate()
    os.kill(proc.pid, sig)
    proc.communicate(timeout=60)
    assert proc.returncode != 0
    assert not out.exists()
    assert not list(tmp_path.glob("**/result.json"))


@pytest.mark.parametrize(
    ("name", "trials"),
    [
        ("mass_calibration", 3000),
        ("bcs_origin", 2000),
        ("five_axis", 3000),
        ("aguado2017", 40),
        ("wang2022", 300),
    ],
)
def test_two_workers_give_the_same_result_as_one(name, trials):
    study = load_study(STUDIES / f"{name}.toml")
    one = study.run(trials=trials, seed=5)
    two = study.run(trials=trials, seed=5, workers=2, executor="thread")
    assert one.to_dict() == two.to_dict()


def test_cli_run_takes_the_parallel_options(tmp_path, capsys):
    study = STUDIES / "mass_calibration.toml"
    base = ["run", str(study), "--trials", "3000", "--seed", "2", "-q"]
    assert main([*base, "-o", str(tmp_path / "one")]) == 0
    assert main([*base, "-o", str(tmp_path / "two"), "--workers", "2"]) == 0
    one, two = (json.loads((tmp_path / d / "result.json").read_text()) for d in ("one", "two"))
    assert one == two
    assert main([*base, "-o", str(tmp_path / "bad"), "--executor", "mpi"]) == 2
    assert "expected thread, process or dask" in capsys.readouterr().err
    assert not (tmp_path / "bad").exists()


def test_write_result_draws_the_plots_asked_and_refuses_a_bad_count_before_writing(tmp_path):
    study = load_study(STUDIES / "ball_centre.toml")
    result = study.run(trials=200, seed=2)
    n = len(result.quantities)
    assert n == 3
    for plotted, drawn in ((0, 0), (1, 1), ("all", n)):
        out = write_result(result, tmp_path / f"r{plotted}", plotted=plotted)
        page = (out / "report.html").read_text(encoding="utf-8")
        assert page.count('data-plot="histogram:') == drawn, plotted
        assert page.count('class="unplotted"') == n - drawn, plotted
    for bad in (-1, 1.5, True, "some"):
        with pytest.raises(InputError, match="whole number >= 0 or 'all'"):
            write_result(result, tmp_path / "bad", plotted=bad)
        assert not (tmp_path / "bad").exists()
    # without a report the count is not read
    assert (write_result(result, tmp_path / "plain", report=False, plotted=-1)).is_dir()
