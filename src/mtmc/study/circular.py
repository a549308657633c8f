"""Study kind ``circular``: an ISO 230-4 circular test simulated with its uncertainty.

The file describes the programmed path, the machine's errors and the axes' effects in
the terms of the first-order model ``ΔR = e · n`` (:mod:`mtmc.circular.model`), each a
PDF or a value, and the ballbar::

    kind = "circular"
    title = "XY circle, R 150 mm"

    [path]
    plane = "XY"                 # XY, YZ or ZX
    radius = 150.0               # R, mm
    centre = [0.0, 0.0]          # the circle's centre in axis coordinates, mm
    points = 720                 # points per direction over 360° (the overrun is not evaluated)
    start = 0.0                  # angle of the first point, deg
    feed = 1000.0                # mm/min
    directions = ["ccw", "cw"]
    # spike_decay = 3.0          # φ₀ of the reversal spikes, deg
    # cyclic_period = [5.0, 5.0] # the screws' periods, mm (for cyclic_*)

    [errors]                     # the model's units: mm, rad, 1 (scale), s (servo lag)
    squareness = "normal(20e-6, 2e-6)"
    backlash_x = 0.004
    ...

    [ballbar]
    length_error = "normal(0, 0.0005)"   # δL, mm
    alpha = "normal(1.1e-5, 1e-6)"       # 1/K
    temperature = "uniform(19, 21)"      # °C
    resolution = 0.0001                  # mm
    noise = 0.0003                       # mm

    [identify]                   # optional: the terms identified (default: what one test separates)
    terms = ["radius", "centre_u", "centre_v", "squareness", ...]

    [conformity.G_lsc]           # limits per parameter (JCGM 106), µm
    upper = 20.0

A measured trace is evaluated by the same kind: ``data`` names its CSV file (read by
:func:`mtmc.circular.load_circular_csv`, with ``units``, ``columns`` and ``directions``
as ``mtmc circle evaluate`` has them), ``[path]`` gives ``radius``, ``plane``, ``feed``
and ``overrun`` (the arc before the evaluated turn, deg: :mod:`mtmc.circular.data`),
and there is no ``[errors]``: the model's errors are identified from the trace,
and the noise of each reading is the ballbar's ``noise``, or, where it gives none, the
residual scatter of the identification (a Type A evaluation of the trace)::

    kind = "circular"
    data = "trace.csv"           # angle,direction,deviation per row
    units = "deg,um"
    [path]
    radius = 150.0
    [conformity.G_lsc]
    upper = 20.0

``mtmc circle evaluate DATA`` writes this study and runs it: one route, one result folder
that reruns from itself (the CSV file copied into ``inputs/``).

The run is :func:`mtmc.circular.evaluate_uncertainty` of
:func:`mtmc.circular.circular_model`: each trial one whole test (the readings, the
parameters from their definitions, the identification), the GUM beside it, §8 per
output. The quantities are the parameters ``F_max`` … ``G_b`` and the identified errors,
reported in µm, µrad, µm/m and ms (the code's mm, rad, 1 and s times the exact factor,
docs/results-format.md's unit rule); ``circular`` of ``result.json`` holds the trace at
the inputs' estimates for the report's polar plot.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from mtmc.document import MAX_DEG, MAX_MM, Fields
from mtmc.errors import MtmcError
from mtmc.study.base import ProgressFn, Study
from mtmc.study.conformity import ConformitySpec, assess_quantity, read_output_conformity
from mtmc.study.observations import input_record, read_distribution
from mtmc.study.options import ADAPTIVE, NAN_POLICY, mc_run_record
from mtmc.study.result import Quantity, StudyResult, Table, quantity
from mtmc.study.settings import RunSettings
from mtmc.study.spec import register_kind

__all__ = ["CircularStudy", "REPORT_UNITS", "measured_study_text"]

#: The reported unit and its exact factor, by the unit of a model's term.
REPORT_UNITS: dict[str, tuple[str, float]] = {
    "mm": ("µm", 1e3),
    "rad": ("µrad", 1e6),
    "1": ("µm/m", 1e6),
    "s": ("ms", 1e3),
}

_PAIR = "two finite numbers [a, b]"

#: The largest feed a path takes, mm/min: ten times the 60 m/min rapid of a fast machine.
MAX_FEED = 600_000.0

_PATH_KEYS = (
    "plane",
    "radius",
    "centre",
    "points",
    "start",
    "feed",
    "directions",
    "spike_decay",
    "cyclic_period",
)
_BALLBAR_KEYS = ("length_error", "alpha", "temperature", "resolution", "noise")


@dataclass(frozen=True)
class CircularStudy(Study):
    """A simulated circular test (kind ``circular``).

    Attributes
    ----------
    model : CircularModel
        The vectorised model of one whole test.
    inputs : dict of str to Distribution
        Its inputs: the errors (model units) and the ballbar's.
    conformity : dict of str to ConformitySpec
        Limits per parameter, in µm.
    units : dict of str to str
        The model's unit of each output (``mm``, ``rad``, ``1``, ``s``).
    plot : dict
        ``circular`` of ``result.json`` less its notes: the trace at the inputs'
        estimates, for the report.
    """

    kind = "circular"
    run_options = frozenset({ADAPTIVE, NAN_POLICY})
    model: Any
    inputs: Any
    conformity: Any
    units: Any
    plot: Any

    def execute(self, settings: RunSettings, progress: ProgressFn | None) -> StudyResult:
        """Run the test by Monte Carlo and the GUM and tabulate it (module docstring)."""
        from mtmc.circular import evaluate_uncertainty

        engine = settings.engine
        trials = engine.pop("trials")
        p = engine.pop("p")
        res = evaluate_uncertainty(
            self.model, self.inputs, trials, settings.seed, p=p, progress=progress, **engine
        )
        units = self.units
        quantities: list[Quantity] = []
        samples: dict[str, Any] = {}
        for name in res.outputs:
            label, f = REPORT_UNITS[units.get(name, "mm")]
            mc, g = res.monte_carlo(name), res.gum_result(name)
            q = quantity(name, units.get(name, "mm"), mc, g, settings).in_unit(label, f)
            spec: ConformitySpec | None = self.conformity.get(name)
            if spec is not None:
                # the limits are in µm: the decision on the samples in µm
                q = assess_quantity(q, spec, _scaled(mc, f), None)
            quantities.append(q)
            if settings.samples:
                samples[name] = f * mc.values
        rows = tuple(
            (
                q.name,
                q.unit,
                q.gum.estimate if q.gum else "",
                q.gum.U if q.gum else "",
                q.mc.estimate,
                q.mc.U,
                "" if q.validation is None else q.validation.verdict,
            )
            for q in quantities
        )
        cols = ("quantity", "unit", "GUM y", "GUM U", "MC y", "MC U", "GUM by JCGM 101 §8")
        n_par = len(_parameters(self.model))
        title = "Parameters of ISO 230-4"
        if "rotary" in self.plot:
            title = (
                "Range of the sphere's displacement along x, y, z (R-test)"
                if self.plot["rotary"]["instrument"] == "rtest"
                else "Range of the ballbar's reading"
            )
        tables = (
            Table("parameters", title, cols, rows[:n_par]),
            Table("errors", "Identified errors (first-order model)", cols, rows[n_par:]),
        )
        limits = {k: {"lower": c.lower, "upper": c.upper} for k, c in self.conformity.items()}
        notes = [*res.notes, *_overrun_notes(self.plot.get("overrun", {}))]
        extra = {
            "circular": {
                **self.plot,
                "notes": notes,
                "limits": limits,
                "symbols": list(_parameters(self.model)),
            }
        }
        inputs = [
            input_record(name, d, _INPUT_UNITS.get(name) or units.get(name, "mm"))
            for name, d in self.inputs.items()
        ]
        return self._result(
            settings,
            run=mc_run_record(settings, res.mc),
            quantities=tuple(quantities),
            tables=tables,
            inputs=tuple(inputs),
            extra=extra,
            samples=samples,
        )


_INPUT_UNITS = {"alpha": "1/K", "temperature": "°C", "gain_x": "1", "gain_y": "1", "gain_z": "1"}


def _circles(theta: Any, direction: Any, trace_um: Any) -> dict[str, Any]:
    """The LSC and the MZ circles of each direction's trace, in µm, for the polar plot.

    ``lsc``: ``(c, a, b)`` of :func:`mtmc.circular.parameters.lsc_fit`; ``mz``: the width
    and ``(c, a, b)`` of :func:`mtmc.circular.parameters.minimum_zone`.
    """
    from mtmc.circular.parameters import lsc_fit, minimum_zone

    out: dict[str, Any] = {}
    for d, key in ((1.0, "ccw"), (-1.0, "cw")):
        idx = direction == d
        if not np.any(idx):
            continue
        lsc, _ = lsc_fit(theta[idx], trace_um[idx])
        width, mz = minimum_zone(theta[idx], trace_um[idx])
        out[key] = {"lsc": lsc[0], "mz_width": float(width[0]), "mz": mz[0]}
    return out


def _scaled(mc: Any, f: float) -> Any:
    """The Monte Carlo result of ``f`` times the output (exact factor: a change of unit)."""
    from mtmc.uncertainty.results import MonteCarloResult

    return MonteCarloResult.from_samples(f * mc.values, seed=mc.seed)


def _read(top: Fields) -> tuple[Any, dict[str, Any], Any, dict[str, str], dict[str, Any]]:
    """The model, its inputs and the limits of a ``circular`` study."""
    from mtmc.circular import Ballbar, circular_model
    from mtmc.circular.model import TERMS, default_terms, design

    path = top.table("path")
    assert path is not None
    path.only(_PATH_KEYS)
    plane = path.text("plane", "XY", choices=("XY", "YZ", "ZX"))
    radius = path.number("radius", low=0.0, open_low=True, high=MAX_MM)
    centre = _numbers(path, "centre", _PAIR, 2, (0.0, 0.0))
    n = path.integer("points", 720, minimum=8, maximum=100_000)
    start = np.radians(path.number("start", 0.0, low=-MAX_DEG, high=MAX_DEG))
    feed = path.number("feed", 1000.0, low=0.0, open_low=True, high=MAX_FEED) / 60.0
    dirs = path.texts("directions", ("ccw", "cw"))
    for d in dirs:
        if d not in ("ccw", "cw"):
            raise path.error(f"expected 'ccw' and/or 'cw', got {d!r}", "directions")
    decay = np.radians(path.number("spike_decay", 3.0, low=0.0, open_low=True, high=MAX_DEG))
    period = _numbers(path, "cyclic_period", _PAIR, 2) if path.has("cyclic_period") else None
    theta = start + 2.0 * np.pi * np.arange(n) / n
    angles = {"theta_ccw": theta if "ccw" in dirs else None}
    angles["theta_cw"] = (start - 2.0 * np.pi * np.arange(n) / n) if "cw" in dirs else None
    common: dict[str, Any] = dict(
        radius=radius, plane=plane, feed=feed, spike_decay=decay, centre=centre, **angles
    )
    all_terms = TERMS if period is not None else tuple(t for t in TERMS if "cyclic" not in t)
    truth = design(terms=all_terms, cyclic_period=period, **common)
    ident = top.table("identify", required=False)
    terms = default_terms(len(dirs))
    if ident is not None:
        ident.only(("terms",))
        terms = ident.texts("terms")
    try:
        identify_with = design(terms=terms, cyclic_period=period, **common)
    except MtmcError as exc:
        raise (ident or path).error(exc.message, "terms" if ident else None) from None
    errs = top.table("errors")
    assert errs is not None
    for key in errs.data:
        if key not in truth.names:
            raise errs.error(
                f"unknown error {key!r}; expected some of {', '.join(truth.names)}", key
            )
    errors = {k: read_distribution(errs, k) for k in errs.data}
    model, inputs = circular_model(
        identify_with, Ballbar(**_ballbar(top)), errors=errors, simulate_with=truth
    )
    limits = read_output_conformity(top, model.symbols)
    units = dict(zip(identify_with.names, identify_with.units, strict=True))
    trace = (
        1e3
        * model.readings(
            **{k: np.asarray(d.mean, dtype=np.float64)[None, ...] for k, d in inputs.items()}
        )[0]
    )
    return model, inputs, limits, units, _plot(identify_with, trace)


def _plot(design: Any, trace_um: Any) -> dict[str, Any]:
    """What the report's polar plot of a circular test needs: the path and its trace (µm)."""
    th, d = design.theta, design.direction
    return {
        "plane": design.plane,
        "radius": design.radius,
        "feed": design.feed,
        "theta_deg": np.degrees(th),
        "direction": d,
        "trace_um": trace_um,
        "circles": _circles(th, d, trace_um),
    }


