"""Batched non-linear least squares: Levenberg–Marquardt on stacked systems.

``M`` independent problems ``min_x ½|r_m(x_m)|²`` (the trials of a Monte Carlo, or the
starts of a test problem) are solved in one pass: every iteration evaluates the residuals
``(M, n)`` and the analytic Jacobians ``(M, n, P)`` of all problems at once and solves the
``M`` damped systems ``[J; √λ D] δ = −[r; 0]`` by one batched QR factorisation
(Moré's scaled Levenberg–Marquardt: ``D = diag`` of the running maximum column norms of
``J``; ``λ`` per problem, divided by 3 after a very successful step, doubled after a poor
one, the step rejected when the cost does not fall). The parameter update may be a
retraction other than ``x + δ`` (a rotation updated multiplicatively).

Stopping (per problem): status 1 when a step is below ``xtol (|x| + xtol)`` (norms over
the parameters, scaled by ``D``), 2 when the actual and predicted relative reductions of
the cost are below ``ftol``, 3 when the scaled gradient ``max_j |Jᵀr|_j / (|J_j| |r|)``
is below ``gtol``, 4 when the root mean square residual is below ``atol`` (an exact fit at
the rounding floor), 0 when ``max_iter`` is reached first, −1 on a non-finite residual.

Polishing: near the solution the cost stops telling a better point from a worse one
(its rounding, about 10⁻¹³ relative for tracker readings of points 2 m away, exceeds the
reduction a step of 10⁻⁸ u promises), so every further step is rejected and the damped
iteration stalls there. ``polish`` undamped Gauss–Newton steps taken after convergence,
without the cost test (kept only where the cost does not rise beyond that rounding),
make the gradient ``Jᵀr`` vanish to rounding instead.

Examples
--------
An exact fit: which test stops each problem (a step below ``xtol`` or the residual at the
rounding floor) depends on the last bits of the QR factorisation, so LAPACK's kernel decides
between status 1 and 4; both say converged.

>>> import numpy as np
>>> t = np.array([0.0, 1.0, 2.0, 3.0]); y = 2.0 * np.exp(-0.5 * t)
>>> fun = lambda x, rows: x[:, :1] * np.exp(-x[:, 1:] * t) - y
>>> def jac(x, rows):
...     e = np.exp(-x[:, 1:] * t)
...     return np.stack([e, -x[:, :1] * t * e], axis=-1)
>>> r = least_squares(fun, jac, [[1.0, 1.0], [3.0, 0.1]])
>>> np.round(r.x, 10).tolist(), r.converged.tolist()
([[2.0, 0.5], [2.0, 0.5]], [True, True])
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import InputError

__all__ = ["LeastSquaresResult", "SolverStatus", "least_squares", "STATUS"]

_F = NDArray[np.float64]

#: Meaning of :attr:`LeastSquaresResult.status`.
STATUS: dict[int, str] = {
    1: "converged: step below xtol",
    2: "converged: relative cost reduction below ftol",
    3: "converged: gradient below gtol",
    4: "converged: residual below atol (the rounding floor of a noise-free problem)",
    0: "not converged: maximum number of iterations reached",
    -1: "not converged: non-finite residual or Jacobian",
}


class SolverStatus:
    """What the solver says of each of ``M`` problems: :attr:`converged`, :meth:`messages`.

    A base of the results that carry a ``status`` array of :data:`STATUS` codes.
    """

    status: NDArray[np.int64]

    @property
    def converged(self) -> NDArray[np.bool_]:
        """True where the status is 1 to 4 (the solver converged), shape (M,)."""
        return self.status > 0

    def messages(self) -> tuple[str, ...]:
        """:data:`STATUS` text of each problem."""
        return tuple(STATUS[int(s)] for s in self.status)


@dataclass(frozen=True)
class LeastSquaresResult(SolverStatus):
    """Solutions of ``M`` least-squares problems (arrays read-only).

    Attributes
    ----------
    x : ndarray, shape (M, P)
    cost : ndarray, shape (M,)
        ``½|r|²`` at ``x``.
    status : ndarray of int, shape (M,)
        See :data:`STATUS`.
    iterations : ndarray of int, shape (M,)
        Iterations until the problem stopped.
    jac : ndarray, shape (M, n, P)
        Jacobian at ``x``.
    residuals : ndarray, shape (M, n)
    """

    x: _F
    cost: _F
    status: NDArray[np.int64]
    iterations: NDArray[np.int64]
    jac: _F
    residuals: _F

    def __post_init__(self) -> None:
        for n in ("x", "cost", "status", "iterations", "jac", "residuals"):
            getattr(self, n).setflags(write=False)

    def covariance(self, sigma2: npt.ArrayLike | None = None) -> _F:
        """Covariance of the solution, ``s² (JᵀJ)⁻¹``, shape (M, P, P).

        Parameters
        ----------
        sigma2 : array_like, shape (M,) or (), optional
            Variance of one residual; by default ``s² = 2 cost / (n − P)``.

        Raises
        ------
        InputError
            If ``n <= P`` and no ``sigma2`` is given.
        """
        n, P = self.jac.shape[1:]
        if sigma2 is None:
            if n <= P:
                raise InputError(f"{n} residuals for {P} parameters: give sigma2", field="sigma2")
            sigma2 = 2.0 * self.cost / (n - P)
        s2 = np.asarray(sigma2, dtype=np.float64)
        JtJ = np.swapaxes(self.jac, 1, 2) @ self.jac
        out: _F = np.asarray(np.linalg.inv(JtJ) * np.reshape(s2, (-1, 1, 1)), dtype=np.float64)
        return out


def least_squares(
    fun: Callable[[_F, NDArray[np.int64]], _F],
    jac: Callable[[_F, NDArray[np.int64]], _F],
    x0: npt.ArrayLike,
    *,
    retract: Callable[[_F, _F], _F] | None = None,
    max_iter: int = 200,
    xtol: float = 1e-12,
    ftol: float = 1e-14,
    gtol: float = 1e-12,
    lam0: float = 1e-2,
    atol: float = 0.0,
    solver: Literal["qr", "normal"] = "qr",
    polish: int = 0,
) -> LeastSquaresResult:
    """Levenberg–Marquardt on ``M`` stacked problems (see the module notes).

    Parameters
    ----------
    fun : callable
        ``fun(x, rows)``: ``x`` of shape (M', P) holds the problems ``rows`` (indices
        into the M problems, shape (M',)) still running -> residuals (M', n).
    jac : callable
        ``jac(x, rows)`` -> (M', n, P), the analytic Jacobian ``∂r/∂δ`` of the update ``δ``.
    x0 : array_like, shape (M, P) or (P,)
        Starting values.
    retract : callable, optional
        ``retract(x, δ)`` -> new ``x`` (default ``x + δ``).
    max_iter : int
        Maximum iterations.
    xtol, ftol, gtol : float
        Stopping tolerances (module notes).
    solver : {"qr", "normal"}
        ``"qr"``: a batched QR factorisation of the damped system (accurate for
        ill-conditioned problems); ``"normal"``: the damped normal equations
        ``(JᵀJ + λ DᵀD) δ = −Jᵀr`` by Cholesky (several times faster for tall systems;
        the condition number is squared, so only for well-scaled problems).
    atol : float
        Stop when the root mean square residual is at most ``atol`` (status 4).
    polish : int
        Undamped Gauss–Newton steps on the converged problems (module notes); only for
        problems of full rank.
    lam0 : float
        Initial damping ``λ`` (the damping term is ``λ DᵀD``, so ``λ`` is relative to the
        squared column norms of ``J``).

    Returns
    -------
    LeastSquaresResult

    Raises
    ------
    InputError
        On a bad shape of ``x0`` or of what ``fun``/``jac`` return.
    """
    x = np.array(x0, dtype=np.float64)
    if x.ndim == 1:
        x = x[None]
    if x.ndim != 2:
        raise InputError(f"expected x0 of shape (M, P) or (P,), got {x.shape}", field="x0")
    add = retract if retract is not None else (lambda a, d: a + d)
    M, P = x.shape
    r = np.asarray(fun(x, np.arange(M)), dtype=np.float64)
    if r.ndim != 2 or r.shape[0] != M:
        raise InputError(f"fun returned shape {r.shape} for {M} problems", field="fun")
    n = r.shape[1]
    J = np.asarray(jac(x, np.arange(M)), dtype=np.float64)
    if J.shape != (M, n, P):
        raise InputError(f"jac returned shape {J.shape}, expected {(M, n, P)}", field="jac")
    cost = 0.5 * np.sum(r * r, axis=1)
    D = np.linalg.norm(J, axis=1)
    D = np.where(D > 0, D, 1.0)
    lam = np.full(M, lam0)
    status = np.zeros(M, dtype=np.int64)
    status[~np.isfinite(cost)] = -1
    iters = np.zeros(M, dtype=np.int64)
    active = status == 0
    for _ in range(max_iter):  # iterations, not trials
        idx = np.nonzero(active)[0]
        if idx.size == 0:
            break
        Ja, ra, Da, xa, ca = J[idx], r[idx], D[idx], x[idx], cost[idx]
        iters[idx] += 1
        g = np.einsum("mnp,mn->mp", Ja, ra)
        rn = np.sqrt(2.0 * ca)
        gs = np.max(np.abs(g) / (Da * np.maximum(rn[:, None], 1e-300)), axis=1)
        gdone = (gs <= gtol) | (rn == 0.0)
        delta = _step(Ja, ra, g, Da, lam[idx], solver)
        xn = add(xa, delta)
        with np.errstate(over="ignore", invalid="ignore"):  # a trial step may overflow
            rn_new = np.asarray(fun(xn, idx), dtype=np.float64)
            cn = 0.5 * np.sum(rn_new * rn_new, axis=1)
        Jd = np.einsum("mnp,mp->mn", Ja, delta)
        pred = -(np.sum(Jd * ra, axis=1) + 0.5 * np.sum(Jd * Jd, axis=1))  # predicted reduction
        actual = ca - cn
        with np.errstate(divide="ignore", invalid="ignore"):
            rho = np.where(pred > 0, actual / pred, -1.0)
        ok = np.isfinite(cn) & (actual >= 0) & (rho > 1e-4)
        sl = np.nonzero(ok)[0]
        if sl.size:
            ii = idx[sl]
            x[ii], r[ii], cost[ii] = xn[sl], rn_new[sl], cn[sl]
            Jn = np.asarray(jac(xn[sl], ii), dtype=np.float64)
            J[ii] = Jn
            D[ii] = np.maximum(D[ii], np.linalg.norm(Jn, axis=1))
        lam_i = lam[idx]
        lam_i = np.where(rho > 0.75, lam_i / 3.0, lam_i)
        lam_i = np.where(rho < 0.25, lam_i * 2.0, lam_i)
        lam_i = np.where(~ok, lam_i * 2.0, lam_i)
        lam[idx] = np.minimum(lam_i, 1e16)
        xs = np.linalg.norm(Da * xa, axis=1)
        step = np.linalg.norm(Da * delta, axis=1)
        xdone = step <= xtol * (xs + xtol)
        with np.errstate(divide="ignore", invalid="ignore"):
            fdone = (np.abs(actual) <= ftol * ca) & (pred <= ftol * ca)
        bad = ~np.isfinite(cn) & ~np.isfinite(ca)
        st = np.where(gdone, 3, np.where(xdone, 1, np.where(fdone, 2, 0)))
        st = np.where(np.sqrt(2.0 * cost[idx] / n) <= atol, 4, st)
        st = np.where(bad, -1, st)
        status[idx] = st
        active[idx] = st == 0
    for _ in range(polish):  # undamped steps without the cost test, converged problems only
        idx = np.nonzero(status > 0)[0]
        if idx.size == 0:
            break
        Ja, ra = J[idx], r[idx]
        g = np.einsum("mnp,mn->mp", Ja, ra)
        delta = _step(Ja, ra, g, D[idx], np.zeros(idx.size), solver)
        xn = add(x[idx], delta)
        with np.errstate(over="ignore", invalid="ignore"):
            rn_new = np.asarray(fun(xn, idx), dtype=np.float64)
            cn = 0.5 * np.sum(rn_new * rn_new, axis=1)
        sl = np.nonzero(np.isfinite(cn) & (cn <= cost[idx] * (1.0 + 1e-10)))[0]
        if sl.size:
            ii = idx[sl]
            x[ii], r[ii], cost[ii] = xn[sl], rn_new[sl], cn[sl]
            J[ii] = np.asarray(jac(xn[sl], ii), dtype=np.float64)
    return LeastSquaresResult(x, cost, status, iters, J, r)


def _step(J: _F, r: _F, g: _F, D: _F, lam: _F, solver: str) -> _F:
    """Solutions ``δ`` of the damped systems ``[J; √λ D] δ = −[r; 0]``, shape (M, P)."""
    P = J.shape[2]
    if solver == "normal":
        H = np.swapaxes(J, 1, 2) @ J
        H = H + (lam[:, None] * D * D)[:, :, None] * np.eye(P)
        Lc = np.linalg.cholesky(H)
        y = np.linalg.solve(Lc, -g[..., None])
        out: _F = np.linalg.solve(np.swapaxes(Lc, 1, 2), y)[..., 0]
        return out
    A = np.concatenate([J, np.sqrt(lam)[:, None, None] * (D[:, :, None] * np.eye(P))], axis=1)
    b = np.concatenate([-r, np.zeros((J.shape[0], P))], axis=1)
    Q, R = np.linalg.qr(A)
    out = np.linalg.solve(R, np.einsum("mkp,mk->mp", Q, b)[..., None])[..., 0]
    return out
