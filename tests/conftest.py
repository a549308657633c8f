"""Settings for the whole test suite."""

from __future__ import annotations

import fcntl
import os
import signal
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, NoReturn

import pytest

# One BLAS thread in each test process, unless the environment says otherwise: pytest-xdist
# runs a worker per core (make test), and each worker's OpenBLAS would start a thread per
# core again, which spin against each other on the thin products of the tests (the tests of
# tests/verification took 110 s on two workers with two BLAS threads each, 67 s with one,
# the machine under the same load). The numbers do not depend on it; the tests of
# one_blas_thread set their own counts (threadpool_limits). Set here, before NumPy is
# imported, it reaches the workers, which inherit this process's environment.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


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


#: The trials each shipped study (``examples/studies``) is run with for the tests that read
#: its result folder and report (:func:`shipped`): enough for every table and plot, few
#: enough that the 16 folders take about a minute. The seed is :data:`SHIPPED_SEED`.
SHIPPED_TRIALS: dict[str, int] = {
    "aguado2016": 20,  # a verification: its Monte Carlo re-identifies the machine per trial
    "aguado2017": 20,
    "wang2022": 100,  # an artefact study: one identification a trial
    "circle_xy": 60,
    "circle_c_axis": 60,
    "circle_b_axis": 60,
}
SHIPPED_SEED = 3


@pytest.fixture(scope="session")
def shipped(tmp_path_factory: pytest.TempPathFactory) -> Callable[[str], Path]:
    """The result folder of a shipped study, written once for the whole test session.

    ``shipped("axis_c")`` runs ``examples/studies/axis_c.toml`` with
    ``SHIPPED_TRIALS`` (400 where it names none) and :data:`SHIPPED_SEED`, and writes its
    folder with its report, as ``mtmc run -o`` does. Under pytest-xdist every worker
    reads the same folders: the first to ask for one writes it, under a file lock, and
    the others wait for that one. The folders are shared: a test that changes one copies
    it first.
    """
    from mtmc.study import load_study, write_result

    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent  # the workers' temporary folders share this one
    root = base / "shipped"
    root.mkdir(exist_ok=True)
    studies = Path(__file__).resolve().parents[1] / "examples" / "studies"

    def folder(name: str) -> Path:
        out = root / name
        with open(root / f"{name}.lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
            if not (out / "report.html").is_file():  # written whole, or not at all
                study = load_study(studies / f"{name}.toml")
                result = study.run(trials=SHIPPED_TRIALS.get(name, 400), seed=SHIPPED_SEED)
                write_result(result, out, study_text=study.source.text)
        return out

    return folder


def _untraced(fn: Callable[..., Any]) -> Callable[..., Any]:
    """``fn`` run with this thread's tracer (coverage's, where it measures) taken off.

    The same tracer goes back after it, with what it knows of the calls around: the lines of
    the caller that follow are counted as before (stopping coverage and starting it again
    would lose them).
    """
    import functools

    @functools.wraps(fn)
    def run(*args: Any, **kwargs: Any) -> Any:
        tracer = sys.gettrace()
        if tracer is None:
            return fn(*args, **kwargs)
        sys.settrace(None)
        try:
            return fn(*args, **kwargs)
        finally:
            sys.settrace(tracer)

    return run


def pytest_sessionstart(session: pytest.Session) -> None:
    """Build and draw Matplotlib's figures with coverage's tracer paused.

    Coverage measures mtmc's lines only, but on Python 3.11 its tracer slows every line of
    every module while it runs. Matplotlib's own work for a report (making axes, measuring
    them for ``mtmc.report.plots._fit``, drawing with ``Figure.savefig``) runs as it is,
    untraced; mtmc's lines are traced as before. The unit and report tests took 170 s of CPU
    under the tracer, 132 s so, and 103 s without coverage; the lines counted are the same.
    """
    if session.config.pluginmanager.hasplugin("_cov"):
        from matplotlib.axis import Axis
        from matplotlib.figure import Figure, FigureBase

        Figure.savefig = _untraced(Figure.savefig)  # type: ignore[method-assign]
        Axis.get_tightbbox = _untraced(Axis.get_tightbbox)  # type: ignore[method-assign]
        FigureBase.add_subplot = _untraced(FigureBase.add_subplot)  # type: ignore[method-assign]
        FigureBase.subplots = _untraced(FigureBase.subplots)  # type: ignore[method-assign]
