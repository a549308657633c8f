"""The TOML graph file: reading (with file and line in every error) and writing.

The format is documented in ``docs/graph-format.md``. Reading is in two steps kept apart:
:mod:`tomllib` parses the text, then :func:`loads` turns the tables into :class:`Place`,
:class:`Transition` and :class:`Graph` objects, checking every key; nothing is skipped
silently. TOML does not report lines, so the text is scanned for the ``[[place]]`` /
``[[transition]]`` headers and ``key =`` lines, and each entry and field keeps its line for
the messages (``ball_centre.toml:23: field op: transition t5: ...``).

:func:`dumps` writes a graph back; ``loads(dumps(g)) == g`` for every valid graph.
"""

from __future__ import annotations

import json
import math
import re
import tomllib
from collections.abc import Callable
from pathlib import Path
from typing import Any

from mtmc.errors import GraphError, MtmcError, ParseError
from mtmc.graph.model import Graph, check
from mtmc.graph.places import Place, ProbeDefaults, Transition
from mtmc.io import decode_utf8, write_text_atomic

__all__ = ["KeyPath", "key_lines", "load", "loads", "dump", "dumps"]

_TOP_KEYS = ("title", "units", "probe", "place", "transition")
_PLACE_KEYS = ("name", "type", "value", "u", "dist", "unit", "pos")
_PROBE_KEYS = ("u_axis", "u_probe", "u_perp")
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
                elif c in "]}":
                    self.depth = max(0, self.depth - 1)
                i += 1


def _escaped(line: str, i: int) -> bool:
    """Whether the character at ``i`` follows an odd number of backslashes."""
    k = i
    while k > 0 and line[k - 1] == "\\":
        k -= 1
    return (i - k) % 2 == 1


class _Lines:
    """Lines of the headers and keys of a graph file, by table (from :func:`key_lines`)."""

    def __init__(self, text: str) -> None:
        lines = key_lines(text)
        self.top: dict[str, int] = {}
        for p, n in lines.items():  # the first line of each top-level key or table
            if isinstance(p[0], str) and n < self.top.get(p[0], n + 1):
                self.top[p[0]] = n
        self.probe: dict[str, int] = {
            str(p[1]): n for p, n in lines.items() if len(p) == 2 and p[0] == "probe"
        }
        self.probe_line: int | None = lines.get(("probe",))
        keys: dict[tuple[Any, ...], dict[str, int]] = {}
        for p, n in lines.items():  # one pass: the keys of each [[place]] / [[transition]]
            if len(p) == 3:
                keys.setdefault(p[:2], {})[str(p[2])] = n
        self.entries: dict[str, list[tuple[int, dict[str, int]]]] = {}
        for table in ("place", "transition"):
            entries = []
            i = 0
            while (table, i) in lines:
                entries.append((lines[(table, i)], keys.get((table, i), {})))
                i += 1
            self.entries[table] = entries


def _where(e: tomllib.TOMLDecodeError) -> tuple[int | None, int | None]:
    m = re.search(r"line (\d+), column (\d+)", str(e))
    return (int(m.group(1)), int(m.group(2))) if m else (None, None)


def loads(text: str, *, file: str | None = None, validate: bool = True) -> Graph:
    """Read a graph from TOML text.

    Parameters
    ----------
    text : str
        The TOML text (format: ``docs/graph-format.md``).
    file : str, optional
        File name for the error messages.
    validate : bool
        Also run :func:`mtmc.graph.check` (default), so a returned graph is runnable.

    Returns
    -------
    Graph
        The graph.

    Raises
    ------
    ParseError
        If the text is not TOML (with line and column).
    GraphError
        On an unknown key, a missing or malformed field, or an invalid graph, naming the
        file, line and field.

    Examples
    --------
    >>> g = loads('''
    ... [[place]]
    ... name = "a"
    ... type = "real"
    ... value = 1.0
    ... [[transition]]
    ... name = "t1"
    ... op = "displace"
    ... in = ["a", "a"]
    ... out = "b"
    ... ''')
    >>> g.transitions[0].inputs
    ('a', 'a')
    """
    data = _parse_toml(text, file)
    lines = _Lines(text)

    def err(msg: str, line: int | None, fld: str | None) -> GraphError:
        return GraphError(msg, file=file, line=line, field=fld)

    title, units, probe = _header(data, lines, err)
    places = _places(data, lines, err)
    transitions = _transitions(data, lines, err)
    graph = Graph(tuple(places), tuple(transitions), title, units, probe, file=file)
    if validate:
        check(graph)
    return graph


_Err = Callable[[str, int | None, str | None], GraphError]


