"""The chain of a :class:`~mtmc.kinematics.machine.Machine` as a program on row arrays.

Forward kinematics runs in internal blocks of :data:`BLOCK` poses. A vector of the chain
(the tool point, or a direction for :meth:`~mtmc.kinematics.machine.Machine.pose`) is a
``(4, B)`` array: its coordinates as three contiguous rows, and a fourth row of ones (a
point) or zeros (a direction), so that a constant affine map is one matrix product. Each
vector has two such buffers, written in turn, and one scratch row serves every product:
a block allocates almost nothing, and its working set stays in the second-level cache.

The chain is lowered once per call into a short list of operations:

- :class:`Affine` -- a constant affine map ``y -> A y + t``. Consecutive constant factors
  (a location error, the pivots, the setup errors, the nominal offsets) are multiplied
  out into one, and those before the first per-pose factor are applied to the starting
  vectors once per call;
- :class:`Translate` -- ``y + sum(sign * source)`` per coordinate (points only);
- :class:`SmallRotation` -- ``y + sign * (e x y)``, ``e`` from sources;
- :class:`AxisRotation` -- an exact rotation about a coordinate axis by a source angle;
- :class:`LinearMotion` -- ``y + q d``, ``d`` a unit vector transformed by operations.

A source is a named row of the block: an axis position ``q:<i>``, an error value, or the
cosine and sine of an angle. The error functions of one axis that share a basis (the
cubic polynomials of the six component errors, say) are evaluated together: the basis
once, every function in one matrix product; the translation errors of a linear axis and
its nominal motion are summed in the same product (:func:`merge_motions`). Cosine and sine
come from ``tan(q / 2)`` in one call instead of two (:func:`cos_sin`).

Nothing here is approximate beyond rounding: the small-angle matrices are those of the
model, and the result equals the product of the homogeneous matrices of the chain.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mtmc.kinematics.functions import ErrorFunction, PolynomialFunction

_F = NDArray[np.float64]
#: A source: a float where it is the same for every pose of the block, else a row (B,).
Src = Any
Sources = Mapping[str, Src]
#: The buffers (4, B) of the vectors, and which vectors are points.
Bufs = list[_F]
Flags = Sequence[bool]

#: Poses per internal block: the buffers of a block (a few dozen rows) stay in the
#: second-level cache.
BLOCK = 8192


def cos_sin(angle: Src, out: tuple[_F, _F] | None = None) -> tuple[Src, Src]:
    """Cosine and sine of an angle (rad) through ``h = tan(angle / 2)``.

    ``cos = (1 - h^2) / (1 + h^2)``, ``sin = 2 h / (1 + h^2)``: one transcendental call
    instead of two, with absolute errors of a few 1e-16 for every angle (``h`` is large
    near an odd multiple of pi, where ``2 / h`` and ``-1 + 2 / h^2`` are still exact to
    rounding; ``h^2`` does not overflow for a double angle). ``out``: two arrays the
    shape of ``angle`` for the cosine and the sine.
    """
    if isinstance(angle, float):
        return math.cos(angle), math.sin(angle)
    c, h = out if out is not None else (np.empty_like(angle), np.empty_like(angle))
    np.multiply(angle, 0.5, out=h)
    np.tan(h, out=h)
    np.multiply(h, h, out=c)  # h^2
    r = c + 1.0
    np.reciprocal(r, out=r)
    np.subtract(1.0, c, out=c)
    c *= r
    h *= r
    h *= 2.0
    return c, h


def _zero(v: Src) -> bool:
    return v is None or (isinstance(v, float) and v == 0.0)


def _cross_row(out: _F, x: _F, p: Src, u: _F, r: Src, v: _F, w: _F) -> None:
    """``out = x + p u - r v`` (p, r sources; a missing one is zero); ``w`` is scratch."""
    have = False
    if not _zero(p):
        np.multiply(p, u, out=out)
        have = True
    if not _zero(r):
        if have:
            np.multiply(r, v, out=w)
            out -= w
        else:
            np.multiply(r, v, out=out)
            np.negative(out, out=out)
            have = True
    if have:
        out += x
    else:
        np.copyto(out, x)


# ----------------------------------------------------------------------------------------
# operations: each acts on the current buffers ``vs`` (n vectors (4, B)), may write the
# spare buffers and swap; ``w`` is a scratch row (B,)


class Op:
    """One operation of the lowered chain."""

    keys: tuple[str, ...] = ()

    def run(self, vs: Bufs, spare: Bufs, points: Flags, src: Sources, w: _F) -> None:
        raise NotImplementedError


@dataclass
class Affine(Op):
    """``y -> A y + t`` (``t`` on points only), constant: one (3, 4) matrix product."""

    A: _F
    t: _F

    def __post_init__(self) -> None:
        self.M = np.hstack([self.A, self.t[:, None]])

    def run(self, vs: Bufs, spare: Bufs, points: Flags, src: Sources, w: _F) -> None:
        for n, v in enumerate(vs):
            np.matmul(self.M, v, out=spare[n][:3])
            vs[n], spare[n] = spare[n], v

    @property
    def pure_translation(self) -> bool:
        return bool(np.array_equal(self.A, np.eye(3)))

    def then(self, other: Affine) -> Affine:
        """The map ``other(self(y))``."""
        return Affine(other.A @ self.A, other.A @ self.t + other.t)


@dataclass
class Translate(Op):
    """``y_j + sum(sign * src[key])`` over the terms of coordinate j (points only)."""

    terms: tuple[tuple[tuple[float, str], ...], ...]  # per coordinate: (sign, key) ...
    #: A source (3, B) holding the three single terms, added in one call (set by Program).
    block: str | None = None

    def __post_init__(self) -> None:
        self.keys = tuple(k for t in self.terms for _, k in t)

    @property
    def triple(self) -> tuple[str, str, str] | None:
        """The keys when each coordinate adds exactly one source, else None."""
        if all(len(t) == 1 and t[0][0] > 0 for t in self.terms):
            return (self.terms[0][0][1], self.terms[1][0][1], self.terms[2][0][1])
        return None

    def run(self, vs: Bufs, spare: Bufs, points: Flags, src: Sources, w: _F) -> None:
        for n, v in enumerate(vs):
            if not points[n]:
                continue
            if self.block is not None:
                v[:3] += src[self.block]
                continue
            for j in range(3):
                for sign, key in self.terms[j]:
                    if sign > 0:
                        v[j] += src[key]
                    else:
                        v[j] -= src[key]


@dataclass
class SmallRotation(Op):
    """``y + sign * (e x y)`` with ``e = (src[a], src[b], src[c])`` (a missing key is 0)."""

    names: tuple[str | None, str | None, str | None]
    sign: float

    def __post_init__(self) -> None:
        self.keys = tuple(k for k in self.names if k is not None)

    def run(self, vs: Bufs, spare: Bufs, points: Flags, src: Sources, w: _F) -> None:
        a, b, c = (None if k is None else src[k] for k in self.names)
        for n, v in enumerate(vs):
            o = spare[n]
            x, y, z = v[0], v[1], v[2]
            if self.sign > 0:
                _cross_row(o[0], x, b, z, c, y, w)
                _cross_row(o[1], y, c, x, a, z, w)
                _cross_row(o[2], z, a, y, b, x, w)
            else:
                _cross_row(o[0], x, c, y, b, z, w)
                _cross_row(o[1], y, a, z, c, x, w)
                _cross_row(o[2], z, b, x, a, y, w)
            vs[n], spare[n] = o, v


@dataclass
class AxisRotation(Op):
    """Exact rotation about coordinate axis ``j`` by ``sign * src[key]``."""

    j: int
    key: str
    sign: float

    def __post_init__(self) -> None:
        self.keys = (self.key,)

    def run(self, vs: Bufs, spare: Bufs, points: Flags, src: Sources, w: _F) -> None:
        c = src[f"{self.key}#cos"]
        s = src[f"{self.key}#sin"]
        j = self.j
        i, k = (j + 1) % 3, (j + 2) % 3
        for n, v in enumerate(vs):
            o = spare[n]
            np.multiply(c, v[i], out=o[i])
            np.multiply(s, v[k], out=w)
            if self.sign > 0:
                o[i] -= w
            else:
                o[i] += w
            np.multiply(c, v[k], out=o[k])
            np.multiply(s, v[i], out=w)
            if self.sign > 0:
                o[k] += w
            else:
                o[k] -= w
            np.copyto(o[j], v[j])
            vs[n], spare[n] = o, v


@dataclass
class LinearMotion(Op):
    """``y + src[q] d`` on points, ``d`` the unit vector ``e_j`` after ``ops``."""

    q: str
    j: int
    ops: list[Op]

    def __post_init__(self) -> None:
        self.keys = (self.q, *(k for op in self.ops for k in op.keys))

    def direction(self, src: Mapping[str, Src], b: int) -> _F:
        """``d``, shape (3, 1) when it is the same for every pose, else (3, b)."""
        width = 1 if all(isinstance(src[k], float) for k in self.keys[1:]) else b
        d = [np.zeros((4, width))]
        d[0][self.j] = 1.0
        tmp = [np.zeros((4, width))]
        for op in self.ops:
            op.run(d, tmp, (False,), src, np.empty(width))
        return d[0][:3]

    def run(self, vs: Bufs, spare: Bufs, points: Flags, src: Sources, w: _F) -> None:
        q = src[self.q]
        d = self.direction(src, w.shape[0])
        for n, v in enumerate(vs):
            if points[n]:
                for i in range(3):
                    if d.shape[1] == 1 and d[i, 0] == 0.0:
                        continue
                    np.multiply(q, d[i], out=w)
                    v[i] += w


def trig_keys(ops: Sequence[Op]) -> set[str]:
    """The sources whose cosine and sine the operations need."""
    out: set[str] = set()
    for op in ops:
        if isinstance(op, AxisRotation):
            out.add(op.key)
        elif isinstance(op, LinearMotion):
            out |= trig_keys(op.ops)
    return out


def _basis_vectors() -> tuple[list[_F], list[_F]]:
    """The origin (a point) and the three unit directions, as (4, 1) buffers."""
    vs = [np.zeros((4, 1)) for _ in range(4)]
    vs[0][3] = 1.0
    for i in range(3):
        vs[1 + i][i] = 1.0
    return vs, [v.copy() for v in vs]


def _as_affine(op: Op, src: Mapping[str, Src]) -> Affine:
    """The matrix and translation of a constant operation (its image of the basis)."""
    vs, spare = _basis_vectors()
    op.run(vs, spare, (True, False, False, False), src, np.empty(1))
    A = np.hstack([v[:3] for v in vs[1:]])
    return Affine(A, vs[0][:3, 0].copy())


def fold(ops: Sequence[Op], const: Mapping[str, Src]) -> list[Op]:
    """Replace constant operations by affine maps and multiply out neighbouring ones.

    An operation is constant when all its sources are in ``const`` (with the cosine and
    sine of its angles). A pure translation commutes with a :class:`Translate`, so it is
    moved across one to meet another affine map.
    """
    out: list[Op] = []
    for op in ops:
        if all(k in const for k in op.keys):
            aff = _as_affine(op, const)
            if out and isinstance(out[-1], Affine):
                out[-1] = out[-1].then(aff)
                continue
            if (
                aff.pure_translation
                and len(out) >= 2
                and isinstance(out[-1], Translate)
                and isinstance(out[-2], Affine)
            ):
                out[-2] = out[-2].then(aff)
                continue
            out.append(aff)
        elif (
            isinstance(op, Translate)
            and out
            and isinstance(out[-1], Affine)
            and out[-1].pure_translation
        ):
            out.insert(len(out) - 1, op)  # the translation stays last, to merge
        else:
            out.append(op)
    return out


# ----------------------------------------------------------------------------------------
# sources: error functions of one axis evaluated together


def _settings(f: ErrorFunction) -> tuple[Any, ...]:
    """What besides the coefficients defines the basis of ``f``."""
    vals: list[Any] = [type(f), f.n_coefficients]
    for fl in fields(f):  # type: ignore[arg-type]
        if fl.name != "coefficients":
            v = getattr(f, fl.name)
            vals.append(v.tobytes() if isinstance(v, np.ndarray) else v)
    return tuple(vals)


class FunctionGroup:
    """Error functions of one axis position with one basis and shared coefficients.

    Each row is a source: an error (its coefficients) or a linear combination of errors,
    of the nominal motion ``d q`` and of constants (see :func:`merge_motions` and
    :meth:`Program._fold_start`). A block evaluates the basis once and every row in one
    matrix product, just before the first operation that reads one of them; ``blocks``
    name triples of consecutive rows, read as one (3, B) source.
    """

    def __init__(self, q: str, first: ErrorFunction) -> None:
        self.q = q
        self.first = first
        self.rows: dict[str, _F] = {}
        self.blocks: dict[str, tuple[int, int]] = {}
        self._bufs: dict[int, tuple[_F, _F]] = {}

    @property
    def power_basis(self) -> bool:
        """Whether the basis is ``1, q, q^2 ...`` (so ``q`` itself is a row)."""
        return isinstance(self.first, PolynomialFunction) and self.first.n_coefficients > 1

    def keep(self, needed: set[str], blocks: Sequence[tuple[str, Sequence[str]]] = ()) -> None:
        """Keep the rows read, with each of ``blocks`` (name, keys) consecutive."""
        order: list[str] = []
        for name, keys in blocks:
            if all(k in self.rows and k not in order for k in keys):
                self.blocks[name] = (len(order), len(order) + len(keys))
                order.extend(keys)
        order += [k for k in self.rows if k in needed and k not in order]
        self.rows = {k: self.rows[k] for k in order}
        self.C = np.stack(list(self.rows.values())) if self.rows else np.zeros((0, 1))

    def evaluate(self, src: dict[str, Src], b: int) -> None:
        """Put every row's values at the block's positions into ``src``."""
        q = src[self.q]
        if isinstance(q, float):
            vals = np.stack(list(self.rows.values())) @ self.first.basis(np.array([q]))[0]
            for name, v in zip(self.rows, vals, strict=True):
                src[name] = float(v)
            return
        if b not in self._bufs:  # reused from block to block
            V = np.empty((self.first.n_coefficients, b))
            V[0] = 1.0
            self._bufs[b] = (V, np.empty((len(self.rows), b)))
        V, out = self._bufs[b]
        if isinstance(self.first, PolynomialFunction):
            if V.shape[0] > 1:
                V[1] = q
            for k in range(2, V.shape[0]):
                np.multiply(V[k - 1], q, out=V[k])
            np.matmul(self.C, V, out=out)
        else:
            np.matmul(self.C, self.first.basis(q).T, out=out)
        for name, row in zip(self.rows, out, strict=True):
            src[name] = row
        for name, (i, j) in self.blocks.items():
            src[name] = out[i:j]


def group_functions(
    funcs: Mapping[str, tuple[str, ErrorFunction]],
) -> tuple[list[FunctionGroup], dict[str, tuple[str, ErrorFunction]]]:
    """Split error functions into groups of one basis and the per-trial ones.

    ``funcs`` maps a name to (position key, function); functions with per-trial
    coefficients are evaluated one by one.
    """
    groups: dict[tuple[Any, ...], FunctionGroup] = {}
    single: dict[str, tuple[str, ErrorFunction]] = {}
    for name, (qk, f) in funcs.items():
        if f.coefficients.ndim != 1:
            single[name] = (qk, f)
            continue
        key = (qk, *_settings(f))
        if key not in groups:
            groups[key] = FunctionGroup(qk, f)
        groups[key].rows[name] = np.asarray(f.coefficients, dtype=np.float64)
    return list(groups.values()), single


def merge_motions(
    ops: Sequence[Op], groups: Sequence[FunctionGroup], const: Mapping[str, Src]
) -> list[Op]:
    """Sum the translations of a linear axis inside its group's matrix product.

    The component translation errors of a linear axis ``(EXK, EYK, EZK)(q)`` and its
    nominal motion ``q d`` (``d`` constant) are one translation ``t_j(q)``; when the errors
    are polynomials of one group, ``t_j`` is a row of the group (the coefficients summed,
    ``d_j`` added to that of ``q``) and the translation costs one addition per coordinate.
    """
    owner = {name: g for g in groups for name in g.rows}
    by_q = {g.q: g for g in groups if g.power_basis}
    out = list(ops)
    for i, op in enumerate(out):
        if not isinstance(op, LinearMotion) or op.q not in by_q:
            continue
        if not all(k in const for k in op.keys[1:]):
            continue
        g = by_q[op.q]
        d = op.direction(const, 1)[:, 0]
        prev = out[i - 1] if i and isinstance(out[i - 1], Translate) else None
        terms = prev.terms if isinstance(prev, Translate) else ((), (), ())
        if any(owner.get(k) is not g for t in terms for _, k in t):
            continue
        new: list[tuple[tuple[float, str], ...]] = []
        for j in range(3):
            row = np.zeros(g.first.n_coefficients)
            for sign, k in terms[j]:
                row += sign * g.rows[k]
            row[1] += d[j]
            key = f"{op.q}#t{j}:" + "".join(k for _, k in terms[j])
            g.rows[key] = row
            new.append(((1.0, key),))
        out[i] = Translate(tuple(new))
        if prev is not None:
            out[i - 1] = Translate(((), (), ()))
    return [op for op in out if not (isinstance(op, Translate) and not op.keys)]


# ----------------------------------------------------------------------------------------
# the program


class Program:
    """The lowered chain of one call, run block by block.

    Parameters
    ----------
    ops : list of Op
        The factors lowered, in the order they act on the vectors (tool to workpiece).
    start : list of sequence of 3 floats
        The vectors the chain acts on.
    points : tuple of bool
        Which of them are points (translations act on them), the others directions.
    const : dict
        The sources that are the same for every pose (floats).
    arrays : dict
        The sources given per pose (arrays (M,)).
    qcols : dict
        Source key -> column of ``q`` for the axis positions that vary.
    funcs : dict
        Error functions of a position: name -> (position key, function).
    """

    def __init__(
        self,
        ops: list[Op],
        start: Sequence[Sequence[float]],
        points: tuple[bool, ...],
        const: dict[str, Src],
        arrays: dict[str, _F],
        qcols: dict[str, int],
        funcs: dict[str, tuple[str, ErrorFunction]],
    ) -> None:
        groups, self.single = group_functions(funcs)
        for g in groups:
            if g.q in const:
                g.keep(set(g.rows))
                g.evaluate(const, 1)
        groups = [g for g in groups if g.q not in const]
        ops = merge_motions(ops, groups, const)
        self.trig = trig_keys(ops)
        for key in self.trig:
            if key in const:
                const[f"{key}#cos"], const[f"{key}#sin"] = cos_sin(const[key])
        ops = fold(ops, const)
        self.points = points
        vs = [
            np.array([[*map(float, v), 1.0 if p else 0.0]]).T
            for v, p in zip(start, points, strict=True)
        ]
        spare = [v.copy() for v in vs]
        while ops and isinstance(ops[0], Affine):  # the constant head, once
            ops.pop(0).run(vs, spare, points, const, np.empty(1))
        self.start = vs
        self.init: list[str] | None = None
        ops = self._fold_start(ops, groups)
        # rows read, triples of rows read together, and when each group is evaluated
        needed = {k for op in ops for k in op.keys} | set(self.init or ())
        triples: list[tuple[str, Sequence[str]]] = []
        for n, op in enumerate(ops):
            if isinstance(op, Translate) and op.triple is not None:
                op.block = f"#block{n}"
                triples.append((op.block, op.triple))
        for g in groups:
            g.keep(needed, [(n, k) for n, k in triples if k[0] in g.rows])
        for op in ops:
            if isinstance(op, Translate) and not any(op.block in g.blocks for g in groups):
                op.block = None
        groups = [g for g in groups if g.rows]
        owner = {k: g for g in groups for k in g.rows}
        self.before: list[tuple[list[FunctionGroup], list[str]]] = []
        done: set[int] = set()
        angles: set[str] = set()
        for step in [None, *ops]:
            keys = set(self.init or ()) if step is None else set(step.keys)
            new = [owner[k] for k in sorted(keys) if k in owner and id(owner[k]) not in done]
            new = list({id(g): g for g in new}.values())
            done |= {id(g) for g in new}
            trig = [] if step is None else sorted(trig_keys([step]) - angles - set(const))
            angles |= set(trig)
            self.before.append((new, trig))
        self.ops = ops
        self.const, self.arrays, self.qcols = const, arrays, qcols

    def _fold_start(self, ops: list[Op], groups: Sequence[FunctionGroup]) -> list[Op]:
        """Fold the first per-pose operations on the constant start into group rows.

        While the vectors are constant, a :class:`SmallRotation` by angles that are rows
        of a polynomial group is linear in those rows (``y0 + e x y0``), and so is a
        :class:`Translate` by rows of the same group: the vectors after them are rows of
        the group, and the block starts from those rows.
        """
        owner = {k: g for g in groups if isinstance(g.first, PolynomialFunction) for k in g.rows}
        g: FunctionGroup | None = None
        R = [np.zeros((3, 0)) for _ in self.start]
        taken = 0
        rotated = False
        for op in ops:
            if not isinstance(op, SmallRotation | Translate) or not op.keys:
                break
            if rotated and isinstance(op, SmallRotation):
                break
            gs = {id(owner.get(k)): owner.get(k) for k in op.keys}
            if len(gs) != 1 or None in gs.values() or (g is not None and id(g) not in gs):
                break
            if g is None:
                g = next(iter(gs.values()))
                assert g is not None
                R = [np.outer(v[:3, 0], np.eye(g.first.n_coefficients)[0]) for v in self.start]
            assert g is not None
            z = np.zeros(g.first.n_coefficients)
            for n, p in enumerate(self.points):
                if isinstance(op, SmallRotation):
                    a, b, c = (z if k is None else g.rows[k] for k in op.names)
                    x, y, zz = (float(t) for t in self.start[n][:3, 0])
                    cross = np.array([b * zz - c * y, c * x - a * zz, a * y - b * x])
                    R[n] = R[n] + op.sign * cross
                elif p:
                    for j in range(3):
                        for sign, k in op.terms[j]:
                            R[n][j] = R[n][j] + sign * g.rows[k]
            rotated = rotated or isinstance(op, SmallRotation)
            taken += 1
        if g is None or taken == 0:
            return ops
        self.init = []
        for n in range(len(self.start)):
            keys = [f"#start{n}:{i}" for i in range(3)]
            for i, k in enumerate(keys):
                g.rows[k] = R[n][i]
            self.init += keys
        return ops[taken:]

    def _sources(
        self, qa: _F, qkeys: list[tuple[str, int]], lo: int, hi: int, m: int
    ) -> dict[str, Src]:
        """The inputs of poses ``lo:hi``: constants, axis columns, arrays, fitted functions."""
        src: dict[str, Src] = dict(self.const)
        if qkeys:
            qt = np.ascontiguousarray(qa[lo:hi].T)
            for key, i in qkeys:
                src[key] = qt[i]
        for name, arr in self.arrays.items():
            src[name] = arr[lo:hi]
        for name, (qk, f) in self.single.items():
            c = f.coefficients[lo:hi] if f.coefficients.shape[0] == m else f.coefficients
            src[name] = np.einsum("...k,...k->...", f.basis(src[qk]), c)
        return src

    def run(self, qa: _F, m: int) -> _F:
        """The vectors at the ``m`` poses: array (m, n_vectors, 3)."""
        y = np.empty((m, len(self.start), 3))
        bufs: dict[int, Any] = {}  # buffers by block length, reused
        qkeys = sorted(self.qcols.items(), key=lambda kv: kv[1])
        for lo in range(0, m, BLOCK):
            hi = min(m, lo + BLOCK)
            b = hi - lo
            if b not in bufs:
                cur = [np.empty((4, b)) for _ in self.start]
                spare = [np.empty((4, b)) for _ in self.start]
                for v, s0 in zip(cur + spare, self.start + self.start, strict=True):
                    v[3] = s0[3, 0]
                trig = {k: (np.empty(b), np.empty(b)) for k in self.trig}
                bufs[b] = (cur, spare, np.empty(b), trig)
            cur, spare, w, trig_out = bufs[b]
            vs, sp = list(cur), list(spare)
            src = self._sources(qa, qkeys, lo, hi, m)
            for g in self.before[0][0]:
                g.evaluate(src, b)
            for n, v in enumerate(vs):
                if self.init is None:
                    v[:3] = self.start[n][:3]
                else:
                    for i in range(3):
                        v[i] = src[self.init[3 * n + i]]
            for op, (groups, angles) in zip(self.ops, self.before[1:], strict=True):
                for g in groups:  # the rows and angles this operation reads first
                    g.evaluate(src, b)
                for key in angles:
                    src[f"{key}#cos"], src[f"{key}#sin"] = cos_sin(src[key], trig_out[key])
                op.run(vs, sp, self.points, src, w)
            for n, v in enumerate(vs):
                y[lo:hi, n, :] = v[:3].T
        return y
