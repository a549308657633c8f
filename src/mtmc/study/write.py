"""The result folder of a run, written whole or not at all.

:func:`write_result` writes ``result.json``, the CSV tables, the samples (``.npy``, when
the study keeps them), ``provenance.json``, a copy of the study file, a copy of every file
it names (``inputs/``) and the HTML report into a hidden temporary folder beside the
destination, and renames it into place at the
end: a run that fails or is interrupted leaves no folder that looks complete (at most a
hidden ``.NAME.*`` folder after a kill, never a ``result.json`` at the destination). Such
a folder names the process that made it, and the next run into the same destination
removes those of processes that are gone. Writers of one destination swap their folders
in one at a time (a lock on the parent folder): the last one's folder stays, whole. A
destination that is a symbolic link is followed. The layout is documented in
``docs/results-format.md``.

The folder reruns by itself: every file the run read through the study file (a graph, a
CSV of observations or readings, an artefact file; :attr:`mtmc.document.Source.files`)
is copied into ``inputs/`` as the run read it (its SHA-256 checked again, and recorded in
``provenance.json``), and the copied ``study.toml`` names the copies, its other text and
comments as they were (:func:`study_copy`): ``mtmc run OUTDIR/study.toml`` with the seed
and trials of the run gives the same numbers wherever the folder is moved.
"""

from __future__ import annotations

import contextlib
import datetime
import hashlib
import json
import os
import platform
import re
import shutil
import sys
import tempfile
from collections.abc import Iterator, Sequence
from dataclasses import replace
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from mtmc._version import __version__
from mtmc.document import InputFile
from mtmc.errors import InputError
from mtmc.io import _umask, deferred_interrupt, naming_os_errors
from mtmc.study.result import StudyResult
from mtmc.uncertainty.results import MonteCarloResult, MonteCarloResults

__all__ = ["INPUTS", "LIBRARIES", "copy_names", "now", "provenance", "study_copy", "write_result"]

#: The folder of a result folder that holds the copies of the files a study names.
INPUTS = "inputs"

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
        ``finished`` (UTC), ``platform`` (system, machine, Python), ``libraries`` and
        ``input_files``: per file the study names, ``field``, ``key`` (its key path),
        ``given`` (the path as the field gave it), ``source`` (the file read), ``copy``
        (in the result folder; None before it is written) and ``sha256``.
    """
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
        "input_files": [
            {
                "field": f.field,
                "key": list(f.key),
                "given": f.given,
                "source": f.source,
                "copy": f.copy,
                "sha256": f.sha256,
            }
            for f in result.input_files
        ],
    }


def copy_names(files: Sequence[InputFile]) -> tuple[InputFile, ...]:
    """The files with the paths of their copies in a result folder.

    A file goes to ``inputs/NAME`` (its own name); a second file of the same name from
    another folder to ``inputs/2/NAME``, a third to ``inputs/3/NAME``, so that no copy
    replaces another, nor a file of the result, and every copy keeps its name (a graph
    result records its file's name). Fields that name one file share its copy.
    """
    by_source: dict[str, str] = {}
    taken: set[str] = set()
    out = []
    for f in files:
        if f.source not in by_source:
            name = Path(f.source).name
            rel, n = f"{INPUTS}/{name}", 1
            while rel in taken:
                n += 1
                rel = f"{INPUTS}/{n}/{name}"
            taken.add(rel)
            by_source[f.source] = rel
        out.append(replace(f, copy=by_source[f.source]))
    return tuple(out)


def study_copy(text: str, files: Sequence[InputFile], file: str = "study.toml") -> str:
    """The study text with each field that names a file naming its copy instead.

    Only those values change (by :mod:`tomlkit`): comments, order and every other value
    stay as the user wrote them.

    Parameters
    ----------
    text : str
        The study file's text.
    files : sequence of InputFile
        The files it names, with their ``copy``.
    file : str
        The study file's name, for an error.

    Returns
    -------
    str

    Raises
    ------
    InputError
        Naming the file and the field, where a key of ``files`` is not in the text.
    """
    import tomlkit
    from tomlkit.exceptions import TOMLKitError

    named = [f for f in files if f.copy is not None]
    if not named:
        return text
    try:
        doc = tomlkit.parse(text)
    except TOMLKitError as exc:
        raise InputError(
            f"cannot rewrite the paths of the study's copy: {exc}", file=file
        ) from None
    for f in named:
        node: Any = doc
        try:
            for key in f.key[:-1]:
                node = node[key]
            node[f.key[-1]] = f.copy
        except (KeyError, IndexError, TypeError):
            raise InputError(
                "cannot name the copy of the file in the study's copy: the field is not there",
                file=file,
                field=f.field,
            ) from None
    return tomlkit.dumps(doc)


def _copy_inputs(files: Sequence[InputFile], tmp: Path, dest: Path) -> None:
    """Copy each file into ``tmp``, checking that its bytes are those the run read."""
    done: set[str] = set()
    for f in files:
        assert f.copy is not None
        if f.copy in done:
            continue
        done.add(f.copy)
        with naming_os_errors(Path(f.source)):
            data = Path(f.source).read_bytes()
        if hashlib.sha256(data).hexdigest() != f.sha256:
            raise InputError(
                f"{f.source} changed after the run read it (SHA-256 {f.sha256[:12]}... then, "
                f"{hashlib.sha256(data).hexdigest()[:12]}... now): its copy would not rerun "
                "to these numbers; run the study again",
                file=f.source,
                field=f.field,
            )
        target = tmp / f.copy
        target.parent.mkdir(parents=True, exist_ok=True)
        with naming_os_errors(dest / f.copy):
            target.write_bytes(data)


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
    plotted: int | str | None = None,
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
        The study file's text, copied as ``study.toml`` with the fields that name files
        naming their copies (:func:`study_copy`).
    started : str, optional
        When the run started (ISO 8601), for ``provenance.json``.
    argv : sequence of str, optional
        The command line (default ``sys.argv``).
    report : bool
        Also render ``report.html`` (:func:`mtmc.report.render`).
    plotted : int or "all", optional
        How many quantities of the report, from the first, get a histogram and a
        convergence plot (default :data:`mtmc.report.MAX_PLOTTED`).

    Returns
    -------
    pathlib.Path
        ``outdir``.

    Raises
    ------
    InputError
        If ``outdir`` exists and is a file or a folder that is not a result folder; if a
        file the study names changed since the run read it; if ``plotted`` is neither a
        whole number >= 0 nor ``"all"``.
    """
    if report:
        from mtmc.report import plotted_count

        plotted_count({}, plotted)  # checked before anything is written
    if not isinstance(result, StudyResult):
        from mtmc.study.load import study_result

        result = study_result(result)
    result = replace(result, input_files=copy_names(result.input_files))
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
        _copy_inputs(result.input_files, tmp, dest)
        if study_text is not None:
            text = study_copy(study_text, result.input_files, result.study_file or "study.toml")
            _write(tmp, dest, "study.toml", text)
        prov = provenance(result, started=started, argv=argv)
        _write(tmp, dest, "provenance.json", _dump(prov))
        if report:
            from mtmc.report import render

            render(tmp, plotted=plotted)
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
