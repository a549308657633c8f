"""Monte Carlo over a measurement graph: all trials of a block in one batched pass.

A run (Stryczek's "simulation cycles"): draw every random input of the graph — the probe
errors of each ``meas`` (:mod:`mtmc.graph.probe`) and the marked places carrying ``u`` or
``dist`` — in blocks through :func:`mtmc.uncertainty.iter_blocks`, then fire every
transition once, in the firing order of :func:`mtmc.graph.check`, on the whole block.
There is no loop over trials: a block of ``m`` trials is a handful of array operations
per transition. The numbers depend only on the seed, not on the block size.

The graph is compiled once into a :class:`GraphModel` that the engine,
:func:`mtmc.uncertainty.monte_carlo`, evaluates block by block like any model. Per place
it keeps the moments of fixed seed blocks of trials merged in trial order, so a run of
10^6 trials needs the memory of one block; the samples of the places named in ``keep``
are kept whole. Each place's result is a :class:`PlaceSummary`.

Units: lengths in mm (a graph in µm is converted on reading its numbers), angles in rad.
"""

from __future__ import annotations

from collections.abc import Callable, Container, Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from mtmc.errors import GraphError, InputError, MtmcError
from mtmc.frozen import frozen_array, frozen_mapping, read_only
from mtmc.graph import ops as _ops
from mtmc.graph import probe as _probe
from mtmc.graph.model import check_graph
from mtmc.graph.places import SCALAR_TYPES, VECTOR_TYPES, Place
from mtmc.graph.structure import Graph, Plan
from mtmc.graph.values import PARTS, flatten, marked_value, place_factor, unflatten
from mtmc.parallel import ExecutorKind
from mtmc.uncertainty.distributions import (
    Constant,
    Distribution,
    Normal,
    NormalMethod,
    parse_distribution,
)
from mtmc.uncertainty.montecarlo import NanPolicy, monte_carlo
from mtmc.uncertainty.results import Moments, MonteCarloResult
from mtmc.uncertainty.sampling import Sampling

__all__ = [
    "GRAPH_BLOCK_SIZE",
    "GraphModel",
    "unflatten",
    "PlaceSummary",
    "GraphResult",
    "random_inputs",
    "run_graph",
    "graph_model",
    "flatten",
]

#: Trials per evaluation block of :func:`run_graph`: small enough that the temporaries of
#: the transitions stay in the processor cache. The numbers do not depend on it.
GRAPH_BLOCK_SIZE: int = 16384

#: Place types with one component.


