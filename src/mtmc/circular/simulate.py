"""A circular or rotary-axis test simulated on a machine model: the exact and the first-order route.

**Circular test (ISO 230-4).** The programmed path is a circle of radius ``R`` in the
plane of two linear axes, about the axis positions ``centre``, at the angles ``θ_i``
(one turn; the overrun arcs at either end are not evaluated and are not simulated: each
axis is taken in continuous motion). The table ball sits at the nominal tool point of
the centre, moved by the set-up's offset; the tool ball is the machine's tool point.

The *exact route* (:func:`simulate_circle`) drives the commanded positions through the
axes' own effects, which a static model lacks (:class:`AxisEffects`: backlash, a servo
lag, reversal spikes, a screw's cyclic error), then through the machine's exact forward
kinematics with its ISO 230-1 / 230-7 errors (:meth:`mtmc.kinematics.Machine.tool_position`
with ``exact=True``), and reads ``|P_tool - P_ball| - R``.

The *first-order route* (:func:`first_order_circle`) projects the error vector on the
ballbar's direction: ``ΔR = n · (J_e e + J_q δq - o)`` with ``J_e`` the Jacobian of the
tool point with respect to the errors (:meth:`~mtmc.kinematics.Machine.jacobian`),
``δq`` the axes' own effects to first order, ``J_q`` the nominal Jacobian with respect
to the axis positions, and ``o`` the table ball's offset. The two agree to second order
in the errors (tested).

**Rotary-axis test (ISO 10791-6 kinematic tests).** A rotary axis turns through its
positions while the linear axes follow so that the nominal tool point stays at a fixed
point of the workpiece frame (:func:`follow_positions`, exact: the nominal tool point is
affine in the linear axes at fixed rotary positions). An R-test reads the 3-D
displacement of the tool-side sphere relative to its nest on the table,
``P_tool - p`` in the workpiece frame (:func:`rotary_displacement`); a ballbar along a
fixed direction ``n`` of the workpiece frame reads ``|P_tool - (p - L n)| - L``
(:func:`rotary_ballbar`). :func:`rotary_design` gives the first-order design ``J_e`` of
either, for the identification of the rotary axis' location errors.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.circular.model import _since_reversal, check_plane
from mtmc.circular.parameters import check_angles
from mtmc.errors import InputError
from mtmc.frozen import frozen_mapping
from mtmc.kinematics import Machine
from mtmc.kinematics.topology import is_linear

__all__ = [
    "AxisEffects",
    "circle_positions",
    "simulate_circle",
    "first_order_circle",
    "follow_positions",
    "rotary_displacement",
    "rotary_ballbar",
    "rotary_design",
]

_F = NDArray[np.float64]


@dataclass(frozen=True)
class AxisEffects:
    """The effects of the axes' drives a static error model lacks (``docs/circular.md``).

    Each mapping is by axis letter; a value is a number or an array ``(M,)`` (one per
    trial).

    Attributes
    ----------
    backlash : mapping of str to float or array
        ``b``, mm: the axis lags its command by ``b/2`` in its direction of motion.
    lag : mapping of str to float or array
        ``τ``, s: the axis follows its command late by ``τ``.
    spike : mapping of str to float or array
        ``p``, mm: after each reversal the axis sticks by ``p exp(-φ/φ₀)``, against its
        new direction, ``φ`` the path angle travelled since.
    spike_decay : float
        ``φ₀``, rad.
    cyclic : mapping of str to (period, a, b)
        A screw's cyclic error ``a cos(2π q/P) + b sin(2π q/P)``, mm.
    """

    backlash: Mapping[str, Any] = field(default_factory=dict)
    lag: Mapping[str, Any] = field(default_factory=dict)
    spike: Mapping[str, Any] = field(default_factory=dict)
    spike_decay: float = float(np.radians(3.0))
    cyclic: Mapping[str, tuple[float, Any, Any]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("backlash", "lag", "spike", "cyclic"):
            object.__setattr__(self, name, frozen_mapping(dict(getattr(self, name))))
        if not (np.isfinite(self.spike_decay) and self.spike_decay > 0):
            raise InputError(
                f"expected a decay angle > 0, got {self.spike_decay!r}", field="spike_decay"
            )

    def axes(self) -> set[str]:
        """Every axis named."""
        return {*self.backlash, *self.lag, *self.spike, *self.cyclic}


def _col(v: Any) -> _F:
    """A number or an array (M,) as a column (M, 1) (or (1, 1))."""
    a = np.asarray(v, dtype=np.float64)
    if a.ndim > 1 or not np.all(np.isfinite(a)):
        raise InputError(f"expected a finite number or an array (M,), got {v!r}", field="effects")
    return a.reshape(-1, 1)


def circle_positions(
    machine: Machine,
    theta: npt.ArrayLike,
    *,
    radius: float,
    plane: str = "XY",
    centre: Mapping[str, float] | None = None,
) -> _F:
    """Commanded axis positions ``(n, n_axes)`` of a circle (rotary axes at ``centre`` or 0)."""
    u, v, _ = check_plane(plane)
    for ax in (u, v):
        if ax not in machine.axes:
            raise InputError(f"machine {machine.topology} has no axis {ax}", field="plane")
    t = np.asarray(theta, dtype=np.float64)
    c = {ax: 0.0 for ax in machine.axes}
    for ax, val in (centre or {}).items():
        if ax not in c:
            raise InputError(f"machine {machine.topology} has no axis {ax}", field="centre")
        c[ax] = float(val)
    q = np.tile([c[ax] for ax in machine.axes], (t.size, 1))
    q[:, machine.axes.index(u)] += radius * np.cos(t)
    q[:, machine.axes.index(v)] += radius * np.sin(t)
    return q


def _effects(
    machine: Machine,
    effects: AxisEffects,
    theta: _F,
    d: float,
    radius: float,
    feed: float,
    plane: str,
    centre: Mapping[str, float] | None,
    exact: bool,
) -> _F:
    """The axes' own displacements ``δq`` (M, n, n_axes) along the path of direction d."""
    u, v, _ = check_plane(plane)
    unknown = effects.axes() - {u, v}
    if unknown:
        raise InputError(
            f"axis effects on {sorted(unknown)[0]}, which the {plane} circle does not move",
            field="effects",
        )
    q0 = circle_positions(machine, theta, radius=radius, plane=plane, centre=centre)
    n = theta.size
    parts: dict[str, _F] = {}
    for ax, trig, at in ((u, np.cos, 0.0), (v, np.sin, 0.5 * np.pi)):
        k = machine.axes.index(ax)
        # sign of the axis' velocity: d/dθ of cos is -sin, of sin is cos
        vel = d * (-np.sin(theta) if ax == u else np.cos(theta))
        dq = np.zeros((1, n))
        if ax in effects.backlash:
            dq = dq - 0.5 * _col(effects.backlash[ax]) * np.sign(vel)
        if ax in effects.lag:
            tau = _col(effects.lag[ax])
            phase = d * feed / radius * tau  # the angle the path has moved on in τ
            if exact:
                dq = dq + radius * (trig(theta - phase) - trig(theta))
            else:
                dq = dq - tau * feed * vel  # -τ u̇, u̇ = v_f (du/dθ) d
        if ax in effects.spike:
            phi = _since_reversal(theta, np.full(n, d), at)
            dq = dq - _col(effects.spike[ax]) * np.sign(vel) * np.exp(-phi / effects.spike_decay)
        if ax in effects.cyclic:
            period, a, b = effects.cyclic[ax]
            arg = 2.0 * np.pi * q0[:, k] / float(period)
            dq = dq + _col(a) * np.cos(arg) + _col(b) * np.sin(arg)
        parts[ax] = dq
    m = max(p.shape[0] for p in parts.values())
    out = np.zeros((m, n, machine.n_axes))
    for ax, dq in parts.items():
        out[:, :, machine.axes.index(ax)] = dq
    return out


