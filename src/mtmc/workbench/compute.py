"""What the workbench computes, each a call of the library as ``mtmc graph`` makes it.

No maths here: the graph is read by the graph's own parser and checked by
:func:`mtmc.graph.check_graph` (the messages of ``mtmc graph check``), run by
:func:`mtmc.graph.run_graph` (randomised quasi-Monte Carlo, a fixed seed) and by
:func:`mtmc.gum` on the graph's own model (every place at once, so one batched call
gives every sensitivity), compared by :func:`mtmc.validate`; the full run is a ``graph``
study (:func:`mtmc.study.loads_study`) written by :func:`mtmc.study.write_result`. This
module turns their results into the JSON the page shows, each number in the file's unit
and rounded as the report rounds it (:func:`mtmc.report.at_place`).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mtmc.errors import ConditioningWarning, MtmcError
from mtmc.graph import GraphResult, Plan, check_graph, loads_graph, run_graph
from mtmc.graph.draw import layout
from mtmc.graph.ops import OP_PARAMS, op_names, variants
from mtmc.graph.places import PLACE_TYPES, VALUE_TYPES
from mtmc.graph.run import GraphModel
from mtmc.graph.units import file_unit
from mtmc.report import at_place
from mtmc.uncertainty.propagation import GumResult, gum, validate
from mtmc.workbench.view import node_of_error

__all__ = [
    "LIVE_SEED",
    "LIVE_TRIALS",
    "arc_refusal",
    "check_text",
    "full_run",
    "live_run",
    "palette",
    "positions",
]

#: Trials of the live run: one Sobol block of 2¹⁴ points (randomised quasi-Monte Carlo).
LIVE_TRIALS = 2**14
#: The seed of the live run: fixed, so an edit changes the numbers only by what it changes.
LIVE_SEED = 20240601
#: Coverage probability of the intervals and the JCGM 101 §8 comparison shown.
P = 0.95


def palette() -> dict[str, Any]:
    """The place types and ops, with the input types each variant of an op accepts.

    Returns
    -------
    dict
        ``{"place_types", "value_types", "ops": {op: {"params", "variants": [{"inputs",
        "rest", "min_rest", "suffix", "output", "doc"}]}}}``.
    """
    ops = {}
    for op in op_names():
        ops[op] = {
            "params": list(OP_PARAMS.get(op, ())),
            "variants": [
                {
                    "inputs": list(v.inputs),
                    "rest": v.rest,
                    "min_rest": v.min_rest,
                    "suffix": list(v.suffix),
                    "output": v.output,
                    "doc": v.doc,
                }
                for v in variants(op)
            ],
        }
    return {"place_types": list(PLACE_TYPES), "value_types": list(VALUE_TYPES), "ops": ops}


def _error(exc: MtmcError, text: str) -> dict[str, Any]:
    return {
        "message": str(exc),
        "text": exc.message,
        "node": node_of_error(exc, text),
        "field": exc.field,
        "line": exc.line,
    }


def check_text(text: str, file: str) -> tuple[Plan | None, dict[str, Any]]:
    """Read and check a graph's TOML text, as ``mtmc graph check`` does.

    Parameters
    ----------
    text : str
        The TOML text.
    file : str
        The file's name, for the messages.

    Returns
    -------
    plan : Plan or None
        The checked graph, or None if it has an error.
    report : dict
        ``{"ok", "errors": [{"message", "text", "node", "field", "line"}], "warnings",
        "types", "generations"}``: ``message`` as ``mtmc graph check`` prints it,
        ``text`` without the file and line, ``node`` the place or transition concerned.
    """
    try:
        with warnings.catch_warnings():  # the page shows them from plan.warnings
            warnings.simplefilter("ignore", ConditioningWarning)
            plan = check_graph(loads_graph(text, file=file, validate=False))
    except MtmcError as exc:
        return None, {"ok": False, "errors": [_error(exc, text)], "warnings": []}
    return plan, {
        "ok": True,
        "errors": [],
        "warnings": list(plan.warnings),
        "types": dict(plan.types),
        "generations": [list(g) for g in plan.generations],
    }


def positions(plan: Plan | None) -> dict[str, list[float]]:
    """Where to draw each node: the stored ``pos``, else :func:`mtmc.graph.draw.layout`."""
    if plan is None:
        return {}
    return {n: [float(x), float(y)] for n, (x, y) in layout(plan).items()}


def _model(plan: Plan, names: Sequence[str]) -> tuple[Any, dict[str, Any]]:
    """The graph's model of every place in ``names``, its components side by side."""
    compiled = GraphModel(plan, tuple(names))

    def model(**arrays: Any) -> NDArray[Any]:
        out = compiled(**arrays)
        cols = [np.asarray(out[n]) for n in names]
        m = cols[0].shape[0]
        return np.concatenate([c.reshape(m, -1) for c in cols], axis=1)

    return model, dict(compiled.inputs)


