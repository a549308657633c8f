"""The refractive index of air by Ciddor's and the Edlén equations, batched and complex-safe.

A laser interferometer counts fringes of its wavelength in air, ``λ_vac / n``: its reading
is as good as the refractive index ``n`` it divides by. Four equations are given here,
each written out in :func:`refractive_index` as the code computes it
(``docs/positioning.md``):

- **Ciddor (1996)**, Applied Optics 35, 1566–1573 (the default): the BIPM-1981/91 density
  of moist air with its compressibility, Ciddor's dispersion of standard air (15 °C,
  101 325 Pa, 450 µmol/mol CO₂) and of water vapour (20 °C, 1333 Pa), with a CO₂ term;
  humidity as NIST's calculator takes it (Stone and Zimmerman, NIST Engineering Metrology
  Toolbox): the IAPWS saturation vapour pressure and the enhancement factor;
- **NIST's modified Edlén**: Birch and Downs (1993, 1994) with NIST's water term
  (a factor 292.75 K / T) and the IAPWS saturation vapour pressure;
- **Birch and Downs (1993, 1994)**, Metrologia 30, 155–162 and the correction in
  Metrologia 31, 315–316: standard air at 15 °C, 101 325 Pa, 450 µmol/mol CO₂ (the
  Birch–Downs equation has no CO₂ term; its CO₂ content is fixed);
- **Bönsch and Potulski (1998)**, Metrologia 35, 133–139: dry standard air at 20 °C,
  100 000 Pa, 400 µmol/mol CO₂.

For the last two, water vapour enters through its partial pressure ``f = h p_sv(t)``,
``h`` the relative humidity and ``p_sv`` the saturation vapour pressure of
:func:`saturation_vapour_pressure` (the formula of the CIPM equation for the density of
moist air, Davis 1992; the enhancement factor, within 0.5 % of 1 at room conditions, is
left out). The first two take ``p_sv`` from :func:`saturation_vapour_pressure_iapws`.

Every function is a polynomial, a rational function, a root, a power or an exponential
of its arguments, so it is batched (any broadcastable shapes) and accepts complex
arguments: the GUM's complex-step derivative (:func:`mtmc.uncertainty.gum`) goes through
it exactly. :data:`DOMAINS` holds the air and the wavelengths each equation is used for;
:func:`refractive_index` refuses a wavelength outside them, and the input model of a
positioning test (:class:`mtmc.positioning.UncertaintyModel`) refuses air whose PDF
reaches outside them. Outside the domain the formulas are extrapolations (and ``p_sv``
has no meaning above water's critical point, 374 °C: NaN there).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from mtmc.errors import InputError

__all__ = [
    "DEFAULT_EQUATION",
    "DOMAINS",
    "EQUATIONS",
    "HENE_WAVELENGTH_NM",
    "Domain",
    "enhancement_factor",
    "refractive_index",
    "saturation_vapour_pressure",
    "saturation_vapour_pressure_iapws",
]

#: The equations :func:`refractive_index` knows.
EQUATIONS = ("ciddor", "nist-edlen", "birch-downs", "bonsch-potulski")

#: The equation used where none is named: Ciddor's, the one of NIST's calculator and of
#: most laser-interferometer makers.
DEFAULT_EQUATION = "ciddor"

#: Vacuum wavelength of a helium–neon laser, nm (the red line, 632.99 nm).
HENE_WAVELENGTH_NM = 632.991


@dataclass(frozen=True)
class Domain:
    """The air and the wavelengths an equation is used for: closed intervals ``(low, high)``.

    Attributes
    ----------
    temperature_C, pressure_Pa, humidity_pct, co2_ppm, wavelength_nm : tuple of float
        Air temperature (°C), pressure (Pa), relative humidity (%), CO₂ content
        (µmol/mol) and vacuum wavelength (nm).
    """

    temperature_C: tuple[float, float]
    pressure_Pa: tuple[float, float]
    humidity_pct: tuple[float, float]
    co2_ppm: tuple[float, float]
    wavelength_nm: tuple[float, float]


# The air of NIST's check values (-40 to 50 °C, 60 to 120 kPa, 0 to 100 %), against which
# the equations are tested here; CO2 up to five times the outdoor content (the CO2 terms are
# linear corrections of about 1.4e-9 per 10 µmol/mol). The wavelengths: Ciddor's dispersion
# covers 300 nm (three of NIST's rows), the Edlén forms' are taken from 350 nm.
_AIR: dict[str, tuple[float, float]] = {
    "temperature_C": (-40.0, 50.0),
    "pressure_Pa": (60e3, 120e3),
    "humidity_pct": (0.0, 100.0),
    "co2_ppm": (0.0, 2000.0),
}

#: The :class:`Domain` of each equation (``docs/positioning.md``).
DOMAINS = {
    "ciddor": Domain(**_AIR, wavelength_nm=(300.0, 1700.0)),
    "nist-edlen": Domain(**_AIR, wavelength_nm=(350.0, 1700.0)),
    "birch-downs": Domain(**_AIR, wavelength_nm=(350.0, 1700.0)),
    "bonsch-potulski": Domain(**_AIR, wavelength_nm=(350.0, 1700.0)),
}

# Davis (1992), the CIPM-81/91 equation for the density of moist air: p_sv in Pa, T in K.
_SV_A = 1.2378847e-5
_SV_B = -1.9121316e-2
_SV_C = 33.93711047
_SV_D = -6.3431645e3

# IAPWS-IF97, the saturation-pressure equation of region 4 (n_1 ... n_10), T in K, p in MPa.
_IF97 = (
    0.11670521452767e4,
    -0.72421316703206e6,
    -0.17073846940092e2,
    0.12020824702470e5,
    -0.32325550322333e7,
    0.14915108613530e2,
    -0.48232657361591e4,
    0.40511340542057e6,
    -0.23855557567849,
    0.65017534844798e3,
)
# Over ice (Wagner, Saul and Pruss 1994), as NIST's calculator takes it below 0 °C.
_ICE_A1 = -13.928169
_ICE_A2 = 34.7078238


def saturation_vapour_pressure(t: npt.ArrayLike) -> Any:
    """Saturation vapour pressure of water over a plane surface, Pa (Davis 1992).

    ``p_sv = exp(A T² + B T + C + D/T)`` Pa with ``T = t + 273.15`` K and ``A =
    1.2378847e-5 K⁻²``, ``B = -1.9121316e-2 K⁻¹``, ``C = 33.93711047``, ``D =
    -6.3431645e3 K`` (Davis 1992, the CIPM equation for the density of moist air). The
    Edlén forms of Birch and Downs and of Bönsch and Potulski use it.

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


