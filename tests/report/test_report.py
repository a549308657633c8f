"""The report shows what the result holds: every number in the HTML is the one in result.json."""

from __future__ import annotations

import json
import re
import shutil
from html.parser import HTMLParser
from pathlib import Path

import pytest

from mtmc.report import fmt, html, render
from mtmc.study import load_study, write_result

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "examples" / "studies"


class _Cells(HTMLParser):
    """Collects (data-key, data-value, text) of every element carrying a data-key, and plots."""

    def __init__(self) -> None:
        super().__init__()
        self.cells: list[tuple[str, str, str]] = []
        self.plots: dict[str, int] = {}
        self._open: list[tuple[str, str, str, list[str]]] = []
        self._plot: str | None = None
        self.urls: list[str] = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        for k in ("src", "href"):
            if k in a and a[k] is not None:
                self.urls.append(a[k])
        if "data-key" in a:
            self._open.append((tag, a["data-key"], a["data-value"], []))
        if tag == "figure" and "data-plot" in a:
            self._plot = a["data-plot"]
            self.plots[self._plot] = 0
        if tag in ("path", "use") and self._plot is not None:
            self.plots[self._plot] += 1

    def handle_endtag(self, tag):
        if self._open and self._open[-1][0] == tag:
            _, key, value, text = self._open.pop()
            self.cells.append((key, value, "".join(text).strip()))
        if tag == "figure":
            self._plot = None

    def handle_data(self, data):
        for item in self._open:
            item[3].append(data)


def _rounds_to(text, want):
    """Whether ``text`` is ``want`` rounded to the last decimal place that ``text`` shows."""
    places = len(text.split(".")[1]) if "." in text else 0
    return abs(float(text) - want) <= 0.5 * 10.0**-places * (1 + 1e-9)


def _lookup(doc, key):
    cur = doc
    for name, index in re.findall(r"([A-Za-z_0-9]+)|\[(\d+)\]", key):
        cur = cur[name] if name else cur[int(index)]
    return cur


@pytest.fixture(scope="module", params=["mass_calibration", "bcs_origin", "axis_c", "five_axis"])
def folder(request, shipped):
    return shipped(request.param)


def test_every_number_shown_is_the_one_in_result_json(folder):
    doc = json.loads((folder / "result.json").read_text(encoding="utf-8"))
    parser = _Cells()
    parser.feed((folder / "report.html").read_text(encoding="utf-8"))
    assert len(parser.cells) > 10 * len(doc["quantities"])
    keys = set()
    for key, value, text in parser.cells:
        want = _lookup(doc, key)
        keys.add(key)
        if isinstance(want, str):
            assert value == want, key
            assert text == want, key
        else:
            assert float(value) == want, key
            if "share" in key:
                assert text == f"{100 * want:.1f} %", key
            elif "max_rel_error" in key:
                assert text == f"{100 * want:.2g} %", key
            elif text != fmt(want):
                # a value rounded for display: the nearest number at its last decimal place
                assert _rounds_to(text, want), (key, text, want)
    # every quantity's statement is there
    for i, q in enumerate(doc["quantities"]):
        for k in ("reported.estimate", "reported.U", "monte_carlo.u", "monte_carlo.symmetric[1]"):
            assert f"quantities[{i}].{k}" in keys
        if q["gum"]:
            assert f"quantities[{i}].gum.u" in keys
            assert f"quantities[{i}].validation.d_low" in keys
            shown = [k for k in keys if k.startswith(f"quantities[{i}].budget[")]
            # a budget of at most 20 inputs shows them all (those the first-order budget
            # cannot see included); a longer one those with a share of 0.01 % or more
            lines = (
                q["budget"]
                if len(q["budget"]) <= 20
                else [b for b in q["budget"] if b["share"] >= 1e-4]
            )
            if q["gum"]["u"] == 0:  # a constant output: no shares of u²(y) to give
                lines = []
            assert len({k.split("]")[1] for k in shown}) == len(lines)


def test_every_plot_is_inline_and_nothing_is_fetched(folder):
    doc = json.loads((folder / "result.json").read_text(encoding="utf-8"))
    text = (folder / "report.html").read_text(encoding="utf-8")
    parser = _Cells()
    parser.feed(text)
    expected = {f"{k}:{q['name']}" for q in doc["quantities"] for k in ("histogram", "convergence")}
    expected |= {f"region:{r['name']}" for r in doc["regions"]}
    if doc.get("graph"):
        expected.add("graph")
    if doc.get("sweep"):
        expected.add("sweep")
    if doc.get("machine"):
        expected.add("machine")
    expected |= {f"field:{f['name']}" for f in doc.get("fields", [])}
    assert set(parser.plots) == expected
    assert all(n > 0 for n in parser.plots.values()), parser.plots
    assert all(u.startswith("#") for u in parser.urls), parser.urls
    assert "<link" not in text
    assert "@import" not in text
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", text)


