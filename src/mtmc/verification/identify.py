"""Identification of a machine's error functions from laser-tracker readings.

Aguado et al. 2016 §2 (Fig. 2, eqs. 13–17) and Aguado et al. 2017 §3: the tracker reads
the reflector at ``N`` commanded positions ``q_i``; the model of the reading is

``x_i(θ, R, t) = Rᵀ (p(q_i; θ) − t)``

with ``p`` the tool position of an :class:`~mtmc.kinematics.ErrorModel` (parameters ``θ``,
the coefficients of its error functions) and ``(R, t)`` the tracker pose
(:class:`~mtmc.instruments.LaserTracker`). The identification minimises
``Σ_i |x_i − x_i^meas|²`` (eq. 17) over the free coefficients and, optionally, the pose,
by the batched Levenberg–Marquardt of :mod:`mtmc.verification.lsq`: ``M`` sets of
readings (the trials of a Monte Carlo) in one pass, with analytic Jacobians:

- ``∂x_i/∂θ = Rᵀ ∂p/∂θ`` (:meth:`ErrorModel.jacobian`);
- the pose is updated as ``R ← R Exp(δω)``, ``t ← t + δt``, so ``∂x_i/∂δω = [x_i]×`` and
  ``∂x_i/∂δt = −Rᵀ``; it is reported as the rotation vector ``φ`` of ``R₀ᵀR`` (rad) and
  the shift ``t − t₀`` (mm) from the nominal pose (names ``LT.rx LT.ry LT.rz LT.x LT.y LT.z``).

Volumetric errors per point (mm): initial ``|x^meas_i − R₀ᵀ(p_i^nominal − t₀)|`` (the
readings against the nominal machine and nominal tracker pose, eq. 17 before
identification) and residual ``|x^meas_i − x_i(θ̂, R̂, t̂)|`` (after).

Identifiability: before solving, the Jacobian at the start (columns scaled to unit norm)
is decomposed by SVD; each singular value below ``rank_tol`` times the largest is a
combination of parameters the measurement cannot see. It is reported by the names and
weights of its right singular vector (weights of the unscaled parameters), and by
default raises :class:`~mtmc.errors.IdentifiabilityError`: nothing is silently absorbed.

Examples
--------
>>> import numpy as np
>>> from mtmc.kinematics import Machine, ErrorModel, PolynomialFunction
>>> from mtmc.instruments import LaserTracker
>>> m = Machine.from_topology("XFYZ")
>>> em = ErrorModel(m, {"EXX": PolynomialFunction([0.0, 0.0]), "EC0Y": 0.0})
>>> q = np.array([[x, y, 0.0] for x in (0, 200, 400) for y in (0, 200, 400)])
>>> lt = LaserTracker.from_euler([-800.0, 200.0, 600.0], [0.0, 0.0, 0.5])
>>> truth = {"EXX": PolynomialFunction([0.0, 2e-5]), "EC0Y": 1e-5}
>>> meas = lt.to_tracker(m.tool_position(q, truth))
>>> r = identify(em, q, meas, lt, pose=False, fixed={"EXX[0]": 0.0})
>>> np.round(r.estimate[0] / np.array([2e-5, 1e-5]), 9).tolist()
[1.0, 1.0]
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import IdentifiabilityError, InputError
from mtmc.geometry.transforms import (
    cross_matrix,
    matrix_from_rotation_vector,
    rotation_vector_from_matrix,
)
from mtmc.instruments.laser_tracker import LaserTracker
from mtmc.kinematics.functions import ErrorFunction
from mtmc.kinematics.machine import Machine
from mtmc.kinematics.parameters import ErrorModel
from mtmc.verification.lsq import SolverStatus, least_squares

__all__ = [
    "POSE_NAMES",
    "Identifiability",
    "Identification",
    "identifiability",
    "identify",
    "parameter_unit",
    "ve_stats",
]

_F = NDArray[np.float64]

#: Names of the tracker pose parameters: rotation vector of ``R₀ᵀR`` (rad), shift (mm).
POSE_NAMES: tuple[str, ...] = ("LT.rx", "LT.ry", "LT.rz", "LT.x", "LT.y", "LT.z")


def parameter_unit(machine: Machine, name: str) -> str:
    """The unit of an identified parameter inside the code: ``"mm"`` or ``"rad"``.

    A coefficient of an error function (``EXX[2]``) has the unit of the error, ISO 230-1:
    mm for a displacement (``EXX``, ``EYX``...), rad for a rotation (``EAX``, ``EC0Y``...);
    the tracker pose (:data:`POSE_NAMES`) is a rotation vector in rad and a shift in mm.

    Parameters
    ----------
    machine : Machine
        The machine whose error names the parameters are.
    name : str
        A parameter name, e.g. ``"EXX[1]"``, ``"EC0Y"``, ``"LT.rx"``.

    Returns
    -------
    str

    Raises
    ------
    InputError
        If ``name`` is not an error of ``machine`` nor a pose parameter.

    Examples
    --------
    >>> from mtmc.kinematics import library_machine
    >>> m = library_machine("xfyz")
    >>> [parameter_unit(m, n) for n in ("EXX[1]", "EAX[2]", "EC0Y", "LT.rx", "LT.z")]
    ['mm', 'rad', 'rad', 'rad', 'mm']
    """
    if name in POSE_NAMES:
        return "rad" if name.startswith("LT.r") else "mm"
    return "rad" if machine.error_term(name.split("[")[0]).angular else "mm"


#: Default relative threshold on the singular values of the column-scaled Jacobian.
RANK_TOL: float = 1e-9


def ve_stats(ve: npt.ArrayLike) -> _F:
    """``(max, mean, min)`` over the points of volumetric errors ``(M, N)`` -> ``(M, 3)``."""
    a = np.asarray(ve, dtype=np.float64)
    return np.stack([a.max(axis=-1), a.mean(axis=-1), a.min(axis=-1)], axis=-1)


@dataclass(frozen=True)
class Identifiability:
    """Which parameter combinations a measurement can separate.

    Attributes
    ----------
    names : tuple of str
        The parameters, in the column order of the Jacobian.
    singular_values : ndarray, shape (P,)
        Of the column-scaled Jacobian, relative to the largest, descending.
    threshold : float
        Relative threshold below which a direction counts as unobservable.
    combinations : tuple of str
        One line per unobservable direction: ``a·NAME1 + b·NAME2 + …``, a change of the
        parameters (in their own units) along which does not change the readings; terms
        whose effect (weight times column norm) is below 1 % of the largest are left out.
    groups : tuple of tuple of str
        The names in each combination.
    """

    names: tuple[str, ...]
    singular_values: _F = field(repr=False)
    threshold: float
    combinations: tuple[str, ...]
    groups: tuple[tuple[str, ...], ...]

    @property
    def rank(self) -> int:
        """Number of observable directions."""
        return int(np.sum(self.singular_values > self.threshold))

    @property
    def ok(self) -> bool:
        """True when every parameter can be identified."""
        return not self.combinations

    def text(self) -> str:
        """A report in words."""
        if self.ok:
            return (
                f"all {len(self.names)} parameters identifiable (smallest scaled singular "
                f"value {self.singular_values[-1]:.3g}, threshold {self.threshold:g})"
            )
        lines = [
            f"{len(self.combinations)} of {len(self.names)} directions cannot be identified "
            f"(scaled singular value < {self.threshold:g}); the readings do not change along:"
        ]
        lines += [f"  {c}" for c in self.combinations]
        lines.append(
            "only the combinations orthogonal to these are observable: fix one parameter of "
            "each group (e.g. a constant term to 0) or add points, offsets or stations"
        )
        return "\n".join(lines)


def identifiability(
    J: npt.ArrayLike, names: Sequence[str], rank_tol: float = RANK_TOL
) -> Identifiability:
    """Unobservable parameter combinations of a Jacobian by SVD with column scaling.

    Parameters
    ----------
    J : array_like, shape (n, P)
        Jacobian of the readings with respect to the parameters.
    names : sequence of str
        Parameter names (P).
    rank_tol : float
        Relative threshold: a singular value ``s_k < rank_tol · s_max`` of ``J D⁻¹``
        (``D`` the column norms) marks an unobservable direction.

    Returns
    -------
    Identifiability

    Raises
    ------
    InputError
        On a shape mismatch.
    """
    A = np.asarray(J, dtype=np.float64)
    if A.ndim != 2 or A.shape[1] != len(names):
        raise InputError(f"expected J of shape (n, {len(names)}), got {A.shape}", field="J")
    d = np.linalg.norm(A, axis=0)
    zero = d == 0
    dd = np.where(zero, 1.0, d)
    # fewer readings than parameters: the full V, whose last rows span the null space the
    # readings leave (U stays small: n < P)
    _, s, Vt = np.linalg.svd(A / dd, full_matrices=A.shape[0] < A.shape[1])
    sv = np.zeros(A.shape[1])
    sv[: s.size] = s / (s[0] if s.size and s[0] > 0 else 1.0)
    combos: list[str] = []
    groups: list[tuple[str, ...]] = []
    for k in np.nonzero(sv <= rank_tol)[0]:
        w = Vt[k] / np.max(np.abs(Vt[k]))  # weights of the scaled parameters
        if w[np.argmax(np.abs(w))] < 0:
            w = -w
        keep = np.nonzero(np.abs(w) >= 0.01)[0]
        v = Vt[k] / dd  # the same direction in the parameters' own units
        v = v / np.max(np.abs(v[keep]))
        terms = [f"{v[j]:+.4g}·{names[int(j)]}" for j in keep]
        combos.append(" ".join(terms).lstrip("+"))
        groups.append(tuple(names[int(j)] for j in keep))
    return Identifiability(tuple(names), sv, float(rank_tol), tuple(combos), tuple(groups))


@dataclass(frozen=True)
class Identification(SolverStatus):
    """Result of :func:`identify` for ``M`` sets of readings (arrays read-only).

    Attributes
    ----------
    names : tuple of str
        The identified parameters: the free coefficients of the error model, then
        :data:`POSE_NAMES` when the pose is identified.
    estimate : ndarray, shape (M, p)
        Their values (coefficients in their units; pose in rad and mm).
    covariance : ndarray, shape (M, p, p)
        ``s² (JᵀJ)⁻¹`` at the solution, ``s² = Σ r² / (3N − p)``.
    theta : ndarray, shape (M, P)
        The full parameter vector of the error model (fixed values included).
    rotation : ndarray, shape (M, 3, 3)
        Identified (or nominal) tracker rotation.
    position : ndarray, shape (M, 3)
        Identified (or nominal) tracker position, mm.
    initial_ve, residual_ve : ndarray, shape (M, N)
        Volumetric error per point before and after, mm.
    residuals : ndarray, shape (M, N, 3)
        Model minus reading at the solution, tracker frame, mm.
    status : ndarray of int, shape (M,)
        :data:`mtmc.verification.lsq.STATUS`.
    iterations : ndarray of int, shape (M,)
    jacobian : ndarray, shape (M, 3N, p)
        At the solution.
    identifiability : Identifiability
        Of the first set of readings at the start.
    """

    names: tuple[str, ...]
    estimate: _F
    covariance: _F
    theta: _F
    rotation: _F
    position: _F
    initial_ve: _F
    residual_ve: _F
    residuals: _F
    status: NDArray[np.int64]
    iterations: NDArray[np.int64]
    jacobian: _F = field(repr=False)
    identifiability: Identifiability = field(repr=False)

    def __post_init__(self) -> None:
        for n in (
            "estimate", "covariance", "theta", "rotation", "position", "initial_ve",
            "residual_ve", "residuals", "status", "iterations", "jacobian",
        ):  # fmt: skip
            getattr(self, n).setflags(write=False)

    @property
    def u(self) -> _F:
        """Standard uncertainties ``(M, p)`` from :attr:`covariance`."""
        return np.sqrt(np.diagonal(self.covariance, axis1=1, axis2=2))

    def initial_stats(self) -> _F:
        """``(max, mean, min)`` of the initial volumetric error, ``(M, 3)``, mm."""
        return ve_stats(self.initial_ve)

    def residual_stats(self) -> _F:
        """``(max, mean, min)`` of the residual volumetric error, ``(M, 3)``, mm."""
        return ve_stats(self.residual_ve)


def _error_basis(model: ErrorModel, q: _F) -> tuple[tuple[str, NDArray[np.int64], _F], ...]:
    """Per error of ``model``: its name, its parameters' indices and basis ``(N, n)``.

    The basis is taken at the points (a column of ones for a constant): the error's value
    at point ``i`` is ``B[i] · θ[idx]`` and ``∂p/∂θ[idx] = ∂p/∂e · B``.
    """
    mach = model.machine
    qa = mach.positions(q)
    out = []
    for n in model.error_names:
        idx = [j for j, pn in enumerate(model.parameter_names) if pn == n or pn.startswith(n + "[")]
        tmpl = model.templates[n]
        if isinstance(tmpl, ErrorFunction):
            B = tmpl.basis(qa[:, mach.axes.index(mach.error_term(n).axis)])
        else:
            B = np.ones((qa.shape[0], 1))
        out.append((n, np.array(idx, dtype=np.int64), np.ascontiguousarray(B, dtype=np.float64)))
    return tuple(out)


@dataclass(frozen=True)
class _Problem:
    """The readings model of one identification (shared by all trials)."""

    model: ErrorModel
    q: _F  # (N, n_axes)
    free: NDArray[np.int64]
    base: _F  # (P,) full theta with fixed values
    R0: _F
    t0: _F
    pose: bool
    exact: bool
    cache: dict[str, _F] = field(default_factory=dict, compare=False, repr=False)

    @property
    def n(self) -> int:
        return int(self.q.shape[0])

    def split(self, x: _F) -> tuple[_F, _F, _F]:
        """Split ``x`` (m, p) into theta (m, P), R (m, 3, 3), t (m, 3)."""
        m = x.shape[0]
        th = np.broadcast_to(self.base, (m, self.base.size)).copy()
        k = self.free.size
        th[:, self.free] = x[:, :k]
        if self.pose:
            R = self.R0 @ matrix_from_rotation_vector(x[:, k : k + 3])
            t = self.t0 + x[:, k + 3 : k + 6]
        else:
            R = np.broadcast_to(self.R0, (m, 3, 3))
            t = np.broadcast_to(self.t0, (m, 3))
        return th, R, t

    @property
    def basis(self) -> tuple[tuple[str, NDArray[np.int64], _F], ...]:
        """:func:`_error_basis` at the points (computed once)."""
        if "basis" not in self.cache:
            self.cache["basis"] = _error_basis(self.model, self.q)  # type: ignore[assignment]
        out: tuple[tuple[str, NDArray[np.int64], _F], ...] = self.cache["basis"]  # type: ignore[assignment]
        return out

    def _errors(self, th: _F) -> tuple[_F, dict[str, _F]]:
        """Rows ``(m·N, n_axes)`` and the error values at every point of every problem."""
        m = th.shape[0]
        qq = np.broadcast_to(self.q, (m, *self.q.shape)).reshape(m * self.n, -1)
        return qq, {n: (th[:, idx] @ B.T).ravel() for n, idx, B in self.basis}

    def positions(self, th: _F) -> _F:
        qq, errs = self._errors(th)
        p = self.model.machine.tool_position(qq, errs, exact=self.exact)
        return p.reshape(th.shape[0], self.n, 3)

    def readings(self, x: _F) -> _F:
        th, R, t = self.split(x)
        p = self.positions(th)
        out: _F = (p - t[:, None, :]) @ R
        self.cache["x"], self.cache["readings"] = x.copy(), out
        return out

    def jac(self, x: _F) -> _F:
        key = self.cache.get("jac_x")
        if key is not None and key.shape == x.shape and np.array_equal(key, x):
            cached: _F = self.cache["jac"]
            return cached
        J = self._jac(x)
        self.cache["jac_x"], self.cache["jac"] = x.copy(), J
        return J

    def _jac(self, x: _F) -> _F:
        th, R, t = self.split(x)
        m, N = x.shape[0], self.n
        qq, errs = self._errors(th)
        names = tuple(n for n, _, _ in self.basis)
        Je = self.model.machine.jacobian(qq, errs, names=names, exact=self.exact)
        Je = Je.reshape(m, N, 3, len(names))
        Jfull = np.zeros((m, N, 3, self.base.size))
        for ie, (_, idx, B) in enumerate(self.basis):  # chain rule: dp/de times the basis
            Jfull[..., idx] = Je[..., ie, None] * B[None, :, None, :]
        Jp = Jfull[..., self.free]
        Jt = np.swapaxes(R, 1, 2)[:, None] @ Jp  # Rᵀ ∂p/∂θ, point by point
        if self.pose:
            xc = self.cache.get("x")
            if xc is not None and xc.shape == x.shape and np.array_equal(xc, x):
                xr = self.cache["readings"]
            else:
                xr = (self.positions(th) - t[:, None, :]) @ R
            Jw = cross_matrix(xr)
            Jtr = -np.broadcast_to(np.swapaxes(R, 1, 2)[:, None], (m, N, 3, 3))
            Jt = np.concatenate([Jt, Jw, Jtr], axis=-1)
        out: _F = Jt.reshape(m, 3 * N, -1)
        return out

    def retract(self, x: _F, d: _F) -> _F:
        out = x + d
        if self.pose:
            k = self.free.size
            out[:, k : k + 3] = rotation_vector_from_matrix(
                matrix_from_rotation_vector(x[:, k : k + 3])
                @ matrix_from_rotation_vector(d[:, k : k + 3])
            )
        return out


def _problem(
    model: ErrorModel,
    q: npt.ArrayLike,
    tracker: LaserTracker,
    pose: bool,
    fixed: Mapping[str, float] | Sequence[str] | None,
    exact: bool,
) -> _Problem:
    qa = np.asarray(q, dtype=np.float64)
    if qa.ndim != 2 or qa.shape[1] != model.machine.n_axes:
        raise InputError(
            f"expected axis positions of shape (N, {model.machine.n_axes}) "
            f"({' '.join(model.machine.axes)}), got {qa.shape}",
            field="q",
        )
    names = model.parameter_names
    fx: dict[str, float] = (
        {}
        if fixed is None
        else dict(fixed)
        if isinstance(fixed, Mapping)
        else dict.fromkeys(fixed, 0.0)
    )
    for n in fx:
        if n not in names:
            raise InputError(
                f"fixed parameter {n} is not one of the model's: {', '.join(names)}", field="fixed"
            )
    base = np.zeros(len(names))
    for i, n in enumerate(names):
        base[i] = float(fx.get(n, 0.0))
    free = np.array([i for i, n in enumerate(names) if n not in fx], dtype=np.int64)
    return _Problem(model, qa, free, base, tracker.rotation, tracker.position, pose, exact)


def identify(
    model: ErrorModel,
    q: npt.ArrayLike,
    measured: npt.ArrayLike,
    tracker: LaserTracker,
    *,
    pose: bool = True,
    fixed: Mapping[str, float] | Sequence[str] | None = None,
    theta0: npt.ArrayLike | None = None,
    rank_tol: float = RANK_TOL,
    on_rank_deficient: Literal["raise", "report"] = "raise",
    max_iter: int = 100,
    exact: bool = False,
) -> Identification:
    """Identify error-function coefficients (and the tracker pose) from tracker readings.

    Parameters
    ----------
    model : ErrorModel
        The errors to identify and their functions.
    q : array_like, shape (N, n_axes)
        Commanded axis positions of the points (mm, rad).
    measured : array_like, shape (N, 3) or (M, N, 3)
        Readings in the tracker frame, mm; ``M`` sets are identified in one pass.
    tracker : LaserTracker
        Nominal pose (the start, and the pose used when ``pose=False``).
    pose : bool
        Identify the tracker pose too (6 parameters).
    fixed : mapping name -> value, or sequence of names (held at 0), optional
        Coefficients not identified (e.g. the constant terms, which a free tracker pose
        cannot be separated from).
    theta0 : array_like, shape (P,), optional
        Start of the free coefficients (default zero, or the fixed values).
    rank_tol : float
        See :func:`identifiability`.
    on_rank_deficient : {"raise", "report"}
        Raise :class:`~mtmc.errors.IdentifiabilityError` (default) or solve anyway (the
        damped solver then picks one point of the unobservable set) and report.
    max_iter : int
        Iterations of the solver.
    exact : bool
        Exact error rotations in the machine model.

    Returns
    -------
    Identification

    Raises
    ------
    InputError
        On bad shapes or names.
    IdentifiabilityError
        When some combination of parameters cannot be identified and
        ``on_rank_deficient="raise"``; the message names it.
    """
    prob = _problem(model, q, tracker, pose, fixed, exact)
    meas = np.asarray(measured, dtype=np.float64)
    if meas.ndim == 2:
        meas = meas[None]
    if meas.ndim != 3 or meas.shape[1:] != (prob.n, 3):
        raise InputError(
            f"expected readings of shape ({prob.n}, 3) or (M, {prob.n}, 3), got {meas.shape}",
            field="measured",
        )
    if not np.all(np.isfinite(meas)):
        raise InputError("expected finite readings", field="measured")
    M = meas.shape[0]
    names = tuple(model.parameter_names[i] for i in prob.free) + (POSE_NAMES if pose else ())
    p = len(names)
    if 3 * prob.n < p:
        raise InputError(f"{3 * prob.n} readings for {p} parameters", field="measured")
    x0 = np.zeros((M, p))
    if theta0 is not None:
        th0 = np.asarray(theta0, dtype=np.float64)
        if th0.shape != (model.n_parameters,):
            raise InputError(f"expected theta0 of shape ({model.n_parameters},)", field="theta0")
        x0[:, : prob.free.size] = th0[prob.free]
    ident = identifiability(prob.jac(x0[:1])[0], names, rank_tol)
    if not ident.ok and on_rank_deficient == "raise":
        raise IdentifiabilityError(ident.text(), combinations=ident.combinations, field="model")
    flat = meas.reshape(M, -1)

    def fun(x: _F, rows: NDArray[np.int64]) -> _F:
        return prob.readings(x).reshape(x.shape[0], -1) - flat[rows]

    def jac(x: _F, rows: NDArray[np.int64]) -> _F:  # noqa: ARG001 - the solver's signature
        return prob.jac(x)

    res = least_squares(
        fun,
        jac,
        x0,
        retract=prob.retract,
        max_iter=max_iter,
        xtol=1e-11,
        ftol=1e-12,
        gtol=1e-10,
        lam0=1e-8,
        atol=1e-12,
        solver="normal",
        polish=2 if ident.ok else 0,
    )
    th, R, t = prob.split(res.x)
    resid = res.residuals.reshape(M, prob.n, 3)
    nominal = model.machine.tool_position(prob.q)
    x_nom = (nominal - tracker.position) @ tracker.rotation
    init = np.linalg.norm(meas - x_nom[None], axis=-1)
    cov = res.covariance() if 3 * prob.n > p else np.full((M, p, p), np.nan)
    return Identification(
        names, np.array(res.x), cov, th, np.array(R), np.array(t), init,
        np.linalg.norm(resid, axis=-1), np.array(resid), np.array(res.status),
        np.array(res.iterations), np.array(res.jac), ident,
    )  # fmt: skip