def _ballbar(top: Fields, keys: tuple[str, ...] = _BALLBAR_KEYS) -> dict[str, Any]:
    """The keywords of :class:`mtmc.circular.Ballbar` from ``[ballbar]`` (none: an ideal bar)."""
    bb = top.table("ballbar", required=False)
    kw: dict[str, Any] = {}
    if bb is not None:
        bb.only(keys)
        for key in ("length_error", "alpha", "temperature"):
            if bb.has(key):
                kw[key] = read_distribution(bb, key)
        for key in ("resolution", "noise"):
            kw[key] = bb.number(key, 0.0, low=0.0, high=MAX_MM)
    return kw


def _mapping(top: Fields, key: str) -> dict[str, str] | None:
    """A table of texts (``columns``, ``directions``) or None where absent."""
    t = top.table(key, required=False)
    if t is None:
        return None
    return {k: t.text(k) for k in t.data}


def _load(top: Fields, load: Any) -> Any:
    """The trace of ``data``, read by ``load(file, columns=..., units=...)``.

    An error of the study's own options (``columns``, ``directions``, ``units``,
    ``overrun``) names the study's line; one of the file names the file's.
    """
    try:
        return load(
            top.source.resolve(top.text("data"), ("data",)),
            columns=_mapping(top, "columns"),
            units=top.text("units", "deg,um"),
        )
    except MtmcError as exc:
        key = (exc.field or "").split(".")[0]
        if exc.file is None or key in ("columns", "directions", "units"):  # the study's option
            raise top.source.error(exc.message, tuple((exc.field or "data").split("."))) from None
        raise


