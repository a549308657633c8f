"""The report's layout in Chromium (Playwright): it fits the page, it can be navigated, and
it answers what it shows.

- No table or figure is wider than the window unless inside a box that scrolls on its own
  and fits; the graph is drawn to the width of the page, at full size on request.
- A contents bar stays in view, its links lead to ids of the page; each quantity is a
  ``<details>`` whose summary line is shown, opened by a link to it and by printing.
- The error vectors of a field fit their axes in every view, the magnification stated.
- The artefact report (Wang et al. 2022, 36 quantities) is measured: it was 33,800 px
  tall at 1280 px wide with every quantity open; a limit guards its new height.
- A verification and an artefact report list their inputs; a t input shows the u the GUM
  takes, as in the budget, and the standard deviation of the PDF apart, labelled.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from conftest import absent
from mtmc.report.plots import field_figure, vector_magnification
from mtmc.study import load_study, write_result

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "examples" / "studies"
VIEW = {"width": 1280, "height": 900}

#: Every table, figure and drawing wider than the window, with whether a box that
#: scrolls by itself (``overflow-x: auto`` or ``scroll``) and fits the window holds it.
WIDE_JS = """() => {
  const vw = document.documentElement.clientWidth, out = [];
  for (const el of document.querySelectorAll('table, figure, svg, pre')) {
    const r = el.getBoundingClientRect();
    if (r.width === 0 || r.right <= vw + 0.5) continue;
    let boxed = false;
    for (let p = el.parentElement; p && p !== document.body; p = p.parentElement) {
      const s = getComputedStyle(p);
      if ((s.overflowX === 'auto' || s.overflowX === 'scroll') &&
          p.getBoundingClientRect().right <= vw + 0.5) { boxed = true; break; }
    }
    out.push({tag: el.tagName, right: Math.round(r.right), boxed: boxed});
  }
  return out;
}"""

#: The href of every link of the contents bar and whether an element has that id.
LINKS_JS = """() => Array.from(document.querySelectorAll('nav.contents a[href^="#"]')).map(
  (a) => [a.getAttribute('href'), !!document.getElementById(a.getAttribute('href').slice(1))])"""


# ---------------------------------------------------------------------------------------
# the error vectors fit their axes (no browser)


def _aguado_like() -> dict[str, Any]:
    """A field as Aguado et al. 2017 gives it: 81 points at Z = 0, errors of a few µm."""
    g = np.linspace(0.0, 400.0, 9)
    pts = np.array([[x, y, 0.0] for x in g for y in g])
    rng = np.random.default_rng(3)
    vals = rng.normal(0.0, 1.0, pts.shape) * np.array([0.0004, 0.0004, 0.0015])
    return {
        "name": "compensation_bias",
        "kind": "vectors",
        "points": pts.tolist(),
        "values": vals.tolist(),
        "unit": "mm",
        "axes": ["x", "y", "z"],
        "magnification": 1000.0,
    }


def test_error_vectors_fit_their_axes_in_every_view_and_say_their_magnification():
    f = _aguado_like()
    mag = vector_magnification(f)
    pts = np.asarray(f["points"])
    vec = np.asarray(f["values"]) * mag
    tips = pts + vec
    span = float(np.ptp(pts, axis=0).max())
    longest = float(np.linalg.norm(vec, axis=1).max())
    # long enough to be seen as vectors, short enough to leave the others in view
    assert 0.02 * span <= longest <= 0.3 * span, (mag, longest)
    fig = field_figure(f)
    a1, a2, a3 = fig.axes[:3]
    for ax in (a1, a2, a3):
        assert ax.get_title() == f"vectors × {mag:g}"
    for ax, (i, j) in ((a1, (0, 1)), (a2, (0, 2))):
        (quiver,) = [c for c in ax.collections if hasattr(c, "U")]
        x, y = quiver.X + quiver.U, quiver.Y + quiver.V  # the tips as drawn
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        assert x0 <= min(pts[:, i].min(), x.min())
        assert max(pts[:, i].max(), x.max()) <= x1
        assert y0 <= min(pts[:, j].min(), y.min())
        assert max(pts[:, j].max(), y.max()) <= y1
    # 3-D: the lines of the quiver (shaft and head) inside the limits of the box
    (lines,) = [c for c in a3.collections if hasattr(c, "_segments3d")]
    seg = np.concatenate([np.asarray(s) for s in lines._segments3d])
    assert len(seg) >= len(pts)
    for k, lim in enumerate((a3.get_xlim3d(), a3.get_ylim3d(), a3.get_zlim3d())):
        assert lim[0] <= seg[:, k].min(), (k, lim)
        assert seg[:, k].max() <= lim[1], (k, lim)
        assert lim[0] <= tips[:, k].min(), (k, lim)
        assert tips[:, k].max() <= lim[1], (k, lim)


def test_a_magnification_that_fits_is_kept():
    f = _aguado_like()
    longest = float(np.linalg.norm(np.asarray(f["values"]), axis=1).max())
    f["magnification"] = 0.1 * 400.0 / longest
    assert vector_magnification(f) == f["magnification"]


# ---------------------------------------------------------------------------------------
# the inputs of a t, a verification and an artefact study (no browser)


def test_a_t_input_shows_the_u_of_the_budget_and_its_standard_deviation_apart(tmp_path):
    path = tmp_path / "t.toml"
    path.write_text(
        'kind = "propagate"\nmodel = "a + b"\n[inputs]\na = "t(4, 1, 0.1)"\nb = "normal(0, 0.1)"\n',
        encoding="utf-8",
    )
    study = load_study(path)
    write_result(study.run(trials=200, seed=1), tmp_path / "out", study_text=study.source.text)
    doc = json.loads((tmp_path / "out" / "result.json").read_text(encoding="utf-8"))
    a = doc["inputs"][0]
    (budget_a,) = [b for b in doc["quantities"][0]["budget"] if b["name"] == "a"]
    assert a["u"] == budget_a["u"] == 0.1  # the scale: the one u on the page
    assert a["sd"] == pytest.approx(0.1 * np.sqrt(2.0), rel=1e-15)  # √(ν/(ν − 2)), ν = 4
    assert "sd" not in doc["inputs"][1]
    page = (tmp_path / "out" / "report.html").read_text(encoding="utf-8")
    assert "standard uncertainty u(x) (the GUM\u2019s, as in the budget)" in page
    assert "standard deviation of the PDF (what the Monte Carlo draws)" in page


@pytest.fixture(scope="module")
def artefact(shipped) -> Path:
    """The report folder of wang2022 (Table 2, 36 quantities)."""
    return shipped("wang2022")


@pytest.fixture(scope="module")
def verification(shipped) -> Path:
    """The report folder of aguado2017 (a verification)."""
    return shipped("aguado2017")


def test_the_verification_and_artefact_results_list_their_inputs(artefact, verification):
    ver = json.loads((verification / "result.json").read_text(encoding="utf-8"))["inputs"]
    names = [x["name"] for x in ver]
    assert names[0].startswith("tracker range L (each of the 81 readings)")
    assert ver[0]["distribution"].startswith("normal(0, 0.004 + 8e-07·L)")
    assert [x["u"] for x in ver[1:3]] == [24e-6, 24e-6]  # Aguado et al. 2017: 24 µrad
    assert [x["unit"] for x in ver] == ["mm", "rad", "rad"]
    art = json.loads((artefact / "result.json").read_text(encoding="utf-8"))["inputs"]
    assert [x["u"] for x in art[:3]] == [0.36, 0.41, 0.25]  # [probing] repeatability_um
    assert art[0]["name"] == "probing repeatability, X (each of the 4050 points)"
    assert art[3]["name"] == "calibrated centres (15 coordinates)"
    for folder in (artefact, verification):
        page = (folder / "report.html").read_text(encoding="utf-8")
        assert "The study names its inputs in its file" not in page
        assert 'data-key="inputs[0].u"' in page
    # the identified setup errors differ from the injected ones (dpx 1 µm, identified
    # about -3.1 µm): the report says why where the table stands
    doc = json.loads((artefact / "result.json").read_text(encoding="utf-8"))
    setup = next(t for t in doc["tables"] if t["name"] == "setup_errors")
    dpx = next(r for r in setup["rows"] if r[0] == "dpx")
    assert dpx[1] == pytest.approx(1.0)
    assert dpx[2] == pytest.approx(-3.13, abs=0.01)  # noise-free, docs/artefact.md
    page = (artefact / "report.html").read_text(encoding="utf-8")
    assert "They are not the injected ones where the machine has errors" in page


# ---------------------------------------------------------------------------------------
# in the browser

try:
    from playwright.sync_api import sync_playwright
except ImportError:  # pragma: no cover - the dev extra installs it
    sync_playwright = None


@pytest.fixture(scope="module")
def browser():
    """Debian's chromium driven by Playwright (no browser download)."""
    if sync_playwright is None:
        absent("playwright (Python)", 'pip install -e ".[dev]"')
    path = shutil.which("chromium") or shutil.which("chromium-browser")
    if path is None:
        absent("chromium", "Debian: apt-get install chromium")
    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=path, args=["--no-sandbox", "--disable-gpu"])
        try:
            yield b
        finally:
            b.close()


