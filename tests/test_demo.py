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
from pathlib import Path

import pytest

from mtmc import demo, load_graph
from mtmc.cli.main import main

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
M = 4000


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo") / "mtmc-demo"
    lines: list[str] = []
    index = demo.run_demo(out, trials=M, seed=101, echo=lines.append)
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
    demo.run_demo(tmp_path, trials=M, seed=101, studies=["axis_c.toml"], echo=lambda _: None)
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
    assert main([*argv[:2], str(tmp_path / "w"), *argv[3:], "--workers", "2"]) == 0
    for d in ("d", "w"):
        assert (tmp_path / d / "ball_centre" / "result.json").is_file()
    one, two = (
        json.loads((tmp_path / d / "ball_centre" / "result.json").read_text()) for d in "dw"
    )
    assert one["quantities"] == two["quantities"]
