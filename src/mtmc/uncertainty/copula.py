"""Correlated input quantities: a correlation matrix and the copula that joins the marginals.

JCGM 101:2008 §6.4.8 gives one joint PDF for correlated inputs, the multivariate
Gaussian; JCGM 100:2008 §5.2 (eq. 13) propagates any correlation coefficients
``r(x_i, x_j)`` through the sensitivity coefficients. To correlate inputs of *any* PDF of
JCGM 101 §6.4 (a rectangular with a triangular, say), the Monte Carlo joins their
marginal PDFs by a copula, as the NIST Uncertainty Machine does (Lafarge and Possolo
2015): a Gaussian copula, or a Student t copula (McNeil, Frey and Embrechts 2015,
§7.3), each with the correlation matrix ``R`` given here.

* :class:`Correlation` is the matrix ``R`` over named scalar inputs, checked to be a
  correlation matrix (symmetric, unit diagonal, entries in [-1, 1], positive
  semi-definite). The GUM (:func:`~mtmc.uncertainty.propagation.gum`) takes its entries as the
  ``r(x_i, x_j)`` of JCGM 100 eq. (13).
* :class:`Copula` says how the Monte Carlo (:func:`~mtmc.uncertainty.montecarlo.
  monte_carlo`) joins the marginals with that ``R``: ``Copula("gaussian")`` or
  ``Copula("t", dof)``.

``R`` is the copula's parameter: the correlation of the underlying normal (or t)
variables. For normal marginals and the Gaussian copula it is also the product-moment
correlation of the inputs; for other marginals their product-moment correlation differs
(it is smaller in magnitude for most PDFs), while the rank correlations follow from
``r`` alone: Kendall's ``τ = (2/π) asin r`` for both copulas, Spearman's
``ρ_s = (6/π) asin(r/2)`` for the Gaussian copula. :func:`realised_correlation` gives the
product-moment correlation that a run actually drew (``docs/correlation.md``).

Sampling
--------
The inputs of a correlated group are drawn together, seed block by seed block, from the
streams that the engine gives each input anyway (:mod:`mtmc.uncertainty.sampling`): in
seed block ``k`` input ``x`` draws ``SEED_BLOCK_SIZE`` independent standard normals
``z_x`` from ``SeedSequence(seed, spawn_key=(k, key(x)))``. With the names of the group
in sorted order and ``L`` a factor of ``R`` in that order (``L Lᵀ = R``; Cholesky where
``R`` is positive definite, else from its eigen-decomposition):

1. ``Z = L z`` (a fixed sum over the group, term by term, so that no number depends on
   a BLAS library or its threads);
2. Gaussian copula: ``U = Φ(Z)``. t copula with ``ν`` degrees of freedom: ``W ~ χ²_ν``
   from a stream of its own, ``SeedSequence(seed, spawn_key=(k, key("copula"), 1))`` (a
   spawn key of three words, which no input's stream has), and ``U = T_ν(Z / √(W/ν))``;
3. ``x = F_x⁻¹(U_x)``, the inverse CDF of each marginal (``Distribution.ppf``; a normal
   marginal under the Gaussian copula is ``μ + σ Z`` directly, the same draw without the
   round trip through ``Φ``).

With ``sampling="sobol"`` the normals come from the input's own quasi-random coordinate,
``z_x = Φ⁻¹(u_x)``, and a t copula takes one more coordinate, after those of every input,
for ``W = 2 P⁻¹(ν/2, u)`` (the inverse regularised incomplete gamma function). Hence one
seed gives the same numbers whatever the block size, the workers or the executor, and
whatever order the names were given in; inputs outside the group draw exactly what they
draw without a correlation. Under the Gaussian copula only inputs with a non-zero
coefficient join the group (the others are independent of it); under a t copula every
name of the :class:`Correlation` does, since the common ``W`` makes them dependent even
where ``r = 0``.

Examples
--------
>>> c = Correlation.from_pairs({("a", "b"): 0.8})
>>> c.names, float(c.coefficient("b", "a"))
(('a', 'b'), 0.8)
>>> Copula("t", 4)
Copula(kind='t', dof=4.0)
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal, cast

import numpy as np
from numpy.typing import NDArray

from mtmc.errors import InputError
from mtmc.frozen import frozen_value
from mtmc.uncertainty.distributions import Distribution, Normal, standard_normal
from mtmc.uncertainty.results import Moments
from mtmc.uncertainty.sampling import (
    BlockSource,
    Sampling,
    check_int,
    check_sampling,
    check_seed,
    input_generator,
    name_key,
    prepare_inputs,
)

__all__ = [
    "Copula",
    "CopulaKind",
    "Correlation",
    "as_copula",
    "as_correlation",
    "kendall_tau",
    "realised_correlation",
    "spearman_rho",
]

CopulaKind = Literal["gaussian", "t"]

#: An asymmetry or a diagonal off 1 of at most this is rounding (a correlation matrix
#: computed from data, or converted from a covariance, is symmetric to a few ulp); larger
#: ones are refused, as no one types two different values for r(a, b) and r(b, a) by
#: accident of rounding.
SYMMETRY_TOLERANCE: float = 1e-12

#: Multiple of ``n ε ‖R‖₂`` that a computed eigenvalue of a PSD matrix may fall below 0.
#: LAPACK's symmetric eigensolvers are backward stable: each computed eigenvalue lies
#: within ``p(n) ε ‖R‖₂`` of an exact one (LAPACK Users' Guide, 3rd ed., §4.7.1; Golub
#: and Van Loan, Matrix Computations, 4th ed., §8.4), with ``p(n)`` a modest function of
#: ``n``; ``10 n`` covers it, so a matrix that is PSD in exact arithmetic (a singular one
#: with r = ±1, or a rank-deficient set of coefficients) passes, and a smaller computed
#: eigenvalue is a true negative one.
PSD_FACTOR: float = 10.0

#: The probabilities mapped through a marginal's inverse CDF are kept in
#: ``[tiny, 1 - 2⁻⁵³]``: every quantile is finite. Only ``|Z| > 8.2`` reaches the bounds
#: (probability below 10⁻¹⁵ per draw).
#: The fewest degrees of freedom of a t copula. ``T = Z / √(W/ν)`` with ``W ~ χ²_ν``, whose
#: ``P(W < w) ≈ (w/2)^{ν/2} / Γ(ν/2 + 1)`` for small ``w``: at ``ν = 0.1`` ``W`` falls below
#: the smallest normal double (2.2e-308) in 4.1e-16 of the trials (10^-3.1 at ``ν = 0.02``,
#: 0.69 at ``ν = 10⁻³``), and a ``W`` lost to 0 makes ``|T|`` infinite: its trial goes to
#: the extreme end of every marginal, far out of its place (at ``ν = 10⁻³`` a normal(0, 1)
#: marginal came out with a standard deviation of 0.34).
MIN_T_DOF = 0.1

_U_LOW = float(np.finfo(np.float64).tiny)
_U_HIGH = float(np.nextafter(1.0, 0.0))


def kendall_tau(r: Any) -> NDArray[np.float64]:
    """Kendall's rank correlation of an elliptical copula: ``τ = (2/π) asin r``.

    Holds for the Gaussian and the t copula alike (Lindskog, McNeil and Schmock 2003),
    whatever the (continuous) marginals.

    Examples
    --------
    >>> float(kendall_tau(0.5))
    0.3333333333333333
    """
    return np.asarray((2.0 / math.pi) * np.arcsin(np.asarray(r, dtype=np.float64)))


def spearman_rho(r: Any) -> NDArray[np.float64]:
    """Spearman's rank correlation of the Gaussian copula: ``ρ_s = (6/π) asin(r/2)``.

    Pearson (1907); whatever the (continuous) marginals, it is the product-moment
    correlation of the inputs' probabilities ``F_i(x_i)``. It holds for the Gaussian
    copula only (the t copula has no closed form).

    Examples
    --------
    >>> float(spearman_rho(1.0))
    1.0
    """
    return np.asarray((6.0 / math.pi) * np.arcsin(0.5 * np.asarray(r, dtype=np.float64)))


@dataclass(frozen=True)
class Copula:
    """How the Monte Carlo joins the marginal PDFs of correlated inputs.

    Parameters
    ----------
    kind : {"gaussian", "t"}, default "gaussian"
        The Gaussian copula, or the Student t copula.
    dof : float, default inf
        Degrees of freedom ``ν ≥ 0.1`` of the t copula (:data:`MIN_T_DOF`; ``inf`` for the
        Gaussian one). The smaller ``ν``, the stronger the dependence in the tails: two
        inputs of a t copula with correlation ``r`` exceed their ``q``-quantiles together
        with a probability that, divided by ``1 - q``, tends to
        ``2 T_{ν+1}(-√((ν+1)(1-r)/(1+r))) > 0`` as ``q → 1``, where the Gaussian copula's
        tends to 0 (McNeil, Frey and Embrechts 2015, Example 7.39).

    Examples
    --------
    >>> Copula(), str(Copula("t", 4))
    (Copula(kind='gaussian', dof=inf), 't(4)')
    """

    kind: CopulaKind = "gaussian"
    dof: float = math.inf

    def __post_init__(self) -> None:
        if self.kind not in ("gaussian", "t"):
            raise InputError(
                f"expected copula kind 'gaussian' or 't', got {self.kind!r}", field="copula"
            )
        if self.kind == "gaussian":
            if self.dof != math.inf:
                raise InputError(
                    f"the Gaussian copula has no degrees of freedom, got dof = {self.dof!r}; "
                    "use Copula('t', dof)",
                    field="copula.dof",
                )
            return
        dof = self.dof
        if isinstance(dof, bool) or not isinstance(dof, int | float | np.integer | np.floating):
            raise InputError(
                f"expected the degrees of freedom of the t copula as a number, got {dof!r}",
                field="copula.dof",
            )
        if not (math.isfinite(dof) and dof >= MIN_T_DOF):
            why = ""
            if dof == math.inf:
                why = " (the t copula tends to the Gaussian one as dof grows: use 'gaussian')"
            elif dof > 0:
                why = (
                    f" (below {MIN_T_DOF:g} its chi-square draw W underflows to 0 in more than "
                    "one trial in 10^15 and the marginals' tails are lost)"
                )
            raise InputError(
                f"expected {MIN_T_DOF:g} <= dof < inf for the t copula, got {dof!r}{why}",
                field="copula.dof",
            )
        object.__setattr__(self, "dof", float(dof))

    def __str__(self) -> str:
        return "gaussian" if self.kind == "gaussian" else f"t({self.dof:g})"

    def to_dict(self) -> dict[str, Any]:
        """``{"kind": "gaussian"}`` or ``{"kind": "t", "dof": ν}`` (JSON-ready)."""
        return {"kind": "gaussian"} if self.kind == "gaussian" else {"kind": "t", "dof": self.dof}


def as_copula(obj: Any, *, field: str = "copula") -> Copula:
    """A :class:`Copula` from ``"gaussian"``, ``("t", ν)``, ``{"kind": "t", "dof": ν}`` or a Copula.

    Raises
    ------
    InputError
        Anything else, naming ``field``.

    Examples
    --------
    >>> as_copula("gaussian"), as_copula(("t", 4)).dof, as_copula({"kind": "t", "dof": 3}).dof
    (Copula(kind='gaussian', dof=inf), 4.0, 3.0)
    """
    if isinstance(obj, Copula):
        return obj
    if obj == "gaussian":
        return Copula()
    if obj == "t":
        raise InputError(
            "a t copula needs its degrees of freedom: ('t', dof) or {kind = 't', dof = ...}",
            field=field,
        )
    if isinstance(obj, Mapping):
        extra = set(obj) - {"kind", "dof"}
        if extra or "kind" not in obj:
            raise InputError(
                f"expected a copula as {{kind, dof}}, got the keys {sorted(map(str, obj))}",
                field=field,
            )
        if obj["kind"] == "t" and "dof" not in obj:
            raise InputError("a t copula needs its degrees of freedom, dof", field=field)
        return Copula(obj["kind"], obj.get("dof", math.inf))
    if isinstance(obj, tuple) and len(obj) == 2 and obj[0] == "t":
        return Copula("t", obj[1])
    raise InputError(
        f"expected 'gaussian', ('t', dof) or a Copula, got {obj!r}",
        field=field,
    )


def _pair_field(a: str, b: str) -> str:
    return f"correlation[{a}, {b}]"


@dataclass(frozen=True, eq=False)
class Correlation:
    """A correlation matrix over named scalar inputs (JCGM 100 §5.2.2; JCGM 101 §6.4.8).

    Build it with :meth:`from_pairs` or :meth:`from_matrix`; the constructor takes the
    names and the matrix in the same order and checks them.

    Parameters
    ----------
    names : tuple of str
        The inputs, in the order of the rows of ``matrix``.
    matrix : array_like, shape (n, n)
        The correlation coefficients (a read-only copy is kept).

    Raises
    ------
    InputError
        Names empty, repeated or not strings; a matrix not square of the names' size,
        not finite, not symmetric or without a unit diagonal (both to
        :data:`SYMMETRY_TOLERANCE`), with an entry outside [-1, 1], or not positive
        semi-definite (its smallest eigenvalue below ``-PSD_FACTOR · n ε λ_max``, see
        :data:`PSD_FACTOR`). The field names the offending pair where there is one.

    Examples
    --------
    >>> c = Correlation.from_matrix([[1, 0.5], [0.5, 1]], ["x", "y"])
    >>> c.pairs()
    (('x', 'y', 0.5),)
    >>> try:
    ...     Correlation.from_pairs({("x", "y"): 0.9, ("y", "z"): 0.9, ("x", "z"): -0.9})
    ... except InputError as exc:
    ...     print(exc.message[:50])
    not a correlation matrix: it is not positive semi-
    """

    names: tuple[str, ...]
    matrix: NDArray[np.float64] = field(repr=False)

    def __post_init__(self) -> None:
        names = tuple(self.names)
        for name in names:
            if not isinstance(name, str) or not name:
                raise InputError(
                    f"expected input names as non-empty strings, got {name!r}",
                    field="correlation",
                )
        if len(set(names)) != len(names):
            twice = sorted({n for n in names if names.count(n) > 1})
            raise InputError(
                f"{', '.join(twice)} named twice in the order of the matrix", field="correlation"
            )
        try:
            r = np.array(self.matrix, dtype=np.float64)
        except (TypeError, ValueError):
            raise InputError(
                "expected a square matrix of numbers", field="correlation.matrix"
            ) from None
        n = len(names)
        if r.shape != (n, n):
            raise InputError(
                f"expected a {n} × {n} matrix for the {n} names {list(names)}, got shape {r.shape}",
                field="correlation.matrix",
            )
        if not np.all(np.isfinite(r)):
            i, j = np.argwhere(~np.isfinite(r))[0]
            raise InputError(
                f"expected finite coefficients, got {r[i, j]}",
                field=_pair_field(names[i], names[j]),
            )
        for i in range(n):
            if abs(r[i, i] - 1.0) > SYMMETRY_TOLERANCE:
                raise InputError(
                    f"expected 1 on the diagonal (the correlation of {names[i]} with itself), "
                    f"got {r[i, i]!r}",
                    field=_pair_field(names[i], names[i]),
                )
        gap = np.abs(r - r.T)
        if np.any(gap > SYMMETRY_TOLERANCE):
            i, j = np.unravel_index(int(np.argmax(gap)), gap.shape)
            raise InputError(
                f"expected a symmetric matrix: r({names[i]}, {names[j]}) = {r[i, j]!r} but "
                f"r({names[j]}, {names[i]}) = {r[j, i]!r}",
                field=_pair_field(names[i], names[j]),
            )
        r = 0.5 * (r + r.T)
        np.fill_diagonal(r, 1.0)
        out = np.abs(r) > 1.0
        if np.any(out):
            i, j = np.argwhere(out)[0]
            raise InputError(
                f"expected a coefficient in [-1, 1], got r({names[i]}, {names[j]}) = {r[i, j]!r}",
                field=_pair_field(names[i], names[j]),
            )
        if n:
            lam, vec = np.linalg.eigh(r)
            tol = PSD_FACTOR * n * np.finfo(np.float64).eps * max(1.0, float(lam[-1]))
            if lam[0] < -tol:
                v = vec[:, 0]
                top = [names[i] for i in np.argsort(-np.abs(v))[: min(3, n)]]
                raise InputError(
                    "not a correlation matrix: it is not positive semi-definite (smallest "
                    f"eigenvalue {lam[0]:.3g} < 0), so no joint distribution has these "
                    f"coefficients; the coefficients among {', '.join(top)} contradict each "
                    "other (e.g. r(a, b) and r(b, c) near 1 force r(a, c) near 1)",
                    field="correlation",
                )
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "matrix", frozen_value(r))

    @classmethod
    def from_matrix(cls, matrix: Any, order: Iterable[str]) -> Correlation:
        """The matrix ``matrix`` whose rows and columns are the inputs ``order``.

        Examples
        --------
        >>> Correlation.from_matrix(np.eye(2), ("a", "b")).pairs()
        ()
        """
        if isinstance(order, str):
            raise InputError(
                f"expected the order as a list of names, got the string {order!r}",
                field="correlation.order",
            )
        return cls(tuple(order), np.asarray(matrix, dtype=np.float64))

    @classmethod
    def from_pairs(
        cls, pairs: Mapping[tuple[str, str], float] | Iterable[tuple[str, str, float]]
    ) -> Correlation:
        """The coefficients of some pairs; every other pair of the names named is 0.

        Parameters
        ----------
        pairs : mapping of (str, str) to float, or iterable of (str, str, float)
            ``{("a", "b"): 0.8}`` or ``[("a", "b", 0.8)]``. The names are taken in the
            order they first appear; each pair once (``(a, b)`` or ``(b, a)``).

        Examples
        --------
        >>> Correlation.from_pairs([("a", "b", 0.8), ("a", "c", -0.3)]).names
        ('a', 'b', 'c')
        """
        items: list[tuple[Any, Any, Any]]
        if isinstance(pairs, Mapping):
            items = []
            for key, value in pairs.items():
                if not (isinstance(key, tuple) and len(key) == 2):
                    raise InputError(
                        f"expected pairs of names as keys, e.g. ('a', 'b'), got {key!r}",
                        field="correlation",
                    )
                items.append((key[0], key[1], value))
        else:
            items = []
            for entry in pairs:
                if not (isinstance(entry, tuple | list) and len(entry) == 3):
                    raise InputError(
                        f"expected (name, name, r), got {entry!r}", field="correlation"
                    )
                items.append((entry[0], entry[1], entry[2]))
        names: list[str] = []
        for a, b, _ in items:
            for n in (a, b):
                if not isinstance(n, str) or not n:
                    raise InputError(
                        f"expected input names as non-empty strings, got {n!r}",
                        field="correlation",
                    )
                if n not in names:
                    names.append(n)
        index = {n: i for i, n in enumerate(names)}
        r = np.eye(len(names))
        seen: set[frozenset[str]] = set()
        for a, b, value in items:
            where = _pair_field(a, b)
            if a == b:
                raise InputError(
                    f"a pair of two different inputs is expected, got ({a}, {b}); the "
                    "correlation of an input with itself is 1",
                    field=where,
                )
            if frozenset((a, b)) in seen:
                raise InputError(f"the pair ({a}, {b}) is given twice", field=where)
            seen.add(frozenset((a, b)))
            if isinstance(value, bool) or not isinstance(
                value, int | float | np.integer | np.floating
            ):
                raise InputError(f"expected a number, got {value!r}", field=where)
            r[index[a], index[b]] = r[index[b], index[a]] = float(value)
        return cls(tuple(names), r)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Correlation):
            return NotImplemented
        return self.names == other.names and bool(np.array_equal(self.matrix, other.matrix))

    def __hash__(self) -> int:
        return hash((self.names, self.matrix.tobytes()))

    def __repr__(self) -> str:
        return f"Correlation(names={self.names!r}, matrix={self.matrix.tolist()!r})"

    def coefficient(self, a: str, b: str) -> float:
        """``r(a, b)``: 1 for ``a == b``, 0 for a pair that was not given.

        Examples
        --------
        >>> Correlation.from_pairs({("a", "b"): 0.5}).coefficient("a", "c")
        0.0
        """
        if a == b:
            return 1.0
        if a not in self.names or b not in self.names:
            return 0.0
        return float(self.matrix[self.names.index(a), self.names.index(b)])

    def pairs(self) -> tuple[tuple[str, str, float], ...]:
        """The non-zero coefficients ``(a, b, r)`` above the diagonal, in the names' order."""
        n = len(self.names)
        return tuple(
            (self.names[i], self.names[j], float(self.matrix[i, j]))
            for i in range(n)
            for j in range(i + 1, n)
            if self.matrix[i, j] != 0.0
        )

    def to_dict(self) -> dict[str, Any]:
        """``{"names": [...], "matrix": [[...]]}`` (JSON-ready)."""
        return {"names": list(self.names), "matrix": self.matrix.tolist()}

    def check_inputs(self, dists: Mapping[str, Any], *, quantiles: bool = True) -> None:
        """Check that every name is a scalar input with an uncertainty.

        Parameters
        ----------
        dists : mapping of str to Distribution
            The inputs of the run.
        quantiles : bool, default True, keyword-only
            Whether each input must also have an inverse CDF (one uniform number per
            draw), through which the copula of the Monte Carlo draws it; the GUM needs
            none.

        Raises
        ------
        InputError
            A name that is not an input, a vector input (its components are correlated
            through its own PDF, e.g. a multivariate normal), a constant, or (with
            ``quantiles``) an input drawn from several uniform numbers.
        """
        for name in self.names:
            if name not in dists:
                known = ", ".join(map(str, dists)) or "none"
                raise InputError(
                    f"{name!r} is not an input of the model (the inputs are {known})",
                    field=f"correlation[{name}]",
                )
            d = dists[name]
            dim = getattr(d, "dim", 0)
            if dim:
                raise InputError(
                    f"{name} is a vector input ({d}): a correlation correlates scalar "
                    "inputs; give correlated components as one multivariate PDF "
                    "(JCGM 101 §6.4.8)",
                    field=f"correlation[{name}]",
                )
            if getattr(d, "uniform_dims", 1) == 0 or float(getattr(d, "std", 1.0)) == 0.0:
                raise InputError(
                    f"{name} is known exactly ({d}): it has no uncertainty to correlate",
                    field=f"correlation[{name}]",
                )
            if quantiles and getattr(d, "uniform_dims", 1) != 1:
                raise InputError(
                    f"{name} ({d}) has no inverse CDF (a draw takes {d.uniform_dims} uniform "
                    "numbers), through which a copula draws an input; correlate it in the "
                    "GUM only, or give it a PDF with one",
                    field=f"correlation[{name}]",
                )

    def factor(self) -> NDArray[np.float64]:
        """A factor ``L`` with ``L Lᵀ = R``, rows and columns in the names' order.

        The (lower) Cholesky factor where ``R`` is positive definite; else (``R``
        singular, as with ``r = ±1``) ``V Λ₊^½`` from the eigen-decomposition
        ``R = V Λ Vᵀ``, with the eigenvalues within the rounding of 0 (the tolerance of
        :data:`PSD_FACTOR`) set to 0, and each row scaled to unit length so that
        ``diag(L Lᵀ) = 1``: every ``Z_i`` stays standard normal, and two inputs with
        ``r = 1`` get the same ``Z`` to rounding.
        """
        r = np.array(self.matrix, dtype=np.float64)
        try:
            return np.asarray(np.linalg.cholesky(r), dtype=np.float64)
        except np.linalg.LinAlgError:
            lam, vec = np.linalg.eigh(r)
            tol = PSD_FACTOR * len(lam) * np.finfo(np.float64).eps * max(1.0, float(lam[-1]))
            f = vec * np.sqrt(np.where(lam > tol, lam, 0.0))
            f /= np.sqrt(np.sum(f * f, axis=1))[:, None]
            return np.asarray(f, dtype=np.float64)


