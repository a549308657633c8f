"""The result folder of a run, written whole or not at all.

:func:`write_result` writes ``result.json``, the CSV tables, the samples (``.npy``, when
the study keeps them), ``provenance.json``, a copy of the study file and the HTML report
into a hidden temporary folder beside the destination, and renames it into place at the
end: a run that fails or is interrupted leaves no folder that looks complete (at most a
hidden ``.NAME.*`` folder after a kill, never a ``result.json`` at the destination). Such
a folder names the process that made it, and the next run into the same destination
removes those of processes that are gone. Writers of one destination swap their folders
in one at a time (a lock on the parent folder): the last one's folder stays, whole. A
destination that is a symbolic link is followed. The layout is documented in
``docs/results-format.md``.
"""

from __future__ import annotations

import contextlib
import datetime
import json
import os
import platform
import re
import shutil
import sys
import tempfile
from collections.abc import Iterator, Sequence
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from mtmc.errors import InputError
from mtmc.io import _umask, deferred_interrupt, naming_os_errors
from mtmc.study.base import StudyResult
from mtmc.uncertainty.results import MonteCarloResult, MonteCarloResults

__all__ = ["LIBRARIES", "now", "provenance", "write_result"]

#: The libraries whose versions ``provenance.json`` records.
LIBRARIES = ("numpy", "scipy", "sympy", "matplotlib", "jinja2", "typer", "rich")


def now() -> str:
    """The current UTC time, ISO 8601 to the microsecond."""
    return datetime.datetime.now(datetime.UTC).isoformat(timespec="microseconds")


def provenance(
    result: StudyResult,
    *,
    started: str | None = None,
    finished: str | None = None,
    argv: Sequence[str] | None = None,
) -> dict[str, Any]:
    """What ``provenance.json`` records of a run.

    Returns
    -------
    dict
        ``mtmc_version``, ``seed``, ``seed_entropy`` (of ``numpy.random.SeedSequence(seed)``),
        ``trials``, ``study_file``, ``study_sha256``, ``command_line``, ``started``,
        ``finished`` (UTC), ``platform`` (system, machine, Python) and ``libraries``.
    """
    from mtmc import __version__

    libs: dict[str, str | None] = {}
    for name in LIBRARIES:
        try:
            libs[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            libs[name] = None
    return {
        "mtmc_version": __version__,
        "seed": result.seed,
        # a result without a seed (values from elsewhere) has no entropy to record
        "seed_entropy": (
            None if result.seed is None else str(np.random.SeedSequence(result.seed).entropy)
        ),
        "trials": result.trials,
        "study_file": result.study_file,
        "study_sha256": result.study_sha256,
        "command_line": list(sys.argv if argv is None else argv),
        "started": started,
        "finished": finished or now(),
        "platform": {
            "system": platform.platform(),
            "machine": platform.machine(),
            "python": platform.python_version(),
            "implementation": platform.python_implementation(),
        },
        "libraries": libs,
    }


def _check_destination(dest: Path) -> None:
    """Refuse a destination that is a file, or a folder that is not a result folder."""
    if dest.exists() and not dest.is_dir():
        raise InputError(f"{dest} exists and is not a folder", field="outdir")
    if dest.is_dir() and any(dest.iterdir()) and not (dest / "result.json").is_file():
        raise InputError(
            f"{dest} exists and is not a result folder (no result.json): not replaced",
            field="outdir",
        )


def _temp_prefix(dest: Path, kind: str = "") -> str:
    """``.NAME.[old.]mtmc-PID-``: the hidden folders of this run beside ``dest``."""
    return f".{dest.name}.{kind}mtmc-{os.getpid()}-"


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process: alive
        return True
    return True


def _remove_stale(dest: Path) -> None:
    """Remove the hidden temporary folders of ``dest`` left by runs that were killed.

    Only folders named as :func:`_temp_prefix` names them, whose process is gone, are
    removed; any other hidden folder, and those of a run still going, are left alone.
    """
    pattern = re.compile(rf"\.{re.escape(dest.name)}\.(?:old\.)?mtmc-(\d+)-[A-Za-z0-9_]+")
    try:
        entries = list(dest.parent.iterdir())
    except OSError:
        return
    for entry in entries:
        match = pattern.fullmatch(entry.name)
        if match is None or int(match.group(1)) == os.getpid():
            continue
        if not _pid_alive(int(match.group(1))) and entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry, ignore_errors=True)


