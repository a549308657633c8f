r"""Reading a measurement export as CSV: its lines, header, cells, numbers and word maps.

Every CSV file of readings that mtmc reads (a positioning test of ISO 230-2, a circular
test of ISO 230-4) goes through here: blank lines and lines starting with ``#`` are left
out, the separator is the first of a comma, a semicolon or a tab that the header holds,
the columns are found by name (case-insensitively; ``columns`` maps ours onto a vendor's),
each number is read by :func:`mtmc.document.read_number` and held to a size, and every
error names the file, the line and the column. The options that map a file's words onto
ours (``--columns target=Pos``, ``--directions Hin=up``) are read by :func:`read_pairs`.

Examples
--------
>>> t = read_csv("# export\nPos;Error;Extra\n10;1.5;x\n", "a.csv", ("target", "deviation"),
...              columns={"target": "Pos", "deviation": "Error"})
>>> t.where, [(k, t.number(c, "deviation", 1e3)) for k, c in t.rows]
({'target': 0, 'deviation': 1}, [(3, 1.5)])
>>> read_pairs("target=Pos, deviation=Error", "columns", "OURS=THEIRS", "target=Position")
[('target', 'Pos'), ('deviation', 'Error')]
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass

from mtmc.document import read_number
from mtmc.errors import InputError

__all__ = ["CsvTable", "read_csv", "read_pairs", "read_units"]

#: The separators a file may use, in the order they are looked for in its header.
DELIMITERS = (",", ";", "\t")


def read_pairs(text: str, field: str, form: str, example: str) -> list[tuple[str, str]]:
    """The ``KEY=VALUE`` pairs of an option such as ``--columns`` or ``--directions``.

    Parameters
    ----------
    text : str
        ``"KEY=VALUE,KEY=VALUE"``; white space around each side is ignored.
    field : str
        The option, named in an error.
    form : str
        What a pair is, in an error: ``"OURS=THEIRS"``, ``"WORD=up or WORD=down"``.
    example : str
        One pair as the option expects it, shown in an error.

    Returns
    -------
    list of (str, str)

    Raises
    ------
    InputError
        On a part that is not ``KEY=VALUE`` with both sides non-empty.
    """
    out = []
    for part in text.split(","):
        key, sep, value = part.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise InputError(
                f"expected --{field} as {form} pairs, e.g. {example}, got {part.strip()!r}",
                field=field,
            )
        out.append((key.strip(), value.strip()))
    return out


def read_units(
    text: str, allowed: Mapping[str, Sequence[str]], names: tuple[str, str]
) -> tuple[str, str]:
    """The two units of a file's columns from ``"FIRST,SECOND"``, or the second alone.

    Parameters
    ----------
    text : str
        ``"mm,um"``; or ``"um"``, the first unit then the first of ``allowed`` that goes
        with it.
    allowed : mapping of str to sequence of str
        Each first unit and the second units that go with it.
    names : (str, str)
        What the two units are, in an error: ``("TARGET", "DEVIATION")``.

    Returns
    -------
    (str, str)

    Examples
    --------
    >>> read_units("um", {"mm": ("um", "mm"), "deg": ("arcsec",)}, ("TARGET", "DEVIATION"))
    ('mm', 'um')
    """
    parts = [p.strip() for p in str(text).split(",")]
    if len(parts) == 1:
        for first, seconds in allowed.items():
            if parts[0] in seconds:
                return first, parts[0]
    elif len(parts) == 2 and parts[1] in allowed.get(parts[0], ()):
        return parts[0], parts[1]
    known = ", ".join(f"{a},{b}" for a, bs in allowed.items() for b in bs)
    raise InputError(
        f"expected units {names[0]},{names[1]} among {known} (or the {names[1].lower()} unit "
        f"alone), got {text!r}",
        field="units",
    )


def _cells(line: str, delim: str) -> list[str]:
    return [c.strip() for c in next(csv.reader(io.StringIO(line), delimiter=delim))]


@dataclass(frozen=True)
class CsvTable:
    """The readings of a CSV file: where each named column is, and the rows below the header.

    Attributes
    ----------
    file : str
        The file, named in errors.
    names : dict of str to str
        The file's name of each of our columns.
    where : dict of str to int
        The index of each of our columns in a row.
    width : int
        The number of fields of the header: each row has at least as many.
    lines : list of (int, str)
        The line number and text of each row below the header.
    delimiter : str
    """

    file: str
    names: dict[str, str]
    where: dict[str, int]
    width: int
    lines: list[tuple[int, str]]
    delimiter: str

    @property
    def rows(self) -> Iterator[tuple[int, list[str]]]:
        """``(line, cells)`` of each row; a row with too few fields is an error at its line."""
        for k, line in self.lines:
            cells = _cells(line, self.delimiter)
            if len(cells) < self.width:
                raise InputError(
                    f"expected {self.width} fields, got {len(cells)}", file=self.file, line=k
                )
            yield k, cells

    def cell(self, cells: Sequence[str], key: str) -> str:
        """The text of column ``key`` of a row."""
        return cells[self.where[key]]

    def number(self, cells: Sequence[str], key: str, limit: float, line: int = 0) -> float:
        """The finite number of column ``key`` of a row, at most ``limit`` in size."""

        def err(message: str) -> InputError:
            return InputError(message, file=self.file, line=line or None, field=self.names[key])

        text = cells[self.where[key]]
        v = read_number(text, err)
        if abs(v) > limit:
            raise err(f"expected a number at most {limit:g} in size, got {text!r}")
        return v


def read_csv(
    text: str,
    file: str,
    expected: Sequence[str],
    columns: Mapping[str, str] | None = None,
) -> CsvTable:
    """The header and rows of CSV ``text`` (module docstring).

    Parameters
    ----------
    text : str
        The file's text.
    file : str
        Its name, in errors.
    expected : sequence of str
        Our names of the columns the file must have.
    columns : mapping of str to str, optional
        The file's name of some of them (``{"target": "Position"}``); the others by our name.

    Returns
    -------
    CsvTable

    Raises
    ------
    InputError
        On a file without lines, an unknown key of ``columns``, a column not in the header.
    """
    lines = [(k, raw.strip()) for k, raw in enumerate(text.splitlines(), start=1)]
    lines = [(k, s) for k, s in lines if s and not s.startswith("#")]
    if not lines:
        raise InputError("expected a header line and readings, the file has none", file=file)
    names = {c: c for c in expected}
    for key, name in (columns or {}).items():
        if key not in names:
            raise InputError(
                f"unknown column {key!r}; expected one of {', '.join(expected)}",
                file=file,
                field="columns",
            )
        names[key] = str(name)
    (head_line, head), rest = lines[0], lines[1:]
    delim = next((d for d in DELIMITERS if d in head), ",")
    header = _cells(head, delim)
    low = [h.lower() for h in header]
    where: dict[str, int] = {}
    for key in expected:
        if names[key].lower() not in low:
            raise InputError(
                f"no column {names[key]!r} (the {key}) in the header; it has {', '.join(header)}",
                file=file,
                line=head_line,
                field=key,
            )
        where[key] = low.index(names[key].lower())
    return CsvTable(file, names, where, len(header), rest, delim)
