"""The demo runs the shipped studies into one folder with an index page; it computes nothing.

Each study's numbers are checked against the library calls it wraps in
``tests/study/test_study_kinds.py``; here: the folder, the index, the last line, the
options, and the study results against independent references.
"""

from __future__ import annotations

import ast
import json
import math
import re
import shutil
from pathlib import Path

import pytest

from conftest import absent
from mtmc import demo, load_graph
from mtmc.cli.main import main
from mtmc.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
M = 1000  # the mass calibration's MC u within 4/sqrt(2M) = 9 % of JCGM 101's, 40 % from the GUM's


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo") / "mtmc-demo"
    lines: list[str] = []
    # one quantity of each report drawn: the run, the folders, the index and the lines are
    # what is tested here; every figure of every shipped study's report, drawn at the
    # default, is held to the layout rule below (shipped folders) and read by test_units
    index = demo.run_demo(out, trials=M, seed=101, echo=lines.append, plotted=1)
    return out, index, lines


def test_every_study_has_its_result_folder_and_the_index_links_them(quick):
    out, index, lines = quick
    stems = [Path(s).stem for s in demo.STUDIES]
    assert sorted(p.name for p in out.iterdir()) == sorted([*stems, "index.html"])
    page = index.read_text(encoding="utf-8")
    assert re.findall(r'href="([^"]+)"', page) == [f"{s}/report.html" for s in stems]
    for s in stems:
        for f in ("result.json", "provenance.json", "report.html", "quantities.csv", "study.toml"):
            assert (out / s / f).is_file(), (s, f)
        result = json.loads((out / s / "result.json").read_text(encoding="utf-8"))
        assert result["trials"] == M
        assert result["seed"] == 101
        assert result["title"] in page
    assert lines[-1] == f"Report: {index}"
    assert len(lines) == len(stems) + 2
    # each headline states U with its unit and the coverage probability (JCGM 100 §7.2.4)
    assert lines[0].startswith("Mass calibration (JCGM 101 §9.3): dm = ")
    for line in lines[:-2]:
        # (in the unit of the study: a verification or an artefact study in µm)
        assert re.search(r" = -?[0-9.]+ (mm|mg|µm), U = [0-9.]+ (mm|mg|µm)", line), line
        assert "(U at p = 95 %; " in line, line
        assert "±" not in line
    assert re.search(r"dm = [0-9.]+ mg, U = [0-9.]+ mg", page)
    assert '<td class="n">95 %</td>' in page


def test_the_results_against_independent_references(quick):
    out, _, _ = quick
    mass = json.loads((out / "mass_calibration" / "result.json").read_text())["quantities"][0]
    # JCGM 101 Table 7: GUM u = 0.0539 mg; MC u = 0.0754 mg within the MC noise of u
    assert mass["gum"]["u"] == pytest.approx(0.0539, abs=5e-5)
    assert mass["monte_carlo"]["u"] == pytest.approx(0.0754, rel=4 / math.sqrt(2 * M))
    bcs = json.loads((out / "bcs_origin" / "result.json").read_text())
    d_ac = bcs["quantities"][0]
    assert d_ac["name"] == "d_ac"
    # the example's nominal A-C distance: C balls at z = -10 with r2 = 40 mm
    assert d_ac["gum"]["estimate"] == pytest.approx(50.0, abs=1e-9)
    assert bcs["sweep"]["surrogate"]["max_rel_error"] <= 0.05  # Stryczek: at most 5 %
    assert len(bcs["sweep"]["u"]) == 25


def test_same_seed_same_numbers(quick, tmp_path):
    out, _, _ = quick
    demo.run_demo(
        tmp_path, trials=M, seed=101, studies=["axis_c.toml"], echo=lambda _: None, plotted=1
    )
    a = json.loads((out / "axis_c" / "result.json").read_text())
    b = json.loads((tmp_path / "axis_c" / "result.json").read_text())
    assert a == b


def test_demo_py_holds_no_mathematics():
    tree = ast.parse(Path(demo.__file__).read_text(encoding="utf-8"))
    imported = {
        (n.module or "") if isinstance(n, ast.ImportFrom) else a.name
        for n in ast.walk(tree)
        if isinstance(n, ast.Import | ast.ImportFrom)
        for a in n.names
    }
    assert not {m for m in imported if m.split(".")[0] in ("numpy", "scipy", "sympy")}
    assert not {m for m in imported if m.startswith("mtmc.uncertainty")}


def test_package_studies_and_graphs_are_the_examples():
    for name in demo.STUDIES:
        assert demo.study_path(name).read_bytes() == (EXAMPLES / "studies" / name).read_bytes()
    graphs = Path(demo.__file__).parent / "data" / "graphs"
    for path in graphs.glob("*.toml"):
        assert path.read_bytes() == (EXAMPLES / "graphs" / path.name).read_bytes(), path.name
        assert load_graph(path).file == path.name


def test_bad_trials_is_refused_with_a_message(capsys, tmp_path):
    with pytest.raises(SystemExit) as exc:
        demo.main(["--trials", "1", "--out", str(tmp_path)])
    assert exc.value.code == 2
    assert "--trials: expected an integer >= 2, got 1" in capsys.readouterr().err
    assert main(["demo", "--trials", "1", "-o", str(tmp_path)]) == 2


