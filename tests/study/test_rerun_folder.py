"""A result folder reruns by itself: the files its study names are in it, checked by SHA-256.

Every shipped study and a workbench full run are run, their folder is copied to another
place (where no path relative to the original can reach the original's files), run again
from the copy's ``study.toml`` with the seed and trials the report prints, and the two
``result.json`` are compared: bit for bit (our seeded draws and reductions) in every
number, only the study file's name and digest differ (the copy names the copies).
"""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import pytest

from mtmc.demo import study_path
from mtmc.document import InputFile
from mtmc.errors import InputError
from mtmc.study import load_result, load_study, write_result
from mtmc.study.write import copy_names, study_copy

SHIPPED = sorted(p.name for p in study_path("").iterdir() if p.suffix == ".toml")
#: Few trials: the numbers are compared bit for bit, their size does not matter.
TRIALS = 200
SEED = 7
#: What differs between a run and its rerun from the folder: the study file (its path and
#: its text, whose paths name the copies), and where a positioning study read its data.
NAMING = ("study_file", "study_sha256")


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _numbers(folder: Path) -> dict[str, object]:
    doc = json.loads((folder / "result.json").read_text(encoding="utf-8"))
    if "positioning" in doc:
        assert Path(doc["positioning"].pop("data")).name == "positioning_x.csv"
    return {k: v for k, v in doc.items() if k not in NAMING}


def _rerun(first: Path, elsewhere: Path) -> Path:
    """Copy ``first`` to ``elsewhere`` and run its study.toml there as the report says."""
    moved = elsewhere / "moved"
    shutil.copytree(first, moved)
    doc = json.loads((moved / "result.json").read_text(encoding="utf-8"))
    study = load_study(moved / "study.toml")
    result = study.run(trials=doc["trials"], seed=doc["seed"])
    text = (moved / "study.toml").read_text(encoding="utf-8")
    return write_result(result, elsewhere / "again", study_text=text, report=False)


def _check_provenance(folder: Path) -> list[dict[str, str]]:
    prov = json.loads((folder / "provenance.json").read_text(encoding="utf-8"))
    for f in prov["input_files"]:
        assert (folder / f["copy"]).is_file(), f
        assert _sha(folder / f["copy"]) == f["sha256"], f  # the copy is the file read
    listed: list[dict[str, str]] = prov["input_files"]
    return listed


def test_every_shipped_study_is_listed():
    # the studies of mtmc/data/studies: the demo's, the tracker's position, ISO 230-2, 230-4
    assert len(SHIPPED) == 16


@pytest.mark.parametrize("name", SHIPPED)
def test_a_shipped_study_reruns_from_its_folder_moved_elsewhere(name, tmp_path):
    study = load_study(study_path(name))
    result = study.run(trials=TRIALS, seed=SEED)
    first = write_result(
        result, tmp_path / "first", study_text=study.source.text, report=name == "axis_c.toml"
    )
    listed = _check_provenance(first)
    for f in listed:  # the original the run read, by its own digest
        assert _sha(Path(f["source"])) == f["sha256"]
    again = _rerun(first, tmp_path / "elsewhere")
    assert _numbers(again) == _numbers(first)
    # the copy's study.toml names files in the folder: a rerun writes the same text
    assert (again / "study.toml").read_text() == (first / "study.toml").read_text()
    assert [f["sha256"] for f in _check_provenance(again)] == [f["sha256"] for f in listed]
    back = load_result(first).input_files
    assert [(f.field, f.copy, f.sha256) for f in back] == [
        (f["field"], f["copy"], f["sha256"]) for f in listed
    ]
    names = {f["field"] for f in listed}
    if name in ("axis_a.toml", "axis_c.toml", "ball_centre.toml", "bcs_origin.toml"):
        assert names == {"graph"}  # ../graphs/NAME.toml: not in the folder before
        assert f'graph = "inputs/{name}"' in (first / "study.toml").read_text()
    elif name == "positioning_x.toml":
        assert names == {"data"}
    else:
        assert names == set()


