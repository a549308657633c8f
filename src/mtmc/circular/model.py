"""The first-order model of a circular test, ``ΔR(θ) = e(θ) · n(θ)``, and its identification.

The programmed path is a circle of radius ``R`` in the plane of two linear axes ``u``
and ``v`` (``XY``: u = X, v = Y; ``YZ``: Y, Z; ``ZX``: Z, X), the tool at
``p(θ) = c + R (cos θ, sin θ)``; ``n(θ) = (cos θ, sin θ)`` is the ballbar's direction,
``d = +1`` counter-clockwise (θ increasing) and ``d = -1`` clockwise, ``v_f`` the feed
(mm/s), ``ω = d v_f / R``. An error vector ``e = (Δu, Δv)`` of the tool relative to the
table ball changes the reading by ``ΔR = e · n`` to first order (the rest is
``|e|² / 2R`` at most). The errors, each a column of the design matrix, with the sign
conventions of ISO 230-1 (an error is a motion of the tool relative to the workpiece,
``docs/conventions.md``):

=================  ===========================================  ==========================
name               error                                         ``ΔR(θ)`` per unit
=================  ===========================================  ==========================
``radius``         the mean scale error of u and v times R,      ``1``
                   less the error of the ballbar's length
``centre_u``       the path's centre relative to the table       ``cos θ``
``centre_v``       ball, mm                                      ``sin θ``
``squareness``     ``S``: v tilted towards u, ``Δu = -v S``      ``-(R/2) sin 2θ``
                   (``EC0Y`` in XY, ``EA0Z`` in YZ, ``EB0X`` in
                   ZX: the angle between +u and +v is 90° + S)
``scale_mismatch`` ``ε_u - ε_v``, ``Δu = ε_u u``, ``Δv = ε_v v``  ``(R/2) cos 2θ``
``backlash_u``     ``b``: the axis lags its command by ``b/2``    ``(d/2) sgn(sin θ) cos θ``
                   in its direction of motion,
                   ``Δu = -(b/2) sgn(u̇)``; the trace steps out
                   by ``b`` at each reversal of u (θ = 0°, 180°)
``backlash_v``     the same of v (reversals at 90°, 270°)        ``-(d/2) sgn(cos θ) sin θ``
``servo_mismatch`` ``τ_u - τ_v``, s: each axis follows its        ``(d v_f / 2) sin 2θ``
                   command late by ``τ``, ``Δu = -τ_u u̇``; an
                   ellipse at ±45° whose tilt flips with d
``spike_u``        ``p``: after each reversal of u the axis       ``d sgn(sin θ) cos θ
                   sticks, ``Δu = -p sgn(u̇) exp(-φ/φ₀)``, φ the   exp(-φ/φ₀)``
                   angle travelled since the reversal
``spike_v``        the same of v                                 ``-d sgn(cos θ) sin θ
                                                                 exp(-φ/φ₀)``
``cyclic_u_cos``,  a screw's cyclic error of period ``P``,       ``cos θ cos(2π u/P)``,
``cyclic_u_sin``   ``Δu = a cos(2π u/P) + b sin(2π u/P)``,       ``cos θ sin(2π u/P)``
                   ``u`` the axis position
=================  ===========================================  ==========================

and ``cyclic_v_*`` likewise with ``sin θ``. The names of an identification replace u and
v by the axes' letters (``centre_x``, ``backlash_y``). A lag common to both axes changes
the radius by ``-R (ω τ)² / 2`` only: second order, and no column.

What one test cannot separate (:func:`structural_notes`): the mean scale of the two axes
from the ballbar's length (one column, ``radius``); any error of the axis normal to the
plane (no column); with one direction, the servo mismatch from the squareness (the same
``sin 2θ``; the other direction separates them, the lag's sign flipping with it).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.circular.parameters import check_angles, check_trace
from mtmc.errors import IdentifiabilityError, InputError
from mtmc.verification.identify import Identifiability, identifiability

__all__ = [
    "PLANES",
    "SQUARENESS_NAMES",
    "TERMS",
    "CircularDesign",
    "CircularIdentification",
    "design",
    "default_terms",
    "identify",
    "linear_identification",
    "structural_notes",
]

_F = NDArray[np.float64]

#: The planes of a circular test: (first axis, second axis, normal axis).
PLANES: dict[str, tuple[str, str, str]] = {
    "XY": ("X", "Y", "Z"),
    "YZ": ("Y", "Z", "X"),
    "ZX": ("Z", "X", "Y"),
}

#: The ISO 230-1 squareness that ``squareness`` is, by plane (see the module docstring).
SQUARENESS_NAMES: dict[str, str] = {"XY": "EC0Y", "YZ": "EA0Z", "ZX": "EB0X"}

#: The error terms of the model, with ``u``/``v`` for the plane's axes.
TERMS: tuple[str, ...] = (
    "radius",
    "centre_u",
    "centre_v",
    "squareness",
    "scale_mismatch",
    "backlash_u",
    "backlash_v",
    "servo_mismatch",
    "spike_u",
    "spike_v",
    "cyclic_u_cos",
    "cyclic_u_sin",
    "cyclic_v_cos",
    "cyclic_v_sin",
)

_UNITS = {
    "radius": "mm",
    "centre_u": "mm",
    "centre_v": "mm",
    "squareness": "rad",
    "scale_mismatch": "1",
    "backlash_u": "mm",
    "backlash_v": "mm",
    "servo_mismatch": "s",
    "spike_u": "mm",
    "spike_v": "mm",
}


def check_plane(plane: str) -> tuple[str, str, str]:
    """The axes of a plane name (``XY``, ``YZ``, ``ZX``; ``YX``, ``ZY``, ``XZ`` refused)."""
    key = str(plane).upper()
    if key not in PLANES:
        raise InputError(
            f"expected a plane XY, YZ or ZX (right-handed), got {plane!r}", field="plane"
        )
    return PLANES[key]


def _name(term: str, u: str, v: str) -> str:
    parts = term.split("_")
    if len(parts) >= 2 and parts[1] in ("u", "v"):
        parts[1] = (u if parts[1] == "u" else v).lower()
    return "_".join(parts)


def _since_reversal(theta: _F, d: _F, at: float) -> _F:
    """Angle travelled since the last reversal (reversals at ``at`` and ``at + π``)."""
    phi = np.mod(theta - at, np.pi)
    return np.where(d > 0, phi, np.mod(np.pi - phi, np.pi))


def _column(
    term: str,
    theta: _F,
    d: _F,
    radius: float,
    feed: float,
    decay: float,
    periods: tuple[float, float],
    centre: tuple[float, float],
) -> _F:
    c, s = np.cos(theta), np.sin(theta)
    if term == "radius":
        return np.ones_like(theta)
    if term == "centre_u":
        return c
    if term == "centre_v":
        return s
    if term == "squareness":
        return -0.5 * radius * np.sin(2.0 * theta)
    if term == "scale_mismatch":
        return 0.5 * radius * np.cos(2.0 * theta)
    if term == "backlash_u":
        return 0.5 * d * np.sign(s) * c
    if term == "backlash_v":
        return -0.5 * d * np.sign(c) * s
    if term == "servo_mismatch":
        return 0.5 * d * feed * np.sin(2.0 * theta)
    if term == "spike_u":
        return d * np.sign(s) * c * np.exp(-_since_reversal(theta, d, 0.0) / decay)
    if term == "spike_v":
        return -d * np.sign(c) * s * np.exp(-_since_reversal(theta, d, 0.5 * np.pi) / decay)
    axis = 0 if term.startswith("cyclic_u") else 1
    pos = centre[axis] + radius * (c if axis == 0 else s)
    arg = 2.0 * np.pi * pos / periods[axis]
    wave = np.cos(arg) if term.endswith("cos") else np.sin(arg)
    return (c if axis == 0 else s) * wave


@dataclass(frozen=True)
class CircularDesign:
    """The design matrix of a circular test: ``ΔR = A β`` over the points of both paths.

    Attributes
    ----------
    plane : str
        ``XY``, ``YZ`` or ``ZX``.
    terms : tuple of str
        The model's terms (:data:`TERMS`), in column order.
    names : tuple of str
        The same with the axes' letters (``centre_x``, ``backlash_y``).
    units : tuple of str
        Of each column's unknown.
    theta : ndarray, shape (N,)
        The angle of each point, rad (CCW points first, then CW).
    direction : ndarray, shape (N,)
        ``+1`` (CCW) or ``-1`` (CW) of each point.
    matrix : ndarray, shape (N, p)
        ``∂ΔR / ∂β``.
    radius, feed : float
        mm, mm/s.
    """

    plane: str
    terms: tuple[str, ...]
    names: tuple[str, ...]
    units: tuple[str, ...]
    theta: _F = field(repr=False)
    direction: _F = field(repr=False)
    matrix: _F = field(repr=False)
    radius: float
    feed: float

    @property
    def directions(self) -> tuple[int, ...]:
        """The directions present, +1 and/or -1."""
        return tuple(int(x) for x in sorted(set(self.direction.tolist()), reverse=True))

    def deviation(self, values: npt.ArrayLike) -> _F:
        """``ΔR = A β`` for values ``(M, p)`` (or ``(p,)``) in column order: ``(M, N)``."""
        b = np.asarray(values, dtype=np.float64)
        if b.ndim == 1:
            b = b[None, :]
        if b.ndim != 2 or b.shape[1] != len(self.terms):
            raise InputError(
                f"expected values of shape (M, {len(self.terms)}), got {b.shape}", field="values"
            )
        return np.asarray(b @ self.matrix.T, dtype=np.float64)


def design(
    *,
    radius: float,
    theta_ccw: npt.ArrayLike | None = None,
    theta_cw: npt.ArrayLike | None = None,
    terms: Sequence[str] | None = None,
    plane: str = "XY",
    feed: float = 1000.0 / 60.0,
    spike_decay: float = np.radians(3.0),
    cyclic_period: tuple[float, float] | None = None,
    centre: tuple[float, float] = (0.0, 0.0),
) -> CircularDesign:
    """The design matrix of the first-order model (module docstring).

    Parameters
    ----------
    radius : float
        Nominal radius ``R``, mm.
    theta_ccw, theta_cw : array_like (n,), optional
        Angles of the CCW and the CW path, rad.
    terms : sequence of str, optional
        Terms of :data:`TERMS`; default :func:`default_terms` of the directions given.
    plane : {"XY", "YZ", "ZX"}
    feed : float
        ``v_f``, mm/s (default 1000 mm/min).
    spike_decay : float
        ``φ₀`` of the reversal spikes, rad.
    cyclic_period : (float, float), optional
        The period of the cyclic error of u and v, mm (needed by ``cyclic_*``).
    centre : (float, float)
        The circle's centre in axis coordinates u, v, mm (the phase of a cyclic error).

    Returns
    -------
    CircularDesign
    """
    u, v, _ = check_plane(plane)
    r = float(radius)
    if not (np.isfinite(r) and r > 0):
        raise InputError(f"expected a radius > 0, got {radius!r}", field="radius")
    vf = float(feed)
    if not (np.isfinite(vf) and vf > 0):
        raise InputError(f"expected a feed > 0, got {feed!r}", field="feed")
    if not (np.isfinite(spike_decay) and spike_decay > 0):
        raise InputError(f"expected a decay angle > 0, got {spike_decay!r}", field="spike_decay")
    thetas: list[_F] = []
    dirs: list[_F] = []
    for t, sign, name in ((theta_ccw, 1.0, "theta_ccw"), (theta_cw, -1.0, "theta_cw")):
        if t is not None:
            ta = check_angles(t, name)
            thetas.append(ta)
            dirs.append(np.full(ta.size, sign))
    if not thetas:
        raise InputError("expected the angles of at least one path", field="theta_ccw")
    theta = np.concatenate(thetas)
    d = np.concatenate(dirs)
    chosen = tuple(default_terms(len(thetas)) if terms is None else terms)
    unknown = [t for t in chosen if t not in TERMS]
    if unknown:
        raise InputError(
            f"unknown term {unknown[0]!r}; expected some of {', '.join(TERMS)}", field="terms"
        )
    if len(set(chosen)) != len(chosen):
        raise InputError("a term is given twice", field="terms")
    periods = (np.inf, np.inf)
    if any(t.startswith("cyclic") for t in chosen):
        if cyclic_period is None:
            raise InputError("the cyclic terms need cyclic_period (mm, of u and v)", field="terms")
        periods = (float(cyclic_period[0]), float(cyclic_period[1]))
        if not all(np.isfinite(p) and p > 0 for p in periods):
            raise InputError(f"expected periods > 0, got {cyclic_period!r}", field="cyclic_period")
    cu, cv = (float(x) for x in centre)
    A = np.stack(
        [_column(t, theta, d, r, vf, float(spike_decay), periods, (cu, cv)) for t in chosen],
        axis=1,
    )
    names = tuple(_name(t, u, v) for t in chosen)
    units = tuple(_UNITS.get(t, "mm") for t in chosen)
    return CircularDesign(
        plane=str(plane).upper(),
        terms=chosen,
        names=names,
        units=units,
        theta=theta,
        direction=d,
        matrix=A,
        radius=r,
        feed=vf,
    )


def default_terms(directions: int) -> tuple[str, ...]:
    """The terms one test separates: without ``servo_mismatch`` from one direction."""
    base = ["radius", "centre_u", "centre_v", "squareness", "scale_mismatch"]
    base += ["backlash_u", "backlash_v"]
    if directions == 2:
        base.append("servo_mismatch")
    return tuple(base)


def structural_notes(plane: str, directions: int) -> tuple[str, ...]:
    """What a circular test in ``plane`` cannot separate, whatever its points, in words."""
    u, v, w = check_plane(plane)
    notes = [
        f"radius: the mean scale error of {u} and {v} (times R) and the error of the "
        "ballbar's calibrated length are one constant; an ISO 230-2 test of one axis or a "
        "second ballbar length separates them",
        f"no error of {w} (normal to the plane) is seen; tests in the {v}{w} and {w}{u} planes "
        "see them",
    ]
    if directions < 2:
        notes.append(
            "with one direction the servo mismatch and the squareness have the same "
            "signature, sin 2θ; the other direction separates them (the lag flips with it)"
        )
    return tuple(notes)


@dataclass(frozen=True)
class CircularIdentification:
    """Errors identified from traces by linear least squares, all trials at once.

    Attributes
    ----------
    design : CircularDesign
    estimates : ndarray, shape (M, p)
        The identified values, in the columns' units.
    covariance : ndarray, shape (M, p, p)
        ``s² (AᵀA)⁻¹`` with ``s²`` each trial's residual variance (``N - p`` degrees of
        freedom).
    residuals : ndarray, shape (M, N)
        Deviations less the model, mm.
    rms : ndarray, shape (M,)
        ``sqrt(Σ r² / (N - p))``, mm.
    identifiability : Identifiability
        The design's SVD report (:func:`mtmc.verification.identifiability`).
    notes : tuple of str
        :func:`structural_notes`.
    """

    design: CircularDesign
    estimates: _F = field(repr=False)
    covariance: _F = field(repr=False)
    residuals: _F = field(repr=False)
    rms: _F = field(repr=False)
    identifiability: Identifiability = field(repr=False)
    notes: tuple[str, ...]

    def value(self, name: str) -> _F:
        """The estimates ``(M,)`` of one error by its name (``squareness``, ``backlash_x``)."""
        if name not in self.design.names:
            raise InputError(
                f"unknown error {name!r}; identified: {', '.join(self.design.names)}",
                field="name",
            )
        return np.asarray(self.estimates[:, self.design.names.index(name)], dtype=np.float64)


def linear_identification(
    matrix: npt.ArrayLike, names: Sequence[str], readings: npt.ArrayLike
) -> tuple[_F, _F, _F, _F, Identifiability]:
    """Linear least squares of readings ``(M, N)`` on a design ``(N, p)``, all trials at once.

    Returns
    -------
    estimates (M, p), covariance (M, p, p), residuals (M, N), rms (M,), identifiability
        ``covariance = s² (AᵀA)⁻¹`` with ``s² = Σ r² / (N - p)`` of each trial.

    Raises
    ------
    IdentifiabilityError
        When the design cannot separate its parameters (the message names the
        combinations) or has no more rows than columns.
    """
    A = np.asarray(matrix, dtype=np.float64)
    dev = check_trace(readings, A.shape[0], "readings")
    ident = identifiability(A, list(names))
    if not ident.ok or A.shape[0] <= A.shape[1]:
        raise IdentifiabilityError(
            "the test cannot separate these errors: " + ident.text(), field="terms"
        )
    pinv = np.linalg.pinv(A)
    est = dev @ np.ascontiguousarray(pinv.T)
    res = dev - est @ A.T
    s2 = np.einsum("mn,mn->m", res, res) / (A.shape[0] - A.shape[1])
    cov = s2[:, None, None] * (pinv @ pinv.T)[None, :, :]  # pinv pinvᵀ = (AᵀA)⁻¹
    return est, cov, res, np.sqrt(s2), ident


def identify(design_: CircularDesign, deviation: npt.ArrayLike) -> CircularIdentification:
    """Identify the errors of the design from traces ``(M, N)`` (both paths, CCW first).

    Raises
    ------
    IdentifiabilityError
        When the design cannot separate its terms (its report names the combinations:
        leave one term of each out).
    """
    est, cov, res, rms, ident = linear_identification(design_.matrix, design_.names, deviation)
    return CircularIdentification(
        design=design_,
        estimates=est,
        covariance=cov,
        residuals=res,
        rms=rms,
        identifiability=ident,
        notes=structural_notes(design_.plane, len(design_.directions)),
    )
