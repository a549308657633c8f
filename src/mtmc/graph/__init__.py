"""The measurement graph of Stryczek: places, transitions, arcs and markers.

A directed bipartite graph G = (Π, T, E, M) whose transitions (``meas``, ``point``,
``middle``, ``plane``, ``axis``, ...) bind their variant by the types of their input
places, validated before running and evaluated in topological generations over whole
batches of Monte Carlo trials. Read from TOML (``docs/graph-format.md``) or from the
Stryczek's assertion database (Table 1), drawn as SVG or DOT, swept over parameter grids with
a surrogate formula fitted to the sweep (Stryczek eq. 31). This package knows nothing of
machines.

Each function has one name, in its module and here: the ones that would be ambiguous at
the top of :mod:`mtmc` carry ``graph`` (``load_graph``, ``check_graph``).
"""

from mtmc.graph.assertions import dumps_assertions, load_assertions, loads_assertions
from mtmc.graph.draw import draw_graph, graph_to_dot
from mtmc.graph.files import load_graph
from mtmc.graph.model import check_graph
from mtmc.graph.ops import rotary_axis
from mtmc.graph.places import Place, ProbeDefaults, Transition
from mtmc.graph.run import GraphResult, PlaceSummary, graph_model, run_graph
from mtmc.graph.structure import Graph, Plan, Step
from mtmc.graph.sweep import Surrogate, SweepResult, fit_surrogate, sweep_graph
from mtmc.graph.toml_format import dump_graph, dumps_graph, loads_graph
from mtmc.graph.units import file_unit, place_dimension, unit_of

__all__: list[str] = [
    "Graph",
    "Plan",
    "Step",
    "Place",
    "Transition",
    "ProbeDefaults",
    "GraphResult",
    "PlaceSummary",
    "check_graph",
    "load_graph",
    "loads_graph",
    "dump_graph",
    "dumps_graph",
    "run_graph",
    "graph_model",
    "rotary_axis",
    "load_assertions",
    "loads_assertions",
    "dumps_assertions",
    "draw_graph",
    "graph_to_dot",
    "sweep_graph",
    "fit_surrogate",
    "SweepResult",
    "Surrogate",
    "place_dimension",
    "file_unit",
    "unit_of",
]