def _open(browser, report: Path):
    """A page of the report at 1280 × 900 px, and the errors its scripts raise."""
    pg = browser.new_page(viewport=VIEW)
    errors: list[str] = []
    pg.on("pageerror", lambda e: errors.append(str(e)))
    pg.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    pg.goto(report.as_uri())
    pg.wait_for_load_state("load")
    return pg, errors


def _check_page(pg, errors) -> None:
    """Nothing wider than the window outside its own scroll box; every contents link lands."""
    wide = pg.evaluate(WIDE_JS)
    assert [w for w in wide if not w["boxed"]] == []
    links = pg.evaluate(LINKS_JS)
    assert links
    assert all(ok for _, ok in links), links
    assert errors == []


@pytest.fixture(scope="module")
def graph(shipped) -> Path:
    """bcs_origin: a graph of 68 places, 3,600 px wide at its own size."""
    return shipped("bcs_origin")


def test_the_artefact_report_fits_the_window_and_is_short(browser, artefact):
    pg, errors = _open(browser, artefact / "report.html")
    try:
        _check_page(pg, errors)
        # Table 2 (18 columns) scrolls in its own box, its header at the top of the box
        (table2,) = [t for t in pg.query_selector_all("table") if "r_max_model" in t.inner_text()]
        box = table2.evaluate(
            "(t) => [t.scrollWidth, t.clientWidth, getComputedStyle(t).overflowX]"
        )
        assert box[0] > box[1], box
        assert box[2] == "auto", box
        # the 36 quantities are collapsed: their summary lines shown, their plots not
        shut = pg.evaluate("() => document.querySelectorAll('details.quantity:not([open])').length")
        assert shut == 36
        height = pg.evaluate("() => document.documentElement.scrollHeight")
        print(f"height of the artefact report at 1280 px: {height} px (33,800 px all open)")
        assert height < 12_000
        # the contents bar stays at the top of the window when scrolled
        pg.evaluate("() => window.scrollTo(0, 3000)")
        top = pg.evaluate(
            "() => document.querySelector('nav.contents').getBoundingClientRect().top"
        )
        assert abs(top) < 1.0
    finally:
        pg.close()


