"""A fast start: importing mtmc (all of its public names, and the CLI) leaves SymPy,
Matplotlib and SciPy's statistics and optimisation unimported; the lazy re-export of the
top-level package gives the same names and objects as the subpackages."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys

import pytest

HEAVY = ("sympy", "matplotlib", "scipy.stats", "scipy.optimize", "scipy.special")


def _loaded_after(code: str) -> list[str]:
    """Run ``code`` in a fresh interpreter; return which of HEAVY it left in sys.modules."""
    probe = (
        f"{code}\nimport json, sys\nprint(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))"
    )
    out = subprocess.run(
        [sys.executable, "-c", probe], check=True, capture_output=True, text=True
    ).stdout
    return list(json.loads(out.strip().splitlines()[-1]))


@pytest.mark.parametrize(
    "code",
    [
        "import mtmc",
        "from mtmc import *",
        "import mtmc.cli.main",
        "import mtmc.uncertainty, mtmc.geometry, mtmc.graph, mtmc.kinematics, mtmc.demo",
    ],
)
def test_import_leaves_heavy_modules_unimported(code):
    assert _loaded_after(code) == []


def test_heavy_module_is_imported_when_used():
    # the probe sees a module that is imported: the check above can fail
    code = "from mtmc.uncertainty.propagation import coverage_factor\ncoverage_factor(0.95, 10)"
    loaded = _loaded_after(code)
    assert "scipy.stats" in loaded
    assert "sympy" not in loaded


def test_lazy_names_are_those_of_the_subpackages():
    import mtmc
    from mtmc import errors, graph, study

    assert mtmc.__all__[:2] == ["__version__", "errors"]
    assert len(set(mtmc.__all__)) == len(mtmc.__all__)
    for name in mtmc.__all__[2:]:
        owner = errors if name in errors.__all__ else importlib.import_module(mtmc._NAMES[name])
        assert getattr(mtmc, name) is getattr(owner, name), name
    assert set(mtmc.__all__) <= set(dir(mtmc))
    assert mtmc.graph is graph
    assert mtmc.load_study is study.load_study
    # the subpackages keep what the top level leaves out
    assert "vector" not in mtmc.__all__
    assert mtmc.geometry.vector is importlib.import_module("mtmc.geometry").vector
    # one name, one thing: mtmc.report is the package that draws a result.json,
    # mtmc.render_report the study layer's function that renders any result
    import mtmc.report.plots

    assert mtmc.report is importlib.import_module("mtmc.report")
    assert mtmc.render_report is study.render_report
    assert not hasattr(mtmc.report, "render_report")
    with pytest.raises(AttributeError, match="no attribute 'not_a_name'"):
        _ = mtmc.not_a_name


def test_type_checker_block_covers_every_name():
    # the names the type checker sees (the star imports under TYPE_CHECKING) are those
    # re-exported at run time, so a module added to a subpackage is not missed
    import ast
    from pathlib import Path

    import mtmc

    tree = ast.parse(Path(mtmc.__file__).read_text(encoding="utf-8"))
    block = next(
        n for n in tree.body if isinstance(n, ast.If) and "TYPE_CHECKING" in ast.dump(n.test)
    )
    seen = {"errors", *importlib.import_module("mtmc.errors").__all__}
    for node in block.body:
        if isinstance(node, ast.ImportFrom) and node.names[0].name == "*":
            seen |= set(importlib.import_module(str(node.module)).__all__)
        elif isinstance(node, ast.ImportFrom) and node.module != "mtmc":
            seen |= {a.asname or a.name for a in node.names}
    assert seen == set(mtmc.__all__) - {"__version__"}


def test_cli_help_imports_no_numpy_nor_the_library():
    # `mtmc --help` builds the command tree only: the library (and NumPy) is imported
    # inside the commands, when one runs
    code = (
        "import contextlib, io, json, sys\n"
        "from mtmc.cli.main import main\n"
        "with contextlib.redirect_stdout(io.StringIO()), contextlib.suppress(SystemExit):\n"
        "    main(['--help'])\n"
        "names = ('numpy', 'mtmc.uncertainty', 'mtmc.graph', 'mtmc.kinematics', 'mtmc.study')\n"
        "print(json.dumps([m for m in names if m in sys.modules]))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], check=True, capture_output=True, text=True
    ).stdout
    assert json.loads(out.strip().splitlines()[-1]) == []
    # the probe sees NumPy once a command that needs it runs
    code2 = code.replace("['--help']", "['graph', 'check', '/nonexistent.toml']")
    out2 = subprocess.run(
        [sys.executable, "-c", code2], check=True, capture_output=True, text=True
    ).stdout
    assert "mtmc.graph" in json.loads(out2.strip().splitlines()[-1])
