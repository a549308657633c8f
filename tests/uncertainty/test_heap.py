"""The heap setting of a Monte Carlo run: set once per process on glibc, or left alone."""

from __future__ import annotations

import os
import platform
import subprocess
import sys

import pytest

CODE = """
import os
import resource
import sys
from mtmc.uncertainty import monte_carlo
from mtmc.uncertainty.heap import keep_heap

def faults():
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt

def model(x, y):
    return {"s": x + y, "p": (x * y)[:, None] * [1.0, 2.0, 3.0]}

inputs = {"x": "normal(0, 1)", "y": "normal(1, 2)"}
if len(sys.argv) > 1:  # set after start, as Dask's nanny does: glibc never saw it
    os.environ["MALLOC_TRIM_THRESHOLD_"] = sys.argv[1]
monte_carlo(model, inputs, trials=200_000, seed=1, keep=False)
before = faults()
monte_carlo(model, inputs, trials=200_000, seed=1, keep=False)
print(keep_heap(), faults() - before)
"""


def _run(*args: str, **env: str) -> tuple[bool, int]:
    full = {k: v for k, v in os.environ.items() if not k.startswith(("MALLOC_", "MTMC_HEAP"))}
    out = subprocess.run(
        [sys.executable, "-c", CODE, *args],
        env={**full, **env},
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()
    return out[0] == "True", int(out[1])


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="a glibc setting")
def test_a_second_run_reuses_the_heap_and_system_leaves_it_alone():
    kept, faults = _run()
    assert kept
    # the second run's blocks reuse the memory of the first: no page is faulted in again
    # (a run of 200 000 trials maps ~1 MB of new arrays per block otherwise)
    assert faults < 200
    left, _ = _run(MTMC_HEAP="system")
    assert not left
    user, _ = _run(MALLOC_TRIM_THRESHOLD_="131072")
    assert not user
    # a variable written into os.environ after start (Dask's nanny does so in the process
    # that starts a LocalCluster) was never read by glibc: the heap is still kept
    late, late_faults = _run("131072")
    assert late
    assert late_faults < 200
