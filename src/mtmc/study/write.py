"""The result folder of a run, written whole or not at all.

:func:`write_result` writes ``result.json``, the CSV tables, the samples (``.npy``, when
the study keeps them), ``provenance.json``, a copy of the study file and the HTML report
into a hidden temporary folder beside the destination, and renames it into place at the
end: a run that fails or is interrupted leaves no folder that looks complete (at most a
hidden ``.NAME.*`` folder after a kill, never a ``result.json`` at the destination). The
layout is documented in ``docs/results-format.md``.
"""

from __future__ import annotations

import contextlib
import datetime
import json
import os
import platform
import shutil
import sys
import tempfile
from collections.abc import Sequence
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from mtmc.errors import InputError
from mtmc.io import _umask, deferred_interrupt
from mtmc.study.base import StudyResult

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
        "seed_entropy": str(np.random.SeedSequence(result.seed).entropy),
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


def _dump(obj: Any) -> str:
    return json.dumps(obj, indent=1, ensure_ascii=False, allow_nan=False) + "\n"


def write_result(
    result: StudyResult,
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
    result : StudyResult
        The result.
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
    dest = Path(outdir)
    if dest.exists() and not dest.is_dir():
        raise InputError(f"{dest} exists and is not a folder", field="outdir")
    if dest.is_dir() and any(dest.iterdir()) and not (dest / "result.json").is_file():
        raise InputError(
            f"{dest} exists and is not a result folder (no result.json): not replaced",
            field="outdir",
        )
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name}.", dir=dest.parent))
    try:
        doc = result.to_dict()
        (tmp / "result.json").write_text(_dump(doc), encoding="utf-8")
        for name, text in result.csv_tables().items():
            (tmp / name).write_text(text, encoding="utf-8")
        if result.samples:
            (tmp / "samples").mkdir()
            for name, arr in result.samples.items():
                np.save(tmp / "samples" / f"{name}.npy", np.asarray(arr))
        if study_text is not None:
            (tmp / "study.toml").write_text(study_text, encoding="utf-8")
        prov = provenance(result, started=started, argv=argv)
        (tmp / "provenance.json").write_text(_dump(prov), encoding="utf-8")
        if report:
            from mtmc.report import render

            render(tmp)
        os.chmod(tmp, 0o777 & ~_umask())
        old = None
        with deferred_interrupt():  # the swap is never cut half-way by Ctrl-C
            if dest.exists():
                old = Path(tempfile.mkdtemp(prefix=f".{dest.name}.old.", dir=dest.parent))
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
