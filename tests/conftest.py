"""Settings for the whole test suite."""

from __future__ import annotations

import signal


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
