"""Wide outputs that are not kept: moments by reduction blocks, memory bounded by a block.

An output of thousands of values a trial (a verification's errors at every point) is
summarised by the moments of reduction blocks of a fixed number of trials that depends on
its width alone (:func:`reduction_block_trials`), merged in trial order: the same bits
whatever the evaluation blocks or the workers, the same values as NumPy's moments of the
kept samples, and no more than one reduction block of its values waiting in memory.
"""

from __future__ import annotations

import concurrent.futures as cf
import pickle

import numpy as np
import pytest

from mtmc.uncertainty import IID, Normal, monte_carlo
from mtmc.uncertainty import montecarlo as mc_module
from mtmc.uncertainty.montecarlo import REDUCE_BYTES, reduction_block_trials
from mtmc.uncertainty.sampling import SEED_BLOCK_SIZE

WIDTH = 3000
TRIALS = 5000
INPUTS = {"e": IID(Normal(0.0, 1.0), WIDTH), "s": Normal(2.0, 0.1)}


def wide(e: np.ndarray, s: np.ndarray) -> dict[str, np.ndarray]:
    return {"comp": e * s[:, None] + np.arange(WIDTH), "y": s * s}


def test_reduction_blocks_by_width():
    assert reduction_block_trials(1) == SEED_BLOCK_SIZE
    assert reduction_block_trials(REDUCE_BYTES // (8 * SEED_BLOCK_SIZE)) == SEED_BLOCK_SIZE
    r = reduction_block_trials(WIDTH)
    assert r * WIDTH * 8 <= REDUCE_BYTES < 2 * r * WIDTH * 8
    assert SEED_BLOCK_SIZE % r == 0  # reduction blocks nest in seed blocks
    assert reduction_block_trials(10**9) == 1


@pytest.fixture(scope="module")
def reference():
    return monte_carlo(wide, INPUTS, trials=TRIALS, seed=3, keep=["y"])


@pytest.mark.parametrize(
    "options", [{"block_size": 777}, {"workers": 2, "block_size": 1000}, {"workers": 2}]
)
def test_wide_moments_are_the_same_bits_on_any_blocks_and_workers(reference, options):
    r = monte_carlo(wide, INPUTS, trials=TRIALS, seed=3, keep=["y"], **options)
    assert r["comp"].estimate_vector.tobytes() == reference["comp"].estimate_vector.tobytes()
    assert r["comp"].u_vector.tobytes() == reference["comp"].u_vector.tobytes()


def test_wide_moments_are_numpys_of_the_kept_samples(reference):
    kept = monte_carlo(wide, INPUTS, trials=TRIALS, seed=3, keep=True)
    x = kept["comp"].samples
    # merged block moments against NumPy's two-pass sums over the same values: rounding
    # of the 5000 additions of values of size up to 3000
    assert np.allclose(reference["comp"].estimate_vector, x.mean(axis=0), rtol=0, atol=1e-9)
    assert np.allclose(reference["comp"].u_vector, x.std(axis=0, ddof=1), rtol=1e-10, atol=0)


def test_values_waiting_for_a_block_are_at_most_one_reduction_block(monkeypatch):
    held = []
    real_add = mc_module._Collector.add

    def add(self, d):
        real_add(self, d)
        held.append(sum(a.nbytes for parts in self.buffer.values() for a in parts))

    monkeypatch.setattr(mc_module._Collector, "add", add)
    monte_carlo(wide, INPUTS, trials=TRIALS, seed=3, keep=["y"], block_size=333)
    assert max(held) <= reduction_block_trials(WIDTH) * WIDTH * 8


class _Recording(cf.ThreadPoolExecutor):
    """A thread pool that records the pickled size of what each task hands back."""

    def __init__(self) -> None:
        super().__init__(max_workers=2)
        self.sent = 0

    def map(self, fn, *iterables, **_):  # type: ignore[override]
        for result in super().map(fn, *iterables):
            self.sent += len(pickle.dumps(result))
            yield result


def test_a_task_reduces_the_reduction_blocks_it_holds_whole(reference, monkeypatch):
    # evaluation blocks of 777 trials never line up with the 1024-trial reduction blocks
    # of the 3000-wide output: each block comes as pieces of values, and a task that holds
    # all the pieces of a block hands back its moments (48 kB) instead of its values
    # (24 MB); only the blocks cut by a task's ends cross as values
    monkeypatch.setattr(mc_module, "TASKS_PER_WORKER", 1)
    assert reduction_block_trials(WIDTH) == 1024
    pool = _Recording()
    r = monte_carlo(wide, INPUTS, trials=TRIALS, seed=3, keep=["y"], block_size=777, executor=pool)
    pool.shutdown()
    raw = 8 * WIDTH * TRIALS
    assert pool.sent < 0.3 * raw, pool.sent / raw
    assert r["comp"].estimate_vector.tobytes() == reference["comp"].estimate_vector.tobytes()
    assert r["comp"].u_vector.tobytes() == reference["comp"].u_vector.tobytes()
