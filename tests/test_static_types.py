"""The return types a type checker infers are the ones the functions return.

mypy (strict) checks a small user program against the package's annotations; each
``assert_type`` is an error if the inferred type differs, and the same calls run here
return objects of those types.
"""

from __future__ import annotations

import shutil
import textwrap
from pathlib import Path

import pytest

from mtmc.uncertainty.montecarlo import monte_carlo
from mtmc.uncertainty.results import MonteCarloResult, MonteCarloResults

ROOT = Path(__file__).resolve().parents[1]

USER_PROGRAM = """
from pathlib import Path
from typing import assert_type

import numpy as np
from numpy.typing import NDArray

from mtmc.graph import PlaceSummary
from mtmc.study import render_report
from mtmc.uncertainty import MonteCarloResult, MonteCarloResults, monte_carlo


def one(x: NDArray[np.float64]) -> NDArray[np.float64]:
    return 2 * x


def named(x: NDArray[np.float64]) -> dict[str, NDArray[np.float64]]:
    return {"a": x}


inputs = {"x": "normal(0, 1)"}
assert_type(monte_carlo(one, inputs, trials=10), MonteCarloResult)
assert_type(monte_carlo(named, inputs, trials=10), MonteCarloResults)
assert_type(render_report(Path("folder")), Path)
assert_type(render_report({"a": 1}), str)
assert_type(render_report({"a": 1}, "page.html"), Path)


def place(s: PlaceSummary) -> None:
    assert_type(s.estimate, float)
    assert_type(s.u, float)
    assert_type(s.estimate_vector, NDArray[np.float64])
    assert_type(s.u_vector, NDArray[np.float64])
    assert_type(s.cov, NDArray[np.float64])
    assert_type(s.part("value"), MonteCarloResult)
"""


def test_mypy_infers_the_declared_types(tmp_path):
    api = pytest.importorskip("mypy.api")
    prog = tmp_path / "user.py"
    prog.write_text(textwrap.dedent(USER_PROGRAM))
    # mypy reads the package from the cache `make typecheck` left (same options: the
    # project's, strict), a copy of it, and checks it against the sources itself: a
    # module changed since is read again. Without one it reads the whole package (16 s
    # under coverage, against 4 s).
    cache = tmp_path / "cache"
    if (ROOT / ".mypy_cache").is_dir():
        shutil.copytree(ROOT / ".mypy_cache", cache)
    out, err, status = api.run(["--strict", "--cache-dir", str(cache), str(prog)])
    assert status == 0, out + err


def _one(x):
    return 2 * x


def _named(x):
    return {"a": x}


def test_the_calls_return_those_types():
    """The same calls at run time (``report``'s three cases: tests/report/test_report.py)."""
    inputs = {"x": "normal(0, 1)"}
    assert type(monte_carlo(_one, inputs, trials=10, seed=1)) is MonteCarloResult
    assert type(monte_carlo(_named, inputs, trials=10, seed=1)) is MonteCarloResults
