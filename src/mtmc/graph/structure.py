"""The measurement graph G = (Π, T, E, M) of Stryczek (eq. 7) and its plan, as data.

A :class:`Graph` holds what a graph file says; :func:`mtmc.graph.model.check_graph`
validates it into a :class:`Plan` (every place's type, the firing order as its steps,
:class:`Step`), which the nominal check, the units and a run read.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from types import MappingProxyType

from mtmc.errors import GraphError
from mtmc.frozen import frozen_mapping
from mtmc.graph import ops
from mtmc.graph.places import Place, ProbeDefaults, Transition

__all__ = ["LENGTH_UNITS", "Graph", "Plan", "Step"]

#: Length units a graph file may use, and their size in mm.
LENGTH_UNITS: Mapping[str, float] = MappingProxyType({"mm": 1.0, "um": 1e-3})


@dataclass(frozen=True)
class Graph:
    """A measurement graph as written in a file (Stryczek, eq. 7).

    Parameters
    ----------
    places : tuple of Place
        The declared places (places produced by a transition may be left implicit).
    transitions : tuple of Transition
        The transitions, with their arcs.
    title : str
        A title.
    units : str
        Length unit of the numbers in the graph: ``"mm"`` (default) or ``"um"``.
    probe : ProbeDefaults
        Defaults of the touch-probe model for every ``meas``.
    file : str, optional
        Source file name, used in error messages (not part of equality).
    """

    places: tuple[Place, ...] = ()
    transitions: tuple[Transition, ...] = ()
    title: str = ""
    units: str = "mm"
    probe: ProbeDefaults = field(default_factory=ProbeDefaults)
    file: str | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "places", tuple(self.places))
        object.__setattr__(self, "transitions", tuple(self.transitions))
        if self.units not in LENGTH_UNITS:
            raise GraphError(
                f"unknown units {self.units!r}; expected one of {', '.join(LENGTH_UNITS)}",
                file=self.file,
                field="units",
            )

    @property
    def factor(self) -> float:
        """The graph's length unit in mm."""
        return LENGTH_UNITS[self.units]

    @cached_property
    def _places_by_name(self) -> dict[str, Place]:
        out: dict[str, Place] = {}
        for p in self.places:
            out.setdefault(p.name, p)  # the first, as a scan would find it
        return out

    @cached_property
    def _transitions_by_name(self) -> dict[str, Transition]:
        out: dict[str, Transition] = {}
        for t in self.transitions:
            out.setdefault(t.name, t)
        return out

    def place(self, name: str) -> Place | None:
        """The declared place ``name``, or None."""
        return self._places_by_name.get(name)

    def transition(self, name: str) -> Transition | None:
        """The transition ``name``, or None."""
        return self._transitions_by_name.get(name)


@dataclass(frozen=True)
class Step:
    """One transition in firing order, with the variant it binds.

    Parameters
    ----------
    transition : Transition
        The transition.
    variant : ops.Variant
        The bound variant.
    generation : int
        Its topological generation (0: fires first).
    """

    transition: Transition
    variant: ops.Variant
    generation: int


@dataclass(frozen=True)
class Plan:
    """A validated graph, ready to run.

    Parameters
    ----------
    graph : Graph
        The graph.
    types : mapping of str to str
        The type of every place (declared or implied); copied into a read-only mapping.
    steps : tuple of Step
        The transitions in firing order.
    producer : mapping of str to str
        The transition producing each produced place; copied into a read-only mapping.
    warnings : tuple of str
        One line per construction that is badly conditioned at the nominal values
        (:func:`mtmc.graph.nominal.check_nominal`).
    """

    graph: Graph
    types: Mapping[str, str]
    steps: tuple[Step, ...]
    producer: Mapping[str, str]
    warnings: tuple[str, ...] = field(default=(), compare=False)
    #: The dimension of the value of each place met so far (:mod:`mtmc.graph.units`
    #: fills it as it is asked): a place's dimension follows from those of its
    #: producer's inputs, so that asking for every place of a chain is linear in its length.
    dimensions: dict[str, tuple[int, int]] = field(
        default_factory=dict, init=False, compare=False, repr=False
    )

    def __post_init__(self) -> None:
        object.__setattr__(self, "types", frozen_mapping(self.types))
        object.__setattr__(self, "producer", frozen_mapping(self.producer))
        object.__setattr__(self, "steps", tuple(self.steps))

    @property
    def marked(self) -> tuple[str, ...]:
        """The places marked from the start (M0)."""
        return tuple(p.name for p in self.graph.places if p.marked)

    @property
    def generations(self) -> tuple[tuple[str, ...], ...]:
        """The transition names by topological generation."""
        n = max((s.generation for s in self.steps), default=-1) + 1
        return tuple(
            tuple(s.transition.name for s in self.steps if s.generation == g) for g in range(n)
        )
