"""The parameters of ISO 230-2 from their definitions, batched over trials and complex-safe.

With ``x_ij↑`` the deviation at target ``i`` in run ``j`` approached in the positive
direction (↓: the negative), ``n`` runs and ``m`` targets, ISO 230-2 defines:

=====================  ============================================================
``x̄_i↑``, ``x̄_i↓``     mean unidirectional positional deviation at a position:
                       ``x̄_i↑ = (1/n) Σ_j x_ij↑``
``x̄_i``                mean bidirectional positional deviation at a position:
                       ``(x̄_i↑ + x̄_i↓) / 2``
``B_i``                reversal value at a position: ``x̄_i↑ - x̄_i↓``
``B``                  reversal value of the axis: ``max_i |B_i|``
``B̄``                  mean reversal value of the axis: ``(1/m) Σ_i B_i``
``s_i↑``, ``s_i↓``     estimator of the unidirectional standard uncertainty of
                       positioning at a position:
                       ``s_i↑ = sqrt(1/(n - 1) Σ_j (x_ij↑ - x̄_i↑)²)``
``R_i↑``, ``R_i↓``     unidirectional repeatability of positioning at a position:
                       ``4 s_i↑``, ``4 s_i↓``
``R_i``                bidirectional repeatability at a position:
                       ``max(2 s_i↑ + 2 s_i↓ + |B_i|, R_i↑, R_i↓)``
``R↑``, ``R↓``, ``R``  repeatability of the axis: ``max_i R_i↑``, ``max_i R_i↓``,
                       ``max_i R_i``
``E↑``, ``E↓``         unidirectional systematic positional deviation of the axis:
                       ``max_i x̄_i↑ - min_i x̄_i↑`` (↓ alike)
``E``                  bidirectional systematic positional deviation of the axis:
                       ``max(x̄_i↑, x̄_i↓) - min(x̄_i↑, x̄_i↓)`` over all ``i``
``M``                  mean bidirectional positional deviation of the axis:
                       ``max_i x̄_i - min_i x̄_i``
``A↑``, ``A↓``         unidirectional accuracy of positioning of the axis:
                       ``max_i (x̄_i↑ + 2 s_i↑) - min_i (x̄_i↑ - 2 s_i↑)`` (↓ alike)
``A``                  bidirectional accuracy of positioning of the axis:
                       ``max(x̄_i↑ + 2 s_i↑, x̄_i↓ + 2 s_i↓) - min(x̄_i↑ - 2 s_i↑,
                       x̄_i↓ - 2 s_i↓)`` over all ``i``
=====================  ============================================================

:func:`axis_parameters` computes them from the means and standard deviations, with any
leading (trial) axes: the Monte Carlo of :mod:`mtmc.positioning.uncertainty` calls it on
a whole block of trials at once. Every operation accepts complex numbers (``|B_i|`` is
written ``B_i sign(Re B_i)``, and NumPy orders complex numbers by their real part first),
so the GUM's complex-step derivative passes through it: the derivative of a maximum is
that of the target where it is reached.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from mtmc.errors import InputError
from mtmc.positioning.data import PositioningTest

__all__ = [
    "OUTLIER_LEVEL",
    "SYMBOLS",
    "Outlier",
    "PositioningParameters",
    "axis_parameters",
    "evaluate",
    "grubbs_critical",
    "outliers",
    "statistics",
]

#: The parameters of the axis, by their symbols (``_up`` ↑, ``_down`` ↓, ``B_mean`` B̄).
SYMBOLS = ("A", "A_up", "A_down", "E", "E_up", "E_down", "M", "R", "R_up", "R_down", "B", "B_mean")

#: What each symbol is called in ISO 230-2.
NAMES = {
    "A": "bidirectional accuracy of positioning",
    "A_up": "unidirectional accuracy of positioning, positive direction",
    "A_down": "unidirectional accuracy of positioning, negative direction",
    "E": "bidirectional systematic positional deviation",
    "E_up": "unidirectional systematic positional deviation, positive direction",
    "E_down": "unidirectional systematic positional deviation, negative direction",
    "M": "mean bidirectional positional deviation",
    "R": "bidirectional repeatability of positioning",
    "R_up": "unidirectional repeatability of positioning, positive direction",
    "R_down": "unidirectional repeatability of positioning, negative direction",
    "B": "reversal value",
    "B_mean": "mean reversal value",
}


def _abs(x: Any) -> Any:
    """``|x|`` for real ``x``, analytic continuation ``x sign(Re x)`` for complex ``x``."""
    return np.where(np.real(x) < 0, -x, x)


def statistics(deviations: npt.ArrayLike) -> tuple[Any, Any]:
    """The means ``x̄_i↑, x̄_i↓`` and standard deviations ``s_i↑, s_i↓`` over the runs.

    Parameters
    ----------
    deviations : array_like, shape (..., m, n, 2)
        Deviations ``x_ij`` (last axis ↑, ↓), any leading (trial) axes; real or complex.

    Returns
    -------
    mean, s : ndarray, shape (..., m, 2)
        ``x̄ = (1/n) Σ_j x_ij`` and ``s = sqrt(Σ_j (x_ij - x̄)² / (n - 1))``.

    Examples
    --------
    >>> x = np.array([[[1.0, 0.0], [3.0, 2.0]]])         # m = 1 target, n = 2 runs
    >>> mean, s = statistics(x)
    >>> mean.tolist(), s.tolist()
    ([[2.0, 1.0]], [[1.4142135623730951, 1.4142135623730951]])
    """
    x = np.asarray(deviations)
    n = x.shape[-2]
    if x.ndim < 3 or x.shape[-1] != 2 or n < 2:
        raise InputError(
            f"expected deviations of shape (..., m, n, 2) with n >= 2, got {x.shape}",
            field="deviations",
        )
    mean = np.mean(x, axis=-2)
    d = x - mean[..., None, :]
    s = np.sqrt(np.sum(d * d, axis=-2) / (n - 1))
    return mean, s


@dataclass(frozen=True)
class PositioningParameters:
    """The parameters of ISO 230-2 of one test (or of each trial, with leading axes).

    Per target ``i`` (arrays ``(..., m)``): ``mean_up`` x̄_i↑, ``mean_down`` x̄_i↓,
    ``mean`` x̄_i, ``reversal`` B_i, ``s_up`` s_i↑, ``s_down`` s_i↓, ``R_i_up`` R_i↑,
    ``R_i_down`` R_i↓, ``R_i`` R_i. Of the axis (arrays ``(...)``): the :data:`SYMBOLS`
    ``A``, ``A_up``, ``A_down``, ``E``, ``E_up``, ``E_down``, ``M``, ``R``, ``R_up``,
    ``R_down``, ``B``, ``B_mean``. All in the unit of the deviations.
    """

    mean_up: Any
    mean_down: Any
    mean: Any
    reversal: Any
    s_up: Any
    s_down: Any
    R_i_up: Any
    R_i_down: Any
    R_i: Any
    A: Any
    A_up: Any
    A_down: Any
    E: Any
    E_up: Any
    E_down: Any
    M: Any
    R: Any
    R_up: Any
    R_down: Any
    B: Any
    B_mean: Any

    def axis_values(self) -> dict[str, Any]:
        """The parameters of the axis by symbol, in the order of :data:`SYMBOLS`."""
        return {k: getattr(self, k) for k in SYMBOLS}

    def stacked(self) -> Any:
        """The parameters of the axis as one array ``(..., 12)`` in the order of :data:`SYMBOLS`."""
        return np.stack([getattr(self, k) for k in SYMBOLS], axis=-1)


def axis_parameters(mean: npt.ArrayLike, s: npt.ArrayLike) -> PositioningParameters:
    """The parameters of ISO 230-2 from the means and standard deviations at the targets.

    Parameters
    ----------
    mean : array_like, shape (..., m, 2)
        ``x̄_i↑`` (``[..., 0]``) and ``x̄_i↓`` (``[..., 1]``).
    s : array_like, shape (..., m, 2)
        ``s_i↑`` and ``s_i↓``.

    Returns
    -------
    PositioningParameters
        With the formulas of the module's table; leading axes kept.

    Examples
    --------
    >>> mean = np.array([[0.0, -2.0], [5.0, 3.0]])   # two targets: x̄↑, x̄↓ in µm
    >>> s = np.array([[0.5, 0.5], [0.25, 0.5]])
    >>> p = axis_parameters(mean, s)
    >>> float(p.E), float(p.M), float(p.B), float(p.A), float(p.R)
    (7.0, 5.0, 2.0, 8.5, 4.0)
    """
    mu = np.asarray(mean)
    sd = np.asarray(s)
    up, down = mu[..., 0], mu[..., 1]
    s_up, s_down = sd[..., 0], sd[..., 1]
    bi = up - down
    xi = 0.5 * (up + down)
    r_up = 4.0 * s_up
    r_down = 4.0 * s_down
    r_i = np.max(np.stack([2.0 * s_up + 2.0 * s_down + _abs(bi), r_up, r_down]), axis=0)
    hi = mu + 2.0 * sd
    lo = mu - 2.0 * sd
    mtarget = up.shape[-1]
    flat = mu.reshape(*mu.shape[:-2], 2 * mtarget)
    return PositioningParameters(
        mean_up=up,
        mean_down=down,
        mean=xi,
        reversal=bi,
        s_up=s_up,
        s_down=s_down,
        R_i_up=r_up,
        R_i_down=r_down,
        R_i=r_i,
        A=np.max(hi.reshape(flat.shape), axis=-1) - np.min(lo.reshape(flat.shape), axis=-1),
        A_up=np.max(hi[..., 0], axis=-1) - np.min(lo[..., 0], axis=-1),
        A_down=np.max(hi[..., 1], axis=-1) - np.min(lo[..., 1], axis=-1),
        E=np.max(flat, axis=-1) - np.min(flat, axis=-1),
        E_up=np.max(up, axis=-1) - np.min(up, axis=-1),
        E_down=np.max(down, axis=-1) - np.min(down, axis=-1),
        M=np.max(xi, axis=-1) - np.min(xi, axis=-1),
        R=np.max(r_i, axis=-1),
        R_up=np.max(r_up, axis=-1),
        R_down=np.max(r_down, axis=-1),
        B=np.max(_abs(bi), axis=-1),
        B_mean=np.mean(bi, axis=-1),
    )


def evaluate(test: PositioningTest) -> PositioningParameters:
    """The parameters of ISO 230-2 of a test, from its readings (no uncertainty).

    Parameters
    ----------
    test : PositioningTest

    Returns
    -------
    PositioningParameters
        Per target arrays ``(m,)``, axis values as 0-d arrays, in ``test.unit``.
    """
    mean, s = statistics(test.deviations)
    return axis_parameters(mean, s)


#: The significance level of the outlier test of :func:`outliers` (two-sided).
OUTLIER_LEVEL = 0.05


@dataclass(frozen=True)
class Outlier:
    """A reading that Grubbs' test finds far from the other runs at its target.

    Attributes
    ----------
    target : float
        The target position ``P_i``.
    direction : int
        0 (↑) or 1 (↓).
    run : int
        The run's label.
    deviation : float
        The reading ``x_ij``.
    G : float
        Grubbs' statistic ``max_j |x_ij - x̄_i| / s_i`` at this target and direction.
    critical : float
        Its critical value at :data:`OUTLIER_LEVEL` for ``n`` runs.
    """

    target: float
    direction: int
    run: int
    deviation: float
    G: float
    critical: float

    def text(self, target_unit: str, unit: str) -> str:
        """One sentence that names the reading, the test and its level."""
        arrow = "↑" if self.direction == 0 else "↓"
        return (
            f"run {self.run} at P = {self.target:g} {target_unit} {arrow} reads "
            f"{self.deviation:.6g} {unit}, far from the other runs: Grubbs' test, G = "
            f"{self.G:.4g} > {self.critical:.4g} (two-sided, α = {OUTLIER_LEVEL:g}). "
            "ISO 230-2 keeps every run: it stays in every parameter; check the test's record"
        )


def grubbs_critical(n: int, alpha: float = OUTLIER_LEVEL) -> float:
    """The critical value of Grubbs' two-sided test for one outlier among ``n`` values.

    ``G_crit = (n - 1)/√n · √(t² / (n - 2 + t²))`` with ``t`` the upper ``α/(2n)``
    quantile of Student's t with ``n - 2`` degrees of freedom (Grubbs 1969; ASTM E178).

    Examples
    --------
    >>> round(grubbs_critical(5), 3)   # ASTM E178, n = 5, two-sided 5 % (one-sided 2.5 %)
    1.715
    """
    from scipy.stats import t as student_t

    if n < 3:
        raise InputError(f"Grubbs' test needs at least 3 values, got {n}", field="runs")
    q = float(student_t.isf(alpha / (2 * n), n - 2))
    return (n - 1) / math.sqrt(n) * math.sqrt(q * q / (n - 2 + q * q))


def outliers(test: PositioningTest, alpha: float = OUTLIER_LEVEL) -> list[Outlier]:
    """Readings far from the other runs at their target and direction (Grubbs' test).

    At each target and direction, the run farthest from the mean is tested by Grubbs'
    two-sided test (:func:`grubbs_critical`) at level ``alpha``. A reading found is only
    reported: ISO 230-2 keeps every run in every parameter.

    Parameters
    ----------
    test : PositioningTest
    alpha : float, default :data:`OUTLIER_LEVEL`

    Returns
    -------
    list of Outlier
        In the order of the targets, ↑ before ↓; empty with fewer than 3 runs.
    """
    if test.n < 3:
        return []
    x = test.deviations  # (m, n, 2)
    mean, s = statistics(x)
    dist = np.abs(x - mean[:, None, :])
    j = np.argmax(dist, axis=1)  # (m, 2)
    with np.errstate(invalid="ignore", divide="ignore"):
        g = np.take_along_axis(dist, j[:, None, :], axis=1)[:, 0, :] / s
    crit = grubbs_critical(test.n, alpha)
    found: list[Outlier] = []
    for i in range(test.m):
        for d in (0, 1):
            if s[i, d] > 0 and g[i, d] > crit:
                found.append(
                    Outlier(
                        target=float(test.targets[i]),
                        direction=d,
                        run=test.runs[int(j[i, d])],
                        deviation=float(x[i, j[i, d], d]),
                        G=float(g[i, d]),
                        critical=crit,
                    )
                )
    return found
