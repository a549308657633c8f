"""Inputs of a study given as a table: observations (a Type A evaluation) or a PDF with ν.

An entry of ``[inputs]`` may be an inline table instead of the text of a distribution
(``docs/study-format.md``):

* ``x = {data = [10.1, 10.3, 10.2]}``: the observations of a Type A evaluation
  (:func:`mtmc.uncertainty.typea.type_a`; JCGM 100 §4.2, JCGM 101 §6.4.9);
* ``x = {data = "readings.csv", column = "x"}``: the same, read from a column of a CSV
  file (relative to the study file; ``column`` defaults to the input's name);
* ``x = {data = [...], pooled_s = 0.02, pooled_dof = 19}``: with a pooled standard
  deviation from an earlier series (JCGM 100 §4.2.4);
* ``x = {dist = "normal(0, 1)", dof = 8}`` or ``u_rel_u = 0.25``: a PDF whose standard
  uncertainty has ν degrees of freedom (:func:`mtmc.uncertainty.typea.with_dof`;
  JCGM 100 G.4.2).

Every error names the file, the line and the field: the study file's for a key of the
table, the CSV file's (line and column) for a value read from it.
"""

from __future__ import annotations

import csv
import io
import math
import warnings
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mtmc.document import Fields, KeyPath, check_number, read_number, read_text
from mtmc.errors import InputError, MtmcError
from mtmc.uncertainty.distributions import IID, Distribution, StudentT, parse_distribution
from mtmc.uncertainty.typea import (
    AutocorrelationWarning,
    TypeA,
    WithDof,
    autocorrelation_limit,
    type_a,
    with_dof,
)

__all__ = ["input_record", "load_csv_column", "read_distribution", "read_input_table"]

#: The keys of an input given as a table.
TABLE_KEYS = ("data", "column", "pooled_s", "pooled_dof", "dist", "dof", "u_rel_u", "unit")


def read_input_table(table: Fields, name: str) -> Distribution:
    """The input ``name`` of an ``[inputs]`` table given as an inline table.

    Parameters
    ----------
    table : Fields
        The inline table (its path ends with the input's name).
    name : str
        The input's name (the default CSV column).

    Returns
    -------
    Distribution
        A :class:`~mtmc.uncertainty.typea.TypeA` (``data``) or the distribution of
        ``dist``, with its ν where ``dof`` or ``u_rel_u`` is given.

    Raises
    ------
    InputError, DistributionError
        Naming the study file, the line and the field (``inputs.x.data``): an unknown key,
        both or neither of ``data`` and ``dist``, keys that do not go with them, fewer
        than 2 observations, a value that is not a finite number; or naming the CSV file,
        the line and the column for a value read from it.
    """
    table.only(TABLE_KEYS)
    if table.has("data") == table.has("dist"):
        raise table.error(
            f"expected either data (the observations of a Type A evaluation) or dist (the "
            f"text of a distribution) for input {name}, got "
            f"{'both' if table.has('data') else 'neither'}"
        )
    if table.has("dist"):
        return _stated(table)
    for key in ("dof", "u_rel_u"):
        if table.has(key):
            raise table.error(
                f"{key} goes with dist; the observations of a Type A evaluation have "
                "ν = n - 1, or pooled_dof with a pooled_s (JCGM 100 §4.2.4)",
                key,
            )
    if table.has("pooled_s") != table.has("pooled_dof"):
        given, missing = (
            ("pooled_s", "pooled_dof") if table.has("pooled_s") else ("pooled_dof", "pooled_s")
        )
        raise table.error(
            f"expected pooled_s and pooled_dof together (JCGM 100 §4.2.4), {missing} is missing",
            given,
        )
    pooled_s = table.number("pooled_s", None, low=0.0, open_low=True)
    pooled_dof = table.number("pooled_dof", None, low=0.0, open_low=True)
    data = table.data["data"]
    if isinstance(data, str):
        column = table.text("column", name)
        path = table.source.resolve(data, (*table.path, "data"))
        values = load_csv_column(path, column)
        least = 1 if pooled_s is not None else 2
        if values.size < least:
            raise InputError(
                f"column {column!r} of {path.name} has {values.size} value"
                f"{'' if values.size == 1 else 's'}; input {name} needs at least {least} "
                "observations",
                file=str(path),
                field=column,
            )
    else:
        if table.has("column"):
            raise table.error(
                'column goes with data = "FILE.csv"; the observations are given here', "column"
            )
        values = _inline(table, data)
    try:
        # serially correlated observations are reported with the result (its warnings, the
        # report), not as a Python warning while the file is read
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", AutocorrelationWarning)
            return type_a(values, pooled_s=pooled_s, pooled_dof=pooled_dof)
    except MtmcError as exc:
        key = {"observations": "data"}.get(str(exc.field), str(exc.field))
        raise table.error(exc.message, key if table.has(key) else "data") from None


