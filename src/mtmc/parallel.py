"""Run independent blocks of Monte Carlo trials, serially or on a local pool.

The Monte Carlo engine (:mod:`mtmc.uncertainty.montecarlo`) cuts a run into blocks of
trials whose random numbers depend only on the seed and the trial indices (see
:mod:`mtmc.uncertainty.sampling`), so the blocks can be evaluated anywhere, in any order,
and the results are put back in trial order. This module is the one place that decides
*where* they are evaluated:

* ``workers=1``: in this process, one block after the other;
* ``executor="thread"``: a thread pool (NumPy releases the GIL in its array loops and in
  its random-number fills, so threads scale for large blocks);
* ``executor="process"``: a process pool (the model must be picklable: a module-level
  function, not a lambda);
* any :class:`concurrent.futures.Executor` given by the caller, e.g. a Dask
  ``distributed`` client's executor, for a cluster.

Whichever is used, the numbers are the same.

Examples
--------
>>> list(map_blocks(abs, [-1, -2, 3], workers=2))
[1, 2, 3]
"""

from __future__ import annotations

import concurrent.futures as cf
import pickle
from collections.abc import Callable, Iterable, Iterator
from typing import Literal, TypeVar

from mtmc.errors import InputError

__all__ = ["ExecutorKind", "map_blocks"]

T = TypeVar("T")
R = TypeVar("R")
ExecutorKind = Literal["thread", "process"]


def map_blocks(
    fn: Callable[[T], R],
    tasks: Iterable[T],
    *,
    workers: int = 1,
    executor: ExecutorKind | cf.Executor = "thread",
) -> Iterator[R]:
    """Apply ``fn`` to each task and yield the results in task order.

    Parameters
    ----------
    fn : callable
        A function of one task. For ``executor="process"`` it and the tasks must be
        picklable.
    tasks : iterable
        The tasks (for Monte Carlo: trial ranges with what is needed to draw them).
    workers : int, default 1
        Number of workers; ``1`` runs in this process, in order, without a pool.
    executor : {"thread", "process"} or concurrent.futures.Executor
        The kind of local pool for ``workers > 1``, or an executor to use as is
        (``workers`` is then ignored and the executor is not shut down).

    Yields
    ------
    object
        ``fn(task)`` for each task, in the order of ``tasks``.

    Raises
    ------
    InputError
        For ``workers < 1``, an unknown executor name, or (process pool) a function or
        task that cannot be pickled.
    """
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError(f"expected an integer >= 1, got {workers!r}", field="workers")
    if isinstance(executor, cf.Executor):
        yield from executor.map(fn, tasks)
        return
    if executor not in ("thread", "process"):
        raise InputError(
            f"expected 'thread', 'process' or an Executor, got {executor!r}", field="executor"
        )
    if workers == 1:
        for task in tasks:
            yield fn(task)
        return
    task_list = list(tasks)
    if executor == "process":
        try:
            pickle.dumps(fn)
            if task_list:
                pickle.dumps(task_list[0])
        except (pickle.PicklingError, AttributeError, TypeError) as exc:
            raise InputError(
                "the model cannot be sent to worker processes (it must be picklable: a "
                f"module-level function, not a lambda or a local function): {exc}",
                field="model",
            ) from None
        pool: cf.Executor = cf.ProcessPoolExecutor(max_workers=workers)
    else:
        pool = cf.ThreadPoolExecutor(max_workers=workers)
    with pool:
        yield from pool.map(fn, task_list)
