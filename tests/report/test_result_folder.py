"""A result folder that came from elsewhere: every tampered file ends in one clear error.

The reference of each case is what ``docs/results-format.md`` allows: a folder written
by ``write_result`` reads back (and renders) unchanged; one that is changed against the
format is refused by :func:`mtmc.load_result` and by ``mtmc report`` alike, as an
:class:`InputError` naming the file, and nothing is written outside the folder.
"""

from __future__ import annotations

import copy
import json
import os
import random
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mtmc.errors import InputError
from mtmc.io import loads_json
from mtmc.report import render
from mtmc.study import load_result, loads_study, write_result

STUDY = """\
kind = "propagate"
title = "Two outputs"
model = "a + b"
output = "y"
unit = "mm"
[inputs]
a = "normal(0, 1)"
b = "uniform(-1, 1)"
[run]
trials = 2000
seed = 5
samples = true
"""


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("res") / "res"
    write_result(loads_study(STUDY, file="s.toml").run(), d, study_text=STUDY)
    return d


@pytest.fixture
def res(written: Path, tmp_path: Path) -> Path:
    d = tmp_path / "res"
    shutil.copytree(written, d)
    return d


def _doc(d: Path) -> dict[str, Any]:
    return json.loads((d / "result.json").read_text(encoding="utf-8"))


def _both_refuse(d: Path, words: str) -> None:
    for read in (load_result, render):
        with pytest.raises(InputError, match=words) as info:
            read(d)
        assert "\n" not in str(info.value)


def test_a_report_html_linked_outside_is_replaced_and_the_target_kept(res: Path) -> None:
    victim = res.parent / "victim.txt"
    victim.write_text("keep me")
    (res / "report.html").unlink()
    (res / "report.html").symlink_to("../victim.txt")
    render(res)
    assert victim.read_text() == "keep me"
    assert not (res / "report.html").is_symlink()
    assert "<html" in (res / "report.html").read_text(encoding="utf-8").lower()


def test_a_linked_result_folder_is_still_followed(res: Path, tmp_path: Path) -> None:
    link = tmp_path / "link"
    link.symlink_to(res)
    render(link)
    assert (res / "report.html").is_file()
    assert link.is_symlink()


def test_a_fifo_for_a_sample_is_refused_without_opening_it(res: Path) -> None:
    npy = res / "samples" / "y.npy"
    npy.unlink()
    os.mkfifo(npy)
    _both_refuse(res, "FIFO")


def test_result_json_linked_outside_the_folder_is_refused(res: Path, tmp_path: Path) -> None:
    outside = tmp_path / "elsewhere.json"
    shutil.move(res / "result.json", outside)
    (res / "result.json").symlink_to(outside)
    _both_refuse(res, "outside the result folder")


def test_a_npy_header_claiming_more_than_its_file_is_refused(res: Path) -> None:
    npy = res / "samples" / "y.npy"
    header = "{'descr': '<f8', 'fortran_order': False, 'shape': (100000000000,), }"
    data = b"\x93NUMPY\x01\x00" + len(header.ljust(118) + "\n").to_bytes(2, "little")
    npy.write_bytes(data + (header.ljust(118) + "\n").encode())
    _both_refuse(res, "samples|bytes")


def test_samples_of_the_wrong_length_are_refused(res: Path) -> None:
    np.save(res / "samples" / "y.npy", np.zeros(7))
    _both_refuse(res, "7 samples; the result ran 2000 trials")


@pytest.mark.parametrize(
    ("raw", "words"),
    [
        (b'{"format": "mtmc-result/1", "title": "\xff"}', "not UTF-8"),
        (b"[" * 100_000 + b"]" * 100_000, "nested deeper"),
        (b'{"format": "mtmc-result/1", "trials": 1' + b"0" * 4999 + b"}", "5000 digits"),
        (b'{"format": "mtmc-result/1", "trials": 1e400}', "largest number"),
        (b'{"format": "mtmc-result/1", "p": NaN}', "NaN is not JSON"),
    ],
)
def test_json_that_would_break_a_reader(res: Path, raw: bytes, words: str) -> None:
    (res / "result.json").write_bytes(raw)
    _both_refuse(res, words)


@pytest.mark.parametrize(
    ("path", "value", "words"),
    [
        (("format",), "mtmc-result/999", "format mtmc-result/1"),
        (("trials",), -3, "trials"),
        (("trials",), 10**30, "trials"),
        (("p",), 7.5, "0 < p < 1"),
        (("quantities", 0, "monte_carlo", "u"), -1.0, "quantities\\[0\\].monte_carlo.u"),
        (("quantities", 0, "monte_carlo", "p"), 0.0, "0 < p < 1"),
        (("quantities", 0, "histogram", "density"), [1.0], "histogram.density"),
        (("quantities", 0, "convergence", "u"), "x", "convergence.u"),
        # make fuzz at 2000 cases: 2**63 trials (OverflowError: Python int too large to
        # convert to C long, in load_result), and a count past the quantity's trials
        (("quantities", 0, "convergence", "m", 0), 2**63, "convergence.m\\[0\\]"),
        (("quantities", 0, "convergence", "m", -1), 2001, "an integer from 1 to 2000"),
        (("quantities", 0, "convergence", "m", 1), 10.5, "convergence.m\\[1\\]"),
        (("quantities", 0, "name"), 3, "quantities\\[0\\].name"),
        (("quantities", 0), False, "quantities\\[0\\]"),
    ],
)
def test_values_against_the_format_are_refused(
    res: Path, path: tuple[Any, ...], value: Any, words: str
) -> None:
    doc = _doc(res)
    node = doc
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    (res / "result.json").write_text(json.dumps(doc), encoding="utf-8")
    _both_refuse(res, words)


