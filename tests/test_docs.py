"""README, getting-started, performance and conformity say what the code does.

The number of studies the demo runs, as each of them words it, is ``len(STUDIES)``; the
Python snippets of README and getting-started run, and write nothing into the folder they
run in.
"""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

import pytest

from mtmc.demo import STUDIES

ROOT = Path(__file__).resolve().parents[1]
DOCS = {
    "README": ROOT / "README.md",
    "getting-started": ROOT / "docs" / "getting-started.md",
    "performance": ROOT / "docs" / "performance.md",
}
WORDS = "zero one two three four five six seven eight nine ten eleven twelve thirteen fourteen"
NUMBER = {w: i for i, w in enumerate(WORDS.split())}


def _count(word: str) -> int:
    """``eleven`` or ``11``: 11."""
    return int(word) if word.isdigit() else NUMBER[word.lower()]


def _shipped_counts(text: str) -> list[int]:
    """Every count a doc gives of the demo's studies: "N shipped studies", "N of the M"."""
    n = rf"(\d+|{'|'.join(NUMBER)})"
    said = re.findall(rf"\b{n} shipped studies", text, flags=re.I)
    said += re.findall(rf"runs, one after the other, {n} of the", text, flags=re.I)
    return [_count(w) for w in said]


@pytest.mark.parametrize("name", sorted(DOCS))
def test_each_doc_counts_the_demos_studies_right(name: str) -> None:
    text = DOCS[name].read_text(encoding="utf-8")
    counts = _shipped_counts(text)
    assert counts, f"{name} says nowhere how many studies the demo runs"
    assert counts == [len(STUDIES)] * len(counts), (name, counts, len(STUDIES))


def test_the_count_reads_words_and_digits() -> None:
    assert _shipped_counts("runs the eleven shipped studies; 8 shipped studies") == [11, 8]
    assert _shipped_counts("runs the shipped studies") == []
    with pytest.raises(KeyError):
        _count("many")


def test_getting_started_counts_the_example_studies_right() -> None:
    text = DOCS["getting-started"].read_text(encoding="utf-8")
    m = re.search(r"runs, one after the other, (\w+) of the\s+(\w+) studies", text)
    assert m is not None
    files = sorted((ROOT / "examples" / "studies").glob("*.toml"))
    assert _count(m[2]) == len(files)
    # every study the demo leaves out is named where the doc says so
    for left in sorted({f.name for f in files} - set(STUDIES)):
        assert f"`{left}`" in text, left


def _snippets(path: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", path.read_text(encoding="utf-8"), flags=re.S)


def _few(code: str) -> str:
    """The code at a few trials: every ``trials=N`` (``10**6``, ``200_000``) lowered."""
    return re.sub(r"trials=[\d_*]+", "trials=500", code)


@pytest.mark.parametrize("name", ["README", "getting-started"])
def test_python_snippets_run_and_leave_the_folder_as_it_was(
    name: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    snippets = _snippets(DOCS[name])
    assert snippets
    cwd, tmp = tmp_path / "cwd", tmp_path / "tmp"
    cwd.mkdir()
    tmp.mkdir()
    (cwd / "examples").symlink_to(ROOT / "examples", target_is_directory=True)
    monkeypatch.chdir(cwd)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    for code in snippets:
        exec(compile(_few(code), f"{name}.md", "exec"), {"__name__": "doc"})
    assert capsys.readouterr().out
    assert sorted(p.name for p in cwd.iterdir()) == ["examples"]
    written = list(tmp.rglob("report.html"))
    assert len(written) == 1


def test_few_lowers_every_trial_count() -> None:
    assert _few("f(trials=10**6); g(trials=200_000)") == "f(trials=500); g(trials=500)"


def test_the_conformity_guide_prints_what_mtmc_run_prints(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The worked example of docs/conformity.md: its study, run as written (200 000 trials,
    seed 1), prints the decision line the guide shows."""
    from mtmc.cli.main import main

    text = (ROOT / "docs" / "conformity.md").read_text(encoding="utf-8")
    study = re.search(r'```toml\n(kind = "propagate".*?)```', text, flags=re.S)
    shown = re.search(r"```text\n(conformity of .*?)\n```", text)
    assert study is not None
    assert shown is not None
    path = tmp_path / "x_axis_acceptance.toml"
    path.write_text(study.group(1), encoding="utf-8")
    assert main(["run", str(path), "-o", str(tmp_path / "out"), "-q", "--plots", "0"]) == 0
    assert shown.group(1) in capsys.readouterr().out.splitlines()
