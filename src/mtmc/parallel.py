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
* ``executor="dask"``: a Dask cluster (the optional extra ``mtmc[distributed]``):
  with ``scheduler=None`` a :class:`distributed.LocalCluster` of ``workers`` worker
  processes started for the call and closed after it (started and closed whole: a
  Ctrl-C or SIGTERM meanwhile waits for it; its scratch files in a temporary folder
  removed with it; Dask's warnings off; its workers deaf to Ctrl-C, which this process
  acts on by closing them); with ``scheduler`` a running
  cluster, by the address of its scheduler (``"tcp://host:8786"``) or a
  :class:`distributed.Client`. The function (the model and what it was built from) is
  sent to every worker once; each task (a few blocks of trials) is submitted with
  ``pure=False`` a few tasks ahead per worker; a task lost with its worker is computed
  again by the scheduler, and gives the same numbers. :func:`local_cluster`
  starts such a cluster to keep across many runs;
* any :class:`concurrent.futures.Executor` given by the caller.

Whichever is used, the numbers are the same: the random numbers of a block depend only
on the seed and the trial indices, and the blocks' results are merged in trial order.

Blocks are the unit of parallelism, so the BLAS inside a block runs on one thread
(:func:`one_blas_thread`): in this process for the time of the map, in a pool's or a
Dask cluster's worker for the time of each task; the BLAS setting of the process is
restored after it, so what a program computes outside Monte Carlo blocks keeps the
user's setting. A block's model multiplies thin matrices (the artefact's 45 products
``(m·R, 90) @ (90, 3)`` a block, the batched solves of a verification) for which
threaded OpenBLAS costs more in waking and synchronising its threads than it gains; on
a 2-core machine under load these 45 products took 6.0 s with the default threads and
0.27 s with one (``docs/performance.md``).

