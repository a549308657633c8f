"""Study kinds ``graph`` and ``sweep``: a measurement graph (Stryczek) run by Monte Carlo.

``graph``: one Monte Carlo run of the graph for all its output places
(:func:`mtmc.run_graph`), and the GUM once per output place with a vector result (each
output is a model of the graph's random inputs, :func:`mtmc.graph_model`), reported
component by component with the JCGM 101 §8 comparison. Points get their coverage
ellipses in the coordinate planes; an axis (a ``line`` place) gets the ellipse of its
location in the plane normal to it and of its direction (JCGM 102 §7.7; Stryczek Fig. 1).

``sweep`` (or a ``[sweep]`` table in a ``graph`` study): the standard uncertainty of one
scalar place on a grid of probe or place uncertainties (:func:`mtmc.sweep_graph`) and
the surrogate ``u² = c0 + Σ cᵢ σᵢ²`` fitted to it (Stryczek Fig. 14–15, eq. 31), with and
without the constant ``c0``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mtmc.document import Fields, check_number
from mtmc.errors import MtmcError
from mtmc.graph import load_graph
from mtmc.graph.model import check_graph
from mtmc.graph.places import SCALAR_TYPES
from mtmc.graph.run import graph_model, random_inputs, run_graph
from mtmc.graph.structure import Graph, Plan
from mtmc.graph.sweep import Surrogate, apply_setting, sweep_graph
from mtmc.graph.units import file_unit, place_dimension, unit_of
from mtmc.graph.values import PARTS, normal_plane_parts
from mtmc.study.base import ProgressFn, Study
from mtmc.study.observations import input_record
from mtmc.study.options import ADAPTIVE, NAN_POLICY, mc_run_record
from mtmc.study.result import Quantity, Region, StudyResult, Table, quantity, region
from mtmc.study.settings import MAX_TRIALS, RunSettings
from mtmc.study.spec import register_kind
from mtmc.uncertainty.propagation import gum
from mtmc.uncertainty.results import MonteCarloResult

__all__ = ["GraphStudy", "SweepSpec", "SweepStudy", "component_names"]


def component_names(place: str, type_: str) -> list[tuple[str, str]]:
    """Names of the scalar components of a place, with the part each belongs to.

    Parameters
    ----------
    place : str
        The place.
    type_ : str
        Its type.

    Returns
    -------
    list of (name, part)
        In the layout of :func:`mtmc.graph.run.flatten`: ``[("d_ac", "value")]`` for a
        scalar, ``[("p.x", "value"), ...]`` for a point, ``[("axis.point.x", "point"),
        ..., ("axis.direction.z", "direction")]`` for a line.

    Examples
    --------
    >>> component_names("s", "sphere")[-1]
    ('s.radius', 'radius')
    """
    out: list[tuple[str, str]] = []
    for part, size in PARTS[type_]:
        base = place if part == "value" else f"{place}.{part}"
        if size == 1:
            out.append((base, part))
        elif size == 3:
            out += [(f"{base}.{c}", part) for c in "xyz"]
        else:  # a rotation matrix, row by row
            out += [(f"{base}.r{i}{j}", part) for i in (1, 2, 3) for j in (1, 2, 3)]
    return out


def _unit(plan: Plan, place: str, part: str) -> str:
    return unit_of(place_dimension(plan, place, part))


def _shown(plan: Plan, place: str, part: str) -> tuple[float, str]:
    """The factor from the library's mm to the graph file's unit, and that unit (µm as µm).

    A study gives its numbers in the unit its graph is written in (``units = "um"``: µm,
    each value in mm times 1000), as ``mtmc graph run`` prints them
    (``docs/results-format.md``, the unit rule).
    """
    scale, unit = file_unit(plan, place, part)
    return 1.0 / scale, unit.replace("um", "µm")


@dataclass(frozen=True)
class SweepSpec:
    """A sweep of a graph: the varied keys and their values, the output, the trials.

    Attributes
    ----------
    output : str
        A scalar place.
    vary : dict of str to ndarray
        Keys of :func:`mtmc.graph.sweep.apply_setting` and their values, in the graph's
        units; the grid is their Cartesian product.
    trials : int
        Trials per grid point (Stryczek: 1000).
    intercept : bool
        Fit ``c0`` too.
    """

    output: str
    vary: dict[str, NDArray[np.float64]]
    trials: int
    intercept: bool


def _surrogate_dict(fit: Surrogate) -> dict[str, Any]:
    return {
        "names": list(fit.names),
        "c0": fit.c0,
        "coefficients": fit.coefficients,
        "rel_errors": fit.rel_errors,
        "max_rel_error": fit.max_rel_error,
        "formula": fit.formula(),
    }


@dataclass(frozen=True)
class GraphStudy(Study):
    """A measurement graph with the places to report (kind ``graph``).

    Attributes
    ----------
    graph : Graph
        The graph (checked).
    graph_text : str
        The text of the graph file (kept in the result, for the drawing).
    outputs : tuple of str
        The places to run by Monte Carlo and the GUM.
    sweep : SweepSpec or None
        An optional sweep of one scalar place.
    """

    kind = "graph"
    run_options = frozenset({ADAPTIVE, NAN_POLICY})
    graph: Graph
    graph_text: str
    outputs: tuple[str, ...]
    sweep: SweepSpec | None

    def execute(self, settings: RunSettings, progress: ProgressFn | None) -> StudyResult:
        """Monte Carlo and GUM of every output, then the sweep (module docstring)."""
        plan = check_graph(self.graph)
        quantities: list[Quantity] = []
        regions: list[Region] = []
        samples: dict[str, NDArray[np.float64]] = {}
        n_grid = 0
        if self.sweep is not None:
            n_grid = int(np.prod([len(v) for v in self.sweep.vary.values()]))
        grid_trials = n_grid * (self.sweep.trials if self.sweep else 0)
        # an adaptive run does not know its number of trials until it stops
        total = None if settings.adaptive else settings.trials + grid_trials
        # one Monte Carlo of the whole graph for every output (each trial fires every
        # transition once), then the GUM once per output, its vector result cut into the
        # components the report shows
        res = run_graph(
            plan,
            seed=settings.seed,
            outputs=self.outputs,
            keep=self.outputs,
            progress=_offset(progress, 0, total),
            **settings.engine,
        )
        for out in self.outputs:
            mc = res.places[out].result
            vals = np.asarray(mc.samples, dtype=np.float64).reshape(res.trials, -1)
            if settings.samples:
                samples[out] = np.asarray(mc.samples)
            model, inputs = graph_model(plan, out)
            g = gum(model, inputs, p=settings.p)
            for j, (name, part) in enumerate(component_names(out, plan.types[out])):
                q_mc = MonteCarloResult(
                    samples=vals[:, j], trials=res.trials, seed=res.seed, omitted=res.omitted
                )
                g_j = g.component(j) if g.dim else g
                q = quantity(name, _unit(plan, out, part), q_mc, g_j, settings)
                factor, unit = _shown(plan, out, part)
                quantities.append(q if factor == 1.0 else q.in_unit(unit, factor))
            regions += self._regions(plan, out, vals, settings.p)
        extra: dict[str, Any] = {
            "graph": {"file": self.graph.file, "title": self.graph.title, "toml": self.graph_text}
        }
        tables: list[Table] = []
        if self.sweep is not None:
            step = _offset(progress, res.trials, res.trials + grid_trials)
            sweep_d, table = self._sweep(settings, step)
            extra["sweep"] = sweep_d
            tables.append(table)
        in_list = tuple(input_record(n, d) for n, d in random_inputs(plan).items())
        run = mc_run_record(settings, res)
        return self._result(
            settings,
            run=run,
            quantities=tuple(quantities),
            regions=tuple(regions),
            tables=tuple(tables),
            inputs=in_list,
            extra=extra,
            samples=samples,
        )

    def _regions(self, plan: Plan, out: str, vals: NDArray[np.float64], p: float) -> list[Region]:
        type_ = plan.types[out]
        found: list[Region | None] = []
        if type_ in ("point", "vector"):
            factor, unit = _shown(plan, out, "value")
            for a, b in ((0, 1), (0, 2), (1, 2)):
                la, lb = "xyz"[a], "xyz"[b]
                ab = factor * vals[:, [a, b]]
                found.append(region(f"{out}: {la}, {lb}", (la, lb), unit, ab, p))
        else:
            for part, xy in normal_plane_parts(type_, vals):
                if part in ("point", "centre"):
                    factor, unit = _shown(plan, out, part)
                    label = f"{out}: {part} in the plane normal to the axis"
                    found.append(region(label, ("e1", "e2"), unit, factor * xy, p))
                else:  # the tilt of a direction, a line's direction or a circle's normal
                    name = f"{out}: {part} (its tilt in the plane normal to it)"
                    if part == "value":
                        name = f"{out}: its tilt in the plane normal to it"
                    found.append(region(name, ("e1", "e2"), "rad", xy, p))
        return [r for r in found if r is not None]

    def _sweep(
        self, settings: RunSettings, progress: ProgressFn | None
    ) -> tuple[dict[str, Any], Table]:
        spec = self.sweep
        assert spec is not None
        sw = sweep_graph(
            self.graph,
            spec.vary,
            spec.output,
            trials=spec.trials,
            seed=settings.seed,
            progress=progress,
            nan_policy=settings.nan_policy,
            **settings.parallel,
        )
        fit = sw.fit(intercept=spec.intercept)
        fit0 = sw.fit(intercept=False)
        pred = fit.predict(sw.grid)
        plan = check_graph(self.graph)
        # in the graph file's units (the unit rule): the grid as the file gives it, u from
        # the library's mm times f (1 for a graph in mm, 1000 for one in um), the
        # surrogate u² = c0 + Σ cᵢ σᵢ² (σ in the grid's unit) with c0 and cᵢ times f²
        f, unit = _shown(plan, sw.output, "value")
        grid_unit = "µm" if self.graph.units == "um" else "mm"
        d = {
            "output": sw.output,
            "unit": unit,
            "names": list(sw.names),
            "grid_unit": grid_unit,
            "grid": sw.grid,
            "u": f * sw.u,
            "estimate": f * sw.estimate,
            "u_surrogate": f * pred,
            "trials": sw.trials,
            "omitted": sw.omitted,
            "seed": sw.seed,
            "surrogate": _surrogate_dict(_in_unit(fit, f)),
            "surrogate_no_intercept": _surrogate_dict(_in_unit(fit0, f)),
            "surface": _surface(fit, sw.grid, f),
        }
        rows = tuple(
            (
                *(float(x) for x in sw.grid[i]),
                float(f * sw.estimate[i]),
                float(f * sw.u[i]),
                float(f * pred[i]),
                float(fit.rel_errors[i]),
            )
            for i in range(len(sw.u))
        )
        table = Table(
            "sweep",
            f"u({sw.output}) on the grid, {sw.trials} trials per point, and the surrogate",
            (
                *(f"{n} / {grid_unit}" for n in sw.names),
                *(f"{c} / {d['unit']}" for c in ("estimate", "u", "u_surrogate")),
                "rel_error",
            ),
            rows,
        )
        return d, table


def _in_unit(fit: Surrogate, f: float) -> Surrogate:
    """The surrogate of ``f`` times ``u``: ``c0`` and the ``cᵢ`` times ``f²`` (f = 1: itself)."""
    if f == 1.0:
        return fit
    return replace(fit, c0=fit.c0 * f**2, coefficients=fit.coefficients * f**2)


def _surface(fit: Surrogate, grid: NDArray[np.float64], f: float) -> dict[str, Any]:
    """The surrogate on a fine grid over the swept box, for the report to draw.

    Two varied parameters: ``axes``, two arrays of 30 values, and ``u``, 30 × 30; otherwise
    a curve along the first parameter (the others at the first grid point): ``axes``, one
    array of 200 values, and ``u`` (200,). Parameters in the unit of ``grid``, ``u`` times
    ``f`` (the factor from mm to the unit of the sweep's ``u``).
    """
    if grid.shape[1] == 2:
        axes = [np.linspace(grid[:, i].min(), grid[:, i].max(), 30) for i in range(2)]
        aa, bb = np.meshgrid(*axes, indexing="ij")
        u = fit.predict(np.column_stack([aa.ravel(), bb.ravel()])).reshape(aa.shape)
    else:
        axes = [np.linspace(grid[:, 0].min(), grid[:, 0].max(), 200)]
        full = np.repeat(grid[:1], 200, axis=0)
        full[:, 0] = axes[0]
        u = fit.predict(full)
    return {"axes": axes, "u": f * u}


@dataclass(frozen=True)
class SweepStudy(GraphStudy):
    """A sweep of a graph without a full Monte Carlo run of its places (kind ``sweep``)."""

    kind = "sweep"
    run_options = frozenset({NAN_POLICY})
    no_adaptive = (
        "its uncertainties are compared over a grid of settings, each run with the same "
        "number of trials ([sweep] trials)"
    )


def _offset(progress: ProgressFn | None, before: int, total: int | None) -> ProgressFn | None:
    if progress is None:
        return None

    def step(done: int, own: int | None) -> None:
        progress(before + done, own if total is None else total)

    return step


def _read_sweep(top: Fields, graph: Graph, plan: Plan) -> SweepSpec:
    from mtmc.graph.sweep import parse_range

    t = top.table("sweep")
    assert t is not None
    t.only(("output", "vary", "trials", "intercept"))
    output = t.text("output")
    if output not in plan.types:
        raise t.error(f"the graph has no place {output!r}", "output")
    if plan.types[output] not in SCALAR_TYPES:
        raise t.error(
            f"a sweep needs a scalar place (x, y, z or real); {output} is a {plan.types[output]}",
            "output",
        )
    vt = t.table("vary")
    assert vt is not None
    if not vt.data:
        raise vt.error('expected at least one key, e.g. "probe.u_probe" = "0.001:0.005:5"')
    vary: dict[str, NDArray[np.float64]] = {}
    for key, value in vt.data.items():
        try:
            if isinstance(value, str):
                vals = parse_range(value, field=key)
            elif isinstance(value, list) and value:
                vals = np.array(
                    [check_number(v, partial(vt.error, key=key), low=0.0) for v in value]
                )
            else:
                raise vt.error(
                    f'expected "LOW:HIGH:N" or a non-empty array of numbers, got {value!r}', key
                )
            if not np.all(np.isfinite(vals)) or np.any(vals < 0):
                raise vt.error(f"expected standard uncertainties >= 0, got {value!r}", key)
            apply_setting(graph, key, float(vals[0]))
        except MtmcError as exc:
            if exc.file == top.source.file:
                raise
            raise vt.error(exc.message, key) from None
        vary[key] = vals
    return SweepSpec(
        output=output,
        vary=vary,
        trials=t.integer("trials", 1000, minimum=2, maximum=MAX_TRIALS),
        intercept=t.flag("intercept", True),
    )


def _load(top: Fields, kind: str) -> GraphStudy:
    top.only(("kind", "title", "graph", "outputs", "run", "sweep"))
    path = top.source.resolve(top.text("graph"), ("graph",))
    try:
        graph = load_graph(path)
    except MtmcError as exc:
        raise top.error(f"{exc}", "graph") from None
    plan = check_graph(graph)
    if kind == "graph":
        outputs = top.texts("outputs")
    else:
        outputs = top.texts("outputs", ())
    for name in outputs:
        if name not in plan.types:
            raise top.error(
                f"the graph {graph.file} has no place {name!r}; its places: "
                f"{', '.join(plan.types)}",
                "outputs",
            )
    spec = None
    if kind == "sweep" or top.has("sweep"):
        spec = _read_sweep(top, graph, plan)
    cls = GraphStudy if kind == "graph" else SweepStudy
    return cls(
        title=top.text("title", graph.title or path.stem),
        source=top.source,
        settings=RunSettings.read(top),
        graph=graph,
        graph_text=path.read_text(encoding="utf-8"),
        outputs=tuple(outputs),
        sweep=spec,
    )


@register_kind("graph", "a measurement graph: Monte Carlo and GUM of its places")
def read_graph_study(top: Fields) -> GraphStudy:
    """Validate a ``graph`` study file (see ``docs/study-format.md``)."""
    return _load(top, "graph")


@register_kind("sweep", "a measurement graph on a grid of uncertainties, with a surrogate")
def read_sweep_study(top: Fields) -> GraphStudy:
    """Validate a ``sweep`` study file (see ``docs/study-format.md``)."""
    return _load(top, "sweep")