@contextlib.contextmanager
def _folder_lock(folder: Path) -> Iterator[None]:
    """An exclusive lock (``flock``) on ``folder`` itself for the block: no lock file."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX: no lock
        yield
        return
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:  # pragma: no cover - a folder that cannot be opened: no lock
        yield
        return
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


def _dump(obj: Any) -> str:
    return json.dumps(obj, indent=1, ensure_ascii=False, allow_nan=False) + "\n"


def _write(tmp: Path, dest: Path, name: str, text: str) -> None:
    """Write ``tmp/name``; an error of the file system names ``dest/name``."""
    with naming_os_errors(dest / name):
        (tmp / name).write_text(text, encoding="utf-8")


def write_result(
    result: StudyResult | MonteCarloResult | MonteCarloResults,
    outdir: str | os.PathLike[str],
    *,
    study_text: str | None = None,
    started: str | None = None,
    argv: Sequence[str] | None = None,
    report: bool = True,
) -> Path:
    """Write the result folder of a run (atomically, as a whole).

    Parameters
    ----------
    result : StudyResult, MonteCarloResult or MonteCarloResults
        The result; a plain Monte Carlo result is first made a study result of kind
        ``monte_carlo`` (:func:`mtmc.study.load.study_result`; its samples are not
        written, as a study's by default).
    outdir : path-like
        The folder to create. An existing folder is replaced only if it is a result
        folder (it holds ``result.json``) or empty.
    study_text : str, optional
        The study file's text, copied as ``study.toml``.
    started : str, optional
        When the run started (ISO 8601), for ``provenance.json``.
    argv : sequence of str, optional
        The command line (default ``sys.argv``).
    report : bool
        Also render ``report.html`` (:func:`mtmc.report.render`).

    Returns
    -------
    pathlib.Path
        ``outdir``.

    Raises
    ------
    InputError
        If ``outdir`` exists and is a file or a folder that is not a result folder.
    """
    if not isinstance(result, StudyResult):
        from mtmc.study.load import study_result

        result = study_result(result)
    dest = Path(outdir)
    if dest.is_symlink():  # a link is followed, for a folder as for a file
        dest = Path(os.path.realpath(dest))
    dest.parent.mkdir(parents=True, exist_ok=True)
    # checked under the lock: another writer's swap leaves OUTDIR absent for a moment
    with _folder_lock(dest.parent):
        _check_destination(dest)
        _remove_stale(dest)
        tmp = Path(tempfile.mkdtemp(prefix=_temp_prefix(dest), dir=dest.parent))
    try:
        doc = result.to_dict()
        _write(tmp, dest, "result.json", _dump(doc))
        for name, text in result.csv_tables().items():
            _write(tmp, dest, name, text)
        if result.samples:
            (tmp / "samples").mkdir()
            for name, arr in result.samples.items():
                with naming_os_errors(dest / "samples" / f"{name}.npy"):
                    np.save(tmp / "samples" / f"{name}.npy", np.asarray(arr))
        if study_text is not None:
            _write(tmp, dest, "study.toml", study_text)
        prov = provenance(result, started=started, argv=argv)
        _write(tmp, dest, "provenance.json", _dump(prov))
        if report:
            from mtmc.report import render

            render(tmp)
        os.chmod(tmp, 0o777 & ~_umask())
        old = None
        # the swap is never cut half-way by Ctrl-C, and one writer of a folder swaps at a
        # time: two runs into one OUTDIR both succeed, the last one's folder stays whole
        with deferred_interrupt(), _folder_lock(dest.parent):
            _check_destination(dest)
            if dest.exists():
                old = Path(tempfile.mkdtemp(prefix=_temp_prefix(dest, "old."), dir=dest.parent))
                os.rmdir(old)
                os.replace(dest, old)
            os.replace(tmp, dest)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        with contextlib.suppress(OSError):
            shutil.rmtree(tmp)
        raise
    return dest
