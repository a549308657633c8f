"""Tracker placement: the position of least calibration uncertainty (Aguado et al. 2016 Fig. 8).

Candidates: upright trackers (z axis vertical) turned towards the centre of the points, on
a grid of positions around the workspace (outside its footprint by a margin) at the
heights the limits allow. A candidate must see every point within the azimuth, elevation
and acceptance limits (:func:`~mtmc.instruments.visibility`). Each is scored by the GUM
linearisation of the identification: the mean over the points of the calibration
uncertainty ``√trace(G Cov(θ̂) Gᵀ)`` with ``Cov(θ̂) = A Σ Aᵀ`` (``A = J⁺`` at the nominal
machine and pose, ``Σ`` the tracker noise of each reading), which takes a few
milliseconds per candidate; the best one is then confirmed by the Monte Carlo of
:func:`~mtmc.verification.simulate.simulate`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize

from mtmc.errors import InputError
from mtmc.geometry.transforms import rotation_z
from mtmc.instruments.laser_tracker import LaserTracker, TrackerLimits, visibility
from mtmc.parallel import one_blas_thread
from mtmc.verification.identify import _problem
from mtmc.verification.simulate import Verification, _gum_propagate

__all__ = ["Placement", "place"]

_F = NDArray[np.float64]


def _gum_score(ver: Verification, tracker: LaserTracker) -> float:
    """Mean calibration uncertainty of the points (mm) by the GUM, at the nominal machine.

    The propagation of :func:`~mtmc.verification.simulate.gum_verification` with the tracker
    noise alone, at the nominal machine and pose (``A = J⁺``, the compensated points the
    measured ones): the mean over the points of ``√trace`` of their covariance.
    """
    if tracker.noise is None:
        raise InputError("the tracker has no noise model", field="tracker")
    prob = _problem(ver.model, ver.q, tracker, ver.pose, ver.fixed, ver.exact)
    p = prob.free.size + (6 if ver.pose else 0)
    J = prob.jac(np.zeros((1, p)))[0]
    N = ver.n_points
    x = tracker.to_tracker(ver.model.machine.tool_position(ver.q))
    _, pc = _gum_propagate(np.linalg.pinv(J), tracker.noise.covariance(x), J.reshape(N, 3, p))
    return float(np.mean(np.sqrt(np.trace(pc, axis1=1, axis2=2))))


@dataclass(frozen=True)
class Placement:
    """Result of :func:`place` (lengths in mm).

    Attributes
    ----------
    best : LaserTracker
    u_best : float
        Its GUM score.
    u_best_mc : float or None
        The same by Monte Carlo (mean over the points of the calibration uncertainty).
    candidates : int
        Candidates scored (visible ones).
    rejected : int
        Candidates that failed a visibility or height limit.
    reference : mapping of str to float
        The GUM score of the study's named positions.
    """

    best: LaserTracker
    u_best: float
    u_best_mc: float | None
    candidates: int
    rejected: int
    reference: Mapping[str, float] = field(default_factory=dict)


def _upright(pos: _F, centre: _F, noise: Any, name: str) -> LaserTracker:
    yaw = math.atan2(centre[1] - pos[1], centre[0] - pos[0])
    return LaserTracker(rotation_z(yaw), pos, noise, name)


class _Steps:
    """The steps of a placement search, reported as the engine reports trials."""

    def __init__(self, total: int, progress: Callable[[int, int | None], None] | None) -> None:
        self.total = total
        self.done = 0
        self.progress = progress

    def __call__(self, n: int) -> None:
        """Count ``n`` more steps (at most the total) and report them."""
        self.done = min(self.done + n, self.total)
        if self.progress is not None and n > 0:
            self.progress(self.done, self.total)


def place(
    ver: Verification,
    limits: TrackerLimits,
    *,
    references: Mapping[str, LaserTracker] | None = None,
    margin: float = 500.0,
    reach: float = 2500.0,
    n_xy: int = 11,
    heights: int = 3,
    trials: int = 0,
    seed: int | None = None,
    refine: int = 300,
    progress: Callable[[int, int | None], None] | None = None,
    **engine: Any,
) -> Placement:
    """Search tracker positions for the smallest mean calibration uncertainty.

    Parameters
    ----------
    ver : Verification
        The verification (its tracker gives the noise).
    limits : TrackerLimits
        Azimuth, elevation, acceptance and height limits (a finite height range).
    references : mapping, optional
        Named positions scored by the same criterion.
    margin, reach : float
        Candidates lie on an ``n_xy × n_xy`` grid over the footprint of the points grown by
        ``reach`` (mm), at least ``margin`` outside the footprint.
    n_xy, heights : int
        Grid size and number of heights within ``limits.height``.
    trials : int
        Monte Carlo trials confirming the best (0: none).
    refine : int
        Evaluations of a Nelder–Mead refinement of the best grid node over its position
        and its three Euler angles (``"xyz"``), within the limits.
    seed : int, optional
    progress : callable, optional
        Called with (steps done, steps in all) after each grid node, each evaluation of
        the refinement and each block of confirming trials, as the engine reports a run:
        ``n_xy² × heights + refine + trials`` steps.
    **engine
        ``workers``, ``executor``, ``scheduler`` of the confirming Monte Carlo
        (:func:`mtmc.verification.simulate.simulate`).

    Returns
    -------
    Placement

    Raises
    ------
    InputError
        If the height limits are not finite or no candidate sees every point.
    """
    from mtmc.verification.simulate import simulate

    if not all(math.isfinite(h) for h in limits.height):
        raise InputError("tracker placement needs finite height limits", field="limits.height")
    noise = ver.tracker.noise
    pts = ver.model.machine.tool_position(ver.q)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre = 0.5 * (lo + hi)
    xs = np.linspace(lo[0] - reach, hi[0] + reach, n_xy)
    ys = np.linspace(lo[1] - reach, hi[1] + reach, n_xy)
    zs = np.linspace(limits.height[0], limits.height[1], heights)
    ref_i = int(np.argmin(np.linalg.norm(pts - centre, axis=1)))
    steps = _Steps(n_xy * n_xy * heights + refine + trials, progress)
    # the candidates' thin factorisations and products on one BLAS thread, as in a block
    # of trials: threaded OpenBLAS spins more than it computes on them (the search of
    # Aguado et al. 2016's mesh took 26.4 s with two threads under load, 7.4 s with one)
    with one_blas_thread():
        best: tuple[float, LaserTracker] | None = None
        scored = rejected = 0
        for x in xs:  # a small grid of candidates, each scored in milliseconds
            for y in ys:
                if lo[0] - margin < x < hi[0] + margin and lo[1] - margin < y < hi[1] + margin:
                    steps(heights)
                    continue
                for z in zs:
                    steps(1)
                    lt = _upright(np.array([x, y, z]), centre, noise, "best")
                    if not visibility(lt, pts, limits, reference=ref_i).ok:
                        rejected += 1
                        continue
                    u = _gum_score(ver, lt)
                    scored += 1
                    if best is None or u < best[0]:
                        best = (u, lt)
        if best is None:
            raise InputError(
                "no candidate position sees every point within the limits", field="limits"
            )
        u0, lt0 = best
        # refine position and orientation (three Euler angles, "xyz") from the best grid node
        x0 = np.concatenate([lt0.position, lt0.euler("xyz")])
        scale = np.array([100.0, 100.0, 100.0, 0.2, 0.2, 0.2])

        refined = steps.done + refine

        def score(v: _F) -> float:
            steps(1 if steps.done < refined else 0)
            w = x0 + v * scale
            if not limits.height[0] <= w[2] <= limits.height[1]:
                return math.inf
            lt = LaserTracker.from_euler(w[:3], w[3:], seq="xyz", noise=noise, name="best")
            if not visibility(lt, pts, limits, reference=ref_i).ok:
                return math.inf
            return _gum_score(ver, lt)

        opt = minimize(
            score,
            np.zeros(6),
            method="Nelder-Mead",
            options={"maxfev": refine, "xatol": 1e-3, "fatol": 1e-9},
        )
        if np.isfinite(opt.fun) and opt.fun < u0:
            w = x0 + opt.x * scale
            best = (
                float(opt.fun),
                LaserTracker.from_euler(w[:3], w[3:], seq="xyz", noise=noise, name="best"),
            )
        steps(refined - steps.done)  # the refinement may stop before ``refine``
        refs = {n: _gum_score(ver, lt) for n, lt in (references or {}).items()}
    u_mc = None
    if trials > 0:
        b = best[1]
        v2 = Verification(ver.model, ver.q, b, ver.true_errors, pose=ver.pose, fixed=ver.fixed)
        offset = steps.done
        mc = simulate(
            v2, trials, seed, progress=lambda n, _t: steps(offset + n - steps.done), **engine
        )
        u_mc = float(np.mean(mc.point_u))
    return Placement(best[1], best[0], u_mc, scored, rejected, refs)
