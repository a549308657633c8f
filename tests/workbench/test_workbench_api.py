"""The workbench's JSON API through Starlette's test client: load, edit, check, run, save,
and every security rule refused."""

from __future__ import annotations

import copy
import difflib
import json
import shutil
import subprocess
import tomllib
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("starlette")
from starlette.testclient import TestClient

from mtmc.graph import check_graph, graph_model, load_graph, loads_graph
from mtmc.uncertainty.propagation import gum
from mtmc.workbench import Session, create_app
from mtmc.workbench.compute import arc_refusal, live_run
from mtmc.workbench.view import GraphDocument, check_payload, graph_json

ROOT = Path(__file__).resolve().parents[2]
GRAPHS = ROOT / "examples" / "graphs"
HOST = "127.0.0.1:8765"
TOKEN = "t0ken-for-the-tests"


def _client(path: Path, max_body: int | None = None) -> tuple[TestClient, Session]:
    session = Session(path)
    kw = {} if max_body is None else {"max_body": max_body}
    app = create_app(session, TOKEN, HOST, **kw)
    return TestClient(app, base_url=f"http://{HOST}"), session


@pytest.fixture
def ball(tmp_path):
    path = tmp_path / "ball_centre.toml"
    shutil.copy(GRAPHS / "ball_centre.toml", path)
    client, session = _client(path)
    with client:
        yield client, session, path


def _get(client, route="api/graph"):
    return client.get(f"/{TOKEN}/{route}")


def _post(client, route, body, **kw):
    return client.post(f"/{TOKEN}/{route}", json=body, **kw)


def _view(client):
    r = _get(client)
    assert r.status_code == 200
    return r.json()["view"]


# ---------------------------------------------------------------------- load


def test_load_gives_the_file_view_palette_check_and_layout(ball):
    client, _, path = ball
    data = _get(client).json()
    assert data["file"] == "ball_centre.toml"
    assert data["exists"]
    g = load_graph(path)
    assert [p["name"] for p in data["view"]["places"]] == [p.name for p in g.places]
    assert [t["name"] for t in data["view"]["transitions"]] == [t.name for t in g.transitions]
    assert data["check"]["ok"]
    assert data["check"]["errors"] == []
    plan = check_graph(g)
    assert set(data["positions"]) == {*plan.types, *(t.name for t in g.transitions)}
    assert set(data["palette"]["ops"]) >= {"meas", "middle", "point", "axis", "plane"}
    assert data["palette"]["place_types"][:4] == ["x", "y", "z", "real"]
    assert data["live"]["trials"] == 2**14


def test_the_page_and_its_files_are_served(ball):
    client, _, _ = ball
    r = client.get(f"/{TOKEN}/")
    assert r.status_code == 200
    assert "cytoscape" not in r.text
    assert "app.js" in r.text
    assert r.headers["content-security-policy"].startswith("default-src 'self'")
    assert r.headers["referrer-policy"] == "no-referrer"
    js = client.get(f"/{TOKEN}/static/app.js")
    assert js.status_code == 200
    assert js.headers["content-type"].startswith("text/javascript")
    lib = client.get(f"/{TOKEN}/static/vendor/cytoscape.esm.min.mjs")
    assert lib.status_code == 200
    assert lib.headers["content-type"].startswith("text/javascript")
    assert client.get(f"/{TOKEN}/static/../server.py").status_code == 404
    assert client.get(f"/{TOKEN}/static/nothing.js").status_code == 404


def test_the_vendored_library_matches_its_record():
    import hashlib

    vendor = ROOT / "src" / "mtmc" / "workbench" / "static" / "vendor"
    record = json.loads((vendor / "VENDOR.json").read_text())["cytoscape.esm.min.mjs"]
    data = (vendor / "cytoscape.esm.min.mjs").read_bytes()
    assert hashlib.sha256(data).hexdigest() == record["sha256"]
    assert record["license"] == "MIT"
    assert (vendor / record["licence_file"]).is_file()
    assert f'version="{record["version"]}"' in data.decode()[-300:]


