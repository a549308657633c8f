r"""Parameter sweeps over a graph and the surrogate formula fitted to them (Stryczek, Fig. 14-15).

Stryczek runs the A-C distance graph on a 5 × 5 grid of the probe and machine standard
deviations (σ_p, σ_m), 1000 trials per point, and fits to the 25 standard uncertainties
the "3-axis ellipsoid" of its eq. 31,

.. math:: U = 0.05999 \sqrt{\sigma_p^2 / 845 + \sigma_m^2 / 868},

with a fit error of at most 5 %. Stryczek's U is the standard uncertainty of the output,
written u here (U is the expanded uncertainty in the GUM and in mtmc's results). Squared,
eq. 31 is ``u² = c_p σ_p² + c_m σ_m²`` with ``c_p = 0.05999²/845`` and
``c_m = 0.05999²/868``: Stryczek's three constants are two free ones.
:func:`fit_surrogate` fits the general form

.. math:: u^2 = c_0 + \sum_i c_i \sigma_i^2

by linear least squares in ``u²`` weighted by ``1/u²`` (so the residuals are relative),
and reports the largest relative error of ``u`` on the grid. For a model linear in its
input errors the form is exact: the output variance is a linear combination of the input
variances (JCGM 100 eq. 10), so what remains is the Monte Carlo noise of each grid point.

Every grid point runs with the same seed (common random numbers): the points differ only
by the varied parameters, so the surface is smooth and the fit error measures the form,
not the sampling noise between points.
"""

from __future__ import annotations

import dataclasses
import io
import itertools
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import GraphError, InputError, MtmcError
from mtmc.graph.model import check_graph
from mtmc.graph.places import SCALAR_TYPES, ProbeDefaults
from mtmc.graph.run import run_graph
from mtmc.graph.structure import Graph
from mtmc.parallel import ExecutorKind, map_blocks, planned_workers
from mtmc.uncertainty.montecarlo import NanPolicy
from mtmc.uncertainty.sampling import resolve_seed

__all__ = [
    "SweepResult",
    "Surrogate",
    "apply_setting",
    "parse_range",
    "sweep_graph",
    "fit_surrogate",
]


def parse_range(text: str, *, field: str | None = None) -> NDArray[np.float64]:
    """Read ``LOW:HIGH:N`` (``N`` equally spaced values from LOW to HIGH) or ``a,b,c``.

    Parameters
    ----------
    text : str
        The range.
    field : str, optional
        Name for the error message.

    Returns
    -------
    ndarray, shape (N,)
        The values.

    Raises
    ------
    InputError
        If the text is not a range.

    Examples
    --------
    >>> parse_range("0.001:0.005:5")
    array([0.001, 0.002, 0.003, 0.004, 0.005])
    """
    try:
        if ":" in text:
            lo, hi, n = text.split(":")
            k = int(n)
            if k < 1:
                raise ValueError
            return np.linspace(float(lo), float(hi), k)
        return np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise InputError(
            f"expected LOW:HIGH:N (N >= 1) or a comma-separated list of numbers, got {text!r}",
            field=field,
        ) from None


def apply_setting(graph: Graph, key: str, value: float) -> Graph:
    """A copy of the graph with one number changed.

    Parameters
    ----------
    graph : Graph
        The graph.
    key : str
        ``probe.u_axis``, ``probe.u_probe``, ``probe.u_perp`` (the ``[probe]`` defaults),
        ``PLACE.u`` (a place's standard uncertainty) or ``TRANSITION.FIELD`` (a field of
        a transition, e.g. ``m1.u_probe``).
    value : float
        The new value, in the graph's units.

    Returns
    -------
    Graph
        The changed graph.

    Raises
    ------
    InputError
        If ``key`` names nothing in the graph, or the value is not valid there; the
        message names the graph's file and the key as the field.
    """
    try:
        return _apply(graph, key, value)
    except MtmcError as exc:
        raise InputError(
            f"{exc.message} (a value of the sweep)", file=graph.file, field=key
        ) from None


