"""BLAS runs on one thread inside a block of trials, and the process's setting comes back.

The model reports, as its output value, the largest thread count of the BLAS libraries
loaded where it runs (this process, a pool's thread or a worker process); the test sets
two threads around the run and reads the setting again after it.
"""

from __future__ import annotations

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from mtmc.parallel import BLAS_THREADS, map_blocks
from mtmc.uncertainty import Normal, monte_carlo


def _blas_threads() -> int:
    return max(d["num_threads"] for d in threadpool_info() if d["user_api"] == "blas")


def threads_model(x: np.ndarray) -> np.ndarray:
    return np.zeros_like(x) + _blas_threads()


def _task_threads(_: int) -> int:
    return _blas_threads()


@pytest.mark.parametrize(("workers", "executor"), [(1, "thread"), (2, "thread"), (2, "process")])
def test_blocks_run_blas_on_one_thread_and_the_setting_is_restored(workers, executor):
    with threadpool_limits(limits=2, user_api="blas"):
        before = _blas_threads()
        res = monte_carlo(
            threads_model,
            {"x": Normal(0, 1)},
            trials=3 * 16_384,
            seed=1,
            workers=workers,
            executor=executor,
            keep=True,
            block_size=16_384,
        )
        after = _blas_threads()
    assert BLAS_THREADS == 1
    assert set(np.unique(res.values)) == {1.0}
    assert after == before


def test_a_map_of_tasks_and_an_error_in_a_task_restore_the_setting():
    with threadpool_limits(limits=2, user_api="blas"):
        before = _blas_threads()
        assert list(map_blocks(_task_threads, range(3))) == [1, 1, 1]
        assert _blas_threads() == before

        def fails(_: int) -> int:
            raise RuntimeError("a model error")

        with pytest.raises(RuntimeError, match="a model error"):
            list(map_blocks(fails, range(2)))
        assert _blas_threads() == before


def test_nested_bodies_set_the_threads_once_and_the_outermost_restores(monkeypatch):
    import threading

    import threadpoolctl

    from mtmc.parallel import one_blas_thread

    made = []
    plain = threadpoolctl.threadpool_limits

    def counting(*args, **kwargs):
        made.append(1)
        return plain(*args, **kwargs)

    monkeypatch.setattr(threadpoolctl, "threadpool_limits", counting)
    inside = threading.Barrier(2)

    def body():
        with one_blas_thread():
            inside.wait(timeout=10)  # both threads in their bodies at once

    with threadpool_limits(limits=2, user_api="blas"):
        with one_blas_thread(), one_blas_thread():
            with one_blas_thread():
                assert _blas_threads() == 1
            assert _blas_threads() == 1
        assert _blas_threads() == 2
        assert len(made) == 1  # set once for three nested bodies
        threads = [threading.Thread(target=body) for _ in range(2)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert _blas_threads() == 2
    assert len(made) == 2  # once for two bodies open at the same time