def _overrun_notes(overrun: dict[str, int]) -> list[str]:
    """The readings of each direction left out as overrun arcs, in words."""
    return [
        f"{n} readings {d.upper()} outside the evaluated turn: read as the overrun arcs of "
        "ISO 230-4 and left out of the evaluation"
        for d, n in overrun.items()
    ]


def _read_measured(top: Fields) -> tuple[Any, dict[str, Any], Any, dict[str, str], dict[str, Any]]:
    """The model, inputs and limits of a measured trace (``data``; module docstring)."""
    from mtmc.circular import Ballbar, circular_model, identify, load_circular_csv
    from mtmc.circular.model import design

    path = top.table("path")
    assert path is not None
    path.only(("plane", "radius", "feed", "overrun"))
    overrun = path.number("overrun", None, low=0.0, high=360.0, open_high=True)
    trace = _load(
        top,
        lambda f, **o: load_circular_csv(
            f, directions=_mapping(top, "directions"), overrun=overrun, **o
        ),
    )
    des = design(
        radius=path.number("radius", low=0.0, open_low=True, high=MAX_MM),
        theta_ccw=trace.theta_ccw,
        theta_cw=trace.theta_cw,
        plane=path.text("plane", "XY", choices=("XY", "YZ", "ZX")),
        feed=path.number("feed", 1000.0, low=0.0, open_low=True, high=MAX_FEED) / 60.0,
    )
    meas = trace.deviation
    kw = _ballbar(top)
    try:
        ident = identify(des, meas)
    except MtmcError as exc:
        raise top.error(f"{exc.message} ({meas.size} readings in {trace.source})", "data") from None
    if kw.get("noise", 0.0) == 0.0:  # the trace's own scatter about the identified model
        kw["noise"] = float(ident.rms[0])
    model, inputs = circular_model(des, Ballbar(**kw), measured=meas)
    limits = read_output_conformity(top, model.symbols)
    units = dict(zip(des.names, des.units, strict=True))
    plot = _plot(des, 1e3 * meas) | {
        "data": trace.source,
        "identifiability": ident.identifiability.text(),
        "rms_um": 1e3 * float(ident.rms[0]),
        "overrun": dict(trace.overrun),
    }
    return model, inputs, limits, units, plot


