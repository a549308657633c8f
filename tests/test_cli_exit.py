"""Exit status of ``mtmc``: 0 on success, 2 with one line on stderr on bad input.

Checked in-process through :func:`mtmc.cli.main.main` and in a real process, both as
``python -m mtmc.cli.main`` and through the installed ``mtmc`` console script.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from mtmc import __version__
from mtmc.cli.main import main

EXAMPLES = Path(__file__).resolve().parent.parent / "examples" / "graphs"
SCRIPT = Path(sys.executable).parent / "mtmc"


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["graph", "run"], "Missing argument 'file'. (see 'mtmc graph run --help')"),
        (["graph", "bogus"], "No such command 'bogus'. (see 'mtmc graph --help')"),
        (["propagate", "x", "-i", "x=normal(0, 1)", "-n", "many"], "Invalid value for '--trials'"),
        (["kinematics", "show", "--colour"], "No such option: --colour"),
        (
            ["run", str(EXAMPLES.parent / "studies" / "ball_centre.toml"), "-n", "-5"],
            "--trials: expected an integer >= 2, got -5",
        ),
        (["report", "no-such-folder"], "no-such-folder: not a result folder: no such folder"),
    ],
)
def test_usage_errors_are_one_line_exit_2(argv, fragment, capsys):
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith("mtmc: error: ")
    assert err.count("\n") == 1
    assert fragment in err


@pytest.mark.parametrize(
    "argv",
    [
        ["graph", "check", "missing.toml"],
        ["kinematics", "show", "XYZ"],
        ["propagate", "a", "-i", "a=normel(0, 1)"],
    ],
)
def test_library_errors_exit_2_through_fail(argv, capsys):
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith("mtmc: error: ")
    assert err.count("\n") == 1


def test_success_and_help_exit_0(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out == f"mtmc {__version__}\n"
    assert main(["graph", "run", "--help"]) == 0
    assert "--progress" in capsys.readouterr().out
    # the help shows the study's keys as written (nothing eaten as Rich markup)
    assert main(["run", "--help"]) == 0
    assert "run.trials" in " ".join(capsys.readouterr().out.split())


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["COLUMNS"] = "120"
    return env


def _commands() -> list[list[str]]:
    cmds = [[sys.executable, "-m", "mtmc.cli.main"]]
    if SCRIPT.exists():
        cmds.append([str(SCRIPT)])
    return cmds


@pytest.mark.parametrize("cmd", _commands(), ids=lambda c: Path(c[-1]).name)
def test_real_process_exit_codes(cmd):
    ok = subprocess.run(
        [
            *cmd,
            "graph",
            "run",
            str(EXAMPLES / "ball_centre.toml"),
            "-n",
            "500",
            "--seed",
            "1",
            "--place",
            "cx",
            "--json",
        ],
        capture_output=True,
        text=True,
        env=_env(),
        timeout=120,
    )
    assert ok.returncode == 0, ok.stderr
    assert ok.stderr == ""
    assert json.loads(ok.stdout)["places"]["cx"]["type"] == "x"

    bad = subprocess.run(
        [*cmd, "graph", "run", str(EXAMPLES / "ball_centre.toml"), "--place", "zz"],
        capture_output=True,
        text=True,
        env=_env(),
        timeout=120,
    )
    assert bad.returncode == 2
    assert bad.stdout == ""
    assert bad.stderr.count("\n") == 1
    assert bad.stderr.startswith("mtmc: error: ")
    assert "the graph has no place zz" in bad.stderr

    usage = subprocess.run(
        [*cmd, "graph", "run"], capture_output=True, text=True, env=_env(), timeout=120
    )
    assert usage.returncode == 2
    assert usage.stderr.count("\n") == 1
