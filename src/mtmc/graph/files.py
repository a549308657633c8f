"""Reading a graph file in either format, chosen by its suffix."""

from __future__ import annotations

from pathlib import Path

from mtmc.document import read_text
from mtmc.graph.assertions import load_assertions
from mtmc.graph.structure import Graph
from mtmc.graph.toml_format import loads_graph

__all__ = ["load_graph", "ASSERTION_SUFFIXES"]

#: Suffixes read as the assertion database of Stryczek (Table 1); the others as TOML.
ASSERTION_SUFFIXES: tuple[str, ...] = (".pl", ".db", ".facts")


def load_graph(path: str | Path, *, validate: bool = True) -> Graph:
    """Read a graph file: the assertion database (``.pl``, ``.db``, ``.facts``), else TOML.

    Parameters
    ----------
    path : str or Path
        The file.
    validate : bool
        Also run :func:`mtmc.graph.check_graph` (default), so the graph is runnable.

    Returns
    -------
    Graph
        The graph (validated unless ``validate`` is false).

    Raises
    ------
    InputError
        If the file cannot be read.
    ParseError, GraphError
        As :func:`mtmc.graph.loads_graph` or :func:`mtmc.graph.assertions.load_assertions`.
    """
    p = Path(path)
    if p.suffix.lower() in ASSERTION_SUFFIXES:
        return load_assertions(p, validate=validate)
    return loads_graph(read_text(p, "graph file"), file=p.name, validate=validate)
