"""A laser tracker: its pose on the machine, spherical coordinates, noise and visibility.

Conventions (``docs/verification.md``)
--------------------------------------
The tracker's pose is the transform ``B_T_LT = [[R, t], [0, 1]]`` from the tracker frame
to the base frame (the workpiece frame of :mod:`mtmc.kinematics`, where the tracker
stands in the kinematic chain, Aguado et al. 2016 §2): a point with tracker coordinates
``x`` is at ``p = R x + t`` in the base frame, so the tracker reads

``x = Rᵀ (p − t)``                                                       (1)

(Aguado et al. 2017 eq. 1 and Aguado et al. 2016 eqs. 14–16 write ``R_LT⁻¹ (… − T_LT)``;
``R`` is active, as in :mod:`mtmc.geometry.transforms`). ``R`` comes from Euler angles
(default sequence ``"xyz"``: rotations about the fixed x, y, z axes in that order,
``R = Rz(a3) Ry(a2) Rx(a1)``, our reading of the "Euler angles (XYZ)" of Aguado et al. 2017)
or from an axis and an angle (Rodrigues, Aguado et al. 2017 eq. 3).

Spherical coordinates of a tracker-frame point ``x = (x1, x2, x3)``: the range
``L = |x|``, the azimuth ``α = atan2(x2, x1)`` about the tracker's z axis from its x axis,
and the elevation ``β = atan2(x3, √(x1² + x2²))`` above its xy plane; back,
``x = L (cos β cos α, cos β sin α, sin β)``.

Noise (Aguado et al. 2016 eqs. 22–24): independent normal errors of ``L``, ``α`` and ``β``
with standard deviations ``u_L = a + b·L``, ``u_α = c + e/L``, ``u_β = d + e/L`` (``e = 0``
in the paper; ``e`` carries the constant part of a transverse MPE, see
:meth:`TrackerNoise.from_mpe`).

Examples
--------
>>> import numpy as np
>>> lt = LaserTracker.from_euler([1000.0, 0.0, 0.0], [0.0, 0.0, 90.0], degrees=True)
>>> np.round(lt.to_tracker([[1000.0, 500.0, 0.0]]), 9)
array([[500.,   0.,   0.]])
>>> np.round(spherical([[0.0, 3.0, 4.0]]), 6)
array([[5.      , 1.570796, 0.927295]])
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import InputError
from mtmc.geometry.transforms import (
    euler_from_matrix,
    matrix_from_axis_angle,
    matrix_from_euler,
)

__all__ = [
    "LaserTracker",
    "NoiseAt",
    "TrackerNoise",
    "TrackerLimits",
    "VisibilityFailure",
    "VisibilityReport",
    "spherical",
    "cartesian",
    "spherical_jacobian",
    "visibility",
]

_F = NDArray[np.float64]

MpeConversion = Literal["typical", "rectangular"]

#: Divisor from a maximum permissible error to a standard uncertainty: ``"typical"``
#: reads the MPE as the makers' two-standard-deviation figure (u = MPE/2);
#: ``"rectangular"`` as the half-width of a rectangular PDF (u = MPE/√3, JCGM 100 §4.3.7).
MPE_DIVISORS: dict[str, float] = {"typical": 2.0, "rectangular": math.sqrt(3.0)}


def _points(p: npt.ArrayLike, name: str = "points") -> _F:
    arr = np.asarray(p, dtype=np.float64)
    if arr.ndim == 0 or arr.shape[-1] != 3:
        raise InputError(f"expected points of shape (..., 3), got shape {arr.shape}", field=name)
    if not np.all(np.isfinite(arr)):
        raise InputError("expected finite coordinates", field=name)
    return arr


def spherical(x: npt.ArrayLike) -> _F:
    """Range, azimuth and elevation of tracker-frame points.

    Parameters
    ----------
    x : array_like, shape (..., 3)
        Points in the tracker frame, mm.

    Returns
    -------
    ndarray, shape (..., 3)
        ``(L, α, β)``: range (mm), azimuth and elevation (rad); see the module notes.

    Raises
    ------
    InputError
        On a bad shape or a non-finite coordinate.
    """
    a = _points(x, "x")
    h = np.hypot(a[..., 0], a[..., 1])
    return np.stack(
        [
            np.sqrt(h * h + a[..., 2] ** 2),
            np.arctan2(a[..., 1], a[..., 0]),
            np.arctan2(a[..., 2], h),
        ],
        axis=-1,
    )


def cartesian(s: npt.ArrayLike) -> _F:
    """Tracker-frame points from ``(L, α, β)``, the inverse of :func:`spherical`.

    Parameters
    ----------
    s : array_like, shape (..., 3)
        Range (mm), azimuth, elevation (rad).

    Returns
    -------
    ndarray, shape (..., 3)
        ``L (cos β cos α, cos β sin α, sin β)``, mm.
    """
    L, ca, sa, ce, se = _trig(s)
    return np.stack([L * ce * ca, L * ce * sa, L * se], axis=-1)


def _trig(s: npt.ArrayLike) -> tuple[_F, _F, _F, _F, _F]:
    """``L, cos α, sin α, cos β, sin β`` of spherical coordinates ``(..., 3)``."""
    a = np.asarray(s, dtype=np.float64)
    L, az, el = a[..., 0], a[..., 1], a[..., 2]
    return L, np.cos(az), np.sin(az), np.cos(el), np.sin(el)


def spherical_jacobian(s: npt.ArrayLike) -> _F:
    """``∂x/∂(L, α, β)`` of :func:`cartesian`.

    Parameters
    ----------
    s : array_like, shape (..., 3)
        Range (mm), azimuth, elevation (rad).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Columns: derivatives with respect to ``L`` (1), ``α`` (mm/rad), ``β`` (mm/rad).
    """
    L, ca, sa, ce, se = _trig(s)
    J = np.empty((*L.shape, 3, 3))
    J[..., :, 0] = np.stack([ce * ca, ce * sa, se], axis=-1)
    J[..., :, 1] = np.stack([-L * ce * sa, L * ce * ca, np.zeros_like(L)], axis=-1)
    J[..., :, 2] = np.stack([-L * se * ca, -L * se * sa, L * ce], axis=-1)
    return J


def _mpe_u(mpe: tuple[float, float], k: float) -> tuple[float, float]:
    """The standard uncertainty ``(A/k, B/k)`` of an MPE ``±(A + B·L)`` (mm, mm/mm)."""
    return mpe[0] / k, mpe[1] / k


def _mpe_text(mpe: tuple[float, float]) -> str:
    """An MPE ``±(A + B·L)`` (mm, mm/mm) in words, ``±(10 µm + 0.3 µm/m)``."""
    return f"±({mpe[0] * 1e3:g} µm + {mpe[1] * 1e6:g} µm/m)"


@dataclass(frozen=True)
class TrackerNoise:
    """Standard deviations of the tracker's spherical coordinates (Aguado et al. 2016 eqs. 22–24).

    Parameters
    ----------
    radial_a : float
        Constant part ``a`` of ``u_L = a + b·L``, mm.
    radial_b : float
        Range-proportional part ``b``, mm per mm (0.8 µm/m = 0.8e-6).
    azimuth : float
        ``c``: standard deviation of the azimuth, rad.
    elevation : float
        ``d``: standard deviation of the elevation, rad.
    transverse_a : float
        ``e``: a constant transverse length, mm, added to both angles as ``e/L`` (0 in
        the papers; from the constant term of a transverse MPE).
    source : str
        How the numbers were obtained (a preset's name, or the MPE conversion used).

    Examples
    --------
    >>> n = TrackerNoise.aguado2017()
    >>> float(n.u_range(1000.0)), n.azimuth
    (0.0048, 2.4e-05)
    >>> TrackerNoise.from_mpe(adm=(0.010, 0.3e-6), transverse=(0.015, 6e-6),
    ...                       conversion="rectangular").source
    'MPE/√3 (rectangular): ADM ±(10 µm + 0.3 µm/m), transverse ±(15 µm + 6 µm/m)'
    """

    radial_a: float
    radial_b: float
    azimuth: float
    elevation: float
    transverse_a: float = 0.0
    source: str = ""

    def __post_init__(self) -> None:
        for n in ("radial_a", "radial_b", "azimuth", "elevation", "transverse_a"):
            v = float(getattr(self, n))
            if not (math.isfinite(v) and v >= 0.0):
                raise InputError(f"expected a finite value >= 0, got {v}", field=n)
            object.__setattr__(self, n, v)

    @classmethod
    def aguado2017(cls) -> TrackerNoise:
        """Aguado et al. 2017 (and 2016 §5): 24 µrad on both angles, 4 µm + 0.8 µm/m radial."""
        return cls(0.004, 0.8e-6, 24e-6, 24e-6, 0.0, "Aguado et al. 2017: 24 µrad, 4 µm + 0.8 µm/m")

    @classmethod
    def from_mpe(
        cls,
        *,
        adm: tuple[float, float],
        transverse: tuple[float, float],
        conversion: MpeConversion,
    ) -> TrackerNoise:
        """Noise from a maker's maximum permissible errors, converted as stated.

        Parameters
        ----------
        adm : (float, float)
            Radial (distance meter) MPE ``±(A + B·L)``: ``A`` in mm, ``B`` in mm/mm.
        transverse : (float, float)
            Transverse MPE ``±(A + B·L)`` of a point at range ``L`` (mm, mm/mm); as an
            angle, ``(A + B·L)/L``, i.e. a constant ``B`` plus ``A/L``.
        conversion : {"typical", "rectangular"}
            ``u = MPE/2`` (the makers' "typical" reading) or ``u = MPE/√3`` (rectangular
            PDF of half-width MPE, JCGM 100 §4.3.7). Required: there is no default.

        Returns
        -------
        TrackerNoise
            ``u_L = (A_r + B_r L)/k``, ``u_α = u_β = B_t/k + (A_t/k)/L`` with ``k`` the divisor.

        Raises
        ------
        InputError
            On an unknown conversion or a negative MPE.
        """
        if conversion not in MPE_DIVISORS:
            raise InputError(
                "expected conversion 'typical' (MPE/2) or 'rectangular' (MPE/√3), "
                f"got {conversion!r}",
                field="conversion",
            )
        k = MPE_DIVISORS[conversion]
        word = "MPE/2 (typical)" if conversion == "typical" else "MPE/√3 (rectangular)"
        radial_a, radial_b = _mpe_u(adm, k)  # u_L = a + b·L
        transverse_a, angle = _mpe_u(transverse, k)  # u_α = u_β = B_t/k + (A_t/k)/L
        text = f"{word}: ADM {_mpe_text(adm)}, transverse {_mpe_text(transverse)}"
        return cls(radial_a, radial_b, angle, angle, transverse_a, text)

    def u_range(self, L: npt.ArrayLike) -> _F:
        """``u_L = a + b·L``, mm, for ranges ``L`` (mm)."""
        return self.radial_a + self.radial_b * np.asarray(L, dtype=np.float64)

    def u_spherical(self, L: npt.ArrayLike) -> _F:
        """Standard deviations ``(u_L, u_α, u_β)``, shape ``(..., 3)``, at ranges ``L`` (mm)."""
        La = np.asarray(L, dtype=np.float64)
        t = self.transverse_a / La
        return np.stack([self.u_range(La), self.azimuth + t, self.elevation + t], axis=-1)

    def perturb(self, x: npt.ArrayLike, z: npt.ArrayLike) -> _F:
        """Noisy readings of tracker-frame points from standard normal numbers.

        Parameters
        ----------
        x : array_like, shape (..., 3)
            True tracker-frame points, mm.
        z : array_like, shape (..., 3)
            Standard normal numbers for ``(L, α, β)`` (broadcast against ``x``).

        Returns
        -------
        ndarray, shape (broadcast, 3)
            ``cartesian(spherical(x) + u ⊙ z)``.

        See Also
        --------
        at : the same for many draws of the noise of the same points.
        """
        return self.at(x).perturb(z)

    def at(self, x: npt.ArrayLike) -> NoiseAt:
        """The noise of the readings of fixed points, for many draws of it.

        The spherical coordinates of the points and their standard deviations are
        computed once; :meth:`NoiseAt.perturb` then gives the same numbers as
        :meth:`perturb` of the same points, bit for bit.

        Parameters
        ----------
        x : array_like, shape (..., 3)
            True tracker-frame points, mm.

        Returns
        -------
        NoiseAt
        """
        s = spherical(x)
        return NoiseAt(s, self.u_spherical(s[..., 0]))

    def covariance(self, x: npt.ArrayLike) -> _F:
        """Linearised covariance of the Cartesian reading of each point.

        Parameters
        ----------
        x : array_like, shape (..., 3)
            Tracker-frame points, mm.

        Returns
        -------
        ndarray, shape (..., 3, 3)
            ``J diag(u_L², u_α², u_β²) Jᵀ``, mm², ``J`` from :func:`spherical_jacobian`.
        """
        s = spherical(x)
        J = spherical_jacobian(s)
        u = self.u_spherical(s[..., 0])
        Ju = J * u[..., None, :]
        return Ju @ np.swapaxes(Ju, -1, -2)


@dataclass(frozen=True, eq=False)
class NoiseAt:
    """The tracker noise at fixed true readings (:meth:`TrackerNoise.at`).

    Parameters
    ----------
    spherical : ndarray, shape (..., 3)
        ``(L, α, β)`` of the true readings: range (mm), azimuth and elevation (rad).
    u : ndarray, shape (..., 3)
        Their standard deviations ``(u_L, u_α, u_β)`` (mm, rad, rad).
    """

    spherical: _F
    u: _F

    def __post_init__(self) -> None:
        for n in ("spherical", "u"):
            a = np.asarray(getattr(self, n), dtype=np.float64).view()  # read-only, no copy
            a.setflags(write=False)
            object.__setattr__(self, n, a)
        if self.spherical.shape != self.u.shape or self.spherical.shape[-1:] != (3,):
            raise InputError(
                f"expected spherical coordinates and standard deviations of one shape "
                f"(..., 3), got {self.spherical.shape} and {self.u.shape}",
                field="u",
            )

    def perturb(self, z: npt.ArrayLike) -> _F:
        """Noisy readings from standard normal numbers ``z`` (broadcast against the points).

        Parameters
        ----------
        z : array_like, shape (..., 3)
            Standard normal numbers for ``(L, α, β)``; a leading axis of trials broadcasts.

        Returns
        -------
        ndarray, shape (broadcast, 3)
            ``cartesian(spherical + u ⊙ z)``, mm, tracker frame.
        """
        return cartesian(self.spherical + self.u * np.asarray(z, dtype=np.float64))


@dataclass(frozen=True)
class LaserTracker:
    """A laser tracker placed on the machine: ``p = R x + t`` (tracker → base frame).

    Parameters
    ----------
    rotation : ndarray, shape (3, 3)
        ``R``, active, tracker axes in base coordinates (orthonormal, det +1).
    position : ndarray, shape (3,)
        ``t``, the tracker's origin in the base (workpiece) frame, mm.
    noise : TrackerNoise, optional
        Its measurement noise.
    name : str
        A label (a study's position name).
    """

    rotation: _F
    position: _F
    noise: TrackerNoise | None = None
    name: str = ""

    def __post_init__(self) -> None:
        R = np.array(self.rotation, dtype=np.float64)
        t = np.array(self.position, dtype=np.float64)
        if (
            R.shape != (3, 3)
            or not np.allclose(R @ R.T, np.eye(3), atol=1e-9)
            or np.linalg.det(R) < 0
        ):
            raise InputError(
                "expected a 3 × 3 rotation matrix (orthonormal, det +1)", field="rotation"
            )
        if t.shape != (3,) or not np.all(np.isfinite(t)):
            raise InputError(f"expected a position of shape (3,), got {t.shape}", field="position")
        R.setflags(write=False)
        t.setflags(write=False)
        object.__setattr__(self, "rotation", R)
        object.__setattr__(self, "position", t)

    @classmethod
    def from_euler(
        cls,
        position: npt.ArrayLike,
        angles: npt.ArrayLike,
        *,
        seq: str = "xyz",
        degrees: bool = False,
        noise: TrackerNoise | None = None,
        name: str = "",
    ) -> LaserTracker:
        """Tracker from its position and Euler angles.

        Parameters
        ----------
        position : array_like, shape (3,)
            mm.
        angles : array_like, shape (3,)
            In the order of ``seq``; rad, or degrees with ``degrees=True``.
        seq : str, default "xyz"
            As :func:`mtmc.geometry.transforms.matrix_from_euler` (lower case extrinsic:
            ``"xyz"`` is ``R = Rz(a3) Ry(a2) Rx(a1)``).
        degrees : bool
            Angles in degrees.
        noise, name
            As for :class:`LaserTracker`.

        Returns
        -------
        LaserTracker
        """
        a = np.asarray(angles, dtype=np.float64)
        if a.shape != (3,):
            raise InputError(f"expected three Euler angles, got shape {a.shape}", field="angles")
        R = matrix_from_euler(np.radians(a) if degrees else a, seq)
        return cls(R, np.asarray(position, dtype=np.float64), noise, name)

    @classmethod
    def from_axis_angle(
        cls,
        position: npt.ArrayLike,
        axis: npt.ArrayLike,
        angle: float,
        *,
        noise: TrackerNoise | None = None,
        name: str = "",
    ) -> LaserTracker:
        """Tracker from its position and a Rodrigues axis and angle (Aguado et al. 2017 eq. 3).

        Parameters
        ----------
        position : array_like, shape (3,)
            mm.
        axis : array_like, shape (3,)
            Rotation axis (normalised here).
        angle : float
            rad.
        noise, name
            As for :class:`LaserTracker`.

        Returns
        -------
        LaserTracker
        """
        R = matrix_from_axis_angle(np.asarray(axis, dtype=np.float64), float(angle))
        return cls(R, np.asarray(position, dtype=np.float64), noise, name)

    def euler(self, seq: str = "xyz") -> _F:
        """Euler angles (rad) of :attr:`rotation` in ``seq``."""
        return euler_from_matrix(self.rotation, seq)

    def to_tracker(self, p: npt.ArrayLike) -> _F:
        """Base-frame points ``(..., 3)`` in the tracker frame: ``x = Rᵀ (p − t)`` (eq. 1 above)."""
        return (_points(p) - self.position) @ self.rotation

    def to_base(self, x: npt.ArrayLike) -> _F:
        """Tracker-frame points ``(..., 3)`` in the base frame: ``p = R x + t``."""
        return _points(x, "x") @ self.rotation.T + self.position

    def spherical(self, p: npt.ArrayLike) -> _F:
        """``(L, α, β)`` of base-frame points as this tracker reads them, ``(..., 3)``."""
        return spherical(self.to_tracker(p))

    def point_covariance(self, p: npt.ArrayLike) -> _F:
        """Covariance ``(..., 3, 3)`` (mm², tracker frame) of the readings of base-frame points.

        Raises
        ------
        InputError
            If the tracker has no noise model.
        """
        if self.noise is None:
            raise InputError("the tracker has no noise model", field="noise")
        return self.noise.covariance(self.to_tracker(p))


@dataclass(frozen=True)
class TrackerLimits:
    """Where a tracker can stand and what it can see (Aguado et al. 2016 §4.4, Fig. 8).

    The paper names these limits but prints no values; the defaults are ours: elevation
    −60…77°, typical of a tracker's head; azimuth unlimited; acceptance 0…30°, a
    reflector's cone; height unlimited.

    Parameters
    ----------
    azimuth : (float, float)
        Allowed azimuth of the beam in the tracker frame, rad.
    elevation : (float, float)
        Allowed elevation, rad.
    height : (float, float)
        Allowed z of the tracker's origin in the base frame, mm.
    acceptance : (float, float)
        Minimum and maximum angle (rad) between the beam to the reference point and the
        beam to each point (Aguado et al. 2016 eq. 21): the reflector, turned towards the
        tracker at the reference point, must accept every beam.
    """

    azimuth: tuple[float, float] = (-math.pi, math.pi)
    elevation: tuple[float, float] = (math.radians(-60.0), math.radians(77.0))
    height: tuple[float, float] = (-math.inf, math.inf)
    acceptance: tuple[float, float] = (0.0, math.radians(30.0))

    def __post_init__(self) -> None:
        for n in ("azimuth", "elevation", "height", "acceptance"):
            lo, hi = (float(v) for v in getattr(self, n))
            if not lo <= hi:
                raise InputError(f"expected low <= high, got ({lo}, {hi})", field=n)
            object.__setattr__(self, n, (lo, hi))


@dataclass(frozen=True)
class VisibilityFailure:
    """One point outside one limit (``azimuth``, ``elevation``, ``acceptance`` or ``height``)."""

    point: int
    limit: str
    value: float
    low: float
    high: float


@dataclass(frozen=True)
class VisibilityReport:
    """Result of :func:`visibility`.

    Attributes
    ----------
    ok : bool
        True when no point fails a limit.
    failures : tuple of VisibilityFailure
        Every failing (point, limit); ``point = -1`` for the tracker's own height.
    angles : ndarray, shape (N, 3)
        Per point: azimuth, elevation, acceptance angle ``α_i`` (rad).
    """

    ok: bool
    failures: tuple[VisibilityFailure, ...]
    angles: _F = field(repr=False)

    def text(self) -> str:
        """The failures in words (degrees, mm), one line each; ``"all points visible"`` if none."""
        if self.ok:
            return "all points visible"
        lines = []
        for f in self.failures:
            if f.limit == "height":
                lines.append(f"tracker height {f.value:.1f} mm outside [{f.low:g}, {f.high:g}] mm")
            else:
                lines.append(
                    f"point {f.point}: {f.limit} {math.degrees(f.value):.2f}° outside "
                    f"[{math.degrees(f.low):.2f}°, {math.degrees(f.high):.2f}°]"
                )
        return "\n".join(lines)


def visibility(
    tracker: LaserTracker,
    points: npt.ArrayLike,
    limits: TrackerLimits,
    *,
    reference: int = 0,
) -> VisibilityReport:
    """Check that a tracker sees every point (Aguado et al. 2016 eqs. 19–21).

    Parameters
    ----------
    tracker : LaserTracker
    points : array_like, shape (N, 3)
        Reflector positions in the base frame, mm.
    limits : TrackerLimits
    reference : int
        Index of the point ``P0`` at which the reflector faces the beam (eq. 19).

    Returns
    -------
    VisibilityReport
        The failing points and limits. The acceptance angle is
        ``α_i = acos(u·v / |u||v|)`` with ``u`` the beam to ``P0`` and ``v`` to ``P_i``
        (eqs. 19–21), both from the tracker's origin.

    Raises
    ------
    InputError
        On a bad shape, or a point at the tracker's origin.
    """
    p = _points(points)
    if p.ndim != 2:
        raise InputError(f"expected points of shape (N, 3), got {p.shape}", field="points")
    if not 0 <= reference < p.shape[0]:
        raise InputError(f"reference {reference} is not a point index", field="reference")
    x = tracker.to_tracker(p)
    s = spherical(x)
    if np.any(s[:, 0] <= 0.0):
        raise InputError("a point lies at the tracker's origin", field="points")
    u = x[reference]
    cosang = (x @ u) / (s[:, 0] * s[reference, 0])
    alpha = np.arccos(np.clip(cosang, -1.0, 1.0))
    angles = np.stack([s[:, 1], s[:, 2], alpha], axis=-1)
    fails: list[VisibilityFailure] = []
    h = float(tracker.position[2])
    if not limits.height[0] <= h <= limits.height[1]:
        fails.append(VisibilityFailure(-1, "height", h, *limits.height))
    for col, name in enumerate(("azimuth", "elevation", "acceptance")):
        lo, hi = getattr(limits, name)
        bad = np.nonzero((angles[:, col] < lo) | (angles[:, col] > hi))[0]
        fails.extend(VisibilityFailure(int(i), name, float(angles[i, col]), lo, hi) for i in bad)
    angles.setflags(write=False)
    return VisibilityReport(not fails, tuple(fails), angles)