def _inline(table: Fields, data: Any) -> NDArray[np.float64]:
    """The observations of ``data = [...]``, each a finite number."""
    if not isinstance(data, list):
        raise table.error(
            f"expected an array of observations or the name of a CSV file, got {data!r}", "data"
        )
    values: list[float] = []
    for i, v in enumerate(data):
        where: KeyPath = (*table.path, "data", i)

        def err(msg: str, w: KeyPath = where) -> InputError:
            return table.source.error(msg, w)

        values.append(check_number(v, err))
    return np.asarray(values, dtype=np.float64)


def _stated(table: Fields) -> Distribution:
    """``dist`` with ``dof`` or ``u_rel_u``."""
    for key in ("column", "pooled_s", "pooled_dof"):
        if table.has(key):
            raise table.error(f"{key} goes with data (the observations), not with dist", key)
    if table.has("dof") and table.has("u_rel_u"):
        raise table.error(
            "expected one of dof and u_rel_u (ν = ½ u_rel_u⁻², JCGM 100 G.4.2), got both",
            "u_rel_u",
        )
    table.text("dist")  # a distribution text here, not a number
    dist = read_distribution(table, "dist")
    if not (table.has("dof") or table.has("u_rel_u")):
        return dist
    key = "dof" if table.has("dof") else "u_rel_u"
    value = table.number(key, low=0.0, open_low=True)
    try:
        return with_dof(dist, value) if key == "dof" else with_dof(dist, u_rel_u=value)
    except MtmcError as exc:
        raise table.error(exc.message, key) from None


def load_csv_column(path: str | Path, column: str) -> NDArray[np.float64]:
    """The numbers of one column of a CSV file.

    The first line that is neither empty nor a ``#`` comment names the columns; the
    delimiter is the first of ``,``, ``;`` and tab found in it. Each line after it gives at
    most one value of the column; an empty cell is no value (a file may hold columns of
    different lengths).

    Parameters
    ----------
    path : str or Path
        The file (UTF-8).
    column : str
        The column's name in the header (matched exactly, else ignoring case).

    Returns
    -------
    ndarray, shape (n,)
        The values in the order of the file.

    Raises
    ------
    InputError
        Naming the file, the line and the column: no such column, a row too short, a
        cell that is not a finite number; or the file cannot be read.
    """
    file = str(path)
    text = read_text(path, "data file")
    lines = [(k, raw.strip()) for k, raw in enumerate(text.splitlines(), start=1)]
    lines = [(k, s) for k, s in lines if s and not s.startswith("#")]
    if not lines:
        raise InputError("expected a header line naming the columns, the file has none", file=file)
    head_line, head = lines[0]
    delim = next((d for d in (",", ";", "\t") if d in head), ",")
    names = _cells(head, delim)
    if column in names:
        index = names.index(column)
    else:
        lower = [c.lower() for c in names]
        if column.lower() not in lower:
            raise InputError(
                f"no column {column!r} in the header; it has {', '.join(names)}",
                file=file,
                line=head_line,
                field=column,
            )
        index = lower.index(column.lower())
    out: list[float] = []
    for k, line in lines[1:]:
        cells = _cells(line, delim)
        if len(cells) <= index:
            raise InputError(
                f"expected {index + 1} or more fields for column {column!r}, got {len(cells)}",
                file=file,
                line=k,
                field=column,
            )
        cell = cells[index]
        if cell == "":
            continue
        out.append(read_number(cell, partial(InputError, file=file, line=k, field=column)))
    return np.asarray(out, dtype=np.float64)


