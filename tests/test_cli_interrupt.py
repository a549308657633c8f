"""Ctrl-C and non-finite model values on the command line: one line, a clear exit status."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mtmc.cli.main import main
from mtmc.io import deferred_interrupt, write_text_atomic

EXAMPLES = Path(__file__).resolve().parent.parent / "examples" / "graphs"


def test_propagate_nan_is_one_line_naming_the_option(capsys):
    argv = ["propagate", "log(x)", "-i", "x=normal(0.1, 1)", "-n", "1000", "--seed", "1"]
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == "", err
    assert err.count("\n") == 1, err
    assert "in 4" in err
    assert "--nan-policy omit" in err
    assert "RuntimeWarning" not in err


def test_propagate_nan_policy_omit_leaves_those_trials_out(capsys):
    argv = ["propagate", "log(x)", "-i", "x=normal(0.1, 1)", "-n", "1000", "--seed", "1"]
    assert main([*argv, "--nan-policy", "omit", "--json"]) == 0
    out, err = capsys.readouterr()
    doc = json.loads(out)
    assert err == ""
    # the same seed: the trials with x <= 0 are the ones left out (P(x <= 0) = 0.46)
    assert 400 < doc["omitted"] < 520
    assert doc["trials"] == 1000


def test_nan_policy_rejects_other_values(capsys):
    argv = ["propagate", "x", "-i", "x=normal(0, 1)", "-n", "1000", "--nan-policy", "skip"]
    assert main(argv) == 2
    assert "field --nan-policy: expected raise or omit" in capsys.readouterr().err


def test_graph_run_has_the_nan_policy_option(capsys):
    argv = ["graph", "run", str(EXAMPLES / "ball_centre.toml"), "-n", "100", "--seed", "1"]
    assert main([*argv, "--nan-policy", "omit", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["trials"] == 100


def test_ctrl_c_in_a_subcommand_is_one_line_exit_130_and_no_file(tmp_path, capsys, monkeypatch):
    import mtmc.graph.draw

    def interrupted(*_args, **_kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(mtmc.graph.draw, "draw_graph", interrupted)
    out_file = tmp_path / "g.svg"
    assert main(["graph", "draw", str(EXAMPLES / "ball_centre.toml"), "-o", str(out_file)]) == 130
    out, err = capsys.readouterr()
    assert out == ""
    assert err == "mtmc: interrupted\n"
    assert list(tmp_path.iterdir()) == []


def test_interrupt_during_the_rename_is_held_until_the_file_is_whole(tmp_path, monkeypatch):
    dest = tmp_path / "r.json"
    dest.write_text("old")
    real_replace = os.replace

    def replace_with_ctrl_c(src, dst):
        os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C arrives in the middle of the commit
        real_replace(src, dst)

    monkeypatch.setattr(os, "replace", replace_with_ctrl_c)
    with pytest.raises(KeyboardInterrupt):
        write_text_atomic(dest, "new")
    assert dest.read_text() == "new"
    assert [p.name for p in tmp_path.iterdir()] == ["r.json"]


def test_deferred_interrupt_restores_the_handler():
    before = signal.getsignal(signal.SIGINT)
    with deferred_interrupt():
        pass
    assert signal.getsignal(signal.SIGINT) is before


def test_real_sigint_to_a_running_graph_run():
    # a child that imports the CLI, says so, then runs a long Monte Carlo; Ctrl-C is sent
    # once it runs (not during the imports, which are outside the CLI's hands)
    code = (
        "import sys; from mtmc.cli.main import main; print('ready', flush=True); "
        f"sys.exit(main(['graph', 'run', {str(EXAMPLES / 'axis_c.toml')!r}, "
        "'-n', '100000000', '--seed', '1', '--no-progress']))"
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )
    assert proc.stdout is not None
    assert proc.stdout.readline() == b"ready\n"
    time.sleep(1.0)
    proc.send_signal(signal.SIGINT)
    _out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert err.decode() == "mtmc: interrupted\n"