def _batch_errors(errors: Mapping[str, Any] | None, m: int, n: int) -> dict[str, Any]:
    """Errors as arrays (M n,): a trial axis (M,) repeated for each of n points.

    Constants are given as arrays too: the exact rotations of a constant squareness are
    not precomputed by the kinematics' column program (a constant ``EC0Y`` with
    ``exact=True`` fails there), while an array of values takes the general path.
    """
    out: dict[str, Any] = {}
    for k, val in (errors or {}).items():
        if isinstance(val, (int, float, np.ndarray, list, tuple)):
            a = np.asarray(val, dtype=np.float64)
            if a.ndim == 1 and a.size > 1:
                if a.size != m:
                    raise InputError(f"expected {m} values (one a trial), got {a.size}", field=k)
                a = np.repeat(a, n)
            else:
                a = np.full(m * n, float(a.reshape(-1)[0]) if a.size else np.nan)
            out[k] = a
        else:
            out[k] = val
    return out


def _trials(errors: Mapping[str, Any] | None, *arrays: Any) -> int:
    sizes = {np.asarray(v).size for v in (errors or {}).values() if np.ndim(v) == 1}
    sizes |= {np.asarray(a).size for a in arrays if np.ndim(a) == 1}
    sizes.discard(1)
    if len(sizes) > 1:
        raise InputError(f"the trial axes do not match: {sorted(sizes)}", field="errors")
    return sizes.pop() if sizes else 1


