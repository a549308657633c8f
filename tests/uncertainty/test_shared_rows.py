"""Kept samples written by worker processes into the client's shared arrays.

The reference is the same run in one process: every kept value, the non-finite trials
left out, the same bits, whether the workers wrote the rows themselves, sent them back,
or some of each.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import os
import pickle

import numpy as np
import pytest

from mtmc.uncertainty import shared_rows
from mtmc.uncertainty.montecarlo import monte_carlo
from mtmc.uncertainty.shared_rows import SharedRows

INPUTS = {"x": "normal(1, 0.1)", "y": "uniform(-1, 1)"}


def model(x, y):
    return {"sum": x + y, "pair": np.stack([x * y, np.exp(y)], axis=1)}


def holes(x, y):
    """Non-finite in about 1 % of the trials, in both outputs."""
    s = np.where(y > 0.98, np.nan, x + y)
    return {"sum": s, "pair": np.stack([x * y, s], axis=1)}


class _Pool(cf.Executor):
    """An executor of this process's threads that is not a thread pool to the engine."""

    def __init__(self) -> None:
        self.pool = cf.ThreadPoolExecutor(2)

    def submit(self, fn, /, *args, **kwargs):
        return self.pool.submit(fn, *args, **kwargs)

    def shutdown(self, wait=True, *, cancel_futures=False):
        self.pool.shutdown(wait, cancel_futures=cancel_futures)


@pytest.fixture
def folder(tmp_path, monkeypatch):
    monkeypatch.setattr(shared_rows, "SHARED_DIR", tmp_path)
    return tmp_path


def _root(a):
    while isinstance(a, np.ndarray) and a.base is not None:
        a = a.base
    return a


def _same(a, b):
    for n in ("sum", "pair"):
        assert a[n].samples.tobytes() == b[n].samples.tobytes()
        assert a[n].samples.shape == b[n].samples.shape
    assert a["sum"].omitted == b["sum"].omitted


@pytest.mark.parametrize("fn", [model, holes])
def test_process_workers_write_the_rows_the_same_bits(fn, folder):
    kw = {"trials": 70_000, "seed": 4, "nan_policy": "omit", "block_size": 8192}
    one = monte_carlo(fn, INPUTS, **kw)
    got = monte_carlo(fn, INPUTS, workers=2, executor="process", **kw)
    _same(one, got)
    if fn is holes:
        assert 0 < one["sum"].omitted < 2000
    else:
        assert isinstance(_root(got["sum"].samples), memoryview)  # the shared mapping
    assert list(folder.iterdir()) == []  # its name removed once the run ended


@pytest.mark.usefixtures("folder")
def test_rows_sent_back_or_written_mix_to_the_same_bits(monkeypatch):
    """Workers that cannot reach the file send their rows back, placed at the same trials."""
    plain = shared_rows.SharedRowsRef.writer
    calls = iter(range(10**6))

    @contextlib.contextmanager
    def every_other(self):
        if next(calls) % 2:
            yield None
        else:
            with plain(self) as w:
                yield w

    monkeypatch.setattr(shared_rows.SharedRowsRef, "writer", every_other)
    kw = {"trials": 50_000, "seed": 9, "nan_policy": "omit", "block_size": 4096}
    one = monte_carlo(holes, INPUTS, **kw)
    with _Pool() as pool:
        got = monte_carlo(holes, INPUTS, executor=pool, **kw)
    assert next(calls) > 4  # both kinds of task ran
    _same(one, got)


def test_without_shared_memory_the_rows_come_back(monkeypatch):
    monkeypatch.setattr(shared_rows, "SHARED_DIR", None)
    kw = {"trials": 30_000, "seed": 2, "nan_policy": "omit"}
    one = monte_carlo(holes, INPUTS, **kw)
    got = monte_carlo(holes, INPUTS, workers=2, executor="process", **kw)
    _same(one, got)
    assert not isinstance(_root(got["sum"].samples), memoryview)


def test_a_full_memory_file_system_gives_no_shared_arrays(folder, monkeypatch):
    def full(*_):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "posix_fallocate", full)
    assert SharedRows.create(1000, {"y": ()}, 0) is None
    assert list(folder.iterdir()) == []


def test_a_worker_writes_only_into_the_runs_own_file(folder):
    shared = SharedRows.create(10, {"y": (), "v": (3,)}, 100)
    assert shared is not None
    assert shared.arrays["y"].shape == (10,)
    assert shared.arrays["v"].shape == (10, 3)
    ref = pickle.loads(pickle.dumps(shared.ref))
    with ref.writer() as w:
        assert w is not None
        w.write(104, {"y": np.array([1.0, 2.0]), "v": np.ones((2, 3))})
    np.testing.assert_array_equal(shared.arrays["y"][4:6], [1.0, 2.0])
    np.testing.assert_array_equal(shared.arrays["v"][4:6], np.ones((2, 3)))
    for other in (
        shared_rows.SharedRowsRef(ref.path, b"x" * len(ref.token), *_rest(ref)),  # token
        shared_rows.SharedRowsRef(ref.path + "-gone", ref.token, *_rest(ref)),  # no file
    ):
        with other.writer() as w:
            assert w is None
    wrong_size = shared_rows.SharedRowsRef(
        ref.path, ref.token, ref.size + 64, ref.base, ref.rows, ref.layout
    )
    with wrong_size.writer() as w:
        assert w is None
    shared.close()
    assert list(folder.iterdir()) == []
    shared.arrays["y"][0] = 7.0  # the mapping outlives the name
    assert shared.arrays["y"][0] == 7.0


@pytest.mark.usefixtures("folder")
def test_a_view_held_elsewhere_does_not_fail_the_task():
    """A sampling profiler (Dask's workers run one) may hold a frame with a view."""
    shared = SharedRows.create(4, {"y": ()}, 0)
    assert shared is not None
    with shared.ref.writer() as w:
        assert w is not None
        held = w.arrays["y"]
        w.write(0, {"y": np.arange(4.0)})
    held[0] = 5.0  # still mapped: unmapped when the last view goes
    np.testing.assert_array_equal(shared.arrays["y"], [5.0, 1.0, 2.0, 3.0])
    shared.close()


def _rest(ref):
    return ref.size, ref.base, ref.rows, ref.layout


def test_files_of_dead_processes_are_removed_and_others_kept(folder):
    gone = 2**22 + 12345  # above the kernel's largest process id
    stale = folder / f"{shared_rows.PREFIX}{gone}-abcd"
    alive = folder / f"{shared_rows.PREFIX}1-abcd"  # init always runs
    other = folder / "unrelated"
    for p in (stale, alive, other):
        p.write_bytes(b"0")
    shared = SharedRows.create(5, {"y": ()}, 0)
    assert shared is not None
    assert not stale.exists()
    assert alive.exists()
    assert other.exists()
    shared.close()


def _fails(x, **_):
    if len(x) > 1:  # every block on the workers (the client probes one trial)
        raise RuntimeError("the model failed")
    return x


def test_a_failed_run_leaves_no_file(folder):
    with pytest.raises(RuntimeError, match="the model failed"):
        monte_carlo(_fails, INPUTS, trials=40_000, seed=1, workers=2, executor="process")
    assert list(folder.iterdir()) == []
