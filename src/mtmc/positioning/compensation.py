"""A pitch-error compensation table from a positioning test, and the residual it leaves.

The table is the positioning error ``E<axis><axis>`` (ISO 230-1: ``EXX`` for a linear axis
X, ``ECC`` for a rotary axis C) tabulated at the targets ``P_i``: the mean bidirectional
positional deviation ``x̄_i = (x̄_i↑ + x̄_i↓) / 2``, the error a control compensates by
subtracting it (:mod:`mtmc.verification.compensation`'s sign convention; ``sign =
"correction"`` writes its negative). It is a :class:`~mtmc.verification.CompensationTable`,
so the writers of that module give it in the ISG CSV, Etalon exchange and plain CSV
formats (:func:`~mtmc.verification.dump_compensation`), in their units: mm or rad for the
values, mm or deg for the positions.

Applied to the test (:func:`apply_compensation`), the table is read back as a control
would read it (linear interpolation between its positions,
:meth:`~mtmc.verification.CompensationTable.errors`) and subtracted from each reading: at
the targets the residual means are ``x̄_i↑ - x̄_i = B_i/2`` and ``x̄_i↓ - x̄_i = -B_i/2``,
so the mean bidirectional deviation vanishes (``M = 0``) and what remains is the reversal
and the scatter, which a pitch table cannot remove.
"""

from __future__ import annotations

import math

import numpy as np

from mtmc.errors import InputError
from mtmc.positioning.data import PositioningTest
from mtmc.positioning.parameters import evaluate
from mtmc.verification.compensation import SIGNS, CompensationTable, ErrorCurve

__all__ = ["apply_compensation", "pitch_compensation"]

#: The unit of a deviation to mm (linear axes) or rad (rotary axes).
_TO_CODE = {"um": 1e-3, "mm": 1.0, "arcsec": math.pi / (180.0 * 3600.0), "urad": 1e-6}


def _axis(test: PositioningTest, axis: str) -> str:
    a = str(axis).upper()
    rotary = a in ("A", "B", "C")
    if len(a) != 1 or a not in "XYZUVWABC":
        raise InputError(f"expected an axis letter X, Y, Z, U, V, W, A, B or C, got {axis!r}")
    if rotary != test.rotary:
        kind = "rotary" if test.rotary else "linear"
        raise InputError(
            f"axis {a} is {'rotary' if rotary else 'linear'}, the test is of a {kind} axis "
            f"({test.target_unit})",
            field="axis",
        )
    return a


def pitch_compensation(
    test: PositioningTest, axis: str = "X", *, sign: str = "error"
) -> CompensationTable:
    """The pitch-error table of an axis: ``x̄_i`` at each target, as ``E<axis><axis>``.

    Parameters
    ----------
    test : PositioningTest
    axis : str, default "X"
        The axis letter (``X``, ``Y``, ``Z``, ``U``, ``V``, ``W``; ``A``, ``B``, ``C`` for
        a rotary test).
    sign : {"error", "correction"}, keyword-only
        Whether the table holds the errors (default) or their negatives.

    Returns
    -------
    CompensationTable
        One curve, positions in mm (rad), values in mm (rad).

    Raises
    ------
    InputError
        On an unknown axis letter or sign, or an axis whose kind is not the test's.

    Examples
    --------
    >>> x = np.zeros((2, 2, 2)); x[1] = [[4.0, 2.0], [4.0, 2.0]]      # µm
    >>> table = pitch_compensation(PositioningTest([0.0, 500.0], x), "X")
    >>> table.curve("EXX").values.tolist()
    [0.0, 0.003]
    """
    a = _axis(test, axis)
    if sign not in SIGNS:
        raise InputError(f"expected sign 'error' or 'correction', got {sign!r}", field="sign")
    xbar = evaluate(test).mean
    values = np.asarray(xbar, dtype=np.float64) * _TO_CODE[test.unit]
    positions = test.targets * (math.pi / 180.0 if test.rotary else 1.0)
    table = CompensationTable({}, (ErrorCurve(f"E{a}{a}", positions, values),), "error")
    return table.with_sign(sign)


def apply_compensation(
    test: PositioningTest, table: CompensationTable, axis: str = "X"
) -> PositioningTest:
    """The readings a compensated axis would give: each minus the table's error at its target.

    Parameters
    ----------
    test : PositioningTest
    table : CompensationTable
        A table with the curve ``E<axis><axis>`` (errors or corrections: the sign is
        honoured), read as a control reads it (linear interpolation between its
        positions); every target must lie within them.
    axis : str, default "X"

    Returns
    -------
    PositioningTest
        The residual readings, in the test's unit.

    Raises
    ------
    InputError
        If the table has no such curve, or a target lies outside its positions.
    """
    a = _axis(test, axis)
    name = f"E{a}{a}"
    errors = table.errors()
    if name not in errors:
        raise InputError(f"the table has no {name}; it has {', '.join(errors)}", field="axis")
    fn = errors[name]
    q = test.targets * (math.pi / 180.0 if test.rotary else 1.0)
    e = np.asarray(fn(q) if callable(fn) else np.full(q.shape, fn), dtype=np.float64)
    shift = e.reshape(-1) / _TO_CODE[test.unit]
    return PositioningTest(
        targets=test.targets,
        deviations=test.deviations - shift[:, None, None],
        unit=test.unit,
        target_unit=test.target_unit,
        runs=test.runs,
        source=test.source,
    )
