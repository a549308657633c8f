"""``mtmc graph edit``: the URL first, 127.0.0.1 only, Ctrl-C stops cleanly, twice over an
unsaved edit; a real server on a free port, always stopped."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import pytest

pytest.importorskip("uvicorn")

ROOT = Path(__file__).resolve().parents[2]
GRAPH = ROOT / "examples" / "graphs" / "ball_centre.toml"
TIMEOUT = 20.0
MAIN = "import sys; from mtmc.cli.main import main; sys.exit(main())"


def _start(path: Path, *args: str) -> tuple[subprocess.Popen[str], str]:
    cmd = [sys.executable, "-c", MAIN, "graph", "edit", str(path), "--no-browser", *args]
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    url = proc.stdout.readline().strip() if proc.stdout else ""
    return proc, url


def _stop(proc: subprocess.Popen[str]) -> tuple[str, str]:
    if proc.poll() is None:
        proc.kill()
    out, err = proc.communicate(timeout=TIMEOUT)
    return out, err


def _request(url: str, body: dict | None = None) -> dict:
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(url, data=data, method="GET" if body is None else "POST")
    if body is not None:
        req.add_header("Content-Type", "application/json")
    with urllib.request.urlopen(req, timeout=TIMEOUT) as resp:
        return json.loads(resp.read())


def _wait_exit(proc: subprocess.Popen[str]) -> int | None:
    deadline = time.monotonic() + TIMEOUT
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            return proc.returncode
        time.sleep(0.05)
    return None


@pytest.fixture
def graph(tmp_path):
    path = tmp_path / "ball_centre.toml"
    shutil.copy(GRAPH, path)
    return path


def test_url_first_then_ctrl_c_stops_cleanly(graph):
    proc, url = _start(graph)
    try:
        assert url.startswith("http://127.0.0.1:")
        assert url.endswith("/")
        token = url.rstrip("/").rsplit("/", 1)[1]
        assert len(token) >= 32
        data = _request(url + "api/graph")
        assert data["file"] == "ball_centre.toml"
        with pytest.raises(urllib.error.HTTPError) as info:
            _request(url.replace(token, "x" * len(token)) + "api/graph")
        assert info.value.code == 404
        proc.send_signal(signal.SIGINT)
        assert _wait_exit(proc) == 0
    finally:
        out, err = _stop(proc)
    assert "workbench stopped" in out
    assert "Traceback" not in err


def test_unsaved_edit_needs_a_second_ctrl_c(graph):
    proc, url = _start(graph)
    try:
        assert _request(url + "api/dirty", {"dirty": True}) == {"unsaved": True}
        proc.send_signal(signal.SIGINT)
        assert proc.stdout is not None
        warning = proc.stdout.readline()
        assert "unsaved edits" in warning
        assert "Ctrl-C again" in warning
        assert proc.poll() is None
        assert _request(url + "api/graph")["file"] == "ball_centre.toml"  # still serving
        proc.send_signal(signal.SIGINT)
        assert _wait_exit(proc) == 0
    finally:
        out, err = _stop(proc)
    assert "unsaved edits discarded" in out
    assert "Traceback" not in err
    assert graph.read_bytes() == GRAPH.read_bytes()


def test_a_taken_port_or_a_bad_file_is_one_line(graph, tmp_path):
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen(1)
        port = s.getsockname()[1]
        proc, _ = _start(graph, "--port", str(port))
        _, err = _stop(proc) if _wait_exit(proc) is not None else ("", "still running")
    assert proc.returncode == 2
    assert err.strip().startswith("mtmc: error:")
    assert f"127.0.0.1:{port}" in err
    assert len(err.strip().splitlines()) == 1
    bad = tmp_path / "bad.toml"
    bad.write_text("a = [")
    proc, _ = _start(bad)
    assert _wait_exit(proc) == 2
    _, err = _stop(proc)
    assert "not valid TOML" in err
    assert "Traceback" not in err


def test_without_the_extra_the_command_says_what_to_install(graph):
    code = (
        "import sys; sys.modules['starlette'] = None; "
        "from mtmc.cli.main import main; sys.exit(main())"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code, "graph", "edit", str(graph), "--no-browser"],
        capture_output=True,
        text=True,
        timeout=TIMEOUT,
    )
    assert proc.returncode == 2
    assert 'pip install "mtmc[editor]"' in proc.stderr