@pytest.mark.parametrize("bad", ["-1", "some", "1.5", "٣"])
def test_bad_plots_is_refused_before_any_study_runs(capsys, tmp_path, bad):
    out = tmp_path / "d"
    with pytest.raises(SystemExit) as exc:
        demo.main(["--plots", bad, "--out", str(out)])
    assert exc.value.code == 2
    assert f"--plots: expected a whole number >= 0 or 'all', got {bad!r}" in capsys.readouterr().err
    assert main(["demo", "--plots", bad, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err == f"mtmc: error: --plots: expected a whole number >= 0 or 'all', got {bad!r}\n"
    with pytest.raises(InputError, match="whole number >= 0 or 'all'"):
        demo.run_demo(out, plotted=bad, echo=lambda _: None)
    assert not out.exists()  # nothing ran, nothing written


def test_out_that_is_a_file_is_refused_with_a_message(capsys, tmp_path):
    f = tmp_path / "results"
    f.write_text("not a folder")
    with pytest.raises(SystemExit) as exc:
        demo.main(["--out", str(f)])
    assert exc.value.code == 2
    assert f"--out: expected a folder, but {f} is a file" in capsys.readouterr().err


def test_cli_demo_ends_with_the_report_path(capsys, tmp_path, monkeypatch):
    monkeypatch.setattr(demo, "STUDIES", ("ball_centre.toml",))
    argv = ["demo", "-o", str(tmp_path / "d"), "--trials", "2000", "--quiet"]
    assert main(argv) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last == f"Report: {tmp_path / 'd' / 'index.html'}"
    argv_w = [*argv[:2], str(tmp_path / "w"), *argv[3:], "--workers", "2", "--plots", "0"]
    assert main(argv_w) == 0
    for d in ("d", "w"):
        assert (tmp_path / d / "ball_centre" / "result.json").is_file()
    one, two = (
        json.loads((tmp_path / d / "ball_centre" / "result.json").read_text()) for d in "dw"
    )
    assert one["quantities"] == two["quantities"]
    # --plots 0: the report draws no histogram and names each quantity it does not draw
    pages = [(tmp_path / d / "ball_centre" / "report.html").read_text("utf-8") for d in "dw"]
    n = len(one["quantities"])
    assert pages[0].count('data-plot="histogram:') == min(n, 12)
    assert pages[1].count('data-plot="histogram:') == 0
    assert pages[1].count('class="unplotted"') == n


# ---------------------------------------------------------------------------------------
# every plot of every report, as a browser shows it

#: For every figure of the page (every ``<details>`` opened), the text elements of its SVG
#: that leave the figure's box, and the pairs of them that overlap. A text's box is its
#: line box (ascent to descent), a little taller than its glyphs: two boxes that share less
#: than 1 px in either direction (the first x tick label under the last y tick label, at a
#: corner, share 0.6 px) have glyphs apart.
TEXT_JS = """() => {
  for (const d of document.querySelectorAll('details')) d.open = true;
  const out = [];
  for (const fig of document.querySelectorAll('figure[data-plot]')) {
    const svg = fig.querySelector('svg');
    if (!svg) continue;
    const plot = fig.getAttribute('data-plot'), box = svg.getBoundingClientRect();
    const texts = Array.from(svg.querySelectorAll('text'))
      .map((t) => ({s: t.textContent.trim(), r: t.getBoundingClientRect()}))
      .filter((t) => t.s && t.r.width > 0);
    for (const t of texts) {
      const r = t.r;
      if (r.left < box.left - 0.5 || r.right > box.right + 0.5 ||
          r.top < box.top - 0.5 || r.bottom > box.bottom + 0.5) out.push([plot, 'outside', t.s]);
    }
    for (let i = 0; i < texts.length; i++) {
      for (let j = i + 1; j < texts.length; j++) {
        const a = texts[i].r, b = texts[j].r;
        const w = Math.min(a.right, b.right) - Math.max(a.left, b.left);
        const h = Math.min(a.bottom, b.bottom) - Math.max(a.top, b.top);
        if (w > 1 && h > 1) out.push([plot, texts[i].s, texts[j].s]);
      }
    }
  }
  return [document.querySelectorAll('figure[data-plot] svg text').length, out];
}"""


def _fonts() -> str:
    """The names of the system's font files, where a browser finds its fonts (Matplotlib
    draws with its own copy of DejaVu Sans: it is not one of them)."""
    from matplotlib import font_manager

    return " ".join(Path(f).name for f in font_manager.findSystemFonts())


def test_no_text_of_a_plot_overlaps_another_or_leaves_its_figure(shipped):
    # Reference: the text boxes Chromium lays out (the reports name DejaVu Sans, the font
    # Matplotlib measured). Before report.plots._fit the 13 reports of `make demo` had 199
    # texts out of their figures or over another (an axis label cut at the left edge,
    # -0.0075 over -0.0050 under a histogram, a 3-D view's ticks over its labels).
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:  # pragma: no cover - the dev extra installs it
        absent("playwright (Python)", 'pip install -e ".[dev]"')
    path = shutil.which("chromium") or shutil.which("chromium-browser")
    if path is None:
        absent("chromium", "Debian: apt-get install chromium")
    if "DejaVuSans.ttf" not in _fonts():
        # the browser would draw the plots' text in another font than Matplotlib measured
        absent("DejaVu Sans", "Debian: apt-get install fonts-dejavu-core")
    # every shipped study's report, each quantity's plots drawn to the default limit
    studies = sorted((EXAMPLES / "studies").glob("*.toml"))
    reports = [shipped(p.stem) / "report.html" for p in studies]
    assert len(reports) == 16
    found: dict[str, list[list[str]]] = {}
    texts = 0
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=path, args=["--no-sandbox", "--disable-gpu"])
        try:
            for report in reports:
                page = browser.new_page(viewport={"width": 1280, "height": 900})
                page.goto(report.as_uri())
                page.wait_for_load_state("load")
                n, bad = page.evaluate(TEXT_JS)
                texts += n
                if bad:
                    found[report.parent.name] = bad
                page.close()
        finally:
            browser.close()
    assert texts > 3000  # every report's plots were looked at, with their tick labels
    assert found == {}
