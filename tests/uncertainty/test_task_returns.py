"""What a task of a pool or a cluster hands back, and that it does not change a number.

A run on workers cuts its evaluation blocks into a few tasks per worker; a task that
holds a whole group of seed blocks merges their quantile sketches where it ran. What
comes back to the merging process is then a fraction of a byte per trial for an output
whose samples are not kept, and the run is the same bits as in one process.
"""

from __future__ import annotations

import concurrent.futures as cf
import pickle

import numpy as np
import pytest

from mtmc.uncertainty import monte_carlo
from mtmc.uncertainty import montecarlo as mc_module
from mtmc.uncertainty.sampling import SEED_BLOCK_SIZE

INPUTS = {"a": "normal(0, 1)", "b": "uniform(-1, 1)"}
GROUP = mc_module.SKETCH_GROUP * SEED_BLOCK_SIZE  # trials of a sketch group: 2²⁰

#: Bytes a task may send back per trial of an output neither kept nor wide, when the task
#: holds whole sketch groups: the group's sketch (about 17 000 values of 8 bytes for 2²⁰
#: trials, 0.14 bytes a trial measured) and the seed blocks' moments. The values
#: themselves would be 8 bytes a trial.
BYTES_PER_TRIAL = 0.5


def hypot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.hypot(a, b)


class Recording(cf.ThreadPoolExecutor):
    """A thread pool that records the pickled size of each task's result."""

    def __init__(self) -> None:
        super().__init__(max_workers=2)
        self.sent: list[tuple[int, int]] = []  # (trials, bytes)

    def map(self, fn, *iterables, **_):  # type: ignore[override]
        (tasks,) = iterables
        tasks = list(tasks)
        for task, result in zip(tasks, super().map(fn, tasks), strict=True):
            self.sent.append((task[-1][1] - task[0][0], len(pickle.dumps(result))))
            yield result


@pytest.fixture(scope="module")
def reference():
    return monte_carlo(hypot, INPUTS, trials=5 * GROUP + 12_345, seed=4, keep=False, sketch=True)


def test_a_task_of_whole_sketch_groups_sends_back_a_fraction_of_a_byte_a_trial(reference):
    pool = Recording()
    r = monte_carlo(
        hypot, INPUTS, trials=5 * GROUP + 12_345, seed=4, keep=False, sketch=True, executor=pool
    )
    pool.shutdown()
    # the first group's first block ran in this process and the run ends 12 345 trials
    # into its last group: the tasks between hold whole groups
    whole = [(trials, sent) for trials, sent in pool.sent if trials >= GROUP]
    assert len(whole) >= 4
    for trials, sent in whole:
        assert sent <= BYTES_PER_TRIAL * trials, (trials, sent)
    # and the same bits as one process
    assert r.coverage_interval(0.95) == reference.coverage_interval(0.95)
    assert r.coverage_interval(0.95, "shortest") == reference.coverage_interval(0.95, "shortest")
    assert r.rank_error == reference.rank_error
    assert r.u == reference.u


@pytest.mark.parametrize(
    "options",
    [{"workers": 2, "block_size": 10_000}, {"workers": 3, "executor": "process"}],
)
def test_sketch_groups_are_the_same_bits_on_any_workers(reference, options):
    r = monte_carlo(
        hypot, INPUTS, trials=5 * GROUP + 12_345, seed=4, keep=False, sketch=True, **options
    )
    assert r.coverage_interval(0.95) == reference.coverage_interval(0.95)
    assert r.coverage_interval(0.95, "shortest") == reference.coverage_interval(0.95, "shortest")
    assert r.rank_error == reference.rank_error


def test_tasks_are_few_per_worker():
    # 1526 evaluation blocks of 10⁸ trials on 2 workers: 8 tasks a worker, not 1526
    assert mc_module._blocks_per_task(1526, 2, 8 * 65536) == 95
    # at most TASK_BYTES of values to send back a task
    assert mc_module._blocks_per_task(1526, 2, 8 * 65536 * 1000) == 1