def saturation_vapour_pressure_iapws(t: npt.ArrayLike) -> Any:
    """Saturation vapour pressure, Pa: over water from 0 °C, over ice below, as NIST takes it.

    Over water, the saturation-pressure equation of IAPWS-IF97 (region 4)::

        ϑ = T + n₉/(T - n₁₀),  A = ϑ² + n₁ϑ + n₂,  B = n₃ϑ² + n₄ϑ + n₅,
        C = n₆ϑ² + n₇ϑ + n₈,   p_sv = 10⁶ (2C / (-B + √(B² - 4AC)))⁴ Pa

    with ``T = t + 273.15`` K; over ice (``t < 0``), ``p_sv = 611.657 exp(A₁(1 - θ^-1.5)
    + A₂(1 - θ^-1.25))`` Pa with ``θ = T / 273.16`` K, ``A₁ = -13.928169``, ``A₂ =
    34.7078238`` (Wagner, Saul and Pruss 1994). Ciddor's and NIST's modified Edlén
    equations use it here, as NIST's calculator does.

    Parameters
    ----------
    t : array_like
        Air temperature, °C (real or complex, any shape; the branch by the real part).

    Returns
    -------
    ndarray
        Pa, the shape of ``t``; NaN for real ``t`` above water's critical point.

    Examples
    --------
    >>> round(float(saturation_vapour_pressure_iapws(20.0)), 2)
    2339.21
    """
    t_ = np.asarray(t)
    tk = t_ + 273.15
    n = _IF97
    th = tk + n[8] / (tk - n[9])
    a = th**2 + n[0] * th + n[1]
    b = n[2] * th**2 + n[3] * th + n[4]
    c = n[5] * th**2 + n[6] * th + n[7]
    with np.errstate(invalid="ignore"):  # no saturation above the critical point: NaN
        water = 1e6 * (2.0 * c / (-b + np.sqrt(b**2 - 4.0 * a * c))) ** 4
    x = tk / 273.16
    ice = 611.657 * np.exp(_ICE_A1 * (1.0 - x**-1.5) + _ICE_A2 * (1.0 - x**-1.25))
    return np.where(np.real(t_) < 0.0, ice, water)