def test_the_static_files_ship_in_the_wheel():
    from importlib import resources

    # hatch puts every file under src/mtmc in the wheel (none of them is git-ignored)
    assert 'packages = ["src/mtmc"]' in (ROOT / "pyproject.toml").read_text()
    static = resources.files("mtmc.workbench") / "static"
    for name in ("index.html", "app.js", "style.css", "vendor/cytoscape.esm.min.mjs"):
        assert (static / name).is_file(), name
    ignored = subprocess.run(
        ["git", "check-ignore", "-q", "src/mtmc/workbench/static/vendor/cytoscape.esm.min.mjs"],
        cwd=ROOT,
        check=False,
    )
    assert ignored.returncode != 0


# ---------------------------------------------------------------------- edit and check


def test_an_edit_is_checked_with_the_message_at_its_node(ball):
    client, _, _ = ball
    view = _view(client)
    t = next(t for t in view["transitions"] if t["name"] == "t_cx")
    t["in"] = ["x1"]  # middle needs two
    r = _post(client, "api/check", {"graph": view})
    assert r.status_code == 200
    report = r.json()
    assert not report["ok"]
    (err,) = report["errors"]
    assert err["node"] == "t_cx"
    assert "op middle accepts no inputs of types (x)" in err["text"]
    assert err["message"].startswith("ball_centre.toml:")  # as mtmc graph check prints it


def test_an_error_naming_a_place_is_shown_at_the_place(ball):
    client, _, _ = ball
    view = _view(client)
    view["places"][0]["u"] = -1.0
    (err,) = _post(client, "api/check", {"graph": view}).json()["errors"]
    assert err["node"] == "neg_r1"
    assert err["field"] == "u"


def test_the_live_run_gives_every_place_with_the_gum_beside_it(ball):
    client, _, path = ball
    view = _view(client)
    r = _post(client, "api/run", {"seq": 1, "graph": view, "selected": "p"})
    assert r.status_code == 200
    out = r.json()
    assert out["ok"]
    assert out["seq"] == 1
    assert out["trials"] == 2**14
    plan = check_graph(load_graph(path))
    assert set(out["places"]) == set(plan.types)
    model, inputs = graph_model(plan, "p")
    g = gum(model, inputs)
    part = out["places"]["p"]["parts"][0]
    assert part["gum_u_value"] == pytest.approx(g.u_vector, rel=1e-9)
    assert part["u_value"] == pytest.approx(g.u_vector, rel=0.02)  # linear: MC = GUM
    summary = out["summary"]
    assert summary["place"] == "p"
    assert [c["component"] for c in summary["components"]] == [
        "x",
        "y",
        "z",
    ]
    first = summary["components"][0]
    assert first["gum"]["validated"]
    assert first["gum"]["budget"][0]["share"] == pytest.approx(50.0)


def test_a_stale_request_is_answered_as_stale(ball):
    client, session, _ = ball
    view = _view(client)
    session.latest["page"] = 5
    out = _post(client, "api/run", {"seq": 3, "client": "page", "graph": view}).json()
    assert out == {"seq": 3, "stale": True}
    # another page (a reload) numbers its requests afresh
    assert _post(client, "api/run", {"seq": 1, "client": "new", "graph": view}).json()["ok"]
    for i in range(20):
        _post(client, "api/run", {"seq": 1, "client": f"c{i}", "graph": view, "selected": "x"})
    assert len(session.latest) == 16
    assert _post(client, "api/run", {"seq": 1, "client": 5, "graph": view}).status_code == 400


def test_a_graph_that_does_not_check_runs_nothing(ball):
    client, _, _ = ball
    view = _view(client)
    view["transitions"][0]["op"] = "nope"
    out = _post(client, "api/run", {"seq": 1, "graph": view}).json()
    assert not out["ok"]
    assert "places" not in out
    assert out["errors"][0]["node"] == "m1"


def test_a_probe_u_changes_the_output_as_the_gum_predicts(ball):
    client, _, path = ball
    view = _view(client)
    before = _post(client, "api/run", {"seq": 1, "graph": view}).json()
    view["probe"]["u_probe"] = 0.004
    after = _post(client, "api/run", {"seq": 2, "graph": view}).json()
    text = path.read_text().replace("u_probe = 0.001 ", "u_probe = 0.004 ")
    model, inputs = graph_model(check_graph(loads_graph(text)), "p")
    u_gum = gum(model, inputs).u_vector
    u0 = np.array(before["places"]["p"]["parts"][0]["u_value"])
    u1 = np.array(after["places"]["p"]["parts"][0]["u_value"])
    assert u1 == pytest.approx(u_gum, rel=0.02)
    assert np.all(u1 > u0)


