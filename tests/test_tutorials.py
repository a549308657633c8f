"""The tutorials of docs/tutorials/ cannot rot.

For each tutorial: its generated tables equal what ``make_figures.py`` renders from the
committed numbers; a rerun of its case at the documented seed (at the documented trials
where that is quick, at fewer otherwise) gives the committed numbers; its figures are
written and small; its Python snippets and its ``mtmc`` commands run (at a few trials).

How close a rerun must come (``make_figures.tolerance``): within five Monte Carlo standard
errors at other trials; at the same trials, 1e-9 relative (``make_figures.RTOL``) where the
route has no ill-conditioned step, or the number's own tolerance, stored with its reason,
where its route amplifies rounding (a central difference of a non-smooth output, a fit):
another BLAS kernel sums in another order, so such a number is reproducible to its
conditioning. Nothing here claims the same bits across machines; the same bits for the same
seed on one machine, whatever the chunking or the executor, are tested with the engine.
"""

from __future__ import annotations

import importlib.util
import math
import re
import shlex
import sys
from pathlib import Path
from typing import Any

import pytest

from mtmc.cli.main import main as cli

ROOT = Path(__file__).resolve().parents[1]
TUTORIALS = ROOT / "docs" / "tutorials"


def _load() -> Any:
    spec = importlib.util.spec_from_file_location("make_figures", TUTORIALS / "make_figures.py")
    assert spec is not None
    assert spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules["make_figures"] = mod
    spec.loader.exec_module(mod)
    return mod


mf = _load()

#: The scale of the trials of each case in the rerun (1.0: the documented trials).
SCALES = {"stryczek": 1.0, "aguado2017": 1.0, "aguado2016": 0.1, "wang2022": 0.05}
NAMES = sorted(SCALES)

#: The figure files of the tutorials may not exceed this size (bytes).
MAX_FIGURE = 300 * 1024


def test_every_tutorial_is_tested() -> None:
    assert sorted(mf.CASES) == NAMES
    for name in NAMES:
        assert (TUTORIALS / f"{name}.md").is_file()


@pytest.mark.parametrize("name", NAMES)
def test_generated_blocks_are_current(name: str) -> None:
    text = (TUTORIALS / f"{name}.md").read_text(encoding="utf-8")
    keys = re.findall(r"<!-- generated: (\S+) -->", text)
    assert keys, "no generated block"
    assert text.count("<!-- end generated -->") == len(keys)
    assert mf.fill(text, mf.blocks(name, mf.read_numbers(name))) == text


def test_fill_replaces_only_the_blocks() -> None:
    text = "a\n<!-- generated: k -->\nold\n<!-- end generated -->\nb\n"
    new = "a\n<!-- generated: k -->\nnew\n<!-- end generated -->\nb\n"
    assert mf.fill(text, {"k": "new\n"}) == new
    with pytest.raises(KeyError):
        mf.fill(text, {})


def test_tolerance() -> None:
    doc = {"value": 1.0, "sd": 2.0, "n": 400}
    assert mf.tolerance(doc, {"value": 1.0, "n": 100}) == pytest.approx(
        5 * 2.0 * math.sqrt(1 / 400 + 1 / 100) + 1e-9
    )
    assert mf.tolerance(doc, {"value": 1.0, "n": 400}) == pytest.approx(1e-9)
    assert mf.tolerance({"value": 3.0}, {"value": 3.0}) == pytest.approx(3e-9)
    loose = mf.exact(0.12, tol=2e-8, why="a central difference")
    assert mf.tolerance(loose, {"value": 0.12}) == 2e-8
    assert mf.tolerance(mf.exact(50.0, tol=1e-12, why="x"), {"value": 50.0}) == pytest.approx(5e-8)
    with pytest.raises(ValueError, match="reason"):
        mf.exact(1.0, tol=1e-6)


@pytest.mark.parametrize("name", NAMES)
def test_every_loosened_tolerance_has_its_reason(name: str) -> None:
    for key, d in mf.read_numbers(name)["values"].items():
        if "tol" in d:
            assert d["why"].strip(), key
            # a tolerance from the conditioning, not a way to let any number through
            assert d["tol"] < 1e-3 * max(abs(d["value"]), 1e-300), key


