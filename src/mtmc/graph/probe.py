r"""The touch-probe point model of Stryczek (transition ``meas``).

Stryczek names three components of the uncertainty of a probed point: u1 of the axis
position (on every coordinate), u2 of the probe and u3 from the non-perpendicularity of
the probing movement to the surface (both along the probing direction). Its eq. 1 is
garbled in print; its text means

.. math:: u_w = \sqrt{u_1^2 + u_2^2 + u_3^2}

along the probing direction ``d`` (a unit vector), the other coordinates carrying u1
only. The probed point is ``at + e`` with

.. math:: e \sim N\left(0,\; u_1^2 I + (u_2^2 + u_3^2)\, d d^T\right).

Sampling (chosen for speed, the same law): ``e = u1 z + s z_d d`` with ``z`` three and
``z_d`` one independent standard normal, ``s = √(u2² + u3²)``. When the output is one
coordinate ``i`` (a place of type ``x``, ``y`` or ``z``), only ``e_i`` is needed, and
``at_i + e_i ~ N(at_i, u1² + s² d_i²)`` is drawn as one normal; when the output is a point and
``d`` lies along a machine axis, the covariance is diagonal and three normals suffice.
A ``dist`` on the transition replaces the normal law of the along-direction error
``s z_d`` by that distribution (then it is drawn apart from the u1 part).

The random inputs are named ``<transition>.<part>`` (``t1.e``, ``t1.x``, ``t1.dir``...)
and drawn by :func:`mtmc.uncertainty.iter_blocks`, so a run repeats exactly.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mtmc.errors import GraphError
from mtmc.graph.places import ProbeDefaults, Transition, finite_number
from mtmc.uncertainty.distributions import Distribution, Normal, parse_distribution

__all__ = ["MeasSpec", "meas_spec", "meas_inputs", "meas_value"]

_AXES = {"x": 0, "y": 1, "z": 2}


class MeasSpec:
    """The resolved parameters of one ``meas`` transition, in mm.

    Attributes
    ----------
    at : ndarray, shape (3,)
        Nominal probed point, mm.
    direction : ndarray, shape (3,)
        Unit probing direction.
    u_axis, u_along : float
        u1 and √(u2² + u3²), mm.
    dist : Distribution or None
        Law of the along-direction error (in the file's units), replacing ``u_along``.
    factor : float
        File length unit in mm.
    """

    __slots__ = ("at", "direction", "dist", "factor", "u_along", "u_axis")

    def __init__(
        self,
        at: NDArray[np.float64],
        direction: NDArray[np.float64],
        u_axis: float,
        u_along: float,
        dist: Distribution | None,
        factor: float,
    ) -> None:
        self.at = at
        self.direction = direction
        self.u_axis = u_axis
        self.u_along = u_along
        self.dist = dist
        self.factor = factor


def _vec(t: Transition, key: str) -> NDArray[np.float64]:
    v = t.param(key)
    line = t.field_line(key)
    if v is None:
        raise GraphError(
            f"transition {t.name}: meas needs {key} = [x, y, z]", line=t.line, field=key
        )
    if not isinstance(v, tuple) or len(v) != 3:
        raise GraphError(
            f"transition {t.name}: {key} must be a list of 3 numbers, got {v!r}",
            line=line,
            field=key,
        )
    return np.array([finite_number(x, f"transition {t.name}: {key}", key, line) for x in v])


def meas_spec(t: Transition, probe: ProbeDefaults, factor: float = 1.0) -> MeasSpec:
    """Resolve the fields of a ``meas`` transition, the ``[probe]`` defaults filling gaps.

    Parameters
    ----------
    t : Transition
        A ``meas`` transition.
    probe : ProbeDefaults
        The file's defaults.
    factor : float
        The file's length unit in mm (1 for mm, 1e-3 for µm).

    Returns
    -------
    MeasSpec
        The nominal point and direction and the standard uncertainties, mm.

    Raises
    ------
    GraphError
        If ``at`` or ``direction`` is missing or malformed, the direction is zero, a ``u`` is
        negative, or ``dist`` does not parse (naming the transition, line and field).
    """
    at = _vec(t, "at") * factor
    d = _vec(t, "direction")
    n = float(np.linalg.norm(d))
    if not n > 0:
        raise GraphError(
            f"transition {t.name}: the probing direction is zero",
            line=t.field_line("direction"),
            field="direction",
        )
    us = {}
    for key in ("u_axis", "u_probe", "u_perp"):
        v = finite_number(
            t.param(key, getattr(probe, key)), f"transition {t.name}", key, t.field_line(key)
        )
        if v < 0:
            raise GraphError(
                f"transition {t.name}: {key} must be a number >= 0, got {v!r}",
                line=t.field_line(key),
                field=key,
            )
        us[key] = v * factor
    dist = None
    text = t.param("dist")
    if text is not None:
        if not isinstance(text, str):
            raise GraphError(
                f"transition {t.name}: dist must be a string",
                line=t.field_line("dist"),
                field="dist",
            )
        try:
            dist = parse_distribution(text)
        except ValueError as exc:
            raise GraphError(
                f"transition {t.name}: {getattr(exc, 'message', exc)}",
                line=t.field_line("dist"),
                field="dist",
            ) from exc
    return MeasSpec(at, d / n, us["u_axis"], math.hypot(us["u_probe"], us["u_perp"]), dist, factor)


def meas_inputs(name: str, spec: MeasSpec, out_type: str) -> dict[str, Distribution]:
    """The random inputs of one ``meas`` transition (see the module docstring).

    Parameters
    ----------
    name : str
        The transition name (prefix of the input names).
    spec : MeasSpec
        Its resolved parameters.
    out_type : str
        ``"point"``, ``"x"``, ``"y"`` or ``"z"``.

    Returns
    -------
    dict of str to Distribution
        Zero standard uncertainties give no input (the value is then exact).
    """
    d = spec.direction
    out: dict[str, Distribution] = {}
    if spec.dist is None:
        if out_type in _AXES:
            i = _AXES[out_type]
            s = math.sqrt(spec.u_axis**2 + (spec.u_along * d[i]) ** 2)
            if s > 0:
                out[f"{name}.e"] = Normal(float(spec.at[i]), s)
            return out
        if np.count_nonzero(d) == 1:
            for i, c in enumerate("xyz"):
                s = math.sqrt(spec.u_axis**2 + (spec.u_along * d[i]) ** 2)
                if s > 0:
                    out[f"{name}.{c}"] = Normal(0.0, s)
            return out
    if spec.u_axis > 0:
        for c in "xyz" if out_type == "point" else out_type:
            out[f"{name}.{c}"] = Normal(0.0, spec.u_axis)
    if spec.dist is not None:
        out[f"{name}.dir"] = spec.dist
    elif spec.u_along > 0:
        out[f"{name}.dir"] = Normal(0.0, spec.u_along)
    return out


def meas_value(
    name: str, spec: MeasSpec, out_type: str, samples: Mapping[str, Any], m: int
) -> NDArray[np.float64]:
    """The probed point (``(m, 3)``) or coordinate (``(m,)``) of one ``meas``, mm.

    Parameters
    ----------
    name : str
        The transition name.
    spec : MeasSpec
        Its resolved parameters.
    out_type : str
        ``"point"``, ``"x"``, ``"y"`` or ``"z"``.
    samples : mapping
        The block's samples of the inputs made by :func:`meas_inputs`.
    m : int
        Trials in the block.

    Returns
    -------
    ndarray, shape (m, 3) or (m,)
        ``at + e`` (or one coordinate of it), mm.
    """
    d = spec.direction
    along = samples.get(f"{name}.dir")
    if out_type in _AXES:
        i = _AXES[out_type]
        if f"{name}.e" in samples:  # at_i + e_i drawn as one normal (read-only view)
            return np.asarray(samples[f"{name}.e"])
        val = np.full(m, spec.at[i])
        c = f"{name}.{out_type}"
        if c in samples:
            val += samples[c]
        if along is not None:
            val += (d[i] * spec.factor if spec.dist is not None else d[i]) * np.asarray(along)
        return val
    val = np.empty((m, 3))
    val[:] = spec.at
    for i, c in enumerate("xyz"):
        key = f"{name}.{c}"
        if key in samples:
            val[:, i] += samples[key]
    if along is not None:
        scale = spec.factor if spec.dist is not None else 1.0
        val += (scale * np.asarray(along))[:, None] * d
    return val
