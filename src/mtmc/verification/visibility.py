"""Visibility of a planned verification from the study's tracker positions.

Aguado et al. 2016 §4.4 (Fig. 7, eqs. 19–21): the workspace is bounded by nine limit
points, ``P0`` in its middle and ``P1``–``P8`` at the lower and upper limits of each of
the three axes (the corners of the box of axis positions; ``2ⁿ`` corners for ``n`` axes).
A tracker position sees the workspace when, for every limit point, the beam's azimuth and
elevation (tracker frame) are inside the tracker's limits, the angle between the beam to
``P0`` (where the reflector faces the tracker) and the beam to the point is inside the
reflector's acceptance range (eq. 21), and the tracker's height is inside its limits
(:func:`mtmc.instruments.visibility`). The reflector positions are the machine's nominal
tool positions at the limit points, for each reflector offset of the plan.

Examples
--------
>>> import numpy as np
>>> names, q = limit_points(np.array([[0.0, 0.0, 0.0], [500.0, 400.0, 300.0]]))
>>> names[:3], q[0].tolist(), q[1].tolist(), q[8].tolist()
(('P0', 'P1', 'P2'), [250.0, 200.0, 150.0], [0.0, 0.0, 0.0], [500.0, 400.0, 300.0])
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.document import Fields, loads_toml, read_text
from mtmc.errors import MtmcError
from mtmc.instruments.laser_tracker import (
    LaserTracker,
    TrackerLimits,
    VisibilityReport,
    visibility,
)
from mtmc.kinematics.machine import Machine
from mtmc.verification.workspace import MeasurementPlan

__all__ = [
    "PlanVisibility",
    "limit_points",
    "plan_visibility",
    "study_visibility",
    "visibility_warnings",
]

if TYPE_CHECKING:
    from mtmc.verification.definition import VerificationStudy

_F = NDArray[np.float64]


def limit_points(q: npt.ArrayLike) -> tuple[tuple[str, ...], _F]:
    """The limit points of a set of axis positions: the middle, then the corners.

    Parameters
    ----------
    q : array_like, shape (N, n_axes)
        Axis positions (mm, rad).

    Returns
    -------
    names : tuple of str
        ``P0`` (the middle), ``P1`` … ``P{2ⁿ}`` (the corners, the first axis slowest).
    points : ndarray, shape (1 + 2ⁿ, n_axes)
    """
    a = np.asarray(q, dtype=np.float64)
    lo, hi = a.min(axis=0), a.max(axis=0)
    corners = [np.where(np.array(c), hi, lo) for c in itertools.product((0, 1), repeat=a.shape[1])]
    pts = np.array([0.5 * (lo + hi), *corners])
    return tuple(f"P{i}" for i in range(pts.shape[0])), pts


@dataclass(frozen=True)
class PlanVisibility:
    """Visibility of the limit points from one tracker position.

    Attributes
    ----------
    tracker : LaserTracker
    names : tuple of str
        The checked points: ``P0`` … ``P8`` (with ``/o2`` … for further reflector offsets).
    q : ndarray, shape (K, n_axes)
        Their axis positions.
    report : VisibilityReport
        Failures index :attr:`names` (``point = -1``: the tracker's height).
    """

    tracker: LaserTracker
    names: tuple[str, ...]
    q: _F
    report: VisibilityReport

    @property
    def ok(self) -> bool:
        """True when every limit point is seen within every limit."""
        return self.report.ok

    def failures(self, axes: tuple[str, ...]) -> list[dict[str, Any]]:
        """The failures as plain data (angles in degrees, heights in mm)."""
        out = []
        for f in self.report.failures:
            scale = 1.0 if f.limit == "height" else 180.0 / math.pi
            d: dict[str, Any] = {
                "point": "tracker" if f.point < 0 else self.names[f.point],
                "limit": f.limit,
                "value": f.value * scale,
                "low": f.low * scale,
                "high": f.high * scale,
                "unit": "mm" if f.limit == "height" else "deg",
            }
            if f.point >= 0:
                d["axes"] = dict(zip(axes, map(float, self.q[f.point]), strict=True))
            out.append(d)
        return out

    def text(self, axes: tuple[str, ...]) -> str:
        """One line per failure, or one line saying every point is seen."""
        name = self.tracker.name or "tracker"
        if self.ok:
            return f"{name}: all {len(self.names)} limit points visible"
        lines = [f"{name}: {len(self.report.failures)} failures"]
        lines += [f"  {_failure_text(f, 'tracker')}" for f in self.failures(axes)]
        return "\n".join(lines)


def _failure_text(f: Mapping[str, Any], tracker: str) -> str:
    """One failure of :meth:`PlanVisibility.failures` in words: where, which limit, how far."""
    where = (
        tracker
        if f["point"] == "tracker"
        else f"{f['point']} ({', '.join(f'{a} {x:g}' for a, x in f['axes'].items())})"
    )
    return (
        f"{where}: {f['limit']} {f['value']:.2f} {f['unit']} outside "
        f"[{f['low']:g}, {f['high']:g}] {f['unit']}"
    )


def plan_visibility(
    machine: Machine,
    q: npt.ArrayLike,
    trackers: Mapping[str, LaserTracker],
    limits: TrackerLimits,
    offsets: npt.ArrayLike | None = None,
) -> dict[str, PlanVisibility]:
    """Check the limit points of a plan from each tracker position.

    Parameters
    ----------
    machine : Machine
        The nominal machine (its tool point is the reflector).
    q : array_like, shape (N, n_axes)
        The plan's axis positions.
    trackers : mapping of str to LaserTracker
        The tracker positions, by name.
    limits : TrackerLimits
    offsets : array_like, shape (k, 3), optional
        Reflector offsets from the tool point, tool frame, mm (default: none); with more
        than one, the limit points are checked for each (names ``P3/o2``, …).

    Returns
    -------
    dict of str to PlanVisibility
        In the order of ``trackers``.
    """
    names0, ql = limit_points(q)
    T = machine.pose(ql)
    offs = np.zeros((1, 3)) if offsets is None else np.atleast_2d(np.asarray(offsets, float))
    pts = np.concatenate([T[:, :3, 3] + T[:, :3, :3] @ o for o in offs])
    names = tuple(n if k == 0 else f"{n}/o{k + 1}" for k in range(offs.shape[0]) for n in names0)
    qq = np.tile(ql, (offs.shape[0], 1))
    return {
        name: PlanVisibility(lt, names, qq, visibility(lt, pts, limits, reference=0))
        for name, lt in trackers.items()
    }


def _machine(top: Fields) -> tuple[Machine, _F]:
    """The study's nominal machine (a library name or a topology) and reflector offset."""
    from mtmc.kinematics.library import library_machine, library_names

    if "machine" not in top.data:
        raise top.error("the visibility check needs the machine", "machine")
    where, key, tool = top, "machine", np.zeros(3)
    if isinstance(top.data["machine"], dict):
        mf = top.table("machine")
        assert mf is not None
        where, key = mf, "topology"
        if "reflector" in mf.data:
            from mtmc.verification.definition import _vector

            tool = _vector(mf, "reflector")
    spec = where.text(key)
    if spec.strip().lower() in library_names():
        return library_machine(spec), tool
    try:
        return Machine.from_topology(spec), tool
    except MtmcError as exc:
        raise where.error(str(exc), key) from None


def load_plan_visibility(
    path: str | Path, plan: MeasurementPlan
) -> dict[str, PlanVisibility] | None:
    """The visibility report of a plan study's tracker positions, if it names any.

    Reads the study's ``machine`` (a library name, a topology, or a table with
    ``topology`` and ``reflector``), its ``[tracker.positions.NAME]`` (``position`` mm,
    ``euler_deg``; the sequence ``[tracker] euler``) and ``[tracker.limits]``
    (``azimuth_deg``, ``elevation_deg``, ``height_mm``, ``acceptance_deg``; the defaults of
    :class:`~mtmc.instruments.TrackerLimits` where absent).

    Parameters
    ----------
    path : str or Path
        The study file.
    plan : MeasurementPlan
        Its plan (:func:`~mtmc.verification.ncprogram.load_plan_study`).

    Returns
    -------
    dict of str to PlanVisibility, or None
        None when the study has no ``[tracker]`` table.

    Raises
    ------
    InputError
        On a bad machine, tracker or limit, naming the file, line and field.
    """
    from mtmc.verification.definition import read_trackers

    top = loads_toml(read_text(path, "study file"), str(path), Path(path).parent)
    if "tracker" not in top.data:
        return None
    tf = top.table("tracker")
    assert tf is not None
    trackers, limits = read_trackers(tf)
    machine, reflector = _machine(top)
    return plan_visibility(
        machine, plan.points, trackers, limits or TrackerLimits(), reflector + plan.offsets
    )


def study_visibility(
    study: VerificationStudy,
    points: str | None = None,
    trackers: Sequence[str] | None = None,
) -> dict[str, PlanVisibility]:
    """Visibility of a point set of a verification study from its tracker positions.

    The check of :func:`plan_visibility` (the nine limit points of Aguado et al. 2016
    §4.4, eqs. 19–21) on the axis positions of one point set, with the reflector of the
    study's machine and the study's ``[tracker.limits]`` (the defaults of
    :class:`~mtmc.instruments.TrackerLimits` where it has none). ``mtmc verify simulate``,
    ``mtmc verify place`` and ``mtmc run`` print :func:`visibility_warnings` of it.

    Parameters
    ----------
    study : VerificationStudy
    points : str, optional
        A point set of the study (default: its ``[run] points``).
    trackers : sequence of str, optional
        Tracker positions of the study (default: all of them).

    Returns
    -------
    dict of str to PlanVisibility
        In the order of ``trackers``.

    Raises
    ------
    InputError
        For an unknown point set or tracker position.
    """
    q = study.point_set(points).q
    names = [study.tracker_name(n) for n in (study.trackers if trackers is None else trackers)]
    return plan_visibility(
        study.machine,
        q,
        {n: study.trackers[n] for n in names},
        study.limits or TrackerLimits(),
    )


def visibility_warnings(vis: Mapping[str, PlanVisibility], axes: tuple[str, ...]) -> list[str]:
    """One line per tracker position that does not see every limit point.

    Parameters
    ----------
    vis : mapping of str to PlanVisibility
        As :func:`study_visibility` or :func:`plan_visibility` return it.
    axes : tuple of str
        The machine's axis letters (to name the points).

    Returns
    -------
    list of str
        Empty when every position sees every point. A line names the position and each
        failing point with its axis positions, the limit,
        the value and the range (degrees, or mm for the height).
    """
    out = []
    for name, v in vis.items():
        if v.ok:
            continue
        parts = [_failure_text(f, "the tracker") for f in v.failures(axes)]
        out.append(
            f"tracker position {name} cannot see every limit point of the measured points "
            "(Aguado et al. 2016 eqs. 19-21): " + "; ".join(parts)
        )
    return out
