"""Monte Carlo of a whole laser-tracker verification (Aguado et al. 2017), and its GUM twin.

One trial re-creates one verification: the machine (its true errors, possibly richer than
the identification model) moves the reflector to the ``N`` points; the tracker reads each
point with noise in spherical coordinates (range ``a + b·L``, azimuth and elevation
constant; Aguado et al. 2016 eqs. 22–24); the error functions and (optionally) the tracker
pose are identified from the readings (eq. 17); the volumetric errors before and after,
the coefficients and the error left after compensation at every point are recorded. The
trials run through the engine :func:`mtmc.uncertainty.monte_carlo` (seeded blocks); the
model is vectorised over trials.

Identification of the ``M`` trials (a shared factorisation, then exact)
-----------------------------------------------------------------------
The noise-free verification is identified once, exactly (:func:`identify`): solution
``(θ̄, R̄, t̄)``, Jacobian ``J₀`` (3N × p) with QR factors giving ``A = J₀⁺`` and
``H₀⁻¹ = (J₀ᵀJ₀)⁻¹``. Each trial is then solved in two stages, all trials at once:

1. chord Gauss–Newton iterations ``δ = −A r(θ, R, t)``, the pose part exact
   (``x = Rᵀ(p − t)``, ``R ← R Exp(δω)``), the machine part linearised,
   ``p = p̄ + J_p (θ − θ̄)``. The readings enter once per trial, ``b = A (ȳ − x)`` with
   ``ȳ = R̄ᵀ(p̄ − t̄)`` the model's readings at the reference; with ``E = R̄ᵀR`` and
   ``Δt = t − t̄`` an iteration is then
   ``A r = b + Σ_ij (E − I)_ij G_ij − S (Rᵀ Δt) + Σ_ij R_ij K_ij (θ − θ̄)``, whose operators
   ``G_ij = Σ_n A_n,j ȳ_n,i``, ``S_j = Σ_n A_n,j`` and ``K_ij = Σ_n A_n,j (J_p)_n,i`` are
   computed once (``A_n,j`` the columns of ``A`` of reading ``j`` of point ``n``): a few
   hundred operations a trial instead of ``6N p``. Their fixed point solves
   ``J₀ᵀ r = 0``, not the trial's own normal equations ``J(θ, R, t)ᵀ r = 0``: it lies
   about 10⁻⁴ u from the trial's optimum (``u`` the coefficient's standard uncertainty),
   which is 10⁻² relative for a coefficient near zero.
2. ``refine`` exact steps ``δ = −H₀⁻¹ J(θ, R, t)ᵀ r(θ, R, t)``: the residual from the
   machine model itself at each trial's parameters and the exact gradient (the machine's
   analytic Jacobian per trial times the residual, in reverse mode,
   :meth:`~mtmc.kinematics.Machine.jacobian_transpose`, block by block; the Jacobian
   itself is never formed). Their fixed point is the trial's exact least-squares solution;
   ``H₀`` only sets the rate, a factor of about 10⁻⁵ per step (the change of ``J``
   between trials and the curvature of the rotation), so two steps reach the rounding
   floor. The result equals the per-trial solution of :func:`identify` and of
   ``scipy.optimize.least_squares`` to better than 10⁻⁶ relative on every coefficient
   (tested; figures in ``docs/performance.md``).

Inputs of the engine (named): ``noise``, ``iid(normal(0, 1), 3N)``, the standard normal
numbers of ``(L, α, β)`` of each point; optionally ``repeatability`` (``3N`` standard
normals times the machine's repeatability, base frame), ``pose`` (6 standard normals
times the standard uncertainties of the tracker pose: rotation vector, rad; position,
mm) and ``reflector`` (3 standard normals times the uncertainty of the reflector offset,
mm, taken to first order through the machine's EXT EYT EZT Jacobian).

Outputs (named, mm and the coefficients' units):

- ``ve`` ``(m, 9)``: max, mean, min over the points of the initial volumetric error
  (readings against the nominal machine, Aguado et al. 2016 eq. 17 before
  identification), of the residual (eq. 17 after) and of the compensated error (below)
  (:data:`VE_NAMES`);
- ``coef`` ``(m, p)``: the identified parameters (:attr:`Identification.names`);
- ``comp`` ``(m, 3·Ne)``: at each evaluation point, the position the identified model
  predicts minus the true one, both in the tracker frame,
  ``R̂ᵀ(p(q; θ̂) − t̂) − R₀ᵀ(p_true − t₀)`` (x, y, z per point): the error the machine
  keeps after compensation with the identified functions. Its mean is the model's bias
  (zero when the model represents the machine), its standard deviation the calibration
  uncertainty of the point. In the tracker frame, the rigid motion that the tracker pose
  absorbs (constant terms, turns) does not count. Evaluated at the measured points (the
  default), ``R̂ᵀ(p(q; θ̂) − t̂)`` are the model readings of the identification, and the
  trial computes them once for both (the same products, the same bits).
- ``point_initial`` ``(m, N)`` and ``point_compensated`` ``(m, Ne)``: the length of the
  initial error at each measured point and of the compensated error at each evaluation
  point, whose means over the trials give the statistics of :data:`POINT_STATS`.

Two statistics of the volumetric error
--------------------------------------
``ve`` takes the max, mean and min over the points of **one** verification, and its
estimate is their mean over the verifications (the maximum of one verification grows
with the number of points: more readings, more chances of a large noise). The
**per-point** statistics (:meth:`VerificationMC.point_mean_ve`) first take, at each
point, the mean over the verifications of the length of its error, then the max, mean
and min of these means over the points: the error map of an average verification. The
two means coincide; the maxima and minima do not.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import ConvergenceError, InputError
from mtmc.frozen import frozen_floats
from mtmc.geometry.transforms import (
    cross_matrix,
    matrix_from_rotation_vector,
    rotation_vector_from_matrix,
)
from mtmc.instruments.laser_tracker import LaserTracker, NoiseAt
from mtmc.kinematics.parameters import ErrorModel
from mtmc.parallel import one_blas_thread
from mtmc.uncertainty.distributions import IID, Normal
from mtmc.uncertainty.montecarlo import monte_carlo
from mtmc.uncertainty.propagation import Validation, gum, validate
from mtmc.uncertainty.results import MonteCarloResult
from mtmc.verification.identify import (
    POSE_NAMES,
    Identification,
    _error_basis,
    _problem,
    identify,
    ve_stats,
)

__all__ = [
    "POINT_STATS",
    "VE_NAMES",
    "Verification",
    "VerificationModel",
    "VerificationMC",
    "VerificationGUM",
    "simulate",
    "gum_verification",
    "validate_verification",
]

_F = NDArray[np.float64]

#: Columns of the ``ve`` output.
VE_NAMES: tuple[str, ...] = tuple(
    f"{a}.{b}" for a in ("initial", "residual", "compensated") for b in ("max", "mean", "min")
)

#: The errors and statistics of :meth:`VerificationMC.point_mean_ve`.
POINT_STATS: tuple[tuple[str, ...], tuple[str, ...]] = (
    ("initial", "compensated"),
    ("max", "mean", "min"),
)


@dataclass(frozen=True)
class Verification:
    """A verification to simulate.

    Parameters
    ----------
    model : ErrorModel
        The identification model.
    q : ndarray, shape (N, n_axes)
        Commanded positions of the measured points.
    tracker : LaserTracker
        Nominal pose and noise (required).
    true_errors : mapping
        The machine's errors, as :meth:`Machine.tool_position` takes them (may be
        richer than ``model``).
    pose : bool
        Identify the tracker pose.
    fixed : mapping or sequence of str
        Parameters of ``model`` held (see :func:`identify`).
    eval_q : ndarray, shape (Ne, n_axes), optional
        Where the compensation is evaluated (default ``q``).
    exact : bool
        Exact error rotations.
    """

    model: ErrorModel
    q: _F
    tracker: LaserTracker
    true_errors: Mapping[str, Any]
    pose: bool = True
    fixed: Mapping[str, float] | Sequence[str] = ()
    eval_q: _F | None = None
    exact: bool = False

    def __post_init__(self) -> None:
        if self.tracker.noise is None:
            raise InputError("the tracker has no noise model", field="tracker.noise")
        q = np.array(self.q, dtype=np.float64)
        q.setflags(write=False)
        object.__setattr__(self, "q", q)
        if self.eval_q is not None:
            e = np.array(self.eval_q, dtype=np.float64)
            e.setflags(write=False)
            object.__setattr__(self, "eval_q", e)

    @property
    def n_points(self) -> int:
        """Number of measured points ``N``."""
        return int(self.q.shape[0])

    def true_positions(self) -> _F:
        """``(N, 3)`` true positions of the reflector, base frame, mm."""
        return self.model.machine.tool_position(self.q, self.true_errors, exact=self.exact)

    def readings(self) -> _F:
        """``(N, 3)`` noise-free tracker readings, mm."""
        return self.tracker.to_tracker(self.true_positions())


def _rows(a: Any, b: Any) -> Any:
    """``a @ b`` for a batch of trials ``a`` (one per row): each row summed on its own.

    A BLAS product of an ``(m, k)`` batch may sum a row in an order that depends on ``m``
    (its kernels switch with the shape), so a trial's numbers would depend on the block it
    is evaluated in; :func:`numpy.einsum` sums every row the same way whatever ``m``, so a
    seed gives the same bits whatever the chunking, the workers or the executor.
    """
    return np.einsum("mk,kn->mn", a, b)


def _chord_operators(A: _F, p_fit: _F, Jp: _F, R_ref: _F, t_ref: _F) -> tuple[_F, _F, _F, _F]:
    """The operators of the chord iterations (module notes), computed once per model.

    Parameters
    ----------
    A : ndarray, shape (p, 3N)
        ``J₀⁺``.
    p_fit : ndarray, shape (N, 3)
        Model positions at the reference solution, base frame, mm.
    Jp : ndarray, shape (N, 3, k)
        Their derivatives with respect to the free coefficients.
    R_ref, t_ref : ndarray, shape (3, 3) and (3,)
        The reference tracker pose.

    Returns
    -------
    y_ref : ndarray, shape (N, 3)
        The model readings ``R̄ᵀ(p̄ − t̄)``, mm.
    G, S, K : ndarray, shape (p, 9), (p, 3) and (p, 9k)
        C-ordered; the columns of ``G`` and the blocks of ``K`` in the C order of ``i, j``.
    """
    N, k = Jp.shape[0], Jp.shape[2]
    A3 = A.reshape(-1, N, 3)
    p = A3.shape[0]
    y = (p_fit - t_ref) @ R_ref
    # G[p,i,j] = Σₙ A[p,n,j] y[n,i] and K[p,i,j,l] = Σₙ A[p,n,j] Jp[n,i,l] as two BLAS
    # products of the rows (p, j) of A (a three-operand einsum took 80 ms at 5408 points)
    Aj = np.swapaxes(A3, 1, 2).reshape(3 * p, N)
    G = np.ascontiguousarray(np.swapaxes((Aj @ y).reshape(p, 3, 3), 1, 2).reshape(p, 9))
    K = (Aj @ Jp.reshape(N, 3 * k)).reshape(p, 3, 3, k)
    K = np.ascontiguousarray(np.swapaxes(K, 1, 2).reshape(p, 9 * k))
    return y, G, np.ascontiguousarray(A3.sum(axis=1)), K


@dataclass(frozen=True)
class VerificationModel:
    """The vectorised model of one verification per trial (see the module notes).

    Build it with :meth:`build`; call it with the engine's arrays.
    """

    names: tuple[str, ...]
    n_theta: int
    pose: bool
    x_true: _F  # (N, 3) true readings
    p_true: _F  # (N, 3) true positions, base frame
    p_fit: _F  # (N, 3) model positions at the reference solution
    Jp: _F  # (N, 3, n_theta) d p / d theta_free at the reference
    est0: _F  # (p,)
    R_ref: _F
    t_ref: _F
    R_nom: _F
    t_nom: _F
    A: _F  # (p, 3N)
    x_nom: _F  # (N, 3) nominal readings (nominal machine, nominal pose)
    J_tool: _F  # (N, 3, 3) d p / d (EXT, EYT, EZT)
    pe_fit: _F  # (Ne, 3)
    pe_true: _F  # (Ne, 3)
    xe_true: _F  # (Ne, 3) true readings at the evaluation points
    Jpe: _F  # (Ne, 3, n_theta)
    noise: Any
    repeatability: float
    pose_u: _F  # (6,)
    reflector_u: float
    model: ErrorModel = field(repr=False)
    q: _F = field(repr=False)  # (N, n_axes)
    free: NDArray[np.int64] = field(repr=False)  # free parameters of the model
    base: _F = field(repr=False)  # (P,) full parameter vector with the fixed values
    Hinv: _F = field(repr=False)  # (p, p) (J0^T J0)^-1
    basis: tuple[tuple[str, NDArray[np.int64], _F], ...] = field(repr=False)
    noise_at: NoiseAt = field(repr=False)  # the noise at x_true, for every block
    y_ref: _F = field(repr=False)  # (N, 3) model readings at the reference solution
    chord_G: _F = field(repr=False)  # (p, 9) chord operators (module notes)
    chord_S: _F = field(repr=False)  # (p, 3)
    chord_K: _F = field(repr=False)  # (p, 9 n_theta)
    exact: bool = False
    iterations: int = 3
    refine: int = 2
    #: The compensation is evaluated at the measured points (``eval_q`` not given): the
    #: evaluation arrays are the measured points' and the compensated readings are the
    #: model readings of the identification.
    at_measured: bool = False

    @classmethod
    def build(
        cls,
        ver: Verification,
        reference: Identification,
        *,
        repeatability: float = 0.0,
        pose_u: npt.ArrayLike | None = None,
        reflector_u: float = 0.0,
        refine: int | None = None,
    ) -> VerificationModel:
        """Precompute the reference solution's factors.

        Parameters
        ----------
        ver : Verification
        reference : Identification
            The noise-free identification of ``ver`` (one set of readings).
        repeatability : float
            Standard deviation of the machine's positioning per coordinate, mm.
        pose_u : array_like, shape (6,), optional
            Standard uncertainties of the tracker pose (rotation vector, rad; position, mm);
            only when the pose is not identified.
        reflector_u : float
            Standard uncertainty of each component of the reflector offset, mm.
        refine : int, optional
            Exact steps after the chord iterations (module notes). By default
            :data:`REFINE` for at most :data:`REFINE_POINTS` points, none above: an exact
            step costs about 1 µs of CPU per point and trial (the machine model and its
            gradient at every trial), so the 5408-point mesh keeps the chord solution
            (within 2·10⁻⁴ u).

        Returns
        -------
        VerificationModel
        """
        prob = _problem(ver.model, ver.q, ver.tracker, ver.pose, ver.fixed, ver.exact)
        noise = ver.tracker.noise
        if noise is None:  # pragma: no cover - Verification checks it
            raise InputError("the tracker has no noise model", field="tracker.noise")
        p_true = ver.true_positions()
        x_true = ver.tracker.to_tracker(p_true)  # ver.readings()
        th = reference.theta[:1]
        p_fit = ver.model.tool_position(ver.q, th[0], exact=ver.exact)
        n_th = prob.free.size
        J0 = reference.jacobian[0]
        Q, R = np.linalg.qr(J0)
        A = np.linalg.solve(R, Q.T)
        Ri = np.linalg.inv(R)
        m = ver.model
        # C-ordered copies: a view here would be a contiguous array in a worker process
        # (pickling copies), and the products of the model would sum in another order
        Jp = np.ascontiguousarray(m.jacobian(ver.q, th[0], exact=ver.exact)[:, :, prob.free])
        # evaluated at the measured points (the default): the same arrays, computed once
        eq = ver.q if ver.eval_q is None else ver.eval_q
        same = ver.eval_q is None
        Jpe = (
            Jp
            if same
            else np.ascontiguousarray(m.jacobian(eq, th[0], exact=ver.exact)[:, :, prob.free])
        )
        pu = np.zeros(6) if pose_u is None else np.asarray(pose_u, dtype=np.float64)
        if pu.shape != (6,) or np.any(pu < 0):
            raise InputError("expected 6 standard uncertainties >= 0", field="pose_u")
        if ver.pose and np.any(pu > 0):
            raise InputError(
                "the tracker pose is identified, so its uncertainty is absorbed exactly; "
                "give pose_u only when the pose is not identified (pose = false)",
                field="pose_u",
            )
        nominal = m.machine.tool_position(ver.q)
        chord = _chord_operators(A, p_fit, Jp, reference.rotation[0], reference.position[0])
        J_tool = m.machine.jacobian(
            ver.q, ver.true_errors, names=("EXT", "EYT", "EZT"), exact=ver.exact
        )
        pe_true = p_true if same else m.machine.tool_position(eq, ver.true_errors, exact=ver.exact)
        return cls(
            names=reference.names,
            n_theta=n_th,
            pose=ver.pose,
            x_true=x_true,
            p_true=p_true,
            p_fit=p_fit,
            Jp=Jp,
            est0=np.array(reference.estimate[0]),
            R_ref=np.array(reference.rotation[0]),
            t_ref=np.array(reference.position[0]),
            R_nom=ver.tracker.rotation,
            t_nom=ver.tracker.position,
            A=A,
            x_nom=ver.tracker.to_tracker(nominal),
            J_tool=J_tool,
            pe_fit=p_fit if same else m.tool_position(eq, th[0], exact=ver.exact),
            pe_true=pe_true,
            xe_true=x_true if same else ver.tracker.to_tracker(pe_true),
            Jpe=Jpe,
            noise=noise,
            repeatability=float(repeatability),
            pose_u=pu,
            reflector_u=float(reflector_u),
            model=m,
            q=ver.q,
            free=prob.free,
            base=prob.base,
            Hinv=Ri @ Ri.T,
            y_ref=chord[0],
            chord_G=chord[1],
            chord_S=chord[2],
            chord_K=chord[3],
            basis=_error_basis(m, ver.q),
            noise_at=noise.at(x_true),
            exact=ver.exact,
            refine=(REFINE if ver.n_points <= REFINE_POINTS else 0) if refine is None else refine,
            at_measured=same,
        )

    def inputs(self) -> dict[str, IID]:
        """The engine's inputs: standard normals, scaled inside the model."""
        n3 = 3 * self.x_true.shape[0]
        out = {"noise": IID(Normal(0.0, 1.0), n3)}
        if self.repeatability > 0:
            out["repeatability"] = IID(Normal(0.0, 1.0), n3)
        if np.any(self.pose_u > 0):
            out["pose"] = IID(Normal(0.0, 1.0), 6)
        if self.reflector_u > 0:
            out["reflector"] = IID(Normal(0.0, 1.0), 3)
        return out

    def true_readings(
        self,
        m: int,
        repeatability: _F | None = None,
        pose: _F | None = None,
        reflector: _F | None = None,
    ) -> Any:
        """True readings of ``m`` trials ``(m, N, 3)`` with the optional inputs applied."""
        N = self.x_true.shape[0]
        if repeatability is None and pose is None and reflector is None:
            return np.broadcast_to(self.x_true, (m, N, 3))
        p = np.broadcast_to(self.p_true, (m, N, 3))
        if repeatability is not None:
            p = p + self.repeatability * repeatability.reshape(m, N, 3)
        if reflector is not None:
            p = p + np.einsum("nij,mj->mni", self.J_tool, self.reflector_u * reflector)
        R = np.broadcast_to(self.R_nom, (m, 3, 3))
        t = np.broadcast_to(self.t_nom, (m, 3))
        if pose is not None:
            dp = pose * self.pose_u
            R = self.R_nom @ matrix_from_rotation_vector(dp[:, :3])
            t = self.t_nom + dp[:, 3:]
        return np.einsum("mij,mni->mnj", R, p - t[:, None, :])

    def solve(self, x_meas: Any) -> tuple[Any, Any, Any, Any]:
        """Identify ``m`` sets of readings ``(m, N, 3)`` (chord, then exact steps).

        Returns
        -------
        est : ndarray, shape (m, p)
        residuals : ndarray, shape (m, N, 3)
            Model minus reading.
        R, t : ndarray, shape (m, 3, 3) and (m, 3)
            The identified tracker pose.
        """
        est, xr, R, t = self._solve(x_meas)
        return est, xr - x_meas, R, t

    def _solve(self, x_meas: Any) -> tuple[Any, Any, Any, Any]:
        """:meth:`solve`, returning the model readings ``R̂ᵀ(p(q; θ̂) − t̂)`` for the residuals."""
        m, N = x_meas.shape[:2]
        k = self.n_theta
        est = np.broadcast_to(self.est0, (m, self.est0.size)).copy()
        R = np.broadcast_to(self.R_ref, (m, 3, 3)).copy()
        t = np.broadcast_to(self.t_ref, (m, 3)).copy()
        Jt = self.Jp.reshape(3 * N, k).T  # (k, 3N)
        # chord iterations, all trials at once; the readings enter once, b = A (ȳ - x)
        b = _rows((self.y_ref - x_meas).reshape(m, 3 * N), self.A.T)
        eye = np.eye(3)
        for _ in range(self.iterations):
            dE = (np.swapaxes(self.R_ref, -1, -2) @ R - eye).reshape(m, 9)  # E - I
            dtR = np.einsum("mi,mij->mj", t - self.t_ref, R)  # R^T (t - t_ref)
            U = (R.reshape(m, 9, 1) * (est[:, None, :k] - self.est0[:k])).reshape(m, -1)
            Ar = b + np.einsum("mq,pq->mp", dE, self.chord_G)
            Ar -= np.einsum("mj,pj->mp", dtR, self.chord_S)
            Ar += np.einsum("mq,pq->mp", U, self.chord_K)
            d = -Ar
            est += d
            if self.pose:
                R = R @ matrix_from_rotation_vector(d[:, k : k + 3])
                t = t + d[:, k + 3 : k + 6]
        for _ in range(self.refine):  # exact steps, all trials at once
            d = -_rows(self.gradient(est, R, t, x_meas), self.Hinv)
            est[:, :k] += d[:, :k]
            if self.pose:
                R = R @ matrix_from_rotation_vector(d[:, k : k + 3])
                t = t + d[:, k + 3 : k + 6]
        if self.pose:  # the pose as reported by identify: Log(R0^T R), t - t0
            est[:, k : k + 3] = rotation_vector_from_matrix(np.swapaxes(self.R_nom, -1, -2) @ R)
            est[:, k + 3 : k + 6] = t - self.t_nom
        p = self.p_fit + _rows(est[:, :k] - self.est0[:k], Jt).reshape(m, N, 3)
        return est, (p - t[:, None, :]) @ R, R, t

    def gradient(self, est: _F, R: _F, t: _F, x_meas: Any) -> _F:
        """Exact gradient ``J(θ, R, t)ᵀ r`` of ``½|r|²`` for ``m`` trials, shape (m, p).

        ``r = Rᵀ(p(q; θ) − t) − x_meas`` with the machine model evaluated at each trial's
        parameters; ``∂r/∂θ = Rᵀ ∂p/∂θ`` from the machine's analytic Jacobian (per
        trial, in blocks of about :data:`_ROWS` points, ``(∂p/∂θ)ᵀ R r`` in reverse
        mode), ``∂r/∂δω = [x]×``,
        ``∂r/∂δt = −Rᵀ`` (the parametrisation of :func:`identify`).
        """
        m, N = x_meas.shape[:2]
        k = self.n_theta
        mach = self.model.machine
        th = np.broadcast_to(self.base, (m, self.base.size)).copy()
        th[:, self.free] = est[:, :k]
        g_th = np.zeros((m, self.base.size))
        g = np.zeros(est.shape)
        names = tuple(n for n, _, _ in self.basis)
        step = max(1, _ROWS // N)
        for a in range(0, m, step):  # blocks of trials, bounded memory
            b = min(m, a + step)
            qq = np.broadcast_to(self.q, (b - a, *self.q.shape)).reshape((b - a) * N, -1)
            errs = {n: _rows(th[a:b, idx], B.T).ravel() for n, idx, B in self.basis}
            p = mach.tool_position(qq, errs, exact=self.exact).reshape(b - a, N, 3)
            xr = (p - t[a:b, None, :]) @ R[a:b]  # model readings
            r = xr - x_meas[a:b]
            w = np.einsum("mij,mnj->mni", R[a:b], r).reshape(-1, 3)  # R r: base frame
            s = mach.jacobian_transpose(qq, errs, w, names=names, exact=self.exact)
            s = s.reshape(b - a, N, -1)
            for ie, (_, idx, B) in enumerate(self.basis):
                g_th[a:b, idx] = _rows(s[:, :, ie], B)
            if self.pose:
                g[a:b, k : k + 3] = np.sum(np.cross(r, xr), axis=1)
                g[a:b, k + 3 : k + 6] = -np.einsum("mij,mj->mi", R[a:b], r.sum(axis=1))
        g[:, :k] = g_th[:, self.free]
        return g

    def __call__(
        self,
        noise: Any,
        repeatability: Any = None,
        pose: Any = None,
        reflector: Any = None,
    ) -> dict[str, Any]:
        """One verification per trial; see the module notes for inputs and outputs.

        The trials go in slices of at most :data:`_SLICE` readings (trials × points), each
        trial computed on its own: the same numbers as one pass over the block, with the
        working arrays of a slice (a few MB) instead of those of the whole block (some
        hundred MB for a block of 5408-point verifications).
        """
        m = noise.shape[0]
        step = max(1, _SLICE // self.x_true.shape[0])
        if m <= step:
            return self._trials(noise, repeatability, pose, reflector)
        out: dict[str, Any] = {}
        inputs = (noise, repeatability, pose, reflector)
        for a in range(0, m, step):
            part = self._trials(*(None if v is None else v[a : a + step] for v in inputs))
            if not out:
                out = {k: np.empty((m, *v.shape[1:])) for k, v in part.items()}
            for k, v in part.items():
                out[k][a : a + step] = v
        return out

    def _trials(
        self,
        noise: Any,
        repeatability: Any = None,
        pose: Any = None,
        reflector: Any = None,
    ) -> dict[str, Any]:
        """The outputs of one slice of trials (:meth:`__call__`)."""
        m = noise.shape[0]
        N = self.x_true.shape[0]
        z = noise.reshape(m, N, 3)
        if repeatability is None and pose is None and reflector is None:
            # the same true readings in every trial: their spherical coordinates and
            # standard deviations were computed once (the same bits as perturb)
            x_meas = self.noise_at.perturb(z)
        else:
            x_meas = self.noise.perturb(self.true_readings(m, repeatability, pose, reflector), z)
        est, xr, R, t = self._solve(x_meas)
        r = xr - x_meas
        init = np.sqrt(np.sum((x_meas - self.x_nom) ** 2, axis=-1))
        res = np.sqrt(np.sum(r * r, axis=-1))
        if self.at_measured:
            # the compensated readings at the measured points are the model readings
            # (the same products as below with the same arrays)
            comp = xr - self.xe_true
        else:
            k = self.n_theta
            Ne = self.pe_fit.shape[0]
            Jte = self.Jpe.reshape(3 * Ne, k).T
            pe = self.pe_fit + _rows(est[:, :k] - self.est0[:k], Jte).reshape(m, Ne, 3)
            comp = (pe - t[:, None, :]) @ R - self.xe_true
        ce = np.sqrt(np.sum(comp * comp, axis=-1))
        ve = np.concatenate([ve_stats(init), ve_stats(res), ve_stats(ce)], axis=1)
        return {
            "ve": ve,
            "coef": est,
            "comp": comp.reshape(m, -1),
            "point_initial": init,
            "point_compensated": ce,
        }


#: Default exact steps of :meth:`VerificationModel.solve`, and the most points for them.
REFINE: int = 2
REFINE_POINTS: int = 1000

#: Points per block of the exact gradient (about 30 MB of machine Jacobian).
_ROWS = 65536

#: Readings (trials × points) per slice of :meth:`VerificationModel.__call__`.
_SLICE = 131072


@dataclass(frozen=True)
class VerificationGUM:
    """GUM linearisation of the identification (JCGM 100 §5, JCGM 102 §6.2).

    Attributes
    ----------
    names : tuple of str
    cov : ndarray, shape (p, p)
        ``A Σ Aᵀ``: ``A = J₀⁺`` the sensitivity of the parameters to the readings at the
        reference solution, ``Σ`` the readings' covariance (tracker noise linearised
        through the spherical coordinates, plus the optional inputs).
    u : ndarray, shape (p,)
    point_cov : ndarray, shape (Ne, 3, 3)
        ``G Cov G ᵀ`` of the compensated position at each evaluation point (tracker
        frame; ``G`` its derivative with respect to the parameters and pose), mm².
    point_u : ndarray, shape (Ne,)
        ``√trace`` of :attr:`point_cov`, mm.
    """

    names: tuple[str, ...]
    cov: _F
    u: _F
    point_cov: _F = field(repr=False)
    point_u: _F = field(repr=False)


def _gum_propagate(A: _F, C: _F, G: _F, extra: Sequence[_F] = ()) -> tuple[_F, _F]:
    """The GUM covariance of identified parameters and of the points they compensate.

    Parameters
    ----------
    A : ndarray, shape (p, 3N)
        Sensitivity of the parameters to the readings (``J⁺`` at the solution).
    C : ndarray, shape (N, 3, 3)
        Covariance of each reading, mm².
    G : ndarray, shape (Ne, 3, p)
        Sensitivity of the compensated points (tracker frame) to the parameters.
    extra : sequence of ndarray, shape (N, 3, k)
        Sensitivities of the readings to further independent inputs of unit variance.

    Returns
    -------
    cov : ndarray, shape (p, p)
        ``A Σ Aᵀ`` with ``Σ`` the block-diagonal ``C`` plus ``Σ_e E Eᵀ`` of each ``extra``.
    point_cov : ndarray, shape (Ne, 3, 3)
        ``G cov Gᵀ`` at each point, mm².
    """
    N = C.shape[0]
    p = A.shape[0]
    A3 = A.reshape(p, N, 3)
    # A Σ Aᵀ as one product of (p, 3N) matrices, Σ block-diagonal: 20 times faster than
    # one three-operand einsum at 5408 points (0.02 against 0.38 s), the same to 2e-15
    # relative; each result made exactly symmetric
    cov = np.einsum("pni,nij->pnj", A3, C).reshape(p, 3 * N) @ A.reshape(p, 3 * N).T
    for E in extra:
        AG = np.einsum("pni,nik->pk", A3, E)
        cov = cov + AG @ AG.T
    cov = 0.5 * (cov + cov.T)
    pc = (G @ cov) @ G.transpose(0, 2, 1)
    return cov, 0.5 * (pc + pc.transpose(0, 2, 1))


def gum_verification(vm: VerificationModel) -> VerificationGUM:
    """The GUM covariance of the identified parameters and compensated points.

    Parameters
    ----------
    vm : VerificationModel

    Returns
    -------
    VerificationGUM
    """
    N = vm.x_true.shape[0]
    C = vm.noise.covariance(vm.x_true)  # (N, 3, 3)
    if vm.repeatability > 0:
        C = C + vm.repeatability**2 * np.eye(3)
    extra = []
    if np.any(vm.pose_u > 0):
        G = np.concatenate(
            [cross_matrix(vm.x_true), -np.broadcast_to(vm.R_nom.T, (N, 3, 3))], axis=-1
        )  # (N, 3, 6)
        extra.append(G * vm.pose_u)
    if vm.reflector_u > 0:
        extra.append(np.einsum("ji,njk->nik", vm.R_nom, vm.J_tool) * vm.reflector_u)
    G = np.einsum("ji,njk->nik", vm.R_ref, vm.Jpe)  # R̂ᵀ ∂p/∂θ at the evaluation points
    if vm.pose:
        xe = np.einsum("ji,nj->ni", vm.R_ref, vm.pe_fit - vm.t_ref)
        Ne = xe.shape[0]
        G = np.concatenate([G, cross_matrix(xe), -np.broadcast_to(vm.R_ref.T, (Ne, 3, 3))], axis=-1)
    cov, pc = _gum_propagate(vm.A, C, G, extra)
    return VerificationGUM(
        vm.names,
        frozen_floats(cov),
        frozen_floats(np.sqrt(np.diag(cov))),
        frozen_floats(pc),
        frozen_floats(np.sqrt(np.trace(pc, axis1=1, axis2=2))),
    )


@dataclass(frozen=True)
class VerificationMC:
    """Result of :func:`simulate` (arrays read-only; lengths in mm).

    Attributes
    ----------
    trials, seed : int
    names : tuple of str
        The identified parameters.
    ve_estimate, ve_u : ndarray, shape (9,)
        Mean and standard deviation over the trials of the :data:`VE_NAMES` statistics.
    ve_samples : ndarray, shape (M, 9)
    coef_estimate, coef_u : ndarray, shape (p,)
    coef_cov : ndarray, shape (p, p)
    coef_samples : ndarray, shape (M, p)
    comp_bias : ndarray, shape (Ne, 3)
        Mean over trials of the compensated minus the true position (tracker frame).
    comp_u : ndarray, shape (Ne, 3)
        Its standard deviation per coordinate (the calibration uncertainty).
    point_u : ndarray, shape (Ne,)
        ``√(u_x² + u_y² + u_z²)`` per point.
    gum : VerificationGUM
    reference : Identification
        The noise-free identification.
    initial_point_mean, initial_point_u : ndarray, shape (N,)
        Mean and standard deviation over the trials of the length of the initial error at
        each measured point.
    compensated_point_mean, compensated_point_u : ndarray, shape (Ne,)
        The same for the error left after compensation at each evaluation point.
    """

    trials: int
    seed: int | None
    names: tuple[str, ...]
    ve_estimate: _F
    ve_u: _F
    ve_samples: _F = field(repr=False)
    coef_estimate: _F = field(repr=False)
    coef_u: _F = field(repr=False)
    coef_cov: _F = field(repr=False)
    coef_samples: _F = field(repr=False)
    comp_bias: _F = field(repr=False)
    comp_u: _F = field(repr=False)
    point_u: _F = field(repr=False)
    gum: VerificationGUM = field(repr=False)
    reference: Identification = field(repr=False)
    initial_point_mean: _F = field(repr=False)
    initial_point_u: _F = field(repr=False)
    compensated_point_mean: _F = field(repr=False)
    compensated_point_u: _F = field(repr=False)

    def ve_result(self, which: str) -> MonteCarloResult:
        """The Monte Carlo result of one of :data:`VE_NAMES`, from its kept samples.

        The one route from the samples to a statistic's estimate, ``u`` and intervals:
        :meth:`ve`, ``mtmc verify simulate`` and the study's quantities all read it.
        """
        i = VE_NAMES.index(which)
        return MonteCarloResult(
            samples=np.asarray(self.ve_samples)[:, i], trials=self.trials, seed=self.seed
        )

    def ve(self, which: str) -> tuple[float, float]:
        """``(estimate, u)`` of one of :data:`VE_NAMES` (:meth:`ve_result`)."""
        r = self.ve_result(which)
        return r.estimate, r.u

    def point_mean_ve(self, which: str) -> dict[str, tuple[float, float]]:
        """Max, mean and min over the points of each point's mean error, with their ``u``.

        At each point the length of the error is averaged over the trials; the max, mean
        and min of these averages over the points are the estimates (module notes: not
        the statistics of :meth:`ve`, which average the max and min of each verification).
        The ``u`` of the max (min) is the standard deviation over the trials (divisor
        ``M − 1``, JCGM 101 eq. 13) of the error at the point where it is attained: the
        spread of one verification's reading there. The ``u`` of the mean is that of the
        mean over the points of one verification (the ``u`` of ``ve(which + ".mean")``).

        Parameters
        ----------
        which : {"initial", "compensated"}
            The error before identification (readings against the nominal machine, at the
            measured points) or the error left after compensation (at the evaluation
            points).

        Returns
        -------
        dict
            ``{"max": (estimate, u), "mean": (...), "min": (...)}``, mm.

        Raises
        ------
        InputError
            For another ``which``.
        """
        if which == "initial":
            mean, u = self.initial_point_mean, self.initial_point_u
        elif which == "compensated":
            mean, u = self.compensated_point_mean, self.compensated_point_u
        else:
            raise InputError(f"expected 'initial' or 'compensated', got {which!r}", field="which")
        i_max, i_min = int(np.argmax(mean)), int(np.argmin(mean))
        return {
            "max": (float(mean[i_max]), float(u[i_max])),
            "mean": (float(np.mean(mean)), self.ve(f"{which}.mean")[1]),
            "min": (float(mean[i_min]), float(u[i_min])),
        }


def reference_identification(ver: Verification, *, max_iter: int = 100) -> Identification:
    """The noise-free identification of a verification (exact, one set of readings).

    Raises
    ------
    ConvergenceError
        If it does not converge.
    IdentifiabilityError
        If the model cannot be identified from these points.
    """
    ref = identify(
        ver.model,
        ver.q,
        ver.readings(),
        ver.tracker,
        pose=ver.pose,
        fixed=ver.fixed,
        max_iter=max_iter,
        exact=ver.exact,
    )
    if not ref.converged[0]:
        raise ConvergenceError(
            f"the noise-free identification did not converge: {ref.messages()[0]}",
            field="model",
        )
    return ref


def simulate(
    ver: Verification,
    trials: int,
    seed: int | None,
    *,
    repeatability: float = 0.0,
    pose_u: npt.ArrayLike | None = None,
    reflector_u: float = 0.0,
    refine: int | None = None,
    workers: int = 1,
    executor: Any = "thread",
    scheduler: Any = None,
    progress: Callable[[int, int | None], None] | None = None,
) -> VerificationMC:
    """Monte Carlo of ``trials`` verifications through :func:`mtmc.uncertainty.monte_carlo`.

    Parameters
    ----------
    ver : Verification
    trials : int
    seed : int or None
    repeatability, pose_u, reflector_u
        Optional further inputs (see :meth:`VerificationModel.build`).
    refine : int, optional
        Exact steps of the identification (see :meth:`VerificationModel.build`).
    workers, executor, scheduler, progress
        Passed to the engine.

    Returns
    -------
    VerificationMC
    """
    # The reference identification, the model's operators and the GUM are factorisations
    # and products of thin matrices (3N × p, p about 40): threaded BLAS gains nothing on
    # them (0.325 s with two threads, 0.33 s with one, for the 5408-point mesh), while its
    # idle threads spin on the cores the trials need (0.3 s of CPU a run). One thread,
    # the setting of the Monte Carlo's own blocks.
    with one_blas_thread():
        ref = reference_identification(ver)
        vm = VerificationModel.build(
            ver,
            ref,
            repeatability=repeatability,
            pose_u=pose_u,
            reflector_u=reflector_u,
            refine=refine,
        )
        try:
            res = monte_carlo(
                vm,
                vm.inputs(),
                trials,
                seed,
                keep=["ve", "coef"],
                workers=workers,
                executor=executor,
                scheduler=scheduler,
                progress=progress,
            )
        except InputError as exc:
            # the verification keeps its samples, so the engine's advice to keep none is not ours
            head, cut, _ = exc.message.partition("; run with keep=False")
            if exc.field != "trials" or not cut:
                raise
            raise InputError(
                f"{head}; the verification keeps the volumetric errors and coefficients of every "
                "trial: run fewer trials",
                field="trials",
            ) from None
        ve, coef, comp = res["ve"], res["coef"], res["comp"]
        cu = np.asarray(comp.u_vector).reshape(-1, 3)
        return VerificationMC(
            trials=int(res.trials),
            seed=res.seed,
            names=vm.names,
            ve_estimate=frozen_floats(ve.estimate_vector),
            ve_u=frozen_floats(ve.u_vector),
            ve_samples=frozen_floats(ve.samples),
            coef_estimate=frozen_floats(coef.estimate_vector),
            coef_u=frozen_floats(coef.u_vector),
            coef_cov=frozen_floats(coef.cov),
            coef_samples=frozen_floats(coef.samples),
            comp_bias=frozen_floats(comp.estimate_vector.reshape(-1, 3)),
            comp_u=frozen_floats(cu),
            point_u=frozen_floats(np.sqrt(np.sum(cu * cu, axis=1))),
            gum=gum_verification(vm),
            reference=ref,
            initial_point_mean=frozen_floats(res["point_initial"].estimate_vector),
            initial_point_u=frozen_floats(res["point_initial"].u_vector),
            compensated_point_mean=frozen_floats(res["point_compensated"].estimate_vector),
            compensated_point_u=frozen_floats(res["point_compensated"].u_vector),
        )


def validate_verification(
    vm: VerificationModel,
    name: str,
    trials: int,
    seed: int | None,
    *,
    p: float = 0.95,
    ndig: int = 2,
) -> Validation:
    """JCGM 101 §8 validation of the GUM by Monte Carlo for one identified parameter.

    The GUM of :func:`mtmc.uncertainty.gum` (sensitivities of the whole verification model
    by differences, stacked in one call) against the engine's Monte Carlo, same model and
    inputs.

    Parameters
    ----------
    vm : VerificationModel
    name : str
        One of ``vm.names``.
    trials, seed
        Of the Monte Carlo run.
    p, ndig
        As :func:`mtmc.uncertainty.validate`.

    Returns
    -------
    Validation

    Raises
    ------
    InputError
        For an unknown name.
    """
    if name not in vm.names:
        raise InputError(f"unknown parameter {name!r}; expected one of {', '.join(vm.names)}")
    j = vm.names.index(name)

    def scalar(**kw: Any) -> Any:
        return vm(**kw)["coef"][:, j]

    inputs = vm.inputs()
    g = gum(scalar, inputs, p=p)
    mc = monte_carlo(scalar, inputs, trials, seed)
    return validate(g, mc, p=p, ndig=ndig)


__all__ += ["reference_identification", "POSE_NAMES"]