def _cells(line: str, delim: str) -> list[str]:
    return [c.strip() for c in next(csv.reader(io.StringIO(line), delimiter=delim))]


def read_distribution(fields: Fields, key: str) -> Distribution:
    """The PDF a study writes as ``key = "normal(0, 1)"`` or ``key = 0.5`` (a constant).

    The one reader of a scalar input of every kind: a distribution text
    (:func:`mtmc.uncertainty.distributions.parse_distribution`) or a finite number; an
    error names the file, the line and the key.

    Parameters
    ----------
    fields : Fields
        The table that holds ``key``.
    key : str

    Returns
    -------
    Distribution

    Raises
    ------
    InputError, DistributionError
        A value that is neither a distribution text nor a finite number, or a
        distribution with bad parameters.
    """
    from mtmc.uncertainty.distributions import as_distribution

    value = fields.data[key]
    where = (*fields.path, key)
    if isinstance(value, str):
        try:
            return parse_distribution(value, field=key)
        except MtmcError as exc:
            raise type(exc)(
                exc.message,
                file=fields.source.file,
                line=fields.source.line(where),
                field=".".join(map(str, where)),
            ) from None

    def err(msg: str) -> InputError:
        text = msg.replace("expected a number", "expected a distribution text or a number")
        return fields.source.error(text, where)

    return as_distribution(check_number(value, err))


def input_record(name: str, dist: Distribution, unit: str | None = None) -> dict[str, Any]:
    """The entry of ``inputs`` in ``result.json`` for one input.

    ``name``, ``distribution`` (its text; for a Type A input the t of JCGM 101 §6.4.9 it
    is drawn from), ``estimate`` and ``u`` (the standard uncertainty the GUM takes:
    ``s/√n`` of a Type A input, the stated ``u`` of an input with ``dof``, otherwise the
    standard deviation of the PDF), ``dof`` (ν; ``inf`` where ``u`` is exactly known),
    ``sd`` where the standard deviation of the PDF the Monte Carlo draws is not ``u``
    (the scale of a t, of a Type A input or of a PDF with finite ν: ``u√(ν/(ν − 2))``;
    null where infinite, ν ≤ 2),
    and for a Type A input ``type_a``: ``n``, ``mean``, ``s``, ``r1``, ``u``, ``dof``,
    ``pooled_s``, ``pooled_dof`` and ``warning`` (null, or why ``s/√n`` may understate
    ``u``).

    An input of ``k`` identically distributed components (:class:`IID`: the noise of
    every reading) is described by one of them, with ``components``: ``k``.

    Parameters
    ----------
    name : str
    dist : Distribution
    unit : str, optional
        The unit of the input, as the study writes it (``unit`` of the entry).

    Returns
    -------
    dict
    """
    if isinstance(dist, IID):
        one = input_record(name, dist.base, unit)
        return {**one, "distribution": str(dist), "components": dist.k}
    text = str(dist)
    u: Any = dist.std
    if isinstance(dist, TypeA):
        text = str(StudentT(dist.dof, dist.mean, dist.u))
        u = dist.u
    elif isinstance(dist, WithDof):
        u = dist.u
    elif isinstance(dist, StudentT):  # the GUM takes the scale (JCGM 101 §6.4.9.2)
        u = dist.scale
    record: dict[str, Any] = {
        "name": name,
        "distribution": text,
        "estimate": float(dist.mean) if dist.dim == 0 else np.asarray(dist.mean).tolist(),
        "u": float(u) if dist.dim == 0 else np.asarray(u).tolist(),
        "dof": float(dist.dof),
    }
    if unit is not None:
        record["unit"] = unit
    if dist.dim == 0 and float(dist.std) != float(u):
        record["sd"] = float(dist.std) if math.isfinite(float(dist.std)) else None
    if isinstance(dist, TypeA):
        record["type_a"] = {
            "n": dist.n,
            "mean": dist.mean,
            "s": dist.s,
            "r1": dist.r1,
            "r1_limit": autocorrelation_limit(dist.n),
            "u": dist.u,
            "dof": dist.dof,
            "pooled_s": dist.pooled_s,
            "pooled_dof": dist.pooled_dof,
            "warning": dist.warning,
        }
    return record
