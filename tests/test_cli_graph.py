"""``mtmc graph``: the CLI prints what the library computes; errors are one line, exit 2."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mtmc.cli.main import main
from mtmc.graph import load_graph, run_graph

EXAMPLES = Path(__file__).resolve().parent.parent / "examples" / "graphs"


def test_check(capsys):
    assert main(["graph", "check", str(EXAMPLES / "axis_c.toml")]) == 0
    out = capsys.readouterr().out
    assert out.startswith("axis_c.toml: ok:")
    assert "generation 3: t_axis_c" in out


def test_run_json_equals_library(capsys):
    f = EXAMPLES / "bcs_origin.toml"
    assert main(["graph", "run", str(f), "--trials", "3000", "--seed", "7", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    lib = run_graph(load_graph(f), 3000, seed=7)
    assert data["trials"] == 3000 and data["seed"] == 7
    d = data["places"]["d_ac"]
    assert d["type"] == "real"
    assert d["estimate"] == lib.places["d_ac"].estimate and d["u"] == lib.places["d_ac"].u
    p = data["places"]["p_o"]
    np.testing.assert_array_equal(p["estimate"], lib.places["p_o"].mean)
    assert np.shape(p["cov"]) == (3, 3)
    line = data["places"]["axis_a"]
    assert set(line) == {"type", "point", "direction"}
    np.testing.assert_array_equal(line["direction"]["u"], lib.places["axis_a"].part("direction")[1])


def test_run_table(capsys):
    assert (
        main(
            [
                "graph",
                "run",
                str(EXAMPLES / "ball_centre.toml"),
                "-n",
                "1000",
                "--seed",
                "1",
                "-p",
                "cx",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    u = (
        run_graph(load_graph(EXAMPLES / "ball_centre.toml"), 1000, seed=1, outputs=["cx"])
        .places["cx"]
        .u
    )
    row = next(ln for ln in out.splitlines() if ln.startswith("│ cx "))
    cells = [c.strip() for c in row.strip("│").split("│")]
    assert cells == ["cx", "x", "", cells[3], f"{u:.6g}", "mm"]
    assert "trials 1000  seed 1" in out


def test_draw_and_export(tmp_path, capsys):
    svg, dot = tmp_path / "g.svg", tmp_path / "g.dot"
    assert main(["graph", "draw", str(EXAMPLES / "plane_3pt.toml"), "-o", str(svg)]) == 0
    assert main(["graph", "draw", str(EXAMPLES / "plane_3pt.toml"), "-o", str(dot)]) == 0
    assert svg.read_text().lstrip().startswith("<?xml")
    assert dot.read_text().startswith("digraph")
    capsys.readouterr()
    assert main(["graph", "export", str(EXAMPLES / "plane_3pt.toml")]) == 0
    db = tmp_path / "plane.pl"
    db.write_text(capsys.readouterr().out)
    assert main(["graph", "check", str(db)]) == 0


def test_sweep(tmp_path, capsys):
    csv = tmp_path / "s.csv"
    args = [
        "graph",
        "sweep",
        str(EXAMPLES / "ball_centre.toml"),
        "--vary",
        "probe.u_probe=0.001:0.003:3",
        "--vary",
        "probe.u_axis=0.001:0.002:2",
        "--output",
        "cx",
        "--trials",
        "500",
        "--seed",
        "4",
    ]
    assert main([*args, "--csv", str(csv), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert len(data["u"]) == 6 and data["surrogate"]["max_rel_error"] < 0.05
    assert csv.read_text().splitlines()[0].startswith("probe.u_probe,probe.u_axis,cx_estimate,cx_u")


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["graph", "check", "nope.toml"], "nope.toml: cannot read the graph file"),
        (
            [
                "graph",
                "sweep",
                str(EXAMPLES / "ball_centre.toml"),
                "--vary",
                "probe.u_probe",
                "--output",
                "cx",
            ],
            "expected KEY=LOW:HIGH:N",
        ),
        (
            ["graph", "run", str(EXAMPLES / "ball_centre.toml"), "-p", "zz"],
            "the graph has no place zz",
        ),
        (
            ["graph", "export", str(EXAMPLES / "ball_centre.toml"), "--to", "yaml"],
            "--to: expected one of",
        ),
    ],
)
def test_errors_exit_2_with_one_line(args, message, capsys):
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("mtmc: error:") and message in err and err.count("\n") == 1


def test_bad_file_names_line(tmp_path, capsys):
    f = tmp_path / "bad.toml"
    f.write_text(
        '[[transition]]\nname = "t1"\nop = "meas"\nat = [0, 0, 0]\n'
        'direction = [1, 0, 0]\nout = "a"\n'
        '[[transition]]\nname = "t2"\nop = "spin"\nin = ["a"]\nout = "b"\n'
    )
    assert main(["graph", "check", str(f)]) == 2
    assert "bad.toml:9: field op: transition t2: unknown op 'spin'" in capsys.readouterr().err
