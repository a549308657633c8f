"""Reading a study file: the ``[run]`` settings and the registry of kinds.

A study file is TOML (``docs/study-format.md``), read and parsed once by
:mod:`mtmc.document` into a :class:`~mtmc.document.Fields` of its top table, whose errors
name the file, the line and the field. Study kinds register a loader under their name with
:func:`register_kind`; :func:`load_study` reads ``kind`` and hands the parsed file to the
loader of that kind; :meth:`RunSettings.read` is the one reader of ``[run]``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from mtmc.document import Fields, loads_toml, read_text
from mtmc.errors import InputError, MtmcError
from mtmc.study.base import Study
from mtmc.study.options import unsupported_option

__all__ = [
    "StudyKind",
    "load_study",
    "loads_study",
    "register_kind",
    "study_kinds",
]


@dataclass(frozen=True)
class StudyKind:
    """A kind of study: its name, a one-line description and its loader.

    Attributes
    ----------
    name : str
        The ``kind`` of the study file.
    summary : str
        What it computes, in one line.
    load : callable
        ``load(fields) -> Study``: validates the whole file (a :class:`Fields` of the
        top-level table) before anything runs.
    """

    name: str
    summary: str
    load: Callable[[Fields], Study]


_KINDS: dict[str, StudyKind] = {}


def register_kind(
    name: str, summary: str
) -> Callable[[Callable[[Fields], Study]], Callable[[Fields], Study]]:
    """Register the loader of a study kind (a decorator); a name is registered once.

    Parameters
    ----------
    name : str
        The ``kind`` a study file names.
    summary : str
        One line on what the kind computes.

    Returns
    -------
    callable
        The decorator, returning the loader unchanged.

    Raises
    ------
    ValueError
        If ``name`` is already registered.
    """

    def deco(load: Callable[[Fields], Study]) -> Callable[[Fields], Study]:
        if name in _KINDS:
            raise ValueError(f"study kind {name!r} is already registered")
        _KINDS[name] = StudyKind(name, summary, load)
        return load

    return deco


def study_kinds() -> dict[str, StudyKind]:
    """The registered study kinds, by name (sorted)."""
    return dict(sorted(_KINDS.items()))


def loads_study(text: str, *, file: str = "<study>", folder: Path | None = None) -> Study:
    """Read and validate a study from TOML text (see :func:`load_study`)."""
    top = loads_toml(text, file, folder)
    data = top.data
    known = study_kinds()
    kind = top.text("kind") if "kind" in data else None
    if kind is None:
        raise top.missing(f"missing kind; expected one of {', '.join(known)}", "kind")
    if kind not in known:
        raise top.error(f"unknown kind {kind!r}; expected one of {', '.join(known)}", "kind")
    try:
        study = known[kind].load(top)
    except MtmcError as exc:
        if exc.file is not None:
            raise
        # an error of the library below (a distribution, an expression, a graph) that
        # knows no file: it happened while reading this study.
        raise InputError(exc.message, file=file, line=exc.line, field=exc.field) from None

    refused = unsupported_option(study, study.settings)
    if refused is not None:
        key, message = refused
        run = top.table("run")
        assert run is not None  # an option other than the defaults was read from [run]
        raise run.error(message, key)
    return study


def load_study(path: str | Path) -> Study:
    """Read and validate a study file; nothing runs until ``.run()``.

    Parameters
    ----------
    path : str or Path
        The TOML study file (``docs/study-format.md``).

    Returns
    -------
    Study
        A frozen study of the kind the file names; ``study.run(...)`` runs it.

    Raises
    ------
    InputError
        If the file cannot be read, or any field is wrong: the message names the file,
        the line and the field and says what was expected (an unknown ``kind`` lists
        the known ones).
    ParseError
        If the file is not TOML.
    """
    p = Path(path)
    return loads_study(read_text(p, "study file"), file=str(path), folder=p.resolve().parent)
