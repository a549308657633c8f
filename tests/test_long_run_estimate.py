"""A long run says, once and at its start, its trials per second and the time it will take."""

from __future__ import annotations

import time

import pytest

from mtmc.cli import common


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


@pytest.fixture
def clock(monkeypatch):
    c = Clock()
    monkeypatch.setattr(time, "perf_counter", c)
    return c


def test_a_long_run_prints_its_rate_and_time_once(clock, capsys):
    with common.progress_bar("s.toml: Monte Carlo", False) as update:
        update(65_536, 10**9)  # the first block: the clock starts
        clock.now += 0.5
        update(131_072, 10**9)  # under a second: too early to say
        clock.now += 1.5
        update(65_536 + 2 * 10**6, 10**9)  # 2·10⁶ trials in 2 s: 10⁶ trials/s
        clock.now += 1.0
        update(65_536 + 3 * 10**6, 10**9)
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    left = (10**9 - 65_536 - 2 * 10**6) / 1e6
    assert "1,000,000,000 trials at 1,000,000 trials/s" in err
    assert common.duration_text(left) in err
    assert "16 min 38 s" in err
    assert "Ctrl-C" in err


def test_a_short_run_says_nothing(clock, capsys):
    with common.progress_bar("s.toml: Monte Carlo", False) as update:
        update(65_536, 10**7)
        clock.now += 2.0
        update(65_536 + 5 * 10**6, 10**7)  # 2.5·10⁶ trials/s: 2 s left
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize(
    ("seconds", "text"),
    [(0.4, "0 s"), (59.4, "59 s"), (60, "1 min 00 s"), (3599, "59 min 59 s"), (7500, "2 h 05 min")],
)
def test_duration_text(seconds, text):
    assert common.duration_text(seconds) == text
