"""One unit rule: the unit a study is written in is the unit of its results everywhere.

From each shipped study's result folder (the session's ``shipped`` fixture: few trials),
its ``result.json`` and its ``report.html``, these tests check that every quantity is given
in the unit of its study file, that the tables and the plots of one quantity (and of a
field, a coverage region, a sweep, a positioning test, the outputs together) name the same
unit, and that ``mtmc run`` and the command of the study's kind print one unit
(``docs/results-format.md``).
"""

from __future__ import annotations

import html as html_text
import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mtmc.cli.main import main as cli
from mtmc.study import write_result

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "examples" / "studies"

#: The unit each shipped study gives its quantities in, as its file writes them (``1``:
#: the components of a unit direction).
STUDY_UNITS: dict[str, set[str]] = {
    # verification: machine errors and tracker noise written in um and urad, travel in mm
    "aguado2016": {"µm"},
    "aguado2017": {"µm"},
    # graph studies: the graph file's units = "mm"
    "axis_a": {"mm", "1"},
    "axis_c": {"mm", "1"},
    "ball_centre": {"mm"},
    "bcs_origin": {"mm"},
    # propagate: the file's unit = "mm" / "mg", or the unit of each of its [outputs]
    "bore_type_a": {"mm"},
    "gauge_blocks_correlated": {"mm"},
    "mass_calibration": {"mg"},
    "polar_coordinates": {"mm", "rad"},
    # kinematics: errors and poses in mm ("lengths in mm, angles in rad")
    "five_axis": {"mm"},
    # positioning: units = "mm,um", the deviations and the parameters in µm
    "positioning_x": {"µm"},
    # artefact: "Lengths in um, angles in urad" (positions of the artefact and probe in mm)
    "wang2022": {"µm"},
    # circular: the parameters and the errors in the report's µm, µrad, µm/m and ms
    "circle_xy": {"µm", "µrad", "µm/m", "ms"},
    "circle_c_axis": {"µm", "µrad"},
    "circle_b_axis": {"µm", "µrad"},
}

#: Units of length: within one report each kind of quantity has one of them.
LENGTHS = {"nm", "µm", "um", "mm", "m"}


def _units_of(label: str) -> str | None:
    """The unit of an axis label or a column head ``what / unit`` (``⁻¹`` and ``²`` dropped)."""
    m = re.search(r" / (?:\(([^\s()]+)\)|([^\s/()]+))$", label.strip())
    if m is None:
        return None
    return (m.group(1) or m.group(2)).replace("⁻¹", "").replace("²", "")


def _texts(svg: str) -> list[str]:
    """The texts of an inline SVG (its labels and ticks), unescaped."""
    out = []
    for t in re.findall(r"<text\b[^>]*>(.*?)</text>", svg, flags=re.S):
        out.append(html_text.unescape(re.sub(r"<[^>]+>", "", t)).strip())
    return out


def _plot_units(svg: str) -> set[str]:
    """The units named by the labels of an inline SVG."""
    return {u for u in map(_units_of, _texts(svg)) if u is not None}


def _figures(page: str) -> dict[str, str]:
    """The inline SVG of each ``<figure data-plot=...>`` of a report."""
    return {
        html_text.unescape(name): body
        for name, body in re.findall(
            r"<figure\b[^>]*\bdata-plot=\"([^\"]+)\"[^>]*>(.*?)</figure>", page, flags=re.S
        )
    }


class Report:
    """A shipped study's result folder: its ``result.json`` and ``report.html``."""

    def __init__(self, name: str, folder: Path) -> None:
        self.name = name
        self.doc: dict[str, Any] = json.loads((folder / "result.json").read_text("utf-8"))
        self.page = (folder / "report.html").read_text("utf-8")
        self.figures = _figures(self.page)
        self.heads = [
            html_text.unescape(re.sub(r"<[^>]+>", "", h)).strip()
            for h in re.findall(r"<th\b[^>]*>(.*?)</th>", self.page, flags=re.S)
        ]


@pytest.fixture(scope="module")
def reports(shipped: Callable[[str], Path]) -> dict[str, Report]:
    return {name: Report(name, shipped(name)) for name in STUDY_UNITS}


def test_every_quantity_is_in_the_unit_its_study_is_written_in(reports: dict[str, Report]) -> None:
    assert set(STUDY_UNITS) == {p.stem for p in STUDIES.glob("*.toml")}  # every shipped study
    for name, units in STUDY_UNITS.items():
        got = {q["unit"] for q in reports[name].doc["quantities"]}
        assert got == units, name