def measured_study_text(
    data: str,
    *,
    radius: float,
    plane: str = "XY",
    feed: float = 1000.0,
    overrun: float | None = None,
    units: str = "deg,um",
    columns: dict[str, str] | None = None,
    directions: dict[str, str] | None = None,
    trials: int | None = None,
    seed: int | None = None,
) -> str:
    """The study file of a measured trace (module docstring), as ``circle evaluate`` writes it."""
    import tomlkit

    doc = tomlkit.document()
    doc["kind"] = "circular"
    doc["title"] = f"Circular test (ISO 230-4): {data}"
    doc["data"] = data
    doc["units"] = units
    if columns:
        doc["columns"] = columns
    if directions:
        doc["directions"] = directions
    doc["path"] = {"plane": plane, "radius": float(radius), "feed": float(feed)}
    if overrun is not None:
        doc["path"]["overrun"] = float(overrun)
    run = {k: v for k, v in (("trials", trials), ("seed", seed)) if v is not None}
    if run:
        doc["run"] = run
    return tomlkit.dumps(doc)


def _parameters(model: Any) -> tuple[str, ...]:
    """The outputs of a model that are the test's parameters (the rest: identified errors)."""
    return tuple(model.symbols)


_ROTARY_KEYS = ("machine", "axis", "start", "stop", "steps", "hold", "ball")
_ROTARY_BALLBAR_KEYS = (*_BALLBAR_KEYS, "length", "direction")


def _rotary_instrument(top: Fields) -> tuple[dict[str, Any], str]:
    """The keywords of :func:`mtmc.circular.rotary_model` for ``[rtest]`` or ``[ballbar]``."""
    from mtmc.circular import Ballbar

    rt = top.table("rtest", required=False)
    bb = top.table("ballbar", required=False)
    if rt is not None and bb is not None:
        raise top.error("expected one instrument, [rtest] or [ballbar], got both", "ballbar")
    if bb is not None:
        return {
            "ballbar": Ballbar(**_ballbar(top, _ROTARY_BALLBAR_KEYS)),
            "direction": _numbers(
                bb, "direction", "the bar's direction in the workpiece frame [x, y, z]", 3
            ),
            "length": bb.number("length", low=0.0, open_low=True, high=MAX_MM),
        }, "ballbar"
    out: dict[str, Any] = {"gain": 0.0, "noise": 0.0}
    if rt is not None:
        rt.only(("gain", "noise"))
        if rt.has("gain"):
            out["gain"] = read_distribution(rt, "gain")
        out["noise"] = rt.number("noise", 0.0, low=0.0, high=MAX_MM)
    return out, "rtest"


def _read_rotary(top: Fields) -> tuple[Any, dict[str, Any], Any, dict[str, str], dict[str, Any]]:
    """The model of a rotary-axis test, the linear axes following (``[rotary]``).

    ``[rotary]``: the machine's topology (``wCBXfYZt``), the rotary ``axis`` turned from
    ``start`` to ``stop`` (deg, ``steps`` positions), the other rotary axes held at
    ``hold`` (deg), the sphere at ``ball`` (mm, workpiece frame); ``[errors]`` by their
    ISO 230-1 / 230-7 names (mm, rad); the instrument: ``[rtest]`` with ``gain`` (a PDF of
    each sensor's relative gain error) and ``noise`` (mm), or ``[ballbar]`` with its
    ``length`` (mm) and ``direction`` in the workpiece frame beside the bar's PDFs;
    ``[identify] terms`` the errors identified (default: those the test separates).

    A measured test (``data``) reads the positions and readings from its CSV file
    (:func:`mtmc.circular.load_rotary_csv`; no ``start``, ``stop``, ``steps`` or
    ``[errors]``): the terms identified are ``[identify] terms`` or the axis' location
    errors and the set-up's offset, and the noise, where the instrument gives none, the
    residual scatter of the identification (Type A).
    """
    from mtmc.circular import load_rotary_csv, rotary_model
    from mtmc.kinematics import Machine
    from mtmc.verification.identify import parameter_unit

    measured = top.has("data")
    rot = top.table("rotary")
    assert rot is not None
    rot.only(_ROTARY_KEYS if not measured else ("machine", "axis", "hold", "ball"))
    topo = rot.text("machine")
    try:
        machine = Machine.from_topology(topo)
    except MtmcError as exc:
        raise rot.error(exc.message, "machine") from None
    axis = rot.text("axis", choices=[a for a in machine.axes if a in "ABC"])
    point = _numbers(rot, "ball", "the sphere's centre in mm [x, y, z]", 3)
    kw, instrument = _rotary_instrument(top)
    trace = None
    if measured:
        trace = _load(top, lambda f, **o: load_rotary_csv(f, instrument=instrument, **o))
        angles = trace.angle
    else:
        steps = rot.integer("steps", 36, minimum=4, maximum=100_000)
        angles = np.radians(
            np.linspace(
                rot.number("start", 0.0, low=-MAX_DEG, high=MAX_DEG),
                rot.number("stop", 360.0, low=-MAX_DEG, high=MAX_DEG),
                steps,
                endpoint=False,
            )
        )
    q = _follow(rot, machine, axis, angles, point)
    ident = top.table("identify", required=False)
    terms: tuple[str, ...] | None = None
    if ident is not None:
        ident.only(("terms",))
        terms = tuple(ident.texts("terms"))
    errors: dict[str, Any] | None = None
    if measured:
        names = terms or (
            *(t for t in machine.error_names if t.endswith("0" + axis)),
            "EXP",
            "EYP",
            "EZP",
        )
        where: Fields = ident or rot
    else:
        errs = top.table("errors")
        assert errs is not None
        names = tuple(errs.data)
        errors = {k: read_distribution(errs, k) for k in names}
        where = errs
    try:
        jac = machine.jacobian(q, None, names=list(names))
    except MtmcError as exc:
        raise where.error(exc.message, "terms" if where is ident else None) from None
    if terms is not None:
        for t in terms:
            if t not in names:
                raise ident.error(  # type: ignore[union-attr]
                    f"unknown error {t!r}; expected some of {', '.join(names)}", "terms"
                )
    meas = None if trace is None else trace.readings
    rms = None
    try:
        model, inputs = rotary_model(jac, errors, names=names, identify=terms, measured=meas, **kw)
        if meas is not None:
            rms = model.residual_rms(meas)  # the readings' own scatter (Type A)
        if rms is not None and kw.get("noise", getattr(kw.get("ballbar"), "noise", 0.0)) == 0.0:
            kw = _with_noise(kw, rms)  # the same design: the same residuals
            model, inputs = rotary_model(
                jac, errors, names=names, identify=terms, measured=meas, **kw
            )
    except MtmcError as exc:
        raise (ident or top).error(exc.message, "terms" if ident else None) from None
    limits = read_output_conformity(top, model.symbols)
    units = {k: parameter_unit(machine, k) for k in names}
    plot = _rotary_plot(topo, machine, axis, angles, point, q, kw, instrument, trace, errors)
    plot["identifiability"] = model.identifiability.text()
    if rms is not None:
        plot["rms_um"] = 1e3 * rms
    return model, inputs, limits, units, plot


