"""Atomic file output: a result file is either written whole or not at all.

Every file mtmc writes (results, drawings, CSV tables, reports) goes through these
functions: the content is written to a temporary file in the destination folder, flushed
to disk, then renamed over the destination in one step (``os.replace``), so a crash or an
error half-way never leaves a truncated file, and an existing file is kept until the new
one is complete.

Examples
--------
>>> import tempfile, pathlib
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> write_text_atomic(d / "out.txt", "hello")
PosixPath('...out.txt')
>>> (d / "out.txt").read_text()
'hello'
"""

from __future__ import annotations

import contextlib
import math
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

__all__ = ["atomic_path", "to_jsonable", "write_bytes_atomic", "write_text_atomic"]


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success rename it over ``path``.

    Use it for writers that want a file name (Matplotlib's ``savefig``, ``np.savetxt``).
    If the block raises, the temporary file is removed and ``path`` is left untouched.

    Parameters
    ----------
    path : path-like
        The destination. Its folder must exist.

    Yields
    ------
    pathlib.Path
        The temporary file to write; it has the same suffix as ``path`` so that writers
        which choose a format by suffix choose the right one.
    """
    dest = Path(path)
    if not dest.parent.is_dir():
        raise FileNotFoundError(f"{dest}: the folder {dest.parent} does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{dest.name}.", suffix=dest.suffix, dir=dest.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        with open(tmp_path, "rb+") as fh:
            fh.flush()
            os.fsync(fh.fileno())
        # mkstemp creates the file owner-only (0600): give it the mode a plain open() would.
        os.chmod(tmp_path, 0o666 & ~_umask())
        os.replace(tmp_path, dest)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text_atomic(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (UTF-8, newlines as given) to ``path`` atomically and return the path."""
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8", newline="") as fh:
        fh.write(text)
    return Path(path)


def write_bytes_atomic(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically and return the path."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def to_jsonable(obj: Any, *, nonfinite_as_null: bool = False) -> Any:
    """NumPy scalars and arrays (nested in dicts, lists, tuples) as plain JSON types.

    Parameters
    ----------
    obj : any
        The value.
    nonfinite_as_null : bool
        Write NaN and infinities as ``None`` (strict JSON) instead of keeping them.

    Returns
    -------
    any
        Dicts (with string keys), lists, floats, ints, strings, booleans and None.

    Examples
    --------
    >>> import numpy as np
    >>> value = {"a": np.arange(2), "b": (np.float64(1.5), float("inf"))}
    >>> to_jsonable(value, nonfinite_as_null=True)
    {'a': [0, 1], 'b': [1.5, None]}
    """
    import numpy as np  # here, so that importing mtmc.io (and mtmc) stays cheap

    if isinstance(obj, dict):
        return {str(k): to_jsonable(v, nonfinite_as_null=nonfinite_as_null) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_jsonable(v, nonfinite_as_null=nonfinite_as_null) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist(), nonfinite_as_null=nonfinite_as_null)
    if isinstance(obj, np.generic):
        obj = obj.item()
    if nonfinite_as_null and isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj
