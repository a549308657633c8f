"""Verification study files (TOML): machine, models, tracker, point sets, run settings.

A plain loader returning frozen objects; every error names the file, the line and the
field (lines from :class:`mtmc.document.Source`). The format (``docs/verification.md``):

.. code-block:: toml

    title = "..."
    note = "..."                       # optional, free text

    [machine]
    topology = "XFYZ"
    reflector = [0.0, 0.0, 0.0]        # tool (reflector) offset, mm
    travel = { X = [0.0, 400.0], Y = [0.0, 400.0], Z = [0.0, 600.0] }   # mm

    [model]                            # what the identification fits
    functions = "legendre"             # legendre | chebyshev | polynomial
    pose = true                        # identify the tracker pose
    errors = { EXX = 3, EC0Y = "constant" }   # degree of each function, or a constant
    fixed = "default"                  # or a list of parameter names held at 0

    [truth]                            # the simulated machine's errors
    functions = "legendre"
    EXX = [12.0, -4.0, 2.0]            # coefficients c1..cn, µm (µrad for angles)
    EC0Y = 20.0                        # a constant, µrad (µm for a length)

    [tracker]
    noise = "aguado2017"               # or { radial_a_um, radial_b_um_per_m,
                                       #      azimuth_urad, elevation_urad }
                                       # or { adm = [A_um, B_um_per_m],
                                       #      transverse = [A_um, B_um_per_m],
                                       #      conversion = "typical" | "rectangular" }
    euler = "xyz"                      # Euler sequence of euler_deg
    [tracker.positions.pos1]
    position = [-863.527, 194.373, 677.782]   # mm, base (workpiece) frame
    euler_deg = [0.0339, 0.0343, 59.4652]
    [tracker.limits]                   # optional (placement, visibility)
    azimuth_deg = [-180.0, 180.0]
    elevation_deg = [-60.0, 77.0]
    height_mm = [0.0, 1800.0]
    acceptance_deg = [0.0, 30.0]

    [points.mesh]                      # commanded positions, mm
    kind = "mesh"                      # or "cloud" (Aguado et al. 2016 eq. 18, with seed)
    start = [0.0, 0.0, 0.0]
    stop = [400.0, 400.0, 0.0]
    step = [50.0, 50.0, 50.0]          # an axis with start == stop stays there

    [run]
    trials = 1000
    seed = 2017
    points = "mesh"
    tracker = "pos1"

A truth function's constant term is set so that the error is zero at the start of the
axis travel (the machine's reference); the identification model's constant terms and the
linear terms of its straightnesses are held at zero by ``fixed = "default"`` (a constant
is a shift or turn of the tracker, a linear straightness term a squareness or a turn of
the tracker: see :mod:`mtmc.verification.identify`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mtmc.document import MAX_DEG, MAX_MM, MAX_UM, MAX_URAD, Fields
from mtmc.errors import InputError, MtmcError
from mtmc.instruments.laser_tracker import LaserTracker, TrackerLimits, TrackerNoise
from mtmc.kinematics.functions import (
    ChebyshevSeries,
    ErrorFunction,
    LegendreSeries,
    PolynomialFunction,
)
from mtmc.kinematics.machine import Machine
from mtmc.kinematics.parameters import ErrorModel
from mtmc.verification.simulate import Verification, VerificationMC, simulate

__all__ = ["RUN_KEYS", "PointSet", "VerificationStudy", "read_verification_study"]

_F = NDArray[np.float64]

_FUNCTIONS = ("legendre", "chebyshev", "polynomial")
_STRAIGHTNESS = ("EYX", "EZX", "EXY", "EZY", "EXZ", "EYZ")


@dataclass(frozen=True)
class PointSet:
    """A named set of commanded positions.

    Attributes
    ----------
    name : str
    q : ndarray, shape (N, n_axes)
        Axis positions, mm (read-only).
    description : str
    """

    name: str
    q: _F = field(repr=False)
    description: str = ""


def _one_of(names: Mapping[str, Any], name: str, what: str, field: str) -> str:
    """``name`` where ``names`` has it; an :class:`InputError` naming those it has otherwise."""
    if name not in names:
        raise InputError(f"no {what} {name!r}; the study has {', '.join(names)}", field=field)
    return name


@dataclass(frozen=True)
class VerificationStudy:
    """A verification study read from a file (see the module notes)."""

    file: str
    title: str
    note: str
    machine: Machine
    model: ErrorModel
    fixed: tuple[str, ...]
    pose: bool
    truth: Mapping[str, Any]
    noise: TrackerNoise
    trackers: Mapping[str, LaserTracker]
    limits: TrackerLimits | None
    points: Mapping[str, PointSet]
    default_points: str
    default_tracker: str
    repeatability: float = 0.0
    reflector_u: float = 0.0
    pose_u: tuple[float, ...] = (0.0,) * 6
    euler: str = "xyz"

    def verification(self, points: str | None = None, tracker: str | None = None) -> Verification:
        """The :class:`Verification` of one point set with one tracker position.

        Raises
        ------
        InputError
            For an unknown point set or tracker name.
        """
        return Verification(
            self.model,
            self.point_set(points).q,
            self.trackers[self.tracker_name(tracker)],
            self.truth,
            pose=self.pose,
            fixed=self.fixed,
        )

    def point_set(self, name: str | None = None) -> PointSet:
        """The point set ``name`` (default: ``[run] points``); InputError for another name."""
        pn = self.default_points if name is None else name
        return self.points[_one_of(self.points, pn, "point set", "points")]

    def tracker_name(self, name: str | None = None) -> str:
        """``name``, a tracker position of the study (default: ``[run] tracker``), checked."""
        tn = self.default_tracker if name is None else name
        return _one_of(self.trackers, tn, "tracker position", "tracker")

    def simulate(
        self,
        trials: int,
        seed: int | None = None,
        *,
        points: str | None = None,
        tracker: str | None = None,
        progress: Any = None,
        **parallel: Any,
    ) -> VerificationMC:
        """The Monte Carlo of whole verifications of this study (:func:`simulate`).

        The study's repeatability, reflector ``u`` and, where the pose is not identified,
        the pose's ``u`` are the uncertainties drawn besides the tracker's noise; ``mtmc
        run`` and ``mtmc verify simulate`` both run this.

        Parameters
        ----------
        trials, seed
            As :func:`simulate`.
        points, tracker : str, optional
            A point set and a tracker position of the study (default: those of ``[run]``).
        progress, **parallel
            As :func:`simulate` (``workers``, ``executor``, ``scheduler``).
        """
        return simulate(
            self.verification(points, tracker),
            trials,
            seed,
            repeatability=self.repeatability,
            reflector_u=self.reflector_u,
            pose_u=None if self.pose else self.pose_u,
            progress=progress,
            **parallel,
        )


def _function(kind: str, values: list[float], lo: float, hi: float) -> ErrorFunction:
    coeffs = np.array(values, dtype=np.float64)
    if kind == "legendre":
        return LegendreSeries(coeffs, low=lo, high=hi)
    if kind == "chebyshev":
        return ChebyshevSeries(coeffs, low=lo, high=hi)
    return PolynomialFunction(coeffs)


def _is_angle(machine: Machine, name: str) -> bool:
    return bool(machine.error_term(name).angular)


#: The highest degree of an error function in ``[model] errors``.
MAX_DEGREE = 20


def _vector(f: Fields, key: str, n: int = 3, limit: float = MAX_MM) -> _F:
    """``n`` finite numbers, each at most ``limit`` in size (mm unless the key says)."""
    if f.data.get(key) is None:
        raise f.error(f"missing {key}", key)
    return np.array(f.numbers(key, n, limit=limit), dtype=np.float64)


def _pair(
    f: Fields, key: str, default: tuple[float, float], limit: float = MAX_MM
) -> tuple[float, float]:
    if key not in f.data:
        return default
    v = _vector(f, key, 2, limit)
    if not v[0] <= v[1]:
        raise f.error(f"expected low <= high, got {v.tolist()}", key)
    return float(v[0]), float(v[1])


def _travel(mf: Fields, topo_axes: tuple[str, ...]) -> dict[str, tuple[float, float]]:
    t = mf.table("travel")
    assert t is not None
    out = {}
    for ax in topo_axes:
        out[ax] = _pair(t, ax, (math.nan, math.nan))
        if math.isnan(out[ax][0]):
            raise t.error(f"missing travel of axis {ax}", ax)
        if not out[ax][0] < out[ax][1]:
            raise t.error(f"expected low < high, got {list(out[ax])}", ax)
    t.only(topo_axes)
    return out


def _mpe_mm(nf: Fields, key: str) -> tuple[float, float]:
    """An MPE ``[A_um, B_um_per_m]`` of the file as ``(A, B)`` in mm and mm/mm."""
    v = _vector(nf, key, 2, MAX_UM)
    return v[0] * 1e-3, v[1] * 1e-6


def _noise(tf: Fields) -> TrackerNoise:
    v = tf.data.get("noise", "aguado2017")
    if v == "aguado2017":
        return TrackerNoise.aguado2017()
    if not isinstance(v, dict):
        raise tf.error(f'expected "aguado2017" or a table, got {v!r}', "noise")
    nf = tf.table("noise")
    assert nf is not None
    if "conversion" in nf.data:
        nf.only(("adm", "transverse", "conversion"))
        adm, tr = _mpe_mm(nf, "adm"), _mpe_mm(nf, "transverse")  # the only µm -> mm step
        conv = nf.text("conversion", choices=("typical", "rectangular"))
        return TrackerNoise.from_mpe(adm=adm, transverse=tr, conversion=conv)
    nf.only(("radial_a_um", "radial_b_um_per_m", "azimuth_urad", "elevation_urad"))
    return TrackerNoise(
        nf.number("radial_a_um", low=0.0, high=MAX_UM) * 1e-3,
        nf.number("radial_b_um_per_m", low=0.0, high=MAX_UM) * 1e-6,
        nf.number("azimuth_urad", low=0.0, high=MAX_URAD) * 1e-6,
        nf.number("elevation_urad", low=0.0, high=MAX_URAD) * 1e-6,
        0.0,
        "study file",
    )


def _points_of(pf: Fields, n_axes: int) -> _F:
    """A mesh or a cloud (Aguado et al. 2016 eq. 18) by :mod:`mtmc.verification.workspace`."""
    from mtmc.verification.workspace import cloud, mesh

    kind = pf.text("kind", "mesh", choices=("mesh", "cloud"))
    a, b = _vector(pf, "start", n_axes), _vector(pf, "stop", n_axes)
    step = _vector(pf, "step", n_axes)
    seed = pf.integer("seed", minimum=0) if kind == "cloud" else None
    try:
        if kind == "mesh":
            return mesh(a, b, step=step)
        rng = np.random.default_rng(np.random.SeedSequence(seed))
        return cloud(a, b, rng, step=step)
    except MtmcError as exc:
        key = {"end": "stop"}.get(exc.field or "", exc.field)
        if key in pf.data:
            raise pf.error(exc.message, key) from exc
        raise pf.error(str(exc)) from exc


def read_trackers(tf: Fields) -> tuple[dict[str, LaserTracker], TrackerLimits | None]:
    """The ``[tracker]`` table of a study: named positions and the optional limits.

    ``noise`` (``"aguado2017"`` or a table), ``euler`` (the sequence, default ``"xyz"``),
    ``[tracker.positions.NAME]`` with ``position`` (mm) and ``euler_deg``, and
    ``[tracker.limits]`` with ``azimuth_deg``, ``elevation_deg``, ``height_mm`` and
    ``acceptance_deg`` (each ``[low, high]``; the defaults of :class:`TrackerLimits`).

    Raises
    ------
    InputError
        Naming the file, line and field of a bad entry, or when no position is given.
    """
    tf.only(("noise", "euler", "positions", "limits"))
    noise = _noise(tf)
    seq = tf.text("euler", "xyz")
    pf = tf.table("positions")
    assert pf is not None
    trackers: dict[str, LaserTracker] = {}
    for name in pf.data:
        one = pf.table(name)
        assert one is not None
        one.only(("position", "euler_deg"))
        position, euler = _vector(one, "position"), _vector(one, "euler_deg", limit=MAX_DEG)
        try:
            trackers[name] = LaserTracker.from_euler(
                position, euler, seq=seq, degrees=True, noise=noise, name=name
            )
        except MtmcError as exc:
            raise one.error(str(exc)) from exc
    if not trackers:
        raise pf.error("expected at least one tracker position")
    limits = None
    lf = tf.table("limits", required=False)
    if lf is not None:
        lf.only(("azimuth_deg", "elevation_deg", "height_mm", "acceptance_deg"))
        d = TrackerLimits()
        az = _pair(lf, "azimuth_deg", tuple(math.degrees(x) for x in d.azimuth), MAX_DEG)  # type: ignore[arg-type]
        el = _pair(lf, "elevation_deg", tuple(math.degrees(x) for x in d.elevation), MAX_DEG)  # type: ignore[arg-type]
        ac = _pair(lf, "acceptance_deg", tuple(math.degrees(x) for x in d.acceptance), MAX_DEG)  # type: ignore[arg-type]
        limits = TrackerLimits(
            azimuth=(math.radians(az[0]), math.radians(az[1])),
            elevation=(math.radians(el[0]), math.radians(el[1])),
            height=_pair(lf, "height_mm", d.height),
            acceptance=(math.radians(ac[0]), math.radians(ac[1])),
        )
    return trackers, limits


def _machine(top: Fields, title: str) -> tuple[Machine, dict[str, tuple[float, float]]]:
    """The ``[machine]`` table: the topology, its travel and the reflector offset."""
    mf = top.table("machine")
    assert mf is not None
    mf.only(("topology", "reflector", "travel"))
    topo = mf.text("topology")
    try:
        bare = Machine.from_topology(topo)
    except MtmcError as exc:
        raise mf.error(str(exc), "topology") from exc
    travel = _travel(mf, bare.axes)
    reflector = _vector(mf, "reflector") if "reflector" in mf.data else np.zeros(3)
    return Machine.from_topology(topo, tool=reflector, travel=travel, name=title), travel


def _term_name(machine: Machine, f: Fields, key: str) -> str:
    """The ISO 230 name of the error ``key`` of table ``f``, or an error at that key."""
    try:
        return machine.error_term(key).name
    except MtmcError as exc:
        raise f.error(str(exc), key) from exc


def _templates(
    ef: Fields, machine: Machine, travel: Mapping[str, tuple[float, float]], kind: str
) -> dict[str, ErrorFunction | float]:
    """``[model] errors``: a zero function of the given degree, or a constant, per error."""
    templates: dict[str, ErrorFunction | float] = {}
    for key, v in ef.data.items():
        name = _term_name(machine, ef, key)
        if v == "constant":
            templates[name] = 0.0
        elif isinstance(v, int) and not isinstance(v, bool) and 1 <= v <= MAX_DEGREE:
            term = machine.error_term(name)
            if term.axis not in travel:
                raise ef.error(f'{name} is not a function of an axis; write "constant"', key)
            lo, hi = travel[term.axis]
            templates[name] = _function(kind, [0.0] * (v + 1), lo, hi)
        else:
            raise ef.error(
                f'expected a degree from 1 to {MAX_DEGREE} or "constant", got {v!r}', key
            )
    return templates


def _fixed(md: Fields, model: ErrorModel) -> list[str]:
    """``[model] fixed``: the parameters held at zero (``"default"``: see the module notes)."""
    fx = md.data.get("fixed", "default")
    if fx == "default":
        fixed = [n for n in model.parameter_names if n.endswith("[0]")]
        fixed += [f"{e}[1]" for e in _STRAIGHTNESS if f"{e}[1]" in model.parameter_names]
        return fixed
    fixed = list(md.texts("fixed"))
    for n in fixed:
        if n not in model.parameter_names:
            raise md.error(
                f"{n} is not a parameter of the model ({', '.join(model.parameter_names)})",
                "fixed",
            )
    return fixed


def _model(
    top: Fields, machine: Machine, travel: Mapping[str, tuple[float, float]]
) -> tuple[ErrorModel, list[str], bool]:
    """The ``[model]`` table: the identification model, its fixed parameters, ``pose``."""
    md = top.table("model")
    assert md is not None
    md.only(("functions", "pose", "errors", "fixed"))
    kind = md.text("functions", "legendre", choices=_FUNCTIONS)
    pose = md.flag("pose", True)
    ef = md.table("errors")
    assert ef is not None
    templates = _templates(ef, machine, travel, kind)
    try:
        model = ErrorModel(machine, templates)
    except MtmcError as exc:
        raise ef.error(str(exc)) from exc
    return model, _fixed(md, model), pose


def _truth(
    top: Fields, machine: Machine, travel: Mapping[str, tuple[float, float]]
) -> dict[str, Any]:
    """The ``[truth]`` table: the simulated machine's errors, mm and rad."""
    tr = top.table("truth")
    assert tr is not None
    tkind = tr.text("functions", "legendre", choices=_FUNCTIONS)
    truth: dict[str, Any] = {}
    for key, v in tr.data.items():
        if key == "functions":
            continue
        name = _term_name(machine, tr, key)
        scale = 1e-6 if _is_angle(machine, name) else 1e-3
        limit = MAX_URAD if _is_angle(machine, name) else MAX_UM
        if isinstance(v, list):
            if not v or not all(isinstance(x, int | float) and not isinstance(x, bool) for x in v):
                raise tr.error(f"expected an array of numbers, got {v!r}", key)
            if not all(abs(x) <= limit for x in v):  # NaN and infinities too
                raise tr.error(
                    f"expected finite numbers each at most {limit:g} in size, got {v!r}", key
                )
            term = machine.error_term(name)
            if term.axis not in travel or term.kind != "component":
                raise tr.error(f"{name} is not a component error of an axis: give a number", key)
            lo, hi = travel[term.axis]
            f0 = _function(tkind, [0.0, *(float(x) * scale for x in v)], lo, hi)
            c0 = -float(f0(np.array([lo]))[0])  # zero at the start of travel
            truth[name] = _function(tkind, [c0, *(float(x) * scale for x in v)], lo, hi)
        else:
            truth[name] = tr.number(key, low=-limit, high=limit) * scale
    return truth


def _point_sets(top: Fields, n_axes: int) -> dict[str, PointSet]:
    """The ``[points.NAME]`` tables: meshes and clouds of commanded positions."""
    ps = top.table("points")
    assert ps is not None
    points: dict[str, PointSet] = {}
    for name in ps.data:
        one = ps.table(name)
        assert one is not None
        one.only(("kind", "start", "stop", "step", "seed", "description"))
        q = np.array(_points_of(one, n_axes), dtype=np.float64)
        q.setflags(write=False)
        points[name] = PointSet(name, q, one.text("description", ""))
    if not points:
        raise ps.error("expected at least one point set")
    return points


#: The keys of ``[run]`` a verification study adds to those of every study (trials, seed,
#: ...), which the study layer reads (:meth:`mtmc.study.spec.RunSettings.read`).
RUN_KEYS = ("points", "tracker", "repeatability_um", "reflector_um", "pose_u")


def _run(
    top: Fields, points: Mapping[str, PointSet], trackers: Mapping[str, Any], pose: bool
) -> dict[str, Any]:
    """The verification's keys of ``[run]`` (:data:`RUN_KEYS`), as keyword arguments."""
    rf = top.table("run", required=False) or Fields(top.source, {}, ("run",))
    dp = rf.text("points", next(iter(points)), choices=tuple(points))
    dt = rf.text("tracker", next(iter(trackers)), choices=tuple(trackers))
    pose_u = tuple(_vector(rf, "pose_u", 6).tolist()) if "pose_u" in rf.data else (0.0,) * 6
    if pose and any(u > 0.0 for u in pose_u):
        raise rf.error(
            "give pose_u only when the pose is not identified ([model] pose = false)", "pose_u"
        )
    return {
        "default_points": dp,
        "default_tracker": dt,
        "repeatability": rf.number("repeatability_um", 0.0, low=0.0, high=MAX_UM) * 1e-3,
        "reflector_u": rf.number("reflector_um", 0.0, low=0.0, high=MAX_UM) * 1e-3,
        "pose_u": pose_u,
    }


