"""Seeded, chunk-independent sampling of the input quantities.

One integer seed fixes every number of a run, whatever the chunking, the number of
workers, or the order of the inputs:

* The trials ``0, 1, ..., M-1`` are cut into *seed blocks* of the fixed size
  :data:`SEED_BLOCK_SIZE` (for an input of more than 64 components, of the smaller fixed
  size :func:`seed_block_trials` gives for its dimension). Seed block ``k`` is drawn
  from the ``k``-th spawned child of ``SeedSequence(seed)``, i.e.
  ``SeedSequence(seed, spawn_key=(k,))``.
* Within seed block ``k``, input ``name`` has its own stream, the child of that child
  keyed by a 64-bit hash of the name: ``SeedSequence(seed, spawn_key=(k, key(name)))``
  with ``key`` the first 8 bytes of SHA-256 of the UTF-8 name. Adding, removing or
  reordering inputs never changes the numbers of another input.
* Every seed block is always drawn in full (``SEED_BLOCK_SIZE`` values per input), and
  the trials needed are sliced from it. Hence the ``M`` trials of a run are the first
  ``M`` trials of any longer run with the same seed, and the *evaluation* blocks
  (``block_size``, the unit of work handed to the model and to the workers) may be of
  any size without changing a single number.

:data:`SEED_BLOCK_SIZE` is part of the reproducibility contract: changing it changes the
numbers of every seeded run.

Randomised quasi-Monte Carlo (``sampling="sobol"``)
---------------------------------------------------
With ``sampling="sobol"`` the inputs of a seed block are drawn together from one point
set: the first :func:`sobol_block_trials` points of a scrambled Sobol sequence in
``D`` dimensions (``scipy.stats.qmc.Sobol`` with ``scramble=True``: a random linear
matrix scrambling and a random digital shift), scrambled afresh for every seed block by
the Generator of ``SeedSequence(seed, spawn_key=(k, key("sobol")))`` (a stream no
pseudo-random run uses: a Sobol run draws no per-input stream). The seed blocks
are therefore independent randomisations of the same low-discrepancy point set: each is
an unbiased estimate, and their spread gives the error estimate of the run (the
adaptive procedure stops on it). Each input takes ``uniform_dims`` consecutive
dimensions (one for a scalar PDF, mapped through its inverse CDF; ``k`` for a
``k``-variate normal, through ``Φ⁻¹`` and the Cholesky factor), the inputs in **sorted
order of their names** (:func:`sobol_layout`): the order of the mapping does not
matter, but adding or removing an input moves the dimensions of the inputs after it in
that order, and so changes their numbers. A constant takes no dimension. As for
pseudo-random draws, no number depends on the evaluation blocks or the workers, and the
first ``M`` trials of a run are those of any longer run with the same seed; the points
are balanced in whole seed blocks, so ``M`` should be a multiple of the seed block.

Correlated inputs
-----------------
Inputs joined by a copula (``correlation`` of
:func:`~mtmc.uncertainty.montecarlo.monte_carlo`, :mod:`mtmc.uncertainty.copula`) are
drawn together, seed block by seed block, from the standard normals of their own
streams (or of their own Sobol coordinates); a t copula's common ``W`` has a stream of
its own (one more Sobol coordinate, after those of every input). The contract above
holds for them unchanged, and every other input draws what it draws without them.

Examples
--------
>>> from mtmc.uncertainty.distributions import Normal, Uniform
>>> inputs = {"x": Normal(0, 1), "y": Uniform(0, 1)}
>>> a = sample_inputs(inputs, 5000, seed=7)
>>> b = {k: np.concatenate([s[k] for _, _, s in iter_blocks(inputs, 5000, 7, 1234)])
...      for k in inputs}
>>> all(np.array_equal(a[k], b[k]) for k in inputs)
True
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterator, Mapping
from typing import Any, Literal, Protocol, cast

import numpy as np
from numpy.typing import NDArray

from mtmc.errors import InputError
from mtmc.uncertainty.distributions import (
    _NORMAL_METHODS,
    Distribution,
    NormalMethod,
    as_distribution,
)

__all__ = [
    "DEFAULT_BLOCK_SIZE",
    "MAX_SOBOL_DIMS",
    "Sampling",
    "sobol_block_trials",
    "sobol_layout",
    "sobol_points",
    "SEED_BLOCK_SIZE",
    "seed_block_trials",
    "sample_inputs",
    "evaluation_block_size",
    "input_generator",
    "iter_blocks",
    "resolve_seed",
]

Sampling = Literal["random", "sobol"]
_SAMPLINGS = ("random", "sobol")

#: The most dimensions of a Sobol point set (those of SciPy's direction numbers).
MAX_SOBOL_DIMS: int = 21201

#: Bits of a Sobol coordinate; each coordinate is moved by half a step, into (0, 1).
_SOBOL_BITS = 32

#: Number of trials drawn from one spawned child of the seed (fixed; see module docs).
SEED_BLOCK_SIZE: int = 16384

#: At most this many numbers of one input in one seed block (8 MiB of float64): an input
#: of dimension ``k > 64`` is drawn in seed blocks of fewer trials (:func:`seed_block_trials`).
MAX_SEED_BLOCK_VALUES: int = 2**20

#: Default number of trials per evaluation block (memory vs call overhead).
DEFAULT_BLOCK_SIZE: int = 65536

#: The drawn inputs of one evaluation block take at most this many bytes
#: (:func:`evaluation_block_size`). A model's temporaries scale with its inputs: a
#: verification of 5408 points (16 224 drawn values a trial) peaked at 560-590 MB with
#: 64 MiB blocks of 517 trials, for any number of trials above one block, and at 290 MB
#: with these of 256, in the same time (1000-10 000 trials; ``docs/performance.md``).
BLOCK_BYTES: int = 32 * 2**20

#: One seed block of every input is kept between evaluation blocks while this fits.
CACHE_BYTES: int = 256 * 2**20


def seed_block_trials(dim: int) -> int:
    """Trials per seed block of an input of dimension ``dim`` (0 for a scalar).

    :data:`SEED_BLOCK_SIZE` for inputs of up to 64 components; for wider inputs
    (e.g. the noise of every coordinate of every point of a verification,
    :class:`~mtmc.uncertainty.distributions.IID`) ``⌊MAX_SEED_BLOCK_VALUES / dim⌋``, so
    that one seed block holds at most :data:`MAX_SEED_BLOCK_VALUES` numbers. Like
    :data:`SEED_BLOCK_SIZE`, this rule is part of the reproducibility contract.

    Parameters
    ----------
    dim : int
        Dimension of the input.

    Returns
    -------
    int

    Examples
    --------
    >>> seed_block_trials(0), seed_block_trials(3), seed_block_trials(288)
    (16384, 16384, 3640)
    """
    width = max(1, int(dim))
    if width * SEED_BLOCK_SIZE <= MAX_SEED_BLOCK_VALUES:
        return SEED_BLOCK_SIZE
    return max(1, MAX_SEED_BLOCK_VALUES // width)


def resolve_seed(seed: int | np.random.SeedSequence | None) -> int:
    """The integer entropy that a run records, so that any run can be repeated.

    Parameters
    ----------
    seed : int, None or numpy.random.SeedSequence
        A non-negative integer is returned as is. ``None`` draws fresh entropy from the
        operating system (``SeedSequence().entropy``, 128 bits) and returns it. A
        ``SeedSequence`` gives its entropy (it must be a root sequence: no spawn key).

    Returns
    -------
    int
        The non-negative integer seed.

    Raises
    ------
    InputError
        For a negative or non-integer seed, or a spawned or list-entropy SeedSequence.

    Examples
    --------
    >>> resolve_seed(42)
    42
    >>> resolve_seed(np.random.SeedSequence(7))
    7
    >>> s = resolve_seed(None)
    >>> isinstance(s, int) and s >= 0
    True
    """
    if seed is None:
        entropy = np.random.SeedSequence().entropy
        return int(entropy)  # type: ignore[arg-type]
    if isinstance(seed, np.random.SeedSequence):
        if seed.spawn_key:
            raise InputError(
                "expected a root SeedSequence (no spawn_key), got one with spawn_key "
                f"{seed.spawn_key}",
                field="seed",
            )
        if not isinstance(seed.entropy, int | np.integer):
            raise InputError(
                "expected a SeedSequence with integer entropy, got a sequence", field="seed"
            )
        return int(seed.entropy)
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise InputError(
            f"expected a non-negative integer, None or a SeedSequence, got {seed!r}",
            field="seed",
        )
    return int(seed)


def name_key(name: str) -> int:
    return int.from_bytes(hashlib.sha256(name.encode("utf-8")).digest()[:8], "little")


def input_generator(seed: int, block: int, name: str) -> np.random.Generator:
    """The Generator that draws input ``name`` in seed block ``block``.

    Parameters
    ----------
    seed : int
        The run's seed (see :func:`resolve_seed`).
    block : int
        Index ``k`` of the seed block (trials ``k·SEED_BLOCK_SIZE`` onwards).
    name : str
        The input's name.

    Returns
    -------
    numpy.random.Generator
        PCG64 seeded by ``SeedSequence(seed, spawn_key=(block, key(name)))``.

    Examples
    --------
    >>> a = input_generator(1, 0, "x").random()
    >>> b = np.random.default_rng(np.random.SeedSequence(1).spawn(1)[0].spawn(1)[0]).random()
    >>> a == input_generator(1, 0, "x").random(), a != b
    (True, True)
    """
    ss = np.random.SeedSequence(seed, spawn_key=(int(block), name_key(name)))
    return np.random.Generator(np.random.PCG64(ss))


def check_seed(seed: Any) -> int:
    if seed is None:
        raise InputError(
            "expected the integer seed of the run (see resolve_seed), got None: numbers drawn "
            "from fresh entropy that is not recorded could not be drawn again",
            field="seed",
        )
    return resolve_seed(seed)


def sobol_layout(dists: Mapping[str, Distribution]) -> dict[str, tuple[int, int]]:
    """The Sobol dimensions of each input: name -> (first, count), names in sorted order.

    Parameters
    ----------
    dists : mapping of str to Distribution
        The inputs.

    Returns
    -------
    dict of str to (int, int)
        For each input (in sorted order of the names), its first dimension and its
        number of dimensions (``uniform_dims``).

    Examples
    --------
    >>> from mtmc.uncertainty.distributions import MultivariateNormal, Normal, Uniform
    >>> sobol_layout({"z": Normal(0, 1), "a": MultivariateNormal([0, 0], [[1, 0], [0, 1]]),
    ...               "m": Uniform(0, 1)})
    {'a': (0, 2), 'm': (2, 1), 'z': (3, 1)}
    """
    out: dict[str, tuple[int, int]] = {}
    first = 0
    for name in sorted(dists):
        k = dists[name].uniform_dims
        out[name] = (first, k)
        first += k
    return out


def sobol_block_trials(dims: int) -> int:
    """Points per seed block of a Sobol run in ``dims`` dimensions: a power of two.

    :data:`SEED_BLOCK_SIZE` (2¹⁴) while the block holds at most
    :data:`MAX_SEED_BLOCK_VALUES` coordinates, else the largest power of two that does
    (at least 2). Part of the reproducibility contract, like :data:`SEED_BLOCK_SIZE`.

    Examples
    --------
    >>> sobol_block_trials(17), sobol_block_trials(288)
    (16384, 2048)
    """
    n = SEED_BLOCK_SIZE
    while n > 2 and n * max(1, dims) > MAX_SEED_BLOCK_VALUES:
        n //= 2
    return n


def _sobol_key() -> int:
    return name_key("sobol")


def sobol_points(seed: int, block: int, dims: int, n: int) -> NDArray[np.float64]:
    """The scrambled Sobol points of seed block ``block``: shape ``(n, dims)`` in (0, 1).

    Parameters
    ----------
    seed : int
        The run's seed.
    block : int
        Index of the seed block; each block is scrambled independently.
    dims : int
        Number of dimensions, at most :data:`MAX_SOBOL_DIMS`.
    n : int
        Number of points, a power of two (the first ``n`` of the sequence).

    Returns
    -------
    ndarray, shape (n, dims)
        The points of ``scipy.stats.qmc.Sobol(dims, scramble=True, bits=32)`` seeded by
        the Generator of ``SeedSequence(seed, spawn_key=(block, key("sobol")))``, moved
        by half a step, 2⁻³³, so that no coordinate is 0 or 1 (every inverse CDF is
        finite; a normal input reaches 6.2 standard deviations).

    Examples
    --------
    >>> u = sobol_points(1, 0, 3, 1024)
    >>> u.shape, bool(np.all((u > 0) & (u < 1))), np.array_equal(u, sobol_points(1, 0, 3, 1024))
    ((1024, 3), True, True)
    """
    if n & (n - 1) or n < 1:
        raise InputError(f"expected a power of two points, got {n}", field="trials")
    if dims == 0:
        return np.empty((n, 0))
    from scipy.stats import qmc  # imported here: scipy.stats costs ~0.5 s at import

    ss = np.random.SeedSequence(seed, spawn_key=(int(block), _sobol_key()))
    eng = qmc.Sobol(
        dims, scramble=True, bits=_SOBOL_BITS, rng=np.random.Generator(np.random.PCG64(ss))
    )
    u: NDArray[np.float64] = eng.random_base2(n.bit_length() - 1)
    u += 2.0 ** -(_SOBOL_BITS + 1)
    return u


def check_sampling(sampling: Any, method: str) -> Sampling:
    if sampling not in _SAMPLINGS:
        raise InputError(
            f"expected one of {', '.join(map(repr, _SAMPLINGS))}, got {sampling!r}",
            field="sampling",
        )
    if sampling == "sobol" and method != "default":
        raise InputError(
            f"normal_method={method!r} is for pseudo-random draws; quasi-random points are "
            "mapped through the normal quantile function",
            field="normal_method",
        )
    return cast(Sampling, sampling)


def check_int(value: Any, field: str, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        raise InputError(f"expected an integer >= {minimum}, got {value!r}", field=field)
    return int(value)


def prepare_inputs(
    inputs: Mapping[str, Any], normal_method: str
) -> tuple[dict[str, Distribution], NormalMethod]:
    if not isinstance(inputs, Mapping):
        raise InputError(
            f"expected a mapping of input names to distributions, got {type(inputs).__name__}",
            field="inputs",
        )
    dists: dict[str, Distribution] = {}
    for name, spec in inputs.items():
        if not isinstance(name, str) or not name:
            raise InputError(f"expected input names to be strings, got {name!r}", field="inputs")
        dists[name] = as_distribution(spec, field=name)
    if normal_method not in _NORMAL_METHODS:
        raise InputError(
            f"expected one of {', '.join(_NORMAL_METHODS)}, got {normal_method!r}",
            field="normal_method",
        )
    return dists, normal_method  # type: ignore[return-value]


class JointDraw(Protocol):
    """What :class:`BlockSource` asks of a correlated group of inputs drawn together.

    :func:`mtmc.uncertainty.copula.joint_sampler` gives one.
    """

    @property
    def names(self) -> tuple[str, ...]:
        """The inputs of the group, sorted."""
        ...  # pragma: no cover - a protocol's member

    @property
    def extra_dims(self) -> int:
        """Quasi-random coordinates taken besides the inputs' own."""
        ...  # pragma: no cover - a protocol's member

    def draw(self, seed: int, block: int, n: int, method: Any) -> dict[str, NDArray[np.float64]]:
        """Seed block ``block`` (``n`` trials) of every input of the group."""
        ...  # pragma: no cover - a protocol's member

    def from_points(
        self, u: NDArray[np.float64], layout: Mapping[str, tuple[int, int]], w_column: int
    ) -> dict[str, NDArray[np.float64]]:
        """The group's values from quasi-random points ``u``."""
        ...  # pragma: no cover - a protocol's member