def enhancement_factor(t: npt.ArrayLike, p: npt.ArrayLike) -> Any:
    """The enhancement factor of water vapour in air, ``f = 1.00062 + 3.14e-8 p + 5.6e-7 t²``.

    The ratio of the saturation vapour pressure of water in air to that of pure water
    (Ciddor 1996 after the CIPM-81/91 equation; NIST's calculator alike): ``p`` in Pa,
    ``t`` in °C.

    Parameters
    ----------
    t, p : array_like
        Air temperature (°C) and pressure (Pa), broadcastable.

    Returns
    -------
    ndarray

    Examples
    --------
    >>> round(float(enhancement_factor(20.0, 101325.0)), 7)
    1.0040256
    """
    return 1.00062 + 3.14e-8 * np.asarray(p) + 5.6e-7 * np.asarray(t) ** 2


# Ciddor (1996): the compressibility of moist air (BIPM-1981/91), T in K, t in °C, p in Pa.
_Z_A = (1.58123e-6, -2.9331e-8, 1.1043e-10)
_Z_B = (5.707e-6, -2.051e-8)
_Z_C = (1.9898e-4, -2.376e-6)
_Z_D = 1.83e-11
_Z_E = -0.765e-8


def _compressibility(t: Any, p: Any, xw: Any) -> Any:
    tk = t + 273.15
    pt = p / tk
    lin = _Z_A[0] + _Z_A[1] * t + _Z_A[2] * t**2 + (_Z_B[0] + _Z_B[1] * t) * xw
    lin = lin + (_Z_C[0] + _Z_C[1] * t) * xw**2
    return 1.0 - pt * lin + pt**2 * (_Z_D + _Z_E * xw**2)


def _ciddor(t: Any, p: Any, h: Any, co2: Any, s2: float) -> Any:
    # dispersion of standard air (15 °C, 101 325 Pa, 450 µmol/mol) and of water vapour
    n_as = 1e-8 * (5792105.0 / (238.0185 - s2) + 167917.0 / (57.362 - s2))
    n_axs = n_as * (1.0 + 0.534e-6 * (co2 - 450.0))
    n_ws = 1.022e-8 * (295.235 + 2.6422 * s2 - 0.032380 * s2**2 + 0.004028 * s2**3)
    xw = h / 100.0 * enhancement_factor(t, p) * saturation_vapour_pressure_iapws(t) / p
    z = _compressibility(t, p, xw)
    # ρ_a/ρ_axs and ρ_w/ρ_ws of Ciddor's eq. (5): the molar masses and R cancel
    z_axs = _compressibility(15.0, 101325.0, 0.0)
    z_ws = _compressibility(20.0, 1333.0, 1.0)
    dens = p / (z * (t + 273.15))
    r_a = dens * (1.0 - xw) * z_axs * 288.15 / 101325.0
    r_w = dens * xw * z_ws * 293.15 / 1333.0
    return 1.0 + r_a * n_axs + r_w * n_ws


def _birch_downs_dry(t: Any, p: Any, s2: float) -> Any:
    n_s = 1e-8 * (8342.54 + 2406147.0 / (130.0 - s2) + 15998.0 / (38.9 - s2))
    n_tp = p * n_s / 96095.43 * (1.0 + 1e-8 * (0.601 - 0.00972 * t) * p)
    return n_tp / (1.0 + 0.0036610 * t)


