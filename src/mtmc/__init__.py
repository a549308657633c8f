"""mtmc — machine-tool Monte Carlo.

How uncertain is a measurement on a machine tool? mtmc answers by Monte Carlo simulation
(JCGM 101) with the GUM law of propagation (JCGM 100) beside it, over measurement graphs
(touch-probe measurements, rotary-axis location), kinematic machine models with ISO 230
geometric errors, laser-tracker verification and fiducial artefacts.

This namespace holds what a user calls: the studies, the Monte Carlo engine and the GUM,
the distributions, the measurement graph's reader and runners, the machine library, and
the errors. Everything else is in the subpackages (:mod:`mtmc.uncertainty`,
:mod:`mtmc.geometry`, :mod:`mtmc.graph`, :mod:`mtmc.kinematics`, :mod:`mtmc.study`,
:mod:`mtmc.instruments`, :mod:`mtmc.verification`, :mod:`mtmc.artefact`, ...);
``docs/api.md`` lists the public API by subpackage. Names not listed there may change
between versions.

``import mtmc`` is cheap: a subpackage is imported on the first access to one of its
names (``mtmc.run_graph``, ``from mtmc import Machine``), and SymPy, Matplotlib and SciPy's
statistics only inside the functions that use them.
"""

from __future__ import annotations

import importlib
import importlib.util
from typing import TYPE_CHECKING, Any

from mtmc import errors as errors
from mtmc._version import __version__ as __version__
from mtmc.errors import *  # noqa: F403

#: The names resolved on first access, and the subpackage each comes from.
_NAMES: dict[str, str] = {
    "render_report": "mtmc.study",
    "load_study": "mtmc.study",
    "loads_study": "mtmc.study",
    "write_result": "mtmc.study",
    "load_result": "mtmc.study",
    "StudyResult": "mtmc.study",
    "monte_carlo": "mtmc.uncertainty",
    "gum": "mtmc.uncertainty",
    "conformity": "mtmc.uncertainty",
    "Conformity": "mtmc.uncertainty",
    "validate": "mtmc.uncertainty",
    "monte_carlo_budget": "mtmc.uncertainty",
    "sobol_indices": "mtmc.uncertainty",
    "expression": "mtmc.uncertainty",
    "parse_distribution": "mtmc.uncertainty",
    "MonteCarloResult": "mtmc.uncertainty",
    "MonteCarloResults": "mtmc.uncertainty",
    "GumResult": "mtmc.uncertainty",
    "Arcsine": "mtmc.uncertainty",
    "Constant": "mtmc.uncertainty",
    "CurvilinearTrapezoid": "mtmc.uncertainty",
    "Exponential": "mtmc.uncertainty",
    "Gamma": "mtmc.uncertainty",
    "IID": "mtmc.uncertainty",
    "MultivariateNormal": "mtmc.uncertainty",
    "Normal": "mtmc.uncertainty",
    "StudentT": "mtmc.uncertainty",
    "Trapezoidal": "mtmc.uncertainty",
    "Triangular": "mtmc.uncertainty",
    "Uniform": "mtmc.uncertainty",
    "TypeA": "mtmc.uncertainty",
    "WithDof": "mtmc.uncertainty",
    "type_a": "mtmc.uncertainty",
    "with_dof": "mtmc.uncertainty",
    "load_graph": "mtmc.graph",
    "loads_graph": "mtmc.graph",
    "check_graph": "mtmc.graph",
    "run_graph": "mtmc.graph",
    "sweep_graph": "mtmc.graph",
    "graph_model": "mtmc.graph",
    "draw_graph": "mtmc.graph",
    "library_machine": "mtmc.kinematics",
    "library_names": "mtmc.kinematics",
    "Machine": "mtmc.kinematics",
    "parse_topology": "mtmc.kinematics",
    "draw_chain": "mtmc.kinematics",
}

__all__: list[str] = [
    "__version__",
    "errors",
    *errors.__all__,
    "render_report",
    "load_study",
    "loads_study",
    "write_result",
    "load_result",
    "StudyResult",
    "monte_carlo",
    "gum",
    "conformity",
    "Conformity",
    "validate",
    "monte_carlo_budget",
    "sobol_indices",
    "expression",
    "parse_distribution",
    "MonteCarloResult",
    "MonteCarloResults",
    "GumResult",
    "Arcsine",
    "Constant",
    "CurvilinearTrapezoid",
    "Exponential",
    "Gamma",
    "IID",
    "MultivariateNormal",
    "Normal",
    "StudentT",
    "Trapezoidal",
    "Triangular",
    "Uniform",
    "TypeA",
    "WithDof",
    "type_a",
    "with_dof",
    "load_graph",
    "loads_graph",
    "check_graph",
    "run_graph",
    "sweep_graph",
    "graph_model",
    "draw_graph",
    "library_machine",
    "library_names",
    "Machine",
    "parse_topology",
    "draw_chain",
]

