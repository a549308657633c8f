"""The workbench's pieces one by one: the server in this process, its Ctrl-C rule, the
file's view and its rendering, the live run's corners."""

from __future__ import annotations

import json
import signal
import threading
import time
import urllib.request
from pathlib import Path

import pytest

pytest.importorskip("starlette")

from mtmc.errors import DegenerateGeometryError, InputError, ParseError
from mtmc.workbench import Session, compute, serve, server
from mtmc.workbench.view import GraphDocument, check_payload, graph_json, node_of_error

ROOT = Path(__file__).resolve().parents[2]
GRAPH = ROOT / "examples" / "graphs" / "ball_centre.toml"


def test_serve_in_this_process_prints_the_url_first_and_opens_the_browser(tmp_path, monkeypatch):
    path = tmp_path / "g.toml"
    path.write_bytes(GRAPH.read_bytes())
    lines: list[str] = []
    opened: list[str] = []
    servers: list = []
    monkeypatch.setattr(server.webbrowser, "open", opened.append)
    run = server._Server.run

    def capture(self, sockets):
        servers.append(self)
        run(self, sockets)

    monkeypatch.setattr(server._Server, "run", capture)
    thread = threading.Thread(
        target=serve, args=(path,), kwargs={"echo": lines.append, "open_browser": True}
    )
    thread.start()
    try:
        deadline = time.monotonic() + 20
        while not (lines and servers and servers[0]._server.started):
            assert time.monotonic() < deadline
            time.sleep(0.02)
        url = lines[0]
        with urllib.request.urlopen(url + "api/graph", timeout=20) as resp:  # 127.0.0.1
            assert json.loads(resp.read())["file"] == "g.toml"
        while not opened:
            assert time.monotonic() < deadline
            time.sleep(0.02)
        assert opened == [url]
    finally:
        while not servers:
            time.sleep(0.02)
        servers[0]._server.should_exit = True
        thread.join(timeout=20)
    assert not thread.is_alive()
    assert lines[-1] == "mtmc: workbench stopped"


def test_the_first_ctrl_c_over_an_unsaved_edit_only_warns(tmp_path):
    import uvicorn

    session = Session(tmp_path / "g.toml")
    said: list[str] = []
    config = uvicorn.Config(lambda *_: None, lifespan="off")
    wrapped = server._Server(config, session, said.append)
    session.unsaved = True
    wrapped._server.handle_exit(signal.SIGINT, None)
    assert not wrapped._server.should_exit
    assert "Ctrl-C again" in said[0]
    wrapped._server.handle_exit(signal.SIGINT, None)
    assert wrapped._server.should_exit
    saved = server._Server(config, Session(tmp_path / "h.toml"), said.append)
    saved._server.handle_exit(signal.SIGINT, None)
    assert saved._server.should_exit


def test_a_file_that_cannot_be_read_or_written(tmp_path):
    folder = tmp_path / "dir.toml"
    folder.mkdir()
    with pytest.raises(InputError, match="cannot read the graph file"):
        Session(folder)
    path = tmp_path / "g.toml"
    path.write_bytes(GRAPH.read_bytes())
    session = Session(path)
    from starlette.testclient import TestClient

    client = TestClient(
        server.create_app(session, "tok", "127.0.0.1:1"), base_url="http://127.0.0.1:1"
    )
    view = client.get("/tok/api/graph").json()["view"]
    path.unlink()
    path.mkdir()  # a folder where the file was: the save reads it first and is refused
    r = client.post("/tok/api/save", json={"graph": view})
    assert r.status_code == 400
    assert "cannot read the graph file" in r.json()["error"]
    assert path.is_dir()
    assert not any(path.iterdir())  # nothing written over it


def test_the_view_of_texts_that_are_not_graphs():
    with pytest.raises(ParseError, match="not valid TOML"):
        GraphDocument("a = [", "g.toml")
    view = graph_json("place = 3\ntransition = [1]\nprobe = 2\n")
    assert view["places"] == []
    assert view["transitions"] == []
    assert view["probe"] == {}
    with pytest.raises(InputError, match="at most"):
        check_payload({"places": [{"name": "a"}] * 5001}, view)


def test_rendering_removes_keys_and_keeps_booleans_apart():
    text = '[[place]]\nname = "a"\ntype = "real"\nvalue = 1.0\nu = 0.1 # the u\n'
    doc = GraphDocument(text, "g.toml")
    view = json.loads(json.dumps(doc.view))
    del view["places"][0]["u"]
    assert doc.render(view) == '[[place]]\nname = "a"\ntype = "real"\nvalue = 1.0\n'
    view["places"][0]["value"] = True  # a boolean is not the number 1
    assert "value = true" in doc.render(view)
    # an entry that ends the file without a newline: the new one still starts on its own line
    doc = GraphDocument('[[place]]\nname = "a"\ntype = "real"\nvalue = 1.0', "g.toml")
    view = json.loads(json.dumps(doc.view))
    view["places"].append({"src": None, "name": "b", "type": "real", "value": 2.0})
    assert doc.render(view).endswith(
        'value = 1.0\n\n[[place]]\nname = "b"\ntype = "real"\nvalue = 2.0\n'
    )


def test_node_of_an_error_by_line_or_by_name():
    text = '[[place]]\nname = "a"\ntype = "real"\n'
    assert node_of_error(InputError("x", line=3), text) == "a"
    assert node_of_error(InputError("x", line=3), "a = [") is None
    assert node_of_error(InputError("transition t9: no"), text) == "t9"
    assert node_of_error(InputError("units are wrong"), text) is None


def test_live_run_units_and_a_failed_run(monkeypatch):
    text = (
        '[[place]]\nname = "a"\ntype = "real"\nvalue = 2.0\nu = 0.1\n'
        '[[place]]\nname = "b"\ntype = "real"\nvalue = 3.0\n'
        '[[place]]\nname = "v"\ntype = "vector"\nvalue = [1, 0, 0]\nu = 0.01\n'
        '[[place]]\nname = "w"\ntype = "vector"\nvalue = [0, 1, 0]\n'
        '[[transition]]\nname = "t"\nop = "ratio"\nin = ["a", "b"]\nout = "c"\n'
        '[[transition]]\nname = "g"\nop = "angle"\nin = ["v", "w"]\nout = "phi"\n'
    )
    out = compute.live_run(text, "g.toml", selected="c")
    assert out["places"]["c"]["parts"][0]["unit"] == "mm^2"
    assert out["places"]["phi"]["parts"][0]["unit"] == "rad"
    assert out["summary"]["components"][0]["component"] == "value"

    def degenerate(*_a, **_k):
        raise DegenerateGeometryError("transition g: the vectors are parallel in trial 3")

    monkeypatch.setattr(compute, "run_graph", degenerate)
    out = compute.live_run(text, "g.toml")
    assert not out["ok"]
    assert out["errors"][0]["node"] == "g"


def test_a_full_run_without_a_seed_draws_one(tmp_path):
    path = tmp_path / "g.toml"
    path.write_bytes(GRAPH.read_bytes())
    folder = compute.full_run(path, "", ["cx"], 200, None)
    result = json.loads((folder / "result.json").read_text())
    assert result["trials"] == 200
    assert isinstance(result["seed"], int)