def _check_quantities(rep: Report) -> None:
    """The heading of each quantity and the axes of its histogram and convergence: its unit."""
    from mtmc.report import plotted_count

    drawn = plotted_count(rep.doc)
    for i, q in enumerate(rep.doc["quantities"]):
        unit = q["unit"]
        if unit in ("", "1"):
            shown: set[str] = set()
        else:
            heads = re.findall(
                rf"<h3\b[^>]*>\s*{re.escape(q['name'])} / ([^<\s]+)\s*</h3>", rep.page
            )
            assert heads == [unit], (rep.name, q["name"], heads)
            shown = {unit}
        if not q["monte_carlo"]["u"]:
            continue
        if i >= drawn:  # the report draws the first MAX_PLOTTED quantities
            assert f"histogram:{q['name']}" not in rep.figures, (rep.name, q["name"])
            continue
        for kind in ("histogram", "convergence"):
            svg = rep.figures[f"{kind}:{q['name']}"]
            assert _plot_units(svg) == shown, (rep.name, kind, q["name"], _plot_units(svg))


def _check_the_rest(rep: Report) -> None:
    """Fields, regions, a sweep, a positioning test, the outputs together: table = plot."""
    name, doc = rep.name, rep.doc
    lengths = {q["unit"] for q in doc["quantities"]} & LENGTHS
    for f in doc.get("fields", []):
        # a value of a field is an error or an uncertainty, in the unit of the quantities
        assert {f["unit"]} == lengths, (name, f["name"], f["unit"])
        units = _plot_units(rep.figures[f"field:{f['name']}"])
        assert units <= {f["unit"], "mm"}, (name, f["name"], units)  # points in mm
        if f["kind"] == "map":
            assert f["unit"] in units, (name, f["name"], units)
        if f["labels"]:
            col = "vector" if f["kind"] == "vectors" else f["name"]
            assert f"{col} / {f['unit']}" in rep.heads, (name, f["name"])
    for g in doc.get("regions", []):
        row = re.search(
            rf"<td>{re.escape(html_text.escape(g['name']))}</td><td>([^<]*)</td>", rep.page
        )
        assert row is not None, (name, g["name"])
        assert row.group(1) == g["unit"], (name, g["name"])
        assert _plot_units(rep.figures[f"region:{g['name']}"]) == {g["unit"]}, (name, g["name"])
    sweep = doc.get("sweep")
    if sweep:
        (table,) = [t for t in doc["tables"] if t["name"] == "sweep"]
        cols = {c.split(" / ")[0]: _units_of(c) for c in table["columns"]}
        assert cols["u"] == sweep["unit"]
        assert f"c0 / {sweep['unit']}²" in rep.heads
        texts = _texts(rep.figures["sweep"])
        assert f"u({sweep['output']}) / {sweep['unit']}" in texts
        for n in sweep["names"]:
            assert cols[n] == sweep["grid_unit"]
            assert f"{n} / {cols[n]}" in texts, (n, texts)
    pos = doc.get("positioning")
    if pos:
        units = _plot_units(rep.figures["positioning"])
        assert units == {pos["unit"], pos["target_unit"]}
        assert {q["unit"] for q in doc["quantities"]} == {pos["unit"]}
    joint = doc.get("joint")
    if joint and "joint" in rep.figures:
        assert _plot_units(rep.figures["joint"]) == set(joint["units"]) - {"", "1"}


def test_the_tables_and_the_plots_of_a_quantity_name_one_unit(reports: dict[str, Report]) -> None:
    for rep in reports.values():
        _check_quantities(rep)


def test_fields_regions_sweeps_and_joint_plots_name_the_unit_of_their_tables(
    reports: dict[str, Report],
) -> None:
    for rep in reports.values():
        _check_the_rest(rep)


