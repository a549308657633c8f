"""The ``[correlation]`` table of a ``propagate`` study: correlated inputs by a copula.

::

    [correlation]
    pairs = [["a", "b", 0.8], ["a", "c", -0.3]]   # r(a, b), r(a, c); other pairs 0
    copula = "gaussian"                           # or {kind = "t", dof = 4}

or the whole matrix, its rows and columns in the order of ``names``::

    [correlation]
    names = ["a", "b", "c"]
    matrix = [[1.0, 0.8, -0.3], [0.8, 1.0, 0.0], [-0.3, 0.0, 1.0]]

The coefficients are the correlation matrix of the copula that joins the inputs'
marginal PDFs in the Monte Carlo (:mod:`mtmc.uncertainty.copula`), and the
``r(x_i, x_j)`` of the GUM's law of propagation (JCGM 100 eq. (13)). The result records
them with the product-moment correlation that the Monte Carlo actually drew and the rank
correlations they imply (``docs/correlation.md``). Every error names the file, the line
and the field (``correlation.pairs[1]``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from mtmc.document import Fields, finite
from mtmc.errors import InputError
from mtmc.uncertainty.copula import (
    Copula,
    Correlation,
    kendall_tau,
    realised_correlation,
    spearman_rho,
)
from mtmc.uncertainty.distributions import Distribution
from mtmc.uncertainty.propagation import GumResult

__all__ = ["CorrelationSpec", "correlation_record", "read_correlation"]

#: At most this many inputs in one correlation matrix (a matrix of 250 000 entries).
MAX_CORRELATED: int = 500


@dataclass(frozen=True)
class CorrelationSpec:
    """The ``[correlation]`` table: the correlation matrix and the copula.

    Attributes
    ----------
    correlation : Correlation
        The coefficients (the copula's parameter; the GUM's ``r``).
    copula : Copula
        How the Monte Carlo joins the marginals.
    """

    correlation: Correlation
    copula: Copula

    @property
    def engine(self) -> dict[str, Any]:
        """The ``correlation`` and ``copula`` keywords of :func:`mtmc.monte_carlo`."""
        return {"correlation": self.correlation, "copula": self.copula}


def _read_copula(table: Fields) -> Copula:
    if not table.has("copula"):
        return Copula()
    value = table.data["copula"]
    if isinstance(value, str):
        kind = table.text("copula", choices=("gaussian", "t"))
        if kind == "t":
            raise table.error(
                'a t copula needs its degrees of freedom: copula = {kind = "t", dof = 4}',
                "copula",
            )
        return Copula()
    if not isinstance(value, dict):
        raise table.error(
            f'expected "gaussian" or {{kind = "t", dof = ...}}, got {value!r}', "copula"
        )
    sub = table.table("copula")
    assert sub is not None
    sub.only(("kind", "dof"))
    kind = sub.text("kind", choices=("gaussian", "t"))
    if kind == "gaussian":
        if sub.has("dof"):
            raise sub.error("the Gaussian copula has no degrees of freedom", "dof")
        return Copula()
    dof = sub.number("dof", low=0.0, open_low=True)
    try:
        return Copula("t", float(dof))
    except InputError as exc:  # below MIN_T_DOF: at the line of dof
        raise sub.error(exc.message, "dof") from None


def _where(message_field: str | None, pairs: list[Any] | None) -> tuple[str | int, ...]:
    """The key path in ``[correlation]`` of an error of :class:`Correlation`."""
    if pairs is None or not message_field or not message_field.startswith("correlation["):
        return ("pairs",) if pairs is not None else ("matrix",)
    inside = message_field[len("correlation[") : -1].split(", ")
    if len(inside) == 2:
        for i in range(len(pairs) - 1, -1, -1):  # the last: the second of a pair given twice
            if {str(pairs[i][0]), str(pairs[i][1])} == set(inside):
                return ("pairs", i)
    return ("pairs",)


def read_correlation(top: Fields, inputs: Mapping[str, Distribution]) -> CorrelationSpec | None:
    """Read the ``[correlation]`` table of a study (None where there is none).

    Parameters
    ----------
    top : Fields
        The study file.
    inputs : mapping of str to Distribution
        The inputs of the model: every name of the table must be a scalar one with an
        uncertainty.

    Returns
    -------
    CorrelationSpec or None

    Raises
    ------
    InputError
        Naming the file, the line and the field: a malformed pair, a name that is not a
        scalar input with an uncertainty, a pair given twice, a coefficient outside
        [-1, 1], a matrix that is not square, symmetric or positive semi-definite, a
        copula other than ``"gaussian"`` or ``{kind = "t", dof = ν}``.
    """
    table = top.table("correlation", required=False)
    if table is None:
        return None
    if top.has("sensitivity"):
        raise top.error(
            "[sensitivity] varies each input alone, which assumes independent inputs; "
            "it cannot be combined with [correlation]",
            "sensitivity",
        )
    table.only(("pairs", "names", "matrix", "copula"))
    copula = _read_copula(table)
    pairs: list[Any] | None = None
    if table.has("pairs"):
        if table.has("names") or table.has("matrix"):
            raise table.error("give either pairs or names and matrix, not both", "pairs")
        pairs = table.data["pairs"]
        items = _read_pairs(table, inputs)
        build: Any = lambda: Correlation.from_pairs(items)  # noqa: E731
    else:
        names, matrix = _read_matrix(table, inputs)
        build = lambda: Correlation.from_matrix(matrix, names)  # noqa: E731
    try:
        corr: Correlation = build()
    except InputError as exc:
        raise table.source.error(exc.message, (*table.path, *_where(exc.field, pairs))) from None
    return CorrelationSpec(corr, copula)


def _read_pairs(table: Fields, inputs: Mapping[str, Distribution]) -> list[tuple[str, str, float]]:
    pairs = table.data["pairs"]
    if not isinstance(pairs, list) or not pairs:
        raise table.error(
            'expected a non-empty array of [name, name, r], e.g. [["a", "b", 0.8]]', "pairs"
        )
    if len(pairs) > MAX_CORRELATED**2 // 2:
        raise table.error(f"expected at most {MAX_CORRELATED**2 // 2} pairs", "pairs")
    items: list[tuple[str, str, float]] = []
    for i, entry in enumerate(pairs):
        where: tuple[str | int, ...] = ("pairs", i)
        if (
            not isinstance(entry, list)
            or len(entry) != 3
            or not isinstance(entry[0], str)
            or not isinstance(entry[1], str)
            or isinstance(entry[2], bool)
            or not isinstance(entry[2], int | float)
        ):
            raise table.source.error(
                f"expected [name, name, r], got {entry!r}", (*table.path, *where)
            )
        for name in entry[:2]:
            _check_name(table, where, name, inputs)
        r = finite(entry[2])
        if r is None:
            raise table.source.error(
                f"expected a finite coefficient, got {entry[2]!r:.80}", (*table.path, *where)
            )
        items.append((entry[0], entry[1], r))
    return items


def _read_matrix(
    table: Fields, inputs: Mapping[str, Distribution]
) -> tuple[tuple[str, ...], np.ndarray[Any, np.dtype[np.float64]]]:
    if not (table.has("names") and table.has("matrix")):
        raise table.missing(
            "expected pairs = [[name, name, r], ...], or names = [...] with matrix = [[...], ...]",
            "pairs",
        )
    names: tuple[str, ...] = table.texts("names", max_items=MAX_CORRELATED)
    for i, name in enumerate(names):
        _check_name(table, ("names", i), name, inputs)
    matrix = table.data["matrix"]
    rows_ok = isinstance(matrix, list) and all(
        isinstance(row, list) and all(finite(v) is not None for v in row) for row in matrix
    )
    if not rows_ok:
        raise table.error("expected a matrix: an array of arrays of finite numbers", "matrix")
    if len(matrix) != len(names) or any(len(row) != len(names) for row in matrix):
        raise table.error(
            f"expected {len(names)} rows of {len(names)} numbers, one per name, in the "
            "order of names",
            "matrix",
        )
    return names, np.array(matrix, dtype=np.float64)


def _check_name(
    table: Fields,
    where: tuple[str | int, ...],
    name: str,
    inputs: Mapping[str, Distribution],
) -> None:
    try:
        Correlation((name,), np.eye(1)).check_inputs(inputs)
    except InputError as exc:
        raise table.source.error(exc.message, (*table.path, *where)) from None


def correlation_record(
    spec: CorrelationSpec,
    inputs: Mapping[str, Distribution],
    *,
    seed: int,
    trials: int,
    gum_result: GumResult | None,
    outputs: Sequence[str] = (),
) -> dict[str, Any]:
    """The ``correlation`` entry of ``result.json``.

    Parameters
    ----------
    spec : CorrelationSpec
        The ``[correlation]`` table.
    inputs : mapping of str to Distribution
        The inputs of the run.
    seed, trials : int
        The seed and the number of trials of the Monte Carlo run.
    gum_result : GumResult or None
        The GUM of the same model, for the part of ``u²(y)`` that the cross terms give;
        for several outputs (a GUM of the stacked model) that part of each ``u²(y_i)``.
    outputs : sequence of str
        The names of the outputs of a GUM of several.

    Returns
    -------
    dict
        ``copula`` (``{"kind", "dof"}``), ``names`` and ``matrix`` (the coefficients given),
        ``realised`` (the product-moment correlation matrix of the drawn inputs, as
        :func:`~mtmc.uncertainty.copula.realised_correlation`), ``pairs``: one entry per
        pair of names with ``r`` (given), ``realised``, ``kendall_tau`` (``(2/π) asin r``)
        and ``spearman_rho`` (``(6/π) asin(r/2)``, Gaussian copula only, else None); and
        ``gum_cross_variance``: ``Σ_{i≠j} c_i c_j u_i u_j r_ij`` of the GUM (None
        without one or with several outputs), and ``gum_cross_share``, its part of
        ``u²(y)``; with several outputs, ``outputs``: per output ``name``,
        ``gum_cross_variance`` and ``gum_cross_share``. The correlation of the inputs is
        the same whatever the number of outputs.
    """
    corr, cop = spec.correlation, spec.copula
    real = realised_correlation(inputs, trials, seed, corr, cop)
    names = corr.names
    pairs = []
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            r = float(corr.matrix[i, j])
            pairs.append(
                {
                    "a": names[i],
                    "b": names[j],
                    "r": r,
                    "realised": float(real[i, j]),
                    "kendall_tau": float(kendall_tau(r)),
                    "spearman_rho": float(spearman_rho(r)) if cop.kind == "gaussian" else None,
                }
            )
    cross = share = None
    by_output = []
    if gum_result is not None:
        by_name = {e.name: e for e in gum_result.budget}
        variances = np.asarray(gum_result.u_vector, dtype=np.float64) ** 2
        for i, var in enumerate(variances):
            total = 0.0
            for a, b, r in corr.pairs():
                ca, cb = by_name[a], by_name[b]
                total += (
                    2.0 * r * float(ca.sensitivity[i, 0] * ca.u[0] * cb.sensitivity[i, 0] * cb.u[0])
                )
            part = total / float(var) if var > 0 else None
            if gum_result.scalar:
                cross, share = total, part
            else:
                name = outputs[i] if i < len(outputs) else f"y[{i}]"
                by_output.append(
                    {"name": name, "gum_cross_variance": total, "gum_cross_share": part}
                )
    return {
        "copula": cop.to_dict(),
        "names": list(names),
        "matrix": corr.matrix.tolist(),
        "realised": real.tolist(),
        "pairs": pairs,
        "gum_cross_variance": cross,
        "gum_cross_share": share,
        **({"outputs": by_output} if by_output else {}),
    }