def test_a_link_opens_its_quantity_and_printing_opens_them_all(browser, artefact):
    pg, errors = _open(browser, artefact / "report.html")
    try:
        pg.click("nav.contents details.toc > summary")
        pg.click('nav.contents a[href="#q-4"]')
        assert pg.evaluate("() => document.getElementById('q-4').open")
        assert pg.evaluate("() => document.querySelectorAll('details.quantity[open]').length") == 1
        fig = pg.locator('#q-4 figure[data-plot^="histogram:"]')
        assert fig.bounding_box()["width"] > 100
        pg.evaluate("() => window.dispatchEvent(new Event('beforeprint'))")
        assert (
            pg.evaluate("() => document.querySelectorAll('details.quantity:not([open])').length")
            == 0
        )
        pg.emulate_media(media="print")
        assert (
            pg.evaluate("() => getComputedStyle(document.querySelector('nav.contents')).display")
            == "none"
        )
        # on A4 (about 718 px inside the margins) every table is whole: Table 2 included
        pg.set_viewport_size({"width": 718, "height": 1000})
        assert pg.evaluate(WIDE_JS) == []
        pg.set_viewport_size(VIEW)
        pg.emulate_media(media="screen")
        pg.evaluate("() => window.dispatchEvent(new Event('afterprint'))")
        assert pg.evaluate("() => document.querySelectorAll('details.quantity[open]').length") == 1
        assert errors == []
    finally:
        pg.close()


