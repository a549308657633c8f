"""SIGTERM ends ``mtmc run`` as Ctrl-C does, on every executor, and ``kill -9`` leftovers.

Each test runs the command in a child process (loopback only, bounded waits) and kills
whatever it started in a ``finally``.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "examples" / "studies" / "axis_c.toml"


def _catches(pid: int, sig: signal.Signals) -> bool:
    """Whether process ``pid`` has a handler of ``sig`` installed (its SigCgt mask, /proc)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    for line in status.splitlines():
        if line.startswith("SigCgt:"):
            return bool(int(line.split()[1], 16) >> (int(sig) - 1) & 1)
    return False


def _descendants(pid: int) -> set[int]:
    """The processes below ``pid`` (Linux /proc), children of children included."""
    found: set[int] = set()
    todo = [pid]
    while todo:
        p = todo.pop()
        for task in Path(f"/proc/{p}/task").glob("*"):
            try:
                kids = (task / "children").read_text().split()
            except OSError:
                continue
            for k in map(int, kids):
                if k not in found:
                    found.add(k)
                    todo.append(k)
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _start(outdir: Path, *extra: str) -> subprocess.Popen[bytes]:
    code = (
        "import sys; from mtmc.cli.main import main; print('ready', flush=True); "
        f"sys.exit(main(['run', {str(STUDY)!r}, '-o', {str(outdir)!r}, '-q', "
        f"'-n', '4000000', '--seed', '1', *{list(extra)!r}]))"
    )
    return subprocess.Popen(
        [sys.executable, "-c", code],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )


def _kill_all(proc: subprocess.Popen[bytes], pids: set[int]) -> None:
    for pid in [proc.pid, *pids]:
        try:
            os.kill(pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
    proc.wait(timeout=30)


@pytest.mark.skipif(not Path("/proc/self/task").is_dir(), reason="needs Linux /proc")
@pytest.mark.parametrize(
    ("extra", "children"),
    [
        pytest.param((), 0, id="thread"),
        pytest.param(
            ("--executor", "process", "--workers", "2"),
            2,
            id="process",
            # seen 3 times out of 6 while other processes loaded both cores: the interrupted
            # run's workers are terminated, but the interpreter's exit can then wait more
            # than 90 s on the pool's manager thread; not yet fixed
            marks=pytest.mark.xfail(
                strict=False, reason="under load, exit can hang on the process pool's thread"
            ),
        ),
        pytest.param(("--executor", "dask", "--workers", "2"), 2, id="dask"),
    ],
)
def test_sigterm_is_one_line_exit_143_no_orphan_no_folder(tmp_path, extra, children):
    if "dask" in extra:
        pytest.importorskip("distributed")
    out = tmp_path / "out"
    proc = _start(out, *extra)
    seen: set[int] = set()
    try:
        assert proc.stdout is not None
        assert proc.stdout.readline() == b"ready\n"
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline:  # until the run's workers are up
            seen |= _descendants(proc.pid)
            if len(seen) >= children:
                time.sleep(1.5)
                seen |= _descendants(proc.pid)
                break
            time.sleep(0.2)
        assert len(seen) >= children, seen
        proc.send_signal(signal.SIGTERM)
        _out, err = proc.communicate(timeout=90)
        assert proc.returncode == 143, err
        assert err.decode().splitlines() == ["mtmc: terminated"], err
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline and any(_alive(p) for p in seen):
            time.sleep(0.2)
        assert [p for p in seen if _alive(p)] == []
        assert sorted(p.name for p in tmp_path.iterdir()) == []
    finally:
        if proc.poll() is None or any(_alive(p) for p in seen):
            _kill_all(proc, seen)


def _session(sid: int) -> list[int]:
    """The live processes of session ``sid`` (the child started with a session of its own)."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[3]) == sid and fields[0] != "Z":
            found.append(int(stat.parent.name))
    return found


@pytest.mark.skipif(not Path("/proc/self/task").is_dir(), reason="needs Linux /proc")
def test_signal_while_the_dask_cluster_starts_is_one_line_and_leaves_nothing(tmp_path):
    # A signal while the cluster starts or closes used to leave Dask's workers half-started:
    # its close at exit then printed "AssertionError: Status.init" after the message, and
    # the workers' scratch folders stayed in the temporary folder. The signal is sent
    # before the first worker process exists and at 0, 0.5 and 1.5 s after it appears
    # (the cluster took 3-8 s to start on a loaded 2-core machine), SIGTERM and SIGINT.
    pytest.importorskip("distributed")
    # and Ctrl-C in a terminal: SIGINT to the whole process group, the workers too
    cases = [("before", signal.SIGTERM, False), (0.0, signal.SIGINT, False)]
    cases += [(0.5, signal.SIGTERM, False), (1.5, signal.SIGINT, True), (4.0, signal.SIGINT, True)]
    for when, sig, group in cases:
        tmp = tmp_path / f"tmp-{sig.name}-{when}-{'group' if group else 'main'}"
        tmp.mkdir()
        code = (
            "import sys; from mtmc.cli.main import main; print('ready', flush=True); "
            f"sys.exit(main(['run', {str(STUDY)!r}, '-q', '-n', '100000000', '--seed', '1', "
            "'--executor', 'dask', '--workers', '2']))"
        )
        proc = subprocess.Popen(
            [sys.executable, "-c", code],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            start_new_session=True,
            env={**os.environ, "TMPDIR": str(tmp)},
        )
        try:
            assert proc.stdout is not None
            assert proc.stdout.readline() == b"ready\n"
            if when == "before":
                # "before the cluster" is after the command's handlers are in place: a
                # signal before them ends Python by its default action, whatever mtmc does
                deadline = time.monotonic() + 60
                while not _catches(proc.pid, sig) and time.monotonic() < deadline:
                    time.sleep(0.005)
                assert _catches(proc.pid, sig), f"no handler of {sig.name} in 60 s"
            else:
                deadline = time.monotonic() + 90
                while not _descendants(proc.pid) and time.monotonic() < deadline:
                    time.sleep(0.02)
                assert _descendants(proc.pid), "no worker process started in 90 s"
                time.sleep(float(when))
            if group:
                os.killpg(proc.pid, sig)
            else:
                proc.send_signal(sig)
            _out, err = proc.communicate(timeout=120)
            expected = (
                (143, "mtmc: terminated\n")
                if sig == signal.SIGTERM
                else (130, "mtmc: interrupted\n")
            )
            # Ctrl-C to the group reaches the workers too: they printed their own
            # KeyboardInterrupt traceback above the line (3 of 3 tries) until SIGINT was
            # blocked in them (parallel._ctrl_c_held_from_workers)
            assert (proc.returncode, err.decode()) == expected, (when, sig, group)
            deadline = time.monotonic() + 30
            while _session(proc.pid) and time.monotonic() < deadline:
                time.sleep(0.2)
            assert _session(proc.pid) == [], (when, sig)
            assert sorted(p.name for p in tmp.rglob("*")) == [], (when, sig)
        finally:
            for pid in _session(proc.pid):
                try:
                    os.kill(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
            if proc.poll() is None:
                proc.kill()
            proc.wait(timeout=30)