def test_arc_rules(ball):
    client, _, _ = ball
    view = _view(client)
    types = _get(client).json()["check"]["types"]

    def arc(a, b):
        return _post(client, "api/arc", {"graph": view, "source": a, "target": b, "types": types})

    assert "bipartite" in arc("x1", "x2").json()["message"]
    assert "bipartite" in arc("m1", "t_cx").json()["message"]
    assert "already has its output" in arc("m1", "p").json()["message"]
    assert "meas takes no input" in arc("x1", "m2").json()["message"]
    assert "accepts no inputs of types (x, x, point)" in arc("p", "t_cx").json()["message"]
    view["transitions"].append({"src": None, "name": "m9", "op": "meas", "in": [], "out": ""})
    assert "already produced by" in arc("m9", "x1").json()["message"]
    assert "is marked" in arc("m9", "neg_r1").json()["message"]
    view["places"].append({"src": None, "declared": True, "name": "q", "type": "point"})
    assert arc("m9", "q").json() == {"ok": True, "message": None}
    view["transitions"].append({"src": None, "name": "tm", "op": "middle", "in": ["x1"], "out": ""})
    assert arc("x2", "tm").json()["ok"]
    assert "accepts no inputs" in arc("y1", "tm").json()["message"]


def test_arc_refusal_cases_of_the_library():
    view = graph_json(
        '[[place]]\nname = "a"\ntype = "point"\n[[transition]]\nname = "s"\nop = "sphere"\n'
        'in = ["a", "a", "a", "a"]\nout = "b"\n[[transition]]\nname = "u"\nop = "what"\n'
        'out = "c"\n'
    )
    types = {"a": "point", "r": "real"}
    view["places"].append({"src": None, "name": "r", "type": "real"})
    assert arc_refusal(view, "r", "s", types) is None  # known radius after the points
    assert arc_refusal(view, "a", "s", types) is None
    assert "unknown op" in arc_refusal(view, "a", "u", types)
    assert "itself" in arc_refusal(view, "a", "a", types)
    assert "no place or transition" in arc_refusal(view, "zz", "s", types)
    assert "no place or transition" in arc_refusal(view, "a", "zz", types)
    view["places"].append({"src": None, "name": "w"})  # type unknown: arity only
    view["transitions"].append({"src": None, "name": "v", "op": "vector", "in": ["a", "a"]})
    assert "at most 2 inputs" in arc_refusal(view, "w", "v", {})


# ---------------------------------------------------------------------- save


def test_save_without_an_edit_writes_the_file_back_byte_for_byte(ball):
    client, session, path = ball
    original = path.read_bytes()
    r = _post(client, "api/save", {"graph": _view(client)})
    assert r.status_code == 200
    assert r.json()["saved"] == "ball_centre.toml"
    assert path.read_bytes() == original
    assert not session.unsaved


@pytest.mark.parametrize("name", sorted(p.name for p in GRAPHS.glob("*.toml")))
def test_every_shipped_graph_round_trips(name):
    text = (GRAPHS / name).read_text(encoding="utf-8")
    doc = GraphDocument(text, name)
    assert doc.render(copy.deepcopy(doc.view)) == text


def test_save_keeps_comments_and_changes_only_what_was_edited(ball):
    client, _, path = ball
    original = path.read_text()
    view = _view(client)
    view["probe"]["u_probe"] = 0.002
    view["places"][0]["value"] = -12.5
    view["transitions"].append(
        {
            "src": None,
            "name": "m6",
            "op": "meas",
            "in": [],
            "out": "q",
            "params": {"at": [0.0, 0.0, -12.7], "direction": [0.0, 0.0, 1.0]},
        }
    )
    view["places"].append({"src": None, "declared": True, "name": "q", "type": "point"})
    r = _post(client, "api/save", {"graph": view})
    assert r.status_code == 200
    assert r.json()["check"]["ok"]
    text = path.read_text()
    assert "u_probe = 0.002             # u2: probe, along the probing direction" in text
    assert "value = -12.5\n" in text
    assert "# --- calibration ball" in text
    diff = list(difflib.ndiff(original.splitlines(), text.splitlines()))
    removed = [line[2:] for line in diff if line.startswith("- ")]
    assert removed == [
        "u_probe = 0.001             # u2: probe, along the probing direction",
        "value = -12.7",
    ]
    g = load_graph(path)
    assert g.transition("m6").param("at") == (0.0, 0.0, -12.7)
    # the file is now the base: a second save without an edit changes nothing
    again = _post(client, "api/save", {"graph": r.json()["view"]})
    assert again.status_code == 200
    assert path.read_text() == text


