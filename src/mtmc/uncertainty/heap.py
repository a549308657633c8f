"""The C heap of a Monte Carlo run: freed blocks kept for the next block (glibc).

A run evaluates its model block after block, and each block allocates and frees the
same arrays again (the drawn inputs, the model's temporaries, the moments). With
glibc's default ``malloc`` an array of 128 KiB or more (16 384 float64 values: one
input of one seed block) is first mapped afresh with ``mmap``, and later, once the
adaptive threshold has risen, taken from the heap, whose free top is returned to the
system (``M_TRIM_THRESHOLD``, twice the largest array freed so far) whenever it grows
past that size, typically at the end of every block. Each new block then page-faults
its memory in and has the kernel zero it: on the graph ``examples/graphs/axis_c.toml``
at 10⁶ trials 66 000–100 000 page faults, 0.16–0.23 s of system time against 0.44–0.55
s of computation.

:func:`keep_heap` sets the two thresholds that mtmc also gives its Dask worker processes
(:data:`mtmc.parallel.WORKER_MALLOC_ENV`): arrays up to 32 MiB come from the heap and
up to 256 MiB of free heap is kept, so the blocks of a run reuse the same memory. On a
fresh process (best of five, 2 cores) it takes the run of ``axis_c.toml`` at 10⁶ trials
from 0.50 s to 0.36 s of wall time (75 000 page faults to 1 700), and a three-input
expression at 2·10⁶ trials from 0.099 s to 0.068 s.

The setting holds for the whole process and glibc cannot undo it (once set, its adaptive
thresholds stay off), so no library call makes it: the ``mtmc`` command calls
:func:`keep_heap` when one of its commands runs, the process being its own, and a
program that runs Monte Carlo often may call it once itself. It does
nothing where the C library is not glibc, where either threshold was set in the
environment the process started with (``MALLOC_MMAP_THRESHOLD_``,
``MALLOC_TRIM_THRESHOLD_``, ``MALLOC_TOP_PAD_``; glibc reads them once, at start, so a
variable put into ``os.environ`` later, as Dask's nanny does in the process that starts a
``LocalCluster``, has set nothing and does not count), or where ``MTMC_HEAP=system``
asks to leave the allocator as it is. The cost: a process that has called it
keeps up to 256 MiB of freed memory for its next arrays instead of returning it to the
system. No number of a run depends on it.
"""

from __future__ import annotations

import ctypes
import os
import platform

__all__ = ["HEAP_SETTINGS", "keep_heap"]

#: ``mallopt`` parameters (glibc ``malloc.h``) and the values :func:`keep_heap` sets.
HEAP_SETTINGS: dict[str, tuple[int, int]] = {
    "M_MMAP_THRESHOLD": (-3, 32 * 2**20),
    "M_TRIM_THRESHOLD": (-1, 256 * 2**20),
}

_ENV = ("MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_", "MALLOC_TOP_PAD_")

_done: list[bool] = []


def _start_environment() -> set[str]:
    """The names of the variables the process started with, as glibc saw them.

    ``/proc/self/environ`` where there is one (Linux), else ``os.environ``.
    """
    try:
        with open("/proc/self/environ", "rb") as f:
            raw = f.read()
    except OSError:  # pragma: no cover - not Linux
        return set(os.environ)
    return {item.split(b"=", 1)[0].decode(errors="replace") for item in raw.split(b"\0") if item}


def keep_heap() -> bool:
    """Keep freed heap memory for the next block of a run (once per process, glibc only).

    Returns
    -------
    bool
        Whether this process's allocator runs with :data:`HEAP_SETTINGS` (set now or by
        an earlier call); False where it was left as it is (see the module notes).
    """
    if _done:
        return _done[0]
    ok = False
    if (
        os.environ.get("MTMC_HEAP", "") != "system"
        and not any(k in _start_environment() for k in _ENV)
        and platform.libc_ver()[0] == "glibc"
    ):
        try:
            mallopt = ctypes.CDLL(None).mallopt
            ok = all(mallopt(param, value) == 1 for param, value in HEAP_SETTINGS.values())
        except (OSError, AttributeError):  # pragma: no cover - no mallopt to call
            ok = False
    _done.append(ok)
    return ok