Examples
--------
>>> list(map_blocks(abs, [-1, -2, 3], workers=2))
[1, 2, 3]
"""

from __future__ import annotations

import collections
import concurrent.futures as cf
import contextlib
import itertools
import pickle
import shutil
import tempfile
import threading
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal, TypeVar

from mtmc.errors import InputError

if TYPE_CHECKING:  # Dask is optional: imported by the functions that use it
    from distributed import LocalCluster

__all__ = [
    "BLAS_THREADS",
    "WORKER_CONFIG",
    "WORKER_MALLOC_ENV",
    "ExecutorKind",
    "local_cluster",
    "map_blocks",
    "planned_workers",
    "one_blas_thread",
]

T = TypeVar("T")
R = TypeVar("R")
ExecutorKind = Literal["thread", "process", "dask"]

#: Dask settings of the workers of :func:`local_cluster`: no statistical profiler (a
#: sample of the running task's stack every 10 ms) and no disk counters in the system
#: monitor. A sweep of 25 × 10⁵ trials took 1.82–1.94 s of the workers' CPU time with
#: them off against 1.90–1.99 s with Dask's defaults; idle, 0.09–0.11 s against
#: 0.16–0.21 s per 5 s.
WORKER_CONFIG: dict[str, Any] = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.system-monitor.disk": False,
}

#: Blocks submitted ahead per Dask worker (bounds the memory of results in flight).
DASK_AHEAD: int = 4

#: Blocks submitted ahead per worker of a local thread or process pool: the results
#: waiting to be merged in order are at most this many per worker, whatever the number
#: of blocks (all submitted at once, the finished blocks of a run of 2·10⁸ trials piled
#: up in memory while the first ones were merged).
POOL_AHEAD: int = 4


#: glibc ``malloc`` settings for Dask worker processes. Dask's nanny sets
#: ``MALLOC_TRIM_THRESHOLD_=65536`` in its workers, which also switches off glibc's
#: adaptive mmap threshold: every array over 128 kB is then mapped afresh and its pages
#: faulted in and zeroed on each block, and a block of 2^20 trials took 1.9 times as long
#: in a worker as in this process (0.126 s against 0.067 s). With these two settings
#: arrays up to 32 MiB are reused from the heap and at most 256 MiB of free heap is kept.
#: A worker runs its tasks in a thread other than its main one, and glibc gives such a
#: thread an arena of its own, made of heaps of at most 64 MiB that are unmapped once
#: empty: a verification's blocks (arrays of up to 33 MB) then faulted in 32 000–42 000
#: pages a 2000 trials against 6 100 in a main thread, and ran 10 % slower (3.6–3.7
#: against 3.2–3.3 s). One arena (``MALLOC_ARENA_MAX=1``; a worker runs one task at a
#: time) keeps every thread in the main heap: 5 600–6 100 pages, 3.3–3.4 s.
WORKER_MALLOC_ENV: dict[str, str] = {
    "MALLOC_MMAP_THRESHOLD_": str(32 * 2**20),
    "MALLOC_TRIM_THRESHOLD_": str(256 * 2**20),
    "MALLOC_ARENA_MAX": "1",
}


#: BLAS threads inside a block of trials (:func:`one_blas_thread`); None leaves the
#: process's setting (a model of a few large matrix products a block may gain from
#: threads where the blocks run one at a time).
BLAS_THREADS: int | None = 1


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """Run the body with the BLAS libraries of this process on :data:`BLAS_THREADS` threads.

    The libraries loaded (NumPy's and SciPy's OpenBLAS, MKL, BLIS) are found by
    ``threadpoolctl``; their thread counts are set for the body and restored after it,
    whatever happens in it. Setting and restoring take about 0.8 ms, paid by the
    outermost of nested bodies only (a task that runs a Monte Carlo that runs its
    blocks: the setting is the process's, so an inner body finds it made). A library
    that the body loads for the first time keeps its own setting.

    Yields
    ------
    None
    """
    if BLAS_THREADS is None:
        yield
        return
    global _blas_depth, _blas_limits
    with _blas_lock:  # a second thread waits until the first has set the threads
        if _blas_depth == 0:
            from threadpoolctl import threadpool_limits

            _blas_limits = threadpool_limits(limits=BLAS_THREADS, user_api="blas")
        _blas_depth += 1
    try:
        yield
    finally:
        with _blas_lock:
            _blas_depth -= 1
            if _blas_depth == 0 and _blas_limits is not None:
                _blas_limits.restore_original_limits()
                _blas_limits = None


#: Bodies of :func:`one_blas_thread` open in this process, and the setting they restore.
_blas_lock = threading.Lock()
_blas_depth = 0
_blas_limits: Any = None


@dataclass(frozen=True)
class _OneBlasThread:
    """``fn`` run with :func:`one_blas_thread` (a task in a worker process); picklable."""

    fn: Callable[[Any], Any]

    def __call__(self, task: Any) -> Any:
        with one_blas_thread():
            return self.fn(task)


def _import_distributed() -> Any:
    try:
        import distributed
    except ImportError:
        raise InputError(
            "executor='dask' needs Dask's distributed scheduler: pip install 'mtmc[distributed]'",
            field="executor",
        ) from None
    return distributed


def local_cluster(workers: int = 2, **kwargs: Any) -> LocalCluster:
    """Start a Dask ``LocalCluster`` of worker processes set up for Monte Carlo blocks.

    One single-threaded worker process per core, on the loopback interface, dashboard
    on a free port, the workers' allocator set by :data:`WORKER_MALLOC_ENV` (variables
    already in the environment win), mtmc's modules imported by each worker as it
    starts (``mtmc._warm``, after any preload of the Dask configuration), and the
    workers' own sampling of their stacks and of the disks off (:data:`WORKER_CONFIG`:
    3–4 % of a worker's CPU time on a sweep; Dask's dashboard then shows no profile).
    Keep it, and pass it (or a ``distributed.Client`` of it) as ``scheduler`` to many
    runs: its start-up (about 0.7 s) is then paid once. ``executor="dask"`` without a
    scheduler starts one of these for the call.

    Parameters
    ----------
    workers : int, default 2
        Number of worker processes.
    **kwargs
        Further keywords of ``distributed.LocalCluster`` (they override the above).

    Returns
    -------
    distributed.LocalCluster
        The running cluster; close it (or use it in a ``with`` block) when done.

    Raises
    ------
    InputError
        If Dask's distributed scheduler is not installed, or ``workers < 1``.
    """
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError(f"expected an integer >= 1, got {workers!r}", field="workers")
    distributed = _import_distributed()
    import dask

    options: dict[str, Any] = {
        "n_workers": workers,
        "threads_per_worker": 1,
        "processes": True,
        # the modules a task's model needs, imported as each worker starts (mtmc._warm)
        "preload": [*(dask.config.get("distributed.worker.preload") or []), "mtmc._warm"],
        "host": "127.0.0.1",
        "dashboard_address": ":0",
    }
    options.update(kwargs)
    env = {f"distributed.nanny.pre-spawn-environ.{k}": v for k, v in WORKER_MALLOC_ENV.items()}
    with dask.config.set({**env, **WORKER_CONFIG}), _ctrl_c_held_from_workers():
        cluster: LocalCluster = distributed.LocalCluster(**options)
    return cluster


@contextlib.contextmanager
def _ctrl_c_held_from_workers() -> Iterator[None]:
    """Processes started in the block (and the threads that start them) never see SIGINT.

    Ctrl-C in a terminal sends SIGINT to the whole process group: to this process and to
    the cluster's worker processes, which print their own ``KeyboardInterrupt`` traceback
    above the command's one-line message. The cluster is this process's to stop (it closes
    it on Ctrl-C), so SIGINT is blocked in this thread for the block: the cluster's threads,
    created here, and their worker processes inherit the blocked mask (across ``exec``)
    and keep it. This process still gets the signal: the kernel hands it to a thread that
    does not block it, or it waits, pending, until the block ends (``pthread_sigmask``);
    Python's handler runs in the main thread either way, and nothing is lost. SIGTERM is
    not blocked: the nanny stops a worker with it. Multiprocessing's resource tracker is
    started first, here: starting it unblocks SIGINT in the thread that starts it
    (``resource_tracker.ensure_running``), which would otherwise be the cluster's.
    """
    import signal
    from multiprocessing import resource_tracker

    if not hasattr(signal, "pthread_sigmask"):  # pragma: no cover - Windows
        yield
        return
    resource_tracker.ensure_running()
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def planned_workers(workers: int, executor: ExecutorKind | cf.Executor) -> int:
    """The workers a run's tasks are cut for: ``workers``, and at least 2 on Dask.

    A Dask cluster's size is not known before it is reached (``workers`` is the size of
    the cluster started for the call, 1 by default), so tasks on Dask are planned for at
    least two workers; the engine's blocks and a sweep's grid points are grouped by it.

    Examples
    --------
    >>> planned_workers(1, "dask"), planned_workers(4, "dask"), planned_workers(1, "thread")
    (2, 4, 1)
    """
    return max(workers, 2) if executor == "dask" else workers


#: Dask's log level in a cluster started for one call (:func:`_dask_client`), in this
#: process and (through :mod:`mtmc._warm`, which reads the setting ``mtmc.worker-log-level``)
#: in its workers: the run reports its own failures (a task's error, a worker lost, reach
#: the client and end the command with one line), and an interrupted run's workers would
#: otherwise log the cancelled tasks of their ending ("Async instruction ... ended with
#: CancelledError", one line a worker, at WARNING) or, under load, a heartbeat that met the
#: scheduler already closed (an ERROR with its traceback, above ``mtmc: interrupted``).
CALL_CLUSTER_LOG_LEVEL: str = "CRITICAL"


@contextlib.contextmanager
def _dask_client(scheduler: Any, workers: int) -> Iterator[Any]:
    """A ``distributed.Client`` for ``scheduler`` (or a new local cluster), closed after.

    A cluster started here is started and closed whole: Ctrl-C or SIGTERM arriving while
    it starts or closes is held until it is running or closed, then raised
    (:func:`mtmc.io.deferred_interrupt`). A start cut short leaves worker processes in
    Dask's start-up state that its close at exit then asserts on (a traceback
    ``AssertionError: Status.init`` after the command's own message), and the workers'
    scratch folders in the temporary folder. The workers keep their scratch files in a
    temporary folder of this call, removed with the cluster.
    """
    from mtmc.io import deferred_interrupt

    distributed = _import_distributed()
    if isinstance(scheduler, distributed.Client):
        yield scheduler
        return
    if scheduler is not None and (not isinstance(scheduler, str) or not scheduler):
        raise InputError(
            f"expected a scheduler address such as 'tcp://127.0.0.1:8786' or a "
            f"distributed.Client, got {scheduler!r}",
            field="scheduler",
        )
    to_close: list[Any] = []
    scratch = tempfile.mkdtemp(prefix="mtmc-dask-") if scheduler is None else None
    try:
        with deferred_interrupt():
            if scratch is None:
                try:
                    client = distributed.Client(scheduler, timeout="5s")
                except (OSError, TimeoutError) as exc:
                    raise InputError(
                        f"cannot reach the Dask scheduler at {scheduler}: {exc}",
                        field="scheduler",
                    ) from None
            else:
                import dask

                quiet = {"mtmc.worker-log-level": CALL_CLUSTER_LOG_LEVEL}
                # the scheduler's and the workers' scratch folders (dask-scratch-space)
                with dask.config.set({**quiet, "temporary-directory": scratch}):
                    cluster = local_cluster(workers, silence_logs=CALL_CLUSTER_LOG_LEVEL)
                to_close.append(cluster)
                client = distributed.Client(cluster)
            to_close.insert(0, client)
        yield client
    finally:
        with deferred_interrupt():  # a second Ctrl-C does not cut the closing short
            for obj in to_close:
                obj.close()
            if scratch is not None:
                shutil.rmtree(scratch, ignore_errors=True)


def _apply(fn: Callable[[T], R], task: T) -> R:
    """``fn(task)``: a Dask task whose function was sent to the workers once."""
    return fn(task)


def _dask_map(fn: Callable[[T], R], tasks: list[T], client: Any) -> Iterator[R]:
    """Submit ``fn(task)`` as Dask tasks a few ahead of the one awaited; yield in order.

    ``fn`` (the model with what it was built from: the operators of a verification of
    5408 points are 13 MiB) is sent to every worker once, not with every task.
    """
    ahead = DASK_AHEAD * max(1, len(client.scheduler_info().get("workers", {})))
    sent = client.scatter(fn, broadcast=True, hash=False)
    pending: list[Any] = []
    it = iter(tasks)
    try:
        for task in it:
            pending.append(client.submit(_apply, sent, task, pure=False))
            if len(pending) >= ahead:
                break
        while pending:
            fut = pending.pop(0)
            yield fut.result()
            fut.release()
            nxt = next(it, None)
            if nxt is not None:
                pending.append(client.submit(_apply, sent, nxt, pure=False))
    finally:
        sent.release()


def _pool_map(pool: cf.Executor, fn: Callable[[T], R], tasks: list[T], ahead: int) -> Iterator[R]:
    """Submit ``fn(task)`` to ``pool`` at most ``ahead`` at a time; yield in task order."""
    pending: collections.deque[cf.Future[R]] = collections.deque()
    it = iter(tasks)
    for task in itertools.islice(it, ahead):
        pending.append(pool.submit(fn, task))
    while pending:
        result = pending.popleft().result()
        for task in itertools.islice(it, 1):
            pending.append(pool.submit(fn, task))
        yield result


def map_blocks(
    fn: Callable[[T], R],
    tasks: Iterable[T],
    *,
    workers: int = 1,
    executor: ExecutorKind | cf.Executor = "thread",
    scheduler: Any = None,
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
    executor : {"thread", "process", "dask"} or concurrent.futures.Executor
        The kind of local pool for ``workers > 1``, a Dask cluster, or an executor to
        use as is (``workers`` is then ignored and the executor is not shut down).
    scheduler : str or distributed.Client, optional
        With ``executor="dask"``: the running cluster to use (its scheduler's address or
        a client, which is not closed); ``None`` starts a local cluster of ``workers``
        worker processes for this call.

    Yields
    ------
    object
        ``fn(task)`` for each task, in the order of ``tasks``.

    Raises
    ------
    InputError
        For ``workers < 1``, an unknown executor name, (process pool) a function or
        task that cannot be pickled, Dask not installed, or a scheduler that cannot be
        reached (the message names its address).
    """
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError(f"expected an integer >= 1, got {workers!r}", field="workers")
    if isinstance(executor, cf.Executor):
        # set here first, so that a task on a thread of this process restores one thread
        with one_blas_thread():
            yield from executor.map(_OneBlasThread(fn), tasks)
        return
    if executor not in ("thread", "process", "dask"):
        raise InputError(
            f"expected 'thread', 'process', 'dask' or an Executor, got {executor!r}",
            field="executor",
        )
    if scheduler is not None and executor != "dask":
        raise InputError(
            f"a scheduler ({scheduler!r}) is used with executor='dask' only", field="scheduler"
        )
    if executor == "dask":
        with _dask_client(scheduler, workers) as client:
            with one_blas_thread():  # a cluster of threads in this process shares its BLAS
                yield from _dask_map(_OneBlasThread(fn), list(tasks), client)
        return
    if workers == 1:
        with one_blas_thread():
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
        pool: cf.Executor = cf.ProcessPoolExecutor(max_workers=workers, initializer=_worker_signals)
        fn = _OneBlasThread(fn)
    else:
        pool = cf.ThreadPoolExecutor(max_workers=workers)
    try:
        with one_blas_thread():  # the threads of a pool share this process's BLAS
            yield from _pool_map(pool, fn, task_list, POOL_AHEAD * workers)
    except BaseException:
        # interrupted (Ctrl-C, SIGTERM) or closed early: no block is started any more, and
        # worker processes are stopped now rather than left to finish (or to outlive us)
        _stop(pool)
        raise
    pool.shutdown(wait=True)


def _worker_signals() -> None:
    """In a pool's worker process: SIGTERM ends it, whatever handler its parent had set."""
    import signal

    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _stop(pool: cf.Executor) -> None:
    """Shut ``pool`` down at once: queued blocks cancelled, worker processes terminated."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    for proc in processes:
        proc.terminate()
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in processes:
        proc.join(timeout=5)
        if proc.is_alive():  # pragma: no cover - a worker deaf to SIGTERM
            proc.kill()
            proc.join(timeout=5)