def refractive_index(
    t: npt.ArrayLike,
    p: npt.ArrayLike,
    humidity: npt.ArrayLike = 0.0,
    *,
    co2: npt.ArrayLike = 400.0,
    wavelength_nm: float = HENE_WAVELENGTH_NM,
    equation: str = DEFAULT_EQUATION,
) -> Any:
    """Refractive index ``n`` of moist air by Ciddor's equation or an updated Edlén equation.

    With the vacuum wavenumber ``σ = 1000/λ`` µm⁻¹ (``λ`` in nm), the air temperature
    ``t`` in °C (``T = t + 273.15`` K), the pressure ``p`` in Pa, the relative humidity
    ``h`` in % and the CO₂ mole fraction ``x_c`` in µmol/mol:

    Ciddor (1996), with ``p_sv`` of :func:`saturation_vapour_pressure_iapws` and ``f`` of
    :func:`enhancement_factor`::

        (n_as - 1) 10⁸ = 5 792 105 / (238.0185 - σ²) + 167 917 / (57.362 - σ²)
        n_axs - 1 = (n_as - 1) (1 + 0.534e-6 (x_c - 450))
        (n_ws - 1) 10⁸ = 1.022 (295.235 + 2.6422 σ² - 0.032380 σ⁴ + 0.004028 σ⁶)
        x_w = (h/100) f(t, p) p_sv(t) / p
        Z(t, p, x_w) = 1 - (p/T) (a₀ + a₁t + a₂t² + (b₀ + b₁t) x_w + (c₀ + c₁t) x_w²)
                         + (p/T)² (d + e x_w²)
        n - 1 = (ρ_a / ρ_axs) (n_axs - 1) + (ρ_w / ρ_ws) (n_ws - 1)

    where ``ρ_a = p M_a (1 - x_w) / (Z R T)`` and ``ρ_w = p M_w x_w / (Z R T)`` are the
    densities of the dry-air and the water-vapour components, ``ρ_axs`` that of standard
    dry air (15 °C, 101 325 Pa, ``x_w = 0``, the same ``x_c``) and ``ρ_ws`` that of pure
    water vapour (20 °C, 1333 Pa, ``x_w = 1``); ``a₀ = 1.58123e-6 K/Pa``, ``a₁ =
    -2.9331e-8 Pa⁻¹``, ``a₂ = 1.1043e-10 (K Pa)⁻¹``, ``b₀ = 5.707e-6 K/Pa``, ``b₁ =
    -2.051e-8 Pa⁻¹``, ``c₀ = 1.9898e-4 K/Pa``, ``c₁ = -2.376e-6 Pa⁻¹``, ``d = 1.83e-11
    K²/Pa²``, ``e = -0.765e-8 K²/Pa²``. In the ratios the molar masses (``M_a`` with its
    CO₂ term) and ``R`` cancel, so the code computes ``ρ_a/ρ_axs = p (1 - x_w) Z_axs
    288.15 K / (101 325 Pa Z T)`` and ``ρ_w/ρ_ws = p x_w Z_ws 293.15 K / (1333 Pa Z T)``.

    NIST's modified Edlén: the Birch–Downs ``n_tp`` below, and the water term
    ``-(292.75 K / T) (3.7345 - 0.0401 σ²) p_v 10⁻¹⁰`` with ``p_v = (h/100) p_sv(t)`` of
    :func:`saturation_vapour_pressure_iapws` (no enhancement factor: it enters a mole
    fraction, not a partial pressure); ``co2`` is not used.

    Birch and Downs (1993, corrected 1994), standard air at 15 °C, 101 325 Pa with
    450 µmol/mol CO₂ (``co2`` is not used), ``f = (h/100) p_sv(t)`` of
    :func:`saturation_vapour_pressure`::

        (n_s - 1) 10⁸ = 8342.54 + 2 406 147 / (130 - σ²) + 15 998 / (38.9 - σ²)
        n_tp - 1 = p (n_s - 1) / 96 095.43 · (1 + 10⁻⁸ (0.601 - 0.00972 t) p) / (1 + 0.0036610 t)
        n - n_tp = -f (3.7345 - 0.0401 σ²) 10⁻¹⁰

    Bönsch and Potulski (1998), eqs. for dry standard air (20 °C, 100 kPa, x = 0.0004),
    CO₂ (``x = x_c 10⁻⁶``), temperature and pressure, water vapour (``f`` as above)::

        (n_N - 1) 10⁸ = 8091.37 + 2 333 983 / (130 - σ²) + 15 518 / (38.9 - σ²)
        n_x - 1 = (n_N - 1) (1 + 0.5327 (x - 0.0004))
        n_tpx - 1 = (n_x - 1) p (1 + 10⁻⁸ (0.5953 - 0.009876 t) p) / (93 214.60 (1 + 0.0036610 t))
        n - n_tpx = -f (3.8020 - 0.0384 σ²) 10⁻¹⁰

    Parameters
    ----------
    t : array_like
        Air temperature, °C.
    p : array_like
        Air pressure, Pa.
    humidity : array_like, default 0
        Relative humidity, % (0 to 100).
    co2 : array_like, default 400, keyword-only
        CO₂ content, µmol/mol (ppm); Ciddor and Bönsch–Potulski only.
    wavelength_nm : float, keyword-only
        Vacuum wavelength, nm (default :data:`HENE_WAVELENGTH_NM`).
    equation : {"ciddor", "nist-edlen", "birch-downs", "bonsch-potulski"}, keyword-only

    Returns
    -------
    ndarray
        ``n``, the broadcast shape of the arguments (complex if any argument is).

    Raises
    ------
    InputError
        On an unknown equation or a wavelength outside the equation's
        :attr:`Domain.wavelength_nm` (Ciddor 300–1700 nm, the Edlén forms 350–1700 nm).
        The air is not checked here (a Monte Carlo draw may fall just outside the
        domain): :class:`mtmc.positioning.UncertaintyModel` checks its PDFs.

    Examples
    --------
    >>> n = refractive_index(20.0, 101325.0, 0.0, co2=450.0, wavelength_nm=633.0)
    >>> round((float(n) - 1) * 1e9)  # NIST's calculator: 1.000271800
    271800
    """
    if equation not in EQUATIONS:
        raise InputError(
            f"expected an equation among {', '.join(EQUATIONS)}, got {equation!r}",
            field="equation",
        )
    lam = float(wavelength_nm)
    low, high = DOMAINS[equation].wavelength_nm
    if not low <= lam <= high:
        raise InputError(
            f"expected a vacuum wavelength in {low:g}-{high:g} nm for the {equation} "
            f"equation, got {wavelength_nm!r}",
            field="wavelength_nm",
        )
    s2 = (1000.0 / lam) ** 2
    t_ = np.asarray(t)
    p_ = np.asarray(p)
    h_ = np.asarray(humidity)
    if equation == "ciddor":
        return _ciddor(t_, p_, h_, np.asarray(co2), s2)
    if equation == "nist-edlen":
        p_v = h_ / 100.0 * saturation_vapour_pressure_iapws(t_)
        water = -292.75 / (t_ + 273.15) * (3.7345 - 0.0401 * s2) * p_v * 1e-10
        return 1.0 + _birch_downs_dry(t_, p_, s2) + water
    f = h_ / 100.0 * saturation_vapour_pressure(t_)
    if equation == "birch-downs":
        return 1.0 + _birch_downs_dry(t_, p_, s2) - f * (3.7345 - 0.0401 * s2) * 1e-10
    n_n = 1e-8 * (8091.37 + 2333983.0 / (130.0 - s2) + 15518.0 / (38.9 - s2))
    x = np.asarray(co2) * 1e-6
    n_x = n_n * (1.0 + 0.5327 * (x - 0.0004))
    n_tp = n_x * p_ * (1.0 + 1e-8 * (0.5953 - 0.009876 * t_) * p_)
    n_tp = n_tp / (93214.60 * (1.0 + 0.0036610 * t_))
    return 1.0 + n_tp - f * (3.8020 - 0.0384 * s2) * 1e-10
