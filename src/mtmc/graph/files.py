"""Reading a graph file in either format, chosen by its suffix."""

from __future__ import annotations

from pathlib import Path

from mtmc.graph.assertions import load_assertions
from mtmc.graph.model import Graph
from mtmc.graph.toml_format import load

__all__ = ["read_graph", "ASSERTION_SUFFIXES"]

#: Suffixes read as the assertion database of Stryczek (Table 1); the others as TOML.
ASSERTION_SUFFIXES: tuple[str, ...] = (".pl", ".db", ".facts")


def read_graph(path: str | Path) -> Graph:
    """Read a graph: TOML (``.toml``), or the assertion database (``.pl``, ``.db``, ``.facts``).

    Parameters
    ----------
    path : str or Path
        The file.

    Returns
    -------
    Graph
        The validated graph.

    Raises
    ------
    ParseError, GraphError
        As :func:`mtmc.graph.toml_format.load` or
        :func:`mtmc.graph.assertions.load_assertions`.
    """
    if Path(path).suffix.lower() in ASSERTION_SUFFIXES:
        return load_assertions(path)
    return load(path)
