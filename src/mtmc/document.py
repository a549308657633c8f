r"""Reading TOML files: one parse per file, one located document, one way to report errors.

Every file mtmc reads as TOML (a study, a graph, an artefact) goes through here:
:func:`read_text` reads it (UTF-8, or an error at the first bad byte), :func:`loads_toml`
parses it once into a :class:`Fields` over a :class:`Source` that knows the line of every key
(:func:`key_lines`), and every error says the file, the line and the field and what was
expected (:class:`~mtmc.errors.InputError`, :class:`~mtmc.errors.ParseError`). The layers
above take the validated values; none parses TOML or reports its errors another way.

Examples
--------
>>> top = loads_toml('[run]\ntrials = 10', "s.toml")
>>> top.table("run").integer("trials"), top.source.line(("run", "trials"))
(10, 2)
>>> loads_toml("a = 1.2.3", "s.toml")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
mtmc.errors.ParseError: s.toml:1:...: not valid TOML: ...
"""

from __future__ import annotations

import hashlib
import math
import re
import sys
import tomllib
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mtmc.errors import InputError, ParseError
from mtmc.io import decode_utf8

__all__ = [
    "MAX_DEPTH",
    "Fields",
    "InputFile",
    "KeyPath",
    "Source",
    "MAX_DEG",
    "MAX_MM",
    "MAX_NAMES",
    "MAX_RAD",
    "MAX_UM",
    "MAX_URAD",
    "check_length",
    "check_number",
    "finite",
    "key_lines",
    "load_toml",
    "loads_toml",
    "read_number",
    "read_text",
]

_REQUIRED: Any = object()

#: The most names an array of names may hold (``outputs``, ``fixed``).
MAX_NAMES = 1000

#: The largest coordinate or length (mm) a file may give: 1 km is no machine tool's. An
#: uncertainty or an error of a length is a length: it has the same limit.
MAX_MM = 1e6

#: The largest angle (deg) a file may give: ten turns. An angular error or its uncertainty
#: has the same limit.
MAX_DEG = 3600.0

#: :data:`MAX_DEG` in radians (20π, about 62.8 rad).
MAX_RAD = math.radians(MAX_DEG)

#: The largest value a file may give in µm (an uncertainty, an error): :data:`MAX_MM`.
MAX_UM = MAX_MM * 1e3

#: The largest value a file may give in µrad (an angular error): :data:`MAX_RAD`.
MAX_URAD = MAX_RAD * 1e6

_HEADER = re.compile(r"""^\s*(\[\[?)\s*([A-Za-z0-9_\-."' ]+?)\s*\]\]?\s*(#.*)?$""")
_KEY = re.compile(
    r"^\s*((?:[A-Za-z0-9_\-]+|\"[^\"]*\")(?:\s*\.\s*(?:[A-Za-z0-9_\-]+|\"[^\"]*\"))*)\s*="
)
_PART = re.compile(r'"([^"]*)"|([A-Za-z0-9_\-]+)')

#: A key path of a TOML document: table and key names, with the 0-based index of an
#: entry of an array of tables, e.g. ``("place", 2, "name")``.
KeyPath = tuple[str | int, ...]


def _parts(text: str) -> list[str]:
    return [m.group(1) if m.group(1) is not None else m.group(2) for m in _PART.finditer(text)]