def _apply(graph: Graph, key: str, value: float) -> Graph:
    head, _, tail = key.partition(".")
    if not tail:
        raise InputError(f"expected SECTION.FIELD (e.g. probe.u_probe), got {key!r}", field=key)
    if head == "probe":
        if tail not in ("u_axis", "u_probe", "u_perp"):
            raise InputError(
                f"probe has no field {tail!r}; expected u_axis, u_probe or u_perp", field=key
            )
        pr = graph.probe
        vals = {"u_axis": pr.u_axis, "u_probe": pr.u_probe, "u_perp": pr.u_perp, tail: value}
        return dataclasses.replace(graph, probe=ProbeDefaults(**vals, line=pr.line))
    place = graph.place(head)
    if place is not None:
        if tail != "u":
            raise InputError(f"a sweep may change a place's u only, got {key!r}", field=key)
        new = dataclasses.replace(place, u=value)
        return dataclasses.replace(
            graph, places=tuple(new if p.name == head else p for p in graph.places)
        )
    t = graph.transition(head)
    if t is not None:
        params = dict(t.params)
        params[tail] = value
        new_t = dataclasses.replace(t, params=tuple(params.items()))
        return dataclasses.replace(
            graph, transitions=tuple(new_t if x.name == head else x for x in graph.transitions)
        )
    raise InputError(f"{head!r} is neither probe, a place nor a transition of the graph", field=key)


@dataclass(frozen=True)
class Surrogate:
    """The surrogate ``u² = c0 + Σ cᵢ σᵢ²`` fitted to a sweep (Stryczek eq. 31, general form).

    Parameters
    ----------
    names : tuple of str
        The varied parameters σᵢ.
    coefficients : ndarray, shape (k,)
        The cᵢ.
    c0 : float
        The constant term (0 when fitted without one).
    rel_errors : ndarray, shape (n,)
        ``u_surrogate / u - 1`` at each grid point.
    """

    names: tuple[str, ...]
    coefficients: NDArray[np.float64]
    c0: float
    rel_errors: NDArray[np.float64]

    @property
    def max_rel_error(self) -> float:
        """The largest ``|u_surrogate / u - 1|`` on the grid (Stryczek: at most 5 %)."""
        return float(np.max(np.abs(self.rel_errors)))

    def predict(self, sigmas: npt.ArrayLike) -> NDArray[np.float64]:
        """``u = √(c0 + Σ cᵢ σᵢ²)`` at the rows of ``sigmas`` (shape ``(n, k)``)."""
        s = np.atleast_2d(np.asarray(sigmas, dtype=np.float64))
        return np.sqrt(np.clip(self.c0 + (s**2) @ self.coefficients, 0.0, None))

    def formula(self) -> str:
        """The fitted formula in words, e.g. ``u = sqrt(0.0041*u_probe^2 + ...)``."""
        terms = [f"{c:.6g}*{n}^2" for c, n in zip(self.coefficients, self.names, strict=True)]
        if self.c0:
            terms.insert(0, f"{self.c0:.6g}")
        return "u = sqrt(" + " + ".join(terms) + ")"


def fit_surrogate(
    sigmas: npt.ArrayLike,
    u: npt.ArrayLike,
    *,
    names: Sequence[str] | None = None,
    intercept: bool = True,
) -> Surrogate:
    """Fit ``u² = c0 + Σ cᵢ σᵢ²`` to a grid of uncertainties (relative least squares).

    Parameters
    ----------
    sigmas : array_like, shape (n, k)
        The varied standard deviations at each grid point.
    u : array_like, shape (n,)
        The standard uncertainty of the output at each point (all > 0).
    names : sequence of str, optional
        Names of the k parameters.
    intercept : bool
        Fit ``c0`` too (default) or force it to 0 (Stryczek's eq. 31 has none).

    Returns
    -------
    Surrogate
        Coefficients and the relative error at each grid point.

    Raises
    ------
    InputError
        If the shapes disagree, a ``u`` is not positive, or the grid has fewer points than
        coefficients.

    Examples
    --------
    >>> s1, s2 = np.meshgrid([1.0, 2.0, 3.0], [1.0, 2.0])
    >>> sig = np.column_stack([s1.ravel(), s2.ravel()])
    >>> fit = fit_surrogate(sig, np.sqrt(0.5 + 3 * sig[:, 0] ** 2 + 5 * sig[:, 1] ** 2))
    >>> np.round(fit.coefficients, 10), round(fit.c0, 10), fit.max_rel_error < 1e-12
    (array([3., 5.]), 0.5, True)
    """
    s = np.atleast_2d(np.asarray(sigmas, dtype=np.float64))
    uu = np.asarray(u, dtype=np.float64).reshape(-1)
    if s.shape[0] != uu.shape[0]:
        raise InputError(f"sigmas has {s.shape[0]} rows but u has {uu.shape[0]} values", field="u")
    if not np.all(uu > 0):
        raise InputError("every u must be > 0 for a relative fit", field="u")
    k = s.shape[1]
    A = s**2
    if intercept:
        A = np.column_stack([np.ones(len(uu)), A])
    if A.shape[0] < A.shape[1]:
        raise InputError(
            f"{A.shape[0]} grid points cannot fit {A.shape[1]} coefficients", field="sigmas"
        )
    w = 1.0 / uu**2
    coef, *_ = np.linalg.lstsq(A * w[:, None], uu**2 * w, rcond=None)
    c0 = float(coef[0]) if intercept else 0.0
    c = coef[1:] if intercept else coef
    nm = tuple(names) if names is not None else tuple(f"sigma{i + 1}" for i in range(k))
    pred = np.sqrt(np.clip(c0 + (s**2) @ c, 0.0, None))
    return Surrogate(nm, np.asarray(c, dtype=np.float64), c0, pred / uu - 1.0)


