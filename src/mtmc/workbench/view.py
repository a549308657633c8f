"""The graph file being edited: its text, the page's JSON view of it, and the merge back.

The page edits a plain JSON view of the graph file (:func:`graph_json`): the title, the
units, the ``[probe]`` table, and one object per ``[[place]]`` and ``[[transition]]``
holding the keys the file gives, as the file gives them. Each entry read from the file
carries ``src``, its index in the file; an entry the page adds has ``src = null``; a
place that a transition produces without being declared is listed with ``declared =
false`` (it is written only once it has a position or a field to store).

:meth:`GraphDocument.render` writes an edited view back as TOML by changing the file's
own syntax tree (tomlkit): a key whose value did not change keeps its text, comments and
position; a changed value is replaced where it stands (its comment kept); a deleted
entry is removed and an added one appended. With nothing edited the text comes back
byte for byte. Nothing here is evaluated: the text is read by the graph's own parser
(:func:`mtmc.graph.loads_graph`), which validates every key.
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass, field
from typing import Any

import tomlkit
from tomlkit.items import Table

from mtmc.errors import InputError, MtmcError, ParseError

__all__ = ["GraphDocument", "PayloadError", "check_payload", "graph_json", "node_of_error"]

#: The keys of a place entry (``docs/graph-format.md``).
PLACE_KEYS: tuple[str, ...] = ("name", "type", "value", "u", "dist", "unit", "pos")
#: The keys of a transition entry other than its op fields (``params``).
TRANSITION_KEYS: tuple[str, ...] = ("name", "op", "in", "out", "pos")
#: The keys of ``[probe]``.
PROBE_KEYS: tuple[str, ...] = ("u_axis", "u_probe", "u_perp")
#: Most places, transitions and op fields the page may send (a graph of Stryczek has tens).
MAX_ENTRIES = 5000


class PayloadError(InputError):
    """What the page sent is not a graph view (a 400 with this message)."""


def _read_toml(text: str, file: str) -> dict[str, Any]:
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"line (\d+), column (\d+)", str(exc))
        msg = re.split(r" \(at (?:line|end of document)", str(exc))[0]
        line = int(m.group(1)) if m else None
        raise ParseError(f"not valid TOML: {msg}", file=file, line=line) from None


def _entries(data: dict[str, Any], key: str) -> list[dict[str, Any]]:
    raw = data.get(key, [])
    if not isinstance(raw, list) or not all(isinstance(e, dict) for e in raw):
        return []
    return raw


def graph_json(text: str, file: str = "<graph>") -> dict[str, Any]:
    r"""The JSON view of a graph file's text (keys as the file gives them, no validation).

    Parameters
    ----------
    text : str
        The TOML text (empty for a new file).
    file : str
        The file name, for a parse error.

    Returns
    -------
    dict
        ``{"title", "units", "probe", "places", "transitions"}``; each place
        ``{"src", "declared": true, "name", "type", ...}``, each transition ``{"src",
        "name", "op", "in", "out", "params", "pos"?}``.

    Raises
    ------
    ParseError
        If the text is not TOML.

    Examples
    --------
    >>> v = graph_json('[[place]]\nname = "a"\ntype = "real"\nvalue = 1.0\n')
    >>> v["places"]
    [{'src': 0, 'declared': True, 'name': 'a', 'type': 'real', 'value': 1.0}]
    """
    data = _read_toml(text, file)
    places = []
    for i, e in enumerate(_entries(data, "place")):
        places.append({"src": i, "declared": True, **e})
    transitions = []
    for i, e in enumerate(_entries(data, "transition")):
        t: dict[str, Any] = {"src": i}
        for key in TRANSITION_KEYS:
            if key in e:
                t[key] = e[key]
        t.setdefault("in", [])
        t["params"] = {k: v for k, v in e.items() if k not in TRANSITION_KEYS}
        transitions.append(t)
    probe = data.get("probe", {})
    return {
        "title": data.get("title", ""),
        "units": data.get("units", "mm"),
        "probe": dict(probe) if isinstance(probe, dict) else {},
        "places": places,
        "transitions": transitions,
    }


def _fail(msg: str) -> PayloadError:
    return PayloadError(msg, field="graph")


def _json_value(v: Any, where: str, depth: int = 0) -> None:
    """Only the plain values TOML holds: numbers, strings, booleans, lists of them."""
    if isinstance(v, bool | int | float | str):
        return
    if isinstance(v, list) and depth < 2:
        for x in v:
            _json_value(x, where, depth + 1)
        return
    raise _fail(f"{where}: expected a number, a string or a list of them, got {type(v).__name__}")


def _check_entry(e: Any, kind: str, n_src: int, keys: tuple[str, ...]) -> None:
    if not isinstance(e, dict):
        raise _fail(f"each {kind} must be an object")
    name = e.get("name")
    if not isinstance(name, str):
        raise _fail(f"a {kind} needs a name (a string)")
    src = e.get("src")
    bad = isinstance(src, bool) or not isinstance(src, int) or not 0 <= src < n_src
    if src is not None and bad:
        raise _fail(f"{kind} {name}: src must be the index of a {kind} of the file, or null")
    extra = set(e) - {*keys, "src", "declared", "params"}
    if extra:
        raise _fail(f"{kind} {name}: unknown key {sorted(extra)[0]!r}")
    for key in keys:
        if key in e and e[key] is not None:
            _json_value(e[key], f"{kind} {name}: {key}")
    params = e.get("params", {})
    if not isinstance(params, dict):
        raise _fail(f"{kind} {name}: params must be an object")
    for key, v in params.items():
        if key in TRANSITION_KEYS:
            raise _fail(f"{kind} {name}: params may not hold {key!r}")
        _json_value(v, f"{kind} {name}: {key}")


def check_payload(view: Any, base: dict[str, Any]) -> dict[str, Any]:
    """Check the shape of a graph view the page sent (the values are the parser's job).

    Parameters
    ----------
    view : object
        The decoded JSON.
    base : dict
        The view of the file (for the ``src`` indices).

    Returns
    -------
    dict
        ``view``, checked.

    Raises
    ------
    PayloadError
        Naming what is wrong.
    """
    if not isinstance(view, dict):
        raise _fail("expected a graph object")
    extra = set(view) - {"title", "units", "probe", "places", "transitions"}
    if extra:
        raise _fail(f"unknown key {sorted(extra)[0]!r} in the graph")
    for key in ("places", "transitions"):
        if not isinstance(view.get(key, []), list):
            raise _fail(f"{key} must be a list")
    places, transitions = view.get("places", []), view.get("transitions", [])
    if len(places) + len(transitions) > MAX_ENTRIES:
        raise _fail(f"at most {MAX_ENTRIES} places and transitions")
    for p in places:
        _check_entry(p, "place", len(base["places"]), PLACE_KEYS)
    for t in transitions:
        _check_entry(t, "transition", len(base["transitions"]), TRANSITION_KEYS)
    for key in ("title", "units"):
        if key in view and not isinstance(view[key], str):
            raise _fail(f"{key} must be a string")
    probe = view.get("probe", {})
    if not isinstance(probe, dict):
        raise _fail("probe must be an object")
    for key, v in probe.items():
        _json_value(v, f"probe: {key}")
    for kind, entries in (("place", places), ("transition", transitions)):
        srcs = [e["src"] for e in entries if e.get("src") is not None]
        if len(srcs) != len(set(srcs)):
            raise _fail(f"two {kind}s name the same src")
    return view


def _same(a: Any, b: Any) -> bool:
    """Equal as TOML values (1 == 1.0; a list equals a list of equal items)."""
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, bool) or isinstance(b, bool):
        return a is b
    return bool(a == b)


def _update(table: Table | Any, old: dict[str, Any], new: dict[str, Any]) -> None:
    """Set the keys of ``table`` that changed from ``old`` to ``new``; drop the removed."""
    for key in list(old):
        if key not in new or new[key] is None:
            if key in table:
                del table[key]
    for key, v in new.items():
        if v is None:
            continue
        if key not in old or not _same(old[key], v):
            table[key] = v


def _place_keys(p: dict[str, Any]) -> dict[str, Any]:
    return {k: p[k] for k in PLACE_KEYS if k in p and p[k] is not None}


def _transition_keys(t: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key in ("name", "op", "in", "out"):
        if key in t and t[key] is not None:
            out[key] = t[key]
    if not out.get("in"):
        out.pop("in", None)
    out.update({k: v for k, v in t.get("params", {}).items() if v is not None})
    if t.get("pos") is not None:
        out["pos"] = t["pos"]
    return out


def _written(p: dict[str, Any]) -> bool:
    """Whether a place entry goes to the file: declared, or given something to store."""
    return bool(p.get("declared", True)) or p.get("pos") is not None or p.get("src") is not None


def _new_table(keys: dict[str, Any]) -> Table:
    t = tomlkit.table()
    for k, v in keys.items():
        t[k] = v
    return t


@dataclass
class GraphDocument:
    """The text of the graph file and its JSON view; renders an edited view as TOML.

    Parameters
    ----------
    text : str
        The file's text as last read or saved ("" for a new file).
    file : str
        Its name, for messages.
    """

    text: str
    file: str
    view: dict[str, Any] = field(init=False)

    def __post_init__(self) -> None:
        self.view = graph_json(self.text, self.file)

    def rebase(self, text: str) -> None:
        """Take ``text`` as the file's text (after a save)."""
        self.view = graph_json(text, self.file)
        self.text = text

    def render(self, view: dict[str, Any]) -> str:
        """The TOML text of an edited view, the file's formatting kept where nothing changed.

        The text is cut into its top-level keys and one piece per table (``[probe]``, each
        ``[[place]]``, each ``[[transition]]``, in the file's order, interleaved or not);
        each piece that changes is edited in its own tomlkit tree, the others are kept as
        they are, a deleted entry's piece is dropped and a new entry follows the last of
        its kind.

        Parameters
        ----------
        view : dict
            A view checked by :func:`check_payload`.

        Returns
        -------
        str
            The text; equal to the file's own text when ``view`` is its view.
        """
        pieces = _pieces(self.text)
        base = self.view
        top = _edit_top(pieces[0][1], base, view)
        pieces[0] = ((), top)
        new_probe = {k: v for k, v in view.get("probe", {}).items() if v is not None}
        if not _same(sorted(base["probe"].items()), sorted(new_probe.items())):
            at = next((i for i, (k, _) in enumerate(pieces) if k == ("probe",)), None)
            if at is None:
                top_text = pieces[0][1]
                gap = "\n" if top_text.strip() and not top_text.endswith("\n\n") else ""
                pieces.insert(1, (("probe",), gap + "[probe]\n"))
                at = 1
            text = _edit(pieces[at][1], ("probe",), base["probe"], new_probe)
            pieces[at] = (("probe",), text if new_probe else "")
        old_places = [_place_keys(p) for p in base["places"]]
        new_places = [(p.get("src"), _place_keys(p)) for p in view.get("places", []) if _written(p)]
        _merge(pieces, "place", old_places, new_places)
        old_trans = [_transition_keys(t) for t in base["transitions"]]
        new_trans = [(t.get("src"), _transition_keys(t)) for t in view.get("transitions", [])]
        _merge(pieces, "transition", old_trans, new_trans)
        return "".join(text for _, text in pieces)


_Piece = tuple[tuple[str | int, ...], str]


def _pieces(text: str) -> list[_Piece]:
    """The text cut at its table headers, each piece with its table's key path.

    ``[((), top-level keys), (("probe",), ...), (("place", 0), ...), ...]``; joined, the
    pieces give the text back.
    """
    from mtmc.document import key_lines

    lines = text.splitlines(keepends=True)
    heads = sorted(
        (n, path) for path, n in key_lines(text).items() if lines[n - 1].lstrip().startswith("[")
    )
    out: list[_Piece] = []
    prev = 0
    key: tuple[str | int, ...] = ()
    for n, path in heads:
        out.append((key, "".join(lines[prev : n - 1])))
        prev, key = n - 1, path
    out.append((key, "".join(lines[prev:])))
    return out


def _edit(text: str, path: tuple[str | int, ...], old: dict[str, Any], new: dict[str, Any]) -> str:
    """One table's piece with the keys that changed set (in its own tomlkit tree)."""
    if all(k in new and _same(old[k], new[k]) for k in old) and set(new) <= set(old):
        return text
    body, trailer = _trailer(text)
    doc = tomlkit.parse(body)
    table: Any = doc[str(path[0])]
    if len(path) > 1:
        table = table[0]
    _update(table, old, new)
    out = doc.as_string()
    return out + trailer if not trailer or out.endswith("\n") else out + "\n" + trailer


def _trailer(text: str) -> tuple[str, str]:
    """A piece cut before the comment and blank lines that end it.

    Those lines introduce the next table (``# the probe's offset`` above ``[[place]]``): a
    key added to this table goes above them, not below, where it would read as the next
    table's.
    """
    lines = text.splitlines(keepends=True)
    cut = len(lines)
    while cut > 0 and (not lines[cut - 1].strip() or lines[cut - 1].lstrip().startswith("#")):
        cut -= 1
    return "".join(lines[:cut]), "".join(lines[cut:])


def _edit_top(text: str, base: dict[str, Any], view: dict[str, Any]) -> str:
    changed = {}
    for key, default in (("title", ""), ("units", "mm")):
        new = view.get(key, default)
        if not _same(base[key], new):
            changed[key] = new if new != default else None
    if not changed:
        return text
    doc = tomlkit.parse(text)
    for key, v in changed.items():
        if v is None:
            if key in doc:
                del doc[key]
        else:
            doc[key] = v
    out = doc.as_string()
    return out if not out or out.endswith("\n") else out + "\n"


def _merge(
    pieces: list[_Piece],
    key: str,
    old: list[dict[str, Any]],
    new: list[tuple[int | None, dict[str, Any]]],
) -> None:
    kept = {src: keys for src, keys in new if src is not None}
    added = [keys for src, keys in new if src is None]
    last = 0
    for j, (path, text) in enumerate(pieces):
        if len(path) == 2 and path[0] == key:
            i = int(path[1])
            last = j
            if i not in kept:
                pieces[j] = (path, "")
            else:
                pieces[j] = (path, _edit(text, path, old[i], kept[i]))
    if not added:
        return
    if last == 0:
        last = len(pieces) - 1
    # the comment lines that end the piece introduce the next table: keep them before it
    path, text = pieces[last]
    lines = text.splitlines(keepends=True)
    cut = len(lines)
    while cut > 0 and lines[cut - 1].lstrip().startswith("#"):
        cut -= 1
    body, trailer = "".join(lines[:cut]), "".join(lines[cut:])
    if body and not body.endswith("\n"):
        body += "\n"
    tables = []
    for keys in added:
        doc = tomlkit.document()
        aot = tomlkit.aot()
        aot.append(_new_table(keys))
        doc[key] = aot
        tables.append(doc.as_string())
    sep = "" if not body.strip() or body.endswith("\n\n") else "\n"
    pieces[last] = (path, body + sep + "\n".join(tables) + trailer)


_NODE = re.compile(r"\b(?:place|transition|input|output place|output) '?([A-Za-z_][A-Za-z0-9_]*)'?")


def node_of_error(exc: MtmcError, text: str) -> str | None:
    """The place or transition an error of the graph's parser or check is about.

    The entry whose ``[[place]]`` or ``[[transition]]`` block holds the error's line, or
    else the first place or transition the message names.

    Parameters
    ----------
    exc : MtmcError
        The error.
    text : str
        The text it was raised on.

    Returns
    -------
    str or None
        The node's name, or None for an error of the file as a whole.
    """
    from mtmc.document import key_lines

    if exc.line is not None:
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError:
            data = {}
        best: tuple[int, str, int] | None = None
        for path, line in key_lines(text).items():
            if len(path) == 2 and path[0] in ("place", "transition") and line <= exc.line:
                if best is None or line > best[0]:
                    best = (line, str(path[0]), int(path[1]))
        if best is not None:
            entries = _entries(data, best[1])
            if best[2] < len(entries) and isinstance(entries[best[2]].get("name"), str):
                return str(entries[best[2]]["name"])
    m = _NODE.search(exc.message)
    return m.group(1) if m else None
