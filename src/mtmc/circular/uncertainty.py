"""The uncertainty of a circular test: one vectorised model, by Monte Carlo and by the GUM.

The measurand is each ISO 230-4 parameter of the machine's path
(:mod:`~mtmc.circular.parameters`) and each error the first-order model identifies
(:mod:`~mtmc.circular.model`). The reading of each point ``i`` of the test is::

    ΔR_i = Σ_j A_ij β_j                     the machine and the set-up (a simulated test)
         or ΔR_i,measured                   (a measured trace)
         - δL - α (t - 20 °C) R             the ballbar's length: its calibration error,
                                            its expansion at the bar's temperature t
         + ε_i + ρ_i                        noise of each reading, rounding to the
                                            resolution r (rectangular, ±r/2)

with ``A`` the design of :func:`~mtmc.circular.model.design` over the errors given as
PDFs (a simulated test: every error of the machine, the axes and the set-up, in the
model's terms), ``ε_i`` normal of the noise given (for a measured trace: the residual
scatter of its identification, a Type A evaluation of the points' repeatability), and
``ρ_i`` the resolution. From the readings the parameters follow from their definitions
and the errors from the least-squares identification, so each trial is one whole test.

:func:`evaluate_uncertainty` runs this one model through the engine's Monte Carlo
(:func:`mtmc.uncertainty.monte_carlo`, trials in blocks, no loop of its own) and its
GUM (:func:`mtmc.uncertainty.gum`, central differences: the model is not analytic), and
validates the GUM for each output by JCGM 101 §8. The identified errors are linear in
the inputs, so there the two agree; ``G``, ``H`` and ``F`` are extremes over the points,
where the GUM linearises at the maximising point and misses that the maximum of noisy
points lies above the maximum of their means (the same argument as for ISO 230-2's A,
E, R): there the Monte Carlo result stands and the validation says it does not.
Conformity of any output is decided by the engine's one rule,
:func:`mtmc.uncertainty.conformity`, on :meth:`CircularUncertainty.monte_carlo`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.circular.model import CircularDesign, structural_notes
from mtmc.circular.parameters import SYMBOLS, circular_parameters
from mtmc.errors import InputError
from mtmc.uncertainty import (
    IID,
    Distribution,
    GumResult,
    MonteCarloResult,
    Normal,
    Uniform,
    Validation,
    as_distribution,
    gum,
    monte_carlo,
    validate,
)

__all__ = [
    "Ballbar",
    "CircularModel",
    "CircularUncertainty",
    "circular_model",
    "evaluate_uncertainty",
    "evaluate_trace",
]

_F = NDArray[np.float64]


class WholeTestModel(Protocol):
    """What :func:`evaluate_uncertainty` takes: a circular or a rotary-axis test's model."""

    outputs: tuple[str, ...]
    notes: tuple[str, ...]
    complex_safe: bool

    def __call__(self, **x: Any) -> _F: ...


@dataclass(frozen=True)
class Ballbar:
    """The instrument of a circular test.

    Attributes
    ----------
    length_error : Distribution or float
        ``δL``, the error of the bar's calibrated length, mm (its calibration's PDF).
    alpha : Distribution or float
        Expansion coefficient of the bar, 1/K.
    temperature : Distribution or float
        The bar's temperature during the test, °C (its reading uncorrected for expansion).
    resolution : float
        ``r``, mm (0 for none).
    noise : float
        Standard deviation of each reading, mm (0 for none).
    """

    length_error: Any = 0.0
    alpha: Any = 0.0
    temperature: Any = 20.0
    resolution: float = 0.0
    noise: float = 0.0

    def __post_init__(self) -> None:
        for name in ("resolution", "noise"):
            v = float(getattr(self, name))
            if not (np.isfinite(v) and v >= 0):
                raise InputError(f"expected a number >= 0, got {v!r}", field=name)
            object.__setattr__(self, name, v)

    def inputs(self, n: int) -> dict[str, Distribution]:
        """The bar's inputs to a test of ``n`` readings, by the names the models read.

        ``length_error``, ``alpha`` and ``temperature``; ``noise`` and ``resolution`` (one
        draw a reading) where given.
        """
        out = {
            key: as_distribution(getattr(self, key), field=f"ballbar.{key}")
            for key in ("length_error", "alpha", "temperature")
        }
        if self.noise > 0:
            out["noise"] = IID(Normal(0.0, self.noise), n)
        if self.resolution > 0:
            half = 0.5 * self.resolution
            out["resolution"] = IID(Uniform(-half, half), n)
        return out


