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
  best fits them to the calibrated ones (least squares, Kabsch/Umeyama: the polar factor
  of the cross-covariance, :func:`best_rotation`), minus the calibrated ones; Table 3
  lists, per ball and axis, the largest magnitude over the poses.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.artefact.artefact import distances
from mtmc.frozen import read_only

__all__ = ["ANALYSIS_OUTPUTS", "Analysis", "analyse", "best_rotation", "rigid_fit_residuals"]

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


def _cofactor(x: list[_F]) -> tuple[list[_F], _F]:
    """Cofactors and determinant of 3 × 3 matrices given as 9 component arrays (row-major)."""
    a, b, c, d, e, f, g, h, i = x
    cof = [e * i - f * h, f * g - d * i, d * h - e * g,
           c * h - b * i, a * i - c * g, b * g - a * h,
           b * f - c * e, c * d - a * f, a * e - b * d]  # fmt: skip
    return cof, a * cof[0] + b * cof[1] + c * cof[2]


def _kabsch_svd(H: _F) -> _F:
    """``R = V D Uᵀ`` from the SVD ``H = U S Vᵀ``, ``D = diag(1, 1, ±1)``: ``det R = +1``."""
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(np.swapaxes(Vt, -1, -2) @ np.swapaxes(U, -1, -2)))
    D = np.ones((*d.shape, 3))
    D[..., 2] = np.where(d == 0, 1.0, d)
    return np.asarray(
        np.swapaxes(Vt, -1, -2) @ (D[..., :, None] * np.swapaxes(U, -1, -2)), dtype=np.float64
    )


def best_rotation(H: npt.ArrayLike, max_iter: int = 40) -> _F:
    """The rotation ``R`` maximising ``tr(R H)``, batched (Kabsch 1976, Umeyama 1991).

    For ``det H > 0`` it is the orthogonal polar factor of ``Hᵀ``, found by Newton's
    iteration ``X ← (g X + X⁻ᵀ / g) / 2`` from ``X = Hᵀ`` with the Frobenius-norm
    scaling ``g = (‖X⁻¹‖ / ‖X‖)^½`` (Higham 1986), ``X⁻ᵀ`` from the cofactors: a few
    element-wise passes over the whole batch instead of one LAPACK SVD per matrix. The
    iteration stops when no entry moves by more than ``10⁻¹⁴`` (the iterates tend to an
    orthogonal matrix, entries of order one); matrices with
    ``det H ≤ 0`` (a reflection would fit better) or not converged go through the SVD
    (``R = V D Uᵀ``, ``D = diag(1, 1, ±1)``). Both give ``R`` to rounding.

    Parameters
    ----------
    H : array_like, shape (..., 3, 3)
        Cross-covariances ``Σ (x_i - x̄)(y_i - ȳ)ᵀ``.
    max_iter : int
        Newton steps at most.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``det R = +1``.

    Examples
    --------
    >>> Rz = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
    >>> H = np.diag([3.0, 2.0, 1.0]) @ Rz.T   # x = diag points, y = Rz x
    >>> bool(np.allclose(best_rotation(H), Rz, atol=1e-15))
    True
    """
    Hm = np.asarray(H, dtype=np.float64)
    shape = Hm.shape
    Hb = Hm.reshape(-1, 3, 3)
    x = list(np.swapaxes(Hb, -1, -2).reshape(-1, 9).T.copy())  # X = Hᵀ, 9 components
    cof, det = _cofactor(x)
    norm = np.sqrt(sum(v * v for v in x))
    bad = ~(det > 1e-13 * norm**3)  # a reflection fits better, or H is (nearly) singular
    if bad.any():
        for k in range(9):
            x[k] = np.where(bad, float(k in (0, 4, 8)), x[k])
        cof, det = _cofactor(x)
    for _ in range(max_iter):
        inv_t = [v / det for v in cof]  # X⁻ᵀ
        g = np.sqrt(np.sqrt(sum(v * v for v in inv_t)) / np.sqrt(sum(v * v for v in x)))
        # unscaled steps once close: the scaling only speeds up the first ones
        g = np.where(np.abs(g - 1.0) < 1e-3, 1.0, g)
        gi = 1.0 / g
        new = [0.5 * (g * u + gi * v) for u, v in zip(x, inv_t, strict=True)]
        change = np.max([np.abs(u - v) for u, v in zip(new, x, strict=True)], axis=0)
        x = new
        if change.max() <= 1e-14:
            break
        cof, det = _cofactor(x)
    else:
        bad |= change > 1e-14
    R = np.stack(x, axis=-1).reshape(-1, 3, 3)
    if bad.any():
        R[bad] = _kabsch_svd(Hb[bad])
    return R.reshape(shape)


def rigid_fit_residuals(points: npt.ArrayLike, reference: npt.ArrayLike) -> _F:
    """Residuals of the least-squares rigid fit of point sets onto a reference, batched.

    The rotation ``R`` and translation ``t`` minimising ``Σ_i |R x_i + t - y_i|²`` (Kabsch
    1976 / Umeyama 1991: ``R`` from the cross-covariance, :func:`best_rotation`, with
    ``det R = +1``); returns ``R x_i + t - y_i``.

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
    Rm = best_rotation(H)
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
    # each E[t, j] a dot product of two contiguous rows summed by einsum's own kernel, not
    # by BLAS: a threaded GEMM sums in an order that depends on its thread count (a Dask
    # worker runs one thread), and a run must give the same bits wherever it runs
    pinv_c = np.ascontiguousarray(np.asarray(pinv, dtype=np.float64))
    E = np.einsum("mk,jk->mj", np.ascontiguousarray(dF), pinv_c)  # (M, 3 + 3N)
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
    a_meas, a_model = np.abs(r_meas), np.abs(r_model)
    return Analysis(
        *(
            read_only(v)
            for v in (
                E,
                mean,
                modelled,
                vol,
                r_meas,
                r_model,
                a_meas.max(axis=2),
                a_meas.mean(axis=2),
                a_model.max(axis=2),
                a_model.mean(axis=2),
                res,
                np.abs(res).max(axis=1),
            )
        )
    )