def test_rename_delete_and_positions(ball):
    client, _, path = ball
    view = _view(client)
    positions = _get(client).json()["positions"]
    for p in view["places"]:
        p["pos"] = positions[p["name"]]
    for t in view["transitions"]:
        t["pos"] = positions[t["name"]]
        t["in"] = ["centre" if x == "cx" else x for x in t["in"]]
        if t["out"] == "cx":
            t["out"] = "centre"
    # an implicit place gets stored once it has a position
    view["places"].append(
        {"src": None, "declared": False, "name": "centre", "type": "x", "pos": [1.0, 2.0]}
    )
    view["places"].append({"src": None, "declared": False, "name": "x1"})  # no pos: not written
    view["transitions"] = [t for t in view["transitions"] if t["name"] != "m5"]
    view["transitions"].append(
        {"src": None, "name": "m5b", "op": "meas", "out": "z1", "pos": [3, 4],
         "params": {"coordinate": "z", "at": [0.0, 0.0, 12.7], "direction": [0.0, 0.0, -1.0]}}
    )  # fmt: skip
    assert _post(client, "api/save", {"graph": view}).json()["check"]["ok"]
    g = load_graph(path)
    assert g.place("centre").pos == (1.0, 2.0)
    assert g.place("centre").type == "x"
    assert g.transition("t_cx").out == "centre"
    assert g.transition("m1").pos == tuple(positions["m1"])
    assert g.transition("m5") is None
    assert g.transition("m5b").pos == (3.0, 4.0)
    assert g.place("x1") is None


def test_title_units_and_probe_edits(tmp_path):
    path = tmp_path / "g.toml"
    path.write_text('title = "a"\n\n[probe]\nu_axis = 0.001\n\n[[place]]\nname = "r"\n'
                    'type = "real"\nvalue = 1.0\nu = 0.1\n')  # fmt: skip
    client, _ = _client(path)
    view = _view(client)
    view["title"] = ""
    view["units"] = "um"
    view["probe"] = {}
    assert _post(client, "api/save", {"graph": view}).status_code == 200
    assert (
        path.read_text()
        == 'units = "um"\n\n[[place]]\nname = "r"\ntype = "real"\nvalue = 1.0\nu = 0.1\n'
    )


def test_a_new_file_is_created_on_save(tmp_path):
    path = tmp_path / "new.toml"
    client, session = _client(path)
    data = _get(client).json()
    assert not data["exists"]
    assert data["view"]["places"] == []
    assert (
        data["check"]["errors"][0]["message"]
        == "new.toml: field transition: the graph has no transition"
    )
    out = _post(client, "api/run", {"seq": 1, "graph": data["view"]}).json()
    assert not out["ok"]
    assert "places" not in out
    view = data["view"]
    view["title"] = "new"
    view["probe"] = {"u_axis": 0.001}
    view["places"].append({"src": None, "declared": True, "name": "a", "type": "real",
                           "value": 1.0, "u": 0.1})  # fmt: skip
    view["transitions"].append({"src": None, "name": "t", "op": "middle", "in": ["a", "a"],
                                "out": "b"})  # fmt: skip
    assert _post(client, "api/save", {"graph": view}).json()["check"]["ok"]
    g = load_graph(path)
    assert g.title == "new"
    assert g.probe.u_axis == 0.001
    assert g.transition("t").out == "b"
    assert path.read_text().startswith('title = "new"\n\n[probe]\n')
    assert not session.unsaved


def test_a_missing_folder_or_an_assertion_file_is_refused(tmp_path):
    from mtmc.errors import InputError
    from mtmc.workbench import serve

    with pytest.raises(InputError, match="no folder"):
        Session(tmp_path / "no" / "g.toml")
    with pytest.raises(InputError, match="edits TOML graph files"):
        serve(tmp_path / "g.pl", open_browser=False)


