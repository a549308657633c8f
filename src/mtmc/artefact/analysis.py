"""From measured fiducial centres to setup errors, volumetric errors and distance errors.

Everything here is batched over a leading trial axis (``M``), so that one call evaluates
the noise-free case (``M = 1``), a block of Monte Carlo trials, or the perturbed points of
the GUM's sensitivities. Inputs, all in the frame ``W`` of the last part-side body, mm:

- ``measured`` ``(M, R, P, N, 3)``: the fitted centres of ``N`` balls at ``P`` poses in
  ``R`` repetitions;
- ``calibrated`` ``(M, N, 3)``: the CMM centres, mounted.

Definitions (Wang, Cheung and Kong 2022, §§2.4, 3.2, 3.3; ``docs/artefact.md``):

- setup errors ``ΔÊ = J⁺ ΔF`` with ``ΔF = calibrated - measured`` over every ball, pose and
  repetition (eq. 20);
- the *modelled* centres: the measured ones (mean over repetitions) with the identified
  setup errors taken out, ``m̃ = m̄ - Δŵ_i + J_p Δp̂``; the *volumetric error* at a ball
  and pose is ``m̃ - calibrated``;
- the distance errors ``r_ij = d_ij(centres) - d_ij(calibrated)`` for the 10 pairs of five
  balls; ``r_max = max |r_ij|`` and ``r_avg = mean |r_ij|`` per pose (Table 2), from the
  measured centres ("measured", ①) and from the modelled ones ("mathematical model", ②);
- the best-fit residuals: the measured centres of a pose moved by the rigid motion that
  best fits them to the calibrated ones (least squares, Kabsch/Umeyama via the SVD),
  minus the calibrated ones; Table 3 lists, per ball and axis, the largest magnitude over
  the poses.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.artefact.artefact import _ro, distances

__all__ = ["ANALYSIS_OUTPUTS", "Analysis", "analyse", "rigid_fit_residuals"]

_F = NDArray[np.float64]

#: The outputs of :func:`analyse`, each ``(M, d)``, mm.
ANALYSIS_OUTPUTS = (
    "setup",
    "centres",
    "volumetric",
    "distance_error_measured",
    "distance_error_model",
    "r_max_measured",
    "r_avg_measured",
    "r_max_model",
    "r_avg_model",
    "best_fit_residuals",
    "table3",
)


def rigid_fit_residuals(points: npt.ArrayLike, reference: npt.ArrayLike) -> _F:
    """Residuals of the least-squares rigid fit of point sets onto a reference, batched.

    The rotation ``R`` and translation ``t`` minimising ``Σ_i |R x_i + t - y_i|²`` (Kabsch
    1976 / Umeyama 1991: the SVD of the cross-covariance, with the sign of the last
    singular vector fixed so that ``det R = +1``); returns ``R x_i + t - y_i``.

    Parameters
    ----------
    points : array_like, shape (..., N, 3)
        The sets to move, mm.
    reference : array_like, shape (..., N, 3)
        The reference sets (broadcast against ``points``), mm.

    Returns
    -------
    ndarray, shape (..., N, 3)
        mm.

    Examples
    --------
    >>> ref = np.array([[0.0, 0, 0], [1, 0, 0], [0, 2, 0], [0, 0, 3]])
    >>> moved = ref @ np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]).T + 5.0
    >>> bool(np.abs(rigid_fit_residuals(moved, ref)).max() < 1e-12)
    True
    """
    X = np.asarray(points, dtype=np.float64)
    Y = np.asarray(reference, dtype=np.float64)
    X, Y = np.broadcast_arrays(X, Y)
    xc = X.mean(axis=-2, keepdims=True)
    yc = Y.mean(axis=-2, keepdims=True)
    H = np.swapaxes(X - xc, -1, -2) @ (Y - yc)  # (..., 3, 3)
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(np.swapaxes(Vt, -1, -2) @ np.swapaxes(U, -1, -2)))
    D = np.ones((*d.shape, 3))
    D[..., 2] = np.where(d == 0, 1.0, d)
    Rm = np.swapaxes(Vt, -1, -2) @ (D[..., :, None] * np.swapaxes(U, -1, -2))
    moved = (X - xc) @ np.swapaxes(Rm, -1, -2) + yc
    return np.asarray(moved - Y, dtype=np.float64)


@dataclass(frozen=True, eq=False)
class Analysis:
    """The quantities of Tables 2 and 3 and of Fig. 7 for a batch of ``M`` evaluations.

    Every array has the trial axis first and is read-only; lengths in mm.

    Attributes
    ----------
    setup : ndarray, shape (M, 3 + 3N)
        Identified setup errors ``ΔÊ`` (eq. 18 order).
    centres : ndarray, shape (M, P, N, 3)
        Measured centres, mean over the repetitions.
    modelled : ndarray, shape (M, P, N, 3)
        Centres with the identified setup errors taken out.
    volumetric : ndarray, shape (M, P, N, 3)
        ``modelled - calibrated``.
    distance_error_measured, distance_error_model : ndarray, shape (M, P, N(N-1)/2)
        ``r_ij`` from the measured and the modelled centres.
    r_max_measured, r_avg_measured, r_max_model, r_avg_model : ndarray, shape (M, P)
        Table 2's columns ① and ②.
    best_fit_residuals : ndarray, shape (M, P, N, 3)
        Measured centres after the rigid best fit to the calibrated ones, minus those.
    table3 : ndarray, shape (M, N, 3)
        Largest ``|best_fit_residuals|`` over the poses, per ball and axis.
    """

    setup: _F
    centres: _F
    modelled: _F
    volumetric: _F
    distance_error_measured: _F
    distance_error_model: _F
    r_max_measured: _F
    r_avg_measured: _F
    r_max_model: _F
    r_avg_model: _F
    best_fit_residuals: _F
    table3: _F

    def flat(self) -> dict[str, _F]:
        """The outputs of :data:`ANALYSIS_OUTPUTS` as ``(M, d)`` arrays (C order)."""
        out = {}
        for name in ANALYSIS_OUTPUTS:
            a = getattr(self, name)
            out[name] = a.reshape(a.shape[0], -1)
        return out

    def by_pose(self) -> dict[str, _F]:
        """The outputs with a pose axis split into one output per pose, ``name/p``.

        ``setup`` and ``table3`` stay whole; each other output ``name`` becomes
        ``name/0`` … ``name/(P-1)``, each ``(M, d/P)`` (``(M,)`` for ``r_max``, ``r_avg``).
        """
        out: dict[str, _F] = {}
        for name in ANALYSIS_OUTPUTS:
            a = getattr(self, name)
            if name in ("setup", "table3"):
                out[name] = a.reshape(a.shape[0], -1)
                continue
            for p in range(a.shape[1]):
                part = a[:, p]
                out[f"{name}/{p}"] = part if part.ndim == 1 else part.reshape(a.shape[0], -1)
        return out


def analyse(
    measured: npt.ArrayLike,
    calibrated: npt.ArrayLike,
    pinv: npt.ArrayLike,
    probe_jacobian: npt.ArrayLike,
) -> Analysis:
    """Setup errors, modelled centres, distance errors and best-fit residuals, batched.

    Parameters
    ----------
    measured : array_like, shape (M, R, P, N, 3)
        Fitted centres, mm.
    calibrated : array_like, shape (M, N, 3) or (N, 3)
        Calibrated (mounted) centres, mm.
    pinv : array_like, shape (3 + 3N, R P N 3)
        The pseudo-inverse of the identification Jacobian for the ``R`` repetitions of
        the ``P`` poses, rows in the order of ``measured``.
    probe_jacobian : array_like, shape (P, N, 3, 3)
        ``J_p`` at each pose and ball (:meth:`FiducialSetup.probe_jacobian`).

    Returns
    -------
    Analysis
    """
    m = np.asarray(measured, dtype=np.float64)
    M, _R, _P, N = m.shape[:4]
    cal = np.broadcast_to(np.asarray(calibrated, dtype=np.float64), (M, N, 3))
    dF = (cal[:, None, None] - m).reshape(M, -1)
    E = dF @ np.asarray(pinv, dtype=np.float64).T  # (M, 3 + 3N)
    dp = E[:, :3]
    dw = E[:, 3:].reshape(M, N, 3)
    mean = m.mean(axis=1)  # (M, P, N, 3)
    Jp = np.asarray(probe_jacobian, dtype=np.float64)
    modelled = mean - dw[:, None] + np.einsum("pnij,mj->mpni", Jp, dp)
    vol = modelled - cal[:, None]
    d_cal = distances(cal)[:, None, :]
    r_meas = distances(mean) - d_cal
    r_model = distances(modelled) - d_cal
    res = rigid_fit_residuals(mean, cal[:, None])
    return Analysis(
        _ro(E),
        _ro(mean),
        _ro(modelled),
        _ro(vol),
        _ro(r_meas),
        _ro(r_model),
        _ro(np.abs(r_meas).max(axis=2)),
        _ro(np.abs(r_meas).mean(axis=2)),
        _ro(np.abs(r_model).max(axis=2)),
        _ro(np.abs(r_model).mean(axis=2)),
        _ro(res),
        _ro(np.abs(res).max(axis=1)),
    )
