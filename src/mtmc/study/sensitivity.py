"""The ``[sensitivity]`` table of a ``propagate`` study: a Monte Carlo budget beside the GUM's.

A study that has the table runs, after its Monte Carlo and GUM, the one-at-a-time budget
of JCGM 101 §B.2 (:func:`mtmc.uncertainty.monte_carlo_budget`) and the first-order and
total Sobol indices (:func:`mtmc.uncertainty.sobol_indices`) of the same model, with the
seed of the run, and records them under ``sensitivity`` in ``result.json``
(``docs/sensitivity.md``)::

    [sensitivity]
    trials = 131072      # rows of each Sobol matrix, and trials of each one-at-a-time run
    sampling = "sobol"   # or "random"
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, cast

from mtmc.document import Fields
from mtmc.study.settings import MAX_TRIALS
from mtmc.uncertainty.distributions import Distribution
from mtmc.uncertainty.propagation import GumResult
from mtmc.uncertainty.sampling import SEED_BLOCK_SIZE, Sampling
from mtmc.uncertainty.sensitivity import (
    agreement_factor,
    monte_carlo_budget,
    sobol_indices,
)

__all__ = ["SensitivitySettings", "read_sensitivity", "sensitivity_record"]

#: Trials of the analysis when the table does not say: 8 seed blocks (8 batches for the
#: standard errors).
DEFAULT_TRIALS = 8 * SEED_BLOCK_SIZE

#: An interaction share ``S_Ti - S_i`` the report names: at least this much of ``V(Y)``.
MATERIAL_SHARE = 0.01


@dataclass(frozen=True)
class SensitivitySettings:
    """What the ``[sensitivity]`` table asks for.

    Attributes
    ----------
    trials : int
        ``N``: trials of each one-at-a-time run and rows of each Sobol matrix (a whole
        number of at least 2 seed blocks of 2¹⁴); the Sobol analysis makes ``N (D + 2)``
        model evaluations for ``D`` inputs.
    sampling : str
        ``"sobol"`` (randomised quasi-Monte Carlo, the default) or ``"random"``.
    """

    trials: int = DEFAULT_TRIALS
    sampling: Sampling = "sobol"


def read_sensitivity(top: Fields) -> SensitivitySettings | None:
    """Read the optional ``[sensitivity]`` table of a study file.

    Parameters
    ----------
    top : Fields
        The study file.

    Returns
    -------
    SensitivitySettings or None
        None where the file has no ``[sensitivity]`` table.

    Raises
    ------
    InputError
        Naming the file, line and key: an unknown key, a ``trials`` that is not a whole
        number of at least 2 seed blocks, or an unknown ``sampling``.
    """
    table = top.table("sensitivity", required=False)
    if table is None:
        return None
    table.only(("trials", "sampling"))
    trials = table.integer(
        "trials", DEFAULT_TRIALS, minimum=2 * SEED_BLOCK_SIZE, maximum=MAX_TRIALS
    )
    if trials % SEED_BLOCK_SIZE:
        raise table.error(
            f"expected a multiple of {SEED_BLOCK_SIZE} (whole seed blocks, whose spread gives "
            f"the standard errors), got {trials}, e.g. "
            f"{max(2, round(trials / SEED_BLOCK_SIZE)) * SEED_BLOCK_SIZE}",
            "trials",
        )
    sampling = cast(Sampling, table.text("sampling", "sobol", choices=("sobol", "random")))
    return SensitivitySettings(trials=trials, sampling=sampling)


def sensitivity_record(
    model: Callable[..., Any],
    inputs: Mapping[str, Distribution],
    spec: SensitivitySettings,
    *,
    seed: int,
    output: str,
    unit: str,
    u_mc: float,
    gum_result: GumResult | None,
    parallel: Mapping[str, Any],
) -> dict[str, Any]:
    """Run the budget and the indices and return the ``sensitivity`` entry of ``result.json``.

    Parameters
    ----------
    model : callable
        The study's model (one scalar output).
    inputs : mapping of str to Distribution
        Its inputs.
    spec : SensitivitySettings
        The ``[sensitivity]`` table.
    seed : int
        The run's seed.
    output, unit : str
        The output and its unit.
    u_mc : float
        ``u(y)`` of the study's Monte Carlo run.
    gum_result : GumResult or None
        The study's GUM result.
    parallel : mapping
        ``workers``, ``executor`` and ``scheduler``.

    Returns
    -------
    dict
        JSON-ready (``docs/results-format.md``): the budget lines, the indices, and the
        names of the inputs in which the model is not linear (``nonlinear``) and of those
        that interact (``interacting``: ``S_Ti - S_i`` at least 1 % of ``V(Y)`` and more
        than :func:`~mtmc.uncertainty.sensitivity.agreement_factor` times the sum of the
        two standard errors).
    """
    budget = monte_carlo_budget(
        model,
        inputs,
        trials=spec.trials,
        seed=seed,
        gum=gum_result,
        sampling=spec.sampling,
        **parallel,
    )
    indices = sobol_indices(
        model,
        inputs,
        trials=spec.trials,
        seed=seed,
        sampling=spec.sampling,
        **parallel,
    )
    lines = [
        {
            "name": e.name,
            "u": e.u,
            "u_se": e.u_se,
            "u_x": e.u_x,
            "sensitivity": e.sensitivity,
            "shift": e.shift,
            "gum_contribution": e.gum_contribution,
            "linear_reference": e.linear_reference,
            "linear": e.linear,
        }
        for e in budget.entries
    ]
    rows = [
        {
            "name": s.name,
            "first": s.first,
            "first_se": s.first_se,
            "total": s.total,
            "total_se": s.total_se,
        }
        for s in indices.entries
    ]
    interacting = sorted(
        (
            s
            for s in indices.entries
            if s.interaction >= MATERIAL_SHARE
            and s.interaction > agreement_factor(indices.batches) * (s.first_se + s.total_se)
        ),
        key=lambda s: -s.interaction,
    )
    return {
        "output": output,
        "unit": unit,
        "trials": spec.trials,
        "sampling": spec.sampling,
        "batches": indices.batches,
        "evaluations": indices.evaluations + budget.trials * len(budget.entries),
        "u_mc": u_mc,
        "u_gum": None if gum_result is None else gum_result.u,
        "budget": lines,
        "u_additive": budget.u_additive,
        "sobol": {
            "variance": indices.variance,
            "first_sum": indices.first_sum,
            "first_sum_se": indices.first_sum_se,
            "additive": indices.additive,
            "indices": rows,
        },
        "nonlinear": [e.name for e in budget.entries if e.linear is False],
        "interacting": [s.name for s in interacting],
    }
