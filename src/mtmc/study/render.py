"""The report of any result: a result folder, a study result, or a plain Monte Carlo result.

:func:`render_report` is the one entry point users call (``mtmc.render_report``). The
report package below draws a ``result.json`` and knows nothing of how it was computed
(:func:`mtmc.report.html`, :func:`mtmc.report.render`); this layer, which makes study
results, makes one of the result of :func:`mtmc.monte_carlo`
(:func:`mtmc.study.load.study_result`) before it is drawn.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any, Protocol, TypeAlias, overload

from mtmc.errors import InputError
from mtmc.io import write_text_atomic
from mtmc.report import html, render
from mtmc.study.load import study_result
from mtmc.uncertainty.results import MonteCarloResult, MonteCarloResults

__all__ = ["render_report"]


class _HasToDict(Protocol):
    """A result that gives the content of its ``result.json``."""

    def to_dict(self) -> Mapping[str, Any]: ...


#: What :func:`render_report` draws besides a result folder.
_Source: TypeAlias = Mapping[str, Any] | _HasToDict | MonteCarloResult | MonteCarloResults


@overload
def render_report(source: str | Path, path: None = None) -> Path: ...


@overload
def render_report(source: _Source, path: None = None) -> str: ...


@overload
def render_report(source: _Source, path: str | Path) -> Path: ...


def render_report(source: str | Path | _Source, path: str | Path | None = None) -> Path | str:
    """Render a result: a result folder, a result object, or a plain Monte Carlo result.

    Parameters
    ----------
    source : path-like, mapping or result
        A result folder (its ``report.html`` is written), the content of a
        ``result.json``, a result whose ``to_dict()`` gives it (a
        :class:`~mtmc.study.result.StudyResult`), or the result of :func:`mtmc.monte_carlo`
        (made a study result of kind ``monte_carlo`` by
        :func:`mtmc.study.load.study_result`).
    path : path-like, optional
        Where to write the page for a mapping or result (default: return the text).

    Returns
    -------
    pathlib.Path or str
        The file written (for a folder, or with ``path``), else the HTML text.

    Raises
    ------
    InputError
        If ``source`` is none of these.
    """
    if isinstance(source, str | Path):
        return render(source)
    doc: Mapping[str, Any]
    if isinstance(source, Mapping):
        doc = source
    elif isinstance(source, MonteCarloResult | MonteCarloResults):
        doc = study_result(source).to_dict()
    elif hasattr(source, "to_dict"):
        doc = source.to_dict()
    else:
        raise InputError(
            f"expected a result folder, a result or its result.json, got {type(source).__name__}",
            field="source",
        )
    text = html(doc)
    if path is None:
        return text
    return write_text_atomic(path, text)
