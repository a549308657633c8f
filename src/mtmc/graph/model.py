"""The measurement graph G = (Π, T, E, M) of Stryczek (eq. 7): validation and firing order.

A :class:`Graph` holds what a graph file says. :func:`check` validates it and returns a
:class:`Plan`: the type of every place (declared, or implied by the op that produces it),
the variant each transition binds by the types of its inputs, and the firing order.

Markers (Stryczek): the places with a value are marked from the start (the set M0); a
transition fires once per simulation cycle, when all its input places are marked, and
marks its output place. The firing order is therefore a topological order of the
bipartite graph; it is taken by generations (the transitions whose inputs are all marked
at the start, then those enabled by them, ...), sorted by name within each generation,
so every run repeats exactly.

Validation errors (:class:`mtmc.errors.GraphError`) name the place or transition, the file
and the line: a transition arc joining two transitions or a place to a place (not
bipartite), a cycle, an input never marked nor produced, two producers of one place, a
marked place that a transition also produces, a type no variant of the op accepts, an
unknown op or field, a ``meas`` without a valid ``at``/``direction``/``u``/``dist``, a
``dist`` that does not parse.
"""

from __future__ import annotations

from mtmc.errors import GraphError, MtmcError
from mtmc.graph import ops
from mtmc.graph.nominal import check_nominal
from mtmc.graph.places import COORDINATE_TYPES, Place, Transition
from mtmc.graph.structure import Graph, Plan, Step

__all__ = ["check_graph"]


def _err(graph: Graph, msg: str, line: int | None, fld: str | None = None) -> GraphError:
    return GraphError(msg, file=graph.file, line=line, field=fld)


def check_graph(graph: Graph, *, nominal: bool = True) -> Plan:
    """Validate a graph and compute its types, bound variants and firing order.

    With ``nominal`` (default) the nominal configuration is then checked too
    (:func:`mtmc.graph.nominal.check_nominal`): every transition is fired once without
    noise, a degenerate construction or a rotary-axis angle that does not match its ball
    centres is refused, and a badly conditioned construction is reported in
    ``Plan.warnings`` (and as a :class:`mtmc.graph.nominal.ConditioningWarning`).

    Parameters
    ----------
    graph : Graph
        The graph.
    nominal : bool
        Also check the nominal configuration (default).

    Returns
    -------
    Plan
        The validated plan.

    Raises
    ------
    GraphError
        On the first problem found, naming the place or transition, the file and line.
    DegenerateGeometryError
        If a construction is degenerate at the nominal values (naming the transition).

    Examples
    --------
    >>> g = Graph(
    ...     places=(Place("a", "real", 1.0), Place("b", "real", 2.0)),
    ...     transitions=(Transition("t1", "middle", ("a", "b"), "c"),),
    ... )
    >>> plan = check_graph(g)
    >>> plan.types["c"], plan.generations
    ('real', (('t1',),))
    >>> check_graph(g) is plan  # a graph is immutable: checked once, its plan kept
    True
    """
    if nominal:
        done = graph.__dict__.get("_plan")
        if done is not None:
            if done.warnings:
                import warnings

                from mtmc.graph.nominal import ConditioningWarning

                for note in done.warnings:
                    warnings.warn(note, ConditioningWarning, stacklevel=2)
            return done  # type: ignore[no-any-return]
    plan = _check(graph, nominal)
    if nominal:
        object.__setattr__(graph, "_plan", plan)
    return plan


def _check(graph: Graph, nominal: bool) -> Plan:
    """:func:`check` without the kept plan."""
    places, trans = _index(graph)
    producer = _check_arcs(graph, places, trans)
    _check_marking(graph, places, producer)
    order = _firing_order(graph, trans)
    types, steps = _bind(graph, order)
    plan = Plan(graph, types, tuple(steps), producer)
    if not nominal:
        return plan

    report = check_nominal(plan)
    return Plan(graph, types, tuple(steps), producer, report.warnings)


def _index(graph: Graph) -> tuple[dict[str, Place], dict[str, Transition]]:
    """The places and transitions by name, each name declared once."""
    if not graph.transitions:
        raise _err(graph, "the graph has no transition", None, "transition")
    places: dict[str, Place] = {}
    for p in graph.places:
        if p.name in places:
            raise _err(graph, f"place {p.name} is declared twice", p.line, "name")
        places[p.name] = p
    trans: dict[str, Transition] = {}
    for t in graph.transitions:
        if t.name in trans:
            raise _err(graph, f"transition {t.name} is declared twice", t.line, "name")
        if t.name in places:
            raise _err(
                graph,
                f"transition {t.name}: the name is also a place; places and transitions "
                "are separate sets",
                t.line,
                "name",
            )
        trans[t.name] = t
    return places, trans


def _check_arcs(
    graph: Graph, places: dict[str, Place], trans: dict[str, Transition]
) -> dict[str, str]:
    """Arcs bipartite, op and fields known, one producer per place: the producer of each."""
    producer: dict[str, str] = {}
    for t in graph.transitions:
        _check_transition(graph, t, places, trans, producer)
        producer[t.out] = t.name
    return producer