def _plan_tables(top: Fields, axes: tuple[str, ...]) -> None:
    """Validate the ``[workspace]`` and ``[nc]`` tables as ``verify plan`` reads them."""
    from mtmc.verification.ncprogram import read_nc
    from mtmc.verification.workspace import read_workspace

    ws = top.table("workspace") if "workspace" in top.data else None
    plan_axes = read_workspace(ws, axes).axes if ws is not None else axes
    nc = top.table("nc") if "nc" in top.data else None
    if nc is not None:
        read_nc(nc, plan_axes)


def read_verification_study(top: Fields) -> VerificationStudy:
    """The verification study of a parsed study file (:func:`mtmc.document.loads_toml`).

    One reader per table, in file order: ``[machine]``, ``[model]``, ``[truth]``,
    ``[tracker]`` (:func:`read_trackers`), ``[points]``, and the keys of ``[run]`` that
    are the verification's (:data:`RUN_KEYS`; the study layer reads the others).

    Parameters
    ----------
    top : Fields
        The top table of the file.

    Returns
    -------
    VerificationStudy

    Raises
    ------
    InputError
        Naming the file, line and field of the first bad entry.
    """
    top.only(
        (
            "title",
            "note",
            "kind",
            "machine",
            "model",
            "truth",
            "tracker",
            "points",
            "run",
            "workspace",
            "nc",  # these two as verify plan reads them (mtmc.verification.ncprogram)
        )
    )
    if "kind" in top.data:
        top.text("kind", choices=("verification",))
    title = top.text("title", "")
    note = top.text("note", "")
    machine, travel = _machine(top, title)
    _plan_tables(top, machine.axes)
    model, fixed, pose = _model(top, machine, travel)
    truth = _truth(top, machine, travel)
    tf = top.table("tracker")
    assert tf is not None
    trackers, limits = read_trackers(tf)
    noise = next(iter(trackers.values())).noise
    assert noise is not None
    points = _point_sets(top, machine.n_axes)
    return VerificationStudy(
        file=top.source.file,
        title=title,
        note=note,
        machine=machine,
        model=model,
        fixed=tuple(fixed),
        pose=pose,
        truth=truth,
        noise=noise,
        trackers=trackers,
        limits=limits,
        points=points,
        euler=tf.text("euler", "xyz"),
        **_run(top, points, trackers, pose),
    )
