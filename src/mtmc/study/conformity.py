"""The ``[conformity]`` table of a study: tolerance limits and a decision rule (JCGM 106).

A study whose output must lie within tolerance limits says so in a table::

    [conformity]
    lower = -0.010          # T_L (optional; at least one limit)
    upper = 0.010           # T_U (optional)
    rule = "guarded"        # "simple" (default) or "guarded"
    guard = 0.5             # r of the guard band w = r·U, U = 2u (JCGM 106 §8.3), or
    # max_consumer_risk = 0.05   # accept when p_c >= 0.95 (JCGM 106 §9.3)
    prior = {mean = 0.0, sd = 0.004}   # the process, for the global risks (§9.5)

:func:`read_conformity` validates it (every error names the file, the line and the
field); :func:`assess` applies it to the Monte Carlo result of the output (the decision)
and the GUM result (its ``p_c`` beside), giving the ``conformity`` entry of the quantity
in ``result.json``.

A study of several outputs (``[outputs]``) gives a table per output that has limits,
named as the output (:func:`read_output_conformity`)::

    [conformity.L1]
    lower = 149.9995
    upper = 150.0005
    [conformity.L2]
    upper = 50.0004
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

from mtmc.document import Fields, KeyPath, Source
from mtmc.errors import InputError
from mtmc.study.result import Quantity
from mtmc.uncertainty.decision import conformance_probability, conformity
from mtmc.uncertainty.propagation import GumResult
from mtmc.uncertainty.results import MonteCarloResult

__all__ = [
    "ConformitySpec",
    "assess",
    "assess_quantity",
    "read_conformity",
    "read_output_conformity",
]

_KEYS = ("lower", "upper", "rule", "guard", "max_consumer_risk", "prior", "coverage_factor")


@dataclass(frozen=True)
class ConformitySpec:
    """A validated ``[conformity]`` table.

    Attributes
    ----------
    lower, upper : float or None
        Tolerance limits ``T_L``, ``T_U``.
    rule : {"simple", "guarded"}
    guard : float or None
        ``r`` of ``w = r U``.
    max_consumer_risk : float or None
        ``α`` of the rule ``p_c >= 1 - α``.
    prior : (float, float) or None
        ``(y_0, u_0)`` of the normal prior of the measurand.
    coverage_factor : float
        ``k`` of ``U = k u``.
    source : Source
        The study file, to name it in an error found when the rule meets the result.
    path : tuple
        The key path of the table.
    """

    lower: float | None
    upper: float | None
    rule: str
    guard: float | None
    max_consumer_risk: float | None
    prior: tuple[float, float] | None
    coverage_factor: float
    source: Source
    path: KeyPath


def read_conformity(top: Fields, key: str = "conformity") -> ConformitySpec | None:
    """Read the ``[conformity]`` table of a study (None when it has none).

    Parameters
    ----------
    top : Fields
        The table that holds it (the study's top level).
    key : str
        Its name.

    Returns
    -------
    ConformitySpec or None

    Raises
    ------
    InputError
        Naming the file, the line and the field: an unknown key, no limit, ``lower >=
        upper``, an unknown rule, a guarded rule without ``guard`` or
        ``max_consumer_risk`` or with both, a simple rule with either,
        ``max_consumer_risk`` outside (0, 0.5), a prior without ``mean`` and ``sd > 0``.
    """
    t = top.table(key, required=False)
    if t is None:
        return None
    t.only(_KEYS)
    lower = t.number("lower", None)
    upper = t.number("upper", None)
    if lower is None and upper is None:
        raise t.error("expected a tolerance limit: lower, upper or both (JCGM 106)", None)
    if lower is not None and upper is not None and not lower < upper:
        raise t.error(f"expected upper > lower = {lower!r}, got {upper!r}", "upper")
    guard = t.number("guard", None)
    alpha = t.number("max_consumer_risk", None, low=0.0, high=0.5, open_low=True, open_high=True)
    default_rule = "guarded" if guard is not None or alpha is not None else "simple"
    rule = t.text("rule", default_rule, choices=("simple", "guarded"))
    if rule == "simple":
        for name, value in (("guard", guard), ("max_consumer_risk", alpha)):
            if value is not None:
                raise t.error(f'{name} needs rule = "guarded"; simple acceptance has none', name)
    elif guard is None and alpha is None:
        raise t.error(
            'rule = "guarded" needs guard (r of the guard band w = r·U) or max_consumer_risk',
            "rule",
        )
    elif guard is not None and alpha is not None:
        raise t.error("expected one of guard and max_consumer_risk, not both", "max_consumer_risk")
    prior = None
    p = t.table("prior", required=False)
    if p is not None:
        p.only(("mean", "sd"))
        prior = (float(p.number("mean")), float(p.number("sd", low=0.0, open_low=True)))
    k = t.number("coverage_factor", 2.0, low=0.0, open_low=True)
    return ConformitySpec(
        lower=None if lower is None else float(lower),
        upper=None if upper is None else float(upper),
        rule=rule,
        guard=None if guard is None else float(guard),
        max_consumer_risk=None if alpha is None else float(alpha),
        prior=prior,
        coverage_factor=float(k),
        source=t.source,
        path=t.path,
    )


def read_output_conformity(top: Fields, outputs: Sequence[str]) -> dict[str, ConformitySpec]:
    """Read the ``[conformity]`` table of a study of several outputs: a table per output.

    Parameters
    ----------
    top : Fields
        The study file.
    outputs : sequence of str
        The names of its outputs (the keys of ``[outputs]``).

    Returns
    -------
    dict of str to ConformitySpec
        By output, in the order of the file (empty where there is no ``[conformity]``).

    Raises
    ------
    InputError
        Naming the file, the line and the field: a key that is not an output (the keys of
        one output's table at the top of ``[conformity]`` are named as such), no table
        for any output, and every error of :func:`read_conformity` in an output's table.
    """
    t = top.table("conformity", required=False)
    if t is None:
        return {}
    if not t.data:
        raise t.error(
            f"expected a table of limits per output, e.g. [conformity.{outputs[0]}] with "
            "lower, upper or both"
        )
    for key, value in t.data.items():
        if key in _KEYS:
            raise t.error(
                f"with [outputs], [conformity] has a table of limits per output: "
                f"[conformity.{outputs[0]}] {key} = ..., not {key} for all of them",
                key,
            )
        if key not in outputs:
            raise t.error(f"unknown output {key!r}; expected one of {', '.join(outputs)}", key)
        if not isinstance(value, dict):
            raise t.error(
                f"expected a table of limits for output {key}, e.g. {key} = {{ upper = 1.0 }}",
                key,
            )
    specs = {key: read_conformity(t, key) for key in t.data}
    return {key: spec for key, spec in specs.items() if spec is not None}


def assess(
    spec: ConformitySpec, mc: MonteCarloResult, gum_result: GumResult | None
) -> dict[str, Any]:
    """The ``conformity`` entry of a quantity: the decision on the Monte Carlo PDF.

    Parameters
    ----------
    spec : ConformitySpec
    mc : MonteCarloResult
        The scalar Monte Carlo result of the output (the decision is made on it,
        :func:`mtmc.uncertainty.decision.conformity`).
    gum_result : GumResult or None
        The GUM result of the same output: ``gum_p_c`` and ``gum_basis`` beside.

    Returns
    -------
    dict
        :meth:`Conformity.to_dict` with ``gum_p_c`` and ``gum_basis`` (None without GUM).

    Raises
    ------
    InputError
        Naming the file and the line of ``guard``: a guard band that leaves no
        acceptance interval at this ``u``.
    """
    try:
        c = conformity(
            mc,
            spec.lower,
            spec.upper,
            rule=spec.rule,  # type: ignore[arg-type]  # "simple" or "guarded", read above
            guard=spec.guard,
            max_consumer_risk=spec.max_consumer_risk,
            prior=spec.prior,
            coverage_factor=spec.coverage_factor,
        )
    except InputError as exc:
        key = exc.field if exc.field in _KEYS else None
        path = spec.path if key is None else (*spec.path, key)
        raise spec.source.error(exc.message, path) from None
    out = c.to_dict()
    out["gum_p_c"] = out["gum_basis"] = None
    if gum_result is not None:
        p_c, _, basis = conformance_probability(gum_result, spec.lower, spec.upper)
        out["gum_p_c"], out["gum_basis"] = p_c, basis
    return out


def assess_quantity(
    q: Quantity, spec: ConformitySpec | None, mc: MonteCarloResult, gum_result: GumResult | None
) -> Quantity:
    """The quantity with its ``conformity`` (:func:`assess`), or as it is without a spec."""
    if spec is None:
        return q
    return replace(q, conformity=assess(spec, mc, gum_result))