def _parse_toml(text: str, file: str | None) -> dict[str, Any]:
    """The TOML table of ``text``; a :class:`ParseError` with line and column if it is not TOML."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        line, col = _where(exc)
        msg = re.split(r" \(at (?:line|end of document)", str(exc))[0]
        if line is None:  # "at end of document": the last line
            lines_ = text.splitlines() or [""]
            line, col = len(lines_), len(lines_[-1]) + 1
            msg += " at the end of the file"
        raise ParseError(f"not valid TOML: {msg}", file=file, line=line, column=col) from None
    return data


def _header(data: dict[str, Any], lines: _Lines, err: _Err) -> tuple[str, str, ProbeDefaults]:
    """The top-level keys checked, then the title, the length unit and the probe defaults."""
    for key in data:
        if key not in _TOP_KEYS:
            raise err(
                f"unknown key {key!r}; expected one of {', '.join(_TOP_KEYS)}",
                lines.top.get(key),
                key,
            )
    title = data.get("title", "")
    if not isinstance(title, str):
        raise err("title must be a string", lines.top.get("title"), "title")
    units = data.get("units", "mm")
    if units == "µm":
        units = "um"
    if units not in ("mm", "um"):
        raise err(f'units must be "mm" or "um", got {units!r}', lines.top.get("units"), "units")
    probe_data = data.get("probe", {})
    if not isinstance(probe_data, dict):
        raise err("probe must be a table [probe]", lines.top.get("probe"), "probe")
    for key in probe_data:
        if key not in _PROBE_KEYS:
            raise err(
                f"probe: unknown key {key!r}; expected one of {', '.join(_PROBE_KEYS)}",
                lines.probe.get(key, lines.probe_line),
                key,
            )
    try:
        probe = ProbeDefaults(**probe_data, line=lines.probe_line)
    except MtmcError as exc:
        raise err(
            exc.message, lines.probe.get(exc.field or "", lines.probe_line), exc.field
        ) from None

    return title, units, probe


def _places(data: dict[str, Any], lines: _Lines, err: _Err) -> list[Place]:
    """The ``[[place]]`` tables as places, errors at the line of the offending key."""
    places = []
    raw_places = data.get("place", [])
    if not isinstance(raw_places, list):
        raise err("place must be an array of tables [[place]]", lines.top.get("place"), "place")
    for i, entry in enumerate(raw_places):
        line, keys = lines.entries["place"][i] if i < len(lines.entries["place"]) else (None, {})
        for key in entry:
            if key not in _PLACE_KEYS:
                raise err(
                    f"place {entry.get('name', i + 1)}: unknown key {key!r}; expected one of "
                    f"{', '.join(_PLACE_KEYS)}",
                    keys.get(key, line),
                    key,
                )
        for key in ("name", "type"):
            if key not in entry:
                raise err(f"place {entry.get('name', '#' + str(i + 1))}: missing {key}", line, key)
        try:
            places.append(Place(**entry, line=line))
        except MtmcError as exc:
            raise err(exc.message, keys.get(exc.field or "", line), exc.field) from None

    return places


def _transitions(data: dict[str, Any], lines: _Lines, err: _Err) -> list[Transition]:
    """The ``[[transition]]`` tables as transitions, errors at the line of the offending key."""
    transitions = []
    raw_trans = data.get("transition", [])
    if not isinstance(raw_trans, list):
        raise err(
            "transition must be an array of tables [[transition]]",
            lines.top.get("transition"),
            "transition",
        )
    for i, entry in enumerate(raw_trans):
        line, keys = (
            lines.entries["transition"][i] if i < len(lines.entries["transition"]) else (None, {})
        )
        label = entry.get("name", f"#{i + 1}")
        for key in ("name", "op", "out"):
            if key not in entry:
                raise err(f"transition {label}: missing {key}", line, key)
        params = {k: v for k, v in entry.items() if k not in ("name", "op", "in", "out", "pos")}
        try:
            transitions.append(
                Transition(
                    entry["name"],
                    entry["op"],
                    entry.get("in", ()),
                    entry["out"],
                    tuple(params.items()),
                    pos=entry.get("pos"),
                    line=line,
                    param_lines=tuple(keys.items()),
                )
            )
        except MtmcError as exc:
            raise err(exc.message, keys.get(exc.field or "", line), exc.field) from None
    return transitions


def load(path: str | Path, *, validate: bool = True) -> Graph:
    """Read a graph file (see :func:`loads`).

    Parameters
    ----------
    path : str or Path
        The TOML file.
    validate : bool
        Also validate the graph.

    Returns
    -------
    Graph
        The graph, its ``file`` set to the file's name.

    Raises
    ------
    InputError
        If the file cannot be read.
    ParseError, GraphError
        As :func:`loads`.
    """
    p = Path(path)
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise GraphError(f"cannot read the graph file: {exc.strerror}", file=str(path)) from None
    return loads(decode_utf8(data, p.name), file=p.name, validate=validate)


def _fmt(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} to TOML")


def dumps(graph: Graph) -> str:
    """Write a graph as TOML text (``loads(dumps(g)) == g``).

    Parameters
    ----------
    graph : Graph
        The graph.

    Returns
    -------
    str
        The TOML text.
    """
    out = []
    if graph.title:
        out.append(f"title = {_fmt(graph.title)}")
    out.append(f"units = {_fmt(graph.units)}")
    out.append("")
    out.append("[probe]")
    for key in _PROBE_KEYS:
        out.append(f"{key} = {_fmt(getattr(graph.probe, key))}")
    for p in graph.places:
        out.append("")
        out.append("[[place]]")
        out.append(f"name = {_fmt(p.name)}")
        out.append(f"type = {_fmt(p.type)}")
        for key in ("value", "u", "dist", "unit", "pos"):
            v = getattr(p, key)
            if v is not None:
                out.append(f"{key} = {_fmt(v)}")
    for t in graph.transitions:
        out.append("")
        out.append("[[transition]]")
        out.append(f"name = {_fmt(t.name)}")
        out.append(f"op = {_fmt(t.op)}")
        if t.inputs:
            out.append(f"in = {_fmt(t.inputs)}")
        out.append(f"out = {_fmt(t.out)}")
        for key, v in t.params:
            out.append(f"{key} = {_fmt(v)}")
        if t.pos is not None:
            out.append(f"pos = {_fmt(t.pos)}")
    return "\n".join(out) + "\n"


def dump(graph: Graph, path: str | Path) -> None:
    """Write a graph to a TOML file (see :func:`dumps`).

    Parameters
    ----------
    graph : Graph
        The graph.
    path : str or Path
        The file to write (atomically, :func:`mtmc.io.write_text_atomic`).
    """
    write_text_atomic(path, dumps(graph))