def simulate_circle(
    machine: Machine,
    theta: npt.ArrayLike,
    *,
    radius: float,
    direction: int = 1,
    plane: str = "XY",
    centre: Mapping[str, float] | None = None,
    feed: float = 1000.0 / 60.0,
    errors: Mapping[str, Any] | None = None,
    effects: AxisEffects | None = None,
    offset: npt.ArrayLike = (0.0, 0.0, 0.0),
) -> _F:
    """The ballbar trace of a circle by the exact route (module docstring).

    Parameters
    ----------
    machine : Machine
    theta : array_like, shape (n,)
        Angles of the points, rad.
    radius : float
        ``R``, mm (the ballbar's length).
    direction : {1, -1}
        ``1`` counter-clockwise, ``-1`` clockwise.
    plane, centre, feed
        The circle's plane (``XY``, ``YZ``, ``ZX``), centre (axis positions) and feed (mm/s).
    errors : mapping, optional
        ISO 230-1 / 230-7 errors as :meth:`~mtmc.kinematics.Machine.tool_position` takes
        them; a value may be an array ``(M,)``.
    effects : AxisEffects, optional
    offset : array_like, shape (3,) or (M, 3)
        The table ball's position relative to the nominal centre, in the workpiece frame,
        mm.

    Returns
    -------
    ndarray, shape (M, n)
        ``ΔR``, mm.
    """
    t = check_angles(theta)
    d = _direction(direction)
    eff = effects or AxisEffects()
    off = np.asarray(offset, dtype=np.float64).reshape(-1, 3)
    dq = _effects(machine, eff, t, d, radius, feed, plane, centre, exact=True)
    m = max(_trials(errors), dq.shape[0], off.shape[0])
    n = t.size
    q = circle_positions(machine, t, radius=radius, plane=plane, centre=centre)
    qa = np.broadcast_to(q[None] + dq, (m, n, machine.n_axes)).reshape(m * n, -1)
    errs = _batch_errors(errors, m, n)
    P = machine.tool_position(qa, errs, exact=True).reshape(m, n, 3)
    c0 = _nominal_centre(machine, q)
    ball = c0 + off[:, None, :]
    return np.asarray(np.linalg.norm(P - ball, axis=2) - radius, dtype=np.float64)


def _direction(direction: int) -> float:
    if direction not in (1, -1):
        raise InputError(
            f"expected direction 1 (CCW) or -1 (CW), got {direction!r}", field="direction"
        )
    return float(direction)


def _nominal_centre(machine: Machine, q: _F) -> _F:
    """The nominal tool point of the circle's centre: the mean over a full turn."""
    return np.asarray(machine.tool_position(q).mean(axis=0), dtype=np.float64)


def _axis_jacobian(machine: Machine, q: _F) -> _F:
    """``∂P/∂q`` of the nominal tool point ``(n, 3, n_axes)``, by central differences.

    Exact (to rounding) for linear axes, in which the nominal tool point is affine.
    """
    h = 1.0
    cols = []
    for k in range(machine.n_axes):
        e = np.zeros(machine.n_axes)
        e[k] = h if is_linear(machine.axes[k]) else 1e-6
        cols.append((machine.tool_position(q + e) - machine.tool_position(q - e)) / (2 * e[k]))
    return np.stack(cols, axis=2)


def first_order_circle(
    machine: Machine,
    theta: npt.ArrayLike,
    *,
    radius: float,
    direction: int = 1,
    plane: str = "XY",
    centre: Mapping[str, float] | None = None,
    feed: float = 1000.0 / 60.0,
    errors: Mapping[str, Any] | None = None,
    effects: AxisEffects | None = None,
    offset: npt.ArrayLike = (0.0, 0.0, 0.0),
) -> _F:
    """The same trace as :func:`simulate_circle` by the first-order route, ``(M, n)``."""
    t = check_angles(theta)
    d = _direction(direction)
    eff = effects or AxisEffects()
    q = circle_positions(machine, t, radius=radius, plane=plane, centre=centre)
    nvec = machine.tool_position(q) - _nominal_centre(machine, q)
    nvec = nvec / np.linalg.norm(nvec, axis=1, keepdims=True)
    dq = _effects(machine, eff, t, d, radius, feed, plane, centre, exact=False)
    e = np.einsum("nij,mnj->mni", _axis_jacobian(machine, q), dq)
    if errors:
        names = list(errors)
        vals = machine.error_values(q, {k: v for k, v in errors.items() if np.ndim(v) == 0})
        J = machine.jacobian(q, None, names=names)  # (n, 3, p)
        cols = []
        for k in names:
            key = machine.error_term(k).name
            v = errors[k]
            cols.append(np.asarray(vals[key]) if np.ndim(v) == 0 else np.asarray(v)[:, None])
        m = max(np.atleast_2d(c).shape[0] for c in cols)
        V = np.stack([np.broadcast_to(np.atleast_2d(c), (m, t.size)) for c in cols], axis=2)
        e = e + np.einsum("nip,mnp->mni", J, V)
    off = np.asarray(offset, dtype=np.float64).reshape(-1, 3)
    e = e - off[:, None, :]
    return np.asarray(np.einsum("mni,ni->mn", e, nvec), dtype=np.float64)


