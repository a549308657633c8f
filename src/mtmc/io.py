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
import shutil
import signal
import stat
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from mtmc.errors import ParseError

__all__ = [
    "atomic_path",
    "decode_utf8",
    "loads_json",
    "naming_os_errors",
    "to_jsonable",
    "write_bytes_atomic",
    "write_text_atomic",
]


@contextlib.contextmanager
def naming_os_errors(path: str | os.PathLike[str]) -> Iterator[None]:
    """Give an ``OSError`` raised in the block that names no file the name of ``path``.

    A full disk seen by NumPy reads ``1000000 requested and 259568 written``; through this
    block it reads ``PATH: cannot write: 1000000 requested and 259568 written``. An error
    that names its file already passes unchanged.

    Parameters
    ----------
    path : path-like
        The file the block writes.

    Raises
    ------
    OSError
        Of the same errno and ``strerror``, with ``filename`` set to ``path``; its text
        reads ``PATH: cannot write: REASON``.
    """
    try:
        yield
    except OSError as exc:
        if exc.filename is not None:
            raise
        raise _WriteError(exc.errno, exc.strerror or str(exc), os.fspath(path)) from exc


class _WriteError(OSError):
    """An ``OSError`` of a write, its file named: ``strerror`` keeps the reason alone."""

    def __str__(self) -> str:
        return f"{self.filename}: cannot write: {self.strerror}"


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], *, follow: bool = True) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success rename it over ``path``.

    Use it for writers that want a file name (Matplotlib's ``savefig``, ``np.savetxt``).
    If the block raises, the temporary file is removed and ``path`` is left untouched.

    What stands at ``path`` is respected:

    - a symbolic link is followed: its target is replaced atomically and the link stays;
    - an existing regular file keeps its permission bits (a 0600 file stays 0600);
    - a FIFO or a character device (``/dev/null``, a terminal) is written through: the
      complete content is first written to a temporary file, then copied into it, and
      the node itself is never replaced;
    - anything else (a folder, a block device, a socket) is refused.

    With ``follow=False`` (a file inside a folder someone else made, such as the report of
    a result folder that came as an archive) a symbolic link, a FIFO or a device at
    ``path`` is itself replaced by the file: nothing outside the folder is written.

    Parameters
    ----------
    path : path-like
        The destination. Its folder must exist.
    follow : bool
        Write through a link, a FIFO or a character device at ``path`` (default), or
        replace it.

    Yields
    ------
    pathlib.Path
        The temporary file to write; it has the same suffix as ``path`` so that writers
        which choose a format by suffix choose the right one.

    Raises
    ------
    FileNotFoundError
        When the folder of ``path`` does not exist.
    IsADirectoryError, PermissionError
        When ``path`` is a folder, a block device or a socket; the message names it.
    OSError
        From the file system (full disk, no permission); ``path`` is then left as it was.
        One that names no file (NumPy's ``1000000 requested and 259568 written``) is
        given the name of ``path`` (:func:`naming_os_errors`).
    """
    dest = _resolve(Path(path)) if follow else Path(path)
    mode = _destination_mode(dest) if follow or not _replaceable(dest) else None
    through = mode is not None and (stat.S_ISFIFO(mode) or stat.S_ISCHR(mode))
    # A write-through target lives in a folder such as /dev: keep the temporary elsewhere.
    folder = None if through else dest.parent
    fd, tmp = tempfile.mkstemp(prefix=f".{dest.name}.", suffix=dest.suffix, dir=folder)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        with naming_os_errors(path):
            yield tmp_path
            if through:
                with open(tmp_path, "rb") as src, open(dest, "wb") as out:
                    shutil.copyfileobj(src, out)
                tmp_path.unlink()
                return
            with deferred_interrupt():
                with open(tmp_path, "rb+") as fh:
                    fh.flush()
                    os.fsync(fh.fileno())
                # mkstemp creates the file owner-only (0600): give it the mode of the file it
                # replaces, or the mode a plain open() would.
                os.chmod(tmp_path, stat.S_IMODE(mode) if mode is not None else 0o666 & ~_umask())
                os.replace(tmp_path, dest)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()
        raise


@contextlib.contextmanager
def deferred_interrupt() -> Iterator[None]:
    """Hold Ctrl-C (SIGINT) back until the block is done, then raise it.

    Wraps the step that makes a result visible (a rename, a swap of folders), so that an
    interrupt lands before or after it, never in the middle: the destination then holds
    the old content or the new, whole. SIGTERM is held too where a Python handler is set
    for it (``mtmc`` sets one), and that handler is then called. Outside the main thread
    (where signal handlers cannot be set) the block runs as it is.

    Raises
    ------
    KeyboardInterrupt
        After the block, if Ctrl-C was pressed during it; also where the block then
        failed (the signal stopped what it waited on), in place of its error.

    Examples
    --------
    >>> import os, signal
    >>> try:
    ...     with deferred_interrupt():
    ...         os.kill(os.getpid(), signal.SIGINT)
    ...         print("the block ran to its end")
    ... except KeyboardInterrupt:
    ...     print("interrupted after it")
    the block ran to its end
    interrupted after it
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    seen: list[int] = []
    held = [signal.SIGINT]
    if callable(signal.getsignal(signal.SIGTERM)):
        held.append(signal.SIGTERM)
    previous = {s: signal.signal(s, lambda signum, _frame: seen.append(signum)) for s in held}
    try:
        yield
    except Exception:
        # a block that fails after the signal failed by it: Ctrl-C in a terminal reaches
        # the whole process group, and a Dask worker it stopped fails the cluster's
        # start; the user asked to stop, and that is what is reported
        if not seen:
            raise
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    if seen:
        handler = previous[signal.Signals(seen[0])]
        if seen[0] == signal.SIGTERM and callable(handler):
            handler(seen[0], None)
        raise KeyboardInterrupt


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _resolve(dest: Path) -> Path:
    """The file a write to ``dest`` lands in: symbolic links followed, the folder checked."""
    if dest.is_symlink():
        dest = Path(os.path.realpath(dest))
    if not dest.parent.is_dir():
        raise FileNotFoundError(f"{dest}: the folder {dest.parent} does not exist")
    return dest


def _replaceable(dest: Path) -> bool:
    """Whether a link, FIFO or device stands at ``dest`` (which a rename replaces)."""
    try:
        mode = os.lstat(dest).st_mode
    except FileNotFoundError:
        return False
    return stat.S_ISLNK(mode) or stat.S_ISFIFO(mode) or stat.S_ISCHR(mode)


def _destination_mode(dest: Path) -> int | None:
    """``st_mode`` of what stands at ``dest`` (None if nothing); refuse what cannot be written."""
    try:
        mode = os.stat(dest).st_mode
    except FileNotFoundError:
        return None
    if stat.S_ISDIR(mode):
        raise IsADirectoryError(f"{dest}: is a folder, expected a file name")
    if not (stat.S_ISREG(mode) or stat.S_ISFIFO(mode) or stat.S_ISCHR(mode)):
        kind = "a block device" if stat.S_ISBLK(mode) else "a socket or special file"
        raise PermissionError(
            f"{dest}: is {kind}; mtmc writes only files, pipes and character devices"
        )
    return mode


def write_text_atomic(path: str | os.PathLike[str], text: str, *, follow: bool = True) -> Path:
    """Write ``text`` (UTF-8, newlines as given) to ``path`` atomically and return the path.

    ``follow=False`` replaces a link, FIFO or device at ``path`` (:func:`atomic_path`).
    """
    with (
        atomic_path(path, follow=follow) as tmp,
        open(tmp, "w", encoding="utf-8", newline="") as fh,
    ):
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


def decode_utf8(data: bytes, file: str) -> str:
    r"""The text of a file that must be UTF-8, or a :class:`ParseError` at the first bad byte.

    Every file mtmc reads is decoded here. A UTF-8 byte order mark at the start is accepted
    (and dropped); UTF-16 text (its byte order mark) is named as such.

    Parameters
    ----------
    data : bytes
        The file's content.
    file : str
        Its name, for the message.

    Returns
    -------
    str
        The text.

    Raises
    ------
    ParseError
        Naming the file, the line and column of the first byte that is not UTF-8.

    Examples
    --------
    >>> decode_utf8(b"a = 1\nb = \xff", "g.toml")
    Traceback (most recent call last):
    ...
    mtmc.errors.ParseError: g.toml:2:5: not UTF-8 text (byte 0xff); expected UTF-8
    >>> decode_utf8(b"\xef\xbb\xbfa = 1", "g.toml")
    'a = 1'
    """
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        msg = "UTF-16 text (byte order mark at the start); expected UTF-8"
        raise ParseError(msg, file=file, line=1, column=1)
    try:
        return data.decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError as exc:
        head = data[: exc.start]
        line = head.count(b"\n") + 1
        column = exc.start - (head.rfind(b"\n") + 1) + 1
        raise ParseError(
            f"not UTF-8 text (byte 0x{data[exc.start]:02x}); expected UTF-8",
            file=file,
            line=line,
            column=column,
        ) from None


#: How deep JSON that mtmc reads may nest (a result's deepest table is some six levels).
JSON_MAX_DEPTH = 64
#: The most digits of a JSON integer mtmc reads (a 128-bit seed has 39).
JSON_MAX_DIGITS = 40


def _json_int(text: str) -> int:
    digits = len(text.lstrip("-"))
    if digits > JSON_MAX_DIGITS:
        raise ValueError(f"an integer of {digits} digits (at most {JSON_MAX_DIGITS})")
    return int(text)


def _json_float(text: str) -> float:
    x = float(text)
    if not math.isfinite(x):
        raise ValueError(f"{text} is beyond the largest number (about 1.8e308)")
    return x


def _json_constant(name: str) -> float:
    raise ValueError(f"{name} is not JSON")


def loads_json(text: str, file: str, *, max_depth: int = JSON_MAX_DEPTH) -> Any:
    """JSON text read within limits: a clear :class:`ParseError` for what would break a reader.

    Every JSON document mtmc reads from outside (a result folder, a request to the
    workbench) is read here: not JSON, nested deeper than ``max_depth`` arrays and
    objects, an integer of more than :data:`JSON_MAX_DIGITS` digits, a number beyond
    the largest float (``1e400``, which Python would read as infinite), and the words
    ``NaN``, ``Infinity`` and ``-Infinity`` (which Python writes and JSON does not know)
    are each one message, never a ``RecursionError`` or a ``ValueError`` of the parser.

    Parameters
    ----------
    text : str
        The JSON text.
    file : str
        Its name, for the message.
    max_depth : int
        The deepest nesting of arrays and objects accepted.

    Returns
    -------
    Any
        The value.

    Raises
    ------
    ParseError
        Naming the file (and the line, where the parser gives one).

    Examples
    --------
    >>> loads_json('{"a": [1, 2.5]}', "r.json")
    {'a': [1, 2.5]}
    >>> loads_json("[" * 100 + "]" * 100, "r.json")
    Traceback (most recent call last):
    ...
    mtmc.errors.ParseError: r.json: not JSON: nested deeper than 64 arrays and objects
    """
    import json

    deep = f"not JSON: nested deeper than {max_depth} arrays and objects"
    try:
        value = json.loads(
            text, parse_int=_json_int, parse_float=_json_float, parse_constant=_json_constant
        )
    except json.JSONDecodeError as exc:
        raise ParseError(f"not JSON: {exc.msg}", file=file, line=exc.lineno) from None
    except ValueError as exc:
        raise ParseError(f"not JSON: {exc}", file=file) from None
    except RecursionError:
        raise ParseError(deep, file=file) from None
    level = [value]
    for _ in range(max_depth):  # breadth first, one level of nesting at a time
        level = [
            x
            for v in level
            if isinstance(v, dict | list)
            for x in (v.values() if isinstance(v, dict) else v)
            if isinstance(x, dict | list)
        ]
        if not level:
            return value
    raise ParseError(deep, file=file)
