"""docs/api.md lists the public API: every name there imports, every top-level name is there."""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import mtmc

API = Path(__file__).resolve().parents[1] / "docs" / "api.md"


def _listed() -> list[str]:
    return re.findall(r"^- `(mtmc(?:\.\w+)+)` — \S", API.read_text(encoding="utf-8"), re.M)


def test_every_documented_name_imports():
    names = _listed()
    assert len(names) > 300
    for dotted in names:
        module, _, name = dotted.rpartition(".")
        assert hasattr(importlib.import_module(module), name), dotted


def test_every_top_level_and_subpackage_name_is_documented():
    listed = set(_listed())
    missing = {f"mtmc.{n}" for n in mtmc.__all__} - listed
    assert not missing
    for dotted in {d.rpartition(".")[0] for d in listed} - {"mtmc"}:
        module = importlib.import_module(dotted)
        assert {f"{dotted}.{n}" for n in module.__all__} <= listed, dotted
    assert "mtmc.vector" not in listed


def test_every_name_the_tutorials_and_guides_import_is_documented():
    root = API.parents[1]
    listed = set(_listed())
    texts = [f.read_text(encoding="utf-8") for f in (root / "docs").rglob("*.md")]
    texts.append((root / "README.md").read_text(encoding="utf-8"))
    used = set()
    for text in texts:
        for block in re.findall(r"```python\n(.*?)```", text, re.S):
            for mod, names in re.findall(r"^from (mtmc[\w.]*) import ([^\n(]+)$", block, re.M):
                used |= {f"{mod}.{n.strip().split(' as ')[0]}" for n in names.split(",")}
    assert used
    assert not used - listed, sorted(used - listed)
