"""Units of a study's inputs and outputs, read with pint, and the model checked against them.

An input of a ``propagate`` study may say its unit (``L = {dist = "normal(100, 0.001)",
unit = "mm"}``). Where every input of the model has one, the model is checked before it
runs (:func:`check_model_units`): each sum adds quantities of one unit, each function
takes what it can (``sqrt`` anything, ``sin`` an angle in rad or a pure number, ``exp``
and ``log`` a pure number), and the unit the model gives is the study's ``unit`` (the
output's), to the factor 1: the engine computes with the numbers as written and converts
nothing, so ``L`` in m and an output in mm would be a factor of 1000 wrong, and is refused.

A number written in the model without a unit takes the unit of what it is added to or
subtracted from (``rho_a - 1.2``: 1.2 kg/m³ where ``rho_a`` is in kg/m³), and is a pure
number in a product, a quotient or an exponent, as a reader of the formula takes it.

The unit texts are pint's (``mm``, ``um``, ``µm``, ``kg/m^3``, ``1/K``, ``ppm``, ``rad``,
``deg``); ``1`` is a pure number.

Examples
--------
>>> from mtmc.uncertainty.formula import expression
>>> str(model_unit(expression("(m + dm) * (1 + (rho - 1.2) / rho_w)"),
...     {"m": "mg", "dm": "mg", "rho": "kg/m^3", "rho_w": "kg/m^3"}))
'milligram'
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from mtmc.errors import InputError

__all__ = ["check_model_units", "model_unit", "read_unit", "registry", "unit_text"]

_REGISTRY: Any = None

#: The longest unit text read.
MAX_UNIT_CHARS = 100
#: What a unit text is made of: names, digits, µ, °, %, and ``/ * ^ . · ( ) -`` and spaces
#: (pint's parser would also take other things, such as ``!`` for a factorial).
_UNIT_TEXT = re.compile(r"[A-Za-zµ°%0-9_ /*^.·()\-⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+")
#: Superscript powers as pint reads them (``m³`` → ``m**3``, as :func:`unit_text` writes).
_POWERS = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹·", "-0123456789*")


def registry() -> Any:
    """The one pint registry of mtmc (made on first use: pint takes 0.4 s to load)."""
    global _REGISTRY
    if _REGISTRY is None:
        import pint

        _REGISTRY = pint.UnitRegistry()
    return _REGISTRY


def read_unit(text: str, error: Callable[[str], Exception] = InputError) -> Any:
    """The pint unit a text names, or ``error(message)`` raised.

    Examples
    --------
    >>> str(read_unit("kg/m^3")), str(read_unit("µm")), str(read_unit("1"))
    ('kilogram / meter ** 3', 'micrometer', 'dimensionless')
    """
    bad = (
        f"expected a unit such as mm, um, kg/m^3, 1/K, ppm, rad or 1, got {text!r}"
        if len(text) <= MAX_UNIT_CHARS
        else f"expected a unit of at most {MAX_UNIT_CHARS} characters"
    )
    if len(text) > MAX_UNIT_CHARS or _UNIT_TEXT.fullmatch(text.strip()) is None:
        raise error(bad)
    reg = registry()
    try:
        q = reg.Quantity(1.0, _plain(text))
    except Exception:  # pint's parse errors are of several types, none of them mtmc's
        raise error(bad) from None
    if not isinstance(q.magnitude, float) or q.magnitude != 1.0:
        raise error(bad)
    powers = [float(v) for v in q.units.dimensionality.values()]
    if any(not math.isfinite(v) or abs(v) > 12 for v in powers):
        raise error(f"expected a unit with powers of at most 12, got {text!r}")
    return q.units


def _plain(text: str) -> str:
    """A unit text with its superscript powers as ``**n`` and µ as ``u``, for pint."""
    out = re.sub(r"([⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+)", lambda m: "**" + m[1], text.replace("µ", "u"))
    return out.translate(_POWERS)


def unit_text(unit: Any) -> str:
    """A unit as a report prints it: ``mm``, ``kg/m³``, ``1`` (pint's short form)."""
    text = f"{unit:~P}"
    return text or "1"


@dataclass(frozen=True)
class _Bare:
    """A number written in the model without a unit."""

    value: float


def _trig(unit: Any, f: str) -> None:
    reg = registry()
    if unit.dimensionality and unit.dimensionality != reg.radian.dimensionality:
        raise InputError(f"{f} takes an angle in rad or a pure number, got {unit_text(unit)}")
    if unit != reg.dimensionless and (1.0 * unit).to(reg.radian).magnitude != 1.0:
        raise InputError(
            f"{f} takes an angle in rad (the engine converts nothing), got {unit_text(unit)}"
        )


def _unit_of(v: Any) -> Any:
    return registry().dimensionless if isinstance(v, _Bare) else v


def _operator(op: str, a: Any, b: Any) -> Any:
    """The unit of ``a op b`` (a bare number: the unit it joins in a sum, else 1)."""
    one = registry().dimensionless
    if op in ("neg", "pos"):
        return a
    if op in ("+", "-"):
        if isinstance(a, _Bare) and isinstance(b, _Bare):
            return _Bare(a.value + b.value)
        if isinstance(a, _Bare) or isinstance(b, _Bare):
            return b if isinstance(a, _Bare) else a
        if a != b:
            raise InputError(
                f"{op} of {unit_text(a)} and {unit_text(b)}: a sum takes one unit "
                "(the engine converts nothing)"
            )
        return a
    if op == "**":
        if isinstance(b, _Bare):
            return _unit_of(a) ** b.value
        if b != one:
            raise InputError(f"an exponent is a pure number, got {unit_text(b)}")
        if _unit_of(a) != one:
            raise InputError(
                f"{unit_text(_unit_of(a))} to a power computed by the model: the unit of "
                "the result would change from trial to trial"
            )
        return one
    ua, ub = _unit_of(a), _unit_of(b)
    return ua * ub if op == "*" else ua / ub


def _call(f: str, args: list[Any]) -> Any:
    """The unit of ``f(*args)``, or the error of an argument ``f`` does not take."""
    reg = registry()
    us = [_unit_of(a) for a in args]
    if f == "sqrt":
        return us[0] ** 0.5
    if f == "abs":
        return us[0]
    if f in ("sin", "cos", "tan"):
        _trig(us[0], f)
        return reg.dimensionless
    if f == "arctan2":
        if not all(isinstance(a, _Bare) for a in args) and us[0] != us[1]:
            raise InputError(
                f"arctan2 takes two quantities of one unit, got {unit_text(us[0])} and "
                f"{unit_text(us[1])}"
            )
        return reg.radian
    if us[0] != reg.dimensionless:  # arcsin, arccos, arctan, exp, log, log10
        raise InputError(f"{f} takes a pure number, got {unit_text(us[0])}")
    return reg.radian if f.startswith("arc") else reg.dimensionless


def model_unit(model: Any, units: Mapping[str, str]) -> Any:
    """The unit the model gives from its inputs' units (module docstring).

    Parameters
    ----------
    model : Expression
    units : mapping of str to str
        The unit of each variable of the model.

    Returns
    -------
    pint.Unit

    Raises
    ------
    InputError
        Naming the operation: a sum of two units, a function of a unit it does not take,
        an exponent with a unit.
    """
    one = registry().dimensionless
    read = {n: read_unit(units[n]) for n in model.names}

    def leaf(name: str, _index: int | None) -> Any:
        return read.get(name, one)  # pi and e: pure numbers

    return _unit_of(model.fold(leaf, _Bare, _operator, _call))


def check_model_units(model: Any, units: Mapping[str, str], output_unit: str) -> Any:
    """Refuse a model whose unit is not the output's, to the factor 1 (module docstring).

    Returns
    -------
    pint.Unit
        The model's unit.

    Raises
    ------
    InputError
        As :func:`model_unit`; or the output's unit of another dimension, or of the same
        dimension but another size (``m`` against ``mm``).
    """
    got = model_unit(model, units)
    want = read_unit(output_unit)
    if got.dimensionality != want.dimensionality:
        raise InputError(
            f"the model gives {unit_text(got)} from its inputs' units; the output's unit "
            f"{unit_text(want)} is another quantity"
        )
    factor = float((1.0 * got).to(want).magnitude)
    if not math.isclose(factor, 1.0, rel_tol=1e-12):
        raise InputError(
            f"the model gives {unit_text(got)} from its inputs' units, {factor:g} "
            f"{unit_text(want)}: the engine converts nothing, so write unit = "
            f'"{unit_text(got)}" or give the inputs in units that make {unit_text(want)}'
        )
    return got