def _follow(rot: Fields, machine: Any, axis: str, angles: Any, point: Any) -> Any:
    """The axis positions of the test: ``axis`` at ``angles``, the others at ``hold``."""
    from mtmc.circular import follow_positions

    hold: dict[str, Any] = {a: 0.0 for a in machine.axes if a in "ABC" and a != axis}
    ht = rot.table("hold", required=False)
    if ht is not None:
        ht.only(tuple(hold))
        for a in ht.data:
            hold[a] = np.radians(ht.number(a, low=-MAX_DEG, high=MAX_DEG))
    try:
        return follow_positions(machine, {**hold, axis: angles}, point)
    except MtmcError as exc:
        raise rot.error(exc.message, None) from None


def _rotary_plot(
    topo: str,
    machine: Any,
    axis: str,
    angles: Any,
    point: Any,
    q: Any,
    kw: dict[str, Any],
    instrument: str,
    trace: Any,
    errors: dict[str, Any] | None,
) -> dict[str, Any]:
    """``circular`` of ``result.json`` of a rotary test: the readings at the estimates."""
    from mtmc.circular import rotary_ballbar, rotary_displacement

    info: dict[str, Any] = {
        "machine": topo,
        "axis": axis,
        "angle_deg": np.degrees(angles),
        "instrument": instrument,
    }
    plot: dict[str, Any] = {"rotary": info}
    if trace is not None:
        plot["data"] = trace.source
        reading = trace.readings
    else:
        means = {k: float(np.mean(np.asarray(d.mean))) for k, d in (errors or {}).items()}
        if instrument == "rtest":
            reading = rotary_displacement(machine, q, point, means)[0]
        else:
            reading = rotary_ballbar(machine, q, point, kw["direction"], kw["length"], means)[0]
    plot["displacement_um" if instrument == "rtest" else "reading_um"] = 1e3 * np.asarray(reading)
    if instrument == "ballbar":
        info["direction"] = [float(x) for x in kw["direction"]]
        info["length"] = float(kw["length"])
    return plot


