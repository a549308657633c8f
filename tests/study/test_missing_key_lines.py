"""A required key taken out of a file: the message points at its table's header, or no line.

A missing key has no line of its own. The error names the line of the header of the
table it is missing from (``[machine]``, ``[[transition]]``, ``[tracker.positions.P]``),
or no line at all when it is missing at the top level (``t.toml: field model: ...``),
never the first line of the file. Each case deletes one line of a shipped example and
reads the message; the expected line is found in the edited text by its header.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from mtmc.artefact.artefact import loads_artefact
from mtmc.errors import MtmcError
from mtmc.graph.toml_format import loads_graph as loads_graph
from mtmc.study import loads_study

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"

# (file under examples/, the line deleted (a regex of it), the header the error points
# at (None: the top level, no line), the field named, the words of the message)
CASES = [
    ("studies/mass_calibration.toml", r"model = .*", None, "model", "missing model in the file"),
    ("studies/mass_calibration.toml", r"kind = .*", None, "kind", "missing kind; expected one of"),
    ("studies/ball_centre.toml", r"outputs = .*", None, "outputs", "missing outputs"),
    ("studies/ball_centre.toml", r"graph = .*", None, "graph", "missing graph in the file"),
    ("studies/bcs_origin.toml", r"output = .*", "[sweep]", "sweep.output", "missing output"),
    ("studies/five_axis.toml", r"machine = .*", None, "machine", "missing machine"),
    ("studies/aguado2017.toml", r"topology = .*", "[machine]", "machine.topology", "missing"),
    ("studies/aguado2017.toml", r"errors = .*", "[model]", "model.errors", "missing errors"),
    (
        "studies/aguado2017.toml",
        r"euler_deg = .*",
        "[tracker.positions.aguado2017]",
        "tracker.positions.aguado2017.euler_deg",
        "missing euler_deg",
    ),
    ("studies/aguado2017.toml", r"stop = .*", "[points.mesh]", "points.mesh.stop", "missing stop"),
    ("studies/wang2022.toml", r"shipped = .*", "[artefact]", "artefact", "expected exactly one"),
    ("studies/wang2022.toml", r"library = .*", "[machine]", "machine", "expected exactly one"),
]


def _delete(text: str, pattern: str) -> str:
    out, n = re.subn(rf"(?m)^{pattern}\n", "", text, count=1)
    assert n == 1, pattern
    return out


def _header_line(text: str, header: str | None) -> int | None:
    if header is None:
        return None
    rows = text.splitlines()
    return next(i for i, row in enumerate(rows, 1) if row.split("#")[0].strip() == header)


@pytest.mark.parametrize(("name", "pattern", "header", "field", "words"), CASES)
def test_study_missing_key_points_at_its_table_or_no_line(name, pattern, header, field, words):
    path = EXAMPLES / name
    text = _delete(path.read_text(encoding="utf-8"), pattern)
    with pytest.raises(MtmcError) as info:
        loads_study(text, file="t.toml", folder=path.parent)
    line = _header_line(text, header)
    where = "t.toml: " if line is None else f"t.toml:{line}: "
    assert str(info.value).startswith(f"{where}field {field}: "), str(info.value)
    assert words in str(info.value)
    assert str(info.value).count("t.toml") == 1  # not wrapped twice


def test_study_missing_key_of_an_implicit_table_has_no_line():
    # [sweep] is only made by its sub-table [sweep.vary]: no header line to name
    text = 'kind = "graph"\ngraph = "ball_centre.toml"\noutputs = ["cx"]\n[sweep.vary]\nx = 1\n'
    with pytest.raises(MtmcError) as info:
        loads_study(text, file="t.toml", folder=EXAMPLES / "graphs")
    assert str(info.value) == "t.toml: field sweep.output: missing output in [sweep]"


GRAPH_CASES = [
    ("name", "[[place]]", 0, "name", "place #1: missing name"),
    ("type", "[[place]]", 1, "type", "missing type"),
    ("op", "[[transition]]", 2, "op", "missing op"),
    ("out", "[[transition]]", 3, "out", "missing out"),
]


@pytest.mark.parametrize(("key", "header", "index", "field", "words"), GRAPH_CASES)
def test_graph_file_missing_key_points_at_its_entry(key, header, index, field, words):
    text = (EXAMPLES / "graphs" / "axis_c.toml").read_text(encoding="utf-8")
    rows = text.splitlines(keepends=True)
    starts = [i for i, row in enumerate(rows) if row.strip() == header]
    entry = starts[index]
    key_row = next(i for i in range(entry, len(rows)) if rows[i].startswith(f"{key} ="))
    del rows[key_row]
    with pytest.raises(MtmcError) as info:
        loads_graph("".join(rows), file="g.toml")
    assert str(info.value).startswith(f"g.toml:{entry + 1}: field {field}: "), str(info.value)
    assert words in str(info.value)


def test_artefact_file_missing_key_points_at_its_ball_or_no_line():
    text = (EXAMPLES / "artefacts" / "wang2022_five_ball.toml").read_text(encoding="utf-8")
    no_diameter = _delete(text, r"diameter = .*")
    with pytest.raises(MtmcError) as info:
        loads_artefact(no_diameter, file="a.toml")
    assert str(info.value).startswith("a.toml: field diameter: missing diameter"), str(info.value)
    rows = text.splitlines(keepends=True)
    ball = [i for i, row in enumerate(rows) if row.strip() == "[[ball]]"][1]
    del rows[ball + 1]  # the name of the second ball
    with pytest.raises(MtmcError) as info:
        loads_artefact("".join(rows), file="a.toml")
    assert str(info.value).startswith(f"a.toml:{ball + 1}: field ball[1].name: missing name")
