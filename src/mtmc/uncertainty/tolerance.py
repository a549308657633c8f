"""Numerical tolerance of a Monte Carlo result (JCGM 101:2008 §7.9.2).

JCGM 101 §7.9.2: write the standard uncertainty as ``u = c × 10**l`` where ``c`` is an
integer with ``ndig`` significant digits; the numerical tolerance associated with ``u`` is
``δ = ½ × 10**l``. The adaptive Monte Carlo procedure of §7.9.4 stops when twice the
standard deviations of the estimate, of ``u`` and of the coverage-interval endpoints over
repeated blocks are all at most ``δ``.

Examples
--------
JCGM 101 §9.3 (mass calibration) reports ``u(δm) = 0.075 mg`` to two significant digits:

>>> numerical_tolerance(0.0754)
0.0005
>>> numerical_tolerance(1.5)
0.05
>>> numerical_tolerance(0.0999)  # rounds to c = 10, l = -2
0.005
"""

from __future__ import annotations

import math

from mtmc.errors import InputError

__all__ = ["numerical_tolerance", "round_to_uncertainty", "significant_decomposition"]


def significant_decomposition(u: float, ndig: int = 2) -> tuple[int, int]:
    """Write ``u`` as ``c × 10**l`` with ``c`` an ``ndig``-digit integer (JCGM 101 §7.9.2).

    Parameters
    ----------
    u : float
        A positive, finite standard uncertainty (any unit).
    ndig : int, default 2
        Number of significant decimal digits regarded as meaningful in ``u``.

    Returns
    -------
    c, l : int, int
        ``c`` has exactly ``ndig`` digits (``10**(ndig-1) <= c < 10**ndig``) and
        ``c × 10**l`` is ``u`` rounded to ``ndig`` significant digits.

    Raises
    ------
    InputError
        If ``u`` is not a positive finite number or ``ndig`` is not a positive integer.

    Examples
    --------
    >>> significant_decomposition(0.0754, 2)
    (75, -3)
    >>> significant_decomposition(0.0996, 2)
    (10, -2)
    """
    if isinstance(ndig, bool) or not isinstance(ndig, int) or ndig < 1:
        raise InputError(f"expected a positive integer, got {ndig!r}", field="ndig")
    try:
        uf = float(u)
    except (TypeError, ValueError):
        raise InputError(f"expected a positive finite number, got {u!r}", field="u") from None
    if not math.isfinite(uf) or uf <= 0.0:
        raise InputError(f"expected a positive finite standard uncertainty, got {uf!r}", field="u")
    # Python's correctly rounded scientific formatting does the rounding to ndig digits,
    # including the carry (0.0996 -> 1.0e-01), without the pitfalls of floor(log10(u)).
    mantissa, exponent = f"{uf:.{ndig - 1}e}".split("e")
    c = int(mantissa.replace(".", ""))
    exp10 = int(exponent) - (ndig - 1)
    return c, exp10


def numerical_tolerance(u: float, ndig: int = 2) -> float:
    """Numerical tolerance ``δ`` associated with a standard uncertainty (JCGM 101 §7.9.2).

    Parameters
    ----------
    u : float
        A positive, finite standard uncertainty (any unit; ``δ`` has the same unit).
    ndig : int, default 2
        Number of significant decimal digits regarded as meaningful in ``u``.

    Returns
    -------
    float
        ``δ = ½ × 10**l`` where ``u = c × 10**l`` with ``c`` an ``ndig``-digit integer.

    Raises
    ------
    InputError
        If ``u`` is not a positive finite number or ``ndig`` is not a positive integer.

    Examples
    --------
    >>> numerical_tolerance(0.028)  # JCGM 101 §7.9.2: c = 28, l = -3
    0.0005
    >>> numerical_tolerance(1234.0, ndig=3)
    5.0
    """
    _, exp10 = significant_decomposition(u, ndig)
    # 0.5 * 10**l computed from a decimal string so that it is the nearest float.
    return float(f"5e{exp10 - 1}")


def round_to_uncertainty(y: float, U: float, ndig: int = 2) -> tuple[str, str]:
    """An estimate and its (expanded) uncertainty as the GUM says to state them.

    JCGM 100 §7.2.6: the uncertainty is given with at most ``ndig`` (usually two)
    significant digits, and the estimate is rounded to the last digit of the
    uncertainty. Both are rounded to nearest (ties to even, on the decimal value of the
    float).

    Parameters
    ----------
    y : float
        The estimate.
    U : float
        Its standard or expanded uncertainty (same unit), positive and finite.
    ndig : int, default 2
        Significant digits of ``U``.

    Returns
    -------
    y_text, U_text : str
        The two numbers as decimal text, with the same last decimal place.

    Raises
    ------
    InputError
        If ``U`` is not a positive finite number or ``y`` is not finite.

    Examples
    --------
    JCGM 100 §7.2.2: m_s = 100.021 47 g with u = 0.35 mg.

    >>> round_to_uncertainty(100.02147, 0.00035)
    ('100.02147', '0.00035')
    >>> round_to_uncertainty(1.234123, 0.075412)  # JCGM 101 §9.3, mg
    ('1.234', '0.075')
    >>> round_to_uncertainty(12345.6, 234.0)
    ('12350', '230')
    """
    c, exp10 = significant_decomposition(U, ndig)
    yf = float(y)
    if not math.isfinite(yf):
        raise InputError(f"expected a finite estimate, got {y!r}", field="y")
    if exp10 >= 0:
        return f"{round(yf / 10**exp10) * 10**exp10:d}", f"{c * 10**exp10:d}"
    places = -exp10
    y_text = f"{yf:.{places}f}"
    if float(y_text) == 0.0:
        y_text = y_text.lstrip("-")
    return y_text, f"{c * 10.0**exp10:.{places}f}"