def key_lines(text: str) -> dict[KeyPath, int]:
    """The 1-based line of every table header and key of a TOML text, by key path.

    :mod:`tomllib` gives no lines, so the text is scanned: ``[a.b]`` headers, ``[[name]]``
    entries (numbered from 0 in order) and ``key =`` lines (dotted and quoted keys
    included); the lines inside a multi-line array are skipped. The first line wins
    when a path repeats.

    Parameters
    ----------
    text : str
        The TOML text (valid or not: what cannot be read is left out).

    Returns
    -------
    dict
        Key path (a tuple of names, with an ``int`` for the entry of an array of
        tables) to line number.

    Examples
    --------
    >>> text = chr(10).join(['title = "x"', '[run]', 'trials = 10', '[[place]]', 'name = "a"'])
    >>> lines = key_lines(text)
    >>> lines[("run", "trials")], lines[("place", 0)], lines[("place", 0, "name")]
    (3, 4, 5)
    """
    out: dict[KeyPath, int] = {}
    counts: dict[tuple[str, ...], int] = {}
    prefix: KeyPath = ()
    state = _Value()
    for n, raw in enumerate(text.splitlines(), start=1):
        if state.open:  # inside a multi-line array or string
            state.scan(raw)
            continue
        h = _HEADER.match(raw)
        if h:
            names = tuple(_parts(h.group(2)))
            if h.group(1) == "[[":
                i = counts.get(names, 0)
                counts[names] = i + 1
                prefix = (*names, i)
            else:
                prefix = names
            out.setdefault(prefix, n)
            continue
        k = _KEY.match(raw)
        if k:
            out.setdefault((*prefix, *_parts(k.group(1))), n)
            state = _Value()
            state.scan(raw[k.end() :])
    return out


class _Value:
    """Where a TOML value stands after the lines scanned so far.

    The depth of its open brackets and braces, and the multi-line string it is inside
    (``\"\"\"`` or ``'''``). Brackets inside strings and comments do not count: after
    ``a = ["x[", "y"]`` the value is closed, and a multi-line string that holds ``[`` opens
    no array.
    """

    def __init__(self) -> None:
        self.depth = 0
        self.peak = 0
        self.string = ""

    @property
    def open(self) -> bool:
        return self.depth > 0 or bool(self.string)

    def scan(self, line: str) -> None:
        i, n = 0, len(line)
        while i < n:
            if self.string:  # inside a multi-line string: only its closing quotes end it
                end = line.find(self.string, i)
                while end > 0 and self.string == '"""' and _escaped(line, end):
                    end = line.find(self.string, end + 1)
                if end < 0:
                    return
                i = end + 3
                self.string = ""
                continue
            c = line[i]
            if c == "#":
                return
            if line.startswith(('"""', "'''"), i):
                self.string = line[i : i + 3]
                i += 3
            elif c in "\"'":  # a one-line string: skip to its closing quote
                j = i + 1
                while j < n and (line[j] != c or (c == '"' and _escaped(line, j))):
                    j += 1
                i = j + 1
            else:
                if c in "[{":
                    self.depth += 1
                    self.peak = max(self.peak, self.depth)
                elif c in "]}":
                    self.depth = max(0, self.depth - 1)
                i += 1


def _escaped(line: str, i: int) -> bool:
    """Whether the character at ``i`` follows an odd number of backslashes."""
    k = i
    while k > 0 and line[k - 1] == "\\":
        k -= 1
    return (i - k) % 2 == 1


@dataclass(frozen=True)
class InputFile:
    """A file that a study file names and a reader read (a graph, a CSV of readings, ...).

    Attributes
    ----------
    key : tuple
        The key path of the field that names it (``("inputs", "d", "data")``).
    given : str
        The path as the field gives it.
    source : str
        The file read, as an absolute path.
    sha256 : str
        SHA-256 of its bytes when it was read (hex).
    copy : str or None
        Its copy in a result folder, relative to the folder (``inputs/d.csv``); None
        until a result folder holds one (:func:`mtmc.study.write_result`).
    """

    key: KeyPath
    given: str
    source: str
    sha256: str
    copy: str | None = None

    @property
    def field(self) -> str:
        """The field as messages name it (``inputs.d.data``, ``pairs[1]``)."""
        return ".".join(str(p) if isinstance(p, str) else f"[{p}]" for p in self.key).replace(
            ".[", "["
        )