def _leaves(obj: Any, at: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    out = [at] if at else []
    if isinstance(obj, dict):
        for k, v in obj.items():
            out += _leaves(v, (*at, k))
    elif isinstance(obj, list):
        for i, v in enumerate(obj[:3]):
            out += _leaves(v, (*at, i))
    return out


HOSTILE = (None, -1, 0, 1e308, -1e-308, "", "x", [], {}, [1, 2], True, 10**39, 0.5)


def test_a_generated_set_of_tampered_folders_each_ends_in_one_clear_error(
    res: Path, tmp_path: Path
) -> None:
    """60 folders, one value replaced in each: read back and rendered, or one InputError.

    A fixed set, against the regressions of what it once found; ``make fuzz`` draws more
    (``tests/fuzz/test_fuzz_files.py``).
    """
    base = _doc(res)
    paths = _leaves(base)
    rnd = random.Random(38)
    outcomes = {"read": 0, "refused": 0}
    messages: list[str] = []
    for case in range(60):
        doc = copy.deepcopy(base)
        path = rnd.choice(paths)
        node = doc
        for key in path[:-1]:
            node = node[key]
        if rnd.random() < 0.1 and isinstance(node, dict):
            del node[path[-1]]
        else:
            node[path[-1]] = rnd.choice(HOSTILE)
        d = tmp_path / f"t{case}"
        shutil.copytree(res, d)
        (d / "result.json").write_text(json.dumps(doc), encoding="utf-8")
        try:
            load_result(d)
            render(d)
        except InputError as exc:
            messages.append(str(exc))
            outcomes["refused"] += 1
        else:
            outcomes["read"] += 1
        shutil.rmtree(d)
    for message in messages:  # one line, naming the file
        assert "\n" not in message
        assert "result.json" in message or "samples" in message
    assert outcomes["refused"] > 25  # most fields are checked (37 of 60), the check is not vacuous


def test_loads_json_limits() -> None:
    assert loads_json('{"a": [[1]]}', "f") == {"a": [[1]]}
    assert loads_json("[" * 64 + "]" * 64, "f") is not None  # 64 levels: the limit
    with pytest.raises(InputError, match="nested deeper than 64"):
        loads_json("[" * 65 + "]" * 65, "f")
    with pytest.raises(InputError, match="nested deeper than 3"):
        loads_json("[[[[1]]]]", "f", max_depth=3)
    assert loads_json("[[[1]]]", "f", max_depth=3) == [[[1]]]


def test_a_report_of_many_quantities_draws_the_first_few_and_says_so(
    written: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import mtmc.report
    from mtmc.report import html

    # the rule at a limit of 2: the same code as at the shipped 12, a sixth of the figures
    # (the test at 12 drew 120, 25 s of the suite); test_browser reads a shipped report
    # drawn at 12
    monkeypatch.setattr(mtmc.report, "MAX_PLOTTED", 2)
    MAX_PLOTTED = mtmc.report.MAX_PLOTTED
    doc = _doc(written)
    q = doc["quantities"][0]
    doc["quantities"] = [dict(q, name=f"pose{i}.x") for i in range(MAX_PLOTTED + 3)]
    # every kind draws the first MAX_PLOTTED (a kinematics study alone did, the artefact
    # study of Wang et al. drew 73 figures) and says which it does not
    for kind in ("graph", "kinematics", "artefact", "circular"):
        page = html(dict(doc, kind=kind))
        assert page.count('data-plot="histogram:') == MAX_PLOTTED, kind
        assert page.count('data-plot="convergence:') == MAX_PLOTTED, kind
        assert page.count('class="unplotted"') == 3, kind
        assert f"the first {MAX_PLOTTED}" in page, kind
    doc["quantities"] = doc["quantities"][:MAX_PLOTTED]
    assert 'class="unplotted"' not in html(doc)


def test_the_provenance_table_names_the_copy_of_each_input_file(written: Path) -> None:
    # Jinja's f.copy found dict.copy, a method, before the "copy" key: the report read
    # "copied as <built-in method copy of dict object at 0x…>". Reference: provenance.json.
    from mtmc.report import html

    prov = json.loads((written / "provenance.json").read_text(encoding="utf-8"))
    prov["input_files"] = [
        {
            "field": "graph",
            "given": "../graphs/axis_c.toml",
            "copy": "inputs/axis_c.toml",
            "sha256": "f" * 64,
        }
    ]
    page = html(_doc(written), prov)
    assert "copied as <code>inputs/axis_c.toml</code>" in page
    assert "built-in method" not in page


def test_a_text_the_plots_font_lacks_is_drawn_without_a_warning(
    written: Path, tmp_path: Path
) -> None:
    # make fuzz (2000 tampered folders) renamed a quantity "˯" (U+02EF), which DejaVu Sans
    # does not have: Matplotlib measured the label without the glyph and the report leaked
    # its UserWarning. The SVG keeps the text as text, for the browser to draw.
    import warnings

    d = Path(shutil.copytree(written, tmp_path / "r"))
    doc = json.loads((d / "result.json").read_text(encoding="utf-8"))
    doc["quantities"][0]["name"] = "˯"
    (d / "result.json").write_text(json.dumps(doc), encoding="utf-8")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        page = render(d).read_text(encoding="utf-8")
    figure = page[page.index('data-plot="histogram:˯"') :]
    figure = figure[: figure.index("</figure>")]
    assert "˯" in figure  # its axis label, as text
