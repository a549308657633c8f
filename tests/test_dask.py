"""The engine on a real Dask cluster: two worker processes on loopback, same numbers."""

from __future__ import annotations

import os
import shutil
import signal
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from conftest import absent
from mtmc.errors import InputError
from mtmc.graph import load_graph, run_graph
from mtmc.graph.sweep import sweep_graph
from mtmc.parallel import WORKER_CONFIG, WORKER_MALLOC_ENV, local_cluster
from mtmc.uncertainty.montecarlo import monte_carlo

try:
    import distributed
except ImportError:  # the extra: pip install "mtmc[dask]" (make test installs it)
    absent("dask.distributed", 'pip install "mtmc[dask]"')

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "graphs"
INPUTS = {"x": "normal(1, 0.1)", "y": "uniform(-1, 1)"}


def model(x, y):
    return {"sum": x + y, "pair": np.stack([x * y, np.exp(y)], axis=1)}


@pytest.fixture(scope="module")
def client():
    cluster = local_cluster(2, scheduler_port=0)
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


#: the allocator variables of this process before any cluster started (they win)
_BEFORE = {k: os.environ.get(k) for k in WORKER_MALLOC_ENV}


def _worker_settings():
    import dask

    env = {k: os.environ.get(k) for k in WORKER_MALLOC_ENV}
    return env, {k: dask.config.get(k) for k in WORKER_CONFIG}


def test_local_cluster_workers_allocator_and_dask_settings(client):
    seen = client.run(_worker_settings)
    assert len(seen) == 2
    for env, config in seen.values():
        # Dask's default MALLOC_TRIM_THRESHOLD_=65536 maps every large array afresh
        for name, value in WORKER_MALLOC_ENV.items():
            assert env[name] == (_BEFORE[name] or value)
        # neither the statistical profiler nor the disk counters sample a worker
        assert config == WORKER_CONFIG
    assert int(WORKER_MALLOC_ENV["MALLOC_MMAP_THRESHOLD_"]) >= 8 * 2**20  # a 2^20-trial column
    assert all(v is False for v in WORKER_CONFIG.values())


def _sigint_blocked():
    return signal.SIGINT in signal.pthread_sigmask(signal.SIG_BLOCK, set())


@pytest.mark.skipif(not hasattr(signal, "pthread_sigmask"), reason="needs pthread_sigmask")
def test_local_cluster_workers_never_see_ctrl_c_and_this_process_still_does(client):
    # Ctrl-C in a terminal reaches the whole process group; a worker that took it printed
    # its own KeyboardInterrupt traceback (tests/test_cli_signals.py has the command)
    assert list(client.run(_sigint_blocked).values()) == [True, True]
    assert not _sigint_blocked()
    # a signal sent while the cluster starts is not lost: it reaches this process after
    from mtmc.parallel import _ctrl_c_held_from_workers

    def signal_in_the_block():
        with _ctrl_c_held_from_workers():
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)
        time.sleep(1)  # pragma: no cover - the interrupt arrives before

    with pytest.raises(KeyboardInterrupt):
        signal_in_the_block()


def _mtmc_modules():
    return sorted(m for m in sys.modules if m.startswith(("mtmc", "colorsys")))


def test_local_cluster_workers_start_with_mtmc_imported():
    """A fresh cluster's first task does not wait for the modules its model needs."""
    import dask

    with (
        dask.config.set({"distributed.worker.preload": ["colorsys"]}),  # a user's preload
        local_cluster(1) as cluster,
        distributed.Client(cluster) as c,
    ):
        (seen,) = c.run(_mtmc_modules).values()
    for m in ("colorsys", "mtmc.graph.run", "mtmc.verification.simulate", "mtmc.artefact.model"):
        assert m in seen


def test_local_cluster_rejects_a_bad_worker_count():
    with pytest.raises(InputError, match="integer >= 1"):
        local_cluster(0)


@pytest.mark.parametrize(
    ("keep", "sampling"), [(True, "random"), (False, "random"), (True, "sobol")]
)
def test_monte_carlo_on_a_cluster_is_bit_identical(client, keep, sampling):
    ref = monte_carlo(model, INPUTS, trials=100_000, seed=7, keep=keep, sampling=sampling)
    got = monte_carlo(
        model,
        INPUTS,
        trials=100_000,
        seed=7,
        keep=keep,
        sampling=sampling,
        executor="dask",
        scheduler=client,
        block_size=20_000,
    )
    for name in ref:
        np.testing.assert_array_equal(got[name].estimate_vector, ref[name].estimate_vector)
        np.testing.assert_array_equal(got[name].cov, ref[name].cov)
        if keep:
            np.testing.assert_array_equal(got[name].samples, ref[name].samples)