@dataclass(frozen=True)
class Source:
    """The text of a study file, where it lies and the line of each of its keys.

    Attributes
    ----------
    file : str
        The name used in messages (the path as given).
    folder : pathlib.Path or None
        The folder that relative paths in the file are read from.
    text : str
        The TOML text.
    sha256 : str
        SHA-256 of the text as UTF-8 (hex).
    lines : dict
        Key path to 1-based line (:func:`mtmc.graph.toml_format.key_lines`).
    files : list of InputFile
        The files named in it that :meth:`resolve` found, in the order they were read:
        what a result folder copies so that it reruns by itself.
    """

    file: str
    folder: Path | None
    text: str
    sha256: str
    lines: dict[KeyPath, int] = field(repr=False)
    files: list[InputFile] = field(default_factory=list, repr=False, compare=False)

    @classmethod
    def from_text(cls, text: str, file: str = "<study>", folder: Path | None = None) -> Source:
        """A source from TOML text (its lines are found here)."""
        digest = hashlib.sha256(text.encode("utf-8")).hexdigest()
        return cls(file, folder, text, digest, key_lines(text))

    def line(self, path: KeyPath) -> int | None:
        """The line of ``path``, or of its longest prefix that has one."""
        for n in range(len(path), 0, -1):
            if path[:n] in self.lines:
                return self.lines[path[:n]]
        return None

    def error(self, message: str, path: KeyPath) -> InputError:
        """An :class:`~mtmc.errors.InputError` naming this file, the line of ``path`` and it."""
        name = InputFile(path, "", "", "").field
        return InputError(message, file=self.file, line=self.line(path), field=name or None)

    def resolve(self, relative: str, path: KeyPath) -> Path:
        """A file named in the study, relative to the study's folder; it must exist.

        The file is recorded in :attr:`files` with the SHA-256 of its bytes.
        """
        p = Path(relative)
        if not p.is_absolute() and self.folder is not None:
            p = self.folder / p
        if not p.is_file():
            raise self.error(f"expected an existing file, {p} is not one", path)
        try:
            digest = hashlib.sha256(p.read_bytes()).hexdigest()
        except OSError as exc:
            raise self.error(f"cannot read {p}: {exc.strerror or exc}", path) from None
        read = InputFile(path, relative, str(p.resolve()), digest)
        if read not in self.files:
            self.files.append(read)
        return p


def _typename(v: Any) -> str:
    names = {bool: "a boolean", int: "an integer", float: "a number", str: "a string"}
    if isinstance(v, dict):
        return "a table"
    if isinstance(v, list):
        return "an array"
    return names.get(type(v), type(v).__name__)