def _with_noise(kw: dict[str, Any], rms: float) -> dict[str, Any]:
    """The instrument's keywords with the noise of each reading set to ``rms``."""
    from dataclasses import replace

    if "ballbar" in kw:
        return {**kw, "ballbar": replace(kw["ballbar"], noise=rms)}
    return {**kw, "noise": rms}


def _numbers(t: Fields, key: str, what: str, n: int, default: Any = None) -> Any:
    """``n`` finite numbers of at most :data:`MAX_MM` in size at ``key``, as a tuple.

    ``what`` names them in an error (``"two finite numbers [a, b]"``); ``default`` where
    absent, or an error where it is None.
    """
    if default is not None and not t.has(key):
        return default
    return t.numbers(key, n, limit=MAX_MM, what=what)


@register_kind("circular", "an ISO 230-4 circular test (ballbar) simulated with its uncertainty")
def read_circular_study(top: Fields) -> CircularStudy:
    """Validate a ``circular`` study file (module docstring)."""
    top.only(
        (
            "kind",
            "title",
            "path",
            "rotary",
            "errors",
            "ballbar",
            "rtest",
            "identify",
            "run",
            "conformity",
            "data",
            "units",
            "columns",
            "directions",
        )
    )
    settings = RunSettings.read(top, default_trials=10_000)
    if top.has("data") and top.has("errors"):
        raise top.error("a measured test (data) identifies the errors: no [errors]", "errors")
    if top.has("rotary"):
        for key in ("path", "directions"):
            if top.has(key):
                raise top.error(f"a rotary-axis test ([rotary]) has no {key}", key)
        read = _read_rotary
    elif top.has("data"):
        for key in ("rtest", "identify"):
            if top.has(key):
                raise top.error(f"a measured circular trace (data) has no [{key}]", key)
        read = _read_measured
    else:
        read = _read
    model, inputs, limits, units, plot = read(top)
    return CircularStudy(
        title=top.text("title", "Circular test"),
        source=top.source,
        settings=settings,
        model=model,
        inputs=inputs,
        conformity=limits,
        units=units,
        plot=plot,
    )