def _gum_all(plan: Plan, names: list[str]) -> tuple[GumResult | None, str]:
    """One GUM over every place (components side by side), or why there is none."""
    model, inputs = _model(plan, names)
    try:
        result = gum(model, inputs, p=P)
    except MtmcError as exc:
        return None, exc.message
    return result, ""


def _place(
    plan: Plan, res: GraphResult, name: str, g: GumResult | None, start: int
) -> dict[str, Any]:
    s = res.places[name]
    parts = []
    col = start
    for part in s.parts:
        r = s.part(part)
        est, u = r.estimate_vector, r.u_vector
        scale, unit = file_unit(plan, name, part)
        k = est.size
        gu = g.u_vector[col : col + k] if g is not None else None
        parts.append(
            {
                "part": part,
                "unit": unit,
                "estimate": [at_place(e / scale, x / scale) for e, x in zip(est, u, strict=True)],
                "u": [at_place(x / scale, x / scale, the_u=True) for x in u],
                "u_value": [float(x / scale) for x in u],
                "gum_u": (
                    None if gu is None else [at_place(x / scale, x / scale, the_u=True) for x in gu]
                ),
                "gum_u_value": None if gu is None else [float(x / scale) for x in gu],
            }
        )
        col += k
    return {"type": s.type, "parts": parts}


def live_run(
    text: str,
    file: str,
    *,
    selected: str | None = None,
    trials: int = LIVE_TRIALS,
    seed: int = LIVE_SEED,
) -> dict[str, Any]:
    """Check the graph, run a short Monte Carlo and the GUM of every place.

    Parameters
    ----------
    text : str
        The graph's TOML text.
    file : str
        The file's name, for messages.
    selected : str, optional
        A place whose summary to add (its samples are kept for the intervals).
    trials : int
        Monte Carlo trials (randomised quasi-Monte Carlo, ``sampling="sobol"``).
    seed : int
        The seed.

    Returns
    -------
    dict
        :func:`check_text`'s report, with ``"positions"`` and, when the graph checks,
        ``"places": {name: {"type", "parts": [{"part", "unit", "estimate", "u",
        "gum_u"}]}}`` (texts rounded as the report rounds them, in the file's units),
        ``"summary"`` of the selected place, ``"trials"``, ``"seed"``, ``"gum"`` (how
        the sensitivities were computed, or why there is no GUM) and ``"seconds"``.
    """
    t0 = time.perf_counter()
    plan, out = check_text(text, file)
    out["positions"] = positions(plan)
    if plan is None:
        return out
    names = list(plan.types)
    keep = [selected] if selected is not None and selected in plan.types else []
    try:
        res = run_graph(plan, trials, seed, keep=keep, sampling="sobol")
    except MtmcError as exc:
        out.update(ok=False, errors=[_error(exc, text)])
        return out
    g, why = _gum_all(plan, names)
    places = {}
    start = 0
    starts = {}
    for n in names:
        starts[n] = start
        places[n] = _place(plan, res, n, g, start)
        start += res.places[n].estimate_vector.size
    out.update(
        places=places,
        trials=res.trials,
        seed=res.seed,
        sampling="sobol",
        gum=why or (g.method if g is not None else ""),
    )
    if keep:
        out["summary"] = _summary(plan, res, keep[0], g, starts[keep[0]])
    out["seconds"] = time.perf_counter() - t0
    return out


