"""The equation of motion of a machine written out with SymPy (Aguado et al. 2016, §4.1).

:func:`equation_of_motion` builds, with SymPy 4 x 4 homogeneous matrices, the position of
the tool point in the workpiece frame as a function of the axis positions, the named
geometric errors, and the tool and workpiece offsets (the small-angle model of
:class:`~mtmc.kinematics.machine.Machine`; its docstring gives the chain). The result
prints as text or LaTeX and compiles to a batched NumPy function.

This is a second, independent construction of the model: the numerical path of
:class:`Machine` applies element-wise operations factor by factor, this one multiplies
symbolic matrices; the tests check that both agree.

Examples
--------
>>> from mtmc.kinematics import Machine
>>> eq = equation_of_motion(Machine.from_topology("XFYZ"), errors=["EXX", "EC0Y"])
>>> print(eq.text())
x_W = -EC0Y*y + EXX + t_x - w_x + x
y_W = t_y - w_y + y
z_W = t_z - w_z + z
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.kinematics.machine import Machine
from mtmc.kinematics.topology import AXIS_DIRECTION, is_linear

if TYPE_CHECKING:  # SymPy is imported where it is used: it costs ~0.3 s at import
    import sympy as sp

__all__ = [
    "EquationOfMotion",
    "equation_of_motion",
    "small_angle_matrix",
    "axis_rotation_matrix",
]

_DIRS = "XYZ"
_ROTS = "ABC"


def _T(v: Sequence[Any]) -> sp.Matrix:
    import sympy as sp

    M = sp.eye(4)
    for i in range(3):
        M[i, 3] = v[i]
    return M


def small_angle_matrix(a: Any, b: Any, c: Any, transpose: bool = False) -> sp.Matrix:
    """The 4 x 4 homogeneous form of the first-order rotation ``I + [e]x``, symbolic.

    The same matrix as :func:`mtmc.geometry.small_angle_rotation` (the numeric chain's
    :func:`mtmc.geometry.small_angle_rotate`), written in SymPy so that the symbolic chain
    stays a construction independent of the numeric one; a test compares the two.

    Parameters
    ----------
    a, b, c : sympy expression or number
        Small rotations about x, y and z, rad.
    transpose : bool
        Give ``I - [e]x`` (the passive form) instead.

    Returns
    -------
    sympy.Matrix, shape (4, 4)
        ``[[1, -c, b, 0], [c, 1, -a, 0], [-b, a, 1, 0], [0, 0, 0, 1]]`` (or its transpose).
    """
    import sympy as sp

    M = sp.eye(4)
    S = sp.Matrix([[1, -c, b], [c, 1, -a], [-b, a, 1]])
    if transpose:
        S = S.T
    M[:3, :3] = S
    return M


def _first_order_product(mats: Sequence[sp.Matrix], errors: tuple[sp.Symbol, ...]) -> sp.Matrix:
    """``(M_1 M_2 … M_n (0, 0, 0, 1))[:3]`` to the first order in the symbols ``errors``.

    Every factor is affine in the errors, ``M = M⁰ + Σ_j e_j Mʲ``, and so is the point
    carried through the chain from the right, ``v = v⁰ + Σ_k e_k vᵏ``; a factor maps it to
    ``M⁰ v⁰ + Σ_k e_k (M⁰ vᵏ + Mᵏ v⁰)``, dropping the products ``e_j e_k``. No expression
    holds an error symbol until the end: the first-order equation of a five-axis machine
    with its 53 errors takes 1.4-1.9 s, where expanding the whole product after each
    factor and dropping its terms of degree two took 8 s (the same text either way).
    """
    import sympy as sp

    zero = dict.fromkeys(errors, sp.Integer(0))
    symbols = set(errors)
    v0 = sp.Matrix([0, 0, 0, 1])
    vk: dict[sp.Symbol, sp.Matrix] = {}
    for M in reversed(mats):
        present = [e for e in errors if e in M.free_symbols]  # in the order of errors
        M0 = M.xreplace(zero)
        parts = {e: M.diff(e) for e in present}
        if any(d.free_symbols & symbols for d in parts.values()):
            raise AssertionError("a factor of the chain is not affine in the errors")
        new = {e: M0 * w for e, w in vk.items()}
        for e, Mk in parts.items():
            term = Mk * v0
            new[e] = term if e not in new else new[e] + term
        vk = {e: w.applyfunc(sp.expand) for e, w in new.items()}
        v0 = (M0 * v0).applyfunc(sp.expand)
    pos = [v0[i] + sum((e * vk[e][i] for e in errors if e in vk), sp.Integer(0)) for i in range(3)]
    return sp.Matrix([sp.collect(sp.expand(p), errors) for p in pos])


def axis_rotation_matrix(axis: int, q: Any) -> sp.Matrix:
    """The 4 x 4 homogeneous active rotation about coordinate axis ``axis`` by ``q``, symbolic.

    The same matrix as :func:`mtmc.geometry.rotation_x` (``y``, ``z``); a test compares them.

    Parameters
    ----------
    axis : int
        0, 1 or 2 for x, y or z.
    q : sympy expression or number
        The angle, rad.

    Returns
    -------
    sympy.Matrix, shape (4, 4)
    """
    import sympy as sp

    c, s = sp.cos(q), sp.sin(q)
    i, k = (axis + 1) % 3, (axis + 2) % 3
    M = sp.eye(4)
    M[i, i] = c
    M[k, k] = c
    M[i, k] = -s
    M[k, i] = s
    return M


@dataclass(frozen=True)
class EquationOfMotion:
    """The tool position in the workpiece frame, written out.

    Parameters
    ----------
    machine : Machine
        The machine it was built from.
    position : sympy.Matrix, shape (3, 1)
        ``(x_W, y_W, z_W)`` in mm.
    axis_symbols : tuple of sympy.Symbol
        One per axis, in the order of ``machine.axes`` (lower-case letters).
    error_symbols : tuple of sympy.Symbol
        The error symbols kept (ISO names).
    offset_symbols : tuple of sympy.Symbol
        ``t_x, t_y, t_z`` (tool point) and ``w_x, w_y, w_z`` (workpiece origin).
    first_order : bool
        Whether products of errors were dropped.
    """

    machine: Machine
    position: sp.Matrix
    axis_symbols: tuple[sp.Symbol, ...]
    error_symbols: tuple[sp.Symbol, ...]
    offset_symbols: tuple[sp.Symbol, ...]
    first_order: bool

    def text(self) -> str:
        """The three coordinate equations as plain text, one per line."""
        import sympy as sp

        return "\n".join(f"{n}_W = {sp.sstr(e)}" for n, e in zip("xyz", self.position, strict=True))

    def latex(self) -> str:
        """The three equations as a LaTeX ``aligned`` block."""
        import sympy as sp

        rows = [f"{n}_W &= {sp.latex(e)}" for n, e in zip("xyz", self.position, strict=True)]
        return "\\begin{aligned}\n" + " \\\\\n".join(rows) + "\n\\end{aligned}"

    def compile(self) -> Callable[..., NDArray[np.float64]]:
        """Compile to a batched NumPy function.

        Returns
        -------
        callable
            ``f(q, errors=None, tool=None, workpiece=None) -> (M, 3)``: ``q`` of shape
            ``(M, n_axes)`` in the order of ``machine.axes``; ``errors`` maps names of
            :attr:`error_symbols` to numbers or arrays ``(M,)`` (missing: zero; error
            functions are not accepted here, evaluate them first); ``tool`` and
            ``workpiece`` default to the machine's offsets.
        """
        import sympy as sp

        args = (*self.axis_symbols, *self.error_symbols, *self.offset_symbols)
        fn = sp.lambdify(args, list(self.position), modules="numpy", cse=True)
        names = [str(s) for s in self.error_symbols]
        machine = self.machine

        def evaluate(
            q: npt.ArrayLike,
            errors: Mapping[str, npt.ArrayLike] | None = None,
            tool: npt.ArrayLike | None = None,
            workpiece: npt.ArrayLike | None = None,
        ) -> NDArray[np.float64]:
            qa = machine.positions(q)
            vals = {machine.error_term(k).name: v for k, v in (errors or {}).items()}
            t = machine.tool if tool is None else np.asarray(tool, dtype=np.float64)
            w = machine.workpiece if workpiece is None else np.asarray(workpiece, dtype=float)
            ev = [np.asarray(vals.get(n, 0.0), dtype=np.float64) for n in names]
            out = fn(*qa.T, *ev, *t, *w)
            m = np.broadcast_shapes(qa.shape[:1], *(np.shape(o) for o in out))
            return np.stack([np.broadcast_to(o, m) for o in out], axis=1).astype(np.float64)

        return evaluate


def equation_of_motion(
    machine: Machine,
    *,
    errors: Sequence[str] | None = None,
    first_order: bool = False,
) -> EquationOfMotion:
    """Write out the equation of motion of a machine (Aguado et al. 2016, §4.1).

    Parameters
    ----------
    machine : Machine
        The machine; its pivots enter as numbers, its tool and workpiece offsets as the
        symbols ``t_x ... w_z``.
    errors : sequence of str, optional
        Error names to keep as symbols (default: ``machine.error_names``); the others
        are zero.
    first_order : bool
        Keep only the terms of order 0 and 1 in the errors (the linearised model:
        nominal position plus the Jacobian times the errors), truncating after each
        factor. The full small-angle product (``False``) is compact for three-axis
        machines but runs to about a megabyte of text for a five-axis machine with
        every error; use ``errors=`` to keep a subset there.

    Returns
    -------
    EquationOfMotion

    Raises
    ------
    InputError
        On an unknown error name.

    Notes
    -----
    The small-angle matrices are ``I + [e]x`` (Aguado et al. 2016, eq. 12 prints their transpose,
    the passive form; see ``docs/conventions.md``). Aguado et al. 2016, eq. (3) reads
    ``T_t = R(z)(R(y)(R(x) T_p + X) + Y) + Z`` for a ZYXF machine; here the same
    nesting appears with our sign of the part-side motion (``+q``, since each part-side
    axis enters as the inverse of its physical motion).
    """
    import sympy as sp

    names = (
        machine.error_names if errors is None else tuple(machine.error_term(n).name for n in errors)
    )
    keep = {n: sp.Symbol(n, real=True) for n in names}

    def E(n: str) -> Any:
        return keep.get(n, sp.Integer(0))

    axsym = {ax: sp.Symbol(ax.lower(), real=True) for ax in machine.axes}
    tsym = sp.symbols("t_x t_y t_z", real=True)
    wsym = sp.symbols("w_x w_y w_z", real=True)
    mats: list[sp.Matrix] = []
    mats.append(small_angle_matrix(E("EAP"), E("EBP"), E("ECP"), transpose=True))
    mats.append(_T([-(wsym[i] + E(f"E{_DIRS[i]}P")) for i in range(3)]))
    for ax in machine.topology.chain:
        d = AXIS_DIRECTION[ax]
        o = machine.pivots.get(ax, np.zeros(3))
        osym = [sp.Float(float(v)) if v else sp.Integer(0) for v in o]
        comp_d = [E(f"E{c}{ax}") for c in _DIRS]
        comp_r = [E(f"E{c}{ax}") for c in _ROTS]
        mats.append(_T(osym))
        if is_linear(ax):
            s = [E(f"E{_ROTS[j]}0{ax}") if j != d else 0 for j in range(3)]
            e = sp.zeros(4, 1)
            e[d] = 1
            direction = small_angle_matrix(s[0], s[1], s[2]) * e
            mats.append(_T([axsym[ax] * direction[i] for i in range(3)]))
            mats.append(_T(comp_d))
            mats.append(small_angle_matrix(comp_r[0], comp_r[1], comp_r[2]))
        else:
            ld = [E(f"E{_DIRS[j]}0{ax}") if j != d else 0 for j in range(3)]
            lr = [E(f"E{_ROTS[j]}0{ax}") if j != d else 0 for j in range(3)]
            mats.append(_T(ld))
            mats.append(small_angle_matrix(lr[0], lr[1], lr[2]))
            mats.append(_T(comp_d))
            mats.append(small_angle_matrix(comp_r[0], comp_r[1], comp_r[2]))
            mats.append(axis_rotation_matrix(d, axsym[ax]))
            mats.append(small_angle_matrix(lr[0], lr[1], lr[2], transpose=True))
            mats.append(_T([-v for v in ld]))
        mats.append(_T([-v for v in osym]))
    mats.append(_T([tsym[i] + E(f"E{_DIRS[i]}T") for i in range(3)]))
    used = tuple(keep.values())
    if first_order and used:
        pos = _first_order_product(mats, used)
    else:
        v = sp.Matrix([0, 0, 0, 1])
        for M in reversed(mats):
            v = M * v
        pos = sp.Matrix([v[i] for i in range(3)])
    return EquationOfMotion(
        machine=machine,
        position=pos,
        axis_symbols=tuple(axsym[a] for a in machine.axes),
        error_symbols=used,
        offset_symbols=(*tsym, *wsym),
        first_order=first_order,
    )
