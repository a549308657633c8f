"""Hostile input to ``mtmc graph``: one line naming the file, line and field; strict JSON."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from mtmc.cli.main import main

EXAMPLES = Path(__file__).resolve().parent / ".." / "examples" / "graphs"


def _one_line(capsys) -> str:
    _out, err = capsys.readouterr()
    assert err.startswith("mtmc: error: "), err
    assert err.count("\n") == 1, err
    return err


def _edit(name: str, old: str, new: str, tmp_path: Path) -> Path:
    text = (EXAMPLES / name).read_text()
    assert old in text
    f = tmp_path / name
    f.write_text(text.replace(old, new, 1))
    return f


def test_non_utf8_file_names_file_line_and_column(tmp_path, capsys):
    f = tmp_path / "b.toml"
    f.write_bytes(b'title = "x"\nunits = "\xff\xfe"\n')
    assert main(["graph", "check", str(f)]) == 2
    assert "b.toml:2:10: not UTF-8 text (byte 0xff)" in _one_line(capsys)


def test_non_utf8_assertion_file(tmp_path, capsys):
    f = tmp_path / "b.pl"
    f.write_bytes(b"% x\n\x96\n")
    assert main(["graph", "check", str(f)]) == 2
    assert "b.pl:2:1: not UTF-8" in _one_line(capsys)


@pytest.mark.parametrize(
    ("name", "old", "new", "where"),
    [
        ("ball_centre.toml", 'op = "meas"', 'pos = true\nop = "meas"', r":\d+: field pos: "),
        ("ball_centre.toml", "u_axis = 0.002", "u_axis = 1e308", r":5: field u_axis: "),
        (
            "plane_lsq.toml",
            "at = [100.0, 0.0, 0.0]",
            "at = [100.0, 40.0, 1e308]",
            r":\d+: field at: transition m3",
        ),
        (
            "axis_c.toml",
            "at = [137.3, 0.0, 40.0]",
            "at = [1e308, 0.0, 40.0]",
            r":\d+: field at: transition c1_m1",
        ),
    ],
)
def test_huge_and_wrong_typed_numbers_are_one_line(tmp_path, capsys, name, old, new, where):
    f = _edit(name, old, new, tmp_path)
    assert main(["graph", "run", str(f), "-n", "10", "--seed", "1", "--json"]) == 2
    err = _one_line(capsys)
    assert re.search(re.escape(name) + where, err), err


def test_json_is_strict_even_with_non_finite_numbers(capsys):
    from mtmc.cli.common import print_json

    print_json({"u": float("nan"), "v": [1.0, float("inf")]})
    out = capsys.readouterr().out
    assert json.loads(out, parse_constant=lambda c: pytest.fail(f"bare {c}")) == {
        "u": None,
        "v": [1.0, None],
    }


@pytest.mark.parametrize(
    ("text", "where"),
    [
        ('title = "x"\n\n[[transitin]]\nname = "a"\n', r"t\.toml:3: field transitin: unknown key"),
        ('title = "x"\n[[place]]\nname = "a', r"t\.toml:3:\d+: not valid TOML: .* end of the file"),
    ],
)
def test_parse_errors_always_name_a_line(tmp_path, capsys, text, where):
    f = tmp_path / "t.toml"
    f.write_text(text)
    assert main(["graph", "check", str(f)]) == 2
    assert re.search(where, _one_line(capsys))


def test_sweep_error_names_the_file_and_the_key(capsys):
    argv = ["graph", "sweep", str(EXAMPLES / "bcs_origin.toml"), "-n", "10"]
    argv += ["--vary", "probe.u_probe=-1:0.002:2", "--quantity", "d_ac"]
    assert main(argv) == 2
    err = _one_line(capsys)
    assert "bcs_origin.toml: field probe.u_probe: probe: u_probe must be >= 0" in err


def test_empty_error_name_names_the_option(capsys):
    assert main(["kinematics", "equation", "XFYZ", "-e", ""]) == 2
    err = _one_line(capsys)
    assert "--error: unknown error name ''" in err
    assert "field :" not in err
