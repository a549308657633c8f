r"""The nominal (noise-free) configuration of a graph, checked before any trial is drawn.

A Monte Carlo run perturbs the nominal configuration: every marked place at its value
(a ``dist`` place at the expectation of its distribution), every ``meas`` at its nominal
point ``at``. If that configuration is degenerate (three collinear points into
``plane``, three coincident ball centres into ``circle``), the noisy trials scatter
around a construction that does not exist and the result means nothing, however small
its spread. :func:`check_nominal` fires every transition once on the nominal values and
refuses such a graph, naming the transition, its file and line.

It also measures how badly conditioned each construction is, by central differences on
one batch: the relative condition number

.. math:: \kappa = \max_{p, j} \left|\frac{\partial y_p}{\partial x_j}\right|
          L^{\,\ell_j - \ell_p},

where ``x`` are the components of the transition's inputs, ``y`` those of its output,
``ℓ`` the power of length of each component (1 for coordinates, radii and distances, 0
for unit vectors and rotations; :func:`mtmc.graph.units.place_dimension`) and ``L`` the
size of the construction (the RMS distance of its input points from their centroid; its
output point is added when there is only one input point; 1 mm when there is one point).
``κ`` is the factor by which a deviation of the inputs, measured against the size of the
construction, grows in the output: 1 for a difference of two points, of the order of
``1/sin θ`` for the normal of a plane through three points whose smallest angle is ``θ``.
Above :data:`MAX_CONDITION` it is reported
as a warning (:class:`ConditioningWarning`).

The rotary-axis construction with a given angle α (``axis`` with a fourth, real input)
is also checked: the angle between ``P1`` and ``P2`` about the centre of the circle
through the three nominal ball centres must equal α (see :data:`ANGLE_RTOL`); a mismatch,
e.g. an angle typed in radians in a place that says ``unit = "deg"``, is refused.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mtmc.errors import ConditioningWarning, DegenerateGeometryError, GraphError, MtmcError
from mtmc.frozen import frozen_floats
from mtmc.geometry.checks import IN_BATCH
from mtmc.graph.places import VECTOR_TYPES
from mtmc.graph.structure import Plan, Step
from mtmc.graph.units import place_dimension
from mtmc.graph.values import PARTS, flatten, marked_value, unflatten

__all__ = [
    "ANGLE_RTOL",
    "MAX_CONDITION",
    "ConditioningWarning",
    "NominalReport",
    "check_nominal",
]

#: Relative condition number above which a construction is reported as badly conditioned.
MAX_CONDITION: float = 1e3

#: Relative tolerance of the check of α against the nominal ball centres: they must agree
#: within ``ANGLE_RTOL · α`` (the nominal centres are typed with a few digits).
ANGLE_RTOL: float = 0.02

#: Relative step of the central differences (of the size of the construction).
_STEP: float = 1e-6


@dataclass(frozen=True)
class NominalReport:
    """What :func:`check_nominal` found.

    Parameters
    ----------
    values : mapping of str to ndarray
        The nominal value of every place, flattened (``(k,)``, layout of
        :data:`mtmc.graph.values.PARTS`), mm and rad.
    condition : mapping of str to float
        The relative condition number κ of every transition other than ``meas``.
    warnings : tuple of str
        One line per badly conditioned transition (κ > ``max_condition``), naming it,
        its file and line.
    """

    values: Mapping[str, NDArray[np.float64]]
    condition: Mapping[str, float]
    warnings: tuple[str, ...]


def _nominal_samples(plan: Plan) -> dict[str, Any]:
    """Samples of one trial that put every ``dist`` place at its expectation."""
    from mtmc.uncertainty.distributions import parse_distribution

    samples: dict[str, Any] = {}
    for p in plan.graph.places:
        if p.dist is None or p.u is not None:
            continue
        mean = np.asarray(parse_distribution(p.dist).mean, dtype=np.float64)
        mean = np.where(np.isfinite(mean), mean, 0.0)
        vec = p.type in VECTOR_TYPES
        flat = mean.reshape(-1)
        if vec and flat.size == 1:  # one scalar law, drawn for each coordinate
            flat = np.repeat(flat, 3)
        for i, c in enumerate("xyz" if vec else ("",)):
            samples[f"{p.name}.{c}" if c else p.name] = flat[i : i + 1]
    return samples


def _length_powers(plan: Plan, name: str) -> NDArray[np.float64]:
    """The power of length of each flattened component of place ``name``."""
    out: list[float] = []
    for part, size in PARTS[plan.types[name]]:
        out += [float(place_dimension(plan, name, part)[0])] * size
    return np.array(out)


def _points(type_: str, flat: NDArray[np.float64]) -> NDArray[np.float64]:
    """The point-like parts (coordinates, centres) of flattened values, ``(n, 3)``."""
    if type_ in ("point", "line", "plane", "circle", "sphere"):
        return flat[:, 0:3]
    if type_ == "frame":
        return flat[:, 9:12]
    return np.empty((0, 3))


def _size(points: NDArray[np.float64]) -> float:
    """RMS distance of points from their centroid; 1 when there are fewer than two."""
    if points.shape[0] < 2:
        return 1.0
    d = points - points.mean(axis=0)
    size = float(np.sqrt(np.mean(np.sum(d * d, axis=1))))
    return size if size > 0 and math.isfinite(size) else 1.0


def _where(plan: Plan, step: Step, fld: str = "in") -> dict[str, Any]:
    t = step.transition
    return {"file": plan.graph.file, "line": t.field_line(fld), "field": fld}


def _fire(step: Step, args: list[Any]) -> Any:
    with np.errstate(all="ignore"):
        return step.variant.func(*args)


def _condition(
    plan: Plan, step: Step, inputs: list[NDArray[np.float64]], out: NDArray[np.float64]
) -> float:
    """κ of one transition by central differences, all steps in one batch of ``2K``."""
    t = step.transition
    types = [plan.types[p] for p in t.inputs]
    x = np.concatenate(inputs)
    k = x.size
    ell_in = np.concatenate([_length_powers(plan, p) for p in t.inputs])
    ell_out = _length_powers(plan, t.out)
    pts = np.concatenate([_points(ty, v[None, :]) for ty, v in zip(types, inputs, strict=True)])
    if pts.shape[0] < 2:
        pts = np.concatenate([pts, _points(plan.types[t.out], out[None, :])])
    size = _size(pts)
    h = _STEP * size**ell_in
    batch = np.repeat(x[None, :], 2 * k, axis=0)
    idx = np.arange(k)
    batch[idx, idx] += h
    batch[k + idx, idx] -= h
    args = []
    i = 0
    for ty, v in zip(types, inputs, strict=True):
        args.append(unflatten(ty, batch[:, i : i + v.size]))
        i += v.size
    try:
        y = flatten(plan.types[t.out], _fire(step, args), 2 * k)
    except MtmcError:
        return math.inf
    dy = (y[:k] - y[k:]) / (2 * h[:, None])  # (K inputs, P outputs)
    scaled = np.abs(dy) * size ** (ell_in[:, None] - ell_out[None, :])
    kappa = float(np.max(scaled)) if scaled.size else 0.0
    return kappa if math.isfinite(kappa) else math.inf


def _check_alpha(plan: Plan, step: Step, inputs: list[NDArray[np.float64]]) -> None:
    """The angle α of an ``axis`` against the angle of its nominal ball centres."""
    from mtmc.geometry import constructions as gc

    p1, p2, p3 = (v.reshape(1, 3) for v in inputs[:3])
    alpha = float(inputs[3][0])
    t = step.transition
    try:
        centre = gc.circle_from_points(p1, p2, p3).centre[0]
    except MtmcError:
        return  # collinear centres: reported by the construction itself
    a, b = p1[0] - centre, p2[0] - centre
    seen = math.atan2(float(np.linalg.norm(np.cross(a, b))), float(a @ b))
    if abs(seen - abs(alpha)) > ANGLE_RTOL * max(abs(alpha), seen):
        alpha_place = t.inputs[3]
        raise GraphError(
            f"transition {t.name} (axis): the angle {alpha_place} is {alpha:.6g} rad "
            f"({math.degrees(alpha):.6g}°), but the nominal ball centres {t.inputs[0]} and "
            f"{t.inputs[1]} are {seen:.6g} rad ({math.degrees(seen):.6g}°) apart about "
            f"the axis; check the value and the unit of {alpha_place}",
            **_where(plan, step),
        )


def check_nominal(plan: Plan, *, max_condition: float = MAX_CONDITION) -> NominalReport:
    """Fire every transition on the nominal values; refuse a degenerate configuration.

    Parameters
    ----------
    plan : Plan
        A checked graph (:func:`mtmc.graph.check`).
    max_condition : float
        The relative condition number above which a transition is reported in
        ``warnings`` (and as a :class:`ConditioningWarning`).

    Returns
    -------
    NominalReport
        The nominal values, the condition number of every construction, the warnings.

    Raises
    ------
    DegenerateGeometryError
        If a construction is degenerate at the nominal values, naming the transition, its
        op, the file and the line of its inputs (field ``in``).
    GraphError
        If a transition gives a value that is not finite at the nominal values, or an
        ``axis`` angle α does not match the angle between its nominal ball centres.
    """
    from mtmc.graph import probe as _probe

    g = plan.graph
    samples = _nominal_samples(plan)
    values: dict[str, NDArray[np.float64]] = {}
    for p in g.places:
        if p.marked:
            values[p.name] = flatten(p.type, marked_value(p, g.factor, samples), 1)[0]
    condition: dict[str, float] = {}
    notes: list[str] = []
    for step in plan.steps:
        t = step.transition
        out_type = plan.types[t.out]
        if t.op == "meas":
            spec = _probe.meas_spec(t, g.probe, g.factor)
            val = _probe.meas_value(t.name, spec, step.variant.output, {}, 1)
            values[t.out] = flatten(out_type, val, 1)[0]
            continue
        inputs = [values[p] for p in t.inputs]
        if t.op == "axis" and len(inputs) == 4:
            _check_alpha(plan, step, inputs)
        args = [_unflat(plan.types[p], v) for p, v in zip(t.inputs, inputs, strict=True)]
        try:
            out = flatten(out_type, _fire(step, args), 1)[0]
        except DegenerateGeometryError as exc:
            what = IN_BATCH.sub("", exc.message)
            raise DegenerateGeometryError(
                f"transition {t.name} ({t.op}): at the nominal values (without noise) "
                f"{what}; the inputs {', '.join(t.inputs)} do not define a {t.op}",
                **_where(plan, step),
            ) from None
        except (ArithmeticError, np.linalg.LinAlgError) as exc:
            out = np.full(1, np.nan)
            why = f" ({exc})"
        else:
            why = ""
        if not np.all(np.isfinite(out)):
            raise GraphError(
                f"transition {t.name} ({t.op}): the value is not finite at the nominal "
                f"values{why}; check the size of the numbers of {', '.join(t.inputs)}",
                **_where(plan, step),
            )
        values[t.out] = out
        kappa = _condition(plan, step, inputs, out)
        condition[t.name] = kappa
        if kappa > max_condition:
            where = f"{g.file}:{t.line}: " if g.file and t.line else ""
            notes.append(
                f"{where}transition {t.name} ({t.op}) is badly conditioned at its nominal "
                f"values: a deviation of its inputs grows {kappa:.3g} times (relative to the "
                f"size of the construction) in {t.out}"
            )
    for note in notes:
        warnings.warn(note, ConditioningWarning, stacklevel=2)
    return NominalReport(
        MappingProxyType({k: frozen_floats(v) for k, v in values.items()}),
        MappingProxyType(condition),
        tuple(notes),
    )


def _unflat(type_: str, flat: NDArray[np.float64]) -> Any:

    return unflatten(type_, flat[None, :])