def as_correlation(obj: Any) -> Correlation | None:
    """A :class:`Correlation` from a Correlation, a mapping of pairs, or None.

    Raises
    ------
    InputError
        Anything else (for a matrix, use :meth:`Correlation.from_matrix`).
    """
    if obj is None or isinstance(obj, Correlation):
        return obj
    if isinstance(obj, Mapping):
        return Correlation.from_pairs(cast(Mapping[tuple[str, str], float], obj))
    raise InputError(
        "expected a mapping of pairs, {('a', 'b'): r}, or a Correlation (for a matrix: "
        f"Correlation.from_matrix(matrix, order)), got {type(obj).__name__}",
        field="correlation",
    )


def _copula_w_generator(seed: int, block: int) -> np.random.Generator:
    """The stream of the t copula's ``W`` in seed block ``block`` (three-word spawn key)."""
    ss = np.random.SeedSequence(seed, spawn_key=(int(block), name_key("copula"), 1))
    return np.random.Generator(np.random.PCG64(ss))


@dataclass(frozen=True, eq=False)
class _JointSampler:
    """The correlated group of a run, names sorted; picklable (sent to worker processes)."""

    names: tuple[str, ...]
    factor: NDArray[np.float64]
    copula: Copula
    marginals: tuple[Distribution, ...]

    @property
    def extra_dims(self) -> int:
        """Quasi-random coordinates taken besides the inputs' own: 1 for ``W`` of a t copula."""
        return 1 if self.copula.kind == "t" else 0

    def draw(self, seed: int, block: int, n: int, method: Any) -> dict[str, NDArray[np.float64]]:
        """Seed block ``block`` (``n`` trials) of every input of the group."""
        z = [standard_normal(input_generator(seed, block, name), n, method) for name in self.names]
        w = None
        if self.copula.kind == "t":
            w = _copula_w_generator(seed, block).chisquare(self.copula.dof, n)
        return self._join(z, w)

    def from_points(
        self, u: NDArray[np.float64], layout: Mapping[str, tuple[int, int]], w_column: int
    ) -> dict[str, NDArray[np.float64]]:
        """The group's values from quasi-random points ``u`` (each input its own column)."""
        from scipy.special import gammaincinv, ndtri

        z = [np.asarray(ndtri(u[:, layout[name][0]]), dtype=np.float64) for name in self.names]
        w = None
        if self.copula.kind == "t":
            half = 0.5 * self.copula.dof
            w = 2.0 * np.asarray(gammaincinv(half, u[:, w_column]), dtype=np.float64)
        return self._join(z, w)

    def _join(
        self, z: list[NDArray[np.float64]], w: NDArray[np.float64] | None
    ) -> dict[str, NDArray[np.float64]]:
        from scipy.special import ndtr, stdtr

        out: dict[str, NDArray[np.float64]] = {}
        scale = None
        if w is not None:  # W = 0 underflows only for ν far below 1: keep 1/√(W/ν) finite
            scale = 1.0 / np.sqrt(np.maximum(w, np.finfo(np.float64).tiny) / self.copula.dof)
        for i, (name, dist) in enumerate(zip(self.names, self.marginals, strict=True)):
            # Z_i = Σ_j L_ij z_j over the non-zero L_ij, term by term in a fixed order
            cols = np.flatnonzero(self.factor[i])
            zi = self.factor[i, cols[0]] * z[cols[0]]
            for j in cols[1:]:
                zi += self.factor[i, j] * z[j]
            if scale is None and isinstance(dist, Normal):
                zi *= dist.std
                zi += dist.mean
                out[name] = zi
                continue
            if scale is None:
                p = np.asarray(ndtr(zi), dtype=np.float64)
            else:
                zi *= scale
                p = np.asarray(stdtr(self.copula.dof, zi), dtype=np.float64)
            np.clip(p, _U_LOW, _U_HIGH, out=p)
            out[name] = np.asarray(dist.ppf(p), dtype=np.float64)
        return out