def test_a_workbench_full_run_reruns_from_its_folder(tmp_path):
    from mtmc.workbench.compute import full_run

    work = tmp_path / "work"
    work.mkdir()
    graph = work / "ball.toml"
    shutil.copyfile(study_path("../graphs/ball_centre.toml"), graph)
    first = full_run(graph, "Ball", ["p"], trials=TRIALS, seed=SEED)
    [f] = _check_provenance(first)
    assert (f["field"], f["given"], f["copy"]) == ("graph", "ball.toml", "inputs/ball.toml")
    assert f["sha256"] == _sha(graph)
    assert 'graph = "inputs/ball.toml"' in (first / "study.toml").read_text()
    again = _rerun(first, tmp_path / "elsewhere")
    assert _numbers(again) == _numbers(first)
    [back] = load_result(first).input_files
    assert back == InputFile(("graph",), "ball.toml", str(graph.resolve()), _sha(graph), f["copy"])


CSV = "x\n10.012\n10.007\n10.015\n10.009\n"


def _csv_study(tmp_path: Path) -> Path:
    """A study naming two CSV files of one name from two folders, and one of them twice."""
    for sub, shift in (("a", 0), ("b", 1)):
        (tmp_path / sub).mkdir()
        (tmp_path / sub / "d.csv").write_text(CSV.replace("10.0", f"1{shift}.0"))
    study = tmp_path / "s" / "study.toml"
    study.parent.mkdir()
    study.write_text(
        "# readings of two gauges\n"
        'kind = "propagate"\n'
        'model = "x - y + z"\n'
        "[inputs]\n"
        'x = {data = "../a/d.csv", column = "x"}  # gauge a\n'
        'y = {data = "../b/d.csv", column = "x"}\n'
        "z.data = '../a/d.csv'  # gauge a again\n"
        "z.column = 'x'\n"
        "[run]\ntrials = 100\nseed = 3\n",
        encoding="utf-8",
    )
    return study


def test_files_of_one_name_get_copies_of_their_own_and_comments_stay(tmp_path):
    study = load_study(_csv_study(tmp_path))
    first = write_result(study.run(), tmp_path / "out", study_text=study.source.text, report=False)
    listed = _check_provenance(first)
    assert [(f["field"], f["copy"]) for f in listed] == [
        ("inputs.x.data", "inputs/d.csv"),
        ("inputs.y.data", "inputs/2/d.csv"),
        ("inputs.z.data", "inputs/d.csv"),
    ]
    assert (first / "inputs" / "d.csv").read_text() == CSV
    text = (first / "study.toml").read_text()
    assert text.startswith("# readings of two gauges\n")
    assert 'x = {data = "inputs/d.csv", column = "x"}  # gauge a\n' in text
    assert 'z.data = "inputs/d.csv"  # gauge a again\n' in text
    again = _rerun(first, tmp_path / "elsewhere")
    assert _numbers(again) == _numbers(first)
    assert [f.copy for f in load_result(again).input_files] == [f["copy"] for f in listed]


def test_a_file_changed_after_the_run_writes_no_folder(tmp_path):
    path = _csv_study(tmp_path)
    study = load_study(path)
    result = study.run()
    (tmp_path / "b" / "d.csv").write_text(CSV + "10.010\n")
    with pytest.raises(InputError, match="changed after the run read it") as info:
        write_result(result, tmp_path / "out", study_text=study.source.text, report=False)
    assert info.value.field == "inputs.y.data"
    assert not (tmp_path / "out").exists()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".out")] == []


