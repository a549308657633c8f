"""The parameters of the circular test (ISO 230-4) from their definitions, on batched traces.

A trace is the radial deviation ``ΔR_i`` (mm) of the actual path from the nominal circle
of radius ``R`` at the angles ``θ_i`` (rad, measured in the plane of the test from its
first axis towards its second), one path per direction of contouring: counter-clockwise
(``ccw``, the angle increasing) and clockwise (``cw``). Every function takes the
deviations as an array ``(M, n)`` (one row per Monte Carlo trial, or ``M = 1`` for a
measured trace) and returns ``(M,)``.

Centres are found in the linear (limaçon) approximation of a ballbar trace: moving the
centre of reference by ``(a, b)`` changes the radial deviation by
``-a cos θ - b sin θ``, exact to ``(a² + b²) / 2R`` (for ``a, b`` of 50 µm and ``R`` of
100 mm, 0.0125 µm). Within it:

- the least-squares circle (LSC) minimises ``Σ (ΔR_i - c - a cos θ_i - b sin θ_i)²``
  (a linear fit; its centre agrees with the orthogonal-distance fit of
  :func:`mtmc.geometry.fit_circle` to second order in ``ΔR / R``);
- the minimum-zone circle (MZ) minimises the range of ``ΔR_i - a cos θ_i - b sin θ_i``:
  the Chebyshev approximation of the trace by ``c + a cos θ + b sin θ``, found by the
  discrete Remez exchange with single-point (Stiefel) exchange, all trials at once. On
  distinct angles the three functions form a Haar system on the circle, so the optimum
  is levelled at four points of alternating sign and the exchange ends in finitely
  many steps.

The parameters (ISO 230-4:2005, §3):

- ``F_max``, ``F_min``: the largest and smallest radial deviation from the nominal
  radius ``R`` about the centre given by the set-up (``centre="setup"``, the deviation
  as read) or by the LSC (``centre="lsc"``: the LSC's centre, the nominal radius);
- ``G_lsc``: the circular deviation, the range of the radial deviations about the LSC
  centre (the radial separation of the two circles about that centre enveloping the
  path);
- ``G_mz``: the same about the minimum-zone centre (the least radial separation of two
  concentric circles enveloping the path); ``G_mz <= G_lsc`` always;
- ``H``: the circular hysteresis, the largest radial difference between the CW and the
  CCW path at the same angle (the CW path interpolated linearly, periodically, onto the
  CCW angles when they differ); a common centre cancels from the difference to first
  order, so H needs none;
- ``G_b``: the bidirectional circular deviation, the range of both paths together about
  their common LSC centre.

With both directions, ``F_max`` and ``F_min`` are taken over both paths and ``G_lsc`` and
``G_mz`` are the larger of the two directions; each direction's value is also given
(``G_lsc_ccw``, ``G_lsc_cw``, ...).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Literal

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import ConvergenceError, InputError

__all__ = [
    "SYMBOLS",
    "check_angles",
    "check_trace",
    "lsc_fit",
    "minimum_zone",
    "periodic_interpolation",
    "hysteresis",
    "circular_parameters",
    "summary",
]

_F = NDArray[np.float64]

#: The summary parameters, in the order of the outputs of a test.
SYMBOLS: tuple[str, ...] = ("F_max", "F_min", "G_lsc", "G_mz", "H", "G_b")

_TWO_PI = 2.0 * np.pi


def check_angles(theta: npt.ArrayLike, field: str = "theta") -> _F:
    """Angles (rad) of a trace: finite, 1-D, at least 4, distinct modulo 2π.

    Returns
    -------
    ndarray, shape (n,)
        The angles reduced to ``[0, 2π)``, in the given order.

    Raises
    ------
    InputError
        On a bad shape, a non-finite angle, fewer than 4 angles or a repeated angle.
    """
    t = np.asarray(theta, dtype=np.float64)
    if t.ndim != 1 or t.size < 4:
        raise InputError(
            f"expected at least 4 angles in a 1-D array, got shape {t.shape}", field=field
        )
    if not np.all(np.isfinite(t)):
        raise InputError("expected finite angles", field=field)
    t = np.mod(t, _TWO_PI)
    s = np.sort(t)
    gaps = np.diff(np.concatenate([s, s[:1] + _TWO_PI]))
    if np.min(gaps) <= 1e-12:
        raise InputError(
            "expected distinct angles within one turn (the overrun of a test is left out "
            "of its evaluation)",
            field=field,
        )
    return t


def check_trace(dev: npt.ArrayLike, n: int, field: str = "deviation") -> _F:
    """Deviations ``(M, n)`` (or ``(n,)`` for one trace), finite."""
    d = np.asarray(dev, dtype=np.float64)
    if d.ndim == 1:
        d = d[None, :]
    if d.ndim != 2 or d.shape[1] != n:
        raise InputError(
            f"expected deviations of shape (M, {n}) or ({n},), got shape {d.shape}", field=field
        )
    if not np.all(np.isfinite(d)):
        raise InputError("expected finite deviations", field=field)
    return d


def _basis(theta: _F) -> _F:
    """``[1, cos θ, sin θ]``, shape (n, 3)."""
    return np.stack([np.ones_like(theta), np.cos(theta), np.sin(theta)], axis=1)


def lsc_fit(theta: npt.ArrayLike, dev: npt.ArrayLike) -> tuple[_F, _F]:
    """The least-squares circle of traces in the limaçon approximation.

    Parameters
    ----------
    theta : array_like, shape (n,)
        Angles, rad (distinct within a turn).
    dev : array_like, shape (M, n) or (n,)
        Radial deviations from the nominal radius, mm.

    Returns
    -------
    coefficients : ndarray, shape (M, 3)
        ``(c, a, b)``: the LSC's radius minus the nominal one, and its centre in the
        plane's two axes, relative to the centre of the trace, mm.
    residuals : ndarray, shape (M, n)
        ``ΔR_i - c - a cos θ_i - b sin θ_i``: the deviations from the LSC.

    Examples
    --------
    A trace offset by 2 µm along the first axis, its radius 1 µm long:

    >>> t = np.linspace(0, 2 * np.pi, 8, endpoint=False)
    >>> coef, res = lsc_fit(t, 0.001 + 0.002 * np.cos(t))
    >>> np.round(coef, 12) + 0.0
    array([[0.001, 0.002, 0.   ]])
    """
    t = check_angles(theta)
    d = check_trace(dev, t.size)
    B = _basis(t)
    # one pseudo-inverse for every trial: the angles are shared (the small factors made
    # contiguous: a transposed one sends matmul off BLAS)
    coef = d @ np.ascontiguousarray(np.linalg.pinv(B).T)
    return coef, d - coef @ np.ascontiguousarray(B.T)


def minimum_zone(
    theta: npt.ArrayLike, dev: npt.ArrayLike, *, max_iterations: int = 500
) -> tuple[_F, _F]:
    """The minimum-zone circle of traces (module docstring), by the Remez exchange.

    Parameters
    ----------
    theta : array_like, shape (n,)
        Angles, rad, distinct within a turn (``n >= 4``).
    dev : array_like, shape (M, n) or (n,)
        Radial deviations, mm.
    max_iterations : int
        Largest number of exchanges.

    Returns
    -------
    width : ndarray, shape (M,)
        The zone's radial width ``G_mz``, mm.
    coefficients : ndarray, shape (M, 3)
        ``(c, a, b)``: the mid-radius of the zone minus the nominal radius, and the zone's
        centre, mm.

    Raises
    ------
    ConvergenceError
        If some trial has not converged in ``max_iterations`` (a trace of NaN-free,
        distinct-angle data converges in a few tens).

    Examples
    --------
    Four points of a square, deviations alternating ±1 µm: no centre shift can narrow
    the zone below 2 µm.

    >>> w, coef = minimum_zone(np.radians([0, 90, 180, 270]), [0.001, -0.001, 0.001, -0.001])
    >>> float(w[0].round(12))
    0.002
    """
    t = check_angles(theta)
    d = check_trace(dev, t.size)
    order = np.argsort(t, kind="stable")
    ts = t[order]
    ds = d[:, order]
    B = _basis(ts)
    BT = np.ascontiguousarray(B.T)
    m = ds.shape[0]
    scale = float(np.max(np.abs(ds))) if ds.size else 0.0
    ref = _start(ts, ds - (ds @ np.ascontiguousarray(np.linalg.pinv(B).T)) @ BT)
    sigma = np.array([1.0, -1.0, 1.0, -1.0])
    coef = np.zeros((m, 3))
    h = np.zeros(m)
    active = np.arange(m)
    for _ in range(max_iterations):
        r = ref[active]
        da = ds if active.size == m else ds[active]
        S = np.concatenate([B[r], np.broadcast_to(sigma, (r.shape[0], 4))[..., None]], axis=2)
        rhs = np.take_along_axis(da, r, axis=1)
        sol = np.linalg.solve(S, rhs[..., None])[..., 0]
        coef[active] = sol[:, :3]
        h[active] = sol[:, 3]
        e = da - sol[:, :3] @ BT
        j = np.argmax(np.abs(e), axis=1)
        ej = np.take_along_axis(e, j[:, None], axis=1)[:, 0]
        done = np.abs(ej) <= np.abs(sol[:, 3]) * (1.0 + 1e-12) + 1e-15 * scale
        keep = ~done
        if not np.any(keep):
            active = active[:0]
            break
        active, r, e, j, ej = active[keep], r[keep], e[keep], j[keep], ej[keep]
        # Stiefel exchange: j enters between two neighbours (cyclically) whose residuals
        # have opposite signs; it replaces the one whose sign it shares
        pos = np.sum(r < j[:, None], axis=1)
        rows = np.arange(r.shape[0])
        left = (pos - 1) % 4
        right = pos % 4
        sl = np.sign(e[rows, r[rows, left]])
        out = np.where(sl == np.sign(ej), left, right)
        r[rows, out] = j
        ref[active] = np.sort(r, axis=1)
    if active.size:
        raise ConvergenceError(
            f"the minimum-zone circle did not converge in {max_iterations} exchanges for "
            f"{active.size} of {m} traces"
        )
    return 2.0 * np.abs(h), coef


def _start(theta: _F, r: _F) -> NDArray[np.int64]:
    """A first reference of four points for the exchange, from the LSC residuals ``r``.

    ``theta`` sorted. The circle in eight octants; quadrants of two octants from the
    octant of the largest residual on: the largest residual in the first and third, the
    smallest in the second and fourth (the alternation of the two-lobed traces of
    squareness, scale mismatch and servo mismatch). Any four distinct points would do;
    these save exchanges. With an empty octant, four points a quarter turn apart.
    """
    m, n = r.shape
    octant = np.minimum((theta // (0.25 * np.pi)).astype(np.int64), 7)
    counts = np.bincount(octant, minlength=8)
    if np.any(counts == 0):
        return np.tile((np.arange(4) * n) // 4, (m, 1))
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    width = int(counts.max())
    # the points of each octant, padded with its last point: (8, width)
    idx = np.minimum(starts[:, None] + np.arange(width), (starts + counts - 1)[:, None])
    g = r[:, idx]  # (m, 8, width)
    imax = np.take_along_axis(idx[None], np.argmax(g, axis=2)[..., None], 2)[..., 0]
    imin = np.take_along_axis(idx[None], np.argmin(g, axis=2)[..., None], 2)[..., 0]
    vmax = np.take_along_axis(r, imax, axis=1)
    vmin = np.take_along_axis(r, imin, axis=1)
    top = np.argmax(vmax, axis=1)
    rows = np.arange(m)
    ref = np.empty((m, 4), dtype=np.int64)
    for k in range(4):
        o1 = (top + 2 * k) % 8
        o2 = (top + 2 * k + 1) % 8
        if k % 2 == 0:
            first = vmax[rows, o1] >= vmax[rows, o2]
            ref[:, k] = np.where(first, imax[rows, o1], imax[rows, o2])
        else:
            first = vmin[rows, o1] <= vmin[rows, o2]
            ref[:, k] = np.where(first, imin[rows, o1], imin[rows, o2])
    return np.sort(ref, axis=1)


def periodic_interpolation(
    theta_from: npt.ArrayLike, theta_to: npt.ArrayLike
) -> tuple[NDArray[np.int64], NDArray[np.int64], _F]:
    """Indices and weights of linear interpolation on the circle: ``y_to = (1-w) y[i0] + w y[i1]``.

    Parameters
    ----------
    theta_from : array_like, shape (n,)
        Angles of the data, rad, distinct within a turn.
    theta_to : array_like, shape (k,)
        Angles wanted, rad.

    Returns
    -------
    i0, i1 : ndarray of int, shape (k,)
    w : ndarray, shape (k,)
    """
    tf = check_angles(theta_from, "theta_from")
    tt = np.mod(np.asarray(theta_to, dtype=np.float64), _TWO_PI)
    order = np.argsort(tf, kind="stable")
    s = tf[order]
    ext = np.concatenate([s[-1:] - _TWO_PI, s, s[:1] + _TWO_PI])
    idx = np.concatenate([order[-1:], order, order[:1]])
    k = np.clip(np.searchsorted(ext, tt, side="right") - 1, 0, ext.size - 2)
    w = (tt - ext[k]) / (ext[k + 1] - ext[k])
    return idx[k].astype(np.int64), idx[k + 1].astype(np.int64), w


def hysteresis(
    theta_ccw: npt.ArrayLike,
    ccw: npt.ArrayLike,
    theta_cw: npt.ArrayLike,
    cw: npt.ArrayLike,
) -> _F:
    """Circular hysteresis ``H``: ``max_θ |ΔR_cw(θ) - ΔR_ccw(θ)|`` at the CCW angles, (M,).

    Examples
    --------
    >>> t = np.radians([0, 90, 180, 270])
    >>> float(hysteresis(t, [[0.0, 0.001, 0.0, 0.0]], t, [[0.0, -0.002, 0.0, 0.0]])[0])
    0.003
    """
    ta = check_angles(theta_ccw, "theta_ccw")
    tb = check_angles(theta_cw, "theta_cw")
    a = check_trace(ccw, ta.size, "ccw")
    b = check_trace(cw, tb.size, "cw")
    if ta.size == tb.size and np.array_equal(ta, tb):
        bi = b
    else:
        i0, i1, w = periodic_interpolation(tb, ta)
        bi = (1.0 - w) * b[:, i0] + w * b[:, i1]
    return np.asarray(np.max(np.abs(bi - a), axis=1), dtype=np.float64)


def _range(x: _F) -> _F:
    return np.asarray(np.max(x, axis=1) - np.min(x, axis=1), dtype=np.float64)


def circular_parameters(
    *,
    theta_ccw: npt.ArrayLike | None = None,
    ccw: npt.ArrayLike | None = None,
    theta_cw: npt.ArrayLike | None = None,
    cw: npt.ArrayLike | None = None,
    centre: Literal["setup", "lsc"] = "lsc",
) -> dict[str, _F]:
    """Every ISO 230-4 parameter of one or two traces (module docstring).

    Parameters
    ----------
    theta_ccw, ccw : array_like, shape (n,) and (M, n), optional
        Angles (rad) and radial deviations (mm) of the counter-clockwise path.
    theta_cw, cw : array_like, shape (k,) and (M, k), optional
        The same of the clockwise path.
    centre : {"lsc", "setup"}
        The centre of ``F``: the LSC's (of each direction) or the set-up's.

    Returns
    -------
    dict of str to ndarray (M,)
        ``F_max``, ``F_min``, ``G_lsc``, ``G_mz`` and per direction ``F_max_ccw``,
        ``G_lsc_ccw``, ... ; with both directions also ``H`` and ``G_b``. In mm.

    Raises
    ------
    InputError
        Without a trace, with angles without deviations, or an unknown centre.
    """
    if centre not in ("setup", "lsc"):
        raise InputError(f"expected centre 'setup' or 'lsc', got {centre!r}", field="centre")
    paths: dict[str, tuple[_F, _F]] = {}
    for name, t, d in (("ccw", theta_ccw, ccw), ("cw", theta_cw, cw)):
        if (t is None) != (d is None):
            raise InputError(f"expected both the angles and the deviations of {name}", field=name)
        if t is not None and d is not None:
            ta = check_angles(t, f"theta_{name}")
            paths[name] = (ta, check_trace(d, ta.size, name))
    if not paths:
        raise InputError("expected at least one trace (ccw or cw)", field="ccw")
    out: dict[str, _F] = {}
    for name, (t, d) in paths.items():
        coef, res = lsc_fit(t, d)
        f = d if centre == "setup" else res + coef[:, :1]
        out[f"F_max_{name}"] = np.max(f, axis=1)
        out[f"F_min_{name}"] = np.min(f, axis=1)
        out[f"G_lsc_{name}"] = _range(res)
        out[f"G_mz_{name}"] = minimum_zone(t, d)[0]
    names = list(paths)
    for sym, red in (("F_max", np.maximum), ("F_min", np.minimum), ("G_lsc", np.maximum)):
        out[sym] = red.reduce([out[f"{sym}_{k}"] for k in names])
    out["G_mz"] = np.maximum.reduce([out[f"G_mz_{k}"] for k in names])
    if len(paths) == 2:
        (ta, a), (tb, b) = paths["ccw"], paths["cw"]
        out["H"] = hysteresis(ta, a, tb, b)
        _, res = _lsc_joint(ta, a, tb, b)
        out["G_b"] = _range(res)
    return out


def _lsc_joint(ta: _F, a: _F, tb: _F, b: _F) -> tuple[_F, _F]:
    """The LSC of both paths together (one centre, one radius): coefficients, residuals."""
    B = np.concatenate([_basis(ta), _basis(tb)])
    d = np.concatenate([a, b], axis=1)
    coef = d @ np.ascontiguousarray(np.linalg.pinv(B).T)
    return coef, d - coef @ np.ascontiguousarray(B.T)


def summary(values: Mapping[str, _F]) -> dict[str, float]:
    """The first trial of each parameter as floats (a measured trace, ``M = 1``)."""
    return {k: float(np.asarray(v)[0]) for k, v in values.items()}
