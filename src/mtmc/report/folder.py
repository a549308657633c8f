"""A result folder read and checked: the one reader of ``mtmc.load_result`` and ``mtmc report``.

A result folder may come from anywhere (an archive someone sent, a disk shared with
others), so nothing in it is trusted before it is checked: :func:`read_folder` reads
only regular files that lie inside the folder (a link to outside, a FIFO, a device or a
folder where a file belongs is refused, never opened), reads JSON within limits
(:func:`mtmc.io.loads_json`: size, nesting, digits, only finite numbers), compares every
``samples/*.npy`` with its header before reading it (a header cannot ask for more memory
than its file holds), and checks ``result.json`` against ``docs/results-format.md``: the
format version, the keys every result has and their types, ``u ≥ 0``, ``trials ≥ 1``,
``0 < p < 1``, and arrays of the lengths they must have. Whatever it returns can be turned
into a :class:`~mtmc.study.result.StudyResult` and drawn as a report; whatever it refuses is
one :class:`~mtmc.errors.InputError` naming the file and the field.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mtmc.errors import InputError
from mtmc.io import decode_utf8, loads_json

__all__ = ["RESULT_FORMAT", "ResultFolder", "read_folder"]

#: The version of ``result.json`` this mtmc writes and reads.
RESULT_FORMAT = "mtmc-result/1"
#: The largest JSON file of a result folder that is read (a verification's fields and a
#: positioning test's readings are some megabytes).
MAX_JSON_BYTES = 256 * 2**20
#: The most trials a result may state (the engine's own limit is far below).
MAX_TRIALS = 10**12


@dataclass(frozen=True)
class ResultFolder:
    """What a result folder holds, checked.

    Attributes
    ----------
    result : dict
        ``result.json``.
    provenance : dict or None
        ``provenance.json``, where the folder has one.
    samples : dict of str to ndarray
        ``samples/NAME.npy`` by name (read-only), where asked for.
    """

    result: dict[str, Any]
    provenance: dict[str, Any] | None
    samples: dict[str, np.ndarray[Any, Any]] = field(default_factory=dict)


def _regular(folder: Path, path: Path) -> bool:
    """Whether ``path`` is a regular file inside ``folder``; False if it is absent.

    Raises
    ------
    InputError
        For a link that leads outside the folder, or anything but a regular file.
    """
    try:
        lmode = os.lstat(path).st_mode
    except FileNotFoundError:
        return False
    except OSError as exc:
        raise InputError(f"cannot read {path.name}: {exc.strerror}", file=str(path)) from None
    if stat.S_ISLNK(lmode):
        real = Path(os.path.realpath(path))
        if not real.is_relative_to(Path(os.path.realpath(folder))):
            raise InputError(
                f"{path.name} is a link to {real}, outside the result folder; "
                "a result folder holds its own files",
                file=str(path),
            )
    try:
        mode = os.stat(path).st_mode
    except OSError as exc:
        raise InputError(f"cannot read {path.name}: {exc.strerror}", file=str(path)) from None
    if not stat.S_ISREG(mode):
        raise InputError(f"{path.name} is {_what(mode)}, expected a regular file", file=str(path))
    return True


def _what(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a FIFO"
    return "a device or special file"


def _json(folder: Path, name: str) -> dict[str, Any] | None:
    path = folder / name
    if not _regular(folder, path):
        return None
    size = path.stat().st_size
    if size > MAX_JSON_BYTES:
        raise InputError(
            f"{name} is {size} bytes; a result's JSON is at most {MAX_JSON_BYTES}", file=str(path)
        )
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(f"cannot read {name}: {exc.strerror or exc}", file=str(path)) from None
    doc = loads_json(decode_utf8(data, str(path)), str(path))
    if not isinstance(doc, dict):
        raise InputError("expected a JSON object", file=str(path))
    return doc


class _Check:
    """The checks of ``result.json``, each naming the file and the field it refuses."""

    def __init__(self, file: str) -> None:
        self.file = file

    def fail(self, where: str, expected: str, got: Any) -> InputError:
        shown = repr(got)
        shown = shown if len(shown) <= 60 else shown[:57] + "..."
        return InputError(
            f"not an mtmc result: expected {expected}, got {shown} (docs/results-format.md)",
            file=self.file,
            field=where,
        )

    def obj(self, d: Any, where: str, keys: tuple[str, ...] = ()) -> dict[str, Any]:
        if not isinstance(d, dict):
            raise self.fail(where, "a JSON object", d)
        for k in keys:
            if k not in d:
                raise InputError(
                    f"not an mtmc result: no {k!r} where a result needs one "
                    "(docs/results-format.md)",
                    file=self.file,
                    field=f"{where}.{k}" if where else k,
                )
        return d

    def seq(self, d: Any, where: str, n: int | None = None) -> list[Any]:
        if not isinstance(d, list):
            raise self.fail(where, "an array", d)
        if n is not None and len(d) != n:
            raise self.fail(where, f"an array of {n}", f"{len(d)} values")
        return d

    def text(self, d: Any, where: str) -> str:
        if not isinstance(d, str):
            raise self.fail(where, "a string", d)
        return d

    def number(
        self, d: Any, where: str, *, low: float | None = None, null: bool = False
    ) -> float | None:
        if d is None and null:
            return None
        if isinstance(d, bool) or not isinstance(d, int | float):
            raise self.fail(where, "a number", d)
        if low is not None and d < low:
            raise self.fail(where, f"a number >= {low}", d)
        return float(d)

    def integer(self, d: Any, where: str, low: int, high: int, *, null: bool = False) -> None:
        if d is None and null:
            return
        if isinstance(d, bool) or not isinstance(d, int) or not low <= d <= high:
            raise self.fail(where, f"an integer from {low} to {high}", d)

    def integers(self, d: Any, where: str, low: int, high: int) -> int:
        """An array of integers from ``low`` to ``high``; its length."""
        for i, x in enumerate(self.seq(d, where)):
            self.integer(x, f"{where}[{i}]", low, high)
        return len(d)

    def probability(self, d: Any, where: str) -> None:
        if isinstance(d, bool) or not isinstance(d, int | float) or not 0 < d < 1:
            raise self.fail(where, "a probability 0 < p < 1", d)

    def numbers(self, d: Any, where: str, n: int | None = None, *, null: bool = False) -> int:
        """An array of numbers (``null`` for a non-finite one, where allowed); its length."""
        for i, x in enumerate(self.seq(d, where, n)):
            self.number(x, f"{where}[{i}]", null=null)
        return len(d)

    def matrix(self, d: Any, where: str, cols: int, rows: int | None = None) -> int:
        for i, row in enumerate(self.seq(d, where, rows)):
            self.numbers(row, f"{where}[{i}]", cols)
        return len(d)


def _quantity(c: _Check, q: Any, where: str) -> None:
    keys = ("name", "unit", "monte_carlo", "gum", "validation", "budget", "histogram")
    c.obj(q, where, (*keys, "convergence", "reported"))
    c.text(q["name"], f"{where}.name")
    c.text(q["unit"], f"{where}.unit")
    mc = c.obj(q["monte_carlo"], f"{where}.monte_carlo", ("estimate", "u", "U", "p", "trials"))
    c.number(mc["estimate"], f"{where}.monte_carlo.estimate", null=True)
    c.number(mc["u"], f"{where}.monte_carlo.u", low=0, null=True)
    c.number(mc["U"], f"{where}.monte_carlo.U", low=0, null=True)
    c.probability(mc["p"], f"{where}.monte_carlo.p")
    c.integer(mc["trials"], f"{where}.monte_carlo.trials", 1, MAX_TRIALS)
    for key in ("shortest", "symmetric"):
        if key in mc:
            c.numbers(mc[key], f"{where}.monte_carlo.{key}", 2, null=True)
    if q["gum"] is not None:
        gum = c.obj(q["gum"], f"{where}.gum", ("estimate", "u"))
        c.number(gum["estimate"], f"{where}.gum.estimate", null=True)
        c.number(gum["u"], f"{where}.gum.u", low=0, null=True)
    if q["validation"] is not None:
        c.obj(q["validation"], f"{where}.validation")
    for i, b in enumerate(c.seq(q["budget"], f"{where}.budget")):
        line = c.obj(b, f"{where}.budget[{i}]", ("name",))
        c.text(line["name"], f"{where}.budget[{i}].name")
        for key in ("u", "contribution", "share"):
            if key in line:
                c.number(line[key], f"{where}.budget[{i}].{key}", low=0, null=True)
    hist = c.obj(q["histogram"], f"{where}.histogram", ("edges", "density"))
    n_edges = c.numbers(hist["edges"], f"{where}.histogram.edges")
    c.numbers(hist["density"], f"{where}.histogram.density", max(n_edges - 1, 0))
    conv = c.obj(q["convergence"], f"{where}.convergence", ("m", "estimate", "u"))
    n = c.integers(conv["m"], f"{where}.convergence.m", 1, mc["trials"])
    c.numbers(conv["estimate"], f"{where}.convergence.estimate", n, null=True)
    c.numbers(conv["u"], f"{where}.convergence.u", n, null=True)
    rep = c.obj(q["reported"], f"{where}.reported", ("estimate", "U"))
    c.text(rep["estimate"], f"{where}.reported.estimate")
    c.text(rep["U"], f"{where}.reported.U")


def _region(c: _Check, r: Any, where: str) -> None:
    c.obj(r, where, ("name", "labels", "unit", "centre", "cov", "k", "k_chi2", "p"))
    c.obj(r, where, ("semi_axes", "axes", "scatter"))
    c.text(r["name"], f"{where}.name")
    c.text(r["unit"], f"{where}.unit")
    for i, label in enumerate(c.seq(r["labels"], f"{where}.labels", 2)):
        c.text(label, f"{where}.labels[{i}]")
    c.numbers(r["centre"], f"{where}.centre", 2)
    c.matrix(r["cov"], f"{where}.cov", 2, 2)
    c.numbers(r["semi_axes"], f"{where}.semi_axes", 2)
    c.matrix(r["axes"], f"{where}.axes", 2, 2)
    c.matrix(r["scatter"], f"{where}.scatter", 2)
    c.number(r["k"], f"{where}.k", low=0)
    c.number(r["k_chi2"], f"{where}.k_chi2", low=0)
    c.probability(r["p"], f"{where}.p")


def _table(c: _Check, t: Any, where: str) -> None:
    c.obj(t, where, ("name", "title", "columns", "rows"))
    c.text(t["name"], f"{where}.name")
    c.text(t["title"], f"{where}.title")
    cols = c.seq(t["columns"], f"{where}.columns")
    for i, col in enumerate(cols):
        c.text(col, f"{where}.columns[{i}]")
    for i, row in enumerate(c.seq(t["rows"], f"{where}.rows")):
        for j, x in enumerate(c.seq(row, f"{where}.rows[{i}]", len(cols))):
            if x is not None and (isinstance(x, list | dict)):
                raise c.fail(f"{where}.rows[{i}][{j}]", "a number, a string or null", x)


def _field(c: _Check, f: Any, where: str) -> None:
    keys = ("name", "title", "points", "values", "unit", "labels", "axes", "magnification")
    c.obj(f, where, keys)
    for key in ("name", "title", "unit"):
        c.text(f[key], f"{where}.{key}")
    n = c.matrix(f["points"], f"{where}.points", 3)
    values = c.seq(f["values"], f"{where}.values", n)
    for i, v in enumerate(values):
        if isinstance(v, list):
            c.numbers(v, f"{where}.values[{i}]", 3, null=True)
        else:
            c.number(v, f"{where}.values[{i}]", null=True)
    for i, label in enumerate(c.seq(f["labels"], f"{where}.labels")):
        c.text(label, f"{where}.labels[{i}]")
    for i, axis in enumerate(c.seq(f["axes"], f"{where}.axes", 3)):
        c.text(axis, f"{where}.axes[{i}]")
    c.number(f["magnification"], f"{where}.magnification", null=True)


def check_result(doc: Mapping[str, Any], file: str) -> None:
    """Check ``result.json`` against ``docs/results-format.md``.

    Parameters
    ----------
    doc : mapping
        The content of ``result.json``.
    file : str
        Its path, for the message.

    Raises
    ------
    InputError
        Naming the file and the first field that is missing or not what it must be.
    """
    c = _Check(file)
    fmt = doc.get("format")
    if fmt != RESULT_FORMAT:
        raise InputError(
            f"expected an mtmc result (format {RESULT_FORMAT}), got format {fmt!r}",
            file=file,
            field="format",
        )
    c.obj(doc, "", ("kind", "title", "study_file", "study_sha256", "seed", "trials", "p"))
    for key in ("kind", "title", "study_file", "study_sha256"):
        c.text(doc[key], key)
    c.integer(doc["seed"], "seed", 0, 2**256, null=True)
    c.integer(doc["trials"], "trials", 1, MAX_TRIALS)
    c.probability(doc["p"], "p")
    parts = (
        ("quantities", _quantity),
        ("regions", _region),
        ("tables", _table),
        ("fields", _field),
    )
    for key, check in parts:
        for i, item in enumerate(c.seq(doc.get(key, []), key)):
            check(c, item, f"{key}[{i}]")
    for i, x in enumerate(c.seq(doc.get("inputs", []), "inputs")):
        c.obj(x, f"inputs[{i}]", ("name",))
        c.text(x["name"], f"inputs[{i}].name")
        if isinstance(x.get("u"), list):  # a vector input: u per component
            for k, u in enumerate(x["u"]):
                c.number(u, f"inputs[{i}].u[{k}]", low=0, null=True)
        elif "u" in x:
            c.number(x["u"], f"inputs[{i}].u", low=0, null=True)
    run = doc.get("run")
    if run is not None:
        c.obj(run, "run")
        c.integer(run.get("trials", doc["trials"]), "run.trials", 1, MAX_TRIALS)
        c.integer(run.get("omitted", 0), "run.omitted", 0, doc["trials"] - 1)
    if "warnings" in doc:
        for i, w in enumerate(c.seq(doc["warnings"], "warnings")):
            c.text(w, f"warnings[{i}]")


def _npy(folder: Path, path: Path, trials: int, omitted: int, load: bool) -> Any:
    """The samples of one ``.npy`` (or None where not loaded), its header checked first."""
    if not _regular(folder, path):
        return None
    with open(path, "rb") as fh:
        try:
            version = np.lib.format.read_magic(fh)
            read = (
                np.lib.format.read_array_header_1_0
                if version == (1, 0)
                else np.lib.format.read_array_header_2_0
            )
            shape, _, dtype = read(fh, max_header_size=10_000)
        except (ValueError, SyntaxError, OSError, EOFError) as exc:
            raise InputError(f"not a NumPy .npy file: {exc}", file=str(path)) from None
        offset = fh.tell()
    if dtype.kind != "f" or dtype.hasobject:
        raise InputError(f"samples of dtype {dtype}, expected floating point", file=str(path))
    if len(shape) not in (1, 2) or not shape[0] or (len(shape) == 2 and not 1 <= shape[1] <= 64):
        raise InputError(f"samples of shape {shape}, expected (M,) or (M, d)", file=str(path))
    if shape[0] not in (trials, trials - omitted):
        raise InputError(
            f"{shape[0]} samples; the result ran {trials} trials"
            + (f" ({omitted} omitted)" if omitted else ""),
            file=str(path),
        )
    need = offset + int(np.prod(shape)) * dtype.itemsize
    size = path.stat().st_size
    if size != need:
        raise InputError(
            f"{size} bytes where its header {shape} {dtype} needs {need}", file=str(path)
        )
    if not load:
        return None
    try:
        arr = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as exc:
        raise InputError(f"cannot read the samples: {exc}", file=str(path)) from None
    arr.setflags(write=False)
    return arr


def read_folder(folder: str | os.PathLike[str], *, samples: bool = True) -> ResultFolder:
    """Read and check a result folder (``docs/results-format.md``).

    Parameters
    ----------
    folder : path-like
        The result folder; a link to a folder is followed.
    samples : bool
        Read ``samples/*.npy`` (their headers and sizes are checked either way).

    Returns
    -------
    ResultFolder
        ``result.json``, ``provenance.json`` and the samples, checked.

    Raises
    ------
    InputError
        Naming the file (and the field): no ``result.json``; a file that is a link to
        outside the folder, a FIFO, a device or a folder; JSON that is not UTF-8, not
        JSON, too large or too deep; a ``result.json`` not of the documented form; a
        ``.npy`` whose header does not match its size or the result's trials.
    """
    d = Path(folder)
    if not d.is_dir():
        raise InputError("not a result folder: no such folder", file=str(d))
    result = _json(d, "result.json")
    if result is None:
        raise InputError("not a result folder: it has no result.json", file=str(d))
    check_result(result, str(d / "result.json"))
    provenance = _json(d, "provenance.json")
    run = result.get("run") or {}
    trials, omitted = int(result["trials"]), int(run.get("omitted", 0))
    arrays: dict[str, np.ndarray[Any, Any]] = {}
    sdir = d / "samples"
    if os.path.lexists(sdir):
        if not os.path.realpath(sdir).startswith(os.path.realpath(d) + os.sep) or not sdir.is_dir():
            raise InputError("samples is not a folder inside the result folder", file=str(sdir))
        for f in sorted(sdir.glob("*.npy")):
            arr = _npy(d, f, trials, omitted, samples)
            if arr is not None:
                arrays[f.stem] = arr
    return ResultFolder(result, provenance, arrays)
