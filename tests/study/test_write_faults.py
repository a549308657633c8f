"""Result folders under faults: ``kill -9`` leftovers, writers at once, links to folders."""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from mtmc.study import load_study, write_result

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "examples" / "studies" / "mass_calibration.toml"


@pytest.fixture(scope="module")
def result():
    return load_study(STUDY).run(trials=1000, seed=3)


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait(timeout=30)
    return proc.pid


#: a child that writes a result folder and stops while its report is being drawn
WRITER = """
import sys, time
import mtmc.report
from mtmc.study import load_study, write_result

def stuck(folder, **options):
    print("writing", flush=True)
    time.sleep(60)

mtmc.report.render = stuck
result = load_study(sys.argv[1]).run(trials=1000, seed=3)
write_result(result, sys.argv[2])
"""


def test_kill_9_leftovers_are_removed_by_the_next_run(tmp_path, result):
    out = tmp_path / "out"
    write_result(result, out, report=False)
    before = (out / "result.json").read_bytes()
    proc = subprocess.Popen(
        [sys.executable, "-c", WRITER, str(STUDY), str(out)], stdout=subprocess.PIPE
    )
    try:
        assert proc.stdout is not None
        assert proc.stdout.readline() == b"writing\n"
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=30)
    left = [p.name for p in tmp_path.iterdir() if p.name != "out"]
    assert len(left) == 1, left
    assert left[0].startswith(f".out.mtmc-{proc.pid}-"), left
    assert (out / "result.json").read_bytes() == before  # the previous result, whole
    # a hidden folder of another kind, and one of a run still going, are not touched
    (tmp_path / ".out.mine").mkdir()
    live = tmp_path / f".out.mtmc-{os.getppid()}-abcdefgh"
    live.mkdir()
    write_result(result, out, report=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["out", ".out.mine", live.name])


def test_stale_old_folder_of_a_dead_run_is_removed(tmp_path, result):
    stale = tmp_path / f".out.old.mtmc-{_dead_pid()}-x1y2z3w4"
    stale.mkdir()
    (stale / "result.json").write_text("{}")
    write_result(result, tmp_path / "out", report=False)
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def _write_many(args: tuple[str, int]) -> str:
    outdir, seed = args
    r = load_study(STUDY).run(trials=200, seed=seed)
    try:
        for _ in range(15):
            write_result(r, outdir, report=False)
    except Exception as exc:  # reported to the test
        return f"{type(exc).__name__}: {exc}"
    return "ok"


def test_writers_of_one_folder_at_once_all_succeed_whole(tmp_path):
    out = tmp_path / "out"
    ctx = mp.get_context("fork" if sys.platform == "linux" else "spawn")
    with ctx.Pool(3) as pool:
        got = pool.map(_write_many, [(str(out), s) for s in (1, 2, 3)])
    assert got == ["ok", "ok", "ok"]
    assert [p.name for p in tmp_path.iterdir()] == ["out"]
    doc = json.loads((out / "result.json").read_text())
    prov = json.loads((out / "provenance.json").read_text())
    assert doc["seed"] == prov["seed"] in (1, 2, 3)  # one writer's folder, whole


def test_outdir_link_to_a_folder_is_followed(tmp_path, result):
    target = tmp_path / "real"
    write_result(result, target, report=False)
    link = tmp_path / "link"
    link.symlink_to(target, target_is_directory=True)
    write_result(result, link, report=False)
    assert link.is_symlink()
    assert (link / "result.json").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link", "real"]


def test_a_full_disk_names_the_file(tmp_path, monkeypatch):
    import numpy as np

    def full(*_args, **_kwargs):
        raise OSError("1000000 requested and 259568 written")  # NumPy's words on ENOSPC

    monkeypatch.setattr(np, "save", full)
    kept = load_study(STUDY).run(trials=100, seed=3, samples=True)
    assert kept.samples
    out = tmp_path / "out"
    with pytest.raises(OSError, match="requested") as info:
        write_result(kept, out, report=False)
    name = next(iter(kept.samples))
    assert str(info.value) == (
        f"{out / 'samples' / name}.npy: cannot write: 1000000 requested and 259568 written"
    )
    assert not out.exists()
