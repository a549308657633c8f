"""Several outputs of one ``propagate`` study, and vector inputs taken by components.

A measurement model with several output quantities ``Y = (Y_1, ..., Y_d)`` of the same
inputs is one model in JCGM 102:2011. A ``propagate`` study gives it as an ``[outputs]``
table instead of ``model``, ``output`` and ``unit``::

    [outputs]
    y1 = "x[0] + x[1]"
    y2 = { model = "x[0] * a", unit = "mm" }

Every output is evaluated on the same Monte Carlo trials (:func:`mtmc.monte_carlo` with
named outputs), so their joint sample gives the covariance and correlation matrices of
``Y`` (JCGM 102 §7.5) and the coverage region of JCGM 102 §7.7 (``k_p`` from the
``p``-quantile of the Mahalanobis distances of the trials); the GUM of the outputs stacked
as one vector model gives ``U_y = C U_x Cᵀ`` (JCGM 102 §6.2.1.3) and its region with
``k_p² = χ²_d(p)`` (JCGM 102 §6.5.2.3). Each output is also a quantity of its own, as in a
single-output study: its Monte Carlo values are those a study of that output alone gives,
bit for bit.

A vector input (``mvnormal(...)``, ``iid(..., k)``) is used in a model by its components,
``x[0]`` to ``x[k-1]`` (:class:`mtmc.uncertainty.formula.Expression`); the checks of
that use against the ``[inputs]`` are here, for both forms of the study.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mtmc.document import MAX_NAMES, Fields, check_length
from mtmc.errors import InputError, MtmcError
from mtmc.study.base import ProgressFn, Study
from mtmc.study.conformity import ConformitySpec, assess_quantity
from mtmc.study.correlation import CorrelationSpec, correlation_record
from mtmc.study.observations import input_record
from mtmc.study.options import ADAPTIVE, NAN_POLICY, run_record
from mtmc.study.result import SCATTER_POINTS, StudyResult, quantity
from mtmc.study.settings import RunSettings
from mtmc.uncertainty.distributions import Distribution
from mtmc.uncertainty.formula import Expression, check_components, expression
from mtmc.uncertainty.joint import (
    JointModel,
    ModelOutput,
    NamedOutputs,
    correlation,
    gum_coverage_ellipsoid,
)
from mtmc.uncertainty.montecarlo import monte_carlo
from mtmc.uncertainty.propagation import GumResult, gum
from mtmc.uncertainty.results import CoverageEllipsoid, MonteCarloResult, MonteCarloResults

__all__ = [
    "OutputsStudy",
    "check_vector_use",
    "joint_summary",
    "read_outputs_study",
]


def check_vector_use(
    model: Expression, inputs: Mapping[str, Distribution], error: Callable[[str], InputError]
) -> None:
    """Refuse a model that uses an input against its number of components.

    A component ``x[i]`` of a scalar input, an index past the last component, or a
    vector input used whole (the output of a study is a scalar: ``x + 1`` of a
    3-component ``x`` would be three outputs) are refused.

    Parameters
    ----------
    model : Expression
    inputs : mapping of str to Distribution
    error : callable
        ``error(message)`` gives the error to raise (naming file, line and field).

    Raises
    ------
    InputError
    """
    dims = {n: int(d.dim) for n, d in inputs.items()}
    try:
        check_components(model, dims)
    except MtmcError as exc:
        raise error(exc.message) from None
    for name in model.names:
        k = dims.get(name, 0)
        if k > 0 and name not in model.components:
            raise error(
                f"{name} has {k} components and {model.text!r} uses it whole; a model of "
                f"a study gives one scalar output: take the components {name}[0] to "
                f"{name}[{k - 1}]"
            )


def _read_output(table: Fields, name: str, default_unit: str) -> ModelOutput:
    value = table.data[name]
    where: tuple[str, ...]
    if not (name.isidentifier() and not name.startswith("_")):
        raise table.error(
            f"expected an output name of letters, digits and '_' not starting with a "
            f"digit or '_', got {name!r}",
            name,
        )
    if isinstance(value, str):
        text, unit, where = value, default_unit, (name,)
    elif isinstance(value, dict):
        sub = Fields(table.source, value, (*table.path, name))
        sub.only(("model", "unit"))
        text, unit, where = sub.text("model"), sub.text("unit", default_unit), (name, "model")
    else:
        raise table.error(
            f'expected a model text, e.g. {name} = "x[0] + x[1]", or a table '
            f'{{ model = "...", unit = "..." }}, got {type(value).__name__}',
            name,
        )
    try:
        model = expression(text)
    except MtmcError as exc:
        raise table.source.error(exc.message, (*table.path, *where)) from None
    if not model.names:
        raise table.source.error(
            f"the model {model.text!r} of output {name} has no input variable; expected a "
            "function of the [inputs]",
            (*table.path, *where),
        )
    return ModelOutput(name=name, model=model, unit=unit)


@dataclass(frozen=True)
class OutputsStudy(Study):
    """A ``propagate`` study of several outputs of the same inputs (JCGM 102).

    Attributes
    ----------
    outputs : tuple of ModelOutput
        The output quantities, in the order of the file.
    inputs : dict of str to Distribution
        The input PDFs (JCGM 101 §6, JCGM 102 §6), in the order of first use.
    conformity : dict of str to ConformitySpec
        The ``[conformity.NAME]`` tables: tolerance limits and a decision rule per output
        (JCGM 106), by output name.
    correlation : CorrelationSpec or None
        The ``[correlation]`` table of the inputs, as in a study of one output.
    input_units : dict of str to str
        The unit of each input where the file gives them (each output's model checked
        against them and its unit).
    """

    kind = "propagate"
    run_options = frozenset({ADAPTIVE, NAN_POLICY})
    outputs: tuple[ModelOutput, ...]
    inputs: dict[str, Distribution]
    conformity: Mapping[str, ConformitySpec] = field(default_factory=dict)
    correlation: CorrelationSpec | None = None
    input_units: Mapping[str, str] = field(default_factory=dict)

    def execute(self, settings: RunSettings, progress: ProgressFn | None) -> StudyResult:
        """Monte Carlo of the outputs on the same trials, the GUM of the stacked model."""
        corr = self.correlation
        mc = monte_carlo(
            NamedOutputs(self.outputs),
            self.inputs,
            seed=settings.seed,
            progress=progress,
            **settings.engine,
            **({} if corr is None else corr.engine),
        )
        assert isinstance(mc, MonteCarloResults)
        r = None if corr is None else corr.correlation
        g = gum(JointModel(self.outputs), self.inputs, p=settings.p, correlation=r)
        quantities = tuple(
            assess_quantity(
                quantity(o.name, o.unit, mc[o.name], g.component(i), settings),
                self.conformity.get(o.name),
                mc[o.name],
                g.component(i),
            )
            for i, o in enumerate(self.outputs)
        )
        units = self.input_units
        inputs = tuple(input_record(n, d, units.get(n)) for n, d in self.inputs.items())
        joint = joint_summary(self.outputs, mc, g, settings.p)
        extra: dict[str, Any] = {
            "model": JointModel(self.outputs).text,
            "models": {o.name: o.model.text for o in self.outputs},
            "joint": joint,
        }
        if corr is not None:
            assert settings.seed is not None
            extra["correlation"] = correlation_record(
                corr,
                self.inputs,
                seed=settings.seed,
                trials=mc.trials,
                gum_result=g,
                outputs=[o.name for o in self.outputs],
            )
        warned = [x for x in inputs if x.get("type_a") and x["type_a"]["warning"]]
        if warned:  # serially correlated observations (JCGM 100 §4.2.7), on the summary
            extra["warnings"] = [f"input {x['name']}: {x['type_a']['warning']}" for x in warned]
        samples = {o.name: mc[o.name].values for o in self.outputs} if settings.samples else {}
        first = mc[self.outputs[0].name]
        run = run_record(
            settings, mc.trials, mc.omitted, blocks=first.blocks, tolerance=first.tolerance
        )
        return self._result(
            settings, run=run, quantities=quantities, inputs=inputs, extra=extra, samples=samples
        )


def _ellipsoid(e: CoverageEllipsoid) -> dict[str, Any]:
    return {
        "centre": e.centre.tolist(),
        "cov": e.cov.tolist(),
        "k": float(e.k),
        "semi_axes": e.semi_axes.tolist(),
        "axes": e.axes.tolist(),
    }


def joint_summary(
    outputs: tuple[ModelOutput, ...], mc: MonteCarloResults, g: GumResult, p: float
) -> dict[str, Any]:
    """The ``joint`` entry of ``result.json``: the outputs together (JCGM 102).

    Parameters
    ----------
    outputs : tuple of ModelOutput
    mc : MonteCarloResults
        The named outputs of one Monte Carlo run (their samples row-aligned).
    g : GumResult
        The GUM of the stacked outputs (a vector output of ``d`` components).
    p : float
        Coverage probability of the region.

    Returns
    -------
    dict
        ``outputs``, ``units``, ``p``; ``monte_carlo`` and ``gum``: ``estimate``, ``u``,
        ``cov`` (JCGM 102 §7.5 and §6.2.1.3) and ``corr`` (JCGM 102 §3.22; None where
        a ``u`` is 0); ``region``: for ``d >= 2`` outputs of non-singular covariance,
        the coverage ellipsoids (``monte_carlo``: JCGM 102 §7.7.2, ``gum``: §6.5.2.3;
        each ``centre``, ``cov``, ``k``, ``semi_axes``, ``axes``), with ``gum_coverage``,
        the fraction of the Monte Carlo trials inside the GUM region (``p`` where the
        Gaussian PDF of the GUM is right), and for ``d = 2`` ``scatter``, the first
        trials; else None with ``region_note`` saying why.
    """
    samples = np.column_stack([mc[o.name].values for o in outputs])
    joint = MonteCarloResult.from_samples(samples, seed=mc.seed, trials=mc.trials)
    d = len(outputs)

    def corr(cov: NDArray[np.float64]) -> list[list[float | None]]:
        r = correlation(cov)
        return [[None if np.isnan(v) else float(v) for v in row] for row in r]

    out: dict[str, Any] = {
        "outputs": [o.name for o in outputs],
        "units": [o.unit for o in outputs],
        "p": p,
        "monte_carlo": {
            "estimate": joint.estimate_vector.tolist(),
            "u": joint.u_vector.tolist(),
            "cov": joint.cov.tolist(),
            "corr": corr(np.asarray(joint.cov)),
        },
        "gum": {
            "estimate": g.estimate_vector.tolist(),
            "u": g.u_vector.tolist(),
            "cov": g.cov.tolist(),
            "corr": corr(np.asarray(g.cov)),
            "method": g.method,
        },
        "region": None,
        "region_note": None,
    }
    if d < 2:
        out["region_note"] = "one output: its coverage interval is its region"
        return out
    try:
        e_mc = joint.coverage_ellipsoid(p, method="mc")
        e_gum = gum_coverage_ellipsoid(g, p)
    except InputError as exc:
        out["region_note"] = exc.message
        return out
    region: dict[str, Any] = {
        "monte_carlo": _ellipsoid(e_mc),
        "gum": {**_ellipsoid(e_gum), "gum_coverage": float(np.mean(e_gum.contains(samples)))},
    }
    if d == 2:
        region["scatter"] = samples[:SCATTER_POINTS].tolist()
    out["region"] = region
    return out


def read_outputs_study(
    top: Fields, inputs_t: Fields, inputs: dict[str, Distribution]
) -> OutputsStudy:
    """Validate a ``propagate`` study with an ``[outputs]`` table (``docs/study-format.md``).

    Parameters
    ----------
    top : Fields
        The study file.
    inputs_t : Fields
        Its ``[inputs]`` table.
    inputs : dict of str to Distribution
        The inputs read from it.

    Returns
    -------
    OutputsStudy

    Raises
    ------
    InputError
        Naming the file, the line and the field: ``model`` or ``output`` beside
        ``[outputs]``, an output that is not a model text (or table of ``model`` and
        ``unit``), a model that does not parse, a variable without an input, an input
        that no output uses, a component out of range of its input.
    """
    for key in ("model", "output"):
        if top.has(key):
            raise top.error(
                f"{key} is for a study of one output; with [outputs] each output gives its "
                'model there (y1 = "x[0] + x[1]"): expected either model, output and unit, '
                "or [outputs]",
                key,
            )
    top.only(("kind", "title", "unit", "inputs", "outputs", "run", "conformity", "correlation"))
    table = top.table("outputs")
    assert table is not None
    if not table.data:
        raise table.error('expected at least one output, e.g. y1 = "x[0] + x[1]"')
    check_length(table.data, MAX_NAMES, table.error)
    default_unit = top.text("unit", "1")
    outputs = tuple(_read_output(table, name, default_unit) for name in table.data)
    for o in outputs:
        where = (o.name,) if isinstance(table.data[o.name], str) else (o.name, "model")

        def err(msg: str, _w: tuple[str, ...] = where) -> InputError:
            return table.source.error(msg, (*table.path, *_w))

        missing = [n for n in o.model.names if n not in inputs]
        if missing:
            raise err(
                f"the model's variable(s) {', '.join(missing)} have no input; expected "
                f'{missing[0]} = "normal(...)" or a number in [inputs]'
            )
        if o.name in inputs:
            raise err(f"output {o.name} has the name of an input; expected another name")
        check_vector_use(o.model, inputs, err)
    used = JointModel(outputs).names
    extra = [n for n in inputs if n not in used]
    if extra:
        raise inputs_t.error(
            f"input {', '.join(extra)} is not a variable of any output (their variables: "
            f"{', '.join(used)})",
            extra[0],
        )
    return OutputsStudy(
        title=top.text("title", "Propagation of distributions"),
        source=top.source,
        settings=RunSettings.read(top, default_trials=10**6),
        outputs=outputs,
        inputs={n: inputs[n] for n in used},
    )
