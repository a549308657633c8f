"""Settings for the whole test suite."""

from __future__ import annotations

import os
import signal
from typing import NoReturn

import pytest


def pytest_configure() -> None:
    """Let Ctrl-C reach the child processes that the tests interrupt on purpose.

    A shell without job control (a CI script's ``cmd &``, ``nohup``) starts its jobs with
    SIGINT ignored; an ignored signal stays ignored across ``exec``, and a Python started
    with it ignored never installs its KeyboardInterrupt handler. The tests that send
    SIGINT to a running ``mtmc`` would then see it run to the end. With a handler here,
    a child starts with SIGINT at its default, as from a terminal.
    """
    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def absent(what: str, remedy: str) -> NoReturn:
    """Skip a test whose tool ``what`` is not on this machine, or fail it in CI.

    The suite installs nothing system-wide: CI's ``.ci/run`` installs what the tests use
    (Debian's ``chromium``), a developer installs it as README.md says, and a test (or a
    module of tests) that cannot find it elsewhere is skipped with the reason. Under
    ``CI=true`` a missing tool means the CI set-up is broken, and the test fails instead of
    passing quietly.
    """
    reason = f"{what} is not installed ({remedy})"
    if os.environ.get("CI", "").lower() == "true":
        pytest.fail(f"{reason}; CI=true, where .ci/run installs it", pytrace=False)
    pytest.skip(reason, allow_module_level=True)