@dataclass(frozen=True)
class SweepResult:
    """The standard uncertainty of one output place on a grid of parameters.

    Parameters
    ----------
    names : tuple of str
        The varied parameters (``probe.u_probe``...).
    grid : ndarray, shape (n, k)
        Their values at each grid point (the first name varies slowest).
    u : ndarray, shape (n,)
        The standard uncertainty of the output at each point, mm (rad for angles).
    estimate : ndarray, shape (n,)
        The output's estimate at each point.
    output : str
        The output place.
    trials : int
        Trials per grid point.
    seed : int
        The seed of every grid point.
    omitted : int
        Trials left out over all grid points because the output was NaN or infinite
        (``nan_policy="omit"``).
    """

    names: tuple[str, ...]
    grid: NDArray[np.float64]
    u: NDArray[np.float64]
    estimate: NDArray[np.float64]
    output: str
    trials: int
    seed: int
    omitted: int = 0

    def fit(self, *, intercept: bool = True) -> Surrogate:
        """Fit the surrogate of :func:`fit_surrogate` to this sweep."""
        return fit_surrogate(self.grid, self.u, names=self.names, intercept=intercept)

    def to_csv(self, surrogate: Surrogate | None = None) -> str:
        """The sweep as CSV: one row per grid point, the varied values, estimate and u.

        Parameters
        ----------
        surrogate : Surrogate, optional
            Adds the columns ``u_surrogate`` and ``rel_error``.

        Returns
        -------
        str
            The CSV text (comma-separated, header line first).
        """
        buf = io.StringIO()
        cols = [*self.names, f"{self.output}_estimate", f"{self.output}_u"]
        if surrogate is not None:
            cols += ["u_surrogate", "rel_error"]
            pred = surrogate.predict(self.grid)
        buf.write(",".join(cols) + "\n")
        for i in range(len(self.u)):
            row = [
                *(repr(float(v)) for v in self.grid[i]),
                repr(float(self.estimate[i])),
                repr(float(self.u[i])),
            ]
            if surrogate is not None:
                row += [repr(float(pred[i])), repr(float(surrogate.rel_errors[i]))]
            buf.write(",".join(row) + "\n")
        return buf.getvalue()


#: Tasks a worker gets of a sweep on a pool or a cluster: the grid points are grouped into
#: about this many tasks a worker (:func:`_point_groups`).
SWEEP_TASKS_PER_WORKER: int = 4


def _point_groups(n: int, workers: int) -> list[range]:
    """The ``n`` grid points in consecutive groups, one task each, the larger first.

    ``min(n, SWEEP_TASKS_PER_WORKER · workers)`` groups whose sizes differ by at most one.
    A task costs the cores of a Dask cluster some 10 ms besides its work (the scheduler's
    and the workers' messages; ``docs/scaling.md``), about a seventh of a grid point of
    Stryczek's Fig. 14 at 10⁵ trials: the 25 points on two workers took 0.89–0.91 s as 8
    tasks against 1.01 s as 25 (best of six rounds each). With the larger groups first,
    workers of equal speed taking the next task as they finish end within
    ``⌈n / workers⌉`` points, as with one point a task (checked for ``n ≤ 300`` and
    ``workers ≤ 32`` in the tests); a few tasks a worker leave room for workers that
    are not equally fast.

    Examples
    --------
    >>> [len(g) for g in _point_groups(25, 2)]
    [4, 3, 3, 3, 3, 3, 3, 3]
    >>> [len(g) for g in _point_groups(3, 2)]
    [1, 1, 1]
    """
    tasks = min(n, SWEEP_TASKS_PER_WORKER * max(1, workers))
    if tasks == 0:
        return []
    size, larger = divmod(n, tasks)
    out, a = [], 0
    for i in range(tasks):
        b = a + size + (i < larger)
        out.append(range(a, b))
        a = b
    return out


@dataclass(frozen=True)
class _SweepGroup:
    """Consecutive grid points of a sweep in one task (picklable, for workers)."""

    point: _SweepPoint

    def __call__(self, graphs: Sequence[Graph]) -> list[tuple[float, float, int]]:
        return [self.point(g) for g in graphs]