if TYPE_CHECKING:
    from mtmc import artefact as artefact
    from mtmc import geometry as geometry
    from mtmc import graph as graph
    from mtmc import instruments as instruments
    from mtmc import kinematics as kinematics
    from mtmc import study as study
    from mtmc import uncertainty as uncertainty
    from mtmc import verification as verification
    from mtmc.graph import check_graph as check_graph
    from mtmc.graph import draw_graph as draw_graph
    from mtmc.graph import loads_graph as loads_graph
    from mtmc.graph import sweep_graph as sweep_graph
    from mtmc.graph.files import load_graph as load_graph
    from mtmc.graph.run import graph_model as graph_model
    from mtmc.graph.run import run_graph as run_graph
    from mtmc.kinematics.draw import draw_chain as draw_chain
    from mtmc.kinematics.library import library_machine as library_machine
    from mtmc.kinematics.library import library_names as library_names
    from mtmc.kinematics.machine import Machine as Machine
    from mtmc.kinematics.topology import parse_topology as parse_topology
    from mtmc.study.load import load_result as load_result
    from mtmc.study.render import render_report as render_report
    from mtmc.study.result import StudyResult as StudyResult
    from mtmc.study.spec import load_study as load_study
    from mtmc.study.spec import loads_study as loads_study
    from mtmc.study.write import write_result as write_result
    from mtmc.uncertainty.decision import Conformity as Conformity
    from mtmc.uncertainty.decision import conformity as conformity
    from mtmc.uncertainty.distributions import IID as IID
    from mtmc.uncertainty.distributions import Arcsine as Arcsine
    from mtmc.uncertainty.distributions import Constant as Constant
    from mtmc.uncertainty.distributions import CurvilinearTrapezoid as CurvilinearTrapezoid
    from mtmc.uncertainty.distributions import Exponential as Exponential
    from mtmc.uncertainty.distributions import Gamma as Gamma
    from mtmc.uncertainty.distributions import MultivariateNormal as MultivariateNormal
    from mtmc.uncertainty.distributions import Normal as Normal
    from mtmc.uncertainty.distributions import StudentT as StudentT
    from mtmc.uncertainty.distributions import Trapezoidal as Trapezoidal
    from mtmc.uncertainty.distributions import Triangular as Triangular
    from mtmc.uncertainty.distributions import Uniform as Uniform
    from mtmc.uncertainty.distributions import parse_distribution as parse_distribution
    from mtmc.uncertainty.formula import expression as expression
    from mtmc.uncertainty.montecarlo import monte_carlo as monte_carlo
    from mtmc.uncertainty.propagation import GumResult as GumResult
    from mtmc.uncertainty.propagation import gum as gum
    from mtmc.uncertainty.propagation import validate as validate
    from mtmc.uncertainty.results import MonteCarloResult as MonteCarloResult
    from mtmc.uncertainty.results import MonteCarloResults as MonteCarloResults
    from mtmc.uncertainty.sensitivity import monte_carlo_budget as monte_carlo_budget
    from mtmc.uncertainty.sensitivity import sobol_indices as sobol_indices
    from mtmc.uncertainty.typea import TypeA as TypeA
    from mtmc.uncertainty.typea import WithDof as WithDof
    from mtmc.uncertainty.typea import type_a as type_a
    from mtmc.uncertainty.typea import with_dof as with_dof


def __getattr__(name: str) -> Any:
    """Resolve a public name or a subpackage on first access (PEP 562)."""
    if name.startswith("_"):
        raise AttributeError(f"module 'mtmc' has no attribute {name!r}")
    owner = _NAMES.get(name)
    if owner is not None:
        value = getattr(importlib.import_module(owner), name)
        globals()[name] = value
        return value
    if importlib.util.find_spec(f"mtmc.{name}") is not None:  # a module: mtmc.graph
        return importlib.import_module(f"mtmc.{name}")
    raise AttributeError(f"module 'mtmc' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_NAMES})
