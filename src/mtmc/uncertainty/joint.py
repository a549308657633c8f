"""Joint summaries of several output quantities (JCGM 102:2011).

Where one model has several outputs ``Y = (Y_1, ..., Y_d)`` the outputs are described
together by their estimate vector and covariance matrix ``U_y`` (JCGM 102 §3.21, §7.5),
their correlation matrix (JCGM 102 §3.22) and a coverage region (JCGM 102 §7.7). The
Monte Carlo region comes from
:meth:`~mtmc.uncertainty.results.MonteCarloResult.coverage_ellipsoid`; this module adds
the region of the GUM (JCGM 102 §6.5.2.3: the ellipsoid of ``U_y = C U_x Cᵀ`` with
``k_p² = χ²_d(p)``, exact for a Gaussian output) and the correlation matrix, and the
vector model itself: outputs of expression models (:class:`ModelOutput`) as one model
with named outputs for :func:`~mtmc.uncertainty.montecarlo.monte_carlo`
(:class:`NamedOutputs`) and as one vector model for :func:`~mtmc.uncertainty.propagation.gum`
(:class:`JointModel`, whose sensitivity matrix is the ``C`` of JCGM 102 §6.2.1.3).

Examples
--------
>>> import numpy as np
>>> correlation(np.array([[4.0, 1.0], [1.0, 1.0]])).tolist()
[[1.0, 0.5], [0.5, 1.0]]
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import InputError
from mtmc.uncertainty.checks import check_probability
from mtmc.uncertainty.formula import Expression
from mtmc.uncertainty.propagation import GumResult
from mtmc.uncertainty.results import CoverageEllipsoid

__all__ = ["JointModel", "ModelOutput", "NamedOutputs", "correlation", "gum_coverage_ellipsoid"]


def correlation(cov: npt.ArrayLike) -> NDArray[np.float64]:
    """The correlation matrix ``r_ij = U_ij / (u_i u_j)`` of a covariance matrix (JCGM 102 §3.22).

    Parameters
    ----------
    cov : array_like, shape (d, d)
        A covariance matrix.

    Returns
    -------
    ndarray, shape (d, d)
        The correlation coefficients; the diagonal is 1 where ``u_i > 0``. A row and a
        column of a component with ``u_i = 0`` (a constant) are NaN: its correlation is
        not defined.

    Raises
    ------
    InputError
        If ``cov`` is not a square matrix.
    """
    c = np.asarray(cov, dtype=np.float64)
    if c.ndim != 2 or c.shape[0] != c.shape[1]:
        raise InputError(f"expected a square covariance matrix, got shape {c.shape}", field="cov")
    u = np.sqrt(np.clip(np.diag(c), 0.0, None))
    with np.errstate(divide="ignore", invalid="ignore"):
        r = c / np.outer(u, u)
    r[u == 0, :] = np.nan
    r[:, u == 0] = np.nan
    # the diagonal is 1 by definition, not by the rounding of U_ii / (√U_ii)²
    np.fill_diagonal(r, np.where(u > 0, 1.0, np.nan))
    out: NDArray[np.float64] = np.clip(r, -1.0, 1.0)
    return out


def gum_coverage_ellipsoid(result: GumResult, p: float | None = None) -> CoverageEllipsoid:
    """The GUM coverage region of a vector output (JCGM 102 §6.5.2.3).

    ``{η : (η - y)ᵀ U_y⁻¹ (η - y) <= k_p²}`` with ``y`` and ``U_y = C U_x Cᵀ`` the GUM
    estimate and covariance (JCGM 102 §6.2.1.3) and ``k_p² = χ²_d(p)``, the ``p``-quantile
    of the chi-squared distribution with ``d`` degrees of freedom: the smallest region of
    probability ``p`` of the Gaussian PDF ``N(y, U_y)`` that the GUM assigns to the output.

    Parameters
    ----------
    result : GumResult
        A GUM result of a vector output (``d >= 1`` components).
    p : float, optional
        Coverage probability; default the ``p`` of ``result``.

    Returns
    -------
    CoverageEllipsoid
        With ``method = "chi2"``.

    Raises
    ------
    InputError
        For a scalar output, a singular ``U_y`` (an output that is constant, or outputs
        that are linearly dependent to first order), or ``p`` outside (0, 1).

    Examples
    --------
    >>> from mtmc.uncertainty.propagation import gum
    >>> class Pair:
    ...     names = ("a", "b")
    ...     def __call__(self, a, b):
    ...         return np.stack([a + b, a - b], axis=-1)
    >>> g = gum(Pair(), {"a": "normal(0, 1)", "b": "normal(0, 1)"})
    >>> e = gum_coverage_ellipsoid(g, 0.95)
    >>> round(e.k**2, 4)  # χ²₂(0.95) = -2 ln 0.05
    5.9915
    """
    if result.scalar:
        raise InputError(
            "a coverage ellipsoid needs a vector output; use coverage_interval", field="result"
        )
    pf = check_probability(result.p if p is None else p)
    centre = np.array(result.estimate_vector)
    cov = np.array(result.cov)
    from scipy import stats  # imported here: scipy.stats costs ~0.5 s at import

    k = math.sqrt(float(stats.chi2.ppf(pf, centre.size)))
    lam, vec = np.linalg.eigh(cov)
    region = CoverageEllipsoid(
        centre=centre,
        cov=cov,
        k=k,
        p=pf,
        method="chi2",
        semi_axes=k * np.sqrt(np.clip(lam, 0.0, None)),
        axes=vec,
    )
    # refuses a singular U_y by the same test as the Monte Carlo region (a Cholesky factor)
    region.mahalanobis2(centre[None, :])
    return region


@dataclass(frozen=True)
class ModelOutput:
    """One output quantity of a study with several outputs.

    Attributes
    ----------
    name : str
        The output (a key of ``[outputs]``).
    model : Expression
        Its measurement model ``Y_i = f_i(X)``.
    unit : str
        Its unit (as text, for the report).
    """

    name: str
    model: Expression
    unit: str


def _union(outputs: tuple[ModelOutput, ...]) -> tuple[str, ...]:
    names: list[str] = []
    for o in outputs:
        names.extend(n for n in o.model.names if n not in names)
    return tuple(names)


class NamedOutputs:
    """The outputs as one model with named outputs, for :func:`mtmc.monte_carlo`.

    ``model(**arrays)`` returns ``{name: (m,) values}``, each output evaluated on the
    same trials from the inputs it uses.

    Parameters
    ----------
    outputs : tuple of ModelOutput
    """

    def __init__(self, outputs: tuple[ModelOutput, ...]) -> None:
        self.outputs = outputs
        self.names = _union(outputs)

    def __call__(self, **arrays: Any) -> dict[str, NDArray[Any]]:
        """``{name: values}`` of every output, from the arrays of its variables."""
        return {o.name: o.model(**{n: arrays[n] for n in o.model.names}) for o in self.outputs}


class JointModel:
    """The outputs stacked as one vector model ``(m, d)``, for :func:`mtmc.gum`.

    Its sensitivity matrix is the ``C`` of ``U_y = C U_x Cᵀ`` (JCGM 102 §6.2.1.3). It is
    complex-safe where every output is, and has the variables and components of all of
    them (:func:`~mtmc.uncertainty.formula.check_variables`,
    :func:`~mtmc.uncertainty.formula.check_components`).

    Parameters
    ----------
    outputs : tuple of ModelOutput
    """

    def __init__(self, outputs: tuple[ModelOutput, ...]) -> None:
        self.outputs = outputs
        self.names = _union(outputs)
        self.complex_safe = all(o.model.complex_safe for o in outputs)
        comps: dict[str, int] = {}
        for o in outputs:
            for n, k in o.model.components.items():
                comps[n] = max(comps.get(n, 0), k)
        self.components: Mapping[str, int] = comps
        self.text = "; ".join(f"{o.name} = {o.model.text}" for o in outputs)

    def __call__(self, **arrays: Any) -> NDArray[Any]:
        """The outputs' values as the columns of an ``(m, d)`` array."""
        cols = [o.model(**{n: arrays[n] for n in o.model.names}) for o in self.outputs]
        return np.stack(cols, axis=-1)