class Fields:
    """Typed access to one table of a study file; errors name file, line and field.

    Parameters
    ----------
    source : Source
        The study file.
    data : dict
        The table.
    path : tuple
        Its key path (``()`` for the top level).
    """

    def __init__(self, source: Source, data: dict[str, Any], path: KeyPath = ()) -> None:
        self.source, self.data, self.path = source, data, path

    def error(self, message: str, key: str | int | None = None) -> InputError:
        """An error at ``key`` of this table (or the table itself)."""
        return self.source.error(message, self.path if key is None else (*self.path, key))

    def missing(self, message: str, key: str) -> InputError:
        """An error for ``key`` absent from this table.

        A missing key has no line of its own: the error points at the line of the
        table's header (``[run]``, ``[[place]]``, ``model = {...}``), or at no line for a
        key missing at the top level, never at the line of another key.
        """
        err = self.source.error(message, (*self.path, key))
        return InputError(message, file=err.file, line=self.source.line(self.path), field=err.field)

    def only(self, allowed: Iterable[str]) -> None:
        """Refuse any key not in ``allowed``, naming the allowed ones."""
        names = tuple(allowed)
        for key in self.data:
            if key not in names:
                raise self.error(f"unknown key {key!r}; expected one of {', '.join(names)}", key)

    def has(self, key: str) -> bool:
        """Whether the table has ``key``."""
        return key in self.data

    def _get(self, key: str, default: Any) -> Any:
        if key in self.data:
            return self.data[key]
        if default is _REQUIRED:
            where = f"[{'.'.join(str(p) for p in self.path)}]" if self.path else "the file"
            raise self.missing(f"missing {key} in {where}", key)
        return default

    def text(self, key: str, default: Any = _REQUIRED, choices: Iterable[str] = ()) -> Any:
        """A string field (one of ``choices`` when given)."""
        v = self._get(key, default)
        if v is default and key not in self.data:
            return v
        if not isinstance(v, str):
            raise self.error(f"expected a string, got {_typename(v)} {v!r}", key)
        opts = tuple(choices)
        if opts and v not in opts:
            raise self.error(f"expected one of {', '.join(map(repr, opts))}, got {v!r}", key)
        return v

    def integer(
        self,
        key: str,
        default: Any = _REQUIRED,
        minimum: int | None = None,
        maximum: int | None = None,
    ) -> Any:
        """An integer field, at least ``minimum`` and at most ``maximum``."""
        v = self._get(key, default)
        if v is default and key not in self.data:
            return v
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.error(f"expected an integer, got {_typename(v)} {v!r}", key)
        if minimum is not None and v < minimum:
            raise self.error(f"expected an integer >= {minimum}, got {v}", key)
        if maximum is not None and v > maximum:
            raise self.error(f"expected an integer <= {maximum}, got {v}", key)
        return v

    def number(
        self,
        key: str,
        default: Any = _REQUIRED,
        *,
        low: float | None = None,
        high: float | None = None,
        open_low: bool = False,
        open_high: bool = False,
    ) -> Any:
        """A finite number in ``[low, high]`` (open ends where asked)."""
        v = self._get(key, default)
        if v is default and key not in self.data:
            return v
        return check_number(v, lambda msg: self.error(msg, key), low, high, open_low, open_high)

    def numbers(
        self,
        key: str,
        n: int,
        default: Any = _REQUIRED,
        *,
        limit: float | None = None,
        low: float | None = None,
        what: str | None = None,
    ) -> Any:
        """An array of ``n`` finite numbers, as a tuple of floats.

        Each at most ``limit`` in size and at least ``low``, where given. ``what`` names
        the array in the error (default ``"an array of n finite numbers"``). An integer
        past the largest float (a file may write 400 digits) is not finite.

        Examples
        --------
        >>> loads_toml("ball = [150, 0.0, 80.0]", file="s.toml").numbers("ball", 3, limit=MAX_MM)
        (150.0, 0.0, 80.0)
        >>> loads_toml("bad = [1, 2, 1e400]", file="s.toml").numbers("bad", 3)
        Traceback (most recent call last):
        ...
        mtmc.errors.InputError: s.toml:1: field bad: expected an array of 3 finite numbers, ...
        """
        v = self._get(key, default)
        if v is default and key not in self.data:
            return v
        values = [finite(x) for x in v] if isinstance(v, list) and len(v) == n else [None]
        if any(
            x is None or (limit is not None and abs(x) > limit) or (low is not None and x < low)
            for x in values
        ):
            text = what or f"an array of {n} finite numbers"
            if limit is not None:
                text += f", each at most {limit:g} in size"
            if low is not None:
                text += f", each at least {low:g}"
            raise self.error(f"expected {text}, got {_short(v)}", key)
        return tuple(values)

    def flag(self, key: str, default: Any = _REQUIRED) -> Any:
        """A boolean field."""
        v = self._get(key, default)
        if not isinstance(v, bool):
            raise self.error(f"expected true or false, got {_typename(v)} {v!r}", key)
        return v

    def texts(self, key: str, default: Any = _REQUIRED, max_items: int = MAX_NAMES) -> Any:
        """A non-empty array of distinct strings (at most ``max_items``), as a tuple."""
        v = self._get(key, default)
        if v is default and key not in self.data:
            return v
        if not isinstance(v, list) or not v or not all(isinstance(x, str) for x in v):
            raise self.error(f"expected a non-empty array of strings, got {_short(v)}", key)
        check_length(v, max_items, lambda msg: self.error(msg, key))
        seen: set[str] = set()
        for x in v:
            if x in seen:
                raise self.error(f"{x!r} is listed twice; expected each name once", key)
            seen.add(x)
        return tuple(v)

    def table(self, key: str, required: bool = True) -> Fields | None:
        """A sub-table (None if absent and not required)."""
        if key not in self.data and not required:
            return None
        v = self._get(key, _REQUIRED)
        if not isinstance(v, dict):
            raise self.error(f"expected a table [{key}], got {_typename(v)}", key)
        return Fields(self.source, v, (*self.path, key))