def test_the_verification_report_fits_the_window(browser, verification):
    pg, errors = _open(browser, verification / "report.html")
    try:
        _check_page(pg, errors)
        titles = pg.evaluate(
            "() => Array.from(document.querySelectorAll("
            "'figure[data-plot=\"field:compensation_bias\"] text'))"
            ".map((t) => t.textContent).filter((t) => t.startsWith('vectors ×'))"
        )
        assert len(titles) == 3, titles  # one in every view
        assert len(set(titles)) == 1, titles
    finally:
        pg.close()


def test_the_graph_is_drawn_to_the_page_width_and_at_full_size_on_request(browser, graph):
    pg, errors = _open(browser, graph / "report.html")
    try:
        _check_page(pg, errors)
        fig = pg.locator('figure[data-plot="graph"]')
        size = fig.evaluate("(f) => [f.scrollWidth, f.clientWidth, f.scrollHeight, f.clientHeight]")
        assert size[0] <= size[1], size  # every place in view
        assert size[2] <= size[3], size
        svg = fig.locator("svg").bounding_box()
        assert svg["x"] >= 0
        assert svg["x"] + svg["width"] <= VIEW["width"]
        pg.click('label[for="graph-full"]')
        text_px = fig.evaluate("(f) => f.querySelector('svg text').getBoundingClientRect().height")
        assert text_px >= 8.0  # 7 pt names, read at the drawing's own size
        size = fig.evaluate("(f) => [f.scrollWidth, f.clientWidth]")
        assert size[0] > size[1]  # now it scrolls, in its own box
        _check_page(pg, errors)
    finally:
        pg.close()


def test_a_study_with_u_zero_is_reported(browser, tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('kind="propagate"\nmodel="a"\n[inputs]\na=2\n', encoding="utf-8")
    out = _run_file(path, tmp_path / "out")
    pg, errors = _open(browser, out / "report.html")
    try:
        _check_page(pg, errors)
        assert pg.evaluate("() => document.getElementById('q-0').open")  # one quantity: open
        assert "u(y) = 0: every one of the 50 trials gave y = 2" in pg.inner_text("#q-0")
    finally:
        pg.close()


def _run_file(path: Path, out: Path) -> Path:
    study = load_study(path)
    write_result(study.run(trials=50, seed=1), out, study_text=study.source.text)
    return out


def test_inputs_the_first_order_budget_cannot_see_are_shown_and_named(tmp_path):
    # JCGM 101 §9.3: the air and mass densities have c = 0 at the estimates, yet they make
    # u(y) 0.075 mg by Monte Carlo against 0.054 mg by the GUM
    import re

    from mtmc.study import load_study, write_result

    root = Path(__file__).resolve().parents[2]
    r = load_study(root / "examples" / "studies" / "mass_calibration.toml").run(
        trials=20_000, seed=1
    )
    write_result(r, tmp_path / "out")
    html = (tmp_path / "out" / "report.html").read_text(encoding="utf-8")
    for name in ("rho_a", "rho_w", "rho_r"):
        assert f"<tr><td>{name}</td>" in html  # a budget row of its own
    note = re.sub("<[^>]+>", "", html[html.index('class="unseen"') :].split("</p>")[0])
    assert note.startswith('class="unseen">rho_a, rho_w, rho_r: uncertain')
    assert "0.076 mg by Monte Carlo against 0.054 mg by the GUM" in note


def test_inputs_are_shown_as_the_study_wrote_them(tmp_path):
    from mtmc.study import write_result
    from mtmc.study.spec import loads_study

    text = (
        'kind = "propagate"\nmodel = "l + dl"\nunit = "mm"\n'
        '[inputs]\nl = "normal(50.000623, 0.000025)"\ndl = "uniform(-0.0001, 0.0001)"\n'
    )
    r = loads_study(text, file="s.toml").run(trials=2000, seed=1)
    write_result(r, tmp_path / "out")
    html = (tmp_path / "out" / "report.html").read_text(encoding="utf-8")
    assert ">50.000623</td>" in html  # not 50.0006
    assert ">2.5e-05</td>" in html
    assert ">5.7735e-05</td>" in html  # 0.0001/√3: a derived value, 6 digits