def _summary(
    plan: Plan, res: GraphResult, name: str, g: GumResult | None, start: int
) -> dict[str, Any]:
    """Per component: MC interval, GUM u, k, interval, the §8 verdict and the budget."""
    mc = res.result(name)
    s = res.places[name]
    rows = []
    col = 0
    for part in s.parts:
        scale, unit = file_unit(plan, name, part)
        k = s.part(part).estimate_vector.size
        for j in range(k):
            label = part if k == 1 else f"{part}[{'xyz'[j] if k == 3 else j}]"
            if label.startswith("value"):
                label = "value" if k == 1 else label[len("value") :].strip("[]")
            m = mc.component(col) if mc.dim else mc
            u = m.u
            lo, hi = m.coverage_interval(P)
            row: dict[str, Any] = {
                "component": label,
                "unit": unit,
                "estimate": at_place(m.estimate / scale, u / scale),
                "u": at_place(u / scale, u / scale, the_u=True),
                "interval": [at_place(lo / scale, u / scale), at_place(hi / scale, u / scale)],
            }
            if g is not None:
                gc = g.component(start + col)
                glo, ghi = gc.coverage_interval()
                v = validate(gc, m, p=P)
                row["gum"] = {
                    "estimate": at_place(gc.estimate / scale, gc.u / scale),
                    "u": at_place(gc.u / scale, gc.u / scale, the_u=True),
                    "k": round(float(gc.coverage_factor()), 3),
                    "interval": [
                        at_place(glo / scale, gc.u / scale),
                        at_place(ghi / scale, gc.u / scale),
                    ],
                    "validated": bool(v.passed),
                    "budget": _budget(gc, scale),
                }
            rows.append(row)
            col += 1
    return {
        "place": name,
        "type": s.type,
        "p": P,
        "trials": res.trials,
        "components": rows,
        "regions": _regions(plan, s.type, np.asarray(mc.samples), name),
    }


def _regions(plan: Plan, type_: str, values: Any, name: str) -> list[dict[str, Any]]:
    """The coverage regions of a point, direction, line or circle (JCGM 102 §7.7).

    A point or vector: its ellipsoid in space; a direction: the ellipse of its tilt in the
    plane normal to it; a line or circle: the ellipse of its point (centre) in the plane
    normal to its direction (normal), and of the tilt of that direction, as the report
    draws them (:mod:`mtmc.study.graph`). Semi-axes in the file's unit (rad for a tilt),
    the factor ``k`` of the Monte Carlo region (JCGM 102 §7.7.2).
    """
    from mtmc.graph.values import normal_plane_parts
    from mtmc.uncertainty.results import MonteCarloResult

    v = np.asarray(values, dtype=np.float64)
    if v.ndim != 2 or v.shape[0] < 3:
        return []
    length = plan.graph.units
    factor = plan.graph.factor
    sets: list[tuple[str, Any, str, float]] = []
    if type_ in ("point", "vector"):
        sets.append((f"{name} in space", v[:, 0:3], length, factor))
    for part, xy in normal_plane_parts(type_, v):
        if part in ("point", "centre"):
            sets.append((f"{part} of {name}, normal to it", xy, length, factor))
        else:
            of = name if part == "value" else f"the {part} of {name}"
            sets.append((f"tilt of {of}", xy, "rad", 1.0))
    out = []
    for label, xs, unit, scale in sets:
        try:
            ell = MonteCarloResult.from_samples(xs, seed=None).coverage_ellipsoid(P)
        except MtmcError:  # a singular covariance: no region
            continue
        semi = np.sort(np.asarray(ell.semi_axes))[::-1] / scale
        out.append(
            {
                "region": label,
                "unit": unit,
                "k": round(float(ell.k), 3),
                "semi_axes": [at_place(a, a, the_u=True) for a in semi],
                "semi_axes_value": [float(a) for a in semi],
            }
        )
    return out


def _budget(g: GumResult, scale: float) -> list[dict[str, Any]]:
    """The budget lines that contribute, largest first (at most 12)."""
    lines = []
    for e in g.budget:
        share = float(np.sum(e.share))
        if share <= 0.0:
            continue
        contribution = float(np.sqrt(np.sum(np.square(e.contribution))))
        lines.append(
            {
                "input": e.name,
                "contribution": at_place(contribution / scale, contribution / scale, the_u=True),
                "share": round(100.0 * share, 1),
            }
        )
    lines.sort(key=lambda d: -float(str(d["share"])))
    return lines[:12]


def _types_of(view: dict[str, Any], types: dict[str, str]) -> dict[str, str]:
    out = dict(types)
    for p in view.get("places", []):
        if isinstance(p.get("type"), str) and p.get("declared", True):
            out.setdefault(p["name"], p["type"])
    return out