def test_render_refuses_what_is_not_a_result(tmp_path):
    from mtmc.errors import InputError

    with pytest.raises(InputError, match=r"no result\.json"):
        render(tmp_path)
    with pytest.raises(InputError, match="mtmc-result/1"):
        html({"format": "other"})


def test_report_of_a_result_object_equals_the_folder(tmp_path):
    from mtmc import render_report

    study = load_study(STUDIES / "mass_calibration.toml")
    result = study.run(trials=2000, seed=1)
    folder = write_result(result, tmp_path / "m")
    page = render_report(result)
    assert page.count("<svg") == (folder / "report.html").read_text().count("<svg") == 2
    assert render_report(folder) == folder / "report.html"
    assert render_report(result, tmp_path / "page.html").read_text(encoding="utf-8") == page


def _decimals(text):
    return len(text.split(".")[1]) if "." in text else 0


def test_summary_rounds_u_and_the_interval_and_the_tables_keep_one_decimal_place(shipped):
    # JCGM 101 §5.5: u(y) to two significant digits, the interval ends to its decimal place
    # (the summary); the tables of each quantity show every length to one decimal place
    # (that of u at four digits), so d_low and d_high can be recomputed from them
    folder = shipped("bcs_origin")
    doc = json.loads((folder / "result.json").read_text(encoding="utf-8"))
    parser = _Cells()
    parser.feed((folder / "report.html").read_text(encoding="utf-8"))
    shown: dict[str, list[str]] = {}
    for key, _, text in parser.cells:
        shown.setdefault(key, []).append(text)
    for i, q in enumerate(doc["quantities"]):
        mc, u = q["monte_carlo"], q["monte_carlo"]["u"]
        u_summary, u_table = shown[f"quantities[{i}].monte_carlo.u"]
        assert len(u_summary.lstrip("0.")) == 2, u_summary  # two significant digits
        places = _decimals(u_summary)
        lo, hi = (
            shown[f"quantities[{i}].monte_carlo.{mc['interval']}[0]"][0],
            shown[f"quantities[{i}].monte_carlo.{mc['interval']}[1]"][0],
        )
        assert _decimals(lo) == _decimals(hi) == places, (lo, hi, u_summary)
        assert shown[f"quantities[{i}].monte_carlo.k"][0] == f"{mc['k']:.2f}"
        assert shown[f"quantities[{i}].gum.u"][0] == f"{q['gum']['u']:.{places}f}"
        # the table of the quantity: u to four digits, every length at its decimal place
        assert len(u_table.lstrip("0.")) == 4, u_table
        for k in ("monte_carlo.estimate", "monte_carlo.U", "gum.estimate", "gum.interval[0]"):
            text = shown[f"quantities[{i}].{k}"][-1]
            assert _decimals(text) == _decimals(u_table), (k, text, u_table)
        v = q["validation"]
        g_lo = float(shown[f"quantities[{i}].gum.interval[0]"][-1])
        m_lo = float(shown[f"quantities[{i}].monte_carlo.{v['kind']}[0]"][-1])
        assert abs(abs(g_lo - m_lo) - v["d_low"]) <= 10.0 ** -_decimals(u_table)
        assert u == pytest.approx(float(u_table), abs=10.0 ** -_decimals(u_table))
    page = (folder / "report.html").read_text(encoding="utf-8")
    assert re.search(r"\(k = \d\.\d\d, p = 95 %\)", page)


@pytest.mark.parametrize("folder", ["bcs_origin"], indirect=True)  # the study with a sweep
def test_the_sweep_names_u_and_gives_its_table_units(folder):
    doc = json.loads((folder / "result.json").read_text(encoding="utf-8"))
    (table,) = [t for t in doc["tables"] if t["name"] == "sweep"]
    assert table["columns"] == [
        "probe.u_probe / mm",
        "probe.u_axis / mm",
        "estimate / mm",
        "u / mm",
        "u_surrogate / mm",
        "rel_error",
    ]
    assert doc["sweep"]["surrogate"]["formula"].startswith("u = sqrt(")
    page = (folder / "report.html").read_text(encoding="utf-8")
    assert "the surrogate u² = c0 + Σ cᵢ σᵢ²" in page
    assert "U² = c0" not in page


