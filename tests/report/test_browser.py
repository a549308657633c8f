"""The report in a real browser: headless Chromium loads it with no console message, draws
every plot with a size, and leaves a screenshot for a person to look at."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from mtmc.study import load_study, write_result

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "examples" / "studies"
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def _find() -> str | None:
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    return None


@pytest.fixture(scope="session")
def chromium() -> str:
    """Debian's chromium, installed with apt-get when absent (as root, as in CI)."""
    path = _find()
    if path is None and shutil.which("apt-get") and hasattr(os, "geteuid") and os.geteuid() == 0:
        env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
        subprocess.run(["apt-get", "update"], capture_output=True, env=env, timeout=600)
        subprocess.run(
            ["apt-get", "install", "-y", "chromium"], capture_output=True, env=env, timeout=900
        )
        path = _find()
    if path is None:
        pytest.skip("chromium is not installed and cannot be installed here (apt-get as root)")
    return path


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    out = tmp_path_factory.mktemp("browser") / "bcs_origin"
    study = load_study(STUDIES / "bcs_origin.toml")
    write_result(study.run(trials=4000, seed=2), out, study_text=study.source.text)
    return out / "report.html"


def _run(chromium: str, profile: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [chromium, *FLAGS, f"--user-data-dir={profile}", *args],
        capture_output=True,
        text=True,
        timeout=180,
    )


def test_the_page_loads_without_console_messages_and_draws_every_plot(chromium, page, tmp_path):
    proc = _run(
        chromium,
        tmp_path / "profile",
        "--enable-logging=stderr",
        "--v=0",
        "--window-size=1280,4000",
        "--dump-dom",
        page.as_uri(),
    )
    dom = proc.stdout
    assert "<figure" in dom, proc.stderr[-2000:]
    console = [ln for ln in proc.stderr.splitlines() if ":CONSOLE" in ln]
    assert console == []
    figures = re.findall(r"<figure[^>]*>", dom)
    plots = [f for f in figures if "data-plot=" in f]
    assert len(plots) >= 2 * 7 + 6 + 2  # 7 quantities, 6 ellipses, the graph and the sweep
    not_drawn = [f for f in plots if 'data-rendered="yes"' not in f]
    assert not_drawn == []


def test_a_screenshot_is_saved(chromium, page, tmp_path_factory):
    shot = tmp_path_factory.getbasetemp() / "report-screenshot.png"
    proc = _run(
        chromium,
        tmp_path_factory.mktemp("profile"),
        f"--screenshot={shot}",
        "--window-size=1280,4000",
        page.as_uri(),
    )
    assert shot.is_file(), proc.stderr[-2000:]
    data = shot.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(data) > 50_000
    print(f"screenshot of the report: {shot}")
