"""The uncertainty of the parameters of ISO 230-2: an input model of the test, GUM and Monte Carlo.

The measurand is each parameter of :mod:`mtmc.positioning.parameters` of the axis at
20 °C, as the test measures it. Each reading ``x_ij`` (in the unit of the test, ``c`` of
that unit per mm; ``L_i = P_i - P_0`` the distance from the datum ``P_0`` where the laser
was zeroed; ``τ_ij`` the time of the reading as a fraction of the test,
:func:`~mtmc.positioning.data.reading_times`) is corrected::

    x'_ij = x_ij + c (L_i + x_ij/c) ((1 + δλ) n_c / n / cos θ - 1)      scale: λ, air, alignment
                 - c L_i (α (t_m - 20) - α₀ (t₀ - 20))                     material at 20 °C
                 - c d Δn τ_ij                                             dead path
                 - D τ_ij                                                  thermal drift
                 + ρ_ij                                                    resolution

with ``δλ`` the relative error of the laser's vacuum wavelength, ``n`` the refractive index
of the air (:func:`~mtmc.positioning.edlen.refractive_index` of the air temperature,
pressure and humidity, plus the equation's own error) and ``n_c`` the index the laser
compensated with (the same equation at the recorded values: the expectations of those
inputs), ``θ`` the angle between the beam and the axis (cosine error), ``α`` and ``t_m``
the expansion coefficient and temperature of the axis (``α₀``, ``t₀`` their recorded
values if the laser already corrected the readings to 20 °C, else 0), ``d`` the dead path
and ``Δn = (n(t + Δt, p + Δp) - n(t, p)) / n`` the change of the index over the test
(taken linear in time), ``D`` the drift of the machine over the test, linear in time,
and ``ρ_ij`` the rounding of each reading to the resolution ``r`` (rectangular,
``±r/2``).

From the corrected readings, the means ``x̄'`` and standard deviations ``s'`` at each
target and direction; then, as the Type A evaluation of the axis' own scatter (JCGM 100
§4.2, JCGM 101 §6.4.9), each mean unidirectional deviation is ``x̄'_i + s'_i/√n · T_i``
with ``T_i`` a t variable of ``ν = n - 1`` degrees of freedom (the scaled-and-shifted t
of ``x̄'``, ``s'/√n``), and (with ``type_a = "means-and-s"``) each standard deviation
``s'_i / √g_i`` with ``ν g_i`` a χ²_ν variable (the PDF of σ given ``s`` under the prior
of JCGM 101 §6.4.9). The parameters then follow from their definitions.

:func:`evaluate_uncertainty` runs this one model by Monte Carlo
(:func:`mtmc.uncertainty.monte_carlo`) and by the GUM (:func:`mtmc.uncertainty.gum`), and
validates the GUM by JCGM 101 §8. The maxima and minima over the targets of A, E, M, R
and B are where the GUM's linearisation is weakest: at a near tie between two targets
the Monte Carlo PDF lies above the GUM's and is skewed; :func:`disagreement_notes` says so.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from mtmc.errors import DistributionError, InputError
from mtmc.positioning.data import PositioningTest, reading_times
from mtmc.positioning.edlen import (
    DEFAULT_EQUATION,
    DOMAINS,
    EQUATIONS,
    HENE_WAVELENGTH_NM,
    refractive_index,
)
from mtmc.positioning.parameters import (
    SYMBOLS,
    PositioningParameters,
    axis_parameters,
    evaluate,
    statistics,
)
from mtmc.uncertainty.distributions import (
    IID,
    Constant,
    Distribution,
    Gamma,
    StudentT,
    Uniform,
    as_distribution,
)
from mtmc.uncertainty.montecarlo import monte_carlo
from mtmc.uncertainty.propagation import GumResult, gum
from mtmc.uncertainty.results import MonteCarloResult

__all__ = [
    "DEPENDS",
    "OUTSIDE",
    "TYPE_A",
    "PositioningUncertainty",
    "UncertaintyModel",
    "check_deviation_ranges",
    "coverage",
    "disagreement_notes",
    "evaluate_uncertainty",
    "physical_ranges",
    "positioning_model",
]

#: How the axis' scatter enters: as Type A uncertainty of the means, of the means and
#: the standard deviations, or not at all (the parameters of the test's readings).
TYPE_A = ("means", "means-and-s", "none")

#: The readings one array of a block of trials holds at most (``trials × 2 m n``): about
#: 32 MiB an array, whatever the size of the test.
BLOCK_READINGS = 1 << 22

#: Millimetres to the unit of the deviations of a linear axis.
_PER_MM = {"um": 1e3, "mm": 1.0}

#: The unit of each named input of the model (the deviation unit for ``drift``, ``resolution``).
INPUT_UNITS = {
    "air_temperature": "°C",
    "air_pressure": "hPa",
    "humidity": "%",
    "co2": "µmol/mol",
    "equation_error": "ppm",
    "wavelength_error": "ppm",
    "material_temperature": "°C",
    "expansion": "ppm/K",
    "misalignment": "µrad",
    "air_temperature_change": "°C",
    "air_pressure_change": "hPa",
}

_LENGTH_ONLY = (
    "air_temperature",
    "air_pressure",
    "humidity",
    "material_temperature",
    "expansion",
    "misalignment",
    "wavelength_error",
    "equation_error",
)


#: The probability a PDF may put outside its input's physical range (:func:`physical_ranges`):
#: its central ``1 - OUTSIDE`` interval, from its quantiles, must lie inside the range (a
#: normal PDF: mean ± 4.9 sd). At the 10⁶ trials JCGM 101 suggests, about one draw falls
#: outside, and only just; a PDF without a quantile function is held to mean ± 1000 sd,
#: which bounds the probability outside to ``OUTSIDE`` by Chebyshev's inequality.
OUTSIDE = 1e-6

# The physical ranges that depend on neither the equation nor the deviation unit:
# (low, high, why), in the unit of INPUT_UNITS.
_RANGES: dict[str, tuple[float, float, str]] = {
    "material_temperature": (
        -40.0,
        100.0,
        "a machine's structure in service; the model takes one expansion coefficient, "
        "and steel's changes by some 10 % over this range",
    ),
    "expansion": (
        -10.0,
        50.0,
        "the materials of axes and scales, from carbon-fibre composites (slightly "
        "negative) and glass ceramics (near 0) through steel (11.5) to aluminium (23) and "
        "magnesium (26)",
    ),
    "misalignment": (
        -1e4,
        1e4,
        "10 mrad: a cosine error of 50 ppm, and a return beam that walks off by 2 cm per "
        "metre of travel, past any interferometer's aperture",
    ),
    "equation_error": (
        -10.0,
        10.0,
        "the equations' own error is some 0.01-0.05 ppm; 10 ppm is 4 % of n - 1 itself",
    ),
    "wavelength_error": (
        -100.0,
        100.0,
        "a stabilised laser is known to 0.05 ppm, a free-running one to a few ppm",
    ),
    "air_temperature_change": (
        -10.0,
        10.0,
        "the change of the air over one test; more than 10 °C is no test of an axis",
    ),
    "air_pressure_change": (
        -50.0,
        50.0,
        "the change of the air over one test; weather moves the pressure by some 30 hPa in a day",
    ),
    "dead_path_mm": (
        0.0,
        1e5,
        "the reach of a laser interferometer (some 40-80 m)",
    ),
}

# Drift and resolution, in the deviation unit: |drift| <= 1 mm or 0.1°, resolution <= 0.1 mm
# or 0.01°.
_DEVIATION_RANGES: dict[str, tuple[float, float]] = {
    "um": (1e3, 1e2),
    "mm": (1.0, 0.1),
    "arcsec": (360.0, 36.0),
    "urad": (math.radians(0.1) * 1e6, math.radians(0.01) * 1e6),
}


def physical_ranges(
    equation: str = DEFAULT_EQUATION, unit: str | None = None
) -> dict[str, tuple[float, float, str]]:
    """The physical range of each input of the model, with the reason for it.

    A value outside its range, or a PDF that puts more than :data:`OUTSIDE` of its
    probability outside it, is refused by :class:`UncertaintyModel` (the air, the
    material, the alignment, the laser, the dead path) and by :func:`positioning_model`
    (drift and resolution, which are in the deviation unit).

    Parameters
    ----------
    equation : str, default :data:`~mtmc.positioning.edlen.DEFAULT_EQUATION`
        The refractive-index equation: the air and the wavelength are its
        :data:`~mtmc.positioning.edlen.DOMAINS`.
    unit : str, optional
        The deviation unit (``um``, ``mm``, ``arcsec``, ``urad``): adds ``drift`` and
        ``resolution``.

    Returns
    -------
    dict of str to (float, float, str)
        ``(low, high, why)`` by input name, in the unit of :data:`INPUT_UNITS` (``nm``
        for ``wavelength_nm``, ``mm`` for ``dead_path_mm``, the deviation unit for
        ``drift`` and ``resolution``).

    Examples
    --------
    >>> physical_ranges()["humidity"][:2]
    (0.0, 100.0)
    >>> physical_ranges(unit="um")["drift"][:2]
    (-1000.0, 1000.0)
    """
    d = DOMAINS[equation]
    air = f"the air over which the {equation} equation is tested against NIST's check values"
    out = {
        "air_temperature": (*d.temperature_C, air),
        "air_pressure": (d.pressure_Pa[0] / 100.0, d.pressure_Pa[1] / 100.0, air),
        "humidity": (*d.humidity_pct, "relative humidity: above 100 % the vapour condenses"),
        "co2": (
            *d.co2_ppm,
            "a mole fraction, at most five times the outdoor content (the equations' CO2 "
            "terms are linear corrections)",
        ),
        "wavelength_nm": (*d.wavelength_nm, f"where the {equation} equation's dispersion holds"),
        **_RANGES,
    }
    if unit is not None:
        drift, res = _DEVIATION_RANGES[unit]
        out["drift"] = (
            -drift,
            drift,
            "a machine that moves by more than 1 mm (0.1° on a rotary axis) over one test is "
            "not thermally stable enough to be tested",
        )
        out["resolution"] = (
            0.0,
            res,
            "a reading coarser than 0.1 mm (0.01°) does not resolve a positioning test",
        )
    return out


def _check_range(name: str, d: Any, rng: tuple[float, float, str], unit: str) -> None:
    """Refuse a value or a PDF that reaches outside ``rng`` (rule of :data:`OUTSIDE`)."""
    low, high, why = rng
    if not isinstance(d, Distribution):
        lo = hi = float(d)
    else:
        try:
            lo, hi = (float(v) for v in d.ppf(np.array([0.5 * OUTSIDE, 1.0 - 0.5 * OUTSIDE])))
        except DistributionError:
            k = 1.0 / math.sqrt(OUTSIDE)
            lo, hi = float(d.mean) - k * float(d.std), float(d.mean) + k * float(d.std)
    if low <= lo and hi <= high:
        return
    span = f"{low:g} to {high:g} {unit}".rstrip()
    if lo == hi:
        msg = f"{name} = {lo:g} {unit} is outside its physical range {span} ({why})"
    else:
        msg = (
            f"{name} = {d} reaches outside its physical range {span} ({why}): its central "
            f"{100 * (1 - OUTSIDE):.4f} % lies in [{lo:.6g}, {hi:.6g}] {unit}; give a PDF "
            "whose central interval lies inside the range (near a limit, a bounded one: "
            "uniform, triangular, trapezoidal)"
        )
    raise InputError(msg, field=name)


def _printed(unit: str) -> str:
    """A deviation unit as printed (``um`` → ``µm``)."""
    return {"um": "µm", "urad": "µrad"}.get(unit, unit)


def _dist(value: Any, name: str) -> Distribution | None:
    if value is None:
        return None
    d = as_distribution(value, field=name)
    if d.dim != 0:
        raise InputError(f"expected a scalar distribution or number, got {d}", field=name)
    return d


@dataclass(frozen=True)
class UncertaintyModel:
    """The influences on a positioning test, each a PDF (JCGM 101 §6.4) or None (left out).

    Every field takes a :class:`~mtmc.uncertainty.Distribution`, a number (a constant)
    or a distribution's text (``"normal(20.4, 0.1)"``), in the unit its name says.

    Parameters
    ----------
    air_temperature, air_pressure, humidity : optional
        The air along the beam: °C, hPa, % relative humidity. Their expectations are the
        values the laser compensated with; their PDFs say how far the true air may be
        from them (the sensors' uncertainty). Given together, or not at all.
    co2 : default 400
        CO₂ content of the air, µmol/mol.
    equation : {"ciddor", "nist-edlen", "birch-downs", "bonsch-potulski"}, default "ciddor"
        The refractive-index equation (:func:`mtmc.positioning.edlen.refractive_index`).
    equation_error : optional
        The equation's own error, as a relative error of ``n``, ppm.
    wavelength_nm : float
        The laser's vacuum wavelength, nm.
    wavelength_error : optional
        Relative error of the vacuum wavelength, ppm.
    material_temperature, expansion : optional
        Temperature of the axis (its scale), °C, and its expansion coefficient, ppm/K;
        given together.
    material_compensated : bool, default True
        Whether the readings are already corrected to 20 °C with the expectations of
        ``material_temperature`` and ``expansion`` (the laser's automatic correction):
        then only their uncertainty remains; if False the correction itself is applied.
    misalignment : optional
        Angle between the beam and the axis, µrad (cosine error).
    dead_path_mm : float, default 0
        Distance from the interferometer to the reflector at the datum, mm.
    air_temperature_change, air_pressure_change : optional
        How much the air temperature (°C) and pressure (hPa) change over the test; with
        ``dead_path_mm`` they give the dead-path error.
    drift : optional
        Thermal drift of the machine over the test, in the deviation unit (linear in
        time over the standard test cycle).
    resolution : float, default 0
        Resolution of the readings, in the deviation unit (each reading ``±r/2``).
    datum_mm : float, optional
        Where the laser was zeroed, in the target unit (default: the first target).
    type_a : {"means", "means-and-s", "none"}, default "means"
        How the axis' own scatter enters (module docstring).

    Raises
    ------
    InputError
        On a field that does not parse, air or material given in part, an unknown
        equation or ``type_a``, a negative dead path or resolution, a value or a PDF
        that reaches outside its input's physical range (:func:`physical_ranges`, the
        rule of :data:`OUTSIDE`).
    """

    air_temperature: Any = None
    air_pressure: Any = None
    humidity: Any = None
    co2: Any = 400.0
    equation: str = DEFAULT_EQUATION
    equation_error: Any = None
    wavelength_nm: float = HENE_WAVELENGTH_NM
    wavelength_error: Any = None
    material_temperature: Any = None
    expansion: Any = None
    material_compensated: bool = True
    misalignment: Any = None
    dead_path_mm: float = 0.0
    air_temperature_change: Any = None
    air_pressure_change: Any = None
    drift: Any = None
    resolution: float = 0.0
    datum_mm: float | None = None
    type_a: str = "means"

    def __post_init__(self) -> None:
        for name in (
            "air_temperature",
            "air_pressure",
            "humidity",
            "co2",
            "equation_error",
            "wavelength_error",
            "material_temperature",
            "expansion",
            "misalignment",
            "air_temperature_change",
            "air_pressure_change",
            "drift",
        ):
            object.__setattr__(self, name, _dist(getattr(self, name), name))
        air = [self.air_temperature, self.air_pressure, self.humidity]
        if any(a is not None for a in air) and not all(a is not None for a in air):
            raise InputError(
                "expected air_temperature, air_pressure and humidity together",
                field="air_temperature",
            )
        if (self.material_temperature is None) != (self.expansion is None):
            raise InputError(
                "expected material_temperature and expansion together",
                field="material_temperature",
            )
        if self.equation not in EQUATIONS:
            raise InputError(
                f"expected an equation among {', '.join(EQUATIONS)}, got {self.equation!r}",
                field="equation",
            )
        if self.type_a not in TYPE_A:
            raise InputError(
                f"expected type_a among {', '.join(TYPE_A)}, got {self.type_a!r}",
                field="type_a",
            )
        for name in ("dead_path_mm", "resolution"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v >= 0):
                raise InputError(f"expected a finite number >= 0, got {v!r}", field=name)
            object.__setattr__(self, name, v)
        ranges = physical_ranges(self.equation)
        for name, unit in (*INPUT_UNITS.items(), ("dead_path_mm", "mm"), ("wavelength_nm", "nm")):
            d = getattr(self, name)
            if d is not None:
                _check_range(name, d, ranges[name], unit)
        if self.dead_path_mm > 0 and self.air_temperature is None:
            raise InputError(
                "a dead path needs the air (air_temperature, air_pressure, humidity)",
                field="dead_path_mm",
            )

    @property
    def air(self) -> bool:
        """Whether the refractive index of the air is modelled."""
        return self.air_temperature is not None


def _mean(d: Distribution | None) -> float:
    return 0.0 if d is None else float(d.mean)


@dataclass(frozen=True, eq=False)
class _Model:
    """The vectorised model of the corrected parameters; built by :func:`positioning_model`.

    Complex-safe by construction (every operation is analytic, ``|x|`` and the extremes
    are taken on the real part; :mod:`mtmc.positioning.parameters`): the GUM uses its
    complex-step derivative as is (``complex_safe``), without the check against central
    differences, whose rounding noise on a sensitivity of exactly zero would reject it.
    """

    complex_safe: ClassVar[bool] = True
    test: PositioningTest
    model: UncertaintyModel
    names_a: tuple[str, ...]
    names_s: tuple[str, ...]

    def __call__(self, **x: Any) -> Any:
        """``(M, 12)`` parameters in the order of :data:`SYMBOLS` from the inputs ``(M,)``."""
        return axis_parameters(*self.statistics(**x)).stacked()

    def statistics(self, **x: Any) -> tuple[Any, Any]:
        """The means and standard deviations ``(M, m, 2)`` from the corrected readings."""
        t, mo = self.test, self.model
        dev = t.deviations
        first = next(iter(x.values()))
        trials = np.shape(first)[0]
        corr: Any = np.zeros((trials, *dev.shape))
        tau = reading_times(t.m, t.n)
        if not t.rotary:
            c = _PER_MM[t.unit]
            datum = float(t.targets[0]) if mo.datum_mm is None else float(mo.datum_mm)
            length = (t.targets - datum)[:, None, None]  # (m, 1, 1) mm
            factor: Any = np.zeros(trials)
            if mo.air:
                n_comp = refractive_index(
                    _mean(mo.air_temperature),
                    100.0 * _mean(mo.air_pressure),
                    _mean(mo.humidity),
                    co2=_mean(mo.co2),
                    wavelength_nm=mo.wavelength_nm,
                    equation=mo.equation,
                )
                n_air = self._index(x, 0.0, 0.0)
                factor = n_comp / n_air
            else:
                factor = factor + 1.0
            if "wavelength_error" in x:
                factor = factor * (1.0 + 1e-6 * x["wavelength_error"])
            if "misalignment" in x:
                factor = factor / np.cos(1e-6 * x["misalignment"])
            indicated = length + dev / c  # (m, n, 2) mm
            corr = corr + c * indicated * (factor - 1.0)[:, None, None, None]
            if "expansion" in x:
                alpha, tm = 1e-6 * x["expansion"], x["material_temperature"]
                thermal = alpha * (tm - 20.0)
                if mo.material_compensated:
                    thermal = thermal - 1e-6 * _mean(mo.expansion) * (
                        _mean(mo.material_temperature) - 20.0
                    )
                corr = corr - c * length * thermal[:, None, None, None]
            if mo.dead_path_mm > 0:
                n0 = self._index(x, 0.0, 0.0)
                dt = x.get("air_temperature_change", 0.0)
                dp = x.get("air_pressure_change", 0.0)
                dn = (self._index(x, dt, dp) - n0) / n0
                corr = corr - c * mo.dead_path_mm * dn[:, None, None, None] * tau
        if "drift" in x:
            corr = corr - x["drift"][:, None, None, None] * tau
        if "resolution" in x:
            corr = corr + x["resolution"].reshape(trials, *dev.shape)
        mean, s = statistics(dev + corr)
        if self.names_a:
            tt = np.stack([x[k] for k in self.names_a], axis=-1).reshape(trials, 2, t.m)
            mean = mean + s / math.sqrt(t.n) * np.swapaxes(tt, 1, 2)
        if self.names_s:
            g = np.stack([x[k] for k in self.names_s], axis=-1).reshape(trials, 2, t.m)
            s = s / np.sqrt(np.swapaxes(g, 1, 2))
        return mean, s

    def _index(self, x: Mapping[str, Any], dt: Any, dp: Any) -> Any:
        mo = self.model
        n = refractive_index(
            x["air_temperature"] + dt,
            100.0 * (x["air_pressure"] + dp),
            x["humidity"],
            co2=x["co2"],
            wavelength_nm=mo.wavelength_nm,
            equation=mo.equation,
        )
        if "equation_error" in x:
            n = n * (1.0 + 1e-6 * x["equation_error"])
        return n


def positioning_model(
    test: PositioningTest, model: UncertaintyModel
) -> tuple[Any, dict[str, Distribution]]:
    """The model function and its named inputs, for Monte Carlo and the GUM.

    Parameters
    ----------
    test : PositioningTest
        The readings.
    model : UncertaintyModel
        The influences.

    Returns
    -------
    model : callable
        ``model(**inputs)`` → ``(M, 12)``: the parameters in the order of :data:`SYMBOLS`,
        in ``test.unit``.
    inputs : dict of str to Distribution
        ``air_temperature``, ``air_pressure``, ``humidity``, ``co2``, ``equation_error``,
        ``wavelength_error``, ``material_temperature``, ``expansion``, ``misalignment``,
        ``air_temperature_change``, ``air_pressure_change``, ``drift`` (those the model
        gives), ``resolution`` (``2 m n`` readings, rectangular ``±r/2``), and the Type A
        inputs ``typeA_up[i]``, ``typeA_down[i]`` (t with ``n - 1`` degrees of freedom)
        and ``chi2_up[i]``, ``chi2_down[i]`` (``χ²_ν/ν``, ``type_a = "means-and-s"``),
        ``i = 1 … m`` the target's number.

    Raises
    ------
    InputError
        A drift or resolution outside its physical range (:func:`check_deviation_ranges`);
        a length influence (air, material, alignment, dead path) given for a rotary axis;
        Type A inputs with fewer than 3 runs (a t PDF with ``ν ≤ 2`` has no variance); a
        model without any uncertain input.
    """
    inputs: dict[str, Distribution] = {}
    _check_rotary(test, model)
    check_deviation_ranges(test, model)
    for name in (
        "air_temperature",
        "air_pressure",
        "humidity",
        "equation_error",
        "wavelength_error",
        "material_temperature",
        "expansion",
        "misalignment",
    ):
        d = getattr(model, name)
        if d is not None:
            inputs[name] = d
    if model.air:
        inputs["co2"] = model.co2
    if model.dead_path_mm > 0:
        for name in ("air_temperature_change", "air_pressure_change"):
            d = getattr(model, name)
            if d is not None:
                inputs[name] = d
    if model.drift is not None:
        inputs["drift"] = model.drift
    if model.resolution > 0:
        half = 0.5 * model.resolution
        inputs["resolution"] = IID(Uniform(-half, half), 2 * test.m * test.n)
    names_a, names_s = _type_a_inputs(test, model, inputs)
    if not any(not isinstance(d, Constant) for d in inputs.values()):
        raise InputError(
            "the model has no uncertain input: give at least one influence or type_a",
            field="type_a",
        )
    return _Model(test, model, names_a, names_s), inputs


def check_deviation_ranges(test: PositioningTest, model: UncertaintyModel) -> None:
    """Refuse a drift or a resolution outside its physical range in the test's unit.

    Parameters
    ----------
    test : PositioningTest
    model : UncertaintyModel

    Raises
    ------
    InputError
        Naming ``drift`` or ``resolution``, the range and the reason
        (:func:`physical_ranges`).
    """
    ranges = physical_ranges(model.equation, test.unit)
    unit = _printed(test.unit)
    for name in ("drift", "resolution"):
        d = getattr(model, name)
        if d is not None:
            _check_range(name, d, ranges[name], unit)


def _check_rotary(test: PositioningTest, model: UncertaintyModel) -> None:
    if not test.rotary:
        return
    # (a dead path needs the air, which is among these)
    given = [k for k in _LENGTH_ONLY if getattr(model, k) is not None]
    if given:
        raise InputError(
            f"{given[0]} is an influence on a length: a rotary axis "
            f"({test.target_unit}, {test.unit}) takes only drift, resolution and the "
            "Type A inputs",
            field=given[0],
        )


def _type_a_inputs(
    test: PositioningTest, model: UncertaintyModel, inputs: dict[str, Distribution]
) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Add the Type A inputs to ``inputs``; return the names of the t and χ² ones."""
    names_a: tuple[str, ...] = ()
    names_s: tuple[str, ...] = ()
    if model.type_a != "none":
        if test.n < 3:
            raise InputError(
                f"Type A inputs need at least 3 runs (a t PDF of n - 1 <= 2 degrees of "
                f"freedom has no variance), the test has {test.n}: use type_a = 'none'",
                file=test.source,
                field="type_a",
            )
        nu = test.n - 1
        names_a = tuple(f"typeA_{d}[{i + 1}]" for d in ("up", "down") for i in range(test.m))
        for k in names_a:
            inputs[k] = StudentT(nu)
        if model.type_a == "means-and-s":
            names_s = tuple(f"chi2_{d}[{i + 1}]" for d in ("up", "down") for i in range(test.m))
            for k in names_s:
                inputs[k] = Gamma(0.5 * nu, 2.0 / nu)
    return names_a, names_s


@dataclass(frozen=True)
class PositioningUncertainty:
    """The parameters of a test with their uncertainty by Monte Carlo and by the GUM.

    Attributes
    ----------
    test : PositioningTest
    model : UncertaintyModel
    readings : PositioningParameters
        The parameters from the readings as they are (no correction, no uncertainty).
    mc : MonteCarloResult
        Monte Carlo values of the parameters, ``(M, 12)`` in the order of :data:`SYMBOLS`.
    gum : GumResult
        The GUM of the same model, a vector of 12 components.
    inputs : dict of str to Distribution
        The inputs of the model.
    p : float
        Coverage probability.
    """

    test: PositioningTest
    model: UncertaintyModel
    readings: PositioningParameters
    mc: MonteCarloResult
    gum: GumResult
    inputs: Mapping[str, Distribution] = field(repr=False)
    p: float = 0.95

    def monte_carlo(self, symbol: str) -> MonteCarloResult:
        """The scalar Monte Carlo result of one parameter (``"A"``, ``"E_up"``, ...)."""
        samples = self.mc.samples
        assert samples is not None
        return MonteCarloResult.from_samples(
            samples[:, _index(symbol)], seed=self.mc.seed, trials=self.mc.trials
        )

    def gum_result(self, symbol: str) -> GumResult:
        """The scalar GUM result of one parameter, with its budget."""
        return self.gum.component(_index(symbol))

    def estimate(self, symbol: str) -> float:
        """The estimate of a parameter: its definition applied to the readings.

        The readings are those of the test corrected by the expected corrections of the
        model (the model at the expectations of its inputs, the GUM's point of
        expansion): the readings as they are wherever the model corrects nothing on
        average (every influence centred on the recorded value, the material already
        compensated). The Monte Carlo mean is another number: for a maximum or a range
        over the targets it lies above this one (:func:`disagreement_notes`).
        """
        return float(np.real(self.gum.estimate_vector[_index(symbol)]))


def _index(symbol: str) -> int:
    if symbol not in SYMBOLS:
        raise InputError(
            f"unknown parameter {symbol!r}; expected one of {', '.join(SYMBOLS)}", field="symbol"
        )
    return SYMBOLS.index(symbol)


def block_trials(test: PositioningTest) -> int:
    """Trials per evaluation block: 8192, or fewer for a large test.

    The largest power of two of trials within :data:`BLOCK_READINGS` readings of the
    test (``2 m n`` a trial), where that is fewer than 8192.

    Examples
    --------
    >>> block_trials(PositioningTest(np.arange(11.0), np.zeros((11, 5, 2))))
    8192
    >>> block_trials(PositioningTest(np.arange(1000.0), np.zeros((1000, 500, 2))))
    4
    """
    fit = BLOCK_READINGS // (2 * test.m * test.n)
    return 8192 if fit >= 8192 else 1 << max(0, fit.bit_length() - 1)


def evaluate_uncertainty(
    test: PositioningTest,
    model: UncertaintyModel,
    trials: int | None = 200_000,
    seed: int | None = None,
    *,
    p: float = 0.95,
    progress: Any = None,
    block_size: int | None = None,
    **parallel: Any,
) -> PositioningUncertainty:
    """Monte Carlo and GUM of the parameters of a positioning test (module docstring).

    Parameters
    ----------
    test : PositioningTest
    model : UncertaintyModel
    trials : int or None, default 200 000
        Monte Carlo trials ``M``; None with ``adaptive=True`` in ``parallel``.
    seed : int, optional
        The seed (None: fresh entropy, recorded in the result).
    p : float, default 0.95, keyword-only
        Coverage probability of the GUM's interval.
    progress : callable, optional, keyword-only
        ``progress(done, total)`` after each block.
    block_size : int, optional, keyword-only
        Trials per evaluation (memory: about ``2 m n`` × 8 bytes × a few arrays per
        trial); it does not change a number. Default: 8192, fewer for a large test, so
        that one array of a block holds at most :data:`BLOCK_READINGS` readings.
    **parallel
        ``workers``, ``executor``, ``scheduler`` of :func:`mtmc.uncertainty.monte_carlo`,
        and its ``nan_policy``, ``adaptive``, ``ndig`` and ``kind`` (JCGM 101 §7.9).

    Returns
    -------
    PositioningUncertainty
    """
    fn, inputs = positioning_model(test, model)
    if block_size is None:
        block_size = block_trials(test)
    mc = monte_carlo(
        fn,
        inputs,
        trials,
        seed,
        p=p,
        block_size=block_size,
        progress=progress,
        keep=True,
        **parallel,
    )
    g = gum(fn, inputs, p=p)
    return PositioningUncertainty(
        test=test,
        model=model,
        readings=evaluate(test),
        mc=mc,
        gum=g,
        inputs=inputs,
        p=p,
    )


def _extrema(params: PositioningParameters, symbol: str) -> tuple[Any, Any]:
    """The candidates over the targets of a maximum and of a minimum, with labels."""
    up, down = params.mean_up, params.mean_down
    hi = (up + 2 * params.s_up, down + 2 * params.s_down)
    lo = (up - 2 * params.s_up, down - 2 * params.s_down)
    both: dict[str, tuple[Any, Any]] = {
        "A": (hi, lo),
        "A_up": ((hi[0], None), (lo[0], None)),
        "A_down": ((None, hi[1]), (None, lo[1])),
        "E": ((up, down), (up, down)),
        "E_up": ((up, None), (up, None)),
        "E_down": ((None, down), (None, down)),
        "M": ((params.mean, None), (params.mean, None)),
        "R": ((params.R_i, None), None),
        "R_up": ((params.R_i_up, None), None),
        "R_down": ((None, params.R_i_down), None),
        "B": ((np.abs(params.reversal), None), None),
    }
    return both[symbol]


def _near_tie(
    test: PositioningTest, cands: Any, sign: float, width: float, unit: str
) -> str | None:
    """A text naming the runner-up within ``width`` of the extremum, or None."""
    vals: list[tuple[float, str]] = []
    for d, arr in enumerate(cands):
        if arr is None:
            continue
        arrow = "" if len([a for a in cands if a is not None]) == 1 else (" ↑", " ↓")[d]
        for i, v in enumerate(np.asarray(arr, dtype=np.float64)):
            vals.append((sign * float(v), f"P = {test.targets[i]:g} {test.target_unit}{arrow}"))
    vals.sort(key=lambda e: -e[0])  # at least two: m >= 2 targets
    gap = vals[0][0] - vals[1][0]
    if gap >= width:
        return None
    return (
        f"the {'maximum' if sign > 0 else 'minimum'} is reached at {vals[0][1]} and "
        f"{vals[1][1]} comes within {gap:.3g} {unit} of it"
    )


def disagreement_notes(result: PositioningUncertainty, validated: Mapping[str, bool]) -> list[str]:
    """Why the GUM and the Monte Carlo disagree, for each parameter the GUM fails on.

    Parameters
    ----------
    result : PositioningUncertainty
    validated : mapping of str to bool
        Whether the GUM of each parameter is validated by JCGM 101 §8.

    Returns
    -------
    list of str
        One sentence per parameter not validated (none if all are), and one on the
        cosine error where the model has a misalignment (the GUM gives it no
        contribution).
    """
    notes: list[str] = []
    test = result.test
    unit = _printed(test.unit)
    params = _gum_statistics(result)
    for sym in SYMBOLS:
        if validated.get(sym, True):
            continue
        g = result.gum_result(sym)
        mc = result.monte_carlo(sym)
        shift = mc.estimate - g.estimate
        base = (
            f"{sym}: the GUM is not validated by the Monte Carlo (JCGM 101 §8); the Monte "
            f"Carlo mean lies {shift:+.3g} {unit} from the GUM's estimate"
        )
        if sym == "B_mean":
            nu = test.n - 1
            ratio = math.sqrt(nu / (nu - 2)) if nu > 2 else math.inf
            notes.append(
                base + f". B_mean is linear in the means; its Type A inputs are t PDFs of "
                f"ν = n - 1 = {nu} degrees of freedom, each with a standard deviation "
                f"{ratio:.3g} times the s/√n the GUM takes as u (JCGM 101 §6.4.9): averaged "
                f"over {2 * test.m} of them, the GUM's ν_eff is large and its k near 2, while "
                "the Monte Carlo keeps their heavier spread (and, with type_a = "
                "'means-and-s', the skewed PDF of σ). The Monte Carlo interval is the one "
                "to use."
            )
            continue
        width = 2.0 * float(g.u)
        upper, lower = _extrema(params, sym)
        ties = [t for t in (_near_tie(test, upper, 1.0, width, unit),) if t]
        if lower is not None:
            ties += [t for t in (_near_tie(test, lower, -1.0, width, unit),) if t]
        why = (
            f". {sym} is a maximum (or a range) over the targets: the GUM linearises it at "
            "the targets where the extremes are reached at the estimates, while the Monte "
            "Carlo takes the extreme of each trial, so its PDF is shifted and skewed"
        )
        if ties:
            why += " (here " + "; ".join(ties) + f", less than 2u = {width:.3g} {unit})"
        notes.append(base + why + ". The Monte Carlo interval is the one to use.")
    if result.model.misalignment is not None and not test.rotary:
        notes.append(
            "misalignment: the cosine error L(1/cos θ - 1) is of second order in θ, so its "
            "GUM sensitivity at θ = 0 is zero and the GUM gives it no share of the budget; "
            "the Monte Carlo carries its mean L⟨θ²⟩/2 and spread."
        )
    return notes


#: What each parameter is a function of: the means ``x̄_i`` (``"means"``), the standard
#: deviations ``s_i`` (``"s"``) or both (module :mod:`mtmc.positioning.parameters`).
DEPENDS: Mapping[str, tuple[str, ...]] = {
    "A": ("means", "s"),
    "A_up": ("means", "s"),
    "A_down": ("means", "s"),
    "E": ("means",),
    "E_up": ("means",),
    "E_down": ("means",),
    "M": ("means",),
    "R": ("means", "s"),
    "R_up": ("s",),
    "R_down": ("s",),
    "B": ("means",),
    "B_mean": ("means",),
}


def _is_type_a(name: str) -> bool:
    return name.startswith(("typeA_", "chi2_"))


def coverage(result: PositioningUncertainty) -> tuple[str, dict[str, str]]:
    """What the U of each parameter covers: one line for the test, one phrase per parameter.

    Three contributions can enter: the instrument and environment (every input of the
    model that is not a Type A input), the scatter of the means (``type_a = "means"`` or
    ``"means-and-s"``) and the scatter of the standard deviations (``"means-and-s"``).
    A parameter covers those it is a function of (:data:`DEPENDS`); one whose Monte
    Carlo values do not move at all has no U: it is "not evaluated", with the reason.

    Parameters
    ----------
    result : PositioningUncertainty

    Returns
    -------
    line : str
        ``"U covers: …"``, the contributions in the model and those left out.
    parameters : dict of str to str
        By symbol: the contributions its U covers (``"instrument and environment +
        scatter of the means"``), or ``"not evaluated: <reason>"``.
    """
    ta = result.model.type_a
    inst = [k for k in result.inputs if not _is_type_a(k)]
    nu = result.test.n - 1
    parts = [
        f"instrument and environment ({', '.join(inst)})"
        if inst
        else "instrument and environment not evaluated (no input of the instrument or the "
        "environment given)",
        f"+ scatter of the means (Type A, t with ν = {nu})"
        if ta != "none"
        else "scatter of the means not evaluated (type_a = 'none')",
        f"+ scatter of s (Type A, χ² with ν = {nu})"
        if ta == "means-and-s"
        else f"scatter of s not evaluated (type_a = '{ta}')",
    ]
    line = "U covers: " + "; ".join(parts)
    present = {"means": ta != "none", "s": ta == "means-and-s"}
    samples = result.mc.samples
    assert samples is not None
    # a spread within the rounding of the arithmetic (a few ulp of the values) is none
    spread = np.ptp(samples, axis=0)
    spread[spread <= 64 * np.finfo(float).eps * np.max(np.abs(samples), axis=0)] = 0.0
    per: dict[str, str] = {}
    for sym in SYMBOLS:
        deps = DEPENDS[sym]
        covered = (["instrument and environment"] if inst else []) + [
            {"means": "scatter of the means", "s": "scatter of s"}[d] for d in deps if present[d]
        ]
        if spread[_index(sym)] > 0:
            per[sym] = " + ".join(covered)
            lo, hi = result.monte_carlo(sym).coverage_interval(result.p)
            if hi - lo == 0:  # moved in too few trials to widen the interval at p
                col = samples[:, _index(sym)]
                moved = float(np.mean(col != np.median(col)))
                per[sym] += (
                    f" (U = 0: they move {sym} in {100 * moved:.2g} % of the trials only, "
                    f"fewer than 1 - p, so its interval at p = {result.p:g} is one value)"
                )
            continue
        missing = [d for d in deps if not present[d]]
        what = {"means": "the means x̄_i", "s": "the standard deviations s_i"}
        if missing == ["s"] and deps == ("s",):
            why = (
                f"{sym} is a function of the standard deviations s_i alone, whose scatter "
                "enters with type_a = 'means-and-s'"
            )
        elif missing == ["s"]:
            why = (
                f"in every trial {sym} is reached where it is a function of the standard "
                "deviations s_i alone, whose scatter enters with type_a = 'means-and-s'"
            )
        elif missing:
            why = (
                f"{sym} is a function of {' and '.join(what[d] for d in deps)}, whose "
                "scatter the model leaves out (type_a = 'none')"
            )
        else:
            why = f"no input of the model moves {sym}: every trial gives one value"
        if not inst:
            why += ", and no instrument or environment input is given"
        per[sym] = f"not evaluated: {why}"
    return line, per


def _gum_statistics(result: PositioningUncertainty) -> PositioningParameters:
    """The per-target statistics at the input estimates (the GUM's point of expansion)."""
    fn, inputs = positioning_model(result.test, result.model)
    assert isinstance(fn, _Model)
    x = {
        k: np.asarray(d.mean, dtype=np.float64).reshape(1, -1 if d.dim else 1)
        for k, d in inputs.items()
    }
    x = {k: (v if inputs[k].dim else v[:, 0]) for k, v in x.items()}
    mean, s = fn.statistics(**x)
    return axis_parameters(mean[0].real, s[0].real)