class BlockSource:
    """Draws the seed blocks of each input on demand and slices the trials asked for.

    The last seed block of each input is kept for the next evaluation block, unless
    keeping one block of every input would take more than :data:`CACHE_BYTES`; then each
    evaluation block draws the seed blocks it needs and keeps only its own trials, so
    the memory of a run is bounded by the evaluation block, whatever the number of
    inputs (at the price of drawing a seed block again for each evaluation block in it).

    ``joint`` (:mod:`mtmc.uncertainty.copula`) draws the inputs of a correlated group
    together, seed block by seed block, from their own streams (or coordinates); a t
    copula's ``W`` takes one more quasi-random coordinate, after every input's.
    """

    def __init__(
        self,
        dists: dict[str, Distribution],
        seed: int,
        method: NormalMethod,
        sampling: Sampling = "random",
        joint: JointDraw | None = None,
    ):
        self.dists, self.seed, self.method, self.sampling = dists, seed, method, sampling
        self.joint = joint
        self.block_trials = SEED_BLOCK_SIZE
        if sampling == "sobol":
            self.layout = sobol_layout(dists)
            self.dims = sum(k for _, k in self.layout.values())
            self.w_column = self.dims  # a t copula's W: the coordinate after the inputs'
            self.dims += 0 if joint is None else joint.extra_dims
            if self.dims > MAX_SOBOL_DIMS:
                raise InputError(
                    f"the inputs take {self.dims} quasi-random dimensions, more than the "
                    f"{MAX_SOBOL_DIMS} of a Sobol sequence; use sampling='random'",
                    field="sampling",
                )
            n = sobol_block_trials(self.dims)
            self.block_trials = n
            self.sizes = {name: n for name in dists}
            self.caching = True  # the inputs of a seed block come from one point set
            # scalar inputs are mapped value by value: the first 2^j points of a block give
            # the first 2^j numbers of every input, so a short run makes only those
            self.prefix = all(d.dim == 0 for d in dists.values())
        else:
            self.sizes = {n: seed_block_trials(d.dim) for n, d in dists.items()}
            width = {n: max(1, d.dim) for n, d in dists.items()}
            self.caching = sum(self.sizes[n] * width[n] for n in dists) * 8 <= CACHE_BYTES
        self.cached: dict[str, tuple[int, NDArray[np.float64]]] = {}

    def _sobol_block(self, k: int, need: int) -> None:
        """Map the points of seed block ``k`` to every input (cached).

        Only the first ``2^j >= need`` points where the inputs are scalars (the same
        numbers as those of the whole block: a Sobol point set's first ``2^j`` points do
        not depend on how many follow, and the inverse CDFs act value by value), so that
        a run of a few hundred trials does not scramble and map 2¹⁴ points.
        """
        n = self.block_trials
        if self.prefix:
            n = min(n, 1 << max(0, need - 1).bit_length())
        u = sobol_points(self.seed, k, self.dims, n)
        together = (
            {} if self.joint is None else self.joint.from_points(u, self.layout, self.w_column)
        )
        for name, (first, count) in self.layout.items():
            arr = together.get(name)
            if arr is None:
                arr = self.dists[name].from_uniform(u[:, first : first + count])
            arr.setflags(write=False)
            self.cached[name] = (k, arr)

    def block(self, name: str, k: int, need: int | None = None) -> NDArray[np.float64]:
        """Seed block ``k`` of input ``name`` (read-only), or at least its first ``need`` trials."""
        want = self.sizes[name] if need is None else need
        hit = self.cached.get(name)
        if hit is not None and hit[0] == k and hit[1].shape[0] >= want:
            return hit[1]
        if self.sampling == "sobol":
            self._sobol_block(k, want)
            return self.cached[name][1]
        if self.joint is not None and name in self.joint.names:  # the group, drawn together
            group = self.joint.draw(self.seed, k, self.sizes[name], self.method)
            for member, drawn in group.items():
                drawn.setflags(write=False)
                self.cached[member] = (k, drawn)
            return self.cached[name][1]
        arr = self.dists[name].sample(
            input_generator(self.seed, k, name), self.sizes[name], normal_method=self.method
        )
        arr.setflags(write=False)  # a model must not change the drawn numbers
        if self.caching:
            self.cached[name] = (k, arr)
        return arr

    def trials(self, start: int, stop: int) -> dict[str, NDArray[np.float64]]:
        several = (stop - 1) // self.block_trials != start // self.block_trials
        if several and (self.sampling == "sobol" or self.joint is not None):
            # several seed blocks: each point set (each joint draw of a correlated group)
            # is made once, for every input
            whole = {
                name: np.empty((stop - start, *((d.dim,) if d.dim else ())))
                for name, d in self.dists.items()
            }
            self.fill(whole, start, stop, offset=start)
            for arr in whole.values():
                arr.setflags(write=False)
            return whole
        out: dict[str, NDArray[np.float64]] = {}
        for name, d in self.dists.items():
            s = self.sizes[name]
            k0, k1 = start // s, (stop - 1) // s
            if k0 == k1 and self.caching:  # inside one seed block: a view, no copy
                out[name] = self.block(name, k0, stop - k0 * s)[start - k0 * s : stop - k0 * s]
                continue
            arr = np.empty((stop - start, *((d.dim,) if d.dim else ())))
            self.fill_one(name, arr, start, stop, offset=start)
            arr.setflags(write=False)
            out[name] = arr
        return out

    def fill_one(
        self, name: str, out: NDArray[np.float64], start: int, stop: int, offset: int
    ) -> None:
        s = self.sizes[name]
        for k in range(start // s, (stop - 1) // s + 1):
            lo, hi = max(start, k * s), min(stop, (k + 1) * s)
            out[lo - offset : hi - offset] = self.block(name, k, hi - k * s)[
                lo - k * s : hi - k * s
            ]

    def fill(self, out: dict[str, NDArray[np.float64]], start: int, stop: int, offset: int) -> None:
        if self.sampling == "sobol":  # seed block by seed block: one point set each
            s = self.block_trials
            for k in range(start // s, (stop - 1) // s + 1):
                lo, hi = max(start, k * s), min(stop, (k + 1) * s)
                for name in self.dists:
                    self.fill_one(name, out[name], lo, hi, offset)
            return
        group = () if self.joint is None else self.joint.names
        for name in self.dists:
            if name not in group:
                self.fill_one(name, out[name], start, stop, offset)
        s = self.block_trials  # a correlated group: seed block by seed block, drawn once each
        for k in range(start // s, (stop - 1) // s + 1) if group else ():
            lo, hi = max(start, k * s), min(stop, (k + 1) * s)
            for name in group:
                self.fill_one(name, out[name], lo, hi, offset)


def evaluation_block_size(dists: Mapping[str, Distribution], block_size: int) -> int:
    """The trials per evaluation block: ``block_size``, less where the inputs are wide.

    The drawn inputs of one evaluation block take at most :data:`BLOCK_BYTES` (or one
    trial); where that limits the block, its trials are a power of two, so that the
    reduction blocks of wide outputs (:func:`mtmc.uncertainty.montecarlo.reduction_block_trials`,
    powers of two too) either hold whole evaluation blocks or are held whole by one, and a
    worker hands back their moments rather than their values. The number of trials per
    block never changes a number of a run.

    Parameters
    ----------
    dists : mapping of str to Distribution
        The inputs.
    block_size : int
        The requested trials per block.

    Returns
    -------
    int
        ``block_size`` if ``BLOCK_BYTES // (8 Σ max(1, dim))`` trials are at least that
        many, else the largest power of two of trials within it (at least 1).

    Examples
    --------
    >>> from mtmc.uncertainty.distributions import IID, Normal
    >>> evaluation_block_size({"x": Normal(0, 1)}, 65536)
    65536
    >>> evaluation_block_size({"noise": IID(Normal(0, 1), 16224)}, 65536)
    256
    """
    width = sum(max(1, d.dim) for d in dists.values())
    fit = BLOCK_BYTES // (8 * max(1, width))
    if fit >= block_size:
        return block_size
    # a power of two, as the reduction blocks of wide outputs are (one divides the other)
    return 1 << (max(1, fit).bit_length() - 1)


def iter_blocks(
    inputs: Mapping[str, Any],
    trials: int,
    seed: int,
    block_size: int = DEFAULT_BLOCK_SIZE,
    *,
    normal_method: NormalMethod = "default",
    start: int = 0,
    sampling: Sampling = "random",
) -> Iterator[tuple[int, int, dict[str, NDArray[np.float64]]]]:
    """Yield the draws of trials ``start..trials-1`` in evaluation blocks.

    Parameters
    ----------
    inputs : mapping of str to Distribution (or number, or text)
        The input quantities by name; values go through :func:`as_distribution`.
    trials : int
        Total number of trials ``M >= 1`` (the last block stops there).
    seed : int
        The run's seed, from :func:`resolve_seed`.
    block_size : int, default DEFAULT_BLOCK_SIZE
        Trials per yielded block (the last one may be shorter). It does not change the
        numbers.
    normal_method : {"default", "box-muller"}
        How standard normal numbers are made (see
        :func:`~mtmc.uncertainty.distributions.standard_normal`).
    start : int, default 0
        First trial (a multiple of nothing in particular; lets a worker draw a range).
    sampling : {"random", "sobol"}
        Pseudo-random draws, or scrambled Sobol points (see the module notes).

    Yields
    ------
    start, stop : int
        The trial range ``[start, stop)`` of the block.
    samples : dict of str to ndarray
        For each input (in the order of ``inputs``), its draws: shape ``(stop - start,)``
        or ``(stop - start, k)``. Arrays may be read-only views; copy before writing.

    Raises
    ------
    InputError
        For a bad ``trials``, ``block_size``, ``seed``, ``start`` or ``normal_method``.
    DistributionError
        For an input that is not a distribution.
    """
    trials = check_int(trials, "trials", 1)
    block_size = check_int(block_size, "block_size", 1)
    start = check_int(start, "start", 0)
    seed = check_seed(seed)
    dists, method = prepare_inputs(inputs, normal_method)
    source = BlockSource(dists, seed, method, check_sampling(sampling, method))
    for a in range(start, trials, block_size):
        b = min(a + block_size, trials)
        yield a, b, source.trials(a, b)


def sample_inputs(
    inputs: Mapping[str, Any],
    trials: int,
    seed: int,
    block_size: int = DEFAULT_BLOCK_SIZE,
    *,
    normal_method: NormalMethod = "default",
    sampling: Sampling = "random",
) -> dict[str, NDArray[np.float64]]:
    """Draw all ``trials`` of every input at once (the same numbers as :func:`iter_blocks`).

    Parameters
    ----------
    inputs : mapping of str to Distribution (or number, or text)
        The input quantities by name.
    trials : int
        Number of trials ``M >= 1``.
    seed : int
        The run's seed.
    block_size : int, default DEFAULT_BLOCK_SIZE
        Accepted for symmetry with :func:`iter_blocks`; it does not change the numbers.
    normal_method : {"default", "box-muller"}
        How standard normal numbers are made.
    sampling : {"random", "sobol"}
        Pseudo-random draws, or scrambled Sobol points (see the module notes).

    Returns
    -------
    dict of str to ndarray
        Each input's draws, shape ``(M,)`` or ``(M, k)``.

    Raises
    ------
    InputError, DistributionError
        As :func:`iter_blocks`.

    Examples
    --------
    >>> from mtmc.uncertainty.distributions import Normal
    >>> x = sample_inputs({"x": Normal(1, 2)}, 100_000, seed=3)["x"]
    >>> x.shape, bool(abs(x.mean() - 1) < 0.03)
    ((100000,), True)
    """
    trials = check_int(trials, "trials", 1)
    check_int(block_size, "block_size", 1)
    seed = check_seed(seed)
    dists, method = prepare_inputs(inputs, normal_method)
    out = {n: np.empty((trials, *((d.dim,) if d.dim else ()))) for n, d in dists.items()}
    BlockSource(dists, seed, method, check_sampling(sampling, method)).fill(
        out, 0, trials, offset=0
    )
    return out
