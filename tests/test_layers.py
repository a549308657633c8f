"""The layers of docs/architecture.md hold: no import circle, no upward import.

The imports of every module of ``src/mtmc`` are read from its source (``ast``), at module
level and inside functions alike; an import under ``if TYPE_CHECKING:`` runs nothing and is
left out. From them: the graph of modules has no cycle, and each package imports only the
packages below it in :data:`ALLOWED` (the table of docs/architecture.md).
"""

from __future__ import annotations

import ast
import functools
from collections import defaultdict
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PKG = SRC / "mtmc"

#: The bottom: imported by every layer, importing nothing of mtmc but each other.
BASE = {"errors", "frozen", "io", "document", "csvtable", "parallel", "_version"}

#: What each package may import besides :data:`BASE` (docs/architecture.md).
ALLOWED: dict[str, set[str]] = {
    "errors": set(),
    "frozen": set(),
    "io": set(),
    "document": set(),
    "csvtable": set(),
    "parallel": set(),
    "_version": set(),
    "uncertainty": set(),
    "geometry": set(),
    "kinematics": {"geometry"},
    "instruments": {"geometry"},
    "graph": {"geometry", "uncertainty"},
    "verification": {"geometry", "instruments", "kinematics", "uncertainty"},
    "artefact": {"geometry", "kinematics", "uncertainty"},
    "circular": {"geometry", "kinematics", "uncertainty", "verification"},
    "positioning": {"geometry", "uncertainty", "verification"},
    "report": {"graph", "kinematics", "uncertainty"},
    "study": {
        "artefact",
        "circular",
        "geometry",
        "graph",
        "instruments",
        "kinematics",
        "positioning",
        "report",
        "uncertainty",
        "verification",
        "version",
    },
    "workbench": {"geometry", "graph", "report", "study", "uncertainty"},
    "demo": {"report", "study"},
    "_warm": set(),  # imports the modules of the layers by name (importlib)
    "cli": {
        "artefact",
        "circular",
        "demo",
        "graph",
        "kinematics",
        "positioning",
        "report",
        "study",
        "uncertainty",
        "verification",
        "version",
        "workbench",
    },
}


