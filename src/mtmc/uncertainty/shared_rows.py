"""Kept samples written by worker processes straight into the client's arrays.

A run that keeps the samples of its outputs on worker processes (a process pool, or a
Dask cluster on this machine) would send every value back through a pipe or a socket:
763 MiB for 10⁸ trials, which on a small machine the client receives, unpickles and
copies while the workers wait for a core. Instead, the client makes its kept arrays the
mapping of one file in shared memory (``/dev/shm``, with its space reserved before the
run), and a worker that can open that file writes each block's rows at the block's
trial positions; its digest then carries no values. A worker that cannot open it (on
another machine, in another container, or where ``/dev/shm`` is absent or full) sends
its rows back as before, and the client writes them at the same positions: the arrays,
and every number of the run, are the same bits either way.

The file holds a random token in its first bytes, which a worker checks before it
writes, so a file of the same name elsewhere is never written. It is removed when the
run ends, however it ends; the arrays keep the mapping (and its memory) for as long as
they live. A file left by a process that died before removing it is removed by the next
run that makes one. (Where containers with their own process ids share one ``/dev/shm``,
a running process's file may be taken for a dead one's: its workers then find no file
and send their rows back, which changes the speed and nothing else.)
"""

from __future__ import annotations

import contextlib
import math
import mmap
import os
import secrets
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

__all__ = ["SHARED_DIR"]

#: Where the files live: a memory file system. ``None`` (or a folder that is absent)
#: turns the shared arrays off; the kept values then come back with each block's results.
SHARED_DIR: Path | None = Path("/dev/shm")

#: The file names' prefix; the creating process's id follows it.
PREFIX = "mtmc-rows-"

#: Bytes before the first array: the token, then padding to a cache line.
_HEADER = 64
_TOKEN = 32


@dataclass(frozen=True)
class SharedRowsRef:
    """What a worker needs to write rows into the shared arrays (small and picklable).

    ``layout``: for each kept output, its name, the byte offset of its array in the file
    and its values a trial. Row ``t - base`` of an array holds trial ``t``.
    """

    path: str
    token: bytes
    size: int
    base: int
    rows: int
    layout: tuple[tuple[str, int, int], ...]

    @contextlib.contextmanager
    def writer(self) -> Iterator[RowWriter | None]:
        """The arrays mapped in this process, or ``None`` where the file is not the run's."""
        try:
            fd = os.open(self.path, os.O_RDWR)
        except OSError:
            yield None
            return
        try:
            if os.fstat(fd).st_size != self.size:
                yield None
                return
            mm = mmap.mmap(fd, self.size)
        finally:
            os.close(fd)
        try:
            if mm[:_TOKEN] != self.token:
                yield None
                return
            w = RowWriter(mm, self)
            try:
                yield w
            finally:
                w.arrays.clear()
        finally:
            # unmapped now, or when the last view goes (a sampling profiler, as Dask's
            # workers run, may hold a frame with a view for a moment)
            with contextlib.suppress(BufferError):
                mm.close()


class RowWriter:
    """The shared arrays of a run, as mapped in a worker."""

    def __init__(self, mm: mmap.mmap, ref: SharedRowsRef) -> None:
        self.base = ref.base
        self.arrays = _views(mm, ref)

    def write(self, start: int, outs: Mapping[str, NDArray[np.float64]]) -> None:
        """Write every row of the kept outputs of trials ``start..``, at their positions."""
        for name, arr in self.arrays.items():
            value = outs[name]
            m = value.shape[0]
            arr[start - self.base : start - self.base + m] = value.reshape(m, -1)


def _views(mm: mmap.mmap, ref: SharedRowsRef) -> dict[str, NDArray[np.float64]]:
    """The ``(rows, values a trial)`` float64 arrays of the mapping, by output."""
    return {
        name: np.frombuffer(mm, dtype=np.float64, count=ref.rows * width, offset=offset).reshape(
            ref.rows, width
        )
        for name, offset, width in ref.layout
    }


class SharedRows:
    """The kept arrays of a run as one shared-memory file, made by the client.

    ``arrays`` are ``(rows, *shape)`` float64 views of the mapping; they stay valid after
    :meth:`close`, which removes the file's name.
    """

    def __init__(
        self, path: Path, mm: mmap.mmap, ref: SharedRowsRef, shapes: Mapping[str, tuple[int, ...]]
    ) -> None:
        self.path, self.ref = path, ref
        self.arrays = {
            name: a.reshape(ref.rows, *shapes[name]) for name, a in _views(mm, ref).items()
        }

    @classmethod
    def create(
        cls, rows: int, shapes: Mapping[str, tuple[int, ...]], base: int
    ) -> SharedRows | None:
        """Shared ``(rows, *shape)`` arrays, or ``None`` where none can be made.

        ``shapes``: each kept output's shape of one trial; row ``t - base`` is trial ``t``.

        The file's space is reserved at once (``posix_fallocate``), so that a worker never
        writes into a full memory file system.
        """
        folder = SHARED_DIR
        if folder is None or not hasattr(os, "posix_fallocate") or not folder.is_dir():
            return None
        _remove_stale(folder)
        layout = []
        offset = _HEADER
        for name, shape in shapes.items():
            width = max(1, math.prod(shape))
            layout.append((name, offset, width))
            offset += -(-8 * rows * width // _HEADER) * _HEADER
        size = max(offset, _HEADER + 8)
        token = secrets.token_bytes(_TOKEN)
        path = folder / f"{PREFIX}{os.getpid()}-{secrets.token_hex(8)}"
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o600)
        except OSError:
            return None
        try:
            os.posix_fallocate(fd, 0, size)
            mm = mmap.mmap(fd, size)
        except (OSError, ValueError):
            os.close(fd)
            with contextlib.suppress(OSError):
                path.unlink()
            return None
        os.close(fd)
        mm[:_TOKEN] = token
        ref = SharedRowsRef(str(path), token, size, base, rows, tuple(layout))
        return cls(path, mm, ref, shapes)

    def close(self) -> None:
        """Remove the file's name; the mapping lives on in :attr:`arrays`."""
        with contextlib.suppress(OSError):
            self.path.unlink()


def _remove_stale(folder: Path) -> None:
    """Remove the files of processes that no longer run (killed before their clean-up)."""
    try:
        names = [p for p in folder.iterdir() if p.name.startswith(PREFIX)]
    except OSError:
        return
    for p in names:
        pid = p.name[len(PREFIX) :].split("-", 1)[0]
        if not pid.isdigit() or int(pid) == os.getpid():
            continue
        try:
            os.kill(int(pid), 0)
        except ProcessLookupError:
            with contextlib.suppress(OSError):
                p.unlink()
        except OSError:
            continue