def joint_sampler(
    correlation: Any, copula: Any, dists: Mapping[str, Distribution]
) -> _JointSampler | None:
    """The correlated group of a run, or None where every input is drawn on its own.

    Parameters
    ----------
    correlation : Correlation, mapping of pairs, or None
        The correlation matrix (see :func:`as_correlation`).
    copula : Copula, str, tuple or mapping
        The copula (see :func:`as_copula`).
    dists : mapping of str to Distribution
        The inputs of the run.

    Returns
    -------
    _JointSampler or None
        None without a correlation, or for a Gaussian copula with no non-zero
        coefficient (independent inputs are then drawn as they are without one: the
        same numbers).

    Raises
    ------
    InputError
        A bad correlation or copula; a name that is not a scalar input with an
        uncertainty; a t copula without a correlation (it would not know which inputs
        to join).
    """
    cop = as_copula(copula)
    corr = as_correlation(correlation)
    if corr is None:
        if cop.kind == "t":
            raise InputError(
                "a t copula joins the inputs that a correlation names; give correlation",
                field="copula",
            )
        return None
    corr.check_inputs(dists)
    names = list(corr.names)
    if cop.kind == "gaussian":  # the inputs uncorrelated with every other stay independent
        off = corr.matrix - np.eye(len(names))
        names = [n for i, n in enumerate(corr.names) if np.any(off[i] != 0.0)]
    if not names:
        return None
    names.sort()
    idx = [corr.names.index(n) for n in names]
    sub = Correlation(tuple(names), corr.matrix[np.ix_(idx, idx)])
    f = sub.factor()
    f.setflags(write=False)
    return _JointSampler(tuple(names), f, cop, tuple(dists[n] for n in names))