@dataclass(frozen=True)
class _SweepPoint:
    """One grid point of a sweep: a run of the graph (picklable, for workers)."""

    output: str
    trials: int
    seed: int
    nan_policy: NanPolicy = "raise"

    def __call__(
        self, graph: Graph, progress: Callable[[int, int | None], None] | None = None
    ) -> tuple[float, float, int]:
        res = run_graph(
            graph,
            self.trials,
            self.seed,
            outputs=[self.output],
            progress=progress,
            nan_policy=self.nan_policy,
        )
        summary = res.places[self.output]
        return summary.u, summary.estimate, res.omitted


def sweep_graph(
    graph: Graph,
    vary: Mapping[str, npt.ArrayLike],
    output: str,
    *,
    trials: int = 1000,
    seed: int | np.random.SeedSequence | None = None,
    progress: Callable[[int, int | None], None] | None = None,
    workers: int = 1,
    executor: ExecutorKind | Any = "thread",
    scheduler: Any = None,
    nan_policy: NanPolicy = "raise",
) -> SweepResult:
    """Run a graph on the grid of all combinations of the varied parameters.

    Parameters
    ----------
    graph : Graph
        The graph.
    vary : mapping of str to array_like
        Parameter keys (see :func:`apply_setting`) and their values; the grid is their
        Cartesian product, the first key varying slowest.
    output : str
        A scalar output place (type ``x``, ``y``, ``z`` or ``real``).
    trials : int
        Trials per grid point (Stryczek: 1000).
    seed : int, SeedSequence or None
        One seed for every grid point (common random numbers).
    progress : callable, optional
        ``progress(done, total)`` with ``total = n·trials`` for the ``n`` grid points,
        called after each block of each grid point with the trials done so far over the
        whole sweep (increasing, the last call with ``done == total``; after each grid
        point of a task as the task returns, when they run on workers). It does not
        change any number.
    workers : int, default 1
        Grid points run on this many workers at once (consecutive points grouped into
        about :data:`SWEEP_TASKS_PER_WORKER` tasks a worker; see :mod:`mtmc.parallel`);
        the numbers do not depend on it.
    executor : {"thread", "process", "dask"} or concurrent.futures.Executor
        Where the grid points run when ``workers > 1``.
    scheduler : str or distributed.Client, optional
        With ``executor="dask"``, a running Dask cluster to use.
    nan_policy : {"raise", "omit"}
        At each grid point, as :func:`~mtmc.uncertainty.monte_carlo`.

    Returns
    -------
    SweepResult
        The grid and the output's standard uncertainty at each point.

    Raises
    ------
    InputError, GraphError
        On an unknown key, a non-scalar output, or an invalid graph.
    """
    plan = check_graph(graph)
    if output not in plan.types:
        raise InputError(f"the graph has no place {output}", file=graph.file, field=output)
    if plan.types[output] not in SCALAR_TYPES:
        raise GraphError(
            f"a sweep needs a scalar output place (x, y, z or real); {output} is a "
            f"{plan.types[output]}",
            file=graph.file,
            field=output,
        )
    if not vary:
        raise InputError("nothing to vary", field="vary")
    names = tuple(vary)
    axes = [np.asarray(v, dtype=np.float64).reshape(-1) for v in vary.values()]
    seed_i = resolve_seed(seed)
    grid = np.array(list(itertools.product(*axes)), dtype=np.float64).reshape(-1, len(names))
    graphs = []
    for row in grid:
        g = graph
        for key, val in zip(names, row, strict=True):
            g = apply_setting(g, key, float(val))
        graphs.append(g)
    trials = int(trials)
    total = grid.shape[0] * trials
    point = _SweepPoint(output, trials, seed_i, nan_policy)
    us, est = [], []
    omitted = 0
    if workers == 1 and executor in ("thread", "process"):
        for i, g in enumerate(graphs):
            step = None
            if progress is not None:
                done_before = i * trials

                def step(done: int, _total: int | None, _before: int = done_before) -> None:
                    progress(_before + done, total)

            u, e, left_out = point(g, step)
            us.append(u)
            est.append(e)
            omitted += left_out
    else:
        groups = _point_groups(len(graphs), planned_workers(workers, executor))
        tasks = [graphs[g.start : g.stop] for g in groups]
        results = map_blocks(
            _SweepGroup(point), tasks, workers=workers, executor=executor, scheduler=scheduler
        )
        for part in results:
            for u, e, left_out in part:
                us.append(u)
                est.append(e)
                omitted += left_out
                if progress is not None:
                    progress(len(us) * trials, total)
    return SweepResult(
        names, grid, np.array(us), np.array(est), output, int(trials), seed_i, omitted
    )