def follow_positions(
    machine: Machine,
    rotary: Mapping[str, npt.ArrayLike],
    point: npt.ArrayLike,
) -> _F:
    """Axis positions ``(n, n_axes)`` that hold the nominal tool point at ``point``.

    Parameters
    ----------
    machine : Machine
    rotary : mapping of str to array_like (n,)
        The position of every rotary axis at each of the ``n`` steps, rad (a number for
        an axis held still).
    point : array_like, shape (3,)
        The point of the workpiece frame the tool point is to stay at, mm.

    Returns
    -------
    ndarray, shape (n, n_axes)
        The rotary positions as given and the linear axes solved for (exactly: the
        nominal tool point is affine in the linear axes at fixed rotary positions).

    Raises
    ------
    InputError
        On a missing or unknown rotary axis, or fewer than three linear axes.
    """
    lin = [k for k, ax in enumerate(machine.axes) if is_linear(ax)]
    rot = [ax for ax in machine.axes if not is_linear(ax)]
    if len(lin) != 3:
        raise InputError(f"expected three linear axes, machine {machine.topology}", field="machine")
    if set(rotary) != set(rot):
        raise InputError(
            f"expected positions of the rotary axes {' '.join(rot)}, got {' '.join(rotary)}",
            field="rotary",
        )
    arrs = np.broadcast_arrays(*(np.atleast_1d(np.asarray(rotary[a], float)) for a in rot))
    n = arrs[0].size
    q = np.zeros((n, machine.n_axes))
    for a, arr in zip(rot, arrs, strict=True):
        q[:, machine.axes.index(a)] = arr
    p = np.asarray(point, dtype=np.float64).reshape(3)
    base = machine.tool_position(q)
    J = np.empty((n, 3, 3))
    for j, k in enumerate(lin):
        e = np.zeros(machine.n_axes)
        e[k] = 1.0
        J[:, :, j] = machine.tool_position(q + e) - base
    x = np.linalg.solve(J, (p - base)[..., None])[..., 0]
    q[:, lin] = x
    return q


def rotary_displacement(
    machine: Machine,
    q: npt.ArrayLike,
    point: npt.ArrayLike,
    errors: Mapping[str, Any] | None = None,
    *,
    exact: bool = True,
) -> _F:
    """The R-test reading: ``P_tool - point`` in the workpiece frame, ``(M, n, 3)``, mm."""
    qa = machine.positions(q)
    n = qa.shape[0]
    m = _trials(errors)
    qq = np.broadcast_to(qa[None], (m, n, qa.shape[1])).reshape(m * n, -1)
    P = machine.tool_position(qq, _batch_errors(errors, m, n), exact=exact).reshape(m, n, 3)
    return np.asarray(P - np.asarray(point, dtype=np.float64).reshape(3), dtype=np.float64)


def rotary_ballbar(
    machine: Machine,
    q: npt.ArrayLike,
    point: npt.ArrayLike,
    direction: npt.ArrayLike,
    length: float,
    errors: Mapping[str, Any] | None = None,
) -> _F:
    """The ballbar reading ``|P_tool - (point - L n)| - L`` (exact kinematics), ``(M, n)``."""
    nvec = np.asarray(direction, dtype=np.float64).reshape(3)
    nvec = nvec / np.linalg.norm(nvec)
    e = rotary_displacement(machine, q, point, errors, exact=True)
    return np.asarray(np.linalg.norm(e + length * nvec, axis=2) - length, dtype=np.float64)


def rotary_design(
    machine: Machine,
    q: npt.ArrayLike,
    names: Sequence[str],
    direction: npt.ArrayLike | None = None,
) -> _F:
    """First-order design of a rotary test: ``(3 n, p)`` (R-test) or ``(n, p)`` (ballbar).

    The rows of the R-test are the x, y, z displacement of each step in turn; for a
    ballbar along ``direction``, ``n · J_e``.
    """
    J = machine.jacobian(q, None, names=list(names))  # (n, 3, p)
    if direction is None:
        return np.asarray(J.reshape(-1, J.shape[2]), dtype=np.float64)
    nvec = np.asarray(direction, dtype=np.float64).reshape(3)
    return np.asarray(np.einsum("i,nip->np", nvec / np.linalg.norm(nvec), J), dtype=np.float64)