@pytest.fixture(scope="module")
def reruns(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    out = {}
    for name in NAMES:
        run, figures, _ = mf.CASES[name]
        numbers, data = run(SCALES[name])
        folder = tmp_path_factory.mktemp(name)
        out[name] = (numbers, figures(data, folder))
    return out


@pytest.mark.parametrize("name", NAMES)
def test_numbers_reproduce(name: str, reruns: dict[str, Any]) -> None:
    doc = mf.read_numbers(name)
    numbers, _ = reruns[name]
    assert sorted(numbers["values"]) == sorted(doc["values"])
    bad = []
    for key, d in doc["values"].items():
        r = numbers["values"][key]
        tol = mf.tolerance(d, r)
        if not abs(r["value"] - d["value"]) <= tol:
            bad.append(f"{key}: documented {d['value']}, rerun {r['value']}, tolerance {tol}")
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("name", NAMES)
def test_figures_written_and_small(name: str, reruns: dict[str, Any]) -> None:
    _, paths = reruns[name]
    assert paths
    text = (TUTORIALS / f"{name}.md").read_text(encoding="utf-8")
    for p in paths:
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        committed = TUTORIALS / "figures" / p.name
        assert committed.is_file(), committed
        assert committed.stat().st_size < MAX_FIGURE, committed
        assert f"(figures/{p.name})" in text, f"{p.name} not shown in {name}.md"
    for shown in re.findall(r"\]\((figures/[^)]+)\)", text):
        assert (TUTORIALS / shown).is_file(), shown


@pytest.mark.parametrize("name", [*NAMES, "README"])
def test_links_resolve(name: str) -> None:
    text = (TUTORIALS / f"{name}.md").read_text(encoding="utf-8")
    links = re.findall(r"\]\(([^)#\s]+)\)", text)
    assert links
    for link in links:
        assert (TUTORIALS / link).exists(), f"{name}.md links to {link}, which does not exist"


def _blocks(name: str, lang: str) -> list[str]:
    text = (TUTORIALS / f"{name}.md").read_text(encoding="utf-8")
    return re.findall(rf"```{lang}\n(.*?)```", text, flags=re.S)


def _few(code: str) -> str:
    """The code at a few trials: every ``trials=N`` (Python) or ``--trials N`` lowered."""
    code = re.sub(r"trials=[\d_]+", "trials=500", code)
    return re.sub(r"--trials [\d_]+", "--trials 500", code)


def _workdir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Work in ``tmp_path``, where ``examples/`` is the repository's: files land there."""
    (tmp_path / "examples").symlink_to(ROOT / "examples", target_is_directory=True)
    monkeypatch.chdir(tmp_path)


@pytest.mark.parametrize("name", NAMES)
def test_python_snippets_run(
    name: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    snippets = _blocks(name, "python")
    assert snippets
    _workdir(tmp_path, monkeypatch)
    for code in snippets:
        exec(compile(_few(code), f"{name}.md", "exec"), {"__name__": "tutorial"})
    assert capsys.readouterr().out


@pytest.mark.parametrize("name", NAMES)
def test_commands_run(name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    _workdir(tmp_path, monkeypatch)
    ran = 0
    for block in _blocks(name, "sh"):
        for line in block.replace("\\\n", " ").splitlines():
            line = line.split(" # ")[0].strip()
            if not line.startswith("mtmc "):
                continue
            argv = shlex.split(_few(line))[1:]
            if argv[0] == "run":  # into the test's folder, at a few trials
                argv = [a for a in argv if a != "-o"]
                argv = [argv[0], argv[1], "-o", str(tmp_path / f"r{ran}"), "--quiet"]
                argv += ["--trials", "500"]
            assert cli(argv) == 0, line
            ran += 1
    assert ran


def test_aguado2016_counts_of_readings_match_the_table() -> None:
    """The sentence on the readings that let position 4 see, recounted from the table's ✗."""
    text = (TUTORIALS / "aguado2016.md").read_text(encoding="utf-8")
    table = re.search(r"<!-- generated: readings -->\n(.*?)<!-- end", text, re.S)
    assert table is not None
    rows = [r.split("|")[1:-1] for r in table[1].strip().splitlines()[2:]]
    assert len(rows) == 48
    ok4 = [r for r in rows if "✗" not in r[5]]
    low = [r for r in ok4 if float(r[4].split("…")[0]) < -60.0]
    high = [r for r in ok4 if float(r[4].split("…")[1].split()[0]) > 77.0]
    said = re.search(
        r"Position 4 sees every point under (\d+) of the (\d+) readings; positions 1–3 all "
        r"see as well under (\d+) of them\. Position 3 leaves the limits below -60° under "
        r"(\d+) of the \d+ and above 77° under (\d+)",
        text,
    )
    assert said is not None
    all_see = [r for r in ok4 if not any("✗" in c for c in r[2:5])]
    assert [int(x) for x in said.groups()] == [len(ok4), 48, len(all_see), len(low), len(high)]
    assert (len(ok4), len(low), len(high)) == (26, 18, 8)