@dataclass(frozen=True)
class PlaceSummary:
    """The Monte Carlo result of one place over a run, whole and by its named parts.

    Each attribute has one type whatever the place type, as for
    :class:`~mtmc.uncertainty.results.MonteCarloResult`: the arrays ``estimate_vector``,
    ``u_vector`` ``(k,)`` and ``cov`` ``(k, k)`` hold the ``k`` components of the place
    in the layout of :func:`flatten` (``k`` = 1 for x, y, z, real; 3 for point, vector,
    direction; 6 for line and plane; 7 for circle; 4 for sphere; 12 for frame), read-only;
    ``estimate`` and ``u`` are the floats of a scalar place (x, y, z, real) and raise an
    :class:`~mtmc.errors.InputError` for any other; :meth:`part` gives one named part
    as its own :class:`~mtmc.uncertainty.results.MonteCarloResult`.

    Parameters
    ----------
    name : str
        The place.
    type : str
        Its type.
    result : MonteCarloResult
        The engine's result for the place's components, flattened in the layout of
        :func:`flatten`: ``(M,)`` values for a scalar place, ``(M, k)`` otherwise (or
        their moments, when the samples were not kept).

    Examples
    --------
    >>> from mtmc.graph.places import Place, Transition
    >>> g = Graph(
    ...     places=(Place("a", "point", [0, 0, 0], u=0.01), Place("b", "point", [2, 0, 0]),),
    ...     transitions=(
    ...         Transition("t1", "middle", ("a", "b"), "c"),
    ...         Transition("t2", "distance", ("a", "b"), "d"),
    ...         Transition("t3", "line", ("a", "b"), "l"),
    ...     ),
    ... )
    >>> r = run_graph(g, trials=20000, seed=1)
    >>> r.places["c"].estimate_vector.shape, r.places["c"].cov.shape
    ((3,), (3, 3))
    >>> round(r.places["d"].estimate, 2), round(float(r.places["c"].u_vector[1]), 4)
    (2.0, 0.005)
    >>> r.places["l"].parts, r.places["l"].part("direction").estimate_vector.shape
    (('point', 'direction'), (3,))
    """

    name: str
    type: str
    result: MonteCarloResult = field(repr=False)

    @property
    def parts(self) -> tuple[str, ...]:
        """The names of the place's parts, in the layout of :func:`flatten`.

        ``("value",)`` for x, y, z, real, point, vector and direction places; ``("point",
        "direction")`` for a line, ``("point", "normal")`` for a plane, ``("centre",
        "normal", "radius")`` for a circle, ``("centre", "radius")`` for a sphere,
        ``("rotation", "translation")`` for a frame.
        """
        return tuple(p for p, _ in PARTS[self.type])

    @property
    def estimate_vector(self) -> NDArray[np.float64]:
        """The estimate (mean) of every component, read-only, ``(k,)``, mm / rad."""
        return self.result.estimate_vector

    @property
    def u_vector(self) -> NDArray[np.float64]:
        """The standard uncertainty of every component (divisor ``M - 1``), read-only, ``(k,)``."""
        return self.result.u_vector

    @property
    def cov(self) -> NDArray[np.float64]:
        """The covariance of the components (divisor ``M - 1``, Stryczek eq. 5), ``(k, k)``.

        Read-only; ``(1, 1)`` for a scalar place.
        """
        return self.result.cov

    @property
    def estimate(self) -> float:
        """The estimate of a scalar place (x, y, z, real), a float, mm / rad.

        Raises
        ------
        InputError
            For any other place: its estimate is :attr:`estimate_vector` (or
            ``part(name).estimate_vector``).
        """
        self._require_scalar("estimate")
        return float(self.result.estimate_vector[0])

    @property
    def u(self) -> float:
        """The standard uncertainty of a scalar place (x, y, z, real), a float, mm / rad.

        Raises
        ------
        InputError
            For any other place: its standard uncertainties are :attr:`u_vector`.
        """
        self._require_scalar("u")
        return float(self.result.u_vector[0])

    def _require_scalar(self, name: str) -> None:
        if self.type not in SCALAR_TYPES:
            k = sum(n for _, n in PARTS[self.type])
            raise InputError(
                f"{name} is the float of a scalar place (x, y, z, real); place {self.name} "
                f"is a {self.type} of {k} components: use {name}_vector (shape ({k},)) or "
                f"part(name) for one of {', '.join(self.parts)}",
                field=name,
            )

    def part(self, name: str) -> MonteCarloResult:
        """One named part of the place as its own Monte Carlo result.

        Parameters
        ----------
        name : str
            One of :attr:`parts` (``"value"`` for x, y, z, real, point, vector, direction).

        Returns
        -------
        MonteCarloResult
            For a part of one component (``"value"`` of a scalar place, ``"radius"``) a
            scalar result: ``estimate`` and ``u`` floats. For the others a vector result
            of ``j`` components: ``estimate_vector`` and ``u_vector`` ``(j,)``, ``cov``
            ``(j, j)`` (``j`` = 3; 9 for ``"rotation"``, the matrix row by row:
            ``estimate_vector.reshape(3, 3)``). Its samples are kept if the place's were
            (``keep`` of :func:`run_graph`), with the same trials, seed and run information.

        Raises
        ------
        InputError
            If the place type has no such part.
        """
        i = 0
        for part, k in PARTS[self.type]:
            if part == name:
                return _part_result(self.result, i, k, whole=k == len(self.estimate_vector))
            i += k
        raise InputError(
            f"a {self.type} has no part {name!r}; its parts: {', '.join(self.parts)}",
            field=name,
        )

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready summary of the place (the layout of ``mtmc graph run --json``).

        Returns
        -------
        dict
            ``type``, ``estimate``, ``u`` (a number for a scalar place; ``(3,)`` lists and
            the ``(3, 3)`` ``cov`` for point, vector and direction places); for line, plane,
            circle, sphere and frame one ``{estimate, u}`` object per part (a number for
            ``radius``, ``(3, 3)`` for ``rotation``, ``(3,)`` otherwise).
        """
        out: dict[str, Any] = {"type": self.type}
        if self.parts == ("value",):
            res = self.result
            if self.type in SCALAR_TYPES:
                out["estimate"], out["u"] = self.estimate, self.u
            else:
                out["estimate"], out["u"] = res.estimate_vector, res.u_vector
                out["cov"] = res.cov
            return out
        for p in self.parts:
            r = self.part(p)
            shape = (3, 3) if p == "rotation" else (-1,)
            if r.dim == 0:
                out[p] = {"estimate": r.estimate, "u": r.u}
            else:
                out[p] = {
                    "estimate": r.estimate_vector.reshape(shape),
                    "u": r.u_vector.reshape(shape),
                }
        return out


def _part_result(res: MonteCarloResult, start: int, k: int, *, whole: bool) -> MonteCarloResult:
    """Components ``start .. start + k - 1`` of ``res`` as a result (a scalar one if ``k == 1``)."""
    if whole:
        return res
    stop = start + k
    samples = moments = None
    if res.samples is not None:
        x = res.samples.reshape(res.samples.shape[0], -1)
        samples = x[:, start] if k == 1 else x[:, start:stop]
    else:
        assert res.moments is not None
        mo = res.moments
        m2 = mo.m2[start:stop, start:stop] if mo.m2.ndim == 2 else mo.m2[start:stop]
        moments = Moments(mo.n, mo.mean[start:stop], m2)
    return replace(res, samples=samples, moments=moments, scalar=k == 1, sketch=None)


@dataclass(frozen=True)
class GraphResult:
    """The result of a Monte Carlo run over a graph.

    Parameters
    ----------
    trials : int
        Number of trials M.
    seed : int
        The seed that reproduces the run.
    places : mapping of str to PlaceSummary
        Estimate and covariance of each summarised place.
    samples : mapping of str to value
        All M samples of each kept place (``(M,)``, ``(M, 3)``, a primitive or ``(M, 4, 4)``).
    types : mapping of str to str
        The type of every place of the graph.
    omitted : int
        Trials left out because a place was NaN or infinite (``nan_policy="omit"``).
    adaptive : bool
        Whether the number of trials was chosen by the adaptive procedure (JCGM 101 §7.9).
    blocks : int
        Blocks of the adaptive procedure (1 for a fixed run).
    tolerance : float or None
        The numerical tolerance δ the adaptive procedure met (None for a fixed run).

    The mappings are read-only, and so are the arrays of the samples (copied when given
    writable).
    """

    trials: int
    seed: int
    places: Mapping[str, PlaceSummary]
    samples: Mapping[str, Any] = field(default_factory=dict)
    types: Mapping[str, str] = field(default_factory=dict)
    omitted: int = 0
    adaptive: bool = False
    blocks: int = 1
    tolerance: float | None = None

    def __post_init__(self) -> None:
        samples = {
            k: frozen_array(v) if isinstance(v, np.ndarray) and v.flags.writeable else v
            for k, v in self.samples.items()
        }
        object.__setattr__(self, "places", frozen_mapping(dict(self.places)))
        object.__setattr__(self, "samples", frozen_mapping(samples))
        object.__setattr__(self, "types", frozen_mapping(dict(self.types)))

    def result(self, name: str) -> MonteCarloResult:
        """The JCGM 101 result of a kept place (its samples, flattened as :func:`flatten`).

        Parameters
        ----------
        name : str
            A place named in ``keep`` of :func:`run_graph`.

        Returns
        -------
        MonteCarloResult
            Samples ``(M,)`` for scalars, ``(M, k)`` otherwise.

        Raises
        ------
        InputError
            If the place's samples were not kept.
        """
        if name not in self.samples:
            raise InputError(
                f"the samples of place {name} were not kept (run with keep=[...])", field=name
            )
        flat = flatten(self.types[name], self.samples[name], self.trials)
        arr = flat[:, 0] if flat.shape[1] == 1 else flat
        return MonteCarloResult.from_samples(
            np.ascontiguousarray(arr), seed=self.seed, trials=self.trials
        )

    def to_dict(self) -> dict[str, Any]:
        """``{"trials", "seed", "omitted", "adaptive", "places": {name: summary}}``.

        JSON-ready apart from arrays; an adaptive run adds ``blocks`` and ``tolerance``
        (JCGM 101 §7.9.4).
        """
        run: dict[str, Any] = {"omitted": self.omitted, "adaptive": self.adaptive}
        if self.adaptive:
            run.update(blocks=self.blocks, tolerance=self.tolerance)
        return {
            "trials": self.trials,
            "seed": self.seed,
            **run,
            "places": {n: s.to_dict() for n, s in self.places.items()},
        }


def _place_dist(p: Place, file: str | None) -> Distribution:
    assert p.dist is not None
    try:
        return parse_distribution(p.dist, file=file, line=p.line, field="dist")
    except GraphError:
        raise
    except InputError as exc:
        raise GraphError(
            f"place {p.name}: {exc.message}", file=file, line=p.line, field="dist"
        ) from None


def random_inputs(plan: Plan) -> dict[str, Distribution]:
    """All random inputs of a graph, by name (what one trial draws).

    Parameters
    ----------
    plan : Plan
        A checked graph (:func:`mtmc.graph.check`).

    Returns
    -------
    dict of str to Distribution
        The probe errors of each ``meas`` (names ``<transition>.<part>``) and the marked
        places with ``u`` (``Normal``; ``<place>.x|y|z`` for 3-vectors) or ``dist``
        (``<place>``; ``<place>.x|y|z``), in a fixed order. Their values are in mm / rad.

    Raises
    ------
    GraphError
        If a ``dist`` or a ``meas`` field is not valid.
    """
    g = plan.graph
    out: dict[str, Distribution] = {}
    for p in g.places:
        f = place_factor(p, g.factor)
        vec = p.type in VECTOR_TYPES
        us = p.coordinate_u(f)
        if p.u is not None and np.any(us > 0):
            assert p.value is not None
            if vec:  # one u for all three coordinates, or (u_x, u_y, u_z)
                assert isinstance(p.value, tuple)
                for c, v, uc in zip("xyz", p.value, us, strict=True):
                    out[f"{p.name}.{c}"] = Normal(v * f, uc) if uc > 0 else Constant(v * f)
            else:
                assert isinstance(p.value, float)
                out[p.name] = Normal(p.value * f, float(us[0]))
        elif p.dist is not None:
            d = _place_dist(p, g.file)
            for c in "xyz" if vec else ("",):
                out[f"{p.name}.{c}" if c else p.name] = d
    for s in plan.steps:
        t = s.transition
        if t.op == "meas":
            out.update(
                _probe.meas_inputs(t.name, _probe.meas_spec(t, g.probe, g.factor), s.variant.output)
            )
    return out


def _releases(plan: Plan, want: Container[str]) -> tuple[tuple[str, ...], ...]:
    """For each step, the places it is the last to read and that are not wanted."""
    last: dict[str, int] = {}
    for i, s in enumerate(plan.steps):
        for p in s.transition.inputs:
            last[p] = i
    out: list[list[str]] = [[] for _ in plan.steps]
    for p, i in last.items():
        if p not in want:
            out[i].append(p)
    return tuple(tuple(ps) for ps in out)


def _fire(
    plan: Plan,
    samples: Mapping[str, Any],
    m: int,
    specs: Mapping[str, _probe.MeasSpec],
    releases: Sequence[tuple[str, ...]],
) -> dict[str, Any]:
    """Fire every transition once on a block of ``m`` trials.

    Returns the values of the places no transition reads and of those read but never
    released (constants as batches of one); ``releases[i]`` are dropped after step ``i``
    (:func:`_releases`).
    """
    g = plan.graph
    values: dict[str, Any] = {}
    for pl in g.places:
        if pl.marked:
            values[pl.name] = marked_value(pl, g.factor, samples)
    for s, drop in zip(plan.steps, releases, strict=True):
        t = s.transition
        if t.op == "meas":
            val = _probe.meas_value(t.name, specs[t.name], s.variant.output, samples, m)
        else:
            try:
                val = s.variant.func(*[values[p] for p in t.inputs])
            except MtmcError as exc:
                # the user's field is the transition's inputs, not the op's argument
                raise type(exc)(
                    f"transition {t.name} ({t.op}), in some trials: {exc.message}",
                    file=g.file,
                    line=t.field_line("in"),
                    field="in",
                ) from None
        values[t.out] = val
        for p in drop:
            del values[p]
    return values


def _as_plan(graph: Graph | Plan) -> Plan:
    return graph if isinstance(graph, Plan) else check_graph(graph)


#: The input a graph without random inputs is given, so that the engine's blocks know
#: their number of trials (a constant zero; no transition reads it).
_TRIAL_INPUT = "_trial"


@dataclass(frozen=True, eq=False)
class GraphModel:
    """A checked graph compiled once into the engine's model: named inputs, named outputs.

    Everything a run re-uses is resolved here once: the random inputs (:func:`random_inputs`,
    their distributions parsed), the ``meas`` parameters of every probing (probe specs),
    and the transition variants bound by input types (the plan's steps). Calling it fires
    every transition once on a block of trials; it is picklable, so worker processes
    can evaluate blocks.

    Parameters
    ----------
    plan : Plan
        A checked graph.
    outputs : tuple of str
        The places it returns, each flattened as :func:`flatten` (``(m,)`` for a scalar
        place, ``(m, k)`` otherwise).

    Attributes
    ----------
    inputs : mapping of str to Distribution
        The random inputs, in mm / rad.
    specs : mapping of str to MeasSpec
        The resolved parameters of each ``meas`` transition.
    """

    plan: Plan
    outputs: tuple[str, ...]
    inputs: Mapping[str, Distribution] = field(init=False, repr=False)
    specs: Mapping[str, _probe.MeasSpec] = field(init=False, repr=False)
    _releases: tuple[tuple[str, ...], ...] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        g = self.plan.graph
        for name in self.outputs:
            if name not in self.plan.types:
                raise InputError(f"the graph has no place {name}", file=g.file, field=name)
        inputs = random_inputs(self.plan) or {_TRIAL_INPUT: Constant(0.0)}
        specs = {
            s.transition.name: _probe.meas_spec(s.transition, g.probe, g.factor)
            for s in self.plan.steps
            if s.transition.op == "meas"
        }
        object.__setattr__(self, "inputs", MappingProxyType(inputs))
        object.__setattr__(self, "specs", MappingProxyType(specs))
        object.__setattr__(self, "_releases", _releases(self.plan, frozenset(self.outputs)))

    def __reduce__(self) -> tuple[Any, ...]:
        return (GraphModel, (self.plan, self.outputs))

    def __call__(self, **arrays: Any) -> dict[str, NDArray[np.float64]]:
        """The output places of a block of trials, flattened (:func:`flatten`)."""
        shapes = (v.shape if isinstance(v, np.ndarray) else np.shape(v) for v in arrays.values())
        m = max((sh[0] for sh in shapes if sh), default=1)
        arrays.pop(_TRIAL_INPUT, None)
        vals = _fire(self.plan, arrays, m, self.specs, self._releases)
        types = self.plan.types
        out = {}
        for name in self.outputs:
            if types[name] in SCALAR_TYPES:  # the values as they are: no copy
                v = np.asarray(vals[name], dtype=np.float64).reshape(-1)
                out[name] = v if v.shape[0] == m else np.broadcast_to(v, (m,))
            else:
                out[name] = flatten(types[name], vals[name], m)
        return out


def run_graph(
    graph: Graph | Plan,
    trials: int | None = None,
    seed: int | np.random.SeedSequence | None = None,
    *,
    outputs: Iterable[str] | None = None,
    keep: Iterable[str] = (),
    block_size: int = GRAPH_BLOCK_SIZE,
    normal_method: NormalMethod = "default",
    progress: Callable[[int, int | None], None] | None = None,
    workers: int = 1,
    executor: ExecutorKind | Any = "thread",
    scheduler: Any = None,
    nan_policy: NanPolicy = "raise",
    sampling: Sampling = "random",
    adaptive: bool = False,
    ndig: int = 2,
    p: float = 0.95,
    kind: Literal["symmetric", "shortest"] = "symmetric",
    max_trials: int = 10**8,
) -> GraphResult:
    """Monte Carlo over a measurement graph (JCGM 101 with Stryczek's graph as the model).

    The graph is compiled once into a :class:`GraphModel` and run by the engine,
    :func:`mtmc.uncertainty.monte_carlo`, like any other model: the same seeded blocks,
    workers, ``nan_policy`` and result type (one :class:`MonteCarloResult` per place,
    wrapped by :class:`PlaceSummary`).

    Parameters
    ----------
    graph : Graph or Plan
        The graph (checked here if a Graph).
    trials : int, optional
        Number of trials M (at least 2; default 100 000). Not with ``adaptive``.
    seed : int, SeedSequence or None
        The seed; None draws fresh entropy, recorded in the result.
    outputs : iterable of str, optional
        Places to summarise (default: all places).
    keep : iterable of str
        Places whose samples to keep whole (for coverage intervals, histograms). The
        others keep the moments of fixed blocks of trials merged in trial order, so a
        run of 10^6 trials needs the memory of one block, and no number depends on
        ``block_size`` or ``workers``.
    block_size : int
        Trials per block (default :data:`GRAPH_BLOCK_SIZE`); it changes the memory used
        and the speed, not the numbers.
    normal_method : {"default", "box-muller"}
        How normal numbers are made (Box-Muller as in Stryczek eq. 6).
    progress : callable, optional
        ``progress(done, trials)``, called after each block with the number of trials
        done so far (increasing, the last call with ``done == trials``). It does not
        change any number.
    workers : int, default 1
        Local workers (see :mod:`mtmc.parallel`); the numbers do not depend on it.
    executor : {"thread", "process", "dask"} or concurrent.futures.Executor
        Where the blocks run when ``workers > 1`` (see :mod:`mtmc.parallel`).
    scheduler : str or distributed.Client, optional
        With ``executor="dask"``, a running Dask cluster to use.
    nan_policy : {"raise", "omit"}
        As :func:`~mtmc.uncertainty.monte_carlo`.
    sampling : {"random", "sobol"}
        Pseudo-random draws or randomised quasi-Monte Carlo, as
        :func:`~mtmc.uncertainty.monte_carlo` (the Sobol dimensions go to the input
        places in sorted order of their names).
    adaptive : bool, default False
        Choose the number of trials by the adaptive procedure of JCGM 101 §7.9.4
        (:func:`~mtmc.uncertainty.monte_carlo`): it stops when every component of every
        summarised place (and of every kept one) has met the numerical tolerance of its
        ``u`` to ``ndig`` significant digits. Every summarised place then keeps its
        samples.
    ndig, p, kind, max_trials
        The adaptive procedure's significant digits of ``u``, coverage probability,
        interval watched and largest number of trials, as
        :func:`~mtmc.uncertainty.monte_carlo`.

    Returns
    -------
    GraphResult
        Per-place summaries and the kept samples.

    Raises
    ------
    GraphError
        If the graph is not valid.
    InputError
        Fewer than 2 trials, ``trials`` with ``adaptive``, or an unknown place in
        ``outputs`` or ``keep``.
    DegenerateGeometryError
        If a construction is degenerate in some trial.

    Examples
    --------
    >>> from mtmc.graph.places import Place, Transition
    >>> g = Graph(
    ...     places=(Place("a", "real", 1.0, u=0.1), Place("b", "real", 3.0)),
    ...     transitions=(Transition("t1", "middle", ("a", "b"), "c"),),
    ... )
    >>> r = run_graph(g, trials=20000, seed=1)
    >>> round(r.places["c"].u, 2)
    0.05
    """
    plan = _as_plan(graph)
    keep_s = list(dict.fromkeys(keep))
    summ = list(plan.types) if outputs is None else list(dict.fromkeys(outputs))
    derived = _derived_parts(plan, set(summ) - set(keep_s))
    reduced = [n for n in summ if n not in derived]
    model = GraphModel(plan, tuple(dict.fromkeys([*reduced, *keep_s])))
    try:
        res = monte_carlo(
            model,
            model.inputs,
            trials if trials is not None or adaptive else 100_000,
            seed,
            adaptive=adaptive,
            ndig=ndig,
            p=p,
            kind=kind,
            max_trials=max_trials,
            keep=keep_s,
            block_size=block_size,
            normal_method=normal_method,
            progress=progress,
            workers=workers,
            executor=executor,
            scheduler=scheduler,
            nan_policy=nan_policy,
            sampling=sampling,
        )
    except InputError as exc:
        if exc.field != "model" or exc.file is not None:
            raise
        # the engine's outputs are the graph's places: name them, and the file
        msg = exc.message.replace("output '", "place '")
        raise InputError(msg, file=plan.graph.file, field="place") from None
    places = {}
    for n in summ:
        if n in derived:  # a part of another place: the same numbers as its own run
            whole, part = derived[n]
            r = PlaceSummary(whole, plan.types[whole], res[whole]).part(part)
        else:
            r = res[n]
        places[n] = PlaceSummary(n, plan.types[n], r)
    samples_out = {n: read_only(unflatten(plan.types[n], res[n].values)) for n in keep_s}
    assert res.seed is not None  # monte_carlo records the seed it drew
    first = next(iter(res.values()), None)  # its adaptive blocks and δ are every output's
    return GraphResult(
        res.trials,
        res.seed,
        places,
        samples_out,
        dict(plan.types),
        omitted=res.omitted,
        adaptive=adaptive,
        blocks=1 if first is None else first.blocks,
        tolerance=None if first is None else first.tolerance,
    )


def _derived_parts(plan: Plan, summarised: Container[str]) -> dict[str, tuple[str, str]]:
    """Places whose value is a part of another summarised place's (:data:`ops.PART_OF_INPUT`).

    Their summaries are read from that place's (its moments hold theirs: the same sums
    and dot products of the same rows), so the run reduces their values once. Returns
    ``{place: (whole, part)}`` for those summarised whose whole is summarised and not
    read from a third place itself.
    """
    out: dict[str, tuple[str, str]] = {}
    for s in plan.steps:
        t = s.transition
        part = _ops.PART_OF_INPUT.get(s.variant.func)
        if part is None or t.out not in summarised:
            continue
        whole = t.inputs[0]
        if whole in summarised and whole not in out:
            out[t.out] = (whole, part)
    return out


def graph_model(
    graph: Graph | Plan, output: str
) -> tuple[Callable[..., NDArray[np.float64]], dict[str, Distribution]]:
    """The graph as a plain model function and its inputs, for ``monte_carlo`` and ``gum``.

    Parameters
    ----------
    graph : Graph or Plan
        The graph.
    output : str
        The output place.

    Returns
    -------
    model : callable
        ``model(**arrays)`` → the output place flattened (:func:`flatten`): ``(m,)`` for a
        scalar place, ``(m, k)`` otherwise.
    inputs : dict of str to Distribution
        :func:`random_inputs` of the graph.

    Examples
    --------
    >>> from mtmc.graph.places import Place, Transition
    >>> g = Graph(
    ...     places=(Place("a", "real", 1.0, u=0.1), Place("b", "real", 3.0)),
    ...     transitions=(Transition("t1", "middle", ("a", "b"), "c"),),
    ... )
    >>> model, inputs = graph_model(g, "c")
    >>> model(a=np.array([1.0, 2.0]))
    array([2. , 2.5])
    """
    plan = _as_plan(graph)
    compiled = GraphModel(plan, (output,))
    return _PlaceModel(compiled, output), dict(compiled.inputs)


@dataclass(frozen=True)
class _PlaceModel:
    """One output place of a :class:`GraphModel` (module-level: worker processes get it)."""

    compiled: GraphModel
    output: str

    def __call__(self, **arrays: Any) -> NDArray[np.float64]:
        return self.compiled(**arrays)[self.output]
