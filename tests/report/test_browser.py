"""The report in a real browser: headless Chromium loads it with no console message, draws
every plot with a size, and leaves a screenshot for a person to look at."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from conftest import absent

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
    """Debian's chromium (``apt-get install chromium``; ``.ci/run`` installs it in CI)."""
    path = _find()
    if path is None:
        absent("chromium", "Debian: apt-get install chromium")
    return path


@pytest.fixture(scope="module")
def page(shipped):
    return shipped("bcs_origin") / "report.html"


def _run(chromium: str, profile: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [chromium, *FLAGS, f"--user-data-dir={profile}", *args],
        capture_output=True,
        text=True,
        timeout=180,
    )


def _dom(chromium: str, page: Path, profile: Path) -> str:
    """The page's DOM after its scripts ran; no console message on the way."""
    proc = _run(
        chromium,
        profile,
        "--enable-logging=stderr",
        "--v=0",
        "--window-size=1280,4000",
        "--dump-dom",
        page.as_uri(),
    )
    assert "<figure" in proc.stdout, proc.stderr[-2000:]
    console = [ln for ln in proc.stderr.splitlines() if ":CONSOLE" in ln]
    assert console == []
    return proc.stdout


def test_the_page_loads_without_console_messages_and_draws_every_plot(chromium, page, tmp_path):
    dom = _dom(chromium, page, tmp_path / "profile")
    figures = re.findall(r"<figure[^>]*>", dom)
    plots = [f for f in figures if "data-plot=" in f]
    assert len(plots) >= 2 * 7 + 6 + 2  # 7 quantities, 6 ellipses, the graph and the sweep
    not_drawn = [f for f in plots if 'data-rendered="yes"' not in f]
    assert not_drawn == []
    # the graph is drawn to the width of the page, every place in view (its names at a
    # size that can be read once drawn at full size: test_report_layout.py)
    (graph,) = [f for f in plots if 'data-plot="graph"' in f]
    assert float(re.search(r'data-text-px="([\d.]+)"', graph).group(1)) > 0.0, graph


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


@pytest.fixture(scope="module")
def artefact_page(shipped):
    return shipped("wang2022") / "report.html"


def test_the_artefact_report_draws_the_histograms_of_its_first_quantities(
    chromium, artefact_page, tmp_path
):
    from mtmc.report import MAX_PLOTTED

    dom = _dom(chromium, artefact_page, tmp_path / "profile")
    hists = re.findall(r'<figure[^>]*data-plot="histogram:([^"]+)"[^>]*>(.*?)</figure>', dom, re.S)
    names = [n for n, _ in hists]
    # of r_max and r_avg at the nine poses of Table 2 and the 18 setup errors, the first
    # MAX_PLOTTED (12): r_max at every pose, r_avg at the first three; the rest are named
    assert MAX_PLOTTED == 12
    assert sum(n.startswith("r_max.") for n in names) == 9
    assert sum(n.startswith("r_avg.") for n in names) == 3
    assert sum(n.startswith("setup.") for n in names) == 0
    assert "r_max.b-10_c5" in names
    assert dom.count('class="unplotted"') == 36 - MAX_PLOTTED
    assert "The histogram and convergence of setup.dw5z are not drawn" in dom
    for name, body in hists:
        # the bars (one path of the stairs), the interval band and the GUM curve
        assert body.count("<path") >= 3, name
        assert "GUM" in body, name
        stairs = max(re.findall(r'<path d="([^"]*)"', body), key=len)
        assert stairs.count("L") > 30, name  # 60 bins: a real histogram, not an empty axis
    figures = re.findall(r'<figure[^>]*data-plot="histogram:[^"]*"[^>]*>', dom)
    assert [f for f in figures if 'data-rendered="yes"' not in f] == []