def test_the_inputs_of_a_kinematics_study_carry_their_units(folder):
    # ISO 230: a displacement error in mm, an angular one in rad, side by side in one table
    doc = json.loads((folder / "result.json").read_text(encoding="utf-8"))
    page = (folder / "report.html").read_text(encoding="utf-8")
    if doc["kind"] != "kinematics":
        given = {x["name"]: x["unit"] for x in doc["inputs"] if "unit" in x}
        if folder.name == "mass_calibration":  # a propagate study that gives its units
            mass, density = "mg", "kg/m³"
            assert given == {"m_rc": mass, "dm_rc": mass} | dict.fromkeys(
                ("rho_a", "rho_w", "rho_r"), density
            )
            assert "<th>unit of x</th>" in page
            assert "<td>kg/m³</td>" in page
        else:
            assert given == {}
            assert "<th>unit of x</th>" not in page
        return
    units = {x["name"]: x["unit"] for x in doc["inputs"]}
    assert units["EX0C"] == units["EZ0A"] == "mm"
    assert units["EA0C"] == units["EC0Y"] == "rad"
    assert "<th>unit of x</th>" in page
    rows = re.findall(
        # name, PDF, estimate, u and ν (∞: every error's u exactly known), then the unit
        r"<tr><td>(E\w+)</td><td><code>[^<]*</code></td>(?:<td[^>]*>[^<]*</td>){3}<td>(\w+)</td>",
        page,
    )
    assert dict(rows) == units


def test_a_study_without_input_rows_points_to_its_file_in_the_folder(shipped, tmp_path):
    # a result with no input rows (result.json without them): the page says where the
    # inputs are, and that place exists (study.toml of the folder, the file whose SHA-256
    # is shown)
    study = load_study(STUDIES / "aguado2017.toml")
    folder = Path(shutil.copytree(shipped("aguado2017"), tmp_path / "v"))
    doc = json.loads((folder / "result.json").read_text(encoding="utf-8"))
    (folder / "result.json").write_text(json.dumps({**doc, "inputs": []}), encoding="utf-8")
    page = render(folder).read_text(encoding="utf-8")
    assert "<code>study.toml</code> of this result folder" in page
    assert "in the provenance" not in page
    assert (folder / "study.toml").read_text(encoding="utf-8") == study.source.text
    # the summary says why its GUM columns are empty, and marks, where it stands, each u
    # that has not settled over the last half of the trials (JCGM 101 §7.9.2)
    summary = page[page.index('<section id="summary">') :]
    summary = summary[: summary.index("</section>")]
    assert "— in the GUM columns: the volumetric errors are the largest" in summary
    for i, q in enumerate(doc["quantities"]):
        cv = q["convergence"]
        mark = f'data-key="quantities[{i}].monte_carlo.u" data-value="{q["monte_carlo"]["u"]!r}">'
        cell = summary[summary.index(mark) :].split("</td>", 1)[0]
        assert ("not settled" in cell) == (cv["last_half"]["u"] > cv["delta"]), q["name"]
    assert any(
        q["convergence"]["last_half"]["u"] > q["convergence"]["delta"] for q in doc["quantities"]
    )


def test_the_histogram_draws_the_pdf_the_gum_interval_is_of():
    # a t input gives a finite ν_eff: the GUM interval is y ± t_p(ν_eff) u, so the curve
    # beside the histogram is that t, not a normal one (which the legend would misname)
    from mtmc.study import loads_study

    text = (
        'kind = "propagate"\ntitle = "t"\nmodel = "a + b"\noutput = "y"\nunit = "mm"\n'
        '[inputs]\na = "t(4, loc=10, scale=0.1)"\nb = "normal(0, 0.05)"\n'
    )
    result = loads_study(text).run(trials=2000, seed=1)
    dof = result.quantity("y").gum.dof
    assert 6.0 < dof < 6.5  # Welch-Satterthwaite: 0.0125**2 / (0.01**2 / 4) = 6.25
    page = html(result.to_dict())
    assert f"GUM: t PDF, ν_eff = {dof:.3g}" in page
    assert "GUM: normal PDF" not in page
    assert f"t with ν<sub>eff</sub> = {fmt(dof, 3)} degrees of freedom" in page
    normal = html(load_study(STUDIES / "mass_calibration.toml").run(trials=2000, seed=1).to_dict())
    assert "GUM: normal PDF" in normal
    assert "the PDF of the GUM (normal)" in normal