def _short(v: Any, n: int = 80) -> str:
    """``repr(v)``, cut to ``n`` characters."""
    r = repr(v)
    return r if len(r) <= n else r[: n - 3] + "..."


def check_length(v: Any, maximum: int, err: Callable[[str], InputError]) -> None:
    """Refuse an array ``v`` of more than ``maximum`` entries: ``err(message)`` raised."""
    if len(v) > maximum:
        raise err(f"expected at most {maximum} entries, got {len(v)}")


def finite(v: Any) -> float | None:
    """``v`` as a float if it is a finite number (not a boolean), else None.

    An integer past the largest float (``10**400``) is None, where ``float()`` raises.

    Examples
    --------
    >>> finite(3), finite(2.5), finite(10**400), finite(float("nan")), finite(True), finite("1")
    (3.0, 2.5, None, None, None, None)
    """
    if isinstance(v, bool) or not isinstance(v, int | float):
        return None
    if isinstance(v, int) and abs(v) > sys.float_info.max:
        return None
    f = float(v)
    return f if math.isfinite(f) else None


def check_number(
    v: Any,
    err: Callable[[str], InputError],
    low: float | None = None,
    high: float | None = None,
    open_low: bool = False,
    open_high: bool = False,
) -> float:
    """``v`` as a finite float in the range, or ``err(message)`` raised."""
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise err(f"expected a number, got {_typename(v)} {_short(v)}")
    f = finite(v)
    if f is None:
        raise err(f"expected a finite number, got {_short(v)}")
    lo_ok = low is None or (f > low if open_low else f >= low)
    hi_ok = high is None or (f < high if open_high else f <= high)
    if not (lo_ok and hi_ok):
        lo = "" if low is None else f"{'(' if open_low else '['}{low:g}"
        hi = "" if high is None else f"{high:g}{')' if open_high else ']'}"
        if low is not None and high is not None:
            rng = f"in {lo}, {hi}"
        elif low is not None:
            rng = f"{'>' if open_low else '>='} {low:g}"
        else:
            rng = f"{'<' if open_high else '<='} {high:g}"
        raise err(f"expected a number {rng}, got {_short(v)}")
    return f


#: A number as a file or a command line writes it: an optional sign, ASCII digits with an
#: optional decimal point, an optional exponent; no ``_``, no other script's digits.
NUMBER_TEXT = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")

#: The longest text :func:`read_number` reads: 17 significant digits carry every double,
#: and a number written with more than this many characters is no measurement's.
MAX_NUMBER_CHARS = 100


def read_number(text: str, err: Callable[[str], Exception]) -> float:
    """The finite float that a text writes, or ``err(message)`` raised.

    The one reader of a number given as text: a cell of a CSV file, a parameter of a
    distribution, a literal of a model expression. It takes what :data:`NUMBER_TEXT`
    matches and nothing else (Python's :class:`float` would also take ``1_0``, ``inf``,
    ``nan``, ``0x1p3`` by other routes, and the digits of every script: Arabic-Indic, fullwidth).

    Parameters
    ----------
    text : str
        The text (white space around it is ignored).
    err : callable
        Makes the exception to raise from a message (it adds the file, line and field).

    Returns
    -------
    float

    Examples
    --------
    >>> read_number(" -1.5e3 ", InputError)
    -1500.0
    >>> read_number("1_0", InputError)
    Traceback (most recent call last):
    ...
    mtmc.errors.InputError: expected a finite number written with the digits 0-9 (an \
optional sign, decimal point and exponent: -1.5e-3), got '1_0'
    >>> read_number("1e400", InputError)
    Traceback (most recent call last):
    ...
    mtmc.errors.InputError: expected a finite number at most 1.8e+308 in size, got '1e400'
    """
    s = text.strip()
    shown = repr(s) if len(s) <= 40 else f"'{s[:4]}...{s[-1]}' ({len(s)} characters)"
    if len(s) > MAX_NUMBER_CHARS or NUMBER_TEXT.fullmatch(s) is None:
        raise err(
            "expected a finite number written with the digits 0-9 (an optional sign, decimal "
            f"point and exponent: -1.5e-3), got {shown}"
            + ("" if len(s) <= MAX_NUMBER_CHARS else f"; at most {MAX_NUMBER_CHARS} characters")
        )
    v = float(s)
    if not math.isfinite(v):
        raise err(f"expected a finite number at most {sys.float_info.max:.2g} in size, got {shown}")
    return v


