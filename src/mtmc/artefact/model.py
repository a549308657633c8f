"""The machine model of the fiducial measurement and the setup-error identification.

Wang, Cheung and Kong (2022) eqs. 3–20, on any topology of :mod:`mtmc.kinematics`.

Frames and the measurement
--------------------------
The probe's centre sits at ``p`` on the last tool-side body (the C spindle of their
wBZfXYCt machine); the artefact is mounted on the last part-side body (the B table),
ball ``i`` at ``w_i``. :meth:`mtmc.kinematics.Machine.tool_position` with ``tool = p``
gives ``f(q, E)``: the probe centre in the frame ``W`` of that body at axis positions
``q`` (ISO 841: the paper's ``(x, y, z, b, c)`` is mtmc's ``(x, y, -z, -b, c)``) with the
errors ``E`` (ISO 230 names). At a rotary pose the nominal ``f(q, 0)`` is affine in the
linear axes, ``f = f₀ + A q_lin``: the readings of the linear axes are turned into points
of ``W`` by ``A``, and the commanded position of a ball is ``q_lin = A⁻¹ (w_i - f₀)``.

A probed point is the reading ``q`` at which the real machine has the probe centre on the
ball's surface, ``f(q, E) = s``; the controller records ``f(q, 0)``. The probe offset's
setup error ``Δp`` is ``(EXT, EYT, EZT)``; the fiducial's ``Δw_i`` moves its real centre to
``w_i + Δw_i``. With ``J_p = ∂f / ∂(EXT, EYT, EZT)`` the measured centre is
``m_i = w_i + Δw_i - J_p Δp - v_i`` (``v_i``: the machine's volumetric error there).

Identification (eqs. 16–20)
---------------------------
``ΔF_i = w_i - m_i = J_p Δp - Δw_i`` (+ the volumetric part), stacked over balls and
poses: ``ΔF = J ΔE`` with ``ΔE = (Δp, Δw₁, …, Δw_N)`` (eq. 18) and the block rows
``[J_p, 0 … -I₃ … 0]``. On wBZfXYCt, ``J_p = R_Bᵀ R_C`` in ``W``; rotated into the frame
``F`` (multiplied by ``R_B``) every block row reads ``[R_C, 0 … -R_B … 0]``, as eq. 16
gives: the last block row of eq. 19 as printed begins with ``I₃`` instead of ``R_C``
(equal only at ``c = 0``). :func:`paper_jacobian` builds the rotated form; the least
squares solution and its covariance are the same in either frame (the rotation is
orthogonal and the noise model isotropic per block).

One pose gives ``3N`` equations in ``3N + 3`` unknowns: a common shift of every fiducial
cannot be told from a probe offset; the null space is ``{(Δp, Δw_i = J_p Δp for all i)}``
(``J_p`` does not depend on the ball). Poses with different ``J_p`` remove it;
:func:`identify_setup` reports the rank and the unidentifiable combinations.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.artefact.artefact import Artefact
from mtmc.artefact.probing import fit_sensitivity, patch_offsets, patch_points
from mtmc.errors import InputError
from mtmc.frozen import frozen_floats
from mtmc.geometry.fits import fit_sphere
from mtmc.kinematics import Machine
from mtmc.kinematics.topology import is_linear

__all__ = [
    "FiducialSetup",
    "SetupIdentification",
    "Measurement",
    "identify_setup",
    "paper_jacobian",
    "setup_error_names",
]

_F = NDArray[np.float64]
PROBE_ERRORS = ("EXT", "EYT", "EZT")


def setup_error_names(ball_names: Sequence[str]) -> tuple[str, ...]:
    """Names of ``ΔE`` (eq. 18): ``dpx dpy dpz``, then ``dw<ball>x dw<ball>y dw<ball>z``.

    Examples
    --------
    >>> setup_error_names(["1", "2"])
    ('dpx', 'dpy', 'dpz', 'dw1x', 'dw1y', 'dw1z', 'dw2x', 'dw2y', 'dw2z')
    """
    out = ["dpx", "dpy", "dpz"]
    for b in ball_names:
        out += [f"dw{b}x", f"dw{b}y", f"dw{b}z"]
    return tuple(out)


def paper_jacobian(b: npt.ArrayLike, c: npt.ArrayLike, n_balls: int) -> _F:
    """Eq. 19 with the departure derived from eq. 16: block rows ``[R_C, 0 … -R_B … 0]``.

    Parameters
    ----------
    b, c : array_like, shape (P,)
        The paper's B and C positions at each pose, rad (``R_B`` about y, ``R_C`` about z,
        eqs. 8 and 12).
    n_balls : int
        ``N``.

    Returns
    -------
    ndarray, shape (3 N P, 3 + 3 N)
        Rows ball by ball within a pose, poses one after the other.
    """
    bb = np.atleast_1d(np.asarray(b, dtype=np.float64))
    cc = np.atleast_1d(np.asarray(c, dtype=np.float64))
    p = bb.shape[0]
    J = np.zeros((p, n_balls, 3, 3 + 3 * n_balls))
    cb, sb, ck, sk = np.cos(bb), np.sin(bb), np.cos(cc), np.sin(cc)
    RC = np.zeros((p, 3, 3))
    RC[:, 0, 0], RC[:, 0, 1], RC[:, 1, 0], RC[:, 1, 1], RC[:, 2, 2] = ck, -sk, sk, ck, 1.0
    RB = np.zeros((p, 3, 3))
    RB[:, 0, 0], RB[:, 0, 2], RB[:, 1, 1], RB[:, 2, 0], RB[:, 2, 2] = cb, sb, 1.0, -sb, cb
    for i in range(n_balls):  # loop over balls (blocks), not trials
        J[:, i, :, :3] = RC
        J[:, i, :, 3 + 3 * i : 6 + 3 * i] = -RB
    return J.reshape(p * n_balls * 3, 3 + 3 * n_balls)


@dataclass(frozen=True, eq=False)
class Measurement:
    """Noise-free probing of every ball at every pose.

    Attributes
    ----------
    poses : ndarray, shape (P, R)
        Rotary axis positions, rad (mtmc convention), columns :attr:`FiducialSetup.rotary`.
    commanded : ndarray, shape (P, N, L)
        Commanded linear axis positions of each ball centre, mm.
    points : ndarray, shape (P, N, n, 3)
        The probed points as recorded, in ``W``, mm.
    centres : ndarray, shape (P, N, 3)
        Their fitted centres (the measured centres ``m_i``), mm.
    sensitivity : ndarray, shape (P, N, 3, 3n)
        The fit's linear map (:func:`~mtmc.artefact.probing.fit_sensitivity`) from point
        displacements in ``W`` to the centre.
    axis_map : ndarray, shape (P, 3, L)
        ``A``: linear-axis readings to ``W`` at each pose.
    """

    poses: _F
    commanded: _F
    points: _F
    centres: _F
    sensitivity: _F
    axis_map: _F

    def in_axes(self, w: npt.ArrayLike) -> _F:
        """Vectors in ``W`` at each ball, in linear-axis coordinates: ``A⁻¹ w`` per pose.

        Parameters
        ----------
        w : array_like, shape (P, N, 3)
            Vectors at each ball of each pose in ``W`` (the volumetric errors), mm.

        Returns
        -------
        ndarray, shape (P, N, 3)
            The axis movements that give them (Wang, Cheung and Kong 2022, Fig. 7).
        """
        v = np.asarray(w, dtype=np.float64)
        return np.asarray(np.linalg.solve(self.axis_map[:, None], v[..., None])[..., 0])


@dataclass(frozen=True, eq=False)
class FiducialSetup:
    """A machine with a probe and a mounted artefact: eqs. 3–15 on any topology.

    Parameters
    ----------
    machine : Machine
        Its ``tool`` is the probe centre ``p`` on the last tool-side body (mm).
    artefact : Artefact
        The calibrated balls and their mounting on the last part-side body.
    patch_axis : ndarray, shape (3,)
        Direction, in the artefact frame, from each ball's centre to the middle of the
        probed patch (default +z: the ball's top, away from the fixture).
    offsets : ndarray, shape (n, 2)
        In-plane coordinates of the probed points (default 30 in 6 × 6 mm).
    """

    machine: Machine
    artefact: Artefact
    patch_axis: _F = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    offsets: _F = field(default_factory=patch_offsets)

    def __post_init__(self) -> None:
        lin = self.linear
        if len(lin) != 3:
            raise InputError(
                f"expected a machine with three linear axes to probe with, got {lin}",
                field="machine",
            )
        object.__setattr__(self, "patch_axis", np.asarray(self.patch_axis, dtype=np.float64))
        object.__setattr__(self, "offsets", np.asarray(self.offsets, dtype=np.float64))

    @property
    def rotary(self) -> tuple[str, ...]:
        """The rotary axes, in the machine's column order."""
        return tuple(a for a in self.machine.axes if not is_linear(a))

    @property
    def linear(self) -> tuple[str, ...]:
        """The linear axes, in the machine's column order."""
        return tuple(a for a in self.machine.axes if is_linear(a))

    def _q(self, poses: _F, lin: _F) -> _F:
        """Full axis vectors (K, n_axes) from rotary (K, R) and linear (K, 3) positions."""
        q = np.zeros((poses.shape[0], self.machine.n_axes))
        ri = [self.machine.axes.index(a) for a in self.rotary]
        li = [self.machine.axes.index(a) for a in self.linear]
        q[:, ri] = poses
        q[:, li] = lin
        return q

    def check_poses(self, poses: npt.ArrayLike) -> _F:
        """Rotary positions as (P, R), rad; refuses a wrong shape."""
        a = np.asarray(poses, dtype=np.float64)
        if a.ndim == 1 and len(self.rotary) == 1:
            a = a[:, None]
        if a.ndim != 2 or a.shape[1] != len(self.rotary) or not np.all(np.isfinite(a)):
            raise InputError(
                f"expected rotary positions of shape (P, {len(self.rotary)}) for axes "
                f"{' '.join(self.rotary)}, got {a.shape}",
                field="poses",
            )
        return a

    def axis_map(self, poses: npt.ArrayLike) -> tuple[_F, _F]:
        """``f₀`` (P, 3) and ``A`` (P, 3, 3): the nominal ``f = f₀ + A q_lin`` at each pose.

        ``f`` is affine in the linear axes at a fixed rotary pose; ``A``'s columns are the
        differences over unit steps (exact up to rounding).
        """
        P = self.check_poses(poses)
        p = P.shape[0]
        lin = np.zeros((4 * p, 3))
        lin[p:] = np.repeat(np.eye(3), p, axis=0)
        f = self.machine.tool_position(self._q(np.tile(P, (4, 1)), lin)).reshape(4, p, 3)
        A = (f[1:] - f[0]).transpose(1, 2, 0)
        return f[0], A

    def commanded(self, poses: npt.ArrayLike) -> _F:
        """Linear axis positions that put the nominal probe centre on each ball, (P, N, 3)."""
        f0, A = self.axis_map(poses)
        w = self.artefact.mounted_centres()
        q = np.linalg.solve(A[:, None], (w[None] - f0[:, None])[..., None])[..., 0]
        return np.asarray(q, dtype=np.float64)

    def probe_jacobian(self, poses: npt.ArrayLike) -> _F:
        """``J_p = ∂f / ∂(EXT, EYT, EZT)`` at each ball and pose, (P, N, 3, 3), in ``W``."""
        P = self.check_poses(poses)
        lin = self.commanded(P)
        p, n = lin.shape[:2]
        q = self._q(np.repeat(P, n, axis=0), lin.reshape(-1, 3))
        return self.machine.jacobian(q, names=list(PROBE_ERRORS)).reshape(p, n, 3, 3)

    def setup_jacobian(self, poses: npt.ArrayLike) -> _F:
        """``J`` of ``ΔF = J ΔE`` in ``W``, (3 N P, 3 + 3 N): block rows ``[J_p … -I₃ …]``."""
        Jp = self.probe_jacobian(poses)
        p, n = Jp.shape[:2]
        J = np.zeros((p, n, 3, 3 + 3 * n))
        J[..., :3] = Jp
        for i in range(n):  # loop over balls (blocks)
            J[:, i, :, 3 + 3 * i : 6 + 3 * i] = -np.eye(3)
        return J.reshape(p * n * 3, 3 + 3 * n)

    def measure(
        self,
        poses: npt.ArrayLike,
        errors: Mapping[str, Any] | None = None,
        setup: npt.ArrayLike | None = None,
        *,
        free_radius: bool = False,
        iterations: int = 4,
    ) -> Measurement:
        """Probe every ball at every pose on the real machine, noise-free, and fit.

        Parameters
        ----------
        poses : array_like, shape (P, R)
            Rotary positions, rad.
        errors : mapping, optional
            The machine's geometric errors (ISO 230 names, numbers or error functions;
            see :meth:`mtmc.kinematics.Machine.tool_position`). Not ``EXT EYT EZT``.
        setup : array_like, shape (3 + 3N,), optional
            The real setup errors ``ΔE`` (eq. 18), mm.
        free_radius : bool
            Fit the radius too instead of using the calibrated one.
        iterations : int
            Newton iterations solving ``f(q, E) = s`` for the readings.

        Returns
        -------
        Measurement
        """
        P = self.check_poses(poses)
        art = self.artefact
        n = art.n_balls
        E = np.zeros(3 + 3 * n) if setup is None else np.asarray(setup, dtype=np.float64)
        if E.shape != (3 + 3 * n,):
            raise InputError(f"expected {3 + 3 * n} setup errors, got {E.shape}", field="setup")
        errs = dict(errors or {})
        for name in PROBE_ERRORS:
            if name in errs:
                raise InputError(f"{name} is the probe's setup error: give it in setup", field=name)
        errs.update({nm: E[k] for k, nm in enumerate(PROBE_ERRORS)})
        f0, A = self.axis_map(P)
        p = P.shape[0]
        w_true = art.mounted_centres() + E[3:].reshape(n, 3)
        axis = art.rotation @ self.patch_axis
        surf = np.stack(
            [patch_points(w_true[i], art.radius, axis, self.offsets) for i in range(n)]
        )  # (N, k, 3)
        k = surf.shape[1]
        s = np.broadcast_to(surf[None], (p, n, k, 3)).reshape(p, n * k, 3)
        Ainv = np.linalg.inv(A)
        lin = np.einsum("pij,pkj->pki", Ainv, s - f0[:, None, :])  # nominal readings
        rot = np.repeat(P, n * k, axis=0)
        for _ in range(iterations):  # Newton on f(q, E) = s (loop over iterations)
            ft = self.machine.tool_position(self._q(rot, lin.reshape(-1, 3)), errs)
            lin = lin + np.einsum("pij,pkj->pki", Ainv, s - ft.reshape(p, n * k, 3))
        rec = f0[:, None, :] + np.einsum("pij,pkj->pki", A, lin)
        pts = rec.reshape(p, n, k, 3)
        radius = None if free_radius else np.full(p * n, art.radius)
        fit = fit_sphere(pts.reshape(p * n, k, 3), radius)
        centres = fit.geometry.centre.reshape(p, n, 3)  # type: ignore[union-attr]
        K = fit_sensitivity(pts.reshape(p * n, k, 3), centres.reshape(-1, 3), free_radius)
        return Measurement(
            frozen_floats(P),
            frozen_floats(self.commanded(P)),
            frozen_floats(pts),
            frozen_floats(centres),
            frozen_floats(K.reshape(p, n, 3, 3 * k)),
            frozen_floats(A),
        )


@dataclass(frozen=True, eq=False)
class SetupIdentification:
    """Least-squares solution of ``ΔF = J ΔE`` with its covariance and its rank.

    Attributes
    ----------
    names : tuple of str
        Parameter names (:func:`setup_error_names`).
    estimate : ndarray, shape (k,)
        ``ΔÊ``, mm (the minimum-norm solution when rank-deficient).
    covariance : ndarray, shape (k, k)
        ``J⁺ V J⁺ᵀ`` (with ``V`` the covariance of ``ΔF``), mm²; infinite along the
        unidentifiable directions when rank-deficient.
    residuals : ndarray, shape (r,)
        ``ΔF - J ΔÊ``, mm.
    rank : int
        Numerical rank of ``J``.
    singular_values : ndarray, shape (k,)
        Of ``J``, descending.
    null_space : ndarray, shape (k - rank, k)
        Rows spanning the unidentifiable combinations of the parameters, in reduced row
        echelon form (each has a 1 where the others have 0).
    """

    names: tuple[str, ...]
    estimate: _F
    covariance: _F
    residuals: _F
    rank: int
    singular_values: _F
    null_space: _F

    @property
    def full_rank(self) -> bool:
        """Whether every parameter is identifiable."""
        return self.rank == len(self.names)

    @property
    def u(self) -> _F:
        """Standard uncertainties, ``sqrt(diag(covariance))``, mm."""
        return np.sqrt(np.diagonal(self.covariance))

    def unidentifiable(self, tol: float = 1e-9) -> list[str]:
        """The unidentifiable combinations in words, one per null-space vector.

        Each reads ``a·name + b·name …`` (coefficients below ``tol`` left out): adding
        any multiple of it to the estimate leaves ``J ΔE`` unchanged.
        """
        out = []
        for v in self.null_space:
            v = v / v[np.argmax(np.abs(v))]
            terms = [f"{c:+.4g}·{n}" for c, n in zip(v, self.names, strict=True) if abs(c) > tol]
            out.append(" ".join(terms))
        return out


def identify_setup(
    J: npt.ArrayLike,
    dF: npt.ArrayLike,
    names: Sequence[str],
    cov: npt.ArrayLike | None = None,
    *,
    rtol: float = 1e-10,
) -> SetupIdentification:
    """Solve ``ΔF = J ΔE`` (eq. 20) by least squares, with covariance, rank and null space.

    Parameters
    ----------
    J : array_like, shape (r, k)
        The Jacobian (e.g. :meth:`FiducialSetup.setup_jacobian`).
    dF : array_like, shape (r,)
        ``ΔF``, mm.
    names : sequence of str
        The ``k`` parameter names.
    cov : array_like, shape (r, r) or (r,), optional
        Covariance of ``ΔF`` (a vector: its diagonal), mm². Default: ``s² I`` with the
        residual variance ``s² = |ΔF - J ΔÊ|² / (r - rank)``.
    rtol : float
        Singular values below ``rtol`` times the largest count as zero.

    Returns
    -------
    SetupIdentification

    Raises
    ------
    InputError
        On mismatched shapes.
    """
    Ja = np.asarray(J, dtype=np.float64)
    d = np.asarray(dF, dtype=np.float64)
    if Ja.ndim != 2 or d.shape != (Ja.shape[0],) or len(names) != Ja.shape[1]:
        raise InputError(
            f"expected J (r, k), dF (r,) and k names, got {Ja.shape}, {d.shape}, {len(names)}",
            field="J",
        )
    U, s, Vt = np.linalg.svd(Ja, full_matrices=True)
    rank = int(np.sum(s > rtol * s[0])) if s.size else 0
    Ur, sr, Vr = U[:, :rank], s[:rank], Vt[:rank]
    pinv = (Vr.T / sr) @ Ur.T
    est = pinv @ d
    res = d - Ja @ est
    if cov is None:
        dof = Ja.shape[0] - rank
        s2 = float(res @ res) / dof if dof > 0 else np.nan
        V = pinv @ pinv.T * s2
    else:
        C = np.asarray(cov, dtype=np.float64)
        V = pinv @ (C[:, None] * pinv.T if C.ndim == 1 else C @ pinv.T)
    null = Vt[rank:]
    if null.shape[0]:
        # a canonical basis: reduced row echelon form on the best-conditioned columns
        import scipy.linalg

        piv = scipy.linalg.qr(null, pivoting=True, mode="r")[1][: null.shape[0]]
        null = np.linalg.solve(null[:, np.sort(piv)], null)
        null = null[np.argsort([int(np.flatnonzero(np.abs(v) > 1e-12)[0]) for v in null])]
    if rank < Ja.shape[1]:
        # unidentifiable directions: infinite variance along them
        inf = np.abs(null).max(axis=0) > 1e-9
        V = V.copy()
        V[inf, :] = np.inf
        V[:, inf] = np.inf
    return SetupIdentification(
        tuple(names),
        frozen_floats(est),
        frozen_floats(V),
        frozen_floats(res),
        rank,
        frozen_floats(s),
        frozen_floats(null),
    )
