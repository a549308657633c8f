"""Checkers of the arguments the uncertainty functions share.

One checker per kind of input, so that :func:`mtmc.uncertainty.gum`, the Monte Carlo
summaries and the validation refuse a bad value alike, with one message.

Examples
--------
>>> check_probability(0.95)
0.95
>>> check_probability("x")
Traceback (most recent call last):
...
mtmc.errors.InputError: field p: expected a coverage probability 0 < p < 1, got 'x'
"""

from __future__ import annotations

from typing import Any

from mtmc.errors import InputError

__all__ = ["check_probability"]


def check_probability(p: Any, field: str = "p") -> float:
    """A coverage probability as a float in the open interval (0, 1).

    Parameters
    ----------
    p : Any
        The value given.
    field : str
        The argument name for the message.

    Returns
    -------
    float

    Raises
    ------
    InputError
        If ``p`` is not a number, or not strictly between 0 and 1 (NaN included).
    """
    try:
        pf = float(p)
    except (TypeError, ValueError):
        pf = float("nan")
    if not 0.0 < pf < 1.0:
        raise InputError(f"expected a coverage probability 0 < p < 1, got {p!r}", field=field)
    return pf
