"""The TOML graph file: reading (with file and line in every error) and writing.

The format is documented in ``docs/graph-format.md``. Reading is in two steps kept apart:
:func:`mtmc.document.loads_toml` parses the text, then :func:`loads_graph` turns the tables into
:class:`Place`, :class:`Transition` and :class:`Graph` objects, checking every key; nothing
is skipped silently. TOML does not report lines, so the text is scanned for the ``[[place]]`` /
``[[transition]]`` headers and ``key =`` lines, and each entry and field keeps its line for
the messages (``ball_centre.toml:23: field op: transition t5: ...``).

:func:`dumps_graph` writes a graph back; ``loads_graph(dumps_graph(g)) == g`` for every valid graph.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from mtmc.document import MAX_DEG, MAX_MM, MAX_RAD, KeyPath, loads_toml
from mtmc.errors import GraphError, MtmcError
from mtmc.graph.model import check_graph
from mtmc.graph.places import MAX_MAGNITUDE, Place, ProbeDefaults, Transition
from mtmc.graph.structure import Graph
from mtmc.io import write_text_atomic
from mtmc.uncertainty.distributions import parse_distribution

__all__ = ["dump_graph", "dumps_graph", "loads_graph", "toml_string"]

_TOP_KEYS = ("title", "units", "probe", "place", "transition")
_PLACE_KEYS = ("name", "type", "value", "u", "dist", "unit", "pos")
_PROBE_KEYS = ("u_axis", "u_probe", "u_perp")


class _Lines:
    """Lines of the headers and keys of a graph file, by table (from :func:`key_lines`)."""

    def __init__(self, lines: dict[KeyPath, int]) -> None:
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


def loads_graph(text: str, *, file: str | None = None, validate: bool = True) -> Graph:
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
    >>> g = loads_graph('''
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
    top = loads_toml(text, file)
    data, lines = top.data, _Lines(top.source.lines)

    def err(msg: str, line: int | None, fld: str | None) -> GraphError:
        return GraphError(msg, file=file, line=line, field=fld)

    title, units, probe = _header(data, lines, err)
    places = _places(data, lines, err, units)
    transitions = _transitions(data, lines, err)
    graph = Graph(tuple(places), tuple(transitions), title, units, probe, file=file)
    if validate:
        check_graph(graph)
    return graph


_Err = Callable[[str, int | None, str | None], GraphError]


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
        limit, unit = _limit(None, units)
        for key in _PROBE_KEYS:
            if getattr(probe, key) > limit:
                raise GraphError(
                    f"probe: expected {key} at most {limit:g} {unit}, got {probe_data[key]!r}",
                    field=key,
                )
    except MtmcError as exc:
        raise err(
            exc.message, lines.probe.get(exc.field or "", lines.probe_line), exc.field
        ) from None

    return title, units, probe


def _limit(unit: str | None, units: str) -> tuple[float, str]:
    """The largest size of a number of a place of ``unit`` in a file of ``units``."""
    if unit == "rad":
        return MAX_RAD, "rad"
    if unit == "deg":
        return MAX_DEG, "deg"
    if unit == "1":
        return MAX_MAGNITUDE, ""
    return (MAX_MM * 1e3, "um") if units == "um" else (MAX_MM, "mm")


def _check_place_range(place: Place, units: str, keys: dict[str, int], line: int | None) -> None:
    """Refuse a value or u of a place beyond :func:`_limit`, or a pos beyond ``MAX_MM``."""
    limit, unit = _limit(place.unit, units)
    for key, v, lim, u in (
        ("value", place.value, limit, unit),
        ("u", place.u, limit, unit),
        ("pos", place.pos, MAX_MM, ""),
    ):
        if v is None:
            continue
        xs = v if isinstance(v, tuple) else (v,)
        if any(abs(float(x)) > lim for x in xs):
            raise GraphError(
                f"place {place.name}: expected {key} at most {lim:g}{' ' + u if u else ''} "
                f"in size, got {list(xs) if len(xs) > 1 else xs[0]!r}",
                line=keys.get(key, line),
                field=key,
            )
    if place.dist is not None:  # its expectation and standard deviation: a value and a u
        try:
            dist = parse_distribution(place.dist)
        except MtmcError:
            return  # the graph's check names what does not parse
        u = getattr(dist, "u", dist.std)  # the stated u of a Type A or a u with dof
        for what, x in (("expectation", dist.mean), ("standard uncertainty", u)):
            size = float(np.max(np.abs(np.asarray(x, dtype=np.float64))))
            if not size <= limit:
                raise GraphError(
                    f"place {place.name}: expected the {what} of dist at most {limit:g}"
                    f"{' ' + unit if unit else ''} in size (as value and u), got {size:g} "
                    f"for {place.dist!r}",
                    line=keys.get("dist", line),
                    field="dist",
                )


def _places(data: dict[str, Any], lines: _Lines, err: _Err, units: str = "mm") -> list[Place]:
    """The ``[[place]]`` tables as places, errors at the line of the offending key."""
    places = []
    raw_places = data.get("place", [])
    if not isinstance(raw_places, list):
        raise err("place must be an array of tables [[place]]", lines.top.get("place"), "place")
    for i, entry in enumerate(raw_places):
        line, keys = lines.entries["place"][i] if i < len(lines.entries["place"]) else (None, {})
        if not isinstance(entry, dict):
            raise err(
                f"place #{i + 1}: expected a table (name = ..., type = ...), got {_kind(entry)}",
                line if line is not None else lines.top.get("place"),
                "place",
            )
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
            place = Place(**entry, line=line)
            _check_place_range(place, units, keys, line)
        except MtmcError as exc:
            raise err(exc.message, keys.get(exc.field or "", line), exc.field) from None
        places.append(place)

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
        if not isinstance(entry, dict):
            raise err(
                f"transition #{i + 1}: expected a table (name = ..., op = ..., out = ...), got "
                f"{_kind(entry)}",
                line if line is not None else lines.top.get("transition"),
                "transition",
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


def _kind(v: Any) -> str:
    """What a TOML value is, for a message: ``a boolean``, ``an array``, ..."""
    kinds = ((bool, "a boolean"), (int, "an integer"), (float, "a number"), (str, "a string"))
    for t, name in kinds:
        if isinstance(v, t):
            return f"{name} ({v!r})"[:80]
    return "an array" if isinstance(v, list) else f"a {type(v).__name__}"


def toml_string(s: str) -> str:
    r"""``s`` as a TOML basic string, which every TOML reader reads back as ``s``.

    JSON's escapes (quotes, backslash, the C0 controls) are TOML's; DEL (U+007F), which
    JSON writes raw and TOML refuses raw, is escaped too. Characters beyond U+FFFF are
    written as themselves (JSON's ASCII form would write them as surrogate pairs, which
    TOML refuses).

    Examples
    --------
    >>> print(toml_string('a "b"\x7f😀'))
    "a \"b\"\u007f😀"
    """
    return json.dumps(s, ensure_ascii=False).replace("\x7f", "\\u007f")


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
        return toml_string(v)
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} to TOML")


def dumps_graph(graph: Graph) -> str:
    """Write a graph as TOML text (``loads_graph(dumps_graph(g)) == g``).

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


def dump_graph(graph: Graph, path: str | Path) -> None:
    """Write a graph to a TOML file (see :func:`dumps_graph`).

    Parameters
    ----------
    graph : Graph
        The graph.
    path : str or Path
        The file to write (atomically, :func:`mtmc.io.write_text_atomic`).
    """
    write_text_atomic(path, dumps_graph(graph))
