"""Propagation of distributions by Monte Carlo (JCGM 101:2008 §7), fixed or adaptive.

:func:`monte_carlo` draws the inputs block by block (:mod:`~mtmc.uncertainty.sampling`),
evaluates the vectorised model on each block, keeps the model values and returns a
:class:`~mtmc.uncertainty.results.MonteCarloResult`. With ``adaptive=True`` it follows
the adaptive procedure of JCGM 101 §7.9.4: blocks of ``h = max(100/(1 - p), 10⁴)`` trials
are added until twice the standard deviations of the block estimates, standard
uncertainties and coverage-interval endpoints are all at most the numerical tolerance.

Examples
--------
Stryczek (Fig. 4): the sum of N(0, 1) and N(0.5, 0.5) has u = √1.25 ≈ 1.118.

>>> r = monte_carlo(lambda x1, x2: x1 + x2, {"x1": "normal(0, 1)", "x2": "normal(0.5, 0.5)"},
...                 trials=200_000, seed=2024)
>>> round(r.estimate, 2), round(r.u, 2)
(0.5, 1.12)
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import dataclasses
import functools
import math
import os
from collections.abc import Callable, Container, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal, overload

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import ConvergenceError, InputError
from mtmc.parallel import ExecutorKind, map_blocks, one_blas_thread, planned_workers
from mtmc.uncertainty.checks import check_probability
from mtmc.uncertainty.copula import joint_sampler
from mtmc.uncertainty.distributions import Distribution, NormalMethod
from mtmc.uncertainty.results import (
    MAX_COV_DIM,
    Moments,
    MonteCarloResult,
    MonteCarloResults,
    Trace,
)
from mtmc.uncertainty.sampling import (
    DEFAULT_BLOCK_SIZE,
    SEED_BLOCK_SIZE,
    BlockSource,
    JointDraw,
    Sampling,
    check_int,
    check_sampling,
    evaluation_block_size,
    prepare_inputs,
    resolve_seed,
)
from mtmc.uncertainty.shared_rows import SharedRows, SharedRowsRef
from mtmc.uncertainty.sketch import QuantileSketch
from mtmc.uncertainty.tolerance import numerical_tolerance

__all__ = ["KEEP_AUTO_BYTES", "RQMC_MIN_BLOCKS", "adaptive_block_size", "monte_carlo"]

NanPolicy = Literal["raise", "omit"]

#: An adaptive run with ``sampling="sobol"`` stops after at least this many independent
#: scramblings: their spread ``s`` then has 9 degrees of freedom, and ``2 s <= δ`` holds
#: the error within ``δ`` about as often (92 %) as the many blocks of a pseudo-random run.
RQMC_MIN_BLOCKS: int = 10

#: ``progress(done, total)``: called after each block of trials with the number of trials
#: done so far; ``total`` is None while it is not known (adaptive runs).
ProgressFn = Callable[[int, int | None], None]


def adaptive_block_size(p: float) -> int:
    """Trials per block of the adaptive procedure: ``h = max(⌈100/(1 - p)⌉, 10⁴)``.

    JCGM 101 §7.9.4 a) asks for ``M > 100/(1 - p)`` trials per block and recommends
    ``M = 10⁴``.

    Parameters
    ----------
    p : float
        Coverage probability, ``0 < p < 1``.

    Returns
    -------
    int

    Examples
    --------
    >>> adaptive_block_size(0.95), adaptive_block_size(0.999)
    (10000, 100000)
    """
    pf = check_probability(p)
    return max(10**4, math.ceil(100.0 / (1.0 - pf) - 1e-6))


Outputs = dict[str, NDArray[np.float64]]

#: ``keep="auto"`` keeps the samples of a run while they take at most this many bytes.
KEEP_AUTO_BYTES: int = 2 * 2**30

#: Seed blocks whose quantile sketches are merged into one before the run's sketch: in
#: trial order within each group of this many seed blocks, then group by group. A task
#: that holds a whole group merges it where it ran and hands back one sketch of about
#: 50 000 values instead of the 2²⁰ values of its seed blocks; the merges are the same,
#: so are the bits, wherever they are done.
SKETCH_GROUP: int = 64

#: Most bytes of the values of one reduction block of a group of outputs (see
#: :func:`reduction_block_trials`): what waits in memory for a block to be complete.
REDUCE_BYTES: int = 32 * 2**20


def reduction_block_trials(width: int) -> int:
    """Trials whose moments are formed together, for outputs of ``width`` values a trial.

    A seed block (:data:`SEED_BLOCK_SIZE` trials) while its values take at most
    :data:`REDUCE_BYTES` (``width <= 256``); for wider outputs (the 16 224 values of a
    verification's errors at 5408 points) the largest power of two of trials that fits,
    at least one. Fixed by the width alone, so the moments are the same bits whatever
    the evaluation blocks or the workers, and the values held for an unfinished block
    are bounded whatever the number of trials.

    Examples
    --------
    >>> reduction_block_trials(1), reduction_block_trials(256), reduction_block_trials(16224)
    (16384, 16384, 256)
    """
    fit = max(1, REDUCE_BYTES // (8 * max(1, width)))
    return min(SEED_BLOCK_SIZE, 1 << (fit.bit_length() - 1))


#: Tasks a worker gets of a run on a pool or a cluster (see :func:`_blocks_per_task`).
TASKS_PER_WORKER: int = 8

#: Most bytes of kept values and sketch values one task hands back.
TASK_BYTES: int = 64 * 2**20

#: Ratio of consecutive numbers of trials at which the convergence curve of an output
#: whose samples are not kept is read (20 points a decade; the curve of 10⁹ trials has
#: about 100 points, whatever the number of seed blocks).
TRACE_STEP: float = 10 ** (1 / 20)

#: The name of the output of a model that returns one array rather than a mapping.
_SINGLE = ""


def _evaluate(
    model: Callable[..., Any], samples: dict[str, NDArray[np.float64]], start: int, stop: int
) -> Outputs:
    """Call the model on one block; its outputs by name, each ``(m,)`` or ``(m, d)``."""
    m = stop - start
    try:
        raw = model(**samples)
    except TypeError as exc:
        raise InputError(
            f"the model could not be called with the inputs {', '.join(samples)} as keyword "
            f"arrays: {exc}",
            field="model",
        ) from exc
    items = raw.items() if isinstance(raw, Mapping) else ((_SINGLE, raw),)
    out: Outputs = {}
    for name, value in items:
        if not isinstance(name, str) or (not name and isinstance(raw, Mapping)):
            raise InputError(
                f"expected the model's outputs to be named by strings, got {name!r}",
                field="model",
            )
        arr = np.asarray(value, dtype=np.float64)
        if arr.ndim not in (1, 2) or arr.shape[0] != m:
            what = f"output {name!r}" if name else "the model"
            raise InputError(
                f"{what} returned shape {arr.shape} for a block of {m} trials (trials "
                f"{start}..{stop - 1}); expected ({m},) or ({m}, d): a vectorised model returns "
                "one value (or one row) per trial",
                field="model",
            )
        out[name] = arr
    if not out:
        raise InputError("the model returned no output", field="model")
    return out


@dataclass
class _Digest:
    """What one evaluation block hands back, in this process or from a worker.

    ``rows``: the finite rows of the kept outputs. ``pieces``: for each group of outputs
    (:func:`_groups`) and each of its reduction blocks (:func:`reduction_block_trials`
    trials: a seed block, or a power-of-two part of one for wide outputs) that the
    evaluation block touches, in order, ``(group, k, complete, part)``. When the
    evaluation block holds all of reduction block ``k`` (``complete``), ``part`` is the
    group's :class:`Moments`, side by side, and the sketches of its outputs; else the
    ``(d, rows)`` values of the piece it holds, one array per output, which the collector
    joins with the neighbouring pieces. Either way the moments of a reduction block come
    from the same C-ordered arrays, so they are the same bits wherever computed.
    """

    start: int
    m: int
    shapes: dict[str, tuple[int, ...]]
    rows: dict[str, NDArray[np.float64]]
    omitted: int
    first_bad: int | None
    bad_outputs: tuple[str, ...]
    pieces: list[tuple[tuple[str, ...], int, bool, Any]]
    #: sketches of whole groups of :data:`SKETCH_GROUP` seed blocks, merged where the
    #: blocks ran (by group number; the pieces of those seed blocks then carry none)
    merged: dict[int, dict[str, QuantileSketch]] = field(default_factory=dict)
    #: which trials were finite, where some were not (``None`` where all were)
    ok: NDArray[np.bool_] | None = None
    #: the kept outputs' rows (all ``m``, finite or not) were written by the worker into
    #: the run's shared arrays (:mod:`mtmc.uncertainty.shared_rows`); ``rows`` is empty
    written: bool = False


#: Moments of a group of outputs and the sketches of its outputs (``None`` if no rows).
_Reduced = tuple[Moments | None, dict[str, QuantileSketch]]


def _groups(shapes: Mapping[str, tuple[int, ...]], kept: Container[str]) -> list[tuple[str, ...]]:
    """The outputs whose moments are formed together: those not kept, by width, in order."""
    by_width: dict[int, list[str]] = {}
    for n, shape in shapes.items():
        if n not in kept:
            by_width.setdefault(max(1, math.prod(shape)), []).append(n)
    return [tuple(names) for names in by_width.values()]


@functools.lru_cache(maxsize=64)
def _groups_of(
    shapes: tuple[tuple[str, tuple[int, ...]], ...], kept: tuple[str, ...]
) -> tuple[tuple[str, ...], ...]:
    """:func:`_groups` of the outputs of a block, resolved once per set of shapes."""
    return tuple(_groups(dict(shapes), kept))


def _block_array(parts: list[NDArray[np.float64]]) -> NDArray[np.float64]:
    """One C-ordered ``(d, rows)`` array of the pieces of a seed block (a view if it is one)."""
    if len(parts) > 1:
        return np.ascontiguousarray(np.concatenate(parts, axis=1))
    return np.ascontiguousarray(parts[0])


def _reduce(
    names: tuple[str, ...],
    xs: list[NDArray[np.float64]],
    sketch: frozenset[str],
    sums: NDArray[np.float64] | None = None,
) -> _Reduced:
    """Moments (side by side) and sketches of one seed block's ``(d, rows)`` values."""
    if not xs[0].shape[1]:
        return None, {}
    sk = {n: QuantileSketch.of(x[0]) for n, x in zip(names, xs, strict=True) if n in sketch}
    return Moments.of_stack(xs, sums), sk


def _digest(
    start: int,
    outs: Outputs,
    keep: bool | frozenset[str],
    total: int,
    sketch: frozenset[str] = frozenset(),
) -> _Digest:
    """Reduce the outputs of trials ``start..start+m-1`` of a run of ``total`` trials."""
    m = next(iter(outs.values())).shape[0]
    kept = [n for n in outs if keep is True or (keep is not False and n in keep)]
    groups = _groups_of(tuple((n, arr.shape[1:]) for n, arr in outs.items()), tuple(kept))
    # the reduced outputs, group by group, as C-ordered (d, rows) arrays per reduction
    # block, and their row sums: the sum of finite values is finite (but for an
    # overflow, which then takes the row-by-row check), so one pass checks the values
    # and gives the means
    cols = {n: outs[n].reshape(m, -1).T for g in groups for n in g}
    plan = []  # per group: its reduction blocks (k, lo, hi, complete), arrays and sums
    finite = all(math.isfinite(float(outs[n].sum())) for n in kept)
    for g in groups:
        s = reduction_block_trials(sum(cols[n].shape[0] for n in g))
        spans: list[tuple[int, int, int, bool]] = []  # block, rows lo..hi, complete
        lo = 0
        while lo < m:
            k = (start + lo) // s
            hi = min(m, (k + 1) * s - start)
            spans.append((k, lo, hi, start + lo == k * s and start + hi == min((k + 1) * s, total)))
            lo = hi
        blocks = [[_block_array([cols[n][:, lo:hi]]) for n in g] for _, lo, hi, _ in spans]
        sums = [np.stack([np.add.reduce(x, axis=1) for x in xb]) for xb in blocks]
        finite = finite and all(math.isfinite(float(t.sum())) for t in sums)
        plan.append((g, spans, blocks, sums))
    ok = np.ones(m, dtype=np.bool_)
    nbad = 0
    if not finite:
        for arr in outs.values():
            if not np.isfinite(arr.sum()):
                fin = np.isfinite(arr)
                ok &= fin if fin.ndim == 1 else fin.all(axis=1)
        nbad = m - int(np.count_nonzero(ok))
    bad: tuple[str, ...] = ()
    if nbad:
        bad = tuple(n for n, arr in outs.items() if not np.isfinite(arr).all())
    rows = {n: (outs[n][ok] if nbad else outs[n]) for n in kept}
    pieces: list[tuple[tuple[str, ...], int, bool, Any]] = []
    for g, spans, blocks, sums in plan:
        for (k, lo, hi, complete), xs, t in zip(spans, blocks, sums, strict=True):
            if nbad:
                sel = ok[lo:hi]
                xs = [_block_array([x[:, sel]]) for x in xs]
            if complete:
                pieces.append((g, k, True, _reduce(g, xs, sketch, None if nbad else t)))
            else:
                pieces.append((g, k, False, xs))
    return _Digest(
        start=start,
        m=m,
        shapes={n: arr.shape[1:] for n, arr in outs.items()},
        rows=rows,
        omitted=nbad,
        first_bad=start + int(np.argmin(ok)) if nbad else None,
        bad_outputs=bad,
        pieces=pieces,
        ok=ok if nbad else None,
    )


@dataclass(frozen=True)
class _BlockJob:
    """Draw, evaluate and reduce one trial range; picklable when the model is."""

    model: Callable[..., Any]
    dists: dict[str, Distribution]
    seed: int
    method: NormalMethod
    keep: bool | frozenset[str]
    total: int
    sketch: frozenset[str]
    sampling: Sampling = "random"
    joint: JointDraw | None = None
    #: the run's shared arrays of kept rows, which a worker writes into where it can
    shared: SharedRowsRef | None = None

    def __call__(self, span: tuple[int, int]) -> _Digest:
        a, b = span
        source = BlockSource(self.dists, self.seed, self.method, self.sampling, self.joint)
        samples = source.trials(a, b)
        outs = _evaluate(self.model, samples, a, b)
        return _digest(a, outs, self.keep, self.total, self.sketch)


@dataclass(frozen=True)
class _TaskJob:
    """Consecutive evaluation blocks as one task of a pool or cluster: their digests.

    The digests are those each block gives alone, in order, so the run is the same bits
    however the blocks are grouped into tasks; one task draws its seed blocks once for
    all its evaluation blocks and pays the scheduler once.
    """

    job: _BlockJob

    def __call__(self, spans: tuple[tuple[int, int], ...]) -> list[_Digest]:
        j = self.job
        source = BlockSource(j.dists, j.seed, j.method, j.sampling, j.joint)
        out = []
        with j.shared.writer() if j.shared else contextlib.nullcontext() as rows:
            for a, b in spans:
                outs = _evaluate(j.model, source.trials(a, b), a, b)
                d = _digest(a, outs, j.keep, j.total, j.sketch)
                if rows is not None:  # the kept rows go to the client's arrays directly
                    rows.write(a, outs)
                    d.rows, d.written = {}, True
                out.append(d)
        _join_pieces(out, spans[0][0], spans[-1][1], j.total, j.sketch)
        if j.sketch:
            _merge_groups(out, spans[0][0], spans[-1][1], j.total)
        return out


def _join_pieces(
    digests: list[_Digest], lo: int, hi: int, total: int, sketch: frozenset[str]
) -> None:
    """Reduce where they ran the reduction blocks that ``digests`` hold in pieces (in place).

    The evaluation blocks of a wide output need not line up with its reduction blocks
    (:func:`reduction_block_trials`): a block cut by evaluation blocks comes as pieces of
    values, which :class:`_Collector` joins and reduces. Where all the pieces of a
    reduction block lie in the digests of one task (trials ``lo..hi-1``), they are joined
    and reduced here, as the collector would, and the task hands back the block's moments
    instead of its values (for a verification of 5408 points, 1 kB a trial instead of
    130 kB). The moments are the same bits: the same C-ordered values, reduced alike.
    The reduced block goes with the digest of its last piece, in its place.
    """
    where: dict[tuple[tuple[str, ...], int], list[tuple[int, int]]] = {}
    for i, d in enumerate(digests):
        for p, (g, k, complete, _) in enumerate(d.pieces):
            if not complete:
                where.setdefault((g, k), []).append((i, p))
    drop: dict[int, set[int]] = {}
    for (g, k), at in where.items():
        shapes = digests[at[0][0]].shapes
        s = reduction_block_trials(len(g) * max(1, math.prod(shapes[g[0]])))
        if k * s < lo or min((k + 1) * s, total) > hi:
            continue  # begun or ended by another task: the collector joins it
        xs = [_block_array([digests[i].pieces[p][3][j] for i, p in at]) for j in range(len(g))]
        i, p = at[-1]
        digests[i].pieces[p] = (g, k, True, _reduce(g, xs, sketch))
        for i, p in at[:-1]:
            drop.setdefault(i, set()).add(p)
    for i, ps in drop.items():
        digests[i].pieces = [pc for p, pc in enumerate(digests[i].pieces) if p not in ps]


def _merge_groups(digests: list[_Digest], lo: int, hi: int, total: int) -> None:
    """Merge the sketches of each whole group of seed blocks in ``digests`` (in place).

    A group of :data:`SKETCH_GROUP` seed blocks whose blocks are all complete pieces of
    these digests is merged in trial order, as :class:`_Collector` merges it; the
    merged sketch goes with the digest holding the group's last seed block.
    """
    s, g = SEED_BLOCK_SIZE, SKETCH_GROUP
    where = {  # the complete seed blocks of the outputs with sketches (scalars)
        k: (i, p)
        for i, d in enumerate(digests)
        for p, (_, k, complete, part) in enumerate(d.pieces)
        if complete and part[1]
    }
    last_block = (total - 1) // s
    for grp in range(lo // s // g, (hi - 1) // s // g + 1):
        blocks = range(grp * g, min((grp + 1) * g - 1, last_block) + 1)
        if not all(k in where for k in blocks):
            continue
        merged: dict[str, QuantileSketch] = {}
        for k in blocks:
            i, p = where[k]
            outputs, _, _, (mom, sketches) = digests[i].pieces[p]
            for n, sk in sketches.items():
                merged[n] = merged[n].merge(sk) if n in merged else sk
            digests[i].pieces[p] = (outputs, k, True, (mom, {}))
        digests[where[blocks[-1]][0]].merged[grp] = merged


def _blocks_per_task(blocks: int, workers: int, block_bytes: int) -> int:
    """Evaluation blocks per task: about :data:`TASKS_PER_WORKER` tasks a worker.

    Fewer, larger tasks where each is cheap to send back (a scheduler's overhead is
    paid per task: 3–14 ms on Dask), but at most :data:`TASK_BYTES` of kept values and
    quantile-sketch values a task, so that what waits to be merged stays bounded.
    """
    by_count = blocks // (TASKS_PER_WORKER * max(1, workers))
    by_bytes = TASK_BYTES // max(1, block_bytes)
    return max(1, min(by_count, by_bytes))


def _memory_bytes() -> int:
    """Physical memory of this machine (bytes), or 8 GiB where it cannot be read."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover - non-POSIX
        return 8 * 2**30


def _gib(nbytes: float) -> str:
    return f"{nbytes / 2**30:.3g} GiB"


class _Collector:
    """Merges the digests of consecutive trial ranges, in trial order.

    Keeps the samples of the outputs named in ``keep`` (preallocated, after a memory
    check) and, for the others, the moments of each fixed block of
    :data:`SEED_BLOCK_SIZE` trials merged in order (:class:`Moments`), so that no number
    depends on the evaluation block size, the number of workers or where they ran.
    """

    def __init__(
        self,
        total: int,
        keep: bool | frozenset[str] | Literal["auto"],
        nan_policy: NanPolicy,
        sketch: bool | frozenset[str] | None = None,
    ) -> None:
        self.total, self.keep, self.nan_policy = total, keep, nan_policy
        self.sketch_spec = sketch
        self.sketch: frozenset[str] = frozenset()
        self.sketches: dict[str, QuantileSketch | None] = {}
        # the sketch of the seed blocks of the current sketch group, by output
        self.group_sketch: dict[str, QuantileSketch] = {}
        self.shapes: dict[str, tuple[int, ...]] | None = None
        self.kept: dict[str, NDArray[np.float64]] = {}
        self.filled = 0  # rows written to the kept arrays
        # kept arrays shared with workers (share()): every block's rows at its trials'
        # positions from trial ``base``, the non-finite ones left out at the end
        self.base: int | None = None
        self.masks: list[tuple[int, NDArray[np.bool_]]] = []
        self.omitted = 0
        self.first_bad: int | None = None
        self.bad_outputs: set[str] = set()
        self.buffer: dict[str, list[NDArray[np.float64]]] = {}
        self.groups: list[tuple[str, ...]] = []
        self.widths: dict[tuple[str, ...], int] = {}  # values a trial of each group
        self.moments: dict[tuple[str, ...], Moments] = {}
        # the streamed convergence curve of the scalar outputs not kept: (m, means, u)
        # of each group at seed-block ends, the next when m reaches ``trace_next``
        self.traces: dict[tuple[str, ...], list[tuple[int, NDArray[np.float64]]]] = {}
        self.trace_next: dict[tuple[str, ...], int] = {}

    def setup(self, shapes: dict[str, tuple[int, ...]]) -> None:
        self.shapes = shapes
        for what, spec in (("keep", self.keep), ("sketch", self.sketch_spec)):
            if isinstance(spec, frozenset):
                unknown = sorted(spec - set(shapes))
                if unknown:
                    raise InputError(
                        f"{what} names {', '.join(unknown)}, which the model does not return; "
                        f"its outputs are {', '.join(shapes) or 'unnamed'}",
                        field=what,
                    )
        limit = _memory_bytes() // 2
        if self.keep == "auto":
            need_all = sum(8 * self.total * max(1, math.prod(sh)) for sh in shapes.values())
            self.keep = need_all <= min(KEEP_AUTO_BYTES, limit)
            if self.keep is False and self.sketch_spec is None:
                self.sketch_spec = frozenset(n for n, sh in shapes.items() if not sh)
        keep = [
            n for n in shapes if self.keep is True or (self.keep is not False and n in self.keep)
        ]
        spec = self.sketch_spec
        self.sketch = frozenset(
            n
            for n in shapes
            if n not in keep and (spec is True or (isinstance(spec, frozenset) and n in spec))
        )
        wide = sorted(n for n in self.sketch if shapes[n])
        if wide:
            raise InputError(
                f"quantile sketches are for scalar outputs; {', '.join(wide)} are vectors",
                field="sketch",
            )
        need = sum(8 * self.total * max(1, math.prod(shapes[n])) for n in keep)
        if need > limit:
            raise InputError(
                f"keeping the samples of {self.total} trials needs {_gib(need)}, more than half "
                f"of this machine's memory ({_gib(2 * limit)}); run with keep=False (estimate, "
                "u and covariance only) or with fewer trials",
                field="trials",
            )
        for n in keep:
            self.kept[n] = np.empty((self.total, *shapes[n]))
        self.groups = _groups(shapes, self.kept)
        for g in self.groups:
            w = max(1, math.prod(shapes[g[0]]))
            self.widths[g] = len(g) * w
            self.moments[g] = Moments(
                0, np.zeros((len(g), w)), np.zeros((len(g), w, w) if w <= MAX_COV_DIM else w)
            )
            for n in g:
                self.buffer[n] = []
                self.sketches[n] = None
            if not shapes[g[0]]:
                self.traces[g] = []
                self.trace_next[g] = 0

    def _merge(self, g: tuple[str, ...], reduced: _Reduced) -> None:
        mom, sketches = reduced
        if mom is not None:
            self.moments[g] = self.moments[g].merge(mom)
            got = self.moments[g]
            if g in self.traces and got.n >= max(2, self.trace_next[g]):
                self.traces[g].append((got.n, np.stack([got.mean[:, 0], got.m2.reshape(-1)])))
                self.trace_next[g] = math.ceil(got.n * TRACE_STEP)
        for n, sk in sketches.items():
            acc = self.group_sketch.get(n)
            self.group_sketch[n] = sk if acc is None else acc.merge(sk)

    def _end_of_group(self, k: int, merged: dict[int, dict[str, QuantileSketch]]) -> None:
        """After seed block ``k``: at the end of its sketch group, merge the group's sketch."""
        if (k + 1) % SKETCH_GROUP and (k + 1) * SEED_BLOCK_SIZE < self.total:
            return
        whole = merged.get(k // SKETCH_GROUP, {})
        for n in self.sketch:
            here = self.group_sketch.pop(n, None)  # merged here, block by block
            sk = whole.get(n, here)  # or where the group's blocks ran
            if sk is not None:
                prev = self.sketches[n]
                self.sketches[n] = sk if prev is None else prev.merge(sk)

    def add(self, d: _Digest) -> None:
        if self.shapes is None:
            self.setup(d.shapes)
        assert self.shapes is not None
        if d.shapes != self.shapes:
            raise InputError(
                f"the model returned outputs of shapes {_shape_text(d.shapes)} for trials from "
                f"{d.start} but {_shape_text(self.shapes)} before; expected the same outputs "
                "and shapes for every block",
                field="model",
            )
        if d.omitted and self.nan_policy == "raise" and self.first_bad is None:
            self.first_bad = d.first_bad
        self.bad_outputs.update(d.bad_outputs)
        self.omitted += d.omitted
        good = d.m - d.omitted
        if self.base is None:
            for n, kept in self.kept.items():
                kept[self.filled : self.filled + good] = d.rows[n]
        else:
            pos = d.start - self.base
            if d.ok is not None:
                self.masks.append((pos, d.ok))
            if not d.written:  # a worker that could not reach the shared arrays
                for n, kept in self.kept.items():
                    if d.ok is None:
                        kept[pos : pos + d.m] = d.rows[n]
                    else:
                        kept[pos : pos + d.m][d.ok] = d.rows[n]
        self.filled += good
        for g, k, complete, part in d.pieces:
            scalar = not self.shapes[g[0]]  # reduced by seed block, its sketches too
            if complete:
                self._merge(g, part)
            else:
                for n, value in zip(g, part, strict=True):
                    self.buffer[n].append(value)
                s = reduction_block_trials(self.widths[g])
                if d.start + d.m < min((k + 1) * s, self.total):
                    continue
                self._close(g)
            if scalar:
                self._end_of_group(k, d.merged)

    def share(self, shared: SharedRows, base: int) -> None:
        """Keep the samples in ``shared``'s arrays, row ``t - base`` for trial ``t``."""
        self.kept = dict(shared.arrays)
        self.base = base

    def _kept(self, n: str) -> NDArray[np.float64]:
        """The kept samples of output ``n``, without the non-finite trials."""
        if not self.masks:
            return self.kept[n][: self.filled]
        ok = np.ones(self.kept[n].shape[0], dtype=np.bool_)
        for pos, mask in self.masks:
            ok[pos : pos + mask.size] = mask
        return self.kept[n][ok]

    def _close(self, g: tuple[str, ...]) -> None:
        if self.buffer[g[0]]:
            xs = [_block_array(self.buffer[n]) for n in g]
            self._merge(g, _reduce(g, xs, self.sketch))
            for n in g:
                self.buffer[n].clear()

    def check(self) -> None:
        """Raise for the non-finite values seen under ``nan_policy="raise"``."""
        if self.first_bad is None:
            return
        what = ", ".join(f"output {n!r}" for n in self.bad_outputs if n) or "the model value"
        raise InputError(
            f"{what} is not finite (NaN or inf) in {self.omitted} of {self.total} trials "
            f"(first at trial {self.first_bad}); expected finite values, or "
            "nan_policy='omit' to leave those trials out",
            field="model",
        )

    def results(self, **run: Any) -> dict[str, MonteCarloResult]:
        assert self.shapes is not None
        self.check()
        for g in self.groups:
            if self.buffer[g[0]]:
                self._close(g)
                if not self.shapes[g[0]]:
                    self._end_of_group((self.total - 1) // SEED_BLOCK_SIZE, {})
        moments = {
            n: mom for g in self.groups for n, mom in zip(g, self.moments[g].unstack(), strict=True)
        }
        traces: dict[str, Trace] = {}
        for g, points in self.traces.items():
            got = self.moments[g]
            if got.n >= 2 and (not points or points[-1][0] != got.n):
                points.append((got.n, np.stack([got.mean[:, 0], got.m2.reshape(-1)])))
            if not points:
                continue
            m = np.array([n for n, _ in points], dtype=np.int64)
            both = np.stack([v for _, v in points], axis=-1)  # (2, len(g), points)
            u = np.sqrt(np.clip(both[1] / (m - 1), 0.0, None))
            for i, n in enumerate(g):
                traces[n] = Trace(m=m, estimate=both[0, i].copy(), u=u[i].copy())
        out: dict[str, MonteCarloResult] = {}
        for n, shape in self.shapes.items():
            if n in self.kept:
                out[n] = MonteCarloResult(samples=self._kept(n), omitted=self.omitted, **run)
            else:
                out[n] = MonteCarloResult(
                    samples=None,
                    moments=moments[n],
                    sketch=self.sketches[n],
                    trace=traces.get(n),
                    scalar=len(shape) == 0,
                    omitted=self.omitted,
                    **run,
                )
        _check_summary(out)
        return out


def _check_summary(results: Mapping[str, MonteCarloResult]) -> None:
    """Refuse finite model values whose estimate or ``u`` overflows float64.

    Every value may be finite while their mean or variance is not: a variance overflows
    once the values spread beyond about ``1e154`` (the square root of the largest
    float). The result would carry ``u = inf``; the run stops here instead, naming the
    output, as for a model value that is not finite.
    """
    with np.errstate(over="ignore", invalid="ignore"):
        for n, res in results.items():
            est, u = res.estimate_vector, res.u_vector
            if np.isfinite(est).all() and np.isfinite(u).all():
                continue
            what = f"output {n!r}" if n else "the model value"
            which = (
                "standard uncertainty overflows"
                if np.isfinite(est).all()
                else "estimate and standard uncertainty overflow"
            )
            raise InputError(
                f"{what} is finite in every trial but its {which} float64: the values "
                "spread beyond about 1e154, whose square overflows; expected a model whose "
                "values a float64 variance holds (state the output in a larger unit)",
                field="model",
            )


def _shape_text(shapes: Mapping[str, tuple[int, ...]]) -> str:
    return ", ".join(f"{n or 'y'}: (m{''.join(f', {k}' for k in sh)})" for n, sh in shapes.items())


class _Runner:
    """Evaluates trial ranges, in this process (reusing drawn seed blocks) or on a pool."""

    def __init__(
        self,
        model: Callable[..., Any],
        dists: dict[str, Distribution],
        seed: int,
        method: NormalMethod,
        block_size: int,
        workers: int,
        executor: ExecutorKind | Any,
        scheduler: Any = None,
        sampling: Sampling = "random",
        joint: JointDraw | None = None,
    ) -> None:
        self.model, self.dists, self.seed, self.method = model, dists, seed, method
        self.block_size = evaluation_block_size(dists, block_size)
        self.workers, self.executor, self.scheduler = workers, executor, scheduler
        self.sampling = sampling
        self.joint = joint
        self.source = BlockSource(dists, seed, method, sampling, joint)
        #: trials per seed block (quasi-random points are scrambled block by block)
        self.seed_block = next(iter(self.source.sizes.values()), SEED_BLOCK_SIZE)

    def run(
        self,
        start: int,
        stop: int,
        collector: _Collector,
        progress: ProgressFn | None = None,
    ) -> None:
        """Evaluate trials ``start..stop-1``, handing each block's digest on in order.

        ``progress(b, stop)`` is called after each block, ``b`` the end of the block.
        """
        with one_blas_thread():  # the first block too, which runs here before the map
            self._run(start, stop, collector, progress)

    def _shared(self, collector: _Collector, start: int) -> SharedRows | None:
        """The kept arrays in shared memory, where worker processes would send them back.

        Worker processes of this machine then write the kept rows straight into them;
        threads of this process hand theirs over without a copy anyway.
        """
        if not collector.kept or not (
            self.executor in ("process", "dask")
            or (
                isinstance(self.executor, cf.Executor)
                and not isinstance(self.executor, cf.ThreadPoolExecutor)
            )
        ):
            return None
        assert collector.shapes is not None
        shapes = {n: collector.shapes[n] for n in collector.kept}
        shared = SharedRows.create(collector.total, shapes, start)
        if shared is not None:
            collector.share(shared, start)
        return shared

    def _run(
        self,
        start: int,
        stop: int,
        collector: _Collector,
        progress: ProgressFn | None,
    ) -> None:
        bs = self.block_size
        total = start + collector.total
        serial = self.workers == 1 and self.executor in ("thread", "process")
        # the spans are listed once the first block has settled the outputs' shapes, and
        # with them whether the run fits: a run refused for its size (10^12 trials kept)
        # is refused at once, not after listing its 1.5e7 blocks (13 s)
        rest = start
        if collector.shapes is None and serial:
            # the first block runs here: its outputs' names and shapes settle what is
            # kept, sketched or reduced
            a, b = start, min(start + bs, stop)
            outs = _evaluate(self.model, self.source.trials(a, b), a, b)
            collector.setup({n: arr.shape[1:] for n, arr in outs.items()})
            assert collector.keep != "auto"
            collector.add(_digest(a, outs, collector.keep, total, collector.sketch))
            if progress is not None:
                progress(b, stop)
            rest = b
        elif collector.shapes is None:
            # on workers, the names and shapes of the outputs come from the first trial
            # alone, evaluated here and left: every block then runs on the workers, none
            # here while they wait (a verification's first block of 256 trials is 0.45 s)
            outs = _evaluate(self.model, self.source.trials(start, start + 1), start, start + 1)
            collector.setup({n: arr.shape[1:] for n, arr in outs.items()})
        spans = [(a, min(a + bs, stop)) for a in range(rest, stop, bs)]
        keep, sketch = collector.keep, collector.sketch
        assert keep != "auto"
        tasks: list[tuple[tuple[int, int], ...]]
        run_task: Callable[[tuple[tuple[int, int], ...]], list[_Digest]]
        shared: SharedRows | None = None
        if serial:
            # in this process, one evaluation block at a time, drawing from self.source
            # (whose last seed block carries over to the next evaluation block)
            tasks = [(span,) for span in spans]

            def here(task: tuple[tuple[int, int], ...]) -> list[_Digest]:
                ((a, b),) = task
                outs = _evaluate(self.model, self.source.trials(a, b), a, b)
                return [_digest(a, outs, keep, total, sketch)]

            run_task = here

        else:
            job = _BlockJob(
                self.model,
                self.dists,
                self.seed,
                self.method,
                keep,
                total,
                sketch,
                self.sampling,
                self.joint,
            )
            assert collector.shapes is not None
            shapes = collector.shapes
            width = sum(max(1, math.prod(shapes[n])) for n in collector.kept) + len(sketch)
            bs = self.block_size
            workers = planned_workers(self.workers, self.executor)
            per = _blocks_per_task(len(spans), workers, 8 * bs * width)
            group = SKETCH_GROUP * SEED_BLOCK_SIZE
            if sketch and group % bs == 0:  # whole sketch groups in a task
                q = group // bs
                per = -(-per // q) * q
            # whole reduction blocks of the outputs not kept in a task, where one spans
            # several evaluation blocks: the task hands back their moments (_join_pieces)
            for g in collector.groups:
                r = reduction_block_trials(collector.widths[g])
                if r > bs and r % bs == 0 and 8 * r * collector.widths[g] > TASK_BYTES // 64:
                    q = r // bs
                    per = -(-per // q) * q
            # tasks cut at multiples of per·bs trials from trial 0, as the groups are
            cut: dict[int, list[tuple[int, int]]] = {}
            for span in spans:
                cut.setdefault(span[0] // (per * bs), []).append(span)
            tasks = [tuple(t) for t in cut.values()]
            shared = self._shared(collector, start)
            if shared is not None:
                job = dataclasses.replace(job, shared=shared.ref)
            run_task = _TaskJob(job)
        digests_in_order = map_blocks(
            run_task,
            tasks,
            workers=self.workers,
            executor=self.executor,
            scheduler=self.scheduler,
        )
        try:
            for task, digests in zip(tasks, digests_in_order, strict=True):
                for (_, b), digest in zip(task, digests, strict=True):
                    collector.add(digest)
                    if progress is not None:
                        progress(b, stop)
        finally:
            if shared is not None:
                shared.close()  # the file's name; the arrays keep the mapping


def _check_names(value: Any, field: str, allowed: tuple[Any, ...]) -> Any:
    if (value in allowed and not isinstance(value, int | float)) or isinstance(value, bool):
        return value
    if isinstance(value, str) or not isinstance(value, Iterable):
        raise InputError(
            f"expected {' or '.join(map(repr, allowed))} or a list of output names, got {value!r}",
            field=field,
        )
    names = frozenset(value)
    if not all(isinstance(n, str) for n in names):
        raise InputError(
            f"expected output names as strings, got {sorted(map(repr, names))}", field=field
        )
    return names


@overload
def monte_carlo(
    model: Callable[..., Mapping[str, npt.ArrayLike]],
    inputs: Mapping[str, Any],
    trials: int | None = None,
    seed: int | np.random.SeedSequence | None = None,
    *,
    adaptive: bool = False,
    tolerance: float | None = None,
    ndig: int = 2,
    p: float = 0.95,
    block_size: int = DEFAULT_BLOCK_SIZE,
    workers: int = 1,
    normal_method: NormalMethod = "default",
    nan_policy: NanPolicy = "raise",
    kind: Literal["symmetric", "shortest"] = "symmetric",
    max_trials: int = 10**8,
    executor: ExecutorKind | Any = "thread",
    scheduler: Any = None,
    progress: ProgressFn | None = None,
    keep: bool | Literal["auto"] | Iterable[str] = "auto",
    sketch: bool | Iterable[str] | None = None,
    sampling: Sampling = "random",
    correlation: Any = None,
    copula: Any = "gaussian",
) -> MonteCarloResults: ...


@overload
def monte_carlo(
    model: Callable[..., npt.ArrayLike],
    inputs: Mapping[str, Any],
    trials: int | None = None,
    seed: int | np.random.SeedSequence | None = None,
    *,
    adaptive: bool = False,
    tolerance: float | None = None,
    ndig: int = 2,
    p: float = 0.95,
    block_size: int = DEFAULT_BLOCK_SIZE,
    workers: int = 1,
    normal_method: NormalMethod = "default",
    nan_policy: NanPolicy = "raise",
    kind: Literal["symmetric", "shortest"] = "symmetric",
    max_trials: int = 10**8,
    executor: ExecutorKind | Any = "thread",
    scheduler: Any = None,
    progress: ProgressFn | None = None,
    keep: bool | Literal["auto"] | Iterable[str] = "auto",
    sketch: bool | Iterable[str] | None = None,
    sampling: Sampling = "random",
    correlation: Any = None,
    copula: Any = "gaussian",
) -> MonteCarloResult: ...


def monte_carlo(
    model: Callable[..., Any],
    inputs: Mapping[str, Any],
    trials: int | None = None,
    seed: int | np.random.SeedSequence | None = None,
    *,
    adaptive: bool = False,
    tolerance: float | None = None,
    ndig: int = 2,
    p: float = 0.95,
    block_size: int = DEFAULT_BLOCK_SIZE,
    workers: int = 1,
    normal_method: NormalMethod = "default",
    nan_policy: NanPolicy = "raise",
    kind: Literal["symmetric", "shortest"] = "symmetric",
    max_trials: int = 10**8,
    executor: ExecutorKind | Any = "thread",
    scheduler: Any = None,
    progress: ProgressFn | None = None,
    keep: bool | Literal["auto"] | Iterable[str] = "auto",
    sketch: bool | Iterable[str] | None = None,
    sampling: Sampling = "random",
    correlation: Any = None,
    copula: Any = "gaussian",
) -> MonteCarloResult | MonteCarloResults:
    """Propagate the input distributions through a vectorised model (JCGM 101 §7).

    The one Monte Carlo engine of mtmc: an expression, a measurement graph, a
    verification or an artefact run are each a vectorised model that this function
    evaluates block by block.

    Parameters
    ----------
    model : callable
        ``model(**arrays)``: receives each input by name as an array whose first axis is
        the trial (``(m,)`` for a scalar input, ``(m, k)`` for a ``k``-variate one; the
        arrays are read-only) and returns the ``m`` model values, ``(m,)`` or ``(m, d)``,
        or a mapping of output names to such arrays (named outputs).
    inputs : mapping of str to Distribution, number or str
        The input quantities by name (numbers are constants, strings are parsed by
        :func:`~mtmc.uncertainty.distributions.parse_distribution`).
    trials : int, default 10**6
        Number of trials ``M`` of a fixed run. Not with ``adaptive``, which chooses it.
    seed : int, None or SeedSequence
        The seed; ``None`` draws fresh entropy, recorded in the result's ``seed`` so the
        run can be repeated exactly.
    adaptive : bool, default False, keyword-only
        Use the adaptive procedure of JCGM 101 §7.9.4 (see Notes).
    tolerance : float, optional, keyword-only
        Numerical tolerance ``δ`` for the adaptive procedure, in the unit of the output;
        by default ``δ`` follows from ``u(y)`` and ``ndig`` (JCGM 101 §7.9.2).
    ndig : int, default 2, keyword-only
        Significant decimal digits of ``u(y)`` regarded as meaningful.
    p : float, default 0.95, keyword-only
        Coverage probability used by the adaptive stopping rule.
    block_size : int, default DEFAULT_BLOCK_SIZE, keyword-only
        Trials per evaluation of the model (memory vs overhead; reduced for wide inputs,
        see :func:`~mtmc.uncertainty.sampling.evaluation_block_size`); it does not change
        the numbers.
    workers : int, default 1, keyword-only
        Number of local workers (threads by default; see :mod:`mtmc.parallel`); it does
        not change the numbers.
    normal_method : {"default", "box-muller"}, keyword-only
        How standard normal numbers are made (Box–Muller: Stryczek eq. 6).
    nan_policy : {"raise", "omit"}, keyword-only
        What to do with trials whose model value is not finite: ``"raise"`` an
        :class:`~mtmc.errors.InputError` giving their number and the first trial, or
        ``"omit"`` them (their number is in the result's ``omitted``). With named
        outputs a trial is left out of every output when one of them is not finite.
    kind : {"symmetric", "shortest"}, default "symmetric", keyword-only
        Coverage interval whose endpoints the adaptive stopping rule watches (as
        :meth:`MonteCarloResult.coverage_interval`).
    max_trials : int, default 10**8, keyword-only
        The adaptive procedure gives up with :class:`~mtmc.errors.ConvergenceError`
        beyond this number of trials.
    executor : {"thread", "process", "dask"} or concurrent.futures.Executor, keyword-only
        Where the blocks run when ``workers > 1`` (or an executor used as is);
        ``"dask"``: a Dask cluster, see :func:`mtmc.parallel.map_blocks`. Worker
        processes on this machine write kept samples straight into this process's
        arrays, in shared memory (:mod:`mtmc.uncertainty.shared_rows`); others send them
        back. The numbers are the same bits either way.
    scheduler : str or distributed.Client, optional, keyword-only
        With ``executor="dask"``, a running cluster (its scheduler's address, e.g.
        ``"tcp://127.0.0.1:8786"``, or a client); ``None`` starts a local cluster of
        ``workers`` processes for the call.
    progress : callable, optional, keyword-only
        ``progress(done, total)``, called in this process after each block with the
        number of trials evaluated so far (non-decreasing). A fixed run passes
        ``total = trials`` and ends with ``done == total``; an adaptive run passes
        ``total = None`` after each block of ``h`` trials and, once it stops,
        ``(n·h, n·h)``. It does not change any number.
    keep : "auto", bool or iterable of str, default "auto", keyword-only
        Which outputs keep all their samples (coverage intervals, histograms, ellipsoids
        need them): all (``True``), none (``False``), those named, or (``"auto"``) all
        while they take at most :data:`KEEP_AUTO_BYTES` (and half the machine's
        memory), else none, with a quantile sketch of every scalar output. The others
        keep their estimate and covariance only, from the moments of fixed blocks of
        :data:`~mtmc.uncertainty.sampling.SEED_BLOCK_SIZE` trials merged in trial order
        (:class:`~mtmc.uncertainty.results.Moments`): memory independent of ``M``, and
        the same numbers whatever ``block_size`` and ``workers``. Each result says
        whether it kept its samples (``kept``). An adaptive run keeps every output. A
        run asked to keep samples that would take more than half of the machine's
        memory is refused before it starts, with the size it would need.
    sketch : bool or iterable of str, optional, keyword-only
        Scalar outputs that are not kept but get a mergeable quantile sketch
        (:class:`~mtmc.uncertainty.sketch.QuantileSketch`), from which their coverage
        intervals are read with a stated rank error (``rank_error`` of the result); by
        default none, except with ``keep="auto"`` past its size.
    sampling : {"random", "sobol"}, default "random", keyword-only
        ``"random"``: pseudo-random draws (JCGM 101 §6). ``"sobol"``: randomised
        quasi-Monte Carlo, each seed block of ``2¹⁴`` trials (fewer for very wide
        inputs) an independently scrambled Sobol point set mapped through the inverse
        CDFs of the inputs (:mod:`mtmc.uncertainty.sampling`). For smooth models the
        error of the estimate and of ``u`` falls much faster than ``M^(-1/2)``; the
        blocks stay independent, so the adaptive procedure works on them as it does
        on pseudo-random blocks (see Notes). ``trials`` should then be a multiple of the
        seed block (a power of two): the points are balanced only in whole blocks.
    correlation : Correlation or mapping, optional, keyword-only
        Correlation coefficients between scalar inputs, ``{("a", "b"): 0.8}`` or a
        :class:`~mtmc.uncertainty.copula.Correlation` (``Correlation.from_matrix(R,
        order)``): the correlation matrix of the copula that joins their marginal PDFs
        (:mod:`mtmc.uncertainty.copula`, ``docs/correlation.md``). Without it, or with
        every coefficient 0 under the Gaussian copula, the inputs are independent and
        drawn exactly as without the argument.
    copula : "gaussian", ("t", dof), mapping or Copula, default "gaussian", keyword-only
        The copula that joins the correlated inputs: Gaussian, or Student t with ``dof``
        degrees of freedom (``{"kind": "t", "dof": 4}``), stronger dependence in the
        tails. Like the rest of the sampling, the numbers depend on neither
        ``block_size`` nor ``workers``.

    Returns
    -------
    MonteCarloResult or MonteCarloResults
        For a model returning one array: its :class:`MonteCarloResult` (the model values
        in trial order, with the seed, number of trials and, for an adaptive run, the
        number of blocks and the tolerance met). For named outputs: a
        :class:`MonteCarloResults` mapping each name to its :class:`MonteCarloResult`.
        The type follows from what the model returns, and so does the static type: a
        model annotated to return a ``Mapping`` gives ``MonteCarloResults``, one
        annotated to return an array ``MonteCarloResult``; for a model whose return type
        is not known (an unannotated function or ``lambda``) a type checker cannot tell
        which, and the call is of either type.

    Raises
    ------
    InputError
        Bad arguments (``trials`` with ``adaptive``); a model returning the wrong shape;
        non-finite values with ``nan_policy="raise"``; kept samples that would not fit
        in memory.
    DistributionError
        An input that is not a distribution.
    ConvergenceError
        The adaptive procedure did not meet the tolerance within ``max_trials``.

    Notes
    -----
    Adaptive procedure (JCGM 101 §7.9.4), for each component of each output:

    1. ``h = max(⌈100/(1 - p)⌉, 10⁴)`` trials per block (:func:`adaptive_block_size`);
    2. after block ``n >= 2``, with ``x⁽¹⁾..x⁽ⁿ⁾`` the block values of the estimate, of
       ``u`` and of the two interval endpoints, form ``s_x² = Σ(x⁽ʳ⁾ - x̄)² / (n(n-1))``;
    3. take ``u(y)`` from all ``n·h`` values and ``δ = numerical_tolerance(u(y), ndig)``
       (or the given ``tolerance``);
    4. stop when ``2 s_x <= δ`` for all four quantities; the result holds all ``n·h``
       values (the first ``n·h`` trials of the seed, as a fixed run of ``n·h`` trials).

    With ``sampling="sobol"`` the blocks of the procedure are whole seed blocks
    (``h`` rounded up to a multiple of the seed block, 2¹⁴ trials for ``p <= 0.9939``),
    each an independent scrambling: the rule stops on the spread of independent
    randomised quasi-Monte Carlo estimates, which for smooth models is far smaller than
    that of pseudo-random blocks of the same size, and not before
    :data:`RQMC_MIN_BLOCKS` of them (with two, ``s`` has one degree of freedom and
    ``2 s <= δ`` is often met by chance). Quantiles gain less than the estimate and
    ``u`` (an interval endpoint is the mean of an indicator, not a smooth function), and
    the position of a shortest interval, set by the minimum of a flat length, gains
    little: where the PDF is symmetric, ``kind="symmetric"`` watches the same interval
    with far less noise.

    Memory: a run leaves the allocator of the calling process as it is. With glibc's
    default ``malloc`` each block page-faults its arrays in afresh, which costs a graph run
    of 10⁶ trials a quarter of its time; the ``mtmc`` command keeps freed heap memory for
    the next block (:func:`mtmc.uncertainty.heap.keep_heap`), and a program that runs
    Monte Carlo often may call that once itself.

    With several workers the blocks are evaluated ahead in parallel but the stopping
    rule is applied block by block in order, so the number of trials and every value are
    the same for any ``workers``.

    The rule bounds the spread of the *block* values. For the shortest interval of the
    pooled ``n·h`` values this is a looser guarantee than for the estimate and ``u``:
    where the output PDF is flat near the interval's ends (JCGM 101 §9.3) the position of
    the pooled shortest interval scatters more than ``s_x`` suggests (on §9.3 with
    ``ndig = 2``, errors of up to about 2.5 δ were seen over 28 seeds), while its length
    is well determined. Where the endpoints of a shortest interval matter, watch the
    symmetric one (the default) or ask for a smaller ``tolerance``.
    """
    if not callable(model):
        raise InputError(f"expected a callable model, got {type(model).__name__}", field="model")
    seed_int = resolve_seed(seed)
    dists, method = prepare_inputs(inputs, normal_method)
    sampling = check_sampling(sampling, method)
    block_size = check_int(block_size, "block_size", 1)
    workers = check_int(workers, "workers", 1)
    if nan_policy not in ("raise", "omit"):
        raise InputError(f"expected 'raise' or 'omit', got {nan_policy!r}", field="nan_policy")
    if kind not in ("shortest", "symmetric"):
        raise InputError(f"expected 'shortest' or 'symmetric', got {kind!r}", field="kind")
    keep_set = _check_names(keep, "keep", (True, False, "auto"))
    sketch_set = _check_names(sketch, "sketch", (True, False, None))
    joint = joint_sampler(correlation, copula, dists)
    runner = _Runner(
        model, dists, seed_int, method, block_size, workers, executor, scheduler, sampling, joint
    )

    if adaptive:
        if trials is not None:
            raise InputError(
                f"trials = {trials!r} was given with adaptive=True, which chooses the number "
                "of trials itself; give max_trials (and tolerance or ndig) instead",
                field="trials",
            )
        return _adaptive(
            runner,
            seed_int,
            method,
            p=check_probability(p),
            ndig=check_int(ndig, "ndig", 1),
            tolerance=tolerance,
            nan_policy=nan_policy,
            kind=kind,
            max_trials=check_int(max_trials, "max_trials", 1),
            progress=progress,
        )
    m_total = check_int(10**6 if trials is None else trials, "trials", 2)
    collector = _Collector(m_total, keep_set, nan_policy, sketch_set)
    runner.run(0, m_total, collector, progress)
    collector.check()
    good = m_total - collector.omitted
    if good < 2:
        raise InputError(
            f"only {good} of {m_total} trials gave a finite value; need at least 2",
            field="model",
        )
    results = collector.results(
        trials=m_total, seed=seed_int, normal_method=method, sampling=sampling
    )
    return _package(results, m_total, seed_int, collector.omitted)


def _package(
    results: dict[str, MonteCarloResult], trials: int, seed: int, omitted: int
) -> MonteCarloResult | MonteCarloResults:
    if list(results) == [_SINGLE]:
        return results[_SINGLE]
    return MonteCarloResults(outputs=results, trials=trials, seed=seed, omitted=omitted)


def _block_stats(vals: NDArray[np.float64], p: float, kind: str) -> NDArray[np.float64]:
    """Estimate, u, y_low, y_high of one block, per component: shape (4, d)."""
    x = vals.reshape(vals.shape[0], -1)
    rows = []
    for j in range(x.shape[1]):
        res = MonteCarloResult(samples=x[:, j], trials=x.shape[0], seed=None)
        lo, hi = res.coverage_interval(p, kind)  # type: ignore[arg-type]
        rows.append((res.estimate, res.u, lo, hi))
    return np.array(rows, dtype=np.float64).T


def _adaptive(
    runner: _Runner,
    seed: int,
    method: NormalMethod,
    *,
    p: float,
    ndig: int,
    tolerance: float | None,
    nan_policy: NanPolicy,
    kind: str,
    max_trials: int,
    progress: ProgressFn | None = None,
) -> MonteCarloResult | MonteCarloResults:
    if tolerance is not None:
        try:
            tol = float(tolerance)
        except (TypeError, ValueError):
            tol = math.nan
        if not (math.isfinite(tol) and tol > 0.0):
            raise InputError(
                f"expected a positive numerical tolerance, got {tolerance!r}", field="tolerance"
            )
    h = adaptive_block_size(p)
    min_blocks = 2
    if runner.sampling == "sobol":  # whole seed blocks: independent scramblings
        h = runner.seed_block * -(-h // runner.seed_block)
        min_blocks = RQMC_MIN_BLOCKS
    ahead = runner.workers if runner.workers > 1 else 1
    kept: list[Outputs] = []
    stats: list[NDArray[np.float64]] = []
    # running moments of all kept values, every component of every output side by side
    total: Moments | None = None
    omitted = 0
    n = 0
    delta = math.inf
    while True:
        if (n + ahead) * h > max_trials and n * h >= max_trials:
            raise ConvergenceError(
                f"adaptive Monte Carlo did not reach the numerical tolerance within "
                f"max_trials = {max_trials} ({n} blocks of {h}); last δ = {delta:.3g}",
                field="max_trials",
            )
        for i in range(ahead):  # blocks n..n+ahead-1, evaluated together
            start = (n + i) * h
            block = _Collector(h, True, nan_policy)
            runner.run(start, start + h, block)
            block.check()
            if h - block.omitted < 2:
                raise InputError(
                    f"only {h - block.omitted} of {h} trials of block {n + i} gave a finite value",
                    field="model",
                )
            omitted += block.omitted
            vals = {k: v[: block.filled] for k, v in block.kept.items()}
            kept.append(vals)
            flat = np.concatenate([v.reshape(v.shape[0], -1) for v in vals.values()], axis=1)
            stats.append(_block_stats(flat, p, kind))
            bm = Moments.of(flat)
            total = bm if total is None else total.merge(bm)
            nblocks = n + i + 1
            if progress is not None:
                progress(nblocks * h, None)
            if nblocks < min_blocks:
                continue
            s = np.stack(stats)  # (nblocks, 4, d)
            sd = s.std(axis=0, ddof=1) / math.sqrt(nblocks)  # (4, d)
            c = total.cov
            u_all = np.sqrt(np.clip(np.diag(c) if c.ndim == 2 else c, 0.0, None))
            if tolerance is not None:
                deltas = np.full(u_all.shape, tol)
            else:
                deltas = np.array(
                    [numerical_tolerance(float(ui), ndig) if ui > 0 else math.inf for ui in u_all]
                )
            delta = float(deltas.min())
            if np.all(2.0 * sd <= deltas):
                if progress is not None:
                    progress(nblocks * h, nblocks * h)
                results = {
                    name: MonteCarloResult(
                        samples=np.concatenate([b[name] for b in kept], axis=0),
                        trials=nblocks * h,
                        seed=seed,
                        adaptive=True,
                        blocks=nblocks,
                        block_trials=h,
                        tolerance=delta,
                        omitted=omitted,
                        normal_method=method,
                        sampling=runner.sampling,
                    )
                    for name in kept[0]
                }
                return _package(results, nblocks * h, seed, omitted)
        n += ahead
