"""Hostile files: inline arrays of graph files, tampered result folders, a graph file
changed under the workbench. Each ends in a result or in one line of error, with no
warning, and an edit on disk is never lost.

The budget is ``MTMC_FUZZ_EXAMPLES`` (default 25 cases, derandomised), as in
``test_fuzz.py``; ``make fuzz`` runs these properties with its larger budget.
"""

from __future__ import annotations

import copy
import json
import os
import shutil
import tempfile
import warnings
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from mtmc.errors import MtmcError
from mtmc.graph import loads_graph
from mtmc.report import render
from mtmc.study import load_result, loads_study, write_result

EXAMPLES = int(os.environ.get("MTMC_FUZZ_EXAMPLES", "25"))
ROOT = Path(__file__).resolve().parents[2]
SETTINGS = settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize=EXAMPLES <= 100,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)

SCALARS = st.one_of(
    st.booleans(),
    st.integers(-(10**30), 10**30),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=5),
    st.lists(st.integers(0, 3), max_size=3),
)


def _toml(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return {"nan": "nan", "inf": "inf", "-inf": "-inf"}.get(repr(v), repr(v))
    if isinstance(v, str):
        from mtmc.graph.toml_format import toml_string

        return toml_string(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    return str(v)


@st.composite
def inline_arrays(draw: st.DrawFn) -> str:
    """A graph file whose places and transitions are inline arrays with scalars among the tables."""
    places = ['{name = "a", type = "real", value = 1.0}', '{name = "b", type = "real", u = 0.1}']
    trans = ['{name = "t", op = "displace", in = ["a", "b"], out = "c"}']
    for entries in (places, trans):
        for _ in range(draw(st.integers(0, 2))):
            entries.insert(draw(st.integers(0, len(entries))), _toml(draw(SCALARS)))
    return f"place = [{', '.join(places)}]\ntransition = [{', '.join(trans)}]\n"


@SETTINGS
@given(text=inline_arrays())
def test_inline_arrays_give_a_graph_or_one_line(text: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        message = "g.toml: read"
        try:
            loads_graph(text, file="g.toml")
        except MtmcError as exc:
            message = str(exc)
    assert "\n" not in message
    assert message.startswith("g.toml:")


STUDY = """\
kind = "propagate"
title = "Sum"
model = "a + b"
output = "y"
unit = "mm"
[inputs]
a = "normal(0, 1)"
b = "uniform(-1, 1)"
[run]
trials = 500
seed = 5
samples = true
"""


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("res") / "res"
    write_result(loads_study(STUDY, file="s.toml").run(), d, study_text=STUDY)
    return d


def _leaves(obj: Any, at: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    out = [at] if at else []
    if isinstance(obj, dict):
        for k, v in obj.items():
            out += _leaves(v, (*at, k))
    elif isinstance(obj, list):
        for i, v in enumerate(obj[:2]):
            out += _leaves(v, (*at, i))
    return out


VALUES = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(10**40), 10**40),
    st.floats(allow_nan=False, allow_infinity=False),
    st.text(max_size=4),
    st.lists(st.floats(allow_nan=False, allow_infinity=False), max_size=3),
    st.just({}),
)
FILE_TAMPERS = ("none", "fifo-npy", "short-npy", "link-out", "bad-utf8", "deep", "drop-key")


@st.composite
def tampered_folders(draw: st.DrawFn) -> tuple[int, Any, str]:
    """A leaf of result.json (by index), its new value, and what is done to the files."""
    return draw(st.integers(0, 10**6)), draw(VALUES), draw(st.sampled_from(FILE_TAMPERS))


def _tamper(d: Path, leaf: int, value: Any, how: str) -> None:
    doc = json.loads((d / "result.json").read_text(encoding="utf-8"))
    paths = _leaves(doc)
    path = paths[leaf % len(paths)]
    node = doc
    for key in path[:-1]:
        node = node[key]
    if how == "drop-key" and isinstance(node, dict):
        del node[path[-1]]
    else:
        node[path[-1]] = copy.deepcopy(value)
    raw = json.dumps(doc).encode()
    if how == "bad-utf8":
        raw = raw.replace(b'"Sum"', b'"S\xffm"')
    elif how == "deep":
        raw = b"[" * 50_000 + b"]" * 50_000
    (d / "result.json").write_bytes(raw)
    npy = d / "samples" / "y.npy"
    if how == "fifo-npy":
        npy.unlink()
        os.mkfifo(npy)
    elif how == "short-npy":
        npy.write_bytes(npy.read_bytes()[:200])
    elif how == "link-out":
        (d / "report.html").unlink()
        (d / "report.html").symlink_to(d.parent / "victim.txt")


@SETTINGS
@given(case=tampered_folders())
# make fuzz at 2000: quantities[0].name = "˯", a glyph DejaVu Sans lacks (a UserWarning)
@example(case=(249, "˯", "none"))
def test_tampered_result_folders_read_or_refused_in_one_line(
    written: Path, case: tuple[int, Any, str]
) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp) / "res"
        shutil.copytree(written, d, symlinks=True)
        (Path(tmp) / "victim.txt").write_text("keep")
        _tamper(d, *case)
        messages = []
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            for read in (load_result, render):
                try:
                    read(d)
                except MtmcError as exc:
                    messages.append(str(exc))
        assert all("\n" not in m for m in messages)
        assert (Path(tmp) / "victim.txt").read_text() == "keep"


@st.composite
def disk_changes(draw: st.DrawFn) -> list[str]:
    """Steps: the page saves, or the file is edited, removed or rewritten the same on disk."""
    return draw(st.lists(st.sampled_from(("save", "edit", "remove", "same")), max_size=5))


@SETTINGS
@given(steps=disk_changes())
def test_a_graph_file_changed_under_the_workbench_is_never_overwritten(steps: list[str]) -> None:
    pytest.importorskip("starlette")
    from starlette.testclient import TestClient

    from mtmc.workbench import Session, create_app

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "g.toml"
        shutil.copy(ROOT / "examples" / "graphs" / "ball_centre.toml", path)
        session = Session(path)
        app = create_app(session, "tok", "127.0.0.1:8765")
        with TestClient(app, base_url="http://127.0.0.1:8765") as client:
            view = client.get("/tok/api/graph").json()["view"]
            changed = False  # the file differs from what the page last loaded or saved
            for n, step in enumerate(steps):
                if step == "edit":
                    path.write_text(path.read_text() + f"# edit {n}\n") if path.exists() else None
                    changed = changed or path.exists()
                elif step == "remove" and path.exists():
                    path.unlink()
                    changed = True
                elif step == "same" and path.exists():
                    path.write_bytes(path.read_bytes())
                elif step == "save":
                    before = path.read_bytes() if path.exists() else None
                    r = client.post("/tok/api/save", json={"graph": view})
                    if changed:
                        assert r.status_code == 409, r.text
                        assert (path.read_bytes() if path.exists() else None) == before
                    else:
                        assert r.status_code == 200, r.text
                        view = r.json()["view"]
