"""A Monte Carlo uncertainty budget beside the GUM's: one input at a time, and Sobol indices.

The GUM's budget (JCGM 100 §5.1.3) splits ``u²(y)`` into ``Σ c_i² u²(x_i)`` with ``c_i``
the first derivatives of the model at the estimates. Where the model is not linear over
the uncertainties of its inputs that split is not the whole story, and JCGM 101 Annex B
("Sensitivity coefficients and uncertainty budgets") says how to obtain the budget by
Monte Carlo instead. Two such budgets are computed here, both from the one engine
(:func:`mtmc.uncertainty.monte_carlo`) and its seeding:

:func:`monte_carlo_budget`
    JCGM 101 §B.2: for each input ``X_i`` the model is evaluated with ``X_i`` drawn from
    its PDF and every other input at its estimate (the expectation of its PDF); the
    standard deviation of those values is ``u_i(y)``, the Monte Carlo counterpart of the
    GUM's ``|c_i| u(x_i)``, and ``u_i(y)/u(x_i)`` a non-linear sensitivity coefficient.
    Where ``u_i(y)`` and ``|c_i| u(x_i)`` differ beyond Monte Carlo noise the model is
    not linear in ``X_i`` over its uncertainty.

:func:`sobol_indices`
    The variance-based indices of Sobol' (1993): the first-order index
    ``S_i = V[E(Y | X_i)] / V(Y)`` (the share of ``V(Y)`` that ``X_i`` explains alone)
    by the estimator of Saltelli et al. (2010), Table 2 (b), and the total index
    ``S_Ti = E[V(Y | X_~i)] / V(Y)`` (its share with all its interactions) by that of
    Jansen (1999), Table 2 (f), from the matrices ``A``, ``B`` and ``A_B^(i)`` (``A``
    with the columns of input ``i`` taken from ``B``). For an additive model
    ``Σ S_i = 1`` and ``S_Ti = S_i``; ``1 - Σ S_i`` is the share of the variance that
    comes from interactions, which the first-order law of propagation of the GUM leaves
    out (JCGM 100 §5.1.2 NOTE gives its second-order terms).

Both assume independent inputs (a multivariate input is one factor, its components
moving together). Each returns frozen results with Monte Carlo standard errors from
*batch means*: the trials are cut into the engine's seed blocks (each block has its own
streams, or, with ``sampling="sobol"``, its own scrambling of the Sobol points, so the
blocks are independent), every quantity is computed again on each block, and its
standard error is the standard deviation of the ``R`` block values divided by ``√R``
(for randomised quasi-Monte Carlo, the error estimate of independent replicates, Owen
1997). The estimate itself is computed from all the trials. Every number is a reduction
of the values that the engine keeps in trial order, so one seed gives the same bits
whatever the evaluation block size or the number of workers.

References
----------
JCGM 101:2008, Annex B. JCGM 100:2008 §5.1.2–5.1.3.
I. M. Sobol', "Sensitivity estimates for nonlinear mathematical models", Math. Model.
Comput. Exp. 1 (1993) 407–414.
M. J. W. Jansen, "Analysis of variance designs for model output", Comput. Phys. Commun.
117 (1999) 35–43.
A. Saltelli, P. Annoni, I. Azzini, F. Campolongo, M. Ratto, S. Tarantola, "Variance
based sensitivity analysis of model output. Design and estimator for the total
sensitivity index", Comput. Phys. Commun. 181 (2010) 259–270.
A. B. Owen, "Monte Carlo variance of scrambled net quadrature", SIAM J. Numer. Anal. 34
(1997) 1884–1910.

Examples
--------
>>> from mtmc.uncertainty import Normal, expression, gum
>>> f = expression("a * b")
>>> xs = {"a": Normal(2.0, 0.1), "b": Normal(3.0, 0.2)}
>>> s = sobol_indices(f, xs, trials=2**15, seed=1)
>>> [round(float(e.first), 2) for e in s.entries]  # 0.09/0.2504, 0.16/0.2504
[0.36, 0.64]
>>> b = monte_carlo_budget(f, xs, trials=2**15, seed=1, gum=gum(f, xs))
>>> [(e.name, round(e.u, 2), round(e.gum_contribution, 12), e.linear) for e in b.entries]
[('a', 0.3, 0.3, True), ('b', 0.4, 0.4, True)]
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mtmc.errors import InputError
from mtmc.frozen import frozen_value
from mtmc.uncertainty.distributions import Constant, Distribution, StudentT, as_distribution
from mtmc.uncertainty.formula import check_variables
from mtmc.uncertainty.montecarlo import ProgressFn, monte_carlo
from mtmc.uncertainty.propagation import GumResult
from mtmc.uncertainty.results import MonteCarloResult
from mtmc.uncertainty.sampling import (
    DEFAULT_BLOCK_SIZE,
    SEED_BLOCK_SIZE,
    Sampling,
    resolve_seed,
    sobol_block_trials,
)

__all__ = [
    "BudgetShare",
    "MonteCarloBudget",
    "SobolIndex",
    "SobolIndices",
    "agreement_factor",
    "monte_carlo_budget",
    "sobol_indices",
]

#: Two-sided level of the agreement checks: a Monte Carlo value and its reference
#: disagree when they differ by more than :func:`agreement_factor` standard errors.
AGREEMENT_ALPHA = 0.005

#: ... and by more than this fraction of the largest line of the budget (the rounding of
#: the GUM's numerical derivatives, far below any Monte Carlo noise).
AGREEMENT_REL = 1e-9

#: The prefix of the names under which the engine draws the matrix B (the matrix A is
#: drawn under the inputs' own names, from the same streams as a Monte Carlo run).
_B_PREFIX = "B:"


def agreement_factor(batches: int) -> float:
    """How many standard errors a value may stray from its reference by Monte Carlo noise.

    A standard error from ``R`` batch means has ``R - 1`` degrees of freedom, so the gap
    between an estimate and the value it estimates, over that standard error, follows
    Student's t with ``R - 1`` degrees of freedom: the factor is its ``1 - α/2``
    quantile with ``α =`` :data:`AGREEMENT_ALPHA` (4.03 for 8 batches, 254 for 2: two
    batches hardly tell noise from a difference).

    Parameters
    ----------
    batches : int
        ``R >= 2``.

    Returns
    -------
    float

    Examples
    --------
    >>> round(agreement_factor(8), 2), round(agreement_factor(16), 2)
    (4.03, 3.29)
    """
    if batches < 2:
        raise InputError(f"expected at least 2 batches, got {batches}", field="batches")
    from scipy.stats import t  # imported here: scipy.stats costs ~0.5 s at import

    return float(t.ppf(1.0 - AGREEMENT_ALPHA / 2, batches - 1))


# --------------------------------------------------------------------------- results
@dataclass(frozen=True)
class BudgetShare:
    """One line of the Monte Carlo budget (JCGM 101 §B.2): one input varied alone.

    Attributes
    ----------
    name : str
        The input quantity ``X_i``.
    u : float
        ``u_i(y)``: the standard deviation of the model values with ``X_i`` drawn from
        its PDF and every other input at its estimate.
    u_se : float
        The Monte Carlo standard error of ``u`` (batch means over the seed blocks).
    u_x : float or None
        The standard deviation of the PDF of ``X_i`` (None for a multivariate input).
    sensitivity : float or None
        ``u_i(y) / u(x_i)`` (JCGM 101 §B.2 NOTE: a sensitivity coefficient that holds
        over the whole PDF rather than at the estimate); None for a multivariate input
        or where ``u(x_i) = 0``.
    shift : float
        The mean of those model values less the model at the estimates: the change of
        the estimate that the non-linearity in ``X_i`` alone brings (0 for a model linear
        in ``X_i``).
    gum_contribution : float or None
        The GUM's ``|c_i| u(x_i)`` (JCGM 100 §5.1.3; for a multivariate input
        ``sqrt(c V cᵀ)``), where a :class:`~mtmc.uncertainty.propagation.GumResult` was given.
    linear_reference : float or None
        What ``u`` is for a model linear in ``X_i``: ``|c_i|`` times the standard
        deviation of the PDF that the Monte Carlo draws. It equals
        ``gum_contribution`` except for a scaled and shifted t input (JCGM 101 §6.4.9),
        whose standard deviation ``s/√n · sqrt(ν/(ν-2))`` exceeds the GUM's ``s/√n``.
    linear : bool or None
        Whether ``u`` agrees with :attr:`linear_reference` within Monte Carlo noise:
        ``|u - linear_reference| <= agreement_factor(batches) · u_se
        + linear_reference / N + 10⁻⁹ · scale``. The second term is the order ``1/N``
        by which the divisor ``N - 1`` of ``u`` (JCGM 101 eq. (13)) exceeds the spread
        of a stratified sample, which the batch spread of Sobol points does not show;
        the third the rounding of the GUM's numerical derivatives, with ``scale`` the
        largest ``u`` or reference of the budget. True: the model acts linearly in this
        input over its PDF; False: it does not; None without a GUM result.
    """

    name: str
    u: float
    u_se: float
    u_x: float | None
    sensitivity: float | None
    shift: float
    gum_contribution: float | None = None
    linear_reference: float | None = None
    linear: bool | None = None


@dataclass(frozen=True)
class MonteCarloBudget:
    """The Monte Carlo uncertainty budget of :func:`monte_carlo_budget`.

    Attributes
    ----------
    entries : tuple of BudgetShare
        One per input that is not a constant, in the order of the inputs.
    estimate : float
        The model at the input estimates, ``f(x)``.
    trials : int
        Trials of each one-at-a-time run.
    batches : int
        Seed blocks over which the standard errors were computed.
    seed : int
        The seed (the streams of each input are those of a Monte Carlo run of the same
        seed: the draws of ``X_i`` are the same numbers).
    sampling : str
        ``"random"`` or ``"sobol"``.
    """

    entries: tuple[BudgetShare, ...]
    estimate: float
    trials: int
    batches: int
    seed: int
    sampling: str

    def __post_init__(self) -> None:
        object.__setattr__(self, "entries", tuple(self.entries))

    @property
    def u_additive(self) -> float:
        """``sqrt(Σ u_i²(y))``: ``u(y)`` if the model were additive in its inputs."""
        return math.sqrt(sum(e.u**2 for e in self.entries))

    def entry(self, name: str) -> BudgetShare:
        """The line of input ``name``."""
        for e in self.entries:
            if e.name == name:
                return e
        raise InputError(
            f"no input {name!r} in the budget; it has {[e.name for e in self.entries]}",
            field=name,
        )


@dataclass(frozen=True)
class SobolIndex:
    """The first-order and total Sobol indices of one input, with standard errors.

    Attributes
    ----------
    name : str
        The input quantity ``X_i`` (a multivariate input is one factor).
    first, first_se : float
        ``S_i = V[E(Y | X_i)] / V(Y)`` (Saltelli et al. 2010, Table 2 (b)) and its
        standard error.
    total, total_se : float
        ``S_Ti = E[V(Y | X_~i)] / V(Y)`` (Jansen 1999; Saltelli et al. 2010, Table 2 (f))
        and its standard error.
    """

    name: str
    first: float
    first_se: float
    total: float
    total_se: float

    @property
    def interaction(self) -> float:
        """``S_Ti - S_i``: the share of ``V(Y)`` from interactions of ``X_i`` with others."""
        return self.total - self.first


@dataclass(frozen=True)
class SobolIndices:
    """The Sobol indices of :func:`sobol_indices`.

    Attributes
    ----------
    entries : tuple of SobolIndex
        One per input that is not a constant, in the order of the inputs.
    variance : float
        ``V(Y)``, from the model values of ``A`` and ``B``.
    first_sum, first_sum_se : float
        ``Σ S_i`` and its standard error; ``1 - Σ S_i`` is the share of ``V(Y)`` that
        comes from interactions (second- and higher-order terms).
    trials : int
        ``N``, the rows of each of the matrices ``A`` and ``B``.
    evaluations : int
        Model evaluations: ``N (D + 2)`` for ``D`` factors.
    batches : int
        Independent seed blocks over which the standard errors were computed.
    seed : int
        The seed.
    sampling : str
        ``"random"`` or ``"sobol"``.
    """

    entries: tuple[SobolIndex, ...]
    variance: float
    first_sum: float
    first_sum_se: float
    trials: int
    evaluations: int
    batches: int
    seed: int
    sampling: str

    def __post_init__(self) -> None:
        object.__setattr__(self, "entries", tuple(self.entries))

    @property
    def additive(self) -> bool:
        """Whether ``Σ S_i`` is 1 within Monte Carlo noise (no interaction seen).

        ``|1 - Σ S_i| <= agreement_factor(batches) · first_sum_se + 1/N``, the last term
        for the divisor ``2N - 1`` of ``V`` (order ``1/N``, not in the batch spread of
        stratified Sobol points).
        """
        noise = agreement_factor(self.batches) * self.first_sum_se
        return abs(1.0 - self.first_sum) <= noise + 1.0 / self.trials

    def entry(self, name: str) -> SobolIndex:
        """The indices of input ``name``."""
        for e in self.entries:
            if e.name == name:
                return e
        raise InputError(
            f"no input {name!r} among the indices; they have {[e.name for e in self.entries]}",
            field=name,
        )

    @property
    def first_vector(self) -> NDArray[np.float64]:
        """``S_i`` of the entries, shape ``(D,)``, read-only."""
        out: NDArray[np.float64] = frozen_value(np.array([e.first for e in self.entries]))
        return out

    @property
    def total_vector(self) -> NDArray[np.float64]:
        """``S_Ti`` of the entries, shape ``(D,)``, read-only."""
        out: NDArray[np.float64] = frozen_value(np.array([e.total for e in self.entries]))
        return out


# --------------------------------------------------------------------------- models
def _stack(parts: list[NDArray[Any]]) -> NDArray[Any]:
    return np.concatenate(parts, axis=0)


def _scalar_values(out: Any, rows: int, what: str) -> NDArray[np.float64]:
    if isinstance(out, Mapping):
        raise InputError(
            f"{what} is for a model of one scalar output; the model returns named outputs "
            f"({', '.join(map(str, out))}): give a model of the one output to analyse",
            field="model",
        )
    arr = np.asarray(out, dtype=np.float64)
    if arr.shape != (rows,):
        raise InputError(
            f"{what} is for a model of one scalar output, shape (m,); for m = {rows} the "
            f"model returned shape {arr.shape}: give a model of one component",
            field="model",
        )
    return arr


class _OneAtATime:
    """The model of every input varied alone, the others at their estimates: ``(m, D)``.

    Column ``j`` is ``f`` with input ``factors[j]`` as drawn and every other input at
    its estimate; the ``D`` sets of rows go to the model in one call.
    """

    def __init__(
        self,
        model: Callable[..., Any],
        factors: tuple[str, ...],
        estimates: Mapping[str, NDArray[np.float64]],
    ) -> None:
        self.model, self.factors, self.estimates = model, factors, estimates

    def __call__(self, **drawn: NDArray[np.float64]) -> NDArray[np.float64]:
        m = next(iter(drawn.values())).shape[0]
        d = len(self.factors)
        kwargs: dict[str, NDArray[Any]] = {}
        for name, x0 in self.estimates.items():
            fixed = np.broadcast_to(x0, (m, *x0.shape))
            parts = [drawn[name] if f == name else fixed for f in self.factors]
            kwargs[name] = _stack(parts)
        y = _scalar_values(self.model(**kwargs), d * m, "monte_carlo_budget")
        return np.ascontiguousarray(y.reshape(d, m).T)


class _SaltelliDesign:
    """The model on the rows of ``A``, ``B`` and ``A_B^(i)``, ``i = 1..D``: ``(m, D + 2)``.

    The engine draws ``A`` under the inputs' names and ``B`` under ``"B:" + name``; the
    ``D + 2`` matrices go to the model in one call.
    """

    def __init__(
        self, model: Callable[..., Any], names: tuple[str, ...], factors: tuple[str, ...]
    ) -> None:
        self.model, self.names, self.factors = model, names, factors

    def __call__(self, **drawn: NDArray[np.float64]) -> NDArray[np.float64]:
        m = next(iter(drawn.values())).shape[0]
        d = len(self.factors)
        kwargs: dict[str, NDArray[Any]] = {}
        for name in self.names:
            a = drawn[name]
            b = drawn.get(_B_PREFIX + name, a)  # a constant: the same in A and B
            kwargs[name] = _stack([a, b, *(b if f == name else a for f in self.factors)])
        y = _scalar_values(self.model(**kwargs), (d + 2) * m, "sobol_indices")
        return np.ascontiguousarray(y.reshape(d + 2, m).T)


# --------------------------------------------------------------------------- helpers
def _prepare(
    model: Any, inputs: Mapping[str, Any], what: str
) -> tuple[dict[str, Distribution], tuple[str, ...]]:
    if not callable(model):
        raise InputError(f"expected a callable model, got {type(model).__name__}", field="model")
    if not isinstance(inputs, Mapping) or not inputs:
        raise InputError(
            f"{what} expects a non-empty mapping of input names to distributions",
            field="inputs",
        )
    check_variables(model, inputs)
    dists = {str(n): as_distribution(d, field=str(n)) for n, d in inputs.items()}
    factors = tuple(n for n, d in dists.items() if not isinstance(d, Constant))
    if not factors:
        raise InputError(f"{what} needs at least one input that is not a constant", field="inputs")
    return dists, factors


def _batch_trials(sampling: Sampling, dims: int) -> int:
    return sobol_block_trials(dims) if sampling == "sobol" else SEED_BLOCK_SIZE


def _check_trials(trials: Any, block: int, sampling: str, what: str) -> tuple[int, int]:
    if isinstance(trials, bool) or not isinstance(trials, int | np.integer):
        raise InputError(f"expected an integer number of trials, got {trials!r}", field="trials")
    trials = int(trials)
    if trials < 2 * block or trials % block:
        raise InputError(
            f"{what} takes a whole number of at least 2 seed blocks of {block} trials "
            f"(sampling={sampling!r}): their spread gives the standard errors; got "
            f"trials = {trials}, e.g. {max(2, round(trials / block)) * block}",
            field="trials",
        )
    return trials, trials // block


def _spread(values: NDArray[np.float64]) -> NDArray[np.float64]:
    """Standard error from the batch values, ``(R, ...)``: ``s / √R``."""
    r = values.shape[0]
    out: NDArray[np.float64] = np.std(values, axis=0, ddof=1) / math.sqrt(r)
    return out


def _run(
    model: Callable[..., Any],
    inputs: Mapping[str, Distribution],
    trials: int,
    seed: int,
    sampling: Sampling,
    block_size: int,
    parallel: Mapping[str, Any],
) -> NDArray[np.float64]:
    res = monte_carlo(
        model,
        inputs,
        trials=trials,
        seed=seed,
        keep=True,
        sampling=sampling,
        block_size=block_size,
        **parallel,
    )
    assert isinstance(res, MonteCarloResult)
    assert res.samples is not None
    return np.asarray(res.samples)


# --------------------------------------------------------------------------- budget
def monte_carlo_budget(
    model: Callable[..., Any],
    inputs: Mapping[str, Any],
    *,
    trials: int,
    seed: int | np.random.SeedSequence | None,
    gum: GumResult | None = None,
    sampling: Sampling = "random",
    block_size: int = DEFAULT_BLOCK_SIZE,
    workers: int = 1,
    executor: Any = "thread",
    scheduler: Any = None,
    progress: ProgressFn | None = None,
) -> MonteCarloBudget:
    """The Monte Carlo uncertainty budget, one input at a time (JCGM 101 §B.2).

    For each input ``X_i`` that is not a constant the model is evaluated on ``trials``
    draws of ``X_i`` with every other input at its estimate (the expectation of its
    PDF); ``u_i(y)`` is the standard deviation of those values. All the inputs' runs go
    through one :func:`~mtmc.uncertainty.monte_carlo` run whose model evaluates the
    ``D`` sets of rows in one call, so that each input is drawn from its own stream of
    the seed: the draws of ``X_i`` are those of a Monte Carlo run of the full model with
    the same seed.

    Parameters
    ----------
    model : callable
        Vectorised model ``model(**arrays)`` of one scalar output (``(m,)``).
    inputs : mapping of str to Distribution, number or str
        The input quantities; a multivariate input is varied as one (its components
        together), a constant is left out of the budget.
    trials : int, keyword-only
        Trials of each input's run: a whole number of at least 2 seed blocks (2¹⁴
        trials each), whose spread gives the standard errors.
    seed : int, SeedSequence or None, keyword-only
        The seed (None draws fresh entropy, recorded in the result).
    gum : GumResult, optional, keyword-only
        The GUM result of the same model and inputs: each line then carries its
        ``|c_i| u(x_i)`` and says whether the two agree (:attr:`BudgetShare.linear`).
    sampling : {"random", "sobol"}, keyword-only
        Pseudo-random or randomised quasi-Monte Carlo draws (as the engine's).
    block_size, workers, executor, scheduler, progress : keyword-only
        As :func:`~mtmc.uncertainty.monte_carlo`; they change no number.

    Returns
    -------
    MonteCarloBudget

    Raises
    ------
    InputError
        No input that is not a constant, trials that are not a whole number of at least
        2 seed blocks, a model of a vector or named outputs, or a GUM result of other
        inputs or of a vector output.
    """
    dists, factors = _prepare(model, inputs, "monte_carlo_budget")
    seed_int = resolve_seed(seed)
    block = _batch_trials(sampling, sum(dists[n].uniform_dims for n in dists))
    trials, batches = _check_trials(trials, block, sampling, "monte_carlo_budget")
    if gum is not None:
        if not isinstance(gum, GumResult) or not gum.scalar:
            raise InputError("expected the GumResult of a scalar output", field="gum")
        missing = [n for n in factors if n not in {e.name for e in gum.budget}]
        if missing:
            raise InputError(
                f"the GUM result has no budget line for {', '.join(missing)}", field="gum"
            )
    estimates = {n: np.asarray(d.mean, dtype=np.float64) for n, d in dists.items()}
    parallel = {"workers": workers, "executor": executor, "scheduler": scheduler}
    if progress is not None:
        parallel["progress"] = progress
    y = _run(
        _OneAtATime(model, factors, estimates),
        {n: dists[n] for n in factors},
        trials,
        seed_int,
        sampling,
        block_size,
        parallel,
    )
    # f at the estimates, the reference of the shifts
    y0 = _scalar_values(
        model(**{n: x0[None, ...] for n, x0 in estimates.items()}), 1, "monte_carlo_budget"
    )[0]
    u = np.std(y, axis=0, ddof=1)
    u_batches = np.std(y.reshape(batches, block, -1), axis=1, ddof=1)
    u_se = _spread(u_batches)
    shift = np.mean(y, axis=0) - y0
    lines: list[BudgetShare] = []
    gum_lines = {} if gum is None else {e.name: e for e in gum.budget}
    for j, name in enumerate(factors):
        d = dists[name]
        u_x = float(d.std) if d.dim == 0 else None
        sens = float(u[j]) / u_x if u_x else None
        contrib = ref = None
        if name in gum_lines:
            line = gum_lines[name]
            contrib = float(line.contribution[0])
            ref = contrib
            if isinstance(d, StudentT) and line.u[0] > 0:  # JCGM 101 §6.4.9: s/√n vs the PDF
                ref = contrib * float(d.std) / float(line.u[0])
        lines.append(
            BudgetShare(
                name=name,
                u=float(u[j]),
                u_se=float(u_se[j]),
                u_x=u_x,
                sensitivity=sens,
                shift=float(shift[j]),
                gum_contribution=contrib,
                linear_reference=ref,
            )
        )
    scale = max([e.u for e in lines] + [e.linear_reference or 0.0 for e in lines])
    k = agreement_factor(batches)
    lines = [
        e
        if e.linear_reference is None
        else dataclasses.replace(
            e,
            linear=abs(e.u - e.linear_reference)
            <= k * e.u_se + e.linear_reference / trials + AGREEMENT_REL * scale,
        )
        for e in lines
    ]
    return MonteCarloBudget(
        entries=tuple(lines),
        estimate=float(y0),
        trials=trials,
        batches=batches,
        seed=seed_int,
        sampling=sampling,
    )


# --------------------------------------------------------------------------- Sobol
def _saltelli_jansen(
    f: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """``V``, ``S_i`` and ``S_Ti`` from model values ``(..., n, D + 2)`` (centred).

    ``f[..., 0]`` are the values of ``A``, ``f[..., 1]`` of ``B``, ``f[..., 2 + i]`` of
    ``A_B^(i)``. ``V`` is the variance of the ``2n`` values of ``A`` and ``B``;
    ``S_i = mean(f_B (f_ABi - f_A)) / V`` (Saltelli et al. 2010, Table 2 (b));
    ``S_Ti = mean((f_A - f_ABi)²) / 2V`` (Jansen 1999; Table 2 (f)).
    """
    fa, fb, fab = f[..., 0], f[..., 1], f[..., 2:]
    both = np.concatenate([fa, fb], axis=-1)
    var = np.var(both, axis=-1, ddof=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        first = np.mean(fb[..., None] * (fab - fa[..., None]), axis=-2) / var[..., None]
        total = 0.5 * np.mean((fa[..., None] - fab) ** 2, axis=-2) / var[..., None]
    return var, first, total


def sobol_indices(
    model: Callable[..., Any],
    inputs: Mapping[str, Any],
    *,
    trials: int,
    seed: int | np.random.SeedSequence | None,
    sampling: Sampling = "sobol",
    block_size: int = DEFAULT_BLOCK_SIZE,
    workers: int = 1,
    executor: Any = "thread",
    scheduler: Any = None,
    progress: ProgressFn | None = None,
) -> SobolIndices:
    """First-order and total Sobol indices (Saltelli et al. 2010; Jansen 1999).

    Two independent samples ``A`` and ``B`` of ``N = trials`` rows of the inputs are
    drawn by the engine (``A`` under the inputs' own names, so that with
    ``sampling="random"`` its rows are the first ``N`` trials of a Monte Carlo run of
    the same seed; ``B`` under ``"B:" + name``; with ``sampling="sobol"`` both are
    columns of one scrambled Sobol point set, as Saltelli et al. 2010 §3 recommend).
    For each factor ``i`` the matrix ``A_B^(i)`` is ``A`` with the columns of input
    ``i`` from ``B``. The ``D + 2`` matrices of an evaluation block go to the model in
    one call (``N (D + 2)`` evaluations in all). With ``V`` the variance of the values
    of ``A`` and ``B``:

    * ``S_i = (1/N) Σ f(B)_j (f(A_B^(i))_j - f(A)_j) / V`` (Saltelli et al. 2010,
      Table 2 (b));
    * ``S_Ti = (1/2N) Σ (f(A)_j - f(A_B^(i))_j)² / V`` (Jansen 1999; Saltelli et al.
      2010, Table 2 (f)).

    The values are centred on their mean first (this changes no expectation and keeps
    an output of large mean and small spread, as in JCGM 101 §9.3, from losing its
    digits). Standard errors are batch means over the seed blocks (module notes).

    Parameters
    ----------
    model : callable
        Vectorised model ``model(**arrays)`` of one scalar output (``(m,)``).
    inputs : mapping of str to Distribution, number or str
        The input quantities, independent; a multivariate input is one factor, a
        constant is held in ``A`` and ``B`` alike and has no index.
    trials : int, keyword-only
        ``N``: a whole number of at least 2 seed blocks (2¹⁴ rows while the ``2D``
        quasi-random dimensions are few, :func:`~mtmc.uncertainty.sampling.sobol_block_trials`).
    seed : int, SeedSequence or None, keyword-only
        The seed (None draws fresh entropy, recorded in the result).
    sampling : {"sobol", "random"}, default "sobol", keyword-only
        Scrambled Sobol points (randomised quasi-Monte Carlo, much smaller errors for a
        smooth model) or pseudo-random draws.
    block_size, workers, executor, scheduler, progress : keyword-only
        As :func:`~mtmc.uncertainty.monte_carlo`: ``block_size`` rows of each matrix per
        call, at most 65536 / (D + 2) so that a call holds no more rows than a block of a
        Monte Carlo run; they change no number.

    Returns
    -------
    SobolIndices

    Raises
    ------
    InputError
        No input that is not a constant, a zero variance of the output, trials that are
        not a whole number of at least 2 seed blocks, a model of a vector or named
        outputs, or an input whose name starts with ``"B:"``.
    """
    dists, factors = _prepare(model, inputs, "sobol_indices")
    clash = [n for n in dists if n.startswith(_B_PREFIX)]
    if clash:
        raise InputError(
            f"input names starting with {_B_PREFIX!r} are reserved for the matrix B",
            field=clash[0],
        )
    seed_int = resolve_seed(seed)
    drawn = dict(dists)
    for n in factors:
        drawn[_B_PREFIX + n] = dists[n]
    block = _batch_trials(sampling, sum(d.uniform_dims for d in drawn.values()))
    trials, batches = _check_trials(trials, block, sampling, "sobol_indices")
    parallel = {"workers": workers, "executor": executor, "scheduler": scheduler}
    if progress is not None:
        parallel["progress"] = progress
    f = _run(
        _SaltelliDesign(model, tuple(dists), factors),
        drawn,
        trials,
        seed_int,
        sampling,
        min(block_size, max(1, DEFAULT_BLOCK_SIZE // (len(factors) + 2))),
        parallel,
    )
    f = f - np.mean(f[:, :2])
    var, first, total = _saltelli_jansen(f)
    if not var > 0:
        raise InputError(
            "the model values do not vary (V(Y) = 0): the indices are not defined",
            field="model",
        )
    _, first_b, total_b = _saltelli_jansen(f.reshape(batches, block, -1))
    first_se = _spread(first_b)
    total_se = _spread(total_b)
    sum_se = float(_spread(first_b.sum(axis=-1)))
    entries = tuple(
        SobolIndex(
            name=n,
            first=float(first[j]),
            first_se=float(first_se[j]),
            total=float(total[j]),
            total_se=float(total_se[j]),
        )
        for j, n in enumerate(factors)
    )
    return SobolIndices(
        entries=entries,
        variance=float(var),
        first_sum=float(np.sum(first)),
        first_sum_se=sum_se,
        trials=trials,
        evaluations=trials * (len(factors) + 2),
        batches=batches,
        seed=seed_int,
        sampling=sampling,
    )
