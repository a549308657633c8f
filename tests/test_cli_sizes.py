"""Sizes a command cannot run: trials beyond the limit, a file that never ends."""

from __future__ import annotations

from pathlib import Path

import pytest

from mtmc.cli.main import main
from mtmc.document import read_text
from mtmc.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
HUGE = "99999999999999999999"


@pytest.mark.parametrize(
    "cmd",
    [
        ["run", str(ROOT / "examples" / "studies" / "mass_calibration.toml")],
        ["propagate", "a * b", "-i", "a=normal(1, 0.1)", "-i", "b=normal(2, 0.1)"],
        ["graph", "run", str(ROOT / "examples" / "graphs" / "axis_a.toml")],
        ["demo"],
    ],
)
def test_trials_beyond_the_limit_are_one_line(capsys, tmp_path, cmd):
    args = [*cmd, "--trials", HUGE]
    if cmd[0] in ("run", "demo"):
        args += ["-o", str(tmp_path / "out")]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err == f"mtmc: error: --trials: expected at most 1000000000 trials, got {HUGE}\n"
    assert not (tmp_path / "out").exists()


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="no /dev/zero")
def test_a_file_that_never_ends_is_refused(capsys):
    with pytest.raises(InputError, match="more than 256 MiB"):
        read_text("/dev/zero", "study file")
    assert main(["run", "/dev/zero"]) == 2
    err = capsys.readouterr().err
    assert err == (
        "mtmc: error: /dev/zero: cannot read the study file: it holds more than 256 MiB "
        "(a device or a stream that does not end?)\n"
    )
