"""A mergeable quantile sketch with a stated rank-error bound, for runs larger than memory.

A Monte Carlo run that does not keep its samples still needs coverage intervals (JCGM 101
§7.7), i.e. order statistics of ``M`` values. :class:`QuantileSketch` keeps a bounded
number of weighted values from which any order statistic is read with a known bound on
its rank error.

Construction (a deterministic multi-level compactor, after Munro and Paterson 1980 and
Manku, Rajagopalan and Lindsay 1998): level ``i`` holds sorted values of weight ``2^i``,
at most ``capacity`` of them. When a level overflows it is *compacted*: its values are
sorted and every other one is promoted to level ``i + 1`` with twice the weight (the
first, or the second, alternately from one compaction of that level to the next; an odd
last value stays). A compaction of level ``i`` changes the rank of any value by at most
``2^i``; the sketch adds these weights up in :attr:`QuantileSketch.rank_error`, a hard
bound (not a probabilistic one) on ``|rank read from the sketch - true rank|``.

The engine sketches each fixed block of :data:`~mtmc.uncertainty.sampling.SEED_BLOCK_SIZE`
trials and merges the sketches in trial order, so the sketch, and every interval read from
it, is the same bits whatever the evaluation blocks and the workers.

Examples
--------
>>> x = np.random.default_rng(1).normal(size=200_000)
>>> s = QuantileSketch.of(x[:100_000], capacity=1024).merge(
...     QuantileSketch.of(x[100_000:], capacity=1024))
>>> s.n, s.rank_error <= 0.01 * s.n
(200000, True)
>>> q = s.value_at_rank(int(0.975 * s.n))
>>> bool(abs(np.searchsorted(np.sort(x), q) - 0.975 * s.n) <= s.rank_error + 1)
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mtmc.errors import InputError

__all__ = ["SKETCH_CAPACITY", "QuantileSketch"]

#: Values per level of the engine's sketches (the rank error is about
#: ``M log2(M / capacity) / capacity``: 0.05 % of the trials at M = 10⁸).
SKETCH_CAPACITY: int = 16384


def _compact(
    levels: list[NDArray[np.float64]], flips: list[int], capacity: int
) -> tuple[list[NDArray[np.float64]], list[int], int]:
    """Compact every overflowing level, bottom up; returns the added rank error."""
    err = 0
    i = 0
    while i < len(levels):
        if levels[i].size > capacity:
            # a level is a few sorted runs end to end (QuantileSketch.of sorts, and a
            # compaction promotes a sorted subsequence), which the "stable" sort (a merge
            # of runs) puts in order in linear time: 0.10 ms for two runs of 16 384 values
            # against 1.2 ms for the default sort. Values alone: any sort gives the same
            # array (zeros are all +0.0, see QuantileSketch.of)
            a = np.sort(levels[i], kind="stable")
            odd = a.size % 2
            body, rest = (a[:-1], a[-1:]) if odd else (a, a[:0])
            promoted = body[flips[i] :: 2]
            flips[i] ^= 1
            levels[i] = rest
            if i + 1 == len(levels):
                levels.append(np.empty(0))
                flips.append(0)
            levels[i + 1] = np.concatenate([levels[i + 1], promoted])
            err += 2**i
        i += 1
    return levels, flips, err


@dataclass(frozen=True, eq=False)
class QuantileSketch:
    """Weighted values from which order statistics are read with a bounded rank error.

    Attributes
    ----------
    levels : tuple of ndarray
        ``levels[i]``: values of weight ``2^i`` (at most ``capacity`` each).
    flips : tuple of int
        The alternation state of each level's compactions (0 or 1).
    n : int
        Number of values summarised.
    rank_error : int
        Bound on ``|rank read - true rank|`` for any order statistic.
    capacity : int
        Values per level before it is compacted.
    """

    levels: tuple[NDArray[np.float64], ...]
    flips: tuple[int, ...]
    n: int
    rank_error: int
    capacity: int = SKETCH_CAPACITY

    def __post_init__(self) -> None:
        for a in self.levels:
            a.setflags(write=False)

    @classmethod
    def of(cls, values: NDArray[np.float64], capacity: int = SKETCH_CAPACITY) -> QuantileSketch:
        """The sketch of a set of values (exact while there are at most ``capacity``)."""
        if isinstance(capacity, bool) or not isinstance(capacity, int) or capacity < 2:
            raise InputError(f"expected a capacity >= 2, got {capacity!r}", field="capacity")
        # -0.0 + 0.0 is +0.0: one zero, so that the order of equal values cannot show;
        # sorted, so that every level of a sketch is made of sorted runs (see _compact)
        x = np.sort(np.array(values, dtype=np.float64).reshape(-1) + 0.0)
        levels, flips, err = _compact([x], [0], capacity)
        return cls(tuple(levels), tuple(flips), int(x.size), err, capacity)

    def merge(self, other: QuantileSketch) -> QuantileSketch:
        """The sketch of the union (the other's values after this one's)."""
        if other.capacity != self.capacity:
            raise InputError("cannot merge sketches of different capacities", field="capacity")
        depth = max(len(self.levels), len(other.levels))
        levels = []
        flips = []
        for i in range(depth):
            parts = [s.levels[i] for s in (self, other) if i < len(s.levels)]
            levels.append(np.concatenate(parts) if len(parts) > 1 else np.array(parts[0]))
            flips.append(self.flips[i] if i < len(self.flips) else other.flips[i])
        levels, flips, err = _compact(levels, flips, self.capacity)
        return QuantileSketch(
            tuple(levels),
            tuple(flips),
            self.n + other.n,
            self.rank_error + other.rank_error + err,
            self.capacity,
        )

    def weighted_values(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The sketch's values, ascending, and the weight (number of values) of each."""
        vals = np.concatenate(self.levels)
        wts = np.concatenate([np.full(a.size, 2.0**i) for i, a in enumerate(self.levels)])
        order = np.argsort(vals, kind="stable")
        return vals[order], wts[order]

    def _weighted(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        vals = np.concatenate(self.levels)
        wts = np.concatenate([np.full(a.size, 2.0**i) for i, a in enumerate(self.levels)])
        order = np.argsort(vals, kind="stable")
        return vals[order], np.cumsum(wts[order])

    def value_at_rank(self, rank: int) -> float:
        """The ``rank``-th smallest value (1-based), to within :attr:`rank_error` ranks."""
        if not 1 <= rank <= self.n:
            raise InputError(f"expected a rank in 1..{self.n}, got {rank}", field="rank")
        vals, cum = self._weighted()
        return float(vals[min(int(np.searchsorted(cum, rank)), vals.size - 1)])

    def shortest(self, q: int) -> tuple[float, float]:
        """The shortest interval holding ``q`` of the ``n`` values (JCGM 101 §7.7.3).

        Evaluated over the sketch's values as candidate lower ends. Each end's rank is
        known to within :attr:`rank_error`, so the interval holds ``q ± 2·rank_error``
        of the values and is no longer than the exact shortest interval holding
        ``q + 2·rank_error + 1``; where the PDF is flat between the candidate windows its
        position may differ more than that from the exact one (as between two seeds).
        """
        vals, cum = self._weighted()
        lower_rank = np.concatenate([[0.0], cum[:-1]]) + 1.0  # rank of each value
        hi_idx = np.searchsorted(cum, lower_rank + q - 1)
        ok = hi_idx < vals.size
        if not np.any(ok):
            raise InputError("too few values for the interval", field="p")
        widths = np.where(ok, vals[np.minimum(hi_idx, vals.size - 1)] - vals, np.inf)
        j = int(np.argmin(widths))
        return float(vals[j]), float(vals[int(hi_idx[j])])