def test_dirty_and_full_run(ball):
    client, _, path = ball
    assert _post(client, "api/dirty", {"dirty": True}).json() == {"unsaved": True}
    r = _post(client, "api/full-run", {"outputs": ["p"], "trials": 1000, "seed": 3})
    assert r.status_code == 409
    assert "save the graph first" in r.json()["error"]
    assert _post(client, "api/dirty", {"dirty": "yes"}).status_code == 400
    assert client.get(f"/{TOKEN}/report").status_code == 404
    _post(client, "api/dirty", {"dirty": False})
    r = _post(client, "api/full-run", {"outputs": ["p"], "trials": 1000, "seed": 3})
    assert r.status_code == 200, r.text
    folder = Path(r.json()["folder"])
    assert folder == path.parent / "ball_centre-result"
    result = json.loads((folder / "result.json").read_text())
    assert result["trials"] == 1000
    assert result["seed"] == 3
    report = client.get(f"/{TOKEN}/report")
    assert report.status_code == 200
    assert "<html" in report.text.lower()
    assert "default-src 'none'" in report.headers["content-security-policy"]
    assert _post(client, "api/full-run", {"outputs": []}).status_code == 400
    assert _post(client, "api/full-run", {"outputs": ["p"], "trials": 1}).status_code == 400


def test_export_and_import(ball):
    client, _, path = ball
    view = _view(client)
    toml = _post(client, "api/export", {"graph": view, "to": "toml"}).json()
    assert toml["text"] == path.read_text()
    assert toml["filename"] == "ball_centre.toml"
    pl = _post(client, "api/export", {"graph": view, "to": "assertions"}).json()
    assert pl["filename"] == "ball_centre.pl"
    assert "tp(" in pl["text"]
    dot = _post(client, "api/export", {"graph": view, "to": "dot"}).json()
    assert dot["text"].startswith("digraph")
    assert _post(client, "api/export", {"graph": view, "to": "svg"}).status_code == 400
    imported = _post(client, "api/import", {"text": pl["text"], "format": "assertions"}).json()
    names = {p["name"] for p in imported["view"]["places"]}
    assert {"p", "neg_r1"} <= names
    assert all(e["src"] is None for e in imported["view"]["places"])
    again = _post(client, "api/import", {"text": path.read_text(), "format": "toml"}).json()
    assert len(again["view"]["transitions"]) == len(view["transitions"])
    assert _post(client, "api/import", {"text": 1, "format": "toml"}).status_code == 400
    assert _post(client, "api/import", {"text": "", "format": "xls"}).status_code == 400
    bad = _post(client, "api/import", {"text": "p(1, 2", "format": "assertions"})
    assert bad.status_code == 400
    assert "Traceback" not in bad.text


# ---------------------------------------------------------------------- security


def test_a_wrong_token_or_another_path_is_not_found(ball):
    client, _, _ = ball
    for url in ("/wrong/api/graph", "/api/graph", "/", f"/{TOKEN}x/api/graph", "/favicon.ico"):
        r = client.get(url)
        assert r.status_code == 404, url
        assert r.json() == {"error": "not found"}
    assert client.post("/wrong/api/save", json={"graph": {}}).status_code == 404


def test_a_foreign_origin_is_refused(ball):
    client, _, path = ball
    before = path.read_bytes()
    r = _post(
        client, "api/save", {"graph": _view(client)}, headers={"Origin": "http://evil.example"}
    )
    assert r.status_code == 403
    assert "Origin" in r.json()["error"]
    r = client.get(f"/{TOKEN}/api/graph", headers={"Origin": "http://127.0.0.1:9999"})
    assert r.status_code == 403
    r = client.get(f"/{TOKEN}/api/graph", headers={"Sec-Fetch-Site": "cross-site"})
    assert r.status_code == 403
    ok = client.get(f"/{TOKEN}/api/graph", headers={"Origin": f"http://{HOST}"})
    assert ok.status_code == 200
    assert path.read_bytes() == before


def test_a_wrong_host_is_refused(ball):
    client, _, _ = ball
    for host in ("evil.example", "localhost:8765", "127.0.0.1:9999", "attacker.test:8765"):
        r = client.get(f"/{TOKEN}/api/graph", headers={"Host": host})
        assert r.status_code == 403, host
        assert "Host" in r.json()["error"], host


