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