def test_graph_and_sweep_through_a_scheduler_address(client):
    graph = load_graph(EXAMPLES / "bcs_origin.toml")
    ref = run_graph(graph, trials=30_000, seed=3, outputs=["d_ac"])
    got = run_graph(
        graph,
        trials=30_000,
        seed=3,
        outputs=["d_ac"],
        executor="dask",
        scheduler=client.scheduler.address,
        block_size=16_384,
    )
    assert got.places["d_ac"].u == ref.places["d_ac"].u
    vary = {"probe.u_probe": [0.001, 0.002], "probe.u_axis": [0.002, 0.004]}
    a = sweep_graph(graph, vary, "d_ac", trials=500, seed=5)
    b = sweep_graph(graph, vary, "d_ac", trials=500, seed=5, executor="dask", scheduler=client)
    np.testing.assert_array_equal(a.u, b.u)


def test_a_worker_killed_mid_run_changes_nothing(client):
    def slow(x):
        time.sleep(0.05)
        return np.sin(x)

    inputs = {"x": "normal(0, 1)"}
    ref = monte_carlo(slow, inputs, trials=60 * 1000, seed=2, block_size=1000)
    pids = list(client.run(os.getpid).values())
    killed = threading.Event()

    def kill(done, _total):
        if done >= 10_000 and not killed.is_set():
            killed.set()
            os.kill(pids[0], signal.SIGKILL)

    got = monte_carlo(
        slow,
        inputs,
        trials=60 * 1000,
        seed=2,
        block_size=1000,
        executor="dask",
        scheduler=client,
        progress=kill,
    )
    assert killed.is_set()
    np.testing.assert_array_equal(got.samples, ref.samples)
    client.wait_for_workers(2, timeout=60)


def test_local_cluster_started_for_the_call():
    ref = monte_carlo(model, INPUTS, trials=40_000, seed=1, keep=False)
    got = monte_carlo(
        model,
        INPUTS,
        trials=40_000,
        seed=1,
        keep=False,
        executor="dask",
        workers=2,
        block_size=16_384,
    )
    np.testing.assert_array_equal(got["pair"].cov, ref["pair"].cov)


def test_unreachable_scheduler_is_one_line_naming_it():
    with pytest.raises(
        InputError, match=r"cannot reach the Dask scheduler at tcp://127\.0\.0\.1:9"
    ):
        monte_carlo(
            model, INPUTS, trials=1000, seed=1, executor="dask", scheduler="tcp://127.0.0.1:9"
        )


def test_without_dask_the_option_says_what_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(InputError, match=r"pip install 'mtmc\[distributed\]'"):
        monte_carlo(model, INPUTS, trials=1000, seed=1, executor="dask", workers=2)
    with pytest.raises(InputError, match="executor='dask' only"):
        monte_carlo(model, INPUTS, trials=1000, seed=1, scheduler="tcp://127.0.0.1:9")