def test_methods_and_content_types(ball):
    client, _, _ = ball
    assert client.delete(f"/{TOKEN}/api/graph").status_code == 405
    r = client.post(f"/{TOKEN}/api/save", content=b"graph=1",
                    headers={"Content-Type": "application/x-www-form-urlencoded"})  # fmt: skip
    assert r.status_code == 415
    assert client.get(f"/{TOKEN}/api/save").status_code == 405


def test_an_oversized_body_is_refused(tmp_path):
    path = tmp_path / "g.toml"
    shutil.copy(GRAPHS / "ball_centre.toml", path)
    client, _ = _client(path, max_body=1000)
    with client:
        view = _view(client)
        r = _post(client, "api/save", {"graph": view})
        assert r.status_code == 413
        assert "larger than 1000 bytes" in r.json()["error"]
        # a body that does not say its length is counted as it arrives

        def chunks():
            yield b'{"graph": '
            yield json.dumps(view).encode()
            yield b"}"

        r = client.post(f"/{TOKEN}/api/check", content=chunks(),
                        headers={"Content-Type": "application/json"})  # fmt: skip
        assert r.status_code == 413
    assert path.read_bytes() == (GRAPHS / "ball_centre.toml").read_bytes()


@pytest.mark.parametrize(
    ("body", "message"),
    [
        (b"{not json", "not JSON"),
        (b"\xff\xfe", "not JSON"),
        (b"[1, 2]", "JSON object"),
        (b"{}", "missing graph"),
        (b'{"graph": []}', "expected a graph object"),
        (b'{"graph": {"places": {}}}', "places must be a list"),
        (b'{"graph": {"places": [1]}}', "each place must be an object"),
        (b'{"graph": {"places": [{"type": "x"}]}}', "needs a name"),
        (b'{"graph": {"places": [{"name": "a", "src": 99}]}}', "src must be"),
        (b'{"graph": {"places": [{"name": "a", "code": "x"}]}}', "unknown key 'code'"),
        (b'{"graph": {"places": [{"name": "a", "value": {"k": 1}}]}}', "expected a number"),
        (b'{"graph": {"transitions": [{"name": "t", "params": []}]}}', "params must be"),
        (b'{"graph": {"transitions": [{"name": "t", "params": {"out": "x"}}]}}', "may not hold"),
        (b'{"graph": {"extra": 1}}', "unknown key 'extra'"),
        (b'{"graph": {"title": 3}}', "title must be a string"),
        (b'{"graph": {"probe": 3}}', "probe must be an object"),
        (b'{"graph": {"places": [{"name": "a", "src": 0}, {"name": "b", "src": 0}]}}', "same src"),
    ],
)
def test_malformed_json_gets_a_400_with_a_message(ball, body, message):
    client, _, path = ball
    before = path.read_bytes()
    r = client.post(
        f"/{TOKEN}/api/save", content=body, headers={"Content-Type": "application/json"}
    )
    assert r.status_code == 400
    assert message in r.json()["error"]
    assert "Traceback" not in r.text
    assert path.read_bytes() == before


def test_bad_fields_of_the_routes(ball):
    client, _, _ = ball
    view = _view(client)
    assert _post(client, "api/run", {"seq": "1", "graph": view}).status_code == 400
    assert _post(client, "api/run", {"seq": 1, "graph": view, "selected": 3}).status_code == 400
    r = _post(client, "api/arc", {"graph": view, "source": 1, "target": "p"})
    assert r.status_code == 400
    r = _post(client, "api/arc", {"graph": view, "source": "x1", "target": "p", "types": []})
    assert r.status_code == 400


def test_nothing_sent_is_evaluated(ball):
    client, _, path = ball
    view = _view(client)
    view["places"][0]["dist"] = "__import__('os').remove('x')"
    view["places"][0].pop("u")
    out = _post(client, "api/check", {"graph": view}).json()
    assert not out["ok"]
    assert out["errors"][0]["node"] == "neg_r1"
    view = _view(client)
    view["title"] = 'x"\n[[place]]\nname = "injected'
    assert _post(client, "api/save", {"graph": view}).status_code == 200
    assert load_graph(path).title == view["title"]  # a string stays a string