def test_the_histogram_draws_lengths_in_the_studys_unit_about_the_estimate():
    # a study in µm is drawn in µm as a deviation from the estimate, as its tables give it:
    # with u = 2 µm the ticks of the x axis are a few µm (a factor of 1000 would put them in
    # the thousands, one of 1/1000 below 0.01)
    from mtmc.report.plots import histogram_svg
    from mtmc.study import loads_study

    text = (
        'kind = "propagate"\ntitle = "t"\nmodel = "a"\noutput = "y"\nunit = "µm"\n'
        '[inputs]\na = "normal(10, 2)"\n'
    )
    q = loads_study(text).run(trials=4000, seed=1).to_dict()["quantities"][0]
    svg = histogram_svg(q)
    assert "y − estimate / µm" in svg
    ticks = [float(t.replace("−", "-")) for t in re.findall(r">(−?\d+(?:\.\d+)?)</text>", svg)]
    assert ticks
    assert max(abs(t) for t in ticks) <= 10.0
    assert max(abs(t) for t in ticks) >= 4.0


def test_the_budget_gives_the_unit_of_each_sensitivity_coefficient():
    # c = ∂y/∂x has the unit of y over that of x: mg/mg is 1, mg over kg/m³ is
    # mg/(kg/m³); the air-buoyancy inputs' c are 0 or the rounding of the estimates
    # (ρ_a's estimate (1.1 + 1.3)/2 is 1.2000000000000002, one ulp from 1.2, so
    # c(ρ_w) = 1e5 mg · 2.2e-16 / (8000 kg/m³)² ≈ 3.5e-19), and the text says so
    study = load_study(STUDIES / "mass_calibration.toml")
    page = html(study.run(trials=2000, seed=1).to_dict())
    budget = page[page.index("Uncertainty budget (JCGM 100 §5.1.3)") :]
    budget = budget[: budget.index("</table>")]
    assert "<th>unit of c</th>" in budget
    cells = {
        name: re.findall(r"<td>([^<]*)</td>", row)
        for name, row in re.findall(r"<tr><td>(\w+)</td>(.*?)</tr>", budget)
    }
    assert cells["m_rc"] == ["mg", "1"]
    assert cells["rho_a"] == ["kg/m³", "mg/(kg/m³)"]
    assert "or no more than the rounding of the estimates (|c| u(x) below 10⁻⁶ u(y))" in page
    assert 1.2 != 0.5 * (1.1 + 1.3)  # the premise of the rounding


def test_mtmc_report_plots_draws_as_many_histograms_as_asked(shipped, tmp_path, capsys):
    # the report draws the first MAX_PLOTTED quantities' histograms and convergence; the
    # reader who wants every one asks for them, and the page of the default says how
    from mtmc.cli.main import main
    from mtmc.errors import InputError
    from mtmc.report import MAX_PLOTTED

    # the ballbar study's 14 quantities: two past the limit (the 36 of Wang et al. took
    # 72 figures to draw them all, 23 s of the suite)
    folder = Path(shutil.copytree(shipped("circle_xy"), tmp_path / "w"))
    n = len(json.loads((folder / "result.json").read_text(encoding="utf-8"))["quantities"])
    assert n == 14 > MAX_PLOTTED

    def drawn() -> tuple[int, int, int]:
        page = (folder / "report.html").read_text(encoding="utf-8")
        return (
            page.count('data-plot="histogram:'),
            page.count('data-plot="convergence:'),
            page.count('class="unplotted"'),
        )

    assert drawn() == (MAX_PLOTTED, MAX_PLOTTED, n - MAX_PLOTTED)
    assert "<code>mtmc report FOLDER --plots all</code> draws every one" in (
        folder / "report.html"
    ).read_text(encoding="utf-8")
    assert main(["report", str(folder), "--plots", "all"]) == 0
    assert drawn() == (n, n, 0)
    assert main(["report", str(folder), "--plots", "2"]) == 0
    assert drawn() == (2, 2, n - 2)
    capsys.readouterr()
    before = (folder / "report.html").read_bytes()
    for bad in ("-1", "some", "1.5", "٣"):
        assert main(["report", str(folder), "--plots", bad]) == 2, bad
        err = capsys.readouterr().err
        assert err.count("\n") == 1, err
        assert "--plots: expected a whole number >= 0 or 'all'" in err, err
    assert (folder / "report.html").read_bytes() == before  # nothing written
    for bad_value in (-1, 1.5, True, "some"):
        with pytest.raises(InputError, match="whole number >= 0 or 'all'"):
            render(folder, plotted=bad_value)