def _modules() -> dict[str, Path]:
    out = {}
    for p in PKG.rglob("*.py"):
        parts = list(p.relative_to(SRC).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = p
    return out


@functools.cache
def _tree(path: Path) -> ast.Module:
    """The syntax tree of a Python file, parsed once per test process."""
    return ast.parse(path.read_text(encoding="utf-8"))


def _imports(
    name: str, path: Path, modules: dict[str, Path], *, typing_too: bool = False
) -> set[str]:
    tree = _tree(path)
    skip: set[int] = set()
    for node in [] if typing_too else ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skip.update(id(n) for b in node.body for n in ast.walk(b))
    package = path.name == "__init__.py"
    found = set()
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                here = name.split(".") if package else name.split(".")[:-1]
                here = here[: len(here) - node.level + 1]
                base = ".".join([*here, *([node.module] if node.module else [])])
            targets = [f"{base}.{a.name}" for a in node.names] + [base]
        elif isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        else:
            continue
        for t in targets:
            if t in modules and t != name:
                found.add(t)
                break
    return found


def _package(module: str) -> str:
    parts = module.split(".")
    if len(parts) == 1:
        return "version"  # the package itself: mtmc.__version__
    return parts[1]


@functools.cache
def _graph(*, typing_too: bool = False) -> dict[str, set[str]]:
    """Each module's imports of other modules of mtmc, read once per test process (the
    three tests that read it took 5-7 s each to parse the package, under coverage)."""
    modules = _modules()
    return {m: _imports(m, p, modules, typing_too=typing_too) for m, p in modules.items()}


@pytest.mark.parametrize("typing_too", [False, True], ids=["run time", "with type-only"])
def test_no_module_imports_in_a_circle(typing_too: bool) -> None:
    """No circle, also counting the imports under ``if TYPE_CHECKING:`` (a type that
    only a circle can name lives in the wrong module)."""
    graph = _graph(typing_too=typing_too)
    state: dict[str, int] = {}
    stack: list[str] = []
    cycles: list[list[str]] = []

    def visit(m: str) -> None:
        state[m] = 1
        stack.append(m)
        for n in sorted(graph.get(m, ())):
            if state.get(n) == 1:
                cycles.append([*stack[stack.index(n) :], n])
            elif n not in state:
                visit(n)
        stack.pop()
        state[m] = 2

    for m in sorted(graph):
        if m not in state and m != "mtmc":  # the package's lazy top-level names
            visit(m)
    assert not cycles, "\n".join(" -> ".join(c) for c in cycles)


def test_every_package_imports_only_the_layers_below_it() -> None:
    bad = defaultdict(set)
    for m, targets in _graph().items():
        if m == "mtmc":
            continue
        pkg = _package(m)
        assert pkg in ALLOWED, f"{pkg} is not in the table of layers"
        for t in targets:
            other = _package(t)
            if other != pkg and other not in BASE and other not in ALLOWED[pkg]:
                bad[f"{pkg} -> {other}"].add(f"{m} imports {t}")
    assert not bad, "\n".join(f"{k}: {sorted(v)}" for k, v in sorted(bad.items()))


def test_the_base_imports_nothing_above_it() -> None:
    for m, targets in _graph().items():
        if _package(m) in BASE:
            assert {_package(t) for t in targets} <= BASE | {_package(m)}, m


#: The layers above the domain packages: they parse, run studies, draw and print.
UPPER = ("cli", "study", "report", "workbench", "demo")

#: Linear algebra and statistics that are the domain's or the engine's, never an upper
#: layer's. ``numpy.linalg.norm`` is left out: a length, as a plot or a table measures it.
_REFUSED = ("numpy.linalg", "scipy.linalg", "scipy.stats")


def _dotted(node: ast.expr) -> list[str] | None:
    """``["np", "linalg", "solve"]`` of ``np.linalg.solve``; None for anything but names."""
    if isinstance(node, ast.Name):
        return [node.id]
    if isinstance(node, ast.Attribute):
        head = _dotted(node.value)
        return None if head is None else [*head, node.attr]
    return None


def _refused_uses(path: Path) -> list[str]:
    """The uses of :data:`_REFUSED` in a module: imports and ``np.linalg.X`` attributes."""
    tree = _tree(path)
    alias = {"numpy": "numpy", "scipy": "scipy"}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                alias[a.asname or a.name] = a.name
        elif isinstance(node, ast.ImportFrom) and node.module in ("numpy", "scipy"):
            for a in node.names:
                alias[a.asname or a.name] = f"{node.module}.{a.name}"
    inner = {id(n.value) for n in ast.walk(tree) if isinstance(n, ast.Attribute)}
    found = []
    for node in ast.walk(tree):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module:
            names = [f"{node.module}.{a.name}" for a in node.names]
        elif isinstance(node, ast.Attribute) and id(node) not in inner:
            chain = _dotted(node)
            if chain and chain[0] in alias:
                names = [".".join([alias[chain[0]], *chain[1:]])]
        for n in names:
            if n == "numpy.linalg.norm":
                continue
            if any(n == r or n.startswith(r + ".") for r in _REFUSED):
                where = path.relative_to(SRC) if path.is_relative_to(SRC) else path.name
                found.append(f"{where}:{getattr(node, 'lineno', 0)}: {n}")
    return found


def test_upper_layers_leave_linear_algebra_and_statistics_below() -> None:
    """cli, study, report and workbench call the library for a solve, a decomposition or
    a distribution; they do not compute one."""
    bad = []
    for m, path in _modules().items():
        if _package(m) in UPPER:
            bad += _refused_uses(path)
    assert not bad, "\n".join(sorted(set(bad)))


def test_the_refusal_sees_each_way_of_writing_it(tmp_path: Path) -> None:
    """The check of upper layers finds an import, a from-import and an attribute."""
    f = tmp_path / "m.py"
    f.write_text(
        "import numpy as np\nfrom scipy import stats\nimport scipy.linalg\n"
        "x = np.linalg.solve(a, b)\ny = np.linalg.norm(a)\nz = stats.t.ppf(0.9, 3)\n",
        encoding="utf-8",
    )
    uses = {u.split(": ")[1] for u in _refused_uses(f)}
    assert uses == {"numpy.linalg.solve", "scipy.stats", "scipy.linalg", "scipy.stats.t.ppf"}
