"""The workbench against a file changed under it and against hostile bodies.

References: the file on disk (an edit made there is never lost by a save), and
docs/editor.md (a body that is not the JSON a route takes is a 400 with a message).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

pytest.importorskip("starlette")
from starlette.testclient import TestClient

from mtmc.study import load_result
from mtmc.workbench import Session, create_app

ROOT = Path(__file__).resolve().parents[2]
HOST = "127.0.0.1:8765"
TOKEN = "t0ken-for-the-tests"


@pytest.fixture
def ball(tmp_path: Path):
    path = tmp_path / "ball_centre.toml"
    shutil.copy(ROOT / "examples" / "graphs" / "ball_centre.toml", path)
    session = Session(path)
    client = TestClient(create_app(session, TOKEN, HOST), base_url=f"http://{HOST}")
    with client:
        yield client, session, path


def _post(client: TestClient, route: str, body: object):
    return client.post(f"/{TOKEN}/{route}", json=body)


def test_a_save_over_an_edit_made_on_disk_is_refused_and_the_edit_kept(ball) -> None:
    client, _, path = ball
    view = client.get(f"/{TOKEN}/api/graph").json()["view"]
    edited = path.read_text().replace("u_axis = 0.002", "u_axis = 0.009")
    assert edited != path.read_text()
    path.write_text(edited)
    view["places"][0]["value"] = -12.5
    r = _post(client, "api/save", {"graph": view})
    assert r.status_code == 409
    assert "changed on disk" in r.json()["error"]
    assert path.read_text() == edited  # the edit on disk is kept
    # the page reloaded shows the file as it is now, and saves over it again
    again = client.get(f"/{TOKEN}/api/graph").json()
    assert again["view"]["probe"]["u_axis"] == 0.009
    assert _post(client, "api/save", {"graph": again["view"]}).status_code == 200
    assert path.read_text() == edited


def test_saves_in_a_row_from_the_page_are_not_refused(ball) -> None:
    client, _, path = ball
    view = client.get(f"/{TOKEN}/api/graph").json()["view"]
    for value in (-12.5, -12.6):
        view["places"][0]["value"] = value
        r = _post(client, "api/save", {"graph": view})
        assert r.status_code == 200
        view = r.json()["view"]
    assert "-12.6" in path.read_text()


def test_a_file_removed_on_disk_is_a_change_too(ball) -> None:
    client, _, path = ball
    view = client.get(f"/{TOKEN}/api/graph").json()["view"]
    path.unlink()
    assert _post(client, "api/save", {"graph": view}).status_code == 409
    assert not path.exists()


@pytest.mark.parametrize(
    ("body", "words"),
    [
        (b"[" * 100_000 + b"]" * 100_000, "nested deeper"),
        (b'{"graph": ' + b"1" * 5000 + b"}", "5000 digits"),
        (b'{"trials": 1e999}', "largest number"),
    ],
)
@pytest.mark.parametrize("route", ["api/save", "api/run", "api/full-run", "api/check"])
def test_bodies_that_would_break_the_parser_get_a_400(ball, body: bytes, words: str, route) -> None:
    client, _, _ = ball
    r = client.post(f"/{TOKEN}/{route}", content=body, headers={"Content-Type": "application/json"})
    assert r.status_code == 400
    assert words in r.json()["error"]


def test_a_full_run_with_an_emoji_in_the_title(ball) -> None:
    client, _, _ = ball
    view = client.get(f"/{TOKEN}/api/graph").json()["view"]
    view["title"] = "Kugel 😀 \x7f"
    assert _post(client, "api/save", {"graph": view}).status_code == 200
    r = _post(client, "api/full-run", {"outputs": ["p"], "trials": 1000, "seed": 3})
    assert r.status_code == 200, r.text
    assert load_result(r.json()["folder"]).title == "Kugel 😀 \x7f"
