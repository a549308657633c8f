"""Study kind ``propagate``: an expression model of named inputs, by Monte Carlo and the GUM.

The file names the model (an expression of :func:`mtmc.expression`), the output and its
unit, and one distribution per input. The run is :func:`mtmc.monte_carlo` (JCGM 101 §7)
and :func:`mtmc.gum` (JCGM 100) of the same model, compared by :func:`mtmc.validate`
(JCGM 101 §8). JCGM 101 §9.3 (the mass calibration) is shipped as
``examples/studies/mass_calibration.toml``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from mtmc.document import Fields
from mtmc.errors import InputError, MtmcError
from mtmc.study.base import ProgressFn, Study, StudyResult, quantity
from mtmc.study.spec import RunSettings, register_kind
from mtmc.uncertainty.distributions import Distribution, as_distribution, parse_distribution
from mtmc.uncertainty.expression import Expression, check_variables, expression
from mtmc.uncertainty.gum import gum
from mtmc.uncertainty.montecarlo import monte_carlo

__all__ = ["PropagateStudy", "read_inputs"]


def read_inputs(table: Fields) -> dict[str, Distribution]:
    """Read an ``[inputs]`` table: ``NAME = "normal(0, 1)"`` or ``NAME = number``.

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
    from mtmc.document import check_number

    out: dict[str, Distribution] = {}
    if not table.data:
        raise table.error('expected at least one input, e.g. x = "normal(0, 1)"')
    for name, value in table.data.items():
        where = (*table.path, name)
        if isinstance(value, str):
            try:
                out[name] = parse_distribution(value, field=name)
            except MtmcError as exc:
                raise type(exc)(
                    exc.message,
                    file=table.source.file,
                    line=table.source.line(where),
                    field=".".join(map(str, where)),
                ) from None
        else:

            def err(msg: str, _w: tuple[str | int, ...] = where) -> InputError:
                text = msg.replace("expected a number", "expected a distribution text or a number")
                return table.source.error(text, _w)

            num = check_number(value, err)
            out[name] = as_distribution(num)
    return out


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
    """

    kind = "propagate"
    model: Expression
    output: str
    unit: str
    inputs: dict[str, Distribution]

    def execute(self, settings: RunSettings, progress: ProgressFn | None) -> StudyResult:
        """Monte Carlo and GUM of the model (see the module docstring)."""
        mc = monte_carlo(
            self.model,
            self.inputs,
            trials=settings.trials,
            seed=settings.seed,
            progress=progress,
            **settings.parallel,
        )
        g = gum(self.model, self.inputs, p=settings.p)
        q = quantity(self.output, self.unit, mc, g, settings)
        inputs = tuple(
            {"name": n, "distribution": str(d), "estimate": float(d.mean), "u": float(d.std)}
            for n, d in self.inputs.items()
        )
        extra: dict[str, Any] = {"model": self.model.text}
        samples = {self.output: mc.samples} if settings.samples else {}
        return self._result(settings, quantities=(q,), inputs=inputs, extra=extra, samples=samples)


@register_kind("propagate", "an expression of named inputs: Monte Carlo beside the GUM")
def load_propagate(top: Fields) -> PropagateStudy:
    """Validate a ``propagate`` study file (see ``docs/study-format.md``)."""
    top.only(("kind", "title", "model", "output", "unit", "inputs", "run"))
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
    return PropagateStudy(
        title=top.text("title", "Propagation of distributions"),
        source=top.source,
        settings=RunSettings.read(top, default_trials=10**6),
        model=model,
        output=top.text("output", "y"),
        unit=top.text("unit", "1"),
        inputs={n: inputs[n] for n in model.names},
    )
