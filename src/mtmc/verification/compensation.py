"""Compensation tables: identified error functions sampled on a grid, written and read back.

A :class:`CompensationTable` holds, for a set of ISO 230-1 errors, the values a control
needs: a constant for each squareness or location error ("position errors" in the ISG
kernel's words: ``C0Y``, ``X0C``), and for each component error a table of values at the
positions of its axis (a grid the user chooses). :func:`compensation_table` samples them
from error functions (``{"EXX": LegendreSeries(...), "EC0Y": 1e-5}``) or from an
:class:`~mtmc.kinematics.ErrorModel` with its coefficient vector.

Three file formats, each with a writer and a reader:

- **ISG CSV** (ISG kernel / Beckhoff TF5280 volumetric compensation): ``//`` comments,
  blocks separated by a ``#`` line, each a header line of names then whitespace-separated
  rows; a block of position errors has one row, a block of component errors has the axis
  (the argument) as its first column. :func:`dumps_isg_csv`, :func:`loads_isg_csv`.
- **Etalon exchange format**, "Vendor" variant (INI-like): one ``[NAME]`` block per error,
  ``VALUE = v`` for a constant, ``Gridpoints = { position value ... }`` for a table.
  :func:`dumps_etalon`, :func:`loads_etalon`.
- **plain CSV**: one row per value, ``error,axis,position,position_unit,value,value_unit``.
  :func:`dumps_plain_csv`, :func:`loads_plain_csv`.

Units in the files: displacements in mm, rotations in rad, positions of linear axes in mm
and of rotary axes in degrees (the ISG convention); inside the code rotary positions are
rad. Values are written with Python's shortest round-trip representation, so reading a
file back gives the same floats.

**Sign convention.** Every file states in its header whether its values are *errors* or
*corrections*. An error is the ISO 230-1 error motion (the actual minus the nominal
position or orientation of the tool relative to the workpiece, as in
:mod:`mtmc.kinematics`); a correction is its negative, the value a control adds to the
commanded position. The ISG kernel reads errors and compensates them itself (its
``negate`` parameter flips the sign), so ``sign="error"`` is the default. A file without
a sign line (one written elsewhere) is read as errors; a sign line that says anything but
``sign = error`` or ``sign = correction`` is refused.

**Whole files only.** A wrong table moves a machine, so a reader refuses a file that is
not whole: an empty or comment-only file, a block not closed, and, in a file written by
mtmc, a missing or different last line ``end of table: N values`` (a comment that counts
the constants and the values of the curves; a file cut anywhere, even inside a number,
lacks it or disagrees with it). A file without that line (written elsewhere) must give
the component errors of each axis at the same positions.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.document import read_text
from mtmc.errors import InputError, ParseError
from mtmc.io import write_text_atomic
from mtmc.kinematics.error_terms import ErrorTerm, parse_error_name
from mtmc.kinematics.functions import ErrorFunction, ErrorTable
from mtmc.kinematics.parameters import ErrorModel
from mtmc.kinematics.topology import AXIS_DIRECTION, is_rotary

__all__ = [
    "FORMATS",
    "SIGNS",
    "CompensationTable",
    "ErrorCurve",
    "compensation_table",
    "measured_grid",
    "dump_compensation",
    "dumps_etalon",
    "dumps_isg_csv",
    "dumps_plain_csv",
    "load_compensation",
    "loads_etalon",
    "loads_isg_csv",
    "loads_plain_csv",
]

#: The file formats: ISG CSV, Etalon exchange ("Vendor"), plain CSV.
FORMATS = ("isg", "etalon", "csv")
#: What the values of a table are: ISO 230-1 errors, or corrections (their negatives).
SIGNS = ("error", "correction")
_SIGN_LINE = re.compile(r"\bsign\s*[=:]\s*([^\s:;,.]*)", re.IGNORECASE)
_END = "end of table"
_END_LINE = re.compile(r"end of table: ([0-9]+) values")
_DEG = 180.0 / math.pi


@dataclass(frozen=True, eq=False)
class ErrorCurve:
    """One component error tabulated along its axis.

    Parameters
    ----------
    name : str
        The ISO 230-1 name (``EXX``, ``ECY``, ...).
    positions : ndarray, shape (n,)
        Strictly increasing positions of the axis (mm, rad for a rotary axis).
    values : ndarray, shape (n,)
        The values there (mm or rad), errors or corrections as the table says.
    """

    name: str
    positions: NDArray[np.float64]
    values: NDArray[np.float64]

    def __post_init__(self) -> None:
        term = parse_error_name(self.name)
        if term.kind != "component":
            raise InputError(
                f"{term.name} is a {term.kind} error: a table along an axis is for component "
                "errors",
                field=self.name,
            )
        p = np.array(self.positions, dtype=np.float64)
        v = np.array(self.values, dtype=np.float64)
        if p.ndim != 1 or p.shape != v.shape or p.size == 0:
            raise InputError(
                f"{term.name}: expected positions and values of the same shape (n,), got "
                f"{p.shape} and {v.shape}",
                field=self.name,
            )
        if not (np.all(np.isfinite(p)) and np.all(np.isfinite(v))):
            raise InputError(f"{term.name}: expected finite positions and values", field=self.name)
        if np.any(np.diff(p) <= 0):
            raise InputError(
                f"{term.name}: expected strictly increasing positions", field=self.name
            )
        p.setflags(write=False)
        v.setflags(write=False)
        object.__setattr__(self, "name", term.name)
        object.__setattr__(self, "positions", p)
        object.__setattr__(self, "values", v)

    @property
    def axis(self) -> str:
        """The axis letter the error is a function of."""
        return parse_error_name(self.name).axis

    def __eq__(self, other: object) -> bool:
        """Same name, identical positions and values."""
        if not isinstance(other, ErrorCurve):
            return NotImplemented
        return (
            self.name == other.name
            and np.array_equal(self.positions, other.positions)
            and np.array_equal(self.values, other.values)
        )

    __hash__ = None  # type: ignore[assignment]


@dataclass(frozen=True, eq=False)
class CompensationTable:
    """Error values for a control: constants and tables along the axes.

    Parameters
    ----------
    constants : mapping of str to float
        Squareness, location (and, for the plain CSV only, tool and part) errors by ISO
        name, mm or rad.
    curves : tuple of ErrorCurve
        Component errors tabulated along their axes.
    sign : {"error", "correction"}
        What the values are (see the module's sign convention).

    Raises
    ------
    InputError
        On an unknown sign, a name given twice, a component error among the constants.
    """

    constants: Mapping[str, float]
    curves: tuple[ErrorCurve, ...] = ()
    sign: str = "error"

    def __post_init__(self) -> None:
        if self.sign not in SIGNS:
            raise InputError(
                f"expected sign 'error' or 'correction', got {self.sign!r}", field="sign"
            )
        consts: dict[str, float] = {}
        for raw, v in self.constants.items():
            term = parse_error_name(raw)
            if term.kind == "component":
                raise InputError(
                    f"{term.name} is a component error: give it as an ErrorCurve along axis "
                    f"{term.axis}",
                    field=raw,
                )
            if term.name in consts:
                raise InputError(f"error {term.name} given twice", field=raw)
            f = float(v)
            if not math.isfinite(f):
                raise InputError(f"{term.name}: expected a finite value, got {v!r}", field=raw)
            consts[term.name] = f
        curves = tuple(self.curves)
        names = [c.name for c in curves]
        for n in names:
            if names.count(n) > 1 or n in consts:
                raise InputError(f"error {n} given twice", field=n)
        object.__setattr__(self, "constants", consts)
        object.__setattr__(self, "curves", curves)

    def curve(self, name: str) -> ErrorCurve:
        """The curve of a component error, by name (``EXX`` or ``XX``).

        Raises
        ------
        KeyError
            If the table has no such curve.
        """
        n = parse_error_name(name).name
        for c in self.curves:
            if c.name == n:
                return c
        raise KeyError(n)

    def with_sign(self, sign: str) -> CompensationTable:
        """The same table with values as errors or as corrections (negated if it changes)."""
        if sign not in SIGNS:
            raise InputError(f"expected sign 'error' or 'correction', got {sign!r}", field="sign")
        if sign == self.sign:
            return self
        return CompensationTable(
            {k: -v for k, v in self.constants.items()},
            tuple(ErrorCurve(c.name, c.positions, -c.values) for c in self.curves),
            sign,
        )

    def errors(self) -> dict[str, ErrorTable | float]:
        """The errors as functions for :meth:`mtmc.kinematics.Machine.tool_position`.

        Returns
        -------
        dict
            Name -> :class:`~mtmc.kinematics.ErrorTable` (linear interpolation between the
            grid positions; a single position gives a constant) or a constant; errors, not
            corrections, whatever the table's sign.
        """
        t = self.with_sign("error")
        out: dict[str, ErrorTable | float] = dict(t.constants)
        for c in t.curves:
            out[c.name] = (
                ErrorTable(c.positions, c.values) if c.positions.size > 1 else float(c.values[0])
            )
        return out

    def __eq__(self, other: object) -> bool:
        """Same sign, constants and curves (exact values)."""
        if not isinstance(other, CompensationTable):
            return NotImplemented
        return (
            self.sign == other.sign
            and self.constants == other.constants
            and sorted(self.curves, key=lambda c: c.name)
            == sorted(other.curves, key=lambda c: c.name)
        )

    __hash__ = None  # type: ignore[assignment]


ErrorSource = ErrorFunction | float | Callable[[NDArray[np.float64]], Any]


def measured_grid(model: ErrorModel, q: npt.ArrayLike) -> dict[str, NDArray[np.float64]]:
    """The grid a compensation table of a verification is tabulated on: the measured positions.

    For each axis that carries an identified error of ``model``, the distinct commanded
    positions of that axis in the verification ``q`` (sorted); an axis without an error of
    the model gets no grid.

    Parameters
    ----------
    model : ErrorModel
        The identified model.
    q : array_like, shape (N, n_axes)
        The commanded axis positions of the verification (mm, rad).

    Examples
    --------
    >>> from mtmc.kinematics import ErrorModel, LegendreSeries, Machine
    >>> exx = LegendreSeries([0.0, 0.0], 0.0, 100.0)
    >>> m = ErrorModel(Machine.from_topology("XFYZ"), {"EXX": exx})
    >>> measured_grid(m, [[0.0, 0.0, 0.0], [50.0, 0.0, 0.0], [50.0, 20.0, 0.0]])
    {'X': array([ 0., 50.])}
    """
    qq = np.asarray(q, dtype=np.float64)
    axes = model.machine.axes
    used = {model.machine.error_term(n).axis for n in model.error_names}
    return {ax: np.unique(qq[:, i]) for i, ax in enumerate(axes) if ax in used}


def compensation_table(
    errors: Mapping[str, ErrorSource] | ErrorModel,
    grid: Mapping[str, npt.ArrayLike],
    *,
    theta: npt.ArrayLike | None = None,
    sign: str = "error",
) -> CompensationTable:
    """Sample error functions on a grid into a compensation table.

    Parameters
    ----------
    errors : mapping or ErrorModel
        ISO 230-1 name -> error function (:class:`~mtmc.kinematics.ErrorFunction`, or any
        callable taking positions ``(n,)`` and returning values ``(n,)``) or a number.
        Component errors (``EXX``, ``ECY``) are sampled at the grid of their axis (a
        number gives a constant curve); squareness and location errors must be numbers.
        Or an :class:`~mtmc.kinematics.ErrorModel` with its coefficients ``theta``.
    grid : mapping of str to array_like
        Axis letter -> increasing positions (mm, rad for a rotary axis) at which the
        component errors of that axis are tabulated.
    theta : array_like, shape (P,), optional
        The coefficient vector of an ErrorModel (``model.parameter_names`` order).
    sign : {"error", "correction"}
        Write the errors themselves, or their negatives.

    Returns
    -------
    CompensationTable

    Raises
    ------
    InputError
        On an unknown error name, a component error whose axis has no grid, a function
        given for a squareness or location error, a grid that is not increasing, values
        of the wrong shape, or an ErrorModel without ``theta``.

    Examples
    --------
    >>> from mtmc.kinematics import LegendreSeries
    >>> t = compensation_table({"EXX": LegendreSeries([0.0, 0.01], low=0.0, high=100.0),
    ...                         "EC0Y": 2e-5}, {"X": [0.0, 50.0, 100.0]})
    >>> t.curve("EXX").values
    array([-0.01,  0.  ,  0.01])
    >>> t.with_sign("correction").constants
    {'EC0Y': -2e-05}
    """
    if isinstance(errors, ErrorModel):
        if theta is None:
            raise InputError("an ErrorModel needs its coefficient vector theta", field="theta")
        th = np.asarray(theta, dtype=np.float64)
        if th.ndim != 1:
            raise InputError(f"expected theta of shape (P,), got {th.shape}", field="theta")
        src: Mapping[str, Any] = errors.errors(th)
    else:
        if theta is not None:
            raise InputError("theta is for an ErrorModel", field="theta")
        src = errors
    grids: dict[str, NDArray[np.float64]] = {}
    for ax, g in grid.items():
        arr = np.atleast_1d(np.asarray(g, dtype=np.float64))
        if (
            arr.ndim != 1
            or arr.size == 0
            or np.any(np.diff(arr) <= 0)
            or not np.all(np.isfinite(arr))
        ):
            raise InputError("expected finite, strictly increasing positions", field=f"grid.{ax}")
        grids[str(ax).upper()] = arr
    consts: dict[str, float] = {}
    curves: list[ErrorCurve] = []
    for raw, f in src.items():
        term: ErrorTerm = parse_error_name(raw)
        if term.kind != "component":
            if callable(f):
                raise InputError(
                    f"{term.name} is a {term.kind} error: expected a number, not a function",
                    field=raw,
                )
            consts[term.name] = float(np.asarray(f, dtype=np.float64))
            continue
        if term.axis not in grids:
            raise InputError(
                f"{term.name} is a function of axis {term.axis}: give a grid for {term.axis}",
                field=raw,
            )
        q = grids[term.axis]
        vals = np.asarray(f(q) if callable(f) else np.full(q.shape, float(f)), dtype=np.float64)
        if vals.shape != q.shape:
            raise InputError(
                f"{term.name}: expected {q.size} values from the function, got shape {vals.shape}",
                field=raw,
            )
        curves.append(ErrorCurve(term.name, q, vals))
    table = CompensationTable(consts, tuple(curves), "error")
    return table.with_sign(sign)


# ---------------------------------------------------------------------------------------
# Writers


def _num(v: float) -> str:
    return repr(float(v))


def _pos_out(axis: str, q: NDArray[np.float64]) -> NDArray[np.float64]:
    return q * _DEG if is_rotary(axis) else q


def _pos_in(axis: str, q: NDArray[np.float64]) -> NDArray[np.float64]:
    return q / _DEG if is_rotary(axis) else q


def _isg_name(name: str) -> str:
    """ISG and Etalon write position errors without the leading E (``C0Y``), components with."""
    term = parse_error_name(name)
    return term.name[1:] if term.kind in ("squareness", "location") else term.name


def _check_exportable(table: CompensationTable, fmt: str) -> None:
    for n in table.constants:
        kind = parse_error_name(n).kind
        if kind in ("tool", "part"):
            raise InputError(
                f"{n} is a {kind} error, which the {fmt} format has no name for: use the "
                "plain CSV format",
                field=n,
            )


def _header(table: CompensationTable, prefix: str, fmt: str) -> list[str]:
    what = (
        "ERRORS (ISO 230-1: actual minus nominal position/orientation of the tool "
        "relative to the workpiece); a control compensates by subtracting them"
        if table.sign == "error"
        else "CORRECTIONS (the negatives of the ISO 230-1 errors); a control adds them "
        "to the commanded position"
    )
    return [
        f"{prefix} mtmc compensation table ({fmt})",
        f"{prefix} sign = {table.sign}: the values are {what}",
        f"{prefix} units: displacements mm, rotations rad; positions of linear axes mm, of "
        "rotary axes deg",
    ]


def _end_line(table: CompensationTable) -> str:
    """The last line of a written table (after its comment marker): the count of values."""
    n = len(table.constants) + sum(c.values.size for c in table.curves)
    return f"{_END}: {n} values"


def _columns(rows: list[list[str]]) -> list[str]:
    widths = [max(len(r[j]) for r in rows) for j in range(len(rows[0]))]
    return ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip() for r in rows]


def dumps_isg_csv(table: CompensationTable) -> str:
    """The table in the ISG CSV format.

    Position (squareness, location) errors form the first block, one header line of
    names without the leading ``E`` (``C0Y Y0A``) and one row of values; each group of
    component errors sharing an axis and a grid forms a further block after a ``#``
    line, with the axis letter as its first (argument) column. Comments start with
    ``//``; the header comments state the sign and the units.

    Parameters
    ----------
    table : CompensationTable

    Returns
    -------
    str

    Raises
    ------
    InputError
        If the table holds tool or part errors (no ISG names).
    """
    _check_exportable(table, "ISG CSV")
    out = _header(table, "//", "ISG CSV format")
    blocks: list[list[str]] = []
    if table.constants:
        names = list(table.constants)
        blocks.append(
            [
                "// position errors",
                *_columns(
                    [[_isg_name(n) for n in names], [_num(table.constants[n]) for n in names]]
                ),
            ]
        )
    for axis, group in _groups(table.curves):
        q = _pos_out(axis, group[0].positions)
        rows = [[axis, *(c.name for c in group)]]
        for i in range(q.size):
            rows.append([_num(q[i]), *(_num(c.values[i]) for c in group)])
        blocks.append([f"// component errors of the {axis} axis", *_columns(rows)])
    for i, b in enumerate(blocks):
        if i:
            out.append("#")
        out += b
    out.append(f"// {_end_line(table)}")
    return "\n".join(out) + "\n"


def _groups(curves: tuple[ErrorCurve, ...]) -> list[tuple[str, list[ErrorCurve]]]:
    """Curves grouped by axis and identical grid, in order of first appearance."""
    groups: list[tuple[str, list[ErrorCurve]]] = []
    for c in curves:
        for axis, g in groups:
            if axis == c.axis and np.array_equal(g[0].positions, c.positions):
                g.append(c)
                break
        else:
            groups.append((c.axis, [c]))
    return groups


def dumps_etalon(table: CompensationTable) -> str:
    """The table in the Etalon exchange format ("Vendor" variant).

    One block per error: ``[NAME]`` (position errors without the leading ``E``), then
    ``VALUE = v`` for a constant or ``Gridpoints = {`` with one ``position value`` line
    per grid point and a closing ``}``. Comments start with ``//``.

    Parameters
    ----------
    table : CompensationTable

    Returns
    -------
    str

    Raises
    ------
    InputError
        If the table holds tool or part errors.
    """
    _check_exportable(table, "Etalon exchange")
    out = _header(table, "//", "Etalon exchange format, Vendor variant")
    for n, v in table.constants.items():
        out += [f"[{_isg_name(n)}]", f"VALUE = {_num(v)}"]
    for c in table.curves:
        q = _pos_out(c.axis, c.positions)
        out += [f"[{c.name}]", "Gridpoints = {"]
        out += [f"{_num(q[i])} {_num(c.values[i])}" for i in range(q.size)]
        out.append("}")
    out.append(f"// {_end_line(table)}")
    return "\n".join(out) + "\n"


_CSV_HEADER = "error,axis,position,position_unit,value,value_unit"


def dumps_plain_csv(table: CompensationTable) -> str:
    """The table as a plain CSV: one row per value.

    Columns ``error,axis,position,position_unit,value,value_unit``: a constant has empty
    ``axis``, ``position`` and ``position_unit``; a component error has one row per grid
    position (``mm``, or ``deg`` for a rotary axis). ``value_unit`` is ``mm`` or ``rad``.
    Comment lines start with ``#`` and state the sign.

    Parameters
    ----------
    table : CompensationTable

    Returns
    -------
    str
    """
    out = _header(table, "#", "plain CSV")
    out.append(_CSV_HEADER)
    for n, v in table.constants.items():
        unit = "rad" if parse_error_name(n).angular else "mm"
        out.append(f"{n},,,,{_num(v)},{unit}")
    for c in table.curves:
        unit = "rad" if parse_error_name(c.name).angular else "mm"
        punit = "deg" if is_rotary(c.axis) else "mm"
        q = _pos_out(c.axis, c.positions)
        out += [
            f"{c.name},{c.axis},{_num(q[i])},{punit},{_num(c.values[i])},{unit}"
            for i in range(q.size)
        ]
    out.append(f"# {_end_line(table)}")
    return "\n".join(out) + "\n"


_WRITERS = {"isg": dumps_isg_csv, "etalon": dumps_etalon, "csv": dumps_plain_csv}


def dump_compensation(table: CompensationTable, path: str | Path, fmt: str) -> Path:
    """Write a table in one of :data:`FORMATS`, atomically (:mod:`mtmc.io`).

    Parameters
    ----------
    table : CompensationTable
    path : path-like
        The file (its folder must exist).
    fmt : {"isg", "etalon", "csv"}

    Returns
    -------
    pathlib.Path

    Raises
    ------
    InputError
        On an unknown format, or a table the format cannot hold.
    """
    if fmt not in _WRITERS:
        raise InputError(
            f"expected a format among {', '.join(FORMATS)}, got {fmt!r}", field="format"
        )
    return write_text_atomic(path, _WRITERS[fmt](table))


# ---------------------------------------------------------------------------------------
# Readers


def _strip(line: str, marker: str) -> str:
    return line.split(marker, 1)[0].strip()


def _sign_of(lines: list[str], marker: str, file: str) -> str:
    """The sign of the ``sign = ...`` comment lines ("error" without one)."""
    sign: str | None = None
    for n, line in enumerate(lines, start=1):
        s = line.strip()
        if s.startswith(marker):
            m = _SIGN_LINE.search(s)
            if m is None:
                continue
            word = m.group(1).lower()
            if word not in SIGNS:
                raise ParseError(
                    f"expected 'sign = error' or 'sign = correction', got 'sign = {m.group(1)}'",
                    file=file, line=n, field="sign",
                )  # fmt: skip
            if sign is not None and word != sign:
                raise ParseError(
                    f"a second sign line says {word}, the first {sign}",
                    file=file, line=n, field="sign",
                )  # fmt: skip
            sign = word
    return sign or "error"


def _check_whole(
    lines: list[str],
    marker: str,
    file: str,
    consts: Mapping[str, object],
    curves: list[_Curve],
) -> None:
    """Refuse a text that is not a whole table (see the module notes)."""
    last = 0  # the last line that is not blank
    ends: list[tuple[int, str]] = []
    for n, raw in enumerate(lines, start=1):
        s = raw.strip()
        if not s:
            continue
        last = n
        body = s[len(marker) :].strip()
        if s.startswith(marker) and body.startswith(_END):
            ends.append((n, body))
    count = len(consts) + sum(len(v) for _, _, v, _ in curves)
    if not count:
        raise ParseError(
            "no table: the file is empty, holds only comments or no values",
            file=file, line=max(last, 1),
        )  # fmt: skip
    if ends:
        n, body = ends[-1]
        m = _END_LINE.fullmatch(body)
        if len(ends) > 1 or n != last or m is None:
            raise ParseError(
                f"expected one last line '{marker} {_END}: N values', got {body!r} "
                f"{'before other lines' if n != last else ''}".rstrip()
                + ": the file is not whole",
                file=file, line=n,
            )  # fmt: skip
        if int(m.group(1)) != count:
            raise ParseError(
                f"the last line declares {m.group(1)} values, the file holds {count}: "
                "the file is not whole",
                file=file, line=n,
            )  # fmt: skip
        return
    first = next(s.strip() for s in lines if s.strip())
    if first.startswith(f"{marker} mtmc compensation table"):
        raise ParseError(
            f"no last line '{marker} {_END}: N values': the file was cut short",
            file=file, line=last,
        )  # fmt: skip
    grids: dict[str, tuple[str, list[float], int]] = {}
    for name, q, _, line in curves:
        try:
            axis = parse_error_name(name).axis
        except InputError:
            continue  # named by the table's own checks
        if axis in grids and grids[axis][1] != q:
            other, q0, _ = grids[axis]
            raise ParseError(
                f"{name} has {len(q)} positions of axis {axis}, {other} {len(q0)} or others: "
                "every component error of an axis needs the same positions (is the file whole?)",
                file=file, line=line, field=name,
            )  # fmt: skip
        grids.setdefault(axis, (name, q, line))


def _float(text: str, file: str, line: int, fld: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise ParseError(
            f"expected a number, got {text!r}", file=file, line=line, field=fld
        ) from None
    if not math.isfinite(v):
        raise ParseError(f"expected a finite number, got {text!r}", file=file, line=line, field=fld)
    return v


def _term(name: str, file: str, line: int) -> ErrorTerm:
    try:
        return parse_error_name(name)
    except InputError as exc:
        raise ParseError(exc.message, file=file, line=line, field=name) from None


def _table(
    consts: dict[str, tuple[float, int]],
    curves: list[tuple[str, list[float], list[float], int]],
    sign: str,
    file: str,
) -> CompensationTable:
    out: list[ErrorCurve] = []
    for name, q, v, line in curves:
        try:
            axis = parse_error_name(name).axis
            out.append(ErrorCurve(name, _pos_in(axis, np.asarray(q)), np.asarray(v)))
        except InputError as exc:
            raise ParseError(exc.message, file=file, line=line, field=name) from None
    seen: dict[str, int] = {}
    for name, (_, line) in consts.items():
        seen[name] = line
    for c, (_, _, _, line) in zip(out, curves, strict=True):
        if c.name in seen:
            raise ParseError(
                f"error {c.name} given twice (first on line {seen[c.name]})",
                file=file,
                line=line,
                field=c.name,
            )
        seen[c.name] = line
    try:
        return CompensationTable({k: v for k, (v, _) in consts.items()}, tuple(out), sign)
    except InputError as exc:
        raise ParseError(
            exc.message, file=file, line=seen.get(exc.field or ""), field=exc.field
        ) from None


_Curve = tuple[str, list[float], list[float], int]
_Rows = list[tuple[int, list[str]]]


def loads_isg_csv(text: str, file: str = "<isg>") -> CompensationTable:
    """Read a table in the ISG CSV format (see :func:`dumps_isg_csv`).

    Blocks are separated by ``#`` lines; ``//`` starts a comment. A block whose header
    has no axis letter holds position errors and one row; a block whose first column is
    an axis letter holds component errors of that axis, one row per position.

    Parameters
    ----------
    text : str
        The file's text.
    file : str
        Its name, for the messages.

    Returns
    -------
    CompensationTable
        Sign from the ``sign = ...`` comment, "error" without one.

    Raises
    ------
    ParseError
        Naming the file, the line and the column: a row with the wrong number of values,
        a value that is not a number, an unknown name, a component error in a block of
        another axis, a block that depends on two axes, an error given twice.
    """
    lines = text.splitlines()
    consts: dict[str, tuple[float, int]] = {}
    curves: list[_Curve] = []
    # each block is read as soon as it ends, before the lines after it
    for header, header_line, rows in _isg_blocks(lines, file):
        if any(len(h) == 1 for h in header):
            curves += _isg_components(header, header_line, rows, file)
        else:
            _isg_positions(header, header_line, rows, file, consts)
    _check_whole(lines, "//", file, consts, curves)
    return _table(consts, curves, _sign_of(lines, "//", file), file)


def _isg_blocks(lines: list[str], file: str) -> Iterator[tuple[list[str], int, _Rows]]:
    """The blocks of an ISG CSV text: header, its line, rows ``(line, values)``.

    Checks the names of each header and the number of values of each row.
    """
    header: list[str] | None = None
    header_line = 0
    rows: _Rows = []
    for n, raw in enumerate(lines, start=1):
        s = _strip(raw, "//")
        if not s:
            continue
        if s == "#":
            if header is not None:
                yield header, header_line, rows
            header, rows = None, []
            continue
        parts = s.split()
        if header is None:
            _isg_header(parts, file, n)
            header, header_line = parts, n
            continue
        if len(parts) != len(header):
            raise ParseError(
                f"expected {len(header)} values ({' '.join(header)}), got {len(parts)}",
                file=file,
                line=n,
                field=header[min(len(parts), len(header) - 1)],
            )
        rows.append((n, parts))
    if header is not None:
        yield header, header_line, rows


def _isg_header(parts: list[str], file: str, n: int) -> None:
    """Check a block header: error names, and axis letters as argument columns."""
    for h in parts:
        if len(h) != 1:
            _term(h, file, n)
        elif h not in AXIS_DIRECTION:
            raise ParseError(
                f"unknown axis {h!r}: expected X Y Z U V W A B C as an argument column",
                file=file,
                line=n,
                field=h,
            )


def _isg_positions(
    header: list[str],
    header_line: int,
    rows: _Rows,
    file: str,
    consts: dict[str, tuple[float, int]],
) -> None:
    """A block of position errors (one row of values) into ``consts``."""
    if len(rows) != 1:
        raise ParseError(
            f"a block of position errors needs exactly one row of values, got {len(rows)}",
            file=file,
            line=rows[1][0] if len(rows) > 1 else header_line,
            field=header[0],
        )
    n, vals = rows[0]
    for name, v in zip(header, vals, strict=True):
        term = _term(name, file, header_line)
        if term.kind == "component":
            raise ParseError(
                f"{term.name} is a component error: its block needs the axis {term.axis} "
                "as the first column",
                file=file,
                line=header_line,
                field=name,
            )
        if term.name in consts:
            raise ParseError(
                f"error {term.name} given twice", file=file, line=header_line, field=name
            )
        consts[term.name] = (_float(v, file, n, name), header_line)


def _isg_components(header: list[str], header_line: int, rows: _Rows, file: str) -> list[_Curve]:
    """A block of component errors of one axis (its first column), one row per position."""
    args = [h for h in header if len(h) == 1]
    if len(args) > 1 or header[0] != args[0]:
        raise ParseError(
            "expected the axis (argument) as the only and first column of the block; "
            f"got {' '.join(args)}: dependencies on more than one axis are not supported",
            file=file,
            line=header_line,
            field=args[-1],
        )
    axis = args[0]
    if not rows:
        raise ParseError(
            "a block of component errors has no rows", file=file, line=header_line, field=axis
        )
    q = [_float(vals[0], file, n, axis) for n, vals in rows]
    curves: list[_Curve] = []
    for j, name in enumerate(header[1:], start=1):
        term = _term(name, file, header_line)
        if term.kind != "component" or term.axis != axis:
            raise ParseError(
                f"{term.name} is not a component error of axis {axis}",
                file=file,
                line=header_line,
                field=name,
            )
        curves.append(
            (term.name, q, [_float(vals[j], file, n, name) for n, vals in rows], header_line)
        )
    return curves


_BLOCK = re.compile(r"^\[\s*([A-Za-z0-9]+)\s*\]$")
_KV = re.compile(r"^([A-Za-z_]+)\s*=\s*(.*)$")


def loads_etalon(text: str, file: str = "<etalon>") -> CompensationTable:
    """Read a table in the Etalon exchange format (see :func:`dumps_etalon`).

    Parameters
    ----------
    text : str
        The file's text.
    file : str
        Its name, for the messages.

    Returns
    -------
    CompensationTable
        Sign from the ``sign = ...`` comment, "error" without one.

    Raises
    ------
    ParseError
        Naming the file, the line and the field: a line outside a block, an unknown key,
        a ``Gridpoints`` line that is not two numbers, a missing ``}``, a block with no
        value, a constant for a component error or a table for a position error.
    """
    lines = text.splitlines()
    reader = _EtalonReader(file)
    for n, raw in enumerate(lines, start=1):
        s = _strip(raw, "//")
        if s:
            reader.line(n, s)
    reader.finish()
    _check_whole(lines, "//", file, reader.consts, reader.curves)
    return _table(reader.consts, reader.curves, _sign_of(lines, "//", file), file)


class _EtalonReader:
    """The state of reading an Etalon text line by line: the block open, its grid."""

    def __init__(self, file: str) -> None:
        self.file = file
        self.consts: dict[str, tuple[float, int]] = {}
        self.curves: list[_Curve] = []
        self.name: str | None = None  # the block open
        self.block_line = 0
        self.filled = True  # the block has its VALUE or Gridpoints
        self.in_grid = False
        self.grid_q: list[float] = []
        self.grid_v: list[float] = []
        self.grid_line = 0

    def line(self, n: int, s: str) -> None:
        """One line without its comment, not empty."""
        if self.in_grid:
            self._grid(n, s)
            return
        m = _BLOCK.match(s)
        if m:
            self._block(n, m.group(1))
            return
        kv = _KV.match(s)
        if kv is None or self.name is None:
            raise ParseError(
                f"expected a [NAME] block, 'VALUE = v' or 'Gridpoints = {{', got {s!r}",
                file=self.file,
                line=n,
                field=self.name,
            )
        if self.filled:
            raise ParseError(
                f"block [{self.name}] has a second value",
                file=self.file,
                line=n,
                field=kv.group(1),
            )
        self._key(n, self.name, kv.group(1), kv.group(2).strip())

    def _grid(self, n: int, s: str) -> None:
        """A ``position value`` line of a Gridpoints table, or its closing ``}``."""
        name = self.name
        if s.startswith("}"):
            if not self.grid_q:
                raise ParseError(
                    "empty Gridpoints", file=self.file, line=self.grid_line, field=name
                )
            assert name is not None
            self.curves.append((name, self.grid_q, self.grid_v, self.block_line))
            self.in_grid, self.filled = False, True
            return
        parts = s.split()
        if len(parts) != 2:
            raise ParseError(
                f"expected 'position value' (two numbers), got {s!r}",
                file=self.file,
                line=n,
                field=name,
            )
        self.grid_q.append(_float(parts[0], self.file, n, name or "Gridpoints"))
        self.grid_v.append(_float(parts[1], self.file, n, name or "Gridpoints"))

    def _block(self, n: int, name: str) -> None:
        """A ``[NAME]`` line: the previous block must have its value."""
        self._require_filled()
        term = _term(name, self.file, n)
        self.name, self.block_line, self.filled = term.name, n, False

    def _key(self, n: int, name: str, key: str, val: str) -> None:
        """``VALUE = v`` (a position error) or ``Gridpoints = {`` (a component error)."""
        term = parse_error_name(name)
        if key.upper() == "VALUE":
            if term.kind == "component":
                raise ParseError(
                    f"{name} is a component error: expected Gridpoints along axis {term.axis}",
                    file=self.file,
                    line=n,
                    field=name,
                )
            if name in self.consts:
                raise ParseError(f"error {name} given twice", file=self.file, line=n, field=name)
            self.consts[name] = (_float(val, self.file, n, name), n)
            self.filled = True
        elif key.lower() == "gridpoints":
            if val != "{":
                raise ParseError(
                    "expected 'Gridpoints = {' on its own line", file=self.file, line=n, field=name
                )
            if term.kind != "component":
                raise ParseError(
                    f"{name} is a {term.kind} error: expected VALUE = v",
                    file=self.file,
                    line=n,
                    field=name,
                )
            self.in_grid, self.grid_q, self.grid_v, self.grid_line = True, [], [], n
        else:
            raise ParseError(
                f"unknown key {key!r}; expected VALUE or Gridpoints",
                file=self.file,
                line=n,
                field=key,
            )

    def finish(self) -> None:
        """The end of the text: no Gridpoints open, the last block filled."""
        if self.in_grid:
            raise ParseError(
                "Gridpoints not closed by '}'", file=self.file, line=self.grid_line, field=self.name
            )
        self._require_filled()

    def _require_filled(self) -> None:
        """The block open has its VALUE or Gridpoints."""
        if not self.filled:
            raise ParseError(
                f"block [{self.name}] has no VALUE or Gridpoints",
                file=self.file,
                line=self.block_line,
                field=self.name,
            )


def loads_plain_csv(text: str, file: str = "<csv>") -> CompensationTable:
    """Read a table in the plain CSV format (see :func:`dumps_plain_csv`).

    Parameters
    ----------
    text : str
        The file's text.
    file : str
        Its name, for the messages.

    Returns
    -------
    CompensationTable

    Raises
    ------
    ParseError
        Naming the file, the line and the column: a missing or different header, a row
        with the wrong number of fields, a unit other than the format's, a value that is
        not a number, a constant given twice.
    """
    lines = text.splitlines()
    consts: dict[str, tuple[float, int]] = {}
    curves: dict[str, tuple[list[float], list[float], int]] = {}
    cols = _CSV_HEADER.split(",")
    header_seen = False
    for n, raw in enumerate(lines, start=1):
        s = raw.strip()
        if not s or s.startswith("#"):
            continue
        parts = [p.strip() for p in s.split(",")]
        if not header_seen:
            if parts != cols:
                raise ParseError(
                    f"expected the header {_CSV_HEADER!r}, got {s!r}", file=file, line=n
                )
            header_seen = True
            continue
        if len(parts) != len(cols):
            raise ParseError(
                f"expected {len(cols)} fields ({_CSV_HEADER}), got {len(parts)}", file=file, line=n
            )
        name, axis, pos, punit, val, vunit = parts
        term = _term(name, file, n)
        want = "rad" if term.angular else "mm"
        if vunit != want:
            raise ParseError(
                f"{term.name}: expected value_unit {want!r}, got {vunit!r}",
                file=file,
                line=n,
                field="value_unit",
            )
        v = _float(val, file, n, "value")
        if term.kind != "component":
            if axis or pos or punit:
                raise ParseError(
                    f"{term.name} is a {term.kind} error: axis, position and position_unit "
                    "must be empty",
                    file=file,
                    line=n,
                    field="axis",
                )
            if term.name in consts:
                raise ParseError(f"error {term.name} given twice", file=file, line=n, field="error")
            consts[term.name] = (v, n)
            continue
        if axis != term.axis:
            raise ParseError(
                f"{term.name} is a function of axis {term.axis}, got axis {axis!r}",
                file=file,
                line=n,
                field="axis",
            )
        pwant = "deg" if is_rotary(axis) else "mm"
        if punit != pwant:
            raise ParseError(
                f"expected position_unit {pwant!r}, got {punit!r}",
                file=file,
                line=n,
                field="position_unit",
            )
        q = _float(pos, file, n, "position")
        entry = curves.setdefault(term.name, ([], [], n))
        entry[0].append(q)
        entry[1].append(v)
    if not header_seen:
        raise ParseError(f"no header line {_CSV_HEADER!r}", file=file, line=1)
    rows = [(k, q, v, line) for k, (q, v, line) in curves.items()]
    _check_whole(lines, "#", file, consts, rows)
    return _table(consts, rows, _sign_of(lines, "#", file), file)


_READERS = {"isg": loads_isg_csv, "etalon": loads_etalon, "csv": loads_plain_csv}


def load_compensation(path: str | Path, fmt: str) -> CompensationTable:
    """Read a compensation file of one of :data:`FORMATS`.

    Parameters
    ----------
    path : path-like
    fmt : {"isg", "etalon", "csv"}

    Returns
    -------
    CompensationTable

    Raises
    ------
    InputError
        On an unknown format or a file that cannot be read.
    ParseError
        As the reader of the format.
    """
    if fmt not in _READERS:
        raise InputError(
            f"expected a format among {', '.join(FORMATS)}, got {fmt!r}", field="format"
        )
    return _READERS[fmt](read_text(path), str(path))