def test_an_internal_error_is_one_line(ball, monkeypatch):
    client, _, _ = ball
    from mtmc.workbench import compute

    def boom(*_a, **_k):
        raise ZeroDivisionError("division by zero")

    view = _view(client)
    monkeypatch.setattr(compute, "check_text", boom)
    r = _post(client, "api/check", {"graph": view})
    assert r.status_code == 500
    assert r.json() == {"error": "internal error: ZeroDivisionError: division by zero"}


def test_live_run_reports_a_failed_run_at_its_transition():
    # a uniform angle of ±180° takes the plane of three points through degenerate trials
    text = (
        '[[place]]\nname = "a"\ntype = "point"\nvalue = [0, 0, 0]\n'
        '[[place]]\nname = "b"\ntype = "point"\nvalue = [1, 0, 0]\nu = 1.0\n'
        '[[place]]\nname = "c"\ntype = "point"\nvalue = [0, 1, 0]\nu = 1.0\n'
        '[[transition]]\nname = "pl"\nop = "plane"\nin = ["a", "b", "c"]\nout = "q"\n'
    )
    out = live_run(text, "g.toml", trials=2**14)
    if out["ok"]:  # no trial degenerate enough: the run stands
        assert "q" in out["places"]
    else:
        assert out["errors"][0]["node"] == "pl"


def test_check_payload_accepts_a_view_of_the_file():
    view = graph_json((GRAPHS / "bcs_origin.toml").read_text())
    assert check_payload(copy.deepcopy(view), view) == view


def test_the_summary_gives_the_coverage_ellipsoid_of_a_point(ball):
    # JCGM 102 §7.7.2: k² is the q-th smallest squared Mahalanobis distance of the trials
    # from their mean (q = ceil(p M)), the semi-axes k √λ of the covariance; recomputed here
    # from the same 2^14 RQMC trials with NumPy alone
    from mtmc.graph import run_graph
    from mtmc.workbench.compute import LIVE_SEED, LIVE_TRIALS

    client, _, path = ball
    out = _post(client, "api/run", {"seq": 1, "graph": _view(client), "selected": "p"}).json()
    (region,) = out["summary"]["regions"]
    assert region["unit"] == "mm"
    res = run_graph(load_graph(path), LIVE_TRIALS, LIVE_SEED, keep=["p"], sampling="sobol")
    x = np.asarray(res.places["p"].result.samples)
    d = x - x.mean(axis=0)
    cov = d.T @ d / (len(x) - 1)
    m2 = np.einsum("ri,ij,rj->r", d, np.linalg.inv(cov), d)
    k = np.sqrt(np.sort(m2)[int(np.ceil(0.95 * len(x))) - 1])
    want = np.sort(k * np.sqrt(np.linalg.eigvalsh(cov)))[::-1]
    assert region["k"] == pytest.approx(k, abs=1e-3)
    # through an eigendecomposition: to the conditioning of the covariance (κ ≈ 2 here)
    np.testing.assert_allclose(region["semi_axes_value"], want, rtol=1e-9)


def test_a_key_added_to_a_table_goes_above_the_comment_of_the_next():
    """A position added on save goes into its own table, above the comment lines that
    introduce the next table (it went below them, where it read as the next table's)."""
    text = (
        'title = "t"\n'
        "[[place]]\n"
        'name = "a"\n'
        'type = "real"\n'
        "value = 1.0\n"
        "\n"
        "# --- the second place: b, the one this comment is about\n"
        "[[place]]\n"
        'name = "b"\n'
        'type = "real"\n'
        "value = 2.0\n"
    )
    doc = GraphDocument(text, "g.toml")
    view = copy.deepcopy(doc.view)
    view["places"][0]["pos"] = [10.0, 20.0]
    out = doc.render(view)
    first, second = out.split("# --- the second place", 1)
    assert "pos = [10.0, 20.0]" in first
    assert "pos" not in second
    # nothing else moved: the one line added
    added = [ln for ln in difflib.ndiff(text.splitlines(), out.splitlines()) if ln[0] in "+-"]
    assert added == ["+ pos = [10.0, 20.0]"]
    assert tomllib.loads(out)["place"][0]["pos"] == [10.0, 20.0]