def test_cli_runs_on_the_cluster_with_the_same_numbers(client, capsys):
    import json

    from mtmc.cli.main import main

    args = [
        "propagate",
        "a * b",
        "-i",
        "a=normal(2, 0.1)",
        "-i",
        "b=uniform(2.5, 3.5)",
        "--trials",
        "40000",
        "--seed",
        "3",
        "--json",
    ]
    assert main(args) == 0
    ref = json.loads(capsys.readouterr().out)
    assert main([*args, "--scheduler", client.scheduler.address]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["u"] == ref["u"]
    assert got["shortest"] == ref["shortest"]
    assert main([*args, "--scheduler", "tcp://127.0.0.1:9"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "tcp://127.0.0.1:9" in err[0]


def test_mtmc_run_through_a_scheduler_address(client, tmp_path):
    from mtmc.cli.main import main

    study = Path(__file__).resolve().parents[1] / "examples" / "studies" / "ball_centre.toml"
    base = ["run", str(study), "--trials", "3000", "--seed", "4", "-q"]
    assert main([*base, "-o", str(tmp_path / "here")]) == 0
    address = client.scheduler.address
    assert main([*base, "-o", str(tmp_path / "dask"), "--scheduler", address]) == 0
    here, there = (
        (tmp_path / d / "result.json").read_text(encoding="utf-8") for d in ("here", "dask")
    )
    assert here == there


def test_a_verification_study_on_the_cluster_is_bit_identical(client):
    from mtmc.study import load_study

    study = load_study(Path(__file__).resolve().parents[1] / "examples/studies/aguado2017.toml")
    here = study.run(trials=60, seed=8)
    there = study.run(trials=60, seed=8, executor="dask", scheduler=client)
    assert here.to_dict() == there.to_dict()


def test_the_dask_example_script_runs():
    import subprocess

    script = Path(__file__).resolve().parents[1] / "examples" / "python" / "sweep_on_dask.py"
    done = subprocess.run(
        [sys.executable, str(script), "300", "2"], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    assert "same numbers" in done.stdout


def test_an_artefact_study_on_the_cluster_is_bit_identical(client):
    from mtmc.study import load_study

    study = load_study(Path(__file__).resolve().parents[1] / "examples/studies/wang2022.toml")
    here = study.run(trials=300, seed=8)
    there = study.run(trials=300, seed=8, executor="dask", scheduler=client)
    assert here.to_dict() == there.to_dict()


@pytest.mark.parametrize(
    "argv",
    [
        ["verify", "simulate", "aguado2017.toml", "-n", "40"],
        ["artefact", "simulate", "wang2022.toml", "-n", "300"],
    ],
)
def test_verify_and_artefact_simulate_on_the_cluster(client, capsys, argv):
    from mtmc.cli.main import main

    argv = [*argv[:2], str(EXAMPLES.parent / "studies" / argv[2]), *argv[3:], "--json"]
    assert main([*argv, "--seed", "3"]) == 0
    here = capsys.readouterr().out
    assert main([*argv, "--seed", "3", "--scheduler", client.scheduler.address]) == 0
    assert capsys.readouterr().out == here
    assert main([*argv, "--seed", "3", "--workers", "2"]) == 0
    assert capsys.readouterr().out == here


#: What a Dask task may send back, per trial, of outputs whose samples are not kept: the
#: moments of whole reduction blocks (2 · 3000 values per 1024 trials of a 3000-wide
#: output, 47 bytes a trial) and group sketches of scalars (0.14 bytes a trial), not the
#: values (24 000 and 8 bytes a trial): at most this fraction of the values' bytes (0.23 %
#: and 0.08 % measured).
SENT_FRACTION = 0.01

WIDE = 3000


def wide_model(e, s):
    return {"comp": e * s[:, None], "y": s * s}


@pytest.fixture
def sent(monkeypatch):
    """The pickled size of each task's result, as the client receives them."""
    import pickle

    from mtmc import parallel

    sizes = []
    plain = parallel._dask_map

    def counting(fn, tasks, c):
        for result in plain(fn, tasks, c):
            sizes.append(len(pickle.dumps(result)))
            yield result

    monkeypatch.setattr(parallel, "_dask_map", counting)
    return sizes


def test_a_dask_run_sends_back_moments_not_values(client, sent):
    from mtmc.uncertainty import IID, Normal

    inputs = {"e": IID(Normal(0.0, 1.0), WIDE), "s": Normal(2.0, 0.1)}
    trials = 6000
    kw = {"trials": trials, "seed": 5, "keep": False, "sketch": ["y"]}
    r = monte_carlo(wide_model, inputs, executor="dask", scheduler=client, **kw)
    assert 0 < sum(sent) <= SENT_FRACTION * 8 * (WIDE + 1) * trials
    one = monte_carlo(wide_model, inputs, **kw)
    assert r["comp"].u_vector.tobytes() == one["comp"].u_vector.tobytes()
    assert r["y"].coverage_interval(0.95) == one["y"].coverage_interval(0.95)
    # a scalar run of 4 sketch groups: a fraction of a byte a trial
    sent.clear()
    n = 4 * 2**20
    r = monte_carlo(model, INPUTS, trials=n, seed=5, keep=False, executor="dask", scheduler=client)
    assert 0 < sum(sent) <= SENT_FRACTION * 8 * 3 * n  # "sum" and the two of "pair"


def test_kept_samples_are_written_by_the_workers_not_sent_back(client, sent, monkeypatch, tmp_path):
    """Workers on this machine write kept rows into the client's arrays (shared memory)."""
    from mtmc.uncertainty import shared_rows

    shm = shared_rows.SHARED_DIR
    if shm is None or not shm.is_dir() or shutil.disk_usage(shm).free < 64 * 2**20:
        monkeypatch.setattr(shared_rows, "SHARED_DIR", tmp_path)  # no room in /dev/shm
    n = 2**20 + 777
    got = monte_carlo(model, INPUTS, trials=n, seed=8, executor="dask", scheduler=client)
    assert got["sum"].kept
    assert 0 < sum(sent) <= SENT_FRACTION * 8 * 3 * n  # 0.05 % measured, 100 % before
    one = monte_carlo(model, INPUTS, trials=n, seed=8)
    for name in ("sum", "pair"):
        assert got[name].samples.tobytes() == one[name].samples.tobytes()
    assert not [
        p
        for p in shared_rows.SHARED_DIR.iterdir()
        if p.name.startswith(f"{shared_rows.PREFIX}{os.getpid()}-")
    ]


def _dask_log_level(_task: int) -> int:
    import logging

    return logging.getLogger("distributed").getEffectiveLevel()


def test_a_cluster_started_for_one_call_logs_nothing_the_command_would_print():
    # Ctrl-C to the group under load: a worker's heartbeat met the scheduler already closed
    # and logged an ERROR with its traceback above "mtmc: interrupted" (tests/
    # test_cli_signals.py, 1 of 5 cases in one CI run at load 4); the run reports its own
    # failures, so the workers of a call's cluster log at CRITICAL only
    import logging

    from mtmc.parallel import CALL_CLUSTER_LOG_LEVEL, map_blocks

    assert CALL_CLUSTER_LOG_LEVEL == "CRITICAL"
    seen = list(map_blocks(_dask_log_level, [0, 1], workers=1, executor="dask"))
    assert seen == [logging.CRITICAL, logging.CRITICAL]