def arc_refusal(
    view: dict[str, Any], source: str, target: str, types: dict[str, str]
) -> str | None:
    """Why an arc from ``source`` to ``target`` cannot be drawn, or None if it can.

    The rules of the graph (:func:`mtmc.graph.check_graph`) that an arc alone decides:
    an arc joins a place and a transition (Stryczek's bipartite graph); a place has at
    most one producer and is not both marked and produced; a transition has one output;
    ``meas`` takes no input; an op takes no more inputs, nor inputs of other types, than
    one of its variants accepts.

    Parameters
    ----------
    view : dict
        The graph view (:func:`mtmc.workbench.view.graph_json`).
    source, target : str
        Node names.
    types : dict
        The types of the places, as last checked (a declared type wins).

    Returns
    -------
    str or None
        The refusal, one line.
    """
    places = {p["name"]: p for p in view.get("places", [])}
    trans = {t["name"]: t for t in view.get("transitions", [])}
    for t in trans.values():  # a produced place may be left undeclared
        if isinstance(t.get("out"), str) and t["out"] and t["out"] not in places:
            places[t["out"]] = {"name": t["out"]}
    if source == target:
        return f"an arc joins two nodes; {source} to itself is none"
    if source not in places and source not in trans:
        return f"no place or transition {source!r}"
    if target not in places and target not in trans:
        return f"no place or transition {target!r}"
    if (source in places) == (target in places):
        what = "places" if source in places else "transitions"
        return (
            f"an arc joins a place and a transition (the graph is bipartite); "
            f"{source} and {target} are both {what}"
        )
    if source in trans:
        return _output_refusal(trans, source, places[target])
    return _input_refusal(trans[target], source, _types_of(view, types))


def _output_refusal(trans: dict[str, Any], source: str, p: dict[str, Any]) -> str | None:
    """Why the transition ``source`` cannot produce the place ``p``, or None."""
    t, target = trans[source], p["name"]
    if t.get("out"):
        return f"transition {source} already has its output {t['out']}: one output each"
    for other in trans.values():
        if other.get("out") == target:
            return f"place {target} is already produced by {other['name']}: one producer each"
    if any(p.get(k) is not None for k in ("value", "u", "dist")):
        return f"place {target} is marked (it has a value): a transition cannot produce it"
    return None


def _input_refusal(t: dict[str, Any], name: str, types: dict[str, str]) -> str | None:
    """Why the place ``name`` cannot be the next input of the transition ``t``, or None."""
    target = t["name"]
    op = t.get("op")
    vs = variants(op) if isinstance(op, str) else ()
    if not vs:
        return f"transition {target}: unknown op {op!r}"
    if op == "meas":
        return "op meas takes no input: it measures its point at and direction"
    inputs = list(t.get("in", []))
    new = [*[types.get(i, "?") for i in inputs], types.get(name, "?")]
    if "?" in new:
        most = max(v.max_inputs for v in vs)
        if len(new) > most:
            return f"op {op} takes at most {int(most)} inputs"
        return None
    if not any(v.accepts_prefix(new) for v in vs):
        sigs = "; ".join(sorted({v.signature for v in vs}))
        return f"op {op} accepts no inputs of types ({', '.join(new)}); it accepts {sigs}"
    return None


def full_run(
    graph_path: Path, title: str, outputs: list[str], trials: int, seed: int | None
) -> Path:
    """Run the saved graph file as a ``graph`` study and write its result folder.

    The study is the text ``mtmc run`` would read (``kind = "graph"``, the file, the
    outputs, ``[run]`` trials and seed); the folder ``<stem>-result`` beside the graph
    file gets ``result.json``, the tables, ``provenance.json`` and ``report.html``.

    Parameters
    ----------
    graph_path : Path
        The saved graph file.
    title : str
        The study's title.
    outputs : list of str
        The places to report.
    trials : int
        Monte Carlo trials.
    seed : int or None
        The seed (None: fresh entropy, recorded).

    Returns
    -------
    Path
        The result folder.
    """
    from mtmc.graph.toml_format import toml_string
    from mtmc.study import loads_study, write_result

    lines = [
        'kind = "graph"',
        f"title = {toml_string(title or graph_path.stem)}",
        f"graph = {toml_string(graph_path.name)}",
        f"outputs = [{', '.join(toml_string(o) for o in outputs)}]",
        "",
        "[run]",
        f"trials = {int(trials)}",
    ]
    if seed is not None:
        lines.append(f"seed = {int(seed)}")
    text = "\n".join(lines) + "\n"
    # the study exists only as this text: its errors name the graph file's full run
    study = loads_study(text, file=f"full run of {graph_path.name}", folder=graph_path.parent)
    result = study.run()
    dest = graph_path.parent / f"{graph_path.stem}-result"
    argv = ["mtmc", "graph", "edit", str(graph_path), "(full run)"]
    write_result(result, dest, study_text=text, argv=argv)
    return dest