class CircularModel:
    """The vectorised model of a whole test (module docstring): ``model(**inputs) -> (m, d)``.

    Attributes
    ----------
    outputs : tuple of str
        The names of the output columns: the parameters of :data:`SYMBOLS` the test has
        (``H`` and ``G_b`` with both directions), then the identified errors.
    complex_safe : bool
        False: the GUM uses central differences (extremes and signs are not analytic).
    """

    complex_safe = False

    def __init__(
        self,
        identify_with: CircularDesign,
        simulate_with: CircularDesign | None,
        measured: _F | None,
        error_names: tuple[str, ...],
    ) -> None:
        self.design = identify_with
        self.truth = simulate_with
        self.measured = measured
        self.error_names = error_names
        d = identify_with.direction
        self._ccw = np.nonzero(d > 0)[0]
        self._cw = np.nonzero(d < 0)[0]
        self._pinv_t = np.ascontiguousarray(np.linalg.pinv(identify_with.matrix).T)
        syms = [s for s in SYMBOLS if s not in ("H", "G_b") or (self._ccw.size and self._cw.size)]
        self.symbols = tuple(syms)
        self.outputs = (*self.symbols, *identify_with.names)
        self.notes = structural_notes(identify_with.plane, len(identify_with.directions))

    def readings(self, **x: Any) -> _F:
        """The readings ``ΔR`` (m, N) of the trials of ``x``."""
        m = int(np.shape(next(iter(x.values())))[0])
        n = self.design.matrix.shape[0]
        if self.truth is not None:
            beta = np.stack([np.asarray(x[k], dtype=np.float64) for k in self.error_names], 1)
            dev = beta @ self.truth.matrix.T
        else:
            assert self.measured is not None
            dev = np.broadcast_to(self.measured, (m, n)).copy()
        length = np.asarray(x["length_error"], dtype=np.float64)
        expansion = np.asarray(x["alpha"], dtype=np.float64) * (
            np.asarray(x["temperature"], dtype=np.float64) - 20.0
        )
        dev -= (length + expansion * self.design.radius)[:, None]
        for key in ("noise", "resolution"):
            if key in x:
                dev += np.asarray(x[key], dtype=np.float64)
        return dev

    def __call__(self, **x: Any) -> _F:
        """The outputs ``(m, d)`` of the trials of ``x``, in the order of :attr:`outputs`."""
        for v in x.values():
            if np.iscomplexobj(v):
                raise TypeError("the circular model takes real inputs only")
        dev = self.readings(**x)
        t = self.design.theta
        kw: dict[str, Any] = {}
        if self._ccw.size:
            kw |= {"theta_ccw": t[self._ccw], "ccw": dev[:, self._ccw]}
        if self._cw.size:
            kw |= {"theta_cw": t[self._cw], "cw": dev[:, self._cw]}
        p = circular_parameters(**kw)
        cols = [p[s] for s in self.symbols]
        est = dev @ self._pinv_t
        return np.concatenate([np.stack(cols, axis=1), est], axis=1)


