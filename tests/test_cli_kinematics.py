"""``mtmc kinematics``: the CLI prints what the library computes; errors are one line."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

from mtmc.cli.main import main
from mtmc.kinematics import equation_of_motion, library_machine, library_names


def test_list(capsys) -> None:  # type: ignore[no-untyped-def]
    assert main(["kinematics", "list"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert [ln.split()[0] for ln in out] == list(library_names())
    assert main(["kinematics", "list", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["wbzfxyct"]["topology"] == "wBZfXYCt"


def test_show(capsys) -> None:  # type: ignore[no-untyped-def]
    assert main(["kinematics", "show", "wCBXfYZt"]) == 0
    out = capsys.readouterr().out
    assert "axes (column order of q): X Y Z B C" in out
    assert "chain: workpiece -> C -> B -> X -> frame -> Y -> Z -> tool" in out
    assert "  C: rotary, moves the part" in out
    assert "  Z: linear, moves the tool" in out
    # the travel with its unit: degrees for a rotary axis, mm for a linear one
    assert "  B: rotary, moves the part, travel -90 .. 90 deg" in out
    assert "  Z: linear, moves the tool, travel -500 .. 0 mm" in out
    assert main(["kinematics", "show", "table-head", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    m = library_machine("table-head")
    assert data["errors"] == list(m.error_names)
    assert data["tool"] == m.tool.tolist()


def test_equation_matches_library(capsys) -> None:  # type: ignore[no-untyped-def]
    assert main(["kinematics", "equation", "XFYZ"]) == 0
    out = capsys.readouterr().out
    eq = equation_of_motion(library_machine("xfyz"), first_order=True)
    assert out.strip() == eq.text()
    assert main(["kinematics", "equation", "xfyz", "--latex", "-e", "EXX", "-e", "C0Y"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("\\begin{aligned}")
    assert "EC0Y" in out
    assert (
        out.strip()
        == equation_of_motion(
            library_machine("xfyz"), errors=["EXX", "EC0Y"], first_order=True
        ).latex()
    )


def test_draw(tmp_path: Path) -> None:
    f = tmp_path / "chain.svg"
    assert main(["kinematics", "draw", "wBZfXYCt", "-o", str(f)]) == 0
    root = ET.fromstring(f.read_text())
    ids = [g.get("id", "") for g in root.iter("{http://www.w3.org/2000/svg}g")]
    assert [i for i in ids if i.startswith("axis-")] == [
        "axis-B-rotary-part",
        "axis-Z-linear-part",
        "axis-X-linear-tool",
        "axis-Y-linear-tool",
        "axis-C-rotary-tool",
    ]
    texts = [t.text for t in root.iter("{http://www.w3.org/2000/svg}text")]
    assert texts[0] == "wBZfXYCt  (ZBFXYC)"
    assert {"B", "about y, part", "Z", "along z, part", "C", "about z, tool"} <= set(texts)


def test_errors_are_one_line(capsys) -> None:  # type: ignore[no-untyped-def]
    assert main(["kinematics", "show", "XYZ"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mtmc: error: field topology: topology 'XYZ': no frame")
    assert "nor is it a library name (xfyz, fxyz" in err
    assert len(err.strip().splitlines()) == 1
    assert main(["kinematics", "equation", "XFYZ", "-e", "EX0C"]) == 2
    err = capsys.readouterr().err
    assert "error EX0C refers to axis C, which machine wXfYZt does not have" in err


def test_draw_refuses_other_formats_and_keeps_old_file(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    png = tmp_path / "chain.png"
    assert main(["kinematics", "draw", "XFYZ", "-o", str(png)]) == 2
    err = capsys.readouterr().err
    assert err == f"mtmc: error: {png}: the chain is drawn as SVG; expected a file ending in .svg\n"
    assert not png.exists()
    svg = tmp_path / "chain.svg"
    svg.write_text("old")
    assert main(["kinematics", "draw", "XYZ", "-o", str(svg)]) == 2  # bad topology
    assert svg.read_text() == "old"
    assert main(["kinematics", "draw", "XFYZ", "-o", str(tmp_path / "no" / "c.svg")]) == 2
    assert "c.svg: cannot write" in capsys.readouterr().err
    assert main(["kinematics", "draw", "XFYZ", "-o", str(svg)]) == 0
    assert svg.read_text().lstrip().startswith("<")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["chain.svg"]