def _check_transition(
    graph: Graph,
    t: Transition,
    places: dict[str, Place],
    trans: dict[str, Transition],
    producer: dict[str, str],
) -> None:
    """The arcs, op and fields of one transition (``producer``: the places produced so far)."""
    for q in (*t.inputs, t.out):
        if q in trans:
            fld = "out" if q == t.out else "in"
            raise _err(
                graph,
                f"transition {t.name}: {q} is a transition; the graph is bipartite, an arc "
                "joins a place and a transition",
                t.field_line(fld),
                fld,
            )
    if not ops.variants(t.op):
        raise _err(
            graph,
            f"transition {t.name}: unknown op {t.op!r}; "
            f"expected one of {', '.join(ops.op_names())}",
            t.field_line("op"),
            "op",
        )
    allowed = ops.OP_PARAMS.get(t.op, ())
    for key, _ in t.params:
        if key not in allowed:
            hint = (
                f"; op {t.op} takes {', '.join(allowed)}"
                if allowed
                else f"; op {t.op} takes no other field"
            )
            raise _err(
                graph,
                f"transition {t.name}: unknown field {key!r}{hint}",
                t.field_line(key),
                key,
            )
    if t.op == "meas" and t.inputs:
        raise _err(graph, f"transition {t.name}: meas takes no input", t.field_line("in"), "in")
    if t.out in t.inputs:
        raise _err(
            graph,
            f"transition {t.name}: {t.out} is both input and output (a cycle)",
            t.field_line("out"),
            "out",
        )
    if t.out in producer:
        raise _err(
            graph,
            f"transition {t.name}: place {t.out} is already produced by {producer[t.out]}; "
            "a place has at most one producer",
            t.field_line("out"),
            "out",
        )
    if t.out in places and places[t.out].marked:
        raise _err(
            graph,
            f"transition {t.name}: place {t.out} is marked from the start (has a value) "
            "and cannot also be produced",
            t.field_line("out"),
            "out",
        )


def _check_marking(graph: Graph, places: dict[str, Place], producer: dict[str, str]) -> None:
    """Every input marked or produced, every place used, every place ``dist`` parsed."""
    for t in graph.transitions:
        for q in t.inputs:
            if q not in producer and not (q in places and places[q].marked):
                why = "is declared without a value" if q in places else "is not declared"
                raise _err(
                    graph,
                    f"transition {t.name}: input place {q} {why} and no transition produces it "
                    "(never marked)",
                    t.field_line("in"),
                    "in",
                )
    used = {q for t in graph.transitions for q in t.inputs}
    for p in graph.places:
        if p.name not in producer and p.name not in used and not p.marked:
            raise _err(
                graph, f"place {p.name} is neither marked, produced nor used", p.line, "name"
            )
    for p in graph.places:
        if p.dist is not None:
            from mtmc.uncertainty.distributions import parse_distribution

            try:
                parse_distribution(p.dist)
            except MtmcError as exc:
                raise _err(graph, f"place {p.name}: {exc.message}", p.line, "dist") from None


def _firing_order(graph: Graph, trans: dict[str, Transition]) -> list[tuple[Transition, int]]:
    """The transitions with their generation, by generations (Kahn), by name within each."""
    marked = {p.name for p in graph.places if p.marked}
    remaining = dict(trans)
    order: list[tuple[Transition, int]] = []
    gen = 0
    while remaining:
        ready = sorted(n for n, t in remaining.items() if all(p in marked for p in t.inputs))
        if not ready:
            name = sorted(remaining)[0]
            t = remaining[name]
            raise _err(
                graph,
                f"transition {t.name}: the graph has a cycle through "
                f"{', '.join(sorted(remaining))}; a measurement graph is a tree (acyclic)",
                t.line,
                "in",
            )
        for n in ready:
            order.append((remaining.pop(n), gen))
        for n in ready:
            marked.add(trans[n].out)
        gen += 1
    return order


def _bind(graph: Graph, order: list[tuple[Transition, int]]) -> tuple[dict[str, str], list[Step]]:
    """The type of every place and the variant of every transition, in firing order."""
    types = {p.name: p.type for p in graph.places}
    steps = []
    for t, g in order:
        in_types = [types[p] for p in t.inputs]
        declared = types.get(t.out)
        want = _meas_output(graph, t, declared) if t.op == "meas" else declared
        try:
            v = ops.bind(t.op, in_types, output=want)
        except MtmcError as exc:
            fld = exc.field or "in"
            raise _err(
                graph, f"transition {t.name}: {exc.message}", t.field_line(fld), fld
            ) from None
        types[t.out] = v.output
        if t.op == "meas":
            from mtmc.graph.probe import meas_spec

            try:
                meas_spec(t, graph.probe, graph.factor)
            except MtmcError as exc:
                raise _err(graph, exc.message, exc.line, exc.field) from None
        steps.append(Step(t, v, g))
    return types, steps


def _meas_output(graph: Graph, t: Transition, declared: str | None) -> str | None:
    """The output type a ``meas`` asks for: its ``coordinate``, else the declared type or point."""
    want = declared
    coord = t.param("coordinate")
    if coord is not None:
        if coord not in COORDINATE_TYPES:
            raise _err(
                graph,
                f"transition {t.name}: coordinate must be x, y or z, got {coord!r}",
                t.field_line("coordinate"),
                "coordinate",
            )
        if declared is not None and declared != coord:
            raise _err(
                graph,
                f"transition {t.name}: coordinate = {coord!r} but place {t.out} "
                f"is declared {declared}",
                t.field_line("coordinate"),
                "coordinate",
            )
        want = coord
    elif declared is None:
        want = "point"
    return want
