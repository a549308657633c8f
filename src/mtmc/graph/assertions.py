"""The assertion database of Stryczek (Table 1): reading and writing.

Stryczek stores a graph as Prolog-like facts, one per element:

==================================  ==================================================
assertion                           reading here
==================================  ==================================================
``p(n, x, y, "p", X, Y, Z)``        place ``n`` (a number gives the name ``p<n>``, an
                                    identifier is the name) drawn at pixel ``(x, y)``,
                                    of type code ``"p"``; ``X, Y, Z`` its values
``t(n, x, y, op)``                  transition ``n`` (name ``t<n>``) at ``(x, y)``
``pt(p, t)``                        input arc: place ``p`` is an input of ``t``; the
                                    inputs keep the order of these facts
``tp(t, p)``                        output arc: ``t`` produces ``p`` (exactly one)
``m(p)``                            marker: ``p`` is marked from the start (M0)
==================================  ==================================================

Type codes: ``"p"`` point, ``"v"`` direction (a directional versor ``I, J, K``), ``"d"``
vector (the components of a section, ``d2``... of Stryczek, Fig. 10), ``"x"``, ``"y"``,
``"z"`` one coordinate, ``"r"`` real (``R_x, R_y, R_z``: ``R, 0, 0`` is the real ``R``;
with ``R_y`` or ``R_z`` non-zero it is read as a vector, a displacement per coordinate).
Types the table does not list are written by their name (``"line"``, ``"plane"``,
``"circle"``, ``"sphere"``, ``"frame"``). The quotes may be ``"``, ``'`` or the
typographic „ ” of the print.

The numbers ``X, Y, Z``:

- of a marked place (``m(p)``): its value (one number for ``x``/``y``/``z``/``r``: the
  coordinate's own, ``X``, ``Y`` or ``Z``, and ``R`` for a real; three for the others);
- of a place produced by ``meas``: the nominal probed point, the transition's ``at``;
- of any other place: the expected values Stryczek's tool shows; they are results, not
  inputs, and are not read (write 0).

The table has no field for the uncertainties or the probing direction. These extensions
carry them (written by :func:`dumps_assertions`, optional on reading):
``title("...")``, ``units(mm)``, ``probe(u1, u2, u3)`` (the ``[probe]`` defaults),
``u(p, u)`` or ``u(p, ux, uy, uz)`` (one standard uncertainty per coordinate of a point,
Stryczek's ``u_x, u_y, u_z``), ``dist(p, "uniform(-1, 1)")``, ``unit(p, deg)``, ``dir(t, I, J, K)``,
``par(t, key, value)`` (any other field of a transition, e.g. ``u_probe``). Without
``dir``, a ``meas`` probes along +X, +Y or +Z for an ``x``, ``y`` or ``z`` output and
along −Z for a point. ``%`` starts a comment; a fact may end with ``.``.

Nothing is skipped silently: an unknown fact, a wrong number of arguments or a stray
character raises :class:`mtmc.errors.ParseError` with its line and column.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

from mtmc.document import read_number
from mtmc.errors import GraphError, MtmcError, ParseError
from mtmc.graph.model import check_graph
from mtmc.graph.places import Place, ProbeDefaults, Transition
from mtmc.graph.structure import Graph
from mtmc.io import decode_utf8

__all__ = ["loads_assertions", "load_assertions", "dumps_assertions", "TYPE_CODES"]

#: Type codes of Table 1 and the place types they stand for.
TYPE_CODES: Mapping[str, str] = MappingProxyType(
    {
        "p": "point",
        "v": "direction",
        "d": "vector",
        "x": "x",
        "y": "y",
        "z": "z",
        "r": "real",
    }
)
_CODE_OF = {v: k for k, v in TYPE_CODES.items()}
_ARITY = {
    "p": 7,
    "t": 4,
    "pt": 2,
    "tp": 2,
    "m": 1,
    "title": 1,
    "units": 1,
    "probe": 3,
    "u": 2,
    "dist": 2,
    "unit": 2,
    "dir": 4,
    "par": 3,
}
_TOKEN = re.compile(
    r"""(?P<ws>[ \t\r]+)|(?P<nl>\n)|(?P<comment>%[^\n]*)
    |(?P<num>[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)
    |(?P<ident>[A-Za-z_][A-Za-z0-9_]*)
    |(?P<str>"[^"\n]*"|'[^'\n]*'|„[^”"\n]*[”"])
    |(?P<punct>[(),.\[\]])""",
    re.VERBOSE,
)


@dataclass(frozen=True)
class _Tok:
    kind: str
    text: str
    line: int
    col: int


def _tokens(text: str, file: str | None) -> list[_Tok]:
    out = []
    pos, line, line_start = 0, 1, 0
    while pos < len(text):
        mt = _TOKEN.match(text, pos)
        if mt is None:
            raise ParseError(
                f"unexpected character {text[pos]!r}",
                file=file,
                line=line,
                column=pos - line_start + 1,
            )
        kind = mt.lastgroup or ""
        if kind == "nl":
            line, line_start = line + 1, mt.end()
        elif kind not in ("ws", "comment"):
            out.append(_Tok(kind, mt.group(), line, pos - line_start + 1))
        pos = mt.end()
    return out


def _value(tok: _Tok, file: str | None) -> Any:
    if tok.kind == "num":
        v = read_number(
            tok.text, lambda message: ParseError(message, file=file, line=tok.line, column=tok.col)
        )
        return int(v) if re.fullmatch(r"[-+]?\d+", tok.text) else v
    if tok.kind == "str":
        return tok.text[1:-1]
    return tok.text  # identifier


def _facts(text: str, file: str | None) -> list[tuple[str, list[Any], int]]:
    toks = _tokens(text, file)
    facts = []
    i = 0

    def expect(kind: str, what: str) -> _Tok:
        nonlocal i
        if i >= len(toks):
            last = toks[-1] if toks else _Tok("", "", 1, 1)
            raise ParseError(f"expected {what} at the end of the text", file=file, line=last.line)
        t = toks[i]
        if (kind == "punct" and t.text != what) or (kind != "punct" and t.kind != kind):
            raise ParseError(
                f"expected {what}, got {t.text!r}", file=file, line=t.line, column=t.col
            )
        i += 1
        return t

    while i < len(toks):
        head = expect("ident", "an assertion name")
        if head.text not in _ARITY:
            raise ParseError(
                f"unknown assertion {head.text!r}; expected one of {', '.join(_ARITY)}",
                file=file,
                line=head.line,
                column=head.col,
            )
        expect("punct", "(")
        args: list[Any] = []
        while True:
            if i >= len(toks):
                raise ParseError(
                    f"unclosed {head.text}(", file=file, line=head.line, column=head.col
                )
            t = toks[i]
            if t.kind in ("num", "ident", "str"):
                args.append(_value(t, file))
                i += 1
            else:
                raise ParseError(
                    f"{head.text}: expected a number, name or quoted text, got {t.text!r}",
                    file=file,
                    line=t.line,
                    column=t.col,
                )
            if i < len(toks) and toks[i].text == ",":
                i += 1
                continue
            expect("punct", ")")
            break
        arity = (2, 4) if head.text == "u" else (_ARITY[head.text],)
        if len(args) not in arity:
            raise ParseError(
                f"{head.text}(...) takes {' or '.join(map(str, arity))} arguments, got {len(args)}",
                file=file,
                line=head.line,
                column=head.col,
            )
        if i < len(toks) and toks[i].text == ".":
            i += 1
        facts.append((head.text, args, head.line))
    return facts


def _name(n: Any, prefix: str, file: str | None, line: int) -> str:
    if isinstance(n, int):
        return f"{prefix}{n}"
    if isinstance(n, str) and re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", n):
        return n
    raise ParseError(f"expected a number or a name, got {n!r}", file=file, line=line)


def _num(v: Any, what: str, file: str | None, line: int) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ParseError(f"{what}: expected a number, got {v!r}", file=file, line=line)
    return float(v)


def _pos(x: Any, y: Any, file: str | None, line: int) -> tuple[float, float] | None:
    if x == "_" and y == "_":
        return None
    return (_num(x, "x", file, line), _num(y, "y", file, line))


def loads_assertions(text: str, *, file: str | None = None, validate: bool = True) -> Graph:
    """Read a graph from the assertion database of Stryczek (Table 1).

    Parameters
    ----------
    text : str
        The facts (see the module docstring for the reading of each field).
    file : str, optional
        File name for the error messages.
    validate : bool
        Also run :func:`mtmc.graph.check` (default).

    Returns
    -------
    Graph
        The graph; every place is declared.

    Raises
    ------
    ParseError
        On a syntax error, an unknown assertion or a wrong number of arguments.
    GraphError
        On an arc to an unknown element, a transition without exactly one output, an
        unknown type code, or an invalid graph.

    Examples
    --------
    >>> g = loads_assertions('''
    ... p(1, 10, 10, "r", 2.0, 0, 0). p(2, 10, 50, "r", 4.0, 0, 0). p(3, 90, 30, "r", 0, 0, 0).
    ... t(1, 50, 30, middle). pt(1, 1). pt(2, 1). tp(1, 3). m(1). m(2).
    ... ''')
    >>> [p.name for p in g.places], g.transitions[0].inputs, g.transitions[0].out
    (['p1', 'p2', 'p3'], ('p1', 'p2'), 'p3')
    """
    facts = _facts(text, file)
    c = _Collected(file)
    for head, a, line in facts:
        c.add(head, a, line)
    producer = c.producers()
    places = c.places(producer)
    transitions = c.transitions({p.name: p.type for p in places})
    graph = Graph(tuple(places), tuple(transitions), c.title, c.units, c.probe, file=file)
    if validate:
        check_graph(graph)
    return graph


class _Collected:
    """The facts of an assertion database, gathered by element, then turned into a graph."""

    def __init__(self, file: str | None) -> None:
        self.file = file
        self.title, self.units = "", "mm"
        self.probe = ProbeDefaults()
        self.praw: dict[str, tuple[list[Any], int]] = {}
        self.traw: dict[str, tuple[list[Any], int]] = {}
        self.inputs: dict[str, list[str]] = {}
        self.outs: dict[str, list[str]] = {}
        self.marked: set[str] = set()
        self.extra_p: dict[str, dict[str, Any]] = {}
        self.extra_t: dict[str, dict[str, Any]] = {}
        self.arc_lines: dict[str, int] = {}
        self.p_refs: list[tuple[str, int]] = []
        self.meas_at: dict[str, tuple[float, float, float]] = {}

    def err(self, msg: str, line: int, fld: str | None = None) -> GraphError:
        return GraphError(msg, file=self.file, line=line, field=fld)

    def add(self, head: str, a: list[Any], line: int) -> None:
        """Record one fact."""
        if head in ("p", "t", "pt", "tp", "m"):
            self._add_net(head, a, line)
        else:
            self._add_field(head, a, line)

    def _add_net(self, head: str, a: list[Any], line: int) -> None:
        """A place, a transition, an arc or a marking."""
        file = self.file
        if head == "p":
            name = _name(a[0], "p", file, line)
            if name in self.praw:
                raise self.err(f"place {name} is asserted twice", line, name)
            self.praw[name] = (a, line)
        elif head == "t":
            name = _name(a[0], "t", file, line)
            if name in self.traw:
                raise self.err(f"transition {name} is asserted twice", line, name)
            self.traw[name] = (a, line)
        elif head == "pt":
            t = _name(a[1], "t", file, line)
            self.inputs.setdefault(t, []).append(_name(a[0], "p", file, line))
            self.p_refs.append((self.inputs[t][-1], line))
            self.arc_lines.setdefault(t, line)
        elif head == "tp":
            t = _name(a[0], "t", file, line)
            self.outs.setdefault(t, []).append(_name(a[1], "p", file, line))
            self.p_refs.append((self.outs[t][-1], line))
            self.arc_lines.setdefault(t, line)
        else:  # m
            self.marked.add(_name(a[0], "p", file, line))
            self.p_refs.append((_name(a[0], "p", file, line), line))

    def _add_field(self, head: str, a: list[Any], line: int) -> None:
        """A title, units, probe defaults, or a field of a place or a transition."""
        file = self.file
        if head == "title":
            self.title = str(a[0])
        elif head == "units":
            self.units = str(a[0])
        elif head == "probe":
            try:
                u1, u2, u3 = (_num(v, "probe", file, line) for v in a)
                self.probe = ProbeDefaults(u1, u2, u3, line=line)
            except MtmcError as exc:
                raise self.err(exc.message, line, exc.field) from None
        elif head in ("u", "dist", "unit"):
            name = _name(a[0], "p", file, line)
            self.p_refs.append((name, line))
            val: Any = str(a[1])
            if head == "u":  # u(p, u) or, per coordinate, u(p, ux, uy, uz)
                nums = tuple(_num(v, head, file, line) for v in a[1:])
                val = nums[0] if len(nums) == 1 else nums
            self.extra_p.setdefault(name, {})[head] = val
        elif head == "dir":
            name = _name(a[0], "t", file, line)
            self.extra_t.setdefault(name, {})["direction"] = tuple(
                _num(v, "dir", file, line) for v in a[1:]
            )
        else:  # par
            name = _name(a[0], "t", file, line)
            self.extra_t.setdefault(name, {})[str(a[1])] = a[2]

    def producers(self) -> dict[str, tuple[str, str]]:
        """Check the references; the producing transition and its op of each output place."""
        for name in (*self.inputs, *self.outs, *self.extra_t):
            if name not in self.traw:
                raise self.err(
                    f"an assertion names transition {name}, which has no t(...)",
                    self.arc_lines.get(name, 1),
                    name,
                )
        for name, line in self.p_refs:
            if name not in self.praw:
                raise self.err(f"an assertion names place {name}, which has no p(...)", line, name)
        producer = {}
        for t, (a, line) in self.traw.items():
            o = self.outs.get(t, [])
            if len(o) != 1:
                raise self.err(
                    f"transition {t} has {len(o)} output arcs tp({t}, ...); expected exactly one",
                    line,
                    t,
                )
            producer[o[0]] = (t, str(a[3]))
        return producer

    def places(self, producer: dict[str, tuple[str, str]]) -> list[Place]:
        """The places (and, in passing, the point of each measurement)."""
        file = self.file
        places = []
        for name, (a, line) in self.praw.items():
            code = str(a[3])
            type_ = TYPE_CODES.get(code, code)
            vals = [_num(v, f"place {name}", file, line) for v in a[4:7]]
            ex = self.extra_p.get(name, {})
            value: Any = None
            if name in self.marked:
                type_, value = _marked_value(type_, vals)
            elif name in producer and producer[name][1] == "meas":
                self.meas_at[producer[name][0]] = (vals[0], vals[1], vals[2])
            try:
                places.append(
                    Place(
                        name,
                        type_,
                        value,
                        u=ex.get("u"),
                        dist=ex.get("dist"),
                        unit=ex.get("unit"),
                        pos=_pos(a[1], a[2], file, line),
                        line=line,
                    )
                )
            except MtmcError as exc:
                raise self.err(exc.message, line, exc.field) from None
        return places

    def transitions(self, types: dict[str, str]) -> list[Transition]:
        """The transitions; a measurement takes its point and direction from its output place."""
        transitions = []
        for name, (a, line) in self.traw.items():
            op = str(a[3])
            params = dict(self.extra_t.get(name, {}))
            out = self.outs[name][0]
            if op == "meas":
                params.setdefault("at", self.meas_at.get(name, (0.0, 0.0, 0.0)))
                if "direction" not in params:
                    params["direction"] = {
                        "x": (1.0, 0.0, 0.0),
                        "y": (0.0, 1.0, 0.0),
                        "z": (0.0, 0.0, 1.0),
                    }.get(types[out], (0.0, 0.0, -1.0))
            try:
                transitions.append(
                    Transition(
                        name,
                        op,
                        tuple(self.inputs.get(name, ())),
                        out,
                        tuple(params.items()),
                        pos=_pos(a[1], a[2], self.file, line),
                        line=line,
                    )
                )
            except MtmcError as exc:
                raise self.err(exc.message, line, exc.field) from None
        return transitions


def _marked_value(type_: str, vals: list[float]) -> tuple[str, Any]:
    """The type and value of a marked place from its three numbers."""
    if type_ in ("x", "y", "z"):
        return type_, vals["xyz".index(type_)]
    if type_ == "real":
        # "r", R_x, R_y, R_z: R, 0, 0 is a real; with R_y or R_z non-zero it is
        # a displacement per coordinate, a vector place (for displace)
        if vals[1] == 0.0 and vals[2] == 0.0:
            return type_, vals[0]
        return "vector", tuple(vals)
    return type_, tuple(vals)


def load_assertions(path: str | Path, *, validate: bool = True) -> Graph:
    """Read an assertion-database file (see :func:`loads_assertions`).

    Parameters
    ----------
    path : str or Path
        The file.
    validate : bool
        Also validate the graph.

    Returns
    -------
    Graph
        The graph.
    """
    p = Path(path)
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise GraphError(
            f"cannot read the assertion file: {exc.strerror}", file=str(path)
        ) from None
    return loads_assertions(decode_utf8(data, p.name), file=p.name, validate=validate)


def _ref(name: str, prefix: str) -> str:
    m = re.fullmatch(prefix + r"(\d+)", name)
    return m.group(1) if m else name


def _f(v: Any) -> str:
    if isinstance(v, str):
        return '"' + v.replace('"', "'") + '"'
    if isinstance(v, tuple):
        raise GraphError(f"a list field cannot be written as par(...): {v!r}")
    return repr(float(v)) if isinstance(v, float) else str(v)


def dumps_assertions(graph: Graph) -> str:
    """Write a graph as the assertion database of Stryczek (with the extensions).

    Every place is written, the implicit ones too, so reading the text back gives the
    same plan (types, arcs, fields) with all places declared, and writing that again
    gives the same text.

    Parameters
    ----------
    graph : Graph
        A valid graph.

    Returns
    -------
    str
        One fact per line.
    """
    plan = check_graph(graph)
    at_of = {}
    for s in plan.steps:
        if s.transition.op == "meas":
            at_of[s.transition.out] = s.transition.param("at")
    lines = ["% measurement graph, assertion database (Stryczek, Table 1)"]
    if graph.title:
        lines.append(f"title({_f(graph.title)}).")
    lines.append(f"units({graph.units}).")
    pr = graph.probe
    lines.append(f"probe({_f(pr.u_axis)}, {_f(pr.u_probe)}, {_f(pr.u_perp)}).")

    for name, type_ in plan.types.items():
        lines += _place_facts(graph.place(name), name, type_, at_of.get(name))
    for t in graph.transitions:
        tn = _ref(t.name, "t")
        lines.append(f"t({tn}, {_xy(t.pos)}, {t.op}).")
        for q in t.inputs:
            lines.append(f"pt({_ref(q, 'p')}, {tn}).")
        lines.append(f"tp({tn}, {_ref(t.out, 'p')}).")
        for key, v in t.params:
            if key == "at":
                continue
            if key == "direction":
                lines.append(f"dir({tn}, {', '.join(_f(float(c)) for c in v)}).")
            else:
                lines.append(f"par({tn}, {key}, {_f(v)}).")
    return "\n".join(lines) + "\n"


def _xy(pos: tuple[float, ...] | None) -> str:
    return "_, _" if pos is None else f"{_f(pos[0])}, {_f(pos[1])}"


def _place_facts(p: Place | None, name: str, type_: str, at: Any) -> list[str]:
    """The facts of one place: ``p(...)``, then ``m``, ``u``, ``dist``, ``unit`` as given."""
    code = _CODE_OF.get(type_, type_)
    vals: list[float] = [0.0, 0.0, 0.0]
    if p is not None and p.value is not None:
        if isinstance(p.value, tuple):
            vals = list(p.value)
        elif type_ in ("x", "y", "z"):
            vals["xyz".index(type_)] = p.value
        else:
            vals[0] = p.value
    elif at is not None:
        vals = [float(v) for v in at]
    pos = p.pos if p is not None else None
    lines = [f'p({_ref(name, "p")}, {_xy(pos)}, "{code}", {", ".join(_f(v) for v in vals)}).']
    if p is not None:
        if p.marked:
            lines.append(f"m({_ref(name, 'p')}).")
        if p.u is not None:
            us = p.u if isinstance(p.u, tuple) else (p.u,)
            lines.append(f"u({_ref(name, 'p')}, {', '.join(_f(v) for v in us)}).")
        if p.dist is not None:
            lines.append(f"dist({_ref(name, 'p')}, {_f(p.dist)}).")
        if p.unit is not None:
            lines.append(f"unit({_ref(name, 'p')}, {p.unit}).")
    return lines