def test_one_report_shows_lengths_in_the_studys_unit_and_positions_in_mm(
    reports: dict[str, Report],
) -> None:
    # every length unit on the page, in a plot or over a column, is the quantities' unit
    # or mm, the unit of positions (a point, a target, the workspace)
    for name, rep in reports.items():
        quantity_units = {q["unit"] for q in rep.doc["quantities"]}
        allowed = (quantity_units & LENGTHS) | {"mm"}
        seen = {u for svg in rep.figures.values() for u in _plot_units(svg)}
        seen |= {u for u in map(_units_of, rep.heads) if u is not None}
        assert seen & LENGTHS <= allowed, (name, seen & LENGTHS, allowed)
        for t in rep.doc["tables"]:
            units = {_units_of(c) for c in t["columns"]} & LENGTHS
            assert units <= allowed, (name, t["name"], units)
            if "unit" in t["columns"]:
                k = t["columns"].index("unit")
                assert {row[k] for row in t["rows"]} & LENGTHS <= allowed, (name, t["name"])


def _json(argv: list[str], capsys: pytest.CaptureFixture[str]) -> Any:
    capsys.readouterr()
    assert cli(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_mtmc_run_and_verify_simulate_print_the_verification_in_one_unit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = str(STUDIES / "aguado2017.toml")
    args = ["--trials", "30", "--seed", "2", "--json"]
    run = _json(["run", path, "-o", str(tmp_path / "r"), *args], capsys)
    ver = _json(["verify", "simulate", path, *args], capsys)
    by_name = {q["name"]: q for q in run["quantities"]}
    for stat in ("max", "mean", "min"):
        q = by_name[f"volumetric_error.compensated.{stat}"]
        assert q["unit"] == "µm"
        assert q["u"] == ver["compensated_ve_um"][stat]["u"]


def _graph(units: str, s: float) -> str:
    """A graph with a point probed and a real place, its lengths written times ``s``."""
    return (
        f'units = "{units}"\n[probe]\nu_axis = {0.001 * s}\nu_probe = {0.002 * s}\n'
        f'u_perp = 0.0\n[[place]]\nname = "a"\ntype = "real"\nvalue = {10 * s}\n'
        f'dist = "uniform({-0.003 * s}, {0.003 * s})"\n[[transition]]\nname = "m"\n'
        f'op = "meas"\nat = [{5 * s}, 0, 0]\ndirection = [1, 0, 0]\n'
        f'dist = "uniform({-0.002 * s}, {0.002 * s})"\nout = "p"\n'
    )


def test_a_graph_written_in_um_gives_its_study_in_um(tmp_path: Path) -> None:
    # the same graph in mm and in um (every length times 1000): the study of the um one
    # gives every quantity, region and its sweep in µm, each the mm value times 1000
    from mtmc.study import loads_study

    docs = {}
    for units, s in (("mm", 1), ("um", 1000)):
        d = tmp_path / units
        d.mkdir()
        (d / "g.toml").write_text(_graph(units, s), encoding="utf-8")
        text = (
            'kind = "graph"\ntitle = "t"\ngraph = "g.toml"\noutputs = ["p", "a"]\n'
            '[sweep]\noutput = "a"\ntrials = 200\n[sweep.vary]\n'
            f'"probe.u_probe" = "{0.001 * s}:{0.003 * s}:3"\n'
        )
        study = loads_study(text, file=str(d / "s.toml"), folder=d)
        write_result(study.run(trials=2000, seed=4), d / "out", study_text=text)
        rep = Report(units, d / "out")
        _check_quantities(rep)
        _check_the_rest(rep)
        docs[units] = rep.doc
    mm, um = docs["mm"], docs["um"]
    assert {q["unit"] for q in mm["quantities"]} == {"mm"}
    assert {q["unit"] for q in um["quantities"]} == {"µm"}
    for a, b in zip(mm["quantities"], um["quantities"], strict=True):
        assert b["monte_carlo"]["u"] == pytest.approx(1e3 * a["monte_carlo"]["u"], rel=1e-9)
        assert b["gum"]["u"] == pytest.approx(1e3 * a["gum"]["u"], rel=1e-9)
    assert {g["unit"] for g in um["regions"]} == {"µm"}
    for a, b in zip(mm["regions"], um["regions"], strict=True):
        np.testing.assert_allclose(b["semi_axes"], 1e3 * np.asarray(a["semi_axes"]), rtol=1e-9)
    assert (um["sweep"]["unit"], um["sweep"]["grid_unit"]) == ("µm", "µm")
    np.testing.assert_allclose(um["sweep"]["grid"], 1e3 * np.asarray(mm["sweep"]["grid"]))
    np.testing.assert_allclose(um["sweep"]["u"], 1e3 * np.asarray(mm["sweep"]["u"]), rtol=1e-9)