def circular_model(
    identify_with: CircularDesign,
    ballbar: Ballbar,
    *,
    errors: Mapping[str, Any] | None = None,
    simulate_with: CircularDesign | None = None,
    measured: npt.ArrayLike | None = None,
) -> tuple[CircularModel, dict[str, Distribution]]:
    """The model and its inputs, for a simulated test or a measured trace.

    Parameters
    ----------
    identify_with : CircularDesign
        The points of the test and the errors identified.
    ballbar : Ballbar
    errors : mapping of str to Distribution or number, optional
        A simulated test: the errors by the names of ``simulate_with`` (default
        ``identify_with``), the machine's, the axes' and the set-up's, in the model's terms.
    simulate_with : CircularDesign, optional
        The design that makes the readings (its points must be those of ``identify_with``).
    measured : array_like (N,), optional
        A measured trace instead (both paths, CCW first, as ``identify_with``), mm.

    Returns
    -------
    model : CircularModel
    inputs : dict of str to Distribution
    """
    n = identify_with.matrix.shape[0]
    inputs: dict[str, Distribution] = {}
    names: tuple[str, ...] = ()
    meas = None
    truth = None
    if (errors is None) == (measured is None):
        raise InputError(
            "expected either errors (a simulated test) or a measured trace", field="errors"
        )
    if errors is not None:
        truth = simulate_with or identify_with
        if truth.matrix.shape[0] != n or not np.array_equal(truth.theta, identify_with.theta):
            raise InputError("the two designs must share their points", field="simulate_with")
        unknown = [k for k in errors if k not in truth.names]
        if unknown:
            raise InputError(
                f"unknown error {unknown[0]!r}; the model has {', '.join(truth.names)}",
                field=f"errors.{unknown[0]}",
            )
        names = tuple(k for k in truth.names if k in errors)
        truth = _restrict(truth, names)
        for k in names:
            inputs[k] = as_distribution(errors[k], field=f"errors.{k}")
    else:
        meas = np.asarray(measured, dtype=np.float64).reshape(-1)
        if meas.size != n or not np.all(np.isfinite(meas)):
            raise InputError(f"expected {n} finite readings", field="measured")
    inputs |= ballbar.inputs(n)
    return CircularModel(identify_with, truth, meas, names), inputs


def _restrict(des: CircularDesign, names: tuple[str, ...]) -> CircularDesign:
    idx = [des.names.index(k) for k in names]
    return CircularDesign(
        plane=des.plane,
        terms=tuple(des.terms[i] for i in idx),
        names=names,
        units=tuple(des.units[i] for i in idx),
        theta=des.theta,
        direction=des.direction,
        matrix=des.matrix[:, idx],
        radius=des.radius,
        feed=des.feed,
    )


@dataclass(frozen=True)
class CircularUncertainty:
    """Every output of a test with its uncertainty by Monte Carlo and by the GUM.

    Attributes
    ----------
    outputs : tuple of str
    mc : MonteCarloResult
        ``(M, d)`` over :attr:`outputs` (samples kept).
    gum : GumResult
        The same model by the GUM, ``d`` components.
    validation : dict of str to Validation
        JCGM 101 §8 of each output.
    notes : tuple of str
        What the test cannot separate (:func:`~mtmc.circular.model.structural_notes`).
    """

    outputs: tuple[str, ...]
    mc: MonteCarloResult = field(repr=False)
    gum: GumResult = field(repr=False)
    validation: Mapping[str, Validation] = field(repr=False)
    notes: tuple[str, ...] = ()

    def _index(self, name: str) -> int:
        if name not in self.outputs:
            raise InputError(
                f"unknown output {name!r}; expected one of {', '.join(self.outputs)}",
                field="name",
            )
        return self.outputs.index(name)

    def monte_carlo(self, name: str) -> MonteCarloResult:
        """The scalar Monte Carlo result of one output."""
        return self.mc.component(self._index(name))

    def gum_result(self, name: str) -> GumResult:
        """The scalar GUM result of one output, with its budget."""
        return self.gum.component(self._index(name))


