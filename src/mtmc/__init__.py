"""mtmc — machine-tool Monte Carlo.

How uncertain is a measurement on a machine tool? mtmc answers by Monte Carlo simulation
(JCGM 101) with the GUM law of propagation (JCGM 100) beside it, over measurement graphs
(touch-probe measurements, rotary-axis location), kinematic machine models with ISO 230
geometric errors, and, later, laser-tracker verification and fiducial artefacts.

The public API is re-exported here; everything else may change between versions.

``import mtmc`` is cheap: the subpackages (:mod:`mtmc.uncertainty`, :mod:`mtmc.geometry`,
:mod:`mtmc.graph`, :mod:`mtmc.kinematics`) are imported on the first access to one of
their names (``mtmc.run_graph``, ``from mtmc import Machine``, ``mtmc.__all__``), and
SymPy, Matplotlib and SciPy's statistics only inside the functions that use them.
"""

from __future__ import annotations

import importlib
import importlib.util
from typing import TYPE_CHECKING, Any

from mtmc import errors as errors
from mtmc.errors import *  # noqa: F403

__version__ = "0.1.0"

# Imported after the version, which the result folders record. ``mtmc.report`` is the
# function that renders a result (the module stays importable as ``mtmc.report``); it is
# bound here, before any later import of the module could bind the name to the module.
from mtmc.report import report as report

#: Names of other modules re-exported first, then those of the subpackages, in the order
#: of ``__all__``.
_NAMES = {
    "StudyResult": "mtmc.study",
    "load_study": "mtmc.study",
    "loads_study": "mtmc.study",
    "register_kind": "mtmc.study",
    "study_kinds": "mtmc.study",
    "write_result": "mtmc.study",
}
_SUBPACKAGES = ("errors", "uncertainty", "geometry", "graph", "kinematics")

if TYPE_CHECKING:
    # The type checker sees every name. It cannot follow the computed ``__all__`` of a
    # subpackage, so the names come from the modules, whose ``__all__`` are literal.
    from mtmc import geometry as geometry
    from mtmc import graph as graph
    from mtmc import kinematics as kinematics
    from mtmc import uncertainty as uncertainty
    from mtmc.geometry.constructions import *  # noqa: F403
    from mtmc.geometry.fits import *  # noqa: F403
    from mtmc.geometry.primitives import *  # noqa: F403
    from mtmc.geometry.transforms import *  # noqa: F403
    from mtmc.graph import *  # noqa: F403
    from mtmc.kinematics.aguado import *  # noqa: F403
    from mtmc.kinematics.draw import *  # noqa: F403
    from mtmc.kinematics.error_terms import *  # noqa: F403
    from mtmc.kinematics.functions import *  # noqa: F403
    from mtmc.kinematics.library import *  # noqa: F403
    from mtmc.kinematics.machine import *  # noqa: F403
    from mtmc.kinematics.parameters import *  # noqa: F403
    from mtmc.kinematics.symbolic import *  # noqa: F403
    from mtmc.kinematics.topology import *  # noqa: F403
    from mtmc.study import StudyResult as StudyResult
    from mtmc.study import load_study as load_study
    from mtmc.study import loads_study as loads_study
    from mtmc.study import register_kind as register_kind
    from mtmc.study import study_kinds as study_kinds
    from mtmc.study import write_result as write_result
    from mtmc.uncertainty.distributions import *  # noqa: F403
    from mtmc.uncertainty.expression import *  # noqa: F403
    from mtmc.uncertainty.gum import *  # noqa: F403
    from mtmc.uncertainty.montecarlo import *  # noqa: F403
    from mtmc.uncertainty.results import *  # noqa: F403
    from mtmc.uncertainty.sampling import *  # noqa: F403
    from mtmc.uncertainty.tolerance import *  # noqa: F403

_exports: dict[str, str] | None = None


def _load_exports() -> dict[str, str]:
    """Import the subpackages and map each public name to the subpackage exporting it."""
    global _exports
    if _exports is None:
        table: dict[str, str] = dict(_NAMES)
        for sub in _SUBPACKAGES:
            mod = importlib.import_module(f"mtmc.{sub}")
            for name in mod.__all__:
                table.setdefault(name, mod.__name__)
        _exports = table
    return _exports


def __getattr__(name: str) -> Any:
    """Resolve a public name (or ``__all__``) on first access (PEP 562)."""
    if name == "__all__":
        names = ["__version__", "errors", "report", *_load_exports()]
        globals()["__all__"] = names
        return names
    if name.startswith("_"):
        raise AttributeError(f"module 'mtmc' has no attribute {name!r}")
    if importlib.util.find_spec(f"mtmc.{name}") is not None:  # a module: mtmc.graph
        return importlib.import_module(f"mtmc.{name}")
    owner = _load_exports().get(name)
    if owner is None:
        raise AttributeError(f"module 'mtmc' has no attribute {name!r}")
    value = getattr(importlib.import_module(owner), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_load_exports()})