def realised_correlation(
    inputs: Mapping[str, Any],
    trials: int,
    seed: int,
    correlation: Any,
    copula: Any = "gaussian",
    *,
    sampling: Sampling = "random",
) -> NDArray[np.float64]:
    """The product-moment correlation of the inputs that a run draws, over ``correlation.names``.

    The same draws as :func:`~mtmc.uncertainty.montecarlo.monte_carlo` with these
    arguments makes, reduced seed block by seed block to their moments, merged in
    trial order (:class:`~mtmc.uncertainty.results.Moments`): memory independent of
    ``trials``.

    Parameters
    ----------
    inputs : mapping of str to Distribution
        The inputs of the run.
    trials : int
        Number of trials ``M``.
    seed : int
        The run's seed.
    correlation : Correlation or mapping of pairs
        The correlation matrix given (the copula's parameter).
    copula : Copula, str, tuple or mapping, default "gaussian"
        The copula.
    sampling : {"random", "sobol"}, keyword-only
        As for the run.

    Returns
    -------
    ndarray, shape (n, n)
        ``corr(x_i, x_j)`` of the draws, rows in the order of ``correlation.names``.

    Examples
    --------
    >>> from mtmc.uncertainty.distributions import Uniform
    >>> c = Correlation.from_pairs({("a", "b"): 0.9})
    >>> r = realised_correlation({"a": Uniform(0, 1), "b": Uniform(0, 1)}, 100_000, 1, c)
    >>> round(float(r[0, 1]), 2)  # (6/π) asin(0.45) = 0.892 for uniform marginals
    0.89
    """
    corr = as_correlation(correlation)
    if corr is None:
        raise InputError("expected a correlation", field="correlation")
    seed = check_seed(seed)
    trials = check_int(trials, "trials", 2)
    dists, method = prepare_inputs(inputs, "default")
    source = BlockSource(
        dists, seed, method, check_sampling(sampling, method), joint_sampler(corr, copula, dists)
    )
    total: Moments | None = None
    step = source.block_trials
    for a in range(0, trials, step):
        s = source.trials(a, min(a + step, trials))
        m = Moments.of(np.stack([s[n] for n in corr.names], axis=1))
        total = m if total is None else total.merge(m)
    assert total is not None
    cov = np.atleast_2d(total.cov)
    d = np.sqrt(np.diag(cov))
    out: NDArray[np.float64] = cov / np.outer(d, d)
    np.fill_diagonal(out, 1.0)
    return out