def read_text(path: str | Path, what: str = "file") -> str:
    """The text of a UTF-8 file.

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        What it is, for the message (``"study file"``, ``"graph file"``).

    Raises
    ------
    InputError
        If the file cannot be read (naming it and the reason), or holds more than 256 MiB.
    ParseError
        If it is not UTF-8 text (naming the line and column of the first bad byte).
    """
    try:
        with open(path, "rb") as fh:
            data = fh.read(_MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise InputError(f"cannot read the {what}: {exc.strerror or exc}", file=str(path)) from None
    if len(data) > _MAX_FILE_BYTES:
        raise InputError(
            f"cannot read the {what}: it holds more than {_MAX_FILE_BYTES >> 20} MiB "
            "(a device or a stream that does not end?)",
            file=str(path),
        )
    return decode_utf8(data, str(path))


#: The most bytes :func:`read_text` reads (a device such as /dev/zero never ends).
_MAX_FILE_BYTES = 256 << 20


def loads_toml(text: str, file: str | None = "<toml>", folder: Path | None = None) -> Fields:
    """Parse TOML text once: its top table, over a :class:`Source` with the line of every key.

    Parameters
    ----------
    text : str
        The TOML text.
    file : str or None
        The name used in messages (None: none).
    folder : Path, optional
        The folder that relative paths in the file are read from.

    Raises
    ------
    ParseError
        If the text is not TOML, with the line and column (the last line's end for an
        error at the end of the document).
    """
    try:
        data = tomllib.loads(text)
    except RecursionError:
        raise _too_deep(text, file) from None
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"line (\d+), column (\d+)", str(exc))
        line, col = (int(m.group(1)), int(m.group(2))) if m else (None, None)
        msg = re.split(r" \(at (?:line|end of document)", str(exc))[0]
        if line is None:  # "at end of document": the last line
            lines_ = text.splitlines() or [""]
            line, col = len(lines_), len(lines_[-1]) + 1
            msg += " at the end of the file"
        raise ParseError(f"not valid TOML: {msg}", file=file, line=line, column=col) from None
    if _depth(data) > MAX_DEPTH:
        raise _too_deep(text, file)
    return Fields(Source.from_text(text, file or "<toml>", folder), data)


#: The deepest nesting of arrays and inline tables a file may have (``[[[1]]]`` is 3 deep).
MAX_DEPTH = 32


def _depth(value: Any) -> int:
    """How deep arrays and tables nest in ``value`` (0 for a scalar), without recursion."""
    deepest, stack = 0, [(value, 0)]
    while stack:
        v, d = stack.pop()
        deepest = max(deepest, d)
        if deepest > MAX_DEPTH:
            break
        if isinstance(v, dict):
            stack.extend((x, d + 1) for x in v.values())
        elif isinstance(v, list):
            stack.extend((x, d + 1) for x in v)
    return deepest


def _too_deep(text: str, file: str | None) -> ParseError:
    """The error for a value nested deeper than :data:`MAX_DEPTH`, at the first line that is."""
    state, line = _Value(), None
    for n, raw in enumerate(text.splitlines(), start=1):
        state.scan(raw)
        if state.peak > MAX_DEPTH:
            line = n
            break
    msg = f"arrays and tables nested too deep; expected at most {MAX_DEPTH} levels"
    return ParseError(msg, file=file, line=line)


def load_toml(path: str | Path, what: str = "file") -> Fields:
    """Read and parse a TOML file (:func:`read_text`, then :func:`loads_toml`).

    Relative paths in the file are read from the file's folder.
    """
    p = Path(path)
    return loads_toml(read_text(p, what), str(path), p.resolve().parent)
