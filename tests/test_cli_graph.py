"""``mtmc graph``: the CLI prints what the library computes; errors are one line, exit 2."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mtmc.cli.main import main
from mtmc.graph import load_graph, run_graph
from mtmc.uncertainty.tolerance import round_to_uncertainty

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
    assert data["trials"] == 3000
    assert data["seed"] == 7
    d = data["places"]["d_ac"]
    assert d["type"] == "real"
    assert d["estimate"] == lib.places["d_ac"].estimate
    assert d["u"] == lib.places["d_ac"].u
    p = data["places"]["p_o"]
    np.testing.assert_array_equal(p["estimate"], lib.places["p_o"].estimate_vector)
    np.testing.assert_array_equal(p["cov"], lib.places["p_o"].cov)
    line = data["places"]["axis_a"]
    assert set(line) == {"type", "point", "direction"}
    direction = lib.places["axis_a"].part("direction")
    np.testing.assert_array_equal(line["direction"]["u"], direction.u_vector)


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
                "--place",
                "cx",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    cx = run_graph(load_graph(EXAMPLES / "ball_centre.toml"), 1000, seed=1, outputs=["cx"])
    est, u = cx.places["cx"].estimate, cx.places["cx"].u
    row = next(ln for ln in out.splitlines() if ln.startswith("│ cx "))
    cells = [c.strip() for c in row.strip("│").split("│")]
    assert cells == ["cx", "x", "", *round_to_uncertainty(est, u), "mm"]
    _check_rounded(cells[3], cells[4], est, u)
    assert 0.001 <= u < 0.01  # a u of some um: the estimate in mm to 4 decimals
    assert len(cells[3].partition(".")[2]) == 4
    assert "trials 1000  seed 1" in out


def _check_rounded(y_text, u_text, y, u):
    """JCGM 100 §7.2.6: u to two significant digits, y to the same decimal place."""
    places = len(u_text.partition(".")[2])
    assert len(y_text.partition(".")[2]) == places
    assert len(u_text.replace(".", "").lstrip("0")) == 2
    assert abs(float(u_text) - u) <= 0.5 * 10.0**-places
    assert abs(float(y_text) - y) <= 0.5 * 10.0**-places


def test_run_table_rounds_each_component_to_its_u(capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "200")  # one line per row
    # a plane fitted to three points: the point in mm at 4 decimals (u of some um), the
    # unit normal at many more (u of some urad on its x, y; far less on its z)
    g = EXAMPLES / "plane_3pt.toml"
    assert main(["graph", "run", str(g), "-n", "2000", "--seed", "5", "--place", "plane"]) == 0
    out = capsys.readouterr().out
    lib = run_graph(load_graph(g), 2000, seed=5, outputs=["plane"]).places["plane"]
    text = "".join(c for c in out if c not in "│ ")
    for part in ("point", "normal"):
        r = lib.part(part)
        pairs = [
            round_to_uncertainty(y, u) for y, u in zip(r.estimate_vector, r.u_vector, strict=True)
        ]
        for (y_text, u_text), y, u in zip(pairs, r.estimate_vector, r.u_vector, strict=True):
            _check_rounded(y_text, u_text, y, u)
        cells = "[" + ",".join(y for y, _ in pairs) + "]", "[" + ",".join(u for _, u in pairs) + "]"
        assert "".join(cells) in text
    argv = ["graph", "run", str(g), "-n", "2000", "--seed", "5", "--place", "plane", "--json"]
    assert main(argv) == 0
    normal = json.loads(capsys.readouterr().out)["places"]["plane"]["normal"]
    np.testing.assert_array_equal(normal["estimate"], lib.part("normal").estimate_vector)


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
        "--quantity",
        "cx",
        "--trials",
        "500",
        "--seed",
        "4",
    ]
    assert main([*args, "--csv", str(csv), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert len(data["u"]) == 6
    assert data["surrogate"]["max_rel_error"] < 0.05
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
                "--quantity",
                "cx",
            ],
            "expected KEY=LOW:HIGH:N",
        ),
        (
            ["graph", "run", str(EXAMPLES / "ball_centre.toml"), "--place", "zz"],
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
    assert err.startswith("mtmc: error:")
    assert message in err
    assert err.count("\n") == 1


def test_bad_file_names_line(tmp_path, capsys):
    f = tmp_path / "bad.toml"
    f.write_text(
        '[[transition]]\nname = "t1"\nop = "meas"\nat = [0, 0, 0]\n'
        'direction = [1, 0, 0]\nout = "a"\n'
        '[[transition]]\nname = "t2"\nop = "spin"\nin = ["a"]\nout = "b"\n'
    )
    assert main(["graph", "check", str(f)]) == 2
    assert "bad.toml:9: field op: transition t2: unknown op 'spin'" in capsys.readouterr().err


def _units_graph(units: str, scale: float) -> str:
    """Three probed points, their distance, a ratio, a plane and an angle, in ``units``."""
    text = f'units = "{units}"\n[probe]\nu_axis = {0.002 * scale}\nu_probe = {0.001 * scale}\n'
    text += 'u_perp = 0.0\n[[place]]\nname = "k"\ntype = "real"\nvalue = 2.0\nunit = "1"\n'
    text += '[[place]]\nname = "tilt"\ntype = "real"\nvalue = 30.0\nu = 0.5\nunit = "deg"\n'
    for i, (x, z) in enumerate([(0.0, 0.0), (100.0, 0.0), (0.0, 80.0)]):
        text += (
            f'[[transition]]\nname = "m{i}"\nop = "meas"\nat = [{x * scale}, 0, {z * scale}]\n'
            f'direction = [0, 1, 0]\nout = "p{i}"\n'
        )
    return text + (
        '[[transition]]\nname = "d"\nop = "distance"\nin = ["p0", "p1"]\nout = "d01"\n'
        '[[transition]]\nname = "d2"\nop = "ratio"\nin = ["d01", "k"]\nout = "twice"\n'
        '[[transition]]\nname = "pl"\nop = "plane"\nin = ["p0", "p1", "p2"]\nout = "pln"\n'
    )


def test_run_table_in_graph_units(tmp_path, capsys):
    # the same geometry in mm and in um: the table shows the um graph in um
    (tmp_path / "mm.toml").write_text(_units_graph("mm", 1.0))
    (tmp_path / "um.toml").write_text(_units_graph("um", 1000.0))
    lib = run_graph(load_graph(tmp_path / "mm.toml"), 2000, seed=3)
    assert main(["graph", "run", str(tmp_path / "um.toml"), "-n", "2000", "--seed", "3"]) == 0
    out = capsys.readouterr().out

    def row(name):
        line = next(ln for ln in out.splitlines() if ln.startswith(f"│ {name} "))
        return [c.strip() for c in line.strip("│").split("│")]

    d = lib.places["d01"]
    assert row("d01") == [
        "d01",
        "real",
        "",
        *round_to_uncertainty(d.estimate * 1e3, d.u * 1e3),
        "um",
    ]
    t = lib.places["twice"]
    assert row("twice")[3:] == [*round_to_uncertainty(t.estimate * 1e3, t.u * 1e3), "um"]
    _check_rounded(*row("twice")[3:5], t.estimate * 1e3, t.u * 1e3)
    assert row("k")[3:] == ["2", "0", "1"]
    tilt = lib.places["tilt"]
    # tilt is written in deg: shown in deg, the library's rad divided by π/180
    deg = np.pi / 180.0
    assert row("tilt")[3:] == [*round_to_uncertainty(tilt.estimate / deg, tilt.u / deg), "deg"]
    assert abs(tilt.estimate - np.pi / 6) < 1e-3
    assert row("pln")[2] == "point"
    assert row("pln")[-1] == "um"
    normal = next(ln for ln in out.splitlines() if "│ normal " in ln)
    assert normal.rstrip("│ ").endswith("│ 1")


def test_progress_keeps_stdout_json(capsys):
    args = ["graph", "run", str(EXAMPLES / "axis_c.toml"), "-n", "40000", "--seed", "2"]
    assert main([*args, "--json", "--no-progress"]) == 0
    quiet = capsys.readouterr()
    assert main([*args, "--json", "--progress"]) == 0
    loud = capsys.readouterr()
    assert loud.out == quiet.out
    assert json.loads(loud.out)["trials"] == 40000
    assert quiet.err == ""
    assert "40000/40000 trials" in loud.err
    sweep = ["graph", "sweep", str(EXAMPLES / "ball_centre.toml"), "--quantity", "cx"]
    sweep += ["--vary", "probe.u_probe=0.001:0.002:2", "-n", "300", "--seed", "1", "--json"]
    assert main([*sweep, "--progress"]) == 0
    loud = capsys.readouterr()
    assert json.loads(loud.out)["trials"] == 300
    assert "600/600 trials" in loud.err


def test_files_are_written_atomically(tmp_path, capsys, monkeypatch):
    import mtmc.graph.draw as gdraw

    out = tmp_path / "g.svg"
    out.write_text("old drawing")

    def broken_draw(_graph, path):
        Path(path).write_text("<svg half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(gdraw, "draw_graph", broken_draw)
    assert main(["graph", "draw", str(EXAMPLES / "plane_3pt.toml"), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err == f"mtmc: error: {out}: cannot write: No space left on device\n"
    assert out.read_text() == "old drawing"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["g.svg"]  # no temporary left


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["graph", "draw", "{plane}", "-o", "{tmp}/g.jpg"], "expected a file ending in .svg, .png"),
        (["graph", "draw", "{plane}", "-o", "{tmp}/no/g.svg"], "cannot write"),
        (["graph", "export", "{plane}", "-o", "{tmp}/no/g.pl"], "g.pl: cannot write"),
        (
            [
                "graph",
                "sweep",
                "{ball}",
                "--vary",
                "probe.u_probe=0.001:0.002:2",
                "--quantity",
                "cx",
                "-n",
                "50",
                "--csv",
                "{tmp}/no/s.csv",
            ],
            "s.csv: cannot write",
        ),
    ],
)
def test_bad_output_files(argv, message, tmp_path, capsys):
    subs = {
        "{plane}": str(EXAMPLES / "plane_3pt.toml"),
        "{ball}": str(EXAMPLES / "ball_centre.toml"),
        "{tmp}": str(tmp_path),
    }
    for k, v in subs.items():
        argv = [a.replace(k, v) for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("mtmc: error:")
    assert message in err
    assert err.count("\n") == 1


def test_export_to_file_equals_stdout(tmp_path, capsys):
    f = EXAMPLES / "axis_c.toml"
    for to in ("assertions", "toml", "dot"):
        assert main(["graph", "export", str(f), "--to", to]) == 0
        text = capsys.readouterr().out
        dest = tmp_path / f"g.{to}"
        assert main(["graph", "export", str(f), "--to", to, "-o", str(dest)]) == 0
        assert capsys.readouterr().out == f"wrote {dest}\n"
        assert dest.read_text() == text