def evaluate_uncertainty(
    model: WholeTestModel,
    inputs: Mapping[str, Distribution],
    trials: int | None = 10_000,
    seed: int | None = None,
    *,
    p: float = 0.95,
    block_size: int = 4096,
    **engine: Any,
) -> CircularUncertainty:
    """Monte Carlo and GUM of a test (module docstring); ``engine`` goes to the engine."""
    mc = monte_carlo(model, inputs, trials, seed, p=p, block_size=block_size, keep=True, **engine)
    g = gum(model, inputs, p=p)
    val = {
        name: validate(g.component(i), mc.component(i), p=p) for i, name in enumerate(model.outputs)
    }
    return CircularUncertainty(model.outputs, mc, g, val, tuple(model.notes))


def _report_unit(unit: str, deviation_unit: str) -> tuple[float, str]:
    """The factor from the model's unit and the reported unit's name (angles in µrad)."""
    if unit == "mm":
        return (1e3, "um") if deviation_unit == "um" else (1.0, "mm")
    if unit == "rad":
        return 1e6, "urad"
    if unit == "s":
        return 1e3, "ms"
    return 1e6, "um/m"


def evaluate_trace(
    theta_ccw: npt.ArrayLike | None,
    ccw: npt.ArrayLike | None,
    theta_cw: npt.ArrayLike | None,
    cw: npt.ArrayLike | None,
    *,
    radius: float,
    feed: float = 1000.0 / 60.0,
    plane: str = "XY",
    ballbar: Ballbar | None = None,
    trials: int | None = 10_000,
    seed: int | None = None,
    p: float = 0.95,
    deviation_unit: str = "um",
    **engine: Any,
) -> dict[str, Any]:
    """Evaluate a measured trace: every parameter and identified error with U.

    The errors of :func:`~mtmc.circular.model.default_terms` are identified; the noise of
    each reading is the ballbar's, or, where it gives none, the residual scatter of the
    identification (a Type A evaluation of the trace's own repeatability). The
    parameters' and errors' estimates are those of the trace (the GUM's, at the input
    estimates); ``U`` is half the Monte Carlo's probabilistically symmetric interval.

    Returns
    -------
    dict
        ``parameters`` and ``errors``: name -> ``estimate``, ``U``, ``U_gum``, ``unit``,
        ``validated`` (JCGM 101 §8), ``mc_mean``; ``notes`` (what the test cannot
        separate), ``identifiability``, ``rms`` (mm) and ``result`` (the
        :class:`CircularUncertainty`).
    """
    from mtmc.circular.model import design as make_design
    from mtmc.circular.model import identify

    des = make_design(radius=radius, theta_ccw=theta_ccw, theta_cw=theta_cw, plane=plane, feed=feed)
    meas = np.concatenate(
        [np.asarray(x, dtype=np.float64).reshape(-1) for x in (ccw, cw) if x is not None]
    )
    ident = identify(des, meas)
    bar = ballbar or Ballbar()
    if bar.noise == 0:
        bar = Ballbar(
            bar.length_error, bar.alpha, bar.temperature, bar.resolution, float(ident.rms[0])
        )
    model, inputs = circular_model(des, bar, measured=meas)
    res = evaluate_uncertainty(model, inputs, trials, seed, p=p, **engine)
    units = dict(zip(des.names, des.units, strict=True))
    out: dict[str, Any] = {"parameters": {}, "errors": {}}
    for name in res.outputs:
        mc, g = res.monte_carlo(name), res.gum_result(name)
        lo, hi = mc.coverage_interval(p)
        f, unit = _report_unit(units.get(name, "mm"), deviation_unit)
        entry = {
            "estimate": g.estimate * f,
            "U": 0.5 * (hi - lo) * f,
            "U_gum": g.expanded_uncertainty(p) * f,
            "unit": unit,
            "validated": res.validation[name].passed,
            "mc_mean": mc.estimate * f,
        }
        out["errors" if name in units else "parameters"][name] = entry
    out["notes"] = list(res.notes)
    out["identifiability"] = ident.identifiability.text()
    out["rms"] = float(ident.rms[0])
    out["result"] = res
    return out
