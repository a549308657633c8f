"""The refractive index of air by the updated Edlén equations, batched and complex-safe.

A laser interferometer counts fringes of its wavelength in air, ``λ_vac / n``: its reading
is as good as the refractive index ``n`` it divides by. Two updates of Edlén's (1966)
equation are given here, each as its authors wrote it (``docs/positioning.md``):

- **Bönsch and Potulski (1998)**, Metrologia 35, 133–139 (the default): dry standard air
  at 20 °C, 100 000 Pa, 400 µmol/mol CO₂;
- **Birch and Downs (1993, 1994)**, Metrologia 30, 155–162 and the correction in
  Metrologia 31, 315–316: standard air at 15 °C, 101 325 Pa, 450 µmol/mol CO₂ (the
  Birch–Downs equation has no CO₂ term; its CO₂ content is fixed).

Water vapour enters through its partial pressure ``f = h p_sv(t)``, ``h`` the relative
humidity and ``p_sv`` the saturation vapour pressure of :func:`saturation_vapour_pressure`
(the formula of the CIPM equation for the density of moist air, Davis 1992; the
enhancement factor, within 0.5 % of 1 at room conditions, is left out).

Every function is a polynomial, a rational function or an exponential of its arguments,
so it is batched (any broadcastable shapes) and accepts complex arguments: the GUM's
complex-step derivative (:func:`mtmc.uncertainty.gum`) goes through it exactly.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from mtmc.errors import InputError

__all__ = [
    "EQUATIONS",
    "HENE_WAVELENGTH_NM",
    "refractive_index",
    "saturation_vapour_pressure",
]

#: The equations :func:`refractive_index` knows.
EQUATIONS = ("bonsch-potulski", "birch-downs")

#: Vacuum wavelength of a helium–neon laser, nm (the red line, 632.99 nm).
HENE_WAVELENGTH_NM = 632.991

# Davis (1992), the CIPM-81/91 equation for the density of moist air: p_sv in Pa, T in K.
_SV_A = 1.2378847e-5
_SV_B = -1.9121316e-2
_SV_C = 33.93711047
_SV_D = -6.3431645e3


def saturation_vapour_pressure(t: npt.ArrayLike) -> Any:
    """Saturation vapour pressure of water over a plane surface, Pa.

    ``p_sv = exp(A T² + B T + C + D/T)`` Pa with ``T = t + 273.15`` K and ``A =
    1.2378847e-5 K⁻²``, ``B = -1.9121316e-2 K⁻¹``, ``C = 33.93711047``, ``D =
    -6.3431645e3 K`` (Davis 1992, the CIPM equation for the density of moist air).

    Parameters
    ----------
    t : array_like
        Air temperature, °C (real or complex, any shape).

    Returns
    -------
    ndarray
        Pa, the shape of ``t``.

    Examples
    --------
    >>> round(float(saturation_vapour_pressure(20.0)), 1)
    2339.2
    """
    tk = np.asarray(t) + 273.15
    return np.exp(_SV_A * tk**2 + _SV_B * tk + _SV_C + _SV_D / tk)


def refractive_index(
    t: npt.ArrayLike,
    p: npt.ArrayLike,
    humidity: npt.ArrayLike = 0.0,
    *,
    co2: npt.ArrayLike = 400.0,
    wavelength_nm: float = HENE_WAVELENGTH_NM,
    equation: str = "bonsch-potulski",
) -> Any:
    """Refractive index ``n`` of moist air by an updated Edlén equation.

    With the vacuum wavenumber ``σ = 1000/λ`` µm⁻¹ (``λ`` in nm), the air temperature
    ``t`` in °C, the pressure ``p`` and the partial pressure of water vapour
    ``f = (h/100) p_sv(t)`` in Pa, and the CO₂ mole fraction ``x``:

    Bönsch and Potulski (1998), eqs. for dry standard air (20 °C, 100 kPa, x = 0.0004),
    CO₂, temperature and pressure, water vapour::

        (n_N - 1) 10⁸ = 8091.37 + 2 333 983 / (130 - σ²) + 15 518 / (38.9 - σ²)
        n_x - 1 = (n_N - 1) (1 + 0.5327 (x - 0.0004))
        n_tpx - 1 = (n_x - 1) p (1 + 10⁻⁸ (0.5953 - 0.009876 t) p) / (93 214.60 (1 + 0.0036610 t))
        n - n_tpx = -f (3.8020 - 0.0384 σ²) 10⁻¹⁰

    Birch and Downs (1993, corrected 1994), standard air at 15 °C, 101 325 Pa with
    450 µmol/mol CO₂ (``co2`` is not used)::

        (n_s - 1) 10⁸ = 8342.54 + 2 406 147 / (130 - σ²) + 15 998 / (38.9 - σ²)
        n_tp - 1 = p (n_s - 1) / 96 095.43 · (1 + 10⁻⁸ (0.601 - 0.00972 t) p) / (1 + 0.0036610 t)
        n - n_tp = -f (3.7345 - 0.0401 σ²) 10⁻¹⁰

    Parameters
    ----------
    t : array_like
        Air temperature, °C.
    p : array_like
        Air pressure, Pa.
    humidity : array_like, default 0
        Relative humidity, % (0 to 100).
    co2 : array_like, default 400, keyword-only
        CO₂ content, µmol/mol (ppm); Bönsch–Potulski only.
    wavelength_nm : float, keyword-only
        Vacuum wavelength, nm (default :data:`HENE_WAVELENGTH_NM`).
    equation : {"bonsch-potulski", "birch-downs"}, keyword-only

    Returns
    -------
    ndarray
        ``n``, the broadcast shape of the arguments (complex if any argument is).

    Raises
    ------
    InputError
        On an unknown equation or a wavelength outside 350–1700 nm (where the equations
        were fitted, roughly).

    Examples
    --------
    >>> n = refractive_index(20.0, 101325.0, 50.0)
    >>> round((float(n) - 1) * 1e8, 1)
    27135.0
    """
    if equation not in EQUATIONS:
        raise InputError(
            f"expected an equation among {', '.join(EQUATIONS)}, got {equation!r}",
            field="equation",
        )
    lam = float(wavelength_nm)
    if not 350.0 <= lam <= 1700.0:
        raise InputError(
            f"expected a vacuum wavelength in 350-1700 nm, got {wavelength_nm!r}",
            field="wavelength_nm",
        )
    s2 = (1000.0 / lam) ** 2
    t_ = np.asarray(t)
    p_ = np.asarray(p)
    f = np.asarray(humidity) / 100.0 * saturation_vapour_pressure(t_)
    if equation == "bonsch-potulski":
        n_n = 1e-8 * (8091.37 + 2333983.0 / (130.0 - s2) + 15518.0 / (38.9 - s2))
        x = np.asarray(co2) * 1e-6
        n_x = n_n * (1.0 + 0.5327 * (x - 0.0004))
        n_tp = n_x * p_ * (1.0 + 1e-8 * (0.5953 - 0.009876 * t_) * p_)
        n_tp = n_tp / (93214.60 * (1.0 + 0.0036610 * t_))
        water = -f * (3.8020 - 0.0384 * s2) * 1e-10
    else:
        n_s = 1e-8 * (8342.54 + 2406147.0 / (130.0 - s2) + 15998.0 / (38.9 - s2))
        n_tp = p_ * n_s / 96095.43 * (1.0 + 1e-8 * (0.601 - 0.00972 * t_) * p_)
        n_tp = n_tp / (1.0 + 0.0036610 * t_)
        water = -f * (3.7345 - 0.0401 * s2) * 1e-10
    return 1.0 + n_tp + water