def test_copy_names_and_study_copy_by_themselves():
    files = [
        InputFile(("graph",), "g.toml", "/p/g.toml", "0"),
        InputFile(("a", 1, "file"), "../q/g.toml", "/q/g.toml", "1"),
        InputFile(("b",), "/r/g.toml", "/r/g.toml", "2"),
        InputFile(("c",), "g.toml", "/p/g.toml", "0"),
    ]
    named = copy_names(files)
    assert [f.copy for f in named] == [
        "inputs/g.toml",
        "inputs/2/g.toml",
        "inputs/3/g.toml",
        "inputs/g.toml",
    ]
    assert named[1].field == "a[1].file"
    text = 'graph = "g.toml"\nb = "/r/g.toml"\nc = "g.toml"\n[[a]]\n[[a]]\nfile = "../q/g.toml"\n'
    assert study_copy(text, named) == (
        'graph = "inputs/g.toml"\nb = "inputs/3/g.toml"\nc = "inputs/g.toml"\n'
        '[[a]]\n[[a]]\nfile = "inputs/2/g.toml"\n'
    )
    with pytest.raises(InputError, match="the field is not there") as info:
        study_copy('graph = "g.toml"\n', named[:2], "s.toml")
    assert (info.value.file, info.value.field) == ("s.toml", "a[1].file")
    assert study_copy("x = 1\n", files) == "x = 1\n"  # no copies named yet: unchanged


def test_the_line_the_report_prints_reruns_a_demo_folder(tmp_path):
    import re

    from mtmc.cli.main import main
    from mtmc.demo import run_demo

    # Stryczek's ball centre: a graph study whose graph file is copied into its folder
    # (the sweep of bcs_origin, also such a study, took 16 s here)
    run_demo(tmp_path / "demo", trials=TRIALS, seed=SEED, studies=["ball_centre.toml"], echo=str)
    moved = tmp_path / "elsewhere" / "ball_centre"
    shutil.copytree(tmp_path / "demo" / "ball_centre", moved)
    assert (moved / "inputs" / "ball_centre.toml").is_file()
    shutil.rmtree(tmp_path / "demo")
    page = (moved / "report.html").read_text(encoding="utf-8")
    line = re.search(r"<code>mtmc run study.toml (--seed \d+ --trials \d+)</code>", page)
    assert line is not None
    argv = ["run", str(moved / "study.toml"), *line.group(1).split(), "-q"]
    assert main([*argv, "-o", str(tmp_path / "again")]) == 0
    assert _numbers(tmp_path / "again") == _numbers(moved)


def test_an_artefact_file_goes_with_its_study(tmp_path):
    (tmp_path / "art").mkdir()
    shipped = study_path("../artefacts/wang2022_five_ball.toml")
    shutil.copyfile(shipped, tmp_path / "art" / "five.toml")
    text = study_path("wang2022.toml").read_text(encoding="utf-8")
    text = text.replace('shipped = "wang2022_five_ball"', 'file = "../art/five.toml"')
    path = tmp_path / "s" / "wang.toml"
    path.parent.mkdir()
    path.write_text(text, encoding="utf-8")
    study = load_study(path)
    first = write_result(
        study.run(trials=TRIALS, seed=SEED), tmp_path / "out", study_text=text, report=False
    )
    [f] = _check_provenance(first)
    assert (f["field"], f["copy"], f["sha256"]) == (
        "artefact.file",
        "inputs/five.toml",
        _sha(shipped),
    )
    again = _rerun(first, tmp_path / "elsewhere")
    assert _numbers(again) == _numbers(first)
    # the same artefact as the shipped one: the same numbers as the study that names it
    shipped_run = load_study(study_path("wang2022.toml")).run(trials=TRIALS, seed=SEED)
    assert (
        json.loads(json.dumps(shipped_run.to_dict()["quantities"])) == _numbers(first)["quantities"]
    )


def test_a_provenance_whose_input_files_are_not_entries_is_named(tmp_path):
    study = load_study(_csv_study(tmp_path))
    out = write_result(study.run(), tmp_path / "out", study_text=study.source.text, report=False)
    prov = json.loads((out / "provenance.json").read_text(encoding="utf-8"))
    prov["input_files"] = [{"key": ["inputs", "x", "data"]}]
    (out / "provenance.json").write_text(json.dumps(prov), encoding="utf-8")
    with pytest.raises(InputError, match="expected input_files entries with key") as info:
        load_result(out)
    assert (info.value.file, info.value.field) == (str(out / "provenance.json"), "input_files")
