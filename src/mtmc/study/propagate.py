"""Study kind ``propagate``: an expression model of named inputs, by Monte Carlo and the GUM.

The file names the model (an expression of :func:`mtmc.expression`), the output and its
unit, and one distribution per input. The run is :func:`mtmc.monte_carlo` (JCGM 101 §7)
and :func:`mtmc.gum` (JCGM 100) of the same model, compared by :func:`mtmc.validate`
(JCGM 101 §8). JCGM 101 §9.3 (the mass calibration) is shipped as
``examples/studies/mass_calibration.toml``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from mtmc.document import Fields
from mtmc.errors import InputError, MtmcError
from mtmc.study.base import ProgressFn, Study
from mtmc.study.conformity import (
    ConformitySpec,
    assess_quantity,
    read_conformity,
    read_output_conformity,
)
from mtmc.study.correlation import CorrelationSpec, correlation_record, read_correlation
from mtmc.study.observations import input_record, read_distribution, read_input_table
from mtmc.study.options import ADAPTIVE, NAN_POLICY, mc_run_record
from mtmc.study.outputs import check_vector_use, read_outputs_study
from mtmc.study.result import StudyResult, quantity
from mtmc.study.sensitivity import SensitivitySettings, read_sensitivity, sensitivity_record
from mtmc.study.settings import RunSettings
from mtmc.study.spec import register_kind
from mtmc.uncertainty.distributions import Distribution
from mtmc.uncertainty.formula import Expression, check_variables, expression
from mtmc.uncertainty.montecarlo import monte_carlo
from mtmc.uncertainty.propagation import gum

__all__ = ["PropagateStudy", "read_inputs"]


def read_inputs(table: Fields) -> dict[str, Distribution]:
    """Read an ``[inputs]`` table: ``NAME = "normal(0, 1)"``, ``NAME = number`` or a table.

    A table gives observations (``{data = [...]}``, ``{data = "FILE.csv", column = "x"}``,
    with ``pooled_s`` and ``pooled_dof`` where pooled) or a distribution with degrees of
    freedom (``{dist = "...", dof = 8}`` or ``u_rel_u``):
    :func:`mtmc.study.observations.read_input_table`.

    Parameters
    ----------
    table : Fields
        The table.

    Returns
    -------
    dict of str to Distribution
        In the order of the file.

    Raises
    ------
    InputError, DistributionError
        Naming the file, the line and the input: a value that is neither a distribution
        text nor a finite number, or a distribution with bad parameters (a negative or
        non-finite standard deviation, ``low >= high``...).
    """
    out: dict[str, Distribution] = {}
    if not table.data:
        raise table.error('expected at least one input, e.g. x = "normal(0, 1)"')
    for name, value in table.data.items():
        if isinstance(value, dict):
            sub = table.table(name)
            assert sub is not None
            out[name] = read_input_table(sub, name)
        else:
            out[name] = read_distribution(table, name)
    return out


def read_input_units(table: Fields, names: list[str] | tuple[str, ...]) -> dict[str, str]:
    """The ``unit`` of each input of ``[inputs]`` that gives one (``{dist = ..., unit = "mm"}``).

    Where some inputs of ``names`` (the model's) have a unit, every one must: a model
    checked for its units is checked whole (:mod:`mtmc.study.units`).

    Raises
    ------
    InputError
        Naming the line: a unit pint does not know, or inputs of the model without one
        beside inputs with one.
    """
    from mtmc.study.units import read_unit, unit_text

    units: dict[str, str] = {}
    for name, value in table.data.items():
        if isinstance(value, dict) and "unit" in value:
            sub = table.table(name)
            assert sub is not None
            text = sub.text("unit")

            def error(message: str, where: Fields = sub) -> InputError:
                return where.error(message, "unit")

            units[name] = unit_text(read_unit(text, error))
    missing = [n for n in names if n not in units]
    if units and missing:
        raise table.error(
            f"{', '.join(missing)} {'has' if len(missing) == 1 else 'have'} no unit beside "
            f"inputs with one ({', '.join(units)}): give every input of the model a unit "
            '({dist = "...", unit = "mm"}; "1" for a pure number), or none',
            missing[0],
        )
    return units


def check_units(top: Fields, model: Expression, units: dict[str, str], key: str) -> None:
    """The model against its inputs' units and the output's ``unit`` (a located error)."""
    from mtmc.study.units import check_model_units, model_unit

    if not units:
        return
    try:
        model_unit(model, units)
    except InputError as exc:
        raise top.error(f"{exc.message}, in {model.text!r}", key) from None
    try:
        check_model_units(model, units, top.text("unit", "1"))
    except InputError as exc:
        raise top.error(exc.message, "unit" if top.has("unit") else key) from None


def _check_output_units(top: Fields, output: Any, units: dict[str, str]) -> None:
    """One output of ``[outputs]`` against its inputs' units and its own unit."""
    from mtmc.study.units import check_model_units

    if not units:
        return
    try:
        check_model_units(output.model, {n: units[n] for n in output.model.names}, output.unit)
    except InputError as exc:
        outputs = top.table("outputs")
        assert outputs is not None
        raise outputs.error(f"{exc.message}, in {output.model.text!r}", output.name) from None


@dataclass(frozen=True)
class PropagateStudy(Study):
    """A model expression with its input PDFs (kind ``propagate``).

    Attributes
    ----------
    model : Expression
        The measurement model ``Y = f(X)``.
    output : str
        Name of the output quantity.
    unit : str
        Its unit (as text, for the report).
    inputs : dict of str to Distribution
        The input PDFs (JCGM 101 §6).
    sensitivity : SensitivitySettings or None
        The ``[sensitivity]`` table: a Monte Carlo budget and Sobol indices beside the
        GUM's budget (JCGM 101 Annex B; ``docs/sensitivity.md``), or None.
    conformity : ConformitySpec or None
        The ``[conformity]`` table: tolerance limits and a decision rule (JCGM 106;
        ``docs/conformity.md``), or None.
    correlation : CorrelationSpec or None
        The ``[correlation]`` table: correlated inputs, joined by a copula in the Monte
        Carlo, ``r`` in the GUM (JCGM 100 eq. (13); ``docs/correlation.md``), or None.
    input_units : dict of str to str
        The unit of each input, where the file gives them (then every input has one and
        the model was checked against them and ``unit``).
    """

    kind = "propagate"
    run_options = frozenset({ADAPTIVE, NAN_POLICY})
    model: Expression
    output: str
    unit: str
    inputs: dict[str, Distribution]
    sensitivity: SensitivitySettings | None = None
    conformity: ConformitySpec | None = None
    correlation: CorrelationSpec | None = None
    input_units: dict[str, str] = dataclasses.field(default_factory=dict)

    def execute(self, settings: RunSettings, progress: ProgressFn | None) -> StudyResult:
        """Monte Carlo and GUM of the model (see the module docstring)."""
        mc = monte_carlo(
            self.model,
            self.inputs,
            seed=settings.seed,
            progress=progress,
            **settings.engine,
            **({} if self.correlation is None else self.correlation.engine),
        )
        corr = None if self.correlation is None else self.correlation.correlation
        g = gum(self.model, self.inputs, p=settings.p, correlation=corr)
        # with the JCGM 106 decision on the Monte Carlo PDF where there are limits
        q = assess_quantity(
            quantity(self.output, self.unit, mc, g, settings), self.conformity, mc, g
        )
        units = self.input_units
        inputs = tuple(input_record(n, d, units.get(n)) for n, d in self.inputs.items())
        extra: dict[str, Any] = {"model": self.model.text}
        if self.correlation is not None:
            assert settings.seed is not None
            extra["correlation"] = correlation_record(
                self.correlation, self.inputs, seed=settings.seed, trials=mc.trials, gum_result=g
            )
        warned = [x for x in inputs if x.get("type_a") and x["type_a"]["warning"]]
        if warned:  # serially correlated observations (JCGM 100 §4.2.7), on the summary
            extra["warnings"] = [f"input {x['name']}: {x['type_a']['warning']}" for x in warned]
        if self.sensitivity is not None:
            assert settings.seed is not None
            extra["sensitivity"] = sensitivity_record(
                self.model,
                self.inputs,
                self.sensitivity,
                seed=settings.seed,
                output=self.output,
                unit=self.unit,
                u_mc=q.mc.u,
                gum_result=g,
                parallel=settings.parallel,
            )
        samples = {self.output: mc.samples} if settings.samples else {}
        run = mc_run_record(settings, mc)
        return self._result(
            settings, run=run, quantities=(q,), inputs=inputs, extra=extra, samples=samples
        )


@register_kind("propagate", "an expression of named inputs: Monte Carlo beside the GUM")
def read_propagate_study(top: Fields) -> Study:
    """Validate a ``propagate`` study file (see ``docs/study-format.md``).

    A file with an ``[outputs]`` table is a study of several outputs
    (:func:`mtmc.study.outputs.read_outputs_study`), with ``[correlation]`` of its inputs
    as in a study of one output and ``[conformity.NAME]`` limits per output
    (:func:`mtmc.study.conformity.read_output_conformity`).
    """
    top.only(
        (
            "kind",
            "title",
            "model",
            "output",
            "unit",
            "inputs",
            "run",
            "sensitivity",
            "outputs",
            "conformity",
            "correlation",
        )
    )
    if top.has("sensitivity") and (top.has("outputs") or top.has("correlation")):
        raise top.error(
            "[sensitivity] applies to the one output of a study without [outputs], and its "
            "one-at-a-time budget and Sobol indices assume independent inputs (no [correlation])",
            "sensitivity",
        )
    if top.has("outputs"):
        outputs_inputs = top.table("inputs")
        assert outputs_inputs is not None
        study = read_outputs_study(top, outputs_inputs, read_inputs(outputs_inputs))
        units = read_input_units(outputs_inputs, tuple(study.inputs))
        for o in study.outputs:
            _check_output_units(top, o, units)
        # limits per output; the inputs' correlation is that of a study of one output
        return dataclasses.replace(
            study,
            conformity=read_output_conformity(top, [o.name for o in study.outputs]),
            correlation=read_correlation(top, study.inputs),
            input_units=units,
        )
    text = top.text("model")
    try:
        model = expression(text)
    except MtmcError as exc:
        raise top.error(exc.message, "model") from None
    inputs_t = top.table("inputs")
    assert inputs_t is not None
    inputs = read_inputs(inputs_t)
    try:
        check_variables(model, inputs)
    except InputError as exc:
        if exc.field in model.names:  # a variable without an input: the model line
            raise top.error(
                f'{exc.message}; expected {exc.field} = "normal(...)" or a number in [inputs]',
                "model",
            ) from None
        raise inputs_t.error(exc.message, str(exc.field)) from None
    check_vector_use(model, inputs, lambda msg: top.error(msg, "model"))
    units = read_input_units(inputs_t, model.names)
    check_units(top, model, units, "model")
    return PropagateStudy(
        title=top.text("title", "Propagation of distributions"),
        source=top.source,
        settings=RunSettings.read(top, default_trials=10**6),
        model=model,
        output=top.text("output", "y"),
        unit=top.text("unit", "1"),
        inputs={n: inputs[n] for n in model.names},
        sensitivity=read_sensitivity(top),
        conformity=read_conformity(top),
        correlation=read_correlation(top, inputs),
        input_units=units,
    )
