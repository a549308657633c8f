"""Each shared rule is written once, in the layer that owns it (docs/architecture.md).

A study kind that needs a rule calls it there: no module outside the rule's layer defines
a function, method or class of the rule's name, and the architecture guide names the home
of each. A kind that brought its own copy (a ``conformity`` method on its result, a second
``coverage_factor``) fails here with the file and line of the copy. Inside its layer a rule
may have more than one face: ``MonteCarloResult.conformity`` and ``GumResult.conformity``
both call :func:`mtmc.uncertainty.conformity`, and the GUM's ``k`` (JCGM 100, a t quantile)
is not the Monte Carlo's (JCGM 101, the interval's half-width over ``u``).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "mtmc"

#: The names of each shared rule and the one module that defines them.
HOMES: dict[str, tuple[str, ...]] = {
    "uncertainty/decision.py": ("conformity", "Conformity"),
    "uncertainty/results.py": ("expanded_uncertainty", "coverage_factor", "Histogram"),
    "uncertainty/propagation.py": ("output_pdf",),
    "graph/values.py": ("normal_plane_parts",),
    "graph/ops.py": ("accepts_prefix", "max_inputs"),
    "instruments/laser_tracker.py": ("u_spherical",),
    "artefact/model.py": ("in_axes",),
    "csvtable.py": ("read_csv", "read_pairs", "read_units"),
    "study/units.py": ("read_unit", "model_unit", "check_model_units"),
    "study/result.py": ("warnings",),
    "cli/run.py": ("study_command", "StudyOptions", "print_outcome", "decision_lines"),
    "geometry/checks.py": ("in_batch",),
    "verification/definition.py": ("point_set", "tracker_name"),
}


def _definitions() -> dict[str, list[str]]:
    """Each name defined (function, method or class) in ``src/mtmc``: where, as file:line."""
    out: dict[str, list[str]] = {}
    for path in sorted(SRC.rglob("*.py")):
        rel = path.relative_to(SRC).as_posix()
        for node in ast.walk(ast.parse(path.read_text("utf-8"), filename=rel)):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
                out.setdefault(node.name, []).append(f"{rel}:{node.lineno}")
    return out


DEFINED = _definitions()


@pytest.mark.parametrize(
    ("home", "name"), [(home, name) for home, names in HOMES.items() for name in names]
)
def test_a_shared_rule_is_defined_once_in_its_home(home: str, name: str) -> None:
    where = DEFINED.get(name, [])
    assert any(w.startswith(home + ":") for w in where), f"{name} is not defined in {home}"
    layer = home.rsplit("/", 1)[0] + "/" if "/" in home else home
    elsewhere = [w for w in where if not w.startswith(layer)]
    assert not elsewhere, f"{name} belongs to {layer}, but is also defined at {elsewhere}"


def test_the_architecture_guide_names_each_home() -> None:
    text = (ROOT / "docs" / "architecture.md").read_text("utf-8")
    table = text.split("## Where each shared rule lives", 1)[1].split("\n## ", 1)[0]
    for home, names in HOMES.items():
        rows = [r for r in table.splitlines() if home.split("/")[-1] in r]
        assert rows, home
        for name in names:
            assert any(re.search(rf"[`.]{name}[`,]", r) for r in rows), (home, name)


def test_no_module_of_a_package_shares_its_name_with_a_function_of_it() -> None:
    """``import mtmc.uncertainty.gum as g`` gave the function, not the module: a module and
    a function of one name in one namespace. Every package's submodules are named for what
    they hold, apart from its functions and classes."""
    import importlib
    import pkgutil

    import mtmc

    clashes = []
    names = ["mtmc"] + [i.name for i in pkgutil.walk_packages(mtmc.__path__, "mtmc.") if i.ispkg]
    for name in names:
        pkg = importlib.import_module(name)
        for sub in pkgutil.iter_modules(pkg.__path__):
            value = getattr(pkg, sub.name, None)
            if value is not None and not hasattr(value, "__path__") and callable(value):
                clashes.append(f"{name}.{sub.name}")
    assert not clashes, clashes
