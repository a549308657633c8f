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
from mtmc.uncertainty import heap, monte_carlo

def faults():
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt

def model(x, y):
    return {"s": x + y, "p": (x * y)[:, None] * [1.0, 2.0, 3.0]}

inputs = {"x": "normal(0, 1)", "y": "normal(1, 2)"}
if len(sys.argv) > 2:  # set after start, as Dask's nanny does: glibc never saw it
    os.environ["MALLOC_TRIM_THRESHOLD_"] = sys.argv[2]
if sys.argv[1] == "command":  # as the mtmc command starts
    from mtmc.cli.main import main

    main(["kinematics", "list"])
monte_carlo(model, inputs, trials=200_000, seed=1, keep=False)
before = faults()
monte_carlo(model, inputs, trials=200_000, seed=1, keep=False)
print(heap._done == [True], heap._done == [], faults() - before)
"""


def _run(*args: str, **env: str) -> tuple[bool, bool, int]:
    """Whether the heap was kept, whether nothing set it, the second run's page faults."""
    full = {k: v for k, v in os.environ.items() if not k.startswith(("MALLOC_", "MTMC_HEAP"))}
    out = subprocess.run(
        [sys.executable, "-c", CODE, *args],
        env={**full, **env},
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()[-3:]  # after what the command prints
    return out[0] == "True", out[1] == "True", int(out[2])


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="a glibc setting")
def test_the_command_keeps_the_heap_and_system_leaves_it_alone():
    kept, _, faults = _run("command")
    assert kept
    # the second run's blocks reuse the memory of the first: no page is faulted in again
    # (a run of 200 000 trials maps ~1 MB of new arrays per block otherwise)
    assert faults < 200
    left, _, _ = _run("command", MTMC_HEAP="system")
    assert not left
    user, _, _ = _run("command", MALLOC_TRIM_THRESHOLD_="131072")
    assert not user
    # a variable written into os.environ after start (Dask's nanny does so in the process
    # that starts a LocalCluster) was never read by glibc: the heap is still kept
    late, _, late_faults = _run("command", "131072")
    assert late
    assert late_faults < 200


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="a glibc setting")
def test_a_library_call_leaves_the_allocator_of_its_process_alone():
    kept, untouched, faults = _run("library")
    assert not kept
    assert untouched
    # glibc's own thresholds: the second run faults its blocks in again
    assert faults > 1000
