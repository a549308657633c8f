"""Reading a study file: the source with its key lines, typed field access, the registry.

A study file is TOML (``docs/study-format.md``). :class:`Source` keeps the text and the
line of every key (:func:`mtmc.graph.toml_format.key_lines`); :class:`Fields` reads one
table of it with a type and a range for each field, so that every error names the file,
the line and the field and says what was expected. Study kinds register a loader under
their name with :func:`register_kind`; :func:`load_study` reads ``kind`` and hands the
file to the loader of that kind.
"""

from __future__ import annotations

import hashlib
import math
import tomllib
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mtmc.errors import InputError, MtmcError, ParseError
from mtmc.graph.toml_format import KeyPath, key_lines
from mtmc.io import decode_utf8

if TYPE_CHECKING:
    from mtmc.study.base import Study

__all__ = [
    "Fields",
    "RunSettings",
    "Source",
    "StudyKind",
    "load_study",
    "loads_study",
    "register_kind",
    "study_kinds",
]

_REQUIRED: Any = object()


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
    """

    file: str
    folder: Path | None
    text: str
    sha256: str
    lines: dict[KeyPath, int] = field(repr=False)

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
        name = ".".join(str(p) if isinstance(p, str) else f"[{p}]" for p in path).replace(".[", "[")
        return InputError(message, file=self.file, line=self.line(path), field=name or None)

    def resolve(self, relative: str, path: KeyPath) -> Path:
        """A file named in the study, relative to the study's folder; it must exist."""
        p = Path(relative)
        if not p.is_absolute() and self.folder is not None:
            p = self.folder / p
        if not p.is_file():
            raise self.error(f"expected an existing file, {p} is not one", path)
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

    def integer(self, key: str, default: Any = _REQUIRED, minimum: int | None = None) -> Any:
        """An integer field, at least ``minimum``."""
        v = self._get(key, default)
        if v is default and key not in self.data:
            return v
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.error(f"expected an integer, got {_typename(v)} {v!r}", key)
        if minimum is not None and v < minimum:
            raise self.error(f"expected an integer >= {minimum}, got {v}", key)
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

    def flag(self, key: str, default: Any = _REQUIRED) -> Any:
        """A boolean field."""
        v = self._get(key, default)
        if not isinstance(v, bool):
            raise self.error(f"expected true or false, got {_typename(v)} {v!r}", key)
        return v

    def texts(self, key: str, default: Any = _REQUIRED) -> Any:
        """A non-empty array of strings, as a tuple."""
        v = self._get(key, default)
        if v is default and key not in self.data:
            return v
        if not isinstance(v, list) or not v or not all(isinstance(x, str) for x in v):
            raise self.error(f"expected a non-empty array of strings, got {v!r}", key)
        return tuple(v)

    def table(self, key: str, required: bool = True) -> Fields | None:
        """A sub-table (None if absent and not required)."""
        if key not in self.data and not required:
            return None
        v = self._get(key, _REQUIRED)
        if not isinstance(v, dict):
            raise self.error(f"expected a table [{key}], got {_typename(v)}", key)
        return Fields(self.source, v, (*self.path, key))


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
        raise err(f"expected a number, got {_typename(v)} {v!r}")
    f = float(v)
    if not math.isfinite(f):
        raise err(f"expected a finite number, got {v!r}")
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
        raise err(f"expected a number {rng}, got {v!r}")
    return f


@dataclass(frozen=True)
class RunSettings:
    """The ``[run]`` table of a study: how many trials, which seed, which probability.

    Attributes
    ----------
    trials : int
        Monte Carlo trials ``M`` (JCGM 101 §7.2).
    seed : int or None
        The seed (None: fresh entropy, recorded in the result).
    p : float
        Coverage probability of the intervals.
    interval : str
        The Monte Carlo coverage interval reported (its half-length is ``U``) and used
        in the JCGM 101 §8 validation: ``"symmetric"`` (probabilistically symmetric,
        JCGM 101 §7.7.2, the default of mtmc) or ``"shortest"`` (§7.7.3).
    ndig : int
        Significant digits of ``u(y)`` regarded as meaningful (JCGM 101 §7.9.2).
    samples : bool
        Keep the model values and write them as ``.npy``.
    workers, executor, scheduler
        Where the blocks of trials (or the grid points of a sweep) are evaluated (see
        :func:`mtmc.parallel.map_blocks`); not read from the file, since they do not
        change a number: given to :meth:`Study.run` or on the command line.
    """

    trials: int = 200_000
    seed: int | None = None
    p: float = 0.95
    interval: str = "symmetric"
    ndig: int = 2
    samples: bool = False
    workers: int = 1
    executor: str = "thread"
    scheduler: Any = None

    @property
    def parallel(self) -> dict[str, Any]:
        """The ``workers``, ``executor`` and ``scheduler`` keywords of the engine."""
        return {"workers": self.workers, "executor": self.executor, "scheduler": self.scheduler}

    @classmethod
    def read(cls, top: Fields, default_trials: int = 200_000) -> RunSettings:
        """Read ``[run]`` (every key optional)."""
        run = top.table("run", required=False)
        if run is None:
            return cls(trials=default_trials)
        run.only(("trials", "seed", "p", "interval", "ndig", "samples"))
        return cls(
            trials=run.integer("trials", default_trials, minimum=2),
            seed=run.integer("seed", None, minimum=0),
            p=run.number("p", 0.95, low=0.0, high=1.0, open_low=True, open_high=True),
            interval=run.text("interval", "symmetric", choices=("symmetric", "shortest")),
            ndig=run.integer("ndig", 2, minimum=1),
            samples=run.flag("samples", False),
        )


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
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        msg = str(exc)
        line = col = None
        if "(at line " in msg:
            msg, _, where = msg.partition(" (at line ")
            nums = where.rstrip(")").split(", column ")
            line, col = int(nums[0]), int(nums[1]) if len(nums) > 1 else None
        raise ParseError(f"not valid TOML: {msg}", file=file, line=line, column=col) from None
    source = Source.from_text(text, file, folder)
    top = Fields(source, data)
    known = study_kinds()
    kind = top.text("kind") if "kind" in data else None
    if kind is None:
        raise top.missing(f"missing kind; expected one of {', '.join(known)}", "kind")
    if kind not in known:
        raise top.error(f"unknown kind {kind!r}; expected one of {', '.join(known)}", "kind")
    try:
        return known[kind].load(top)
    except MtmcError as exc:
        if exc.file is not None:
            raise
        # an error of the library below (a distribution, an expression, a graph) that
        # knows no file: it happened while reading this study.
        raise InputError(exc.message, file=file, line=exc.line, field=exc.field) from None


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
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise InputError(
            f"cannot read the study file: {exc.strerror or exc}", file=str(path)
        ) from None
    text = decode_utf8(data, str(path))
    return loads_study(text, file=str(path), folder=p.resolve().parent)
