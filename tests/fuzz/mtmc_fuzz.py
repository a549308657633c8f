"""Hostile input for every file mtmc reads: mutate the shipped files, run the reader or command.

A case is a target (a shipped file and the command or reader that takes it) and a list of
mutations (each an operation name and a seed). :func:`run_case` writes the mutated file in
a copy of ``examples/`` and runs the command in this process; its :class:`Outcome` is one of

- ``ok``: exit 0, no NaN or infinity printed or written;
- ``error``: exit 2 and exactly one line ``mtmc: error: ...`` on stderr (a reader: an
  :class:`~mtmc.errors.MtmcError` whose text is one line);
- ``traceback``: any other exception, exit status or stderr;
- ``warning``: a Python warning (a NumPy floating-point warning) left the code;
- ``nonfinite``: exit 0 with NaN or infinity in the output;
- ``hang``: the case ran past its time limit;
- ``memory``: a ``MemoryError`` (run under a limit on the address space, see :func:`main`).

Run as a script for a campaign with counts by outcome (``make fuzz``)::

    python tests/fuzz/mtmc_fuzz.py --cases 2000 --seed 1
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import random
import re
import shutil
import signal
import sys
import tempfile
import time
import warnings
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
FORMATS = ROOT / "tests" / "reference" / "formats"

# ---------------------------------------------------------------------------------------------
# mutations
# ---------------------------------------------------------------------------------------------

NUMBERS = (
    "0",
    "-1",
    "1e-300",
    "1e308",
    "-1e308",
    "1e30",
    "nan",
    "inf",
    "-inf",
    "1e-30",
    "100000000000000000000",
    "9223372036854775808",
    "3.5",
)
VALUES = (*NUMBERS, '"text"', "true", "[1, 2]", "[]", "{a = 1}", '""', "[[1, 2], [3]]")
_KEYLINE = re.compile(r"^(\s*[A-Za-z0-9_\-\"\.]+\s*=\s*)(.*)$")
_NUMBER = re.compile(r"(?<![\w.])-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?(?![\w.])")
_ARRAY = re.compile(r"\[([^\[\]]+)\]")
_BLOCK = re.compile(r"^\[\[[^\]]+\]\]", re.M)


def _pick(rnd: random.Random, items: list[Any]) -> Any:
    return items[rnd.randrange(len(items))] if items else None


def _keylines(lines: list[str]) -> list[int]:
    return [i for i, s in enumerate(lines) if _KEYLINE.match(s) and not s.lstrip().startswith("#")]


def _bytes_op(op: str, data: bytes, rnd: random.Random) -> bytes | None:
    """The operations on bytes, common to every format (None: not one of them)."""
    if op == "utf16":
        return data.decode("utf-8", "replace").encode("utf-16")
    if op == "bom":
        return b"\xef\xbb\xbf" + data
    if op == "bad_byte":
        i = rnd.randrange(len(data) + 1)
        return data[:i] + rnd.choice([b"\xff", b"\x96", b"\xc3", b"\xe2\x82"]) + data[i:]
    if op == "truncate":
        return data[: rnd.randrange(len(data) + 1)]
    if op == "nul":
        i = rnd.randrange(len(data) + 1)
        return data[:i] + b"\x00" + data[i:]
    if op == "empty":
        return b""
    if op == "crlf":
        return data.replace(b"\n", b"\r\n")
    return None


TOML_OPS = (
    "delete_line",
    "rename_key",
    "retype",
    "number",
    "empty_array",
    "grow_array",
    "grow_block",
    "deep",
    "dup_line",
    "dup_block",
    "utf16",
    "bom",
    "bad_byte",
    "truncate",
    "nul",
)


def mutate_toml(data: bytes, op: str, seed: int, scale: int = 1) -> bytes:
    """``data`` (a TOML file) with one mutation ``op`` drawn with ``seed``.

    ``scale`` multiplies the sizes of grown arrays and blocks.
    """
    rnd = random.Random(seed)
    out = _bytes_op(op, data, rnd)
    if out is not None:
        return out
    text = data.decode("utf-8", "replace")
    lines = text.split("\n")
    keys = _keylines(lines)
    i = _pick(rnd, keys)
    if op == "delete_line" and i is not None:
        del lines[i]
    elif op == "rename_key" and i is not None:
        lines[i] = "zz_" + lines[i].lstrip()
    elif op == "retype" and i is not None:
        m = _KEYLINE.match(lines[i])
        assert m is not None
        lines[i] = m.group(1) + rnd.choice(VALUES)
    elif op == "number":
        spots = list(_NUMBER.finditer(text))
        hit: re.Match[str] | None = _pick(rnd, spots)
        if hit is not None:
            text = text[: hit.start()] + rnd.choice(NUMBERS) + text[hit.end() :]
        return text.encode()
    elif op in ("empty_array", "grow_array"):
        spots = list(_ARRAY.finditer(text))
        m = _pick(rnd, spots)
        if m is not None:
            k = rnd.choice([2, 10, 300]) * scale
            body = "" if op == "empty_array" else ", ".join([m.group(1)] * k)
            text = text[: m.start()] + "[" + body + "]" + text[m.end() :]
        return text.encode()
    elif op in ("grow_block", "dup_block"):
        starts = [b.start() for b in _BLOCK.finditer(text)]
        if starts:
            j = rnd.randrange(len(starts))
            end = starts[j + 1] if j + 1 < len(starts) else len(text)
            block = text[starts[j] : end].rstrip("\n") + "\n"
            k = 1 if op == "dup_block" else rnd.choice([10, 100]) * scale
            text = text[:end] + "\n" + block * k + text[end:]
        return text.encode()
    elif op == "deep":
        n = rnd.choice([400, 2000, 100_000])
        if rnd.random() < 0.5:
            value = "[" * n + "]" * n
        else:
            value = "{a = " * n + "1" + "}" * n
        if i is not None and rnd.random() < 0.5:
            m = _KEYLINE.match(lines[i])
            assert m is not None
            lines[i] = m.group(1) + value
        else:
            lines.insert(0, "zz = " + value)
    elif op == "dup_line" and i is not None:
        lines.insert(i, lines[i])
    return "\n".join(lines).encode()


# hostile numbers: pathological distribution parameters, copula dof, numbers in odd scripts

#: Numbers that Python's float() or parser reads but a file's number is not, and numbers at
#: the ends of the doubles.
ODD_NUMBERS = (
    "1_0",
    "\u0661\u0660",  # Arabic-Indic 10
    "\uff11\uff10",  # fullwidth 10
    "\u0967\u0966",  # Devanagari 10
    "0x10",
    "1e400",
    "1" + "0" * 400,
    "5e-324",
    "-0",
    "1e-320",
    "Infinity",
    "1.5e3.2",
)
#: Distributions whose parameters a reader must refuse or carry: sizes, widths at rounding
#: level, degrees of freedom at the ends of the doubles, components beyond memory.
PATHOLOGICAL_DISTS = (
    "normal(0, 1e300)",
    "normal(1e300, 1)",
    "uniform(1, 1.00000000000001)",
    "uniform(-1e308, 1e308)",
    "normal(0, 5e-324)",
    "normal(0, 1, u_rel_u=1e-200)",
    "normal(0, 1, dof=1e-300)",
    "t(1e-300)",
    "t(1e300, 0, 1)",
    "gamma(1e-300, 1)",
    "gamma(1e300, 1e-300)",
    "exponential(1e-320)",
    "triangular(0, 1e-300, 1e-300)",
    "arcsine(1, 1.0000000000000002)",
    "iid(normal(0, 1), 1e9)",
    "iid(normal(0, 1), 100000000)",
    "type_a([5e-324, 5e-324, 5e-324])",
    "type_a([5e-324, 1e-323, 5e-324])",
    "type_a([1e308, -1e308, 1e308])",
)
#: Degrees of freedom of a t copula: below, at and above what the numerics carry.
COPULA_DOFS = ("1e-300", "1e-3", "0.0999", "0.1", "1e308", "-1", "0", "nan", "inf", '"4"')
NUMBER_OPS = ("odd_digits", "pathological_dist", "copula_dof")
_DIST_TEXT = re.compile(r'"[a-z_]+\([^"\n]*\)"')


def mutate_numbers(data: bytes, op: str, seed: int, _scale: int = 1) -> bytes:
    """``data`` (a TOML or CSV file) with one hostile number ``op`` drawn with ``seed``.

    ``odd_digits`` writes a number of :data:`ODD_NUMBERS` in place of one (bare, in a
    distribution's text, a model or a CSV cell); ``pathological_dist`` puts one of
    :data:`PATHOLOGICAL_DISTS` in place of a distribution's text; ``copula_dof`` gives a
    ``[correlation]`` table a t copula of :data:`COPULA_DOFS` (adding the table over the
    first two inputs where there is none). ``_scale`` is not used (a size of its own).
    """
    rnd = random.Random(seed)
    text = data.decode("utf-8", "replace")
    if op == "odd_digits":
        hit: re.Match[str] | None = _pick(rnd, list(_NUMBER.finditer(text)))
        if hit is not None:
            text = text[: hit.start()] + rnd.choice(ODD_NUMBERS) + text[hit.end() :]
    elif op == "pathological_dist":
        spot: re.Match[str] | None = _pick(rnd, list(_DIST_TEXT.finditer(text)))
        if spot is not None:
            dist = rnd.choice(PATHOLOGICAL_DISTS)
            text = f'{text[: spot.start()]}"{dist}"{text[spot.end() :]}'
    elif op == "copula_dof":
        copula = f'copula = {{kind = "t", dof = {rnd.choice(COPULA_DOFS)}}}'
        if "[correlation]" in text:
            lines = [ln for ln in text.split("\n") if not ln.startswith("copula")]
            at = lines.index("[correlation]") + 1
            text = "\n".join([*lines[:at], copula, *lines[at:]])
        else:
            names = re.findall(r"^(\w+) = \"", text.split("[inputs]", 1)[-1], re.M)[:2]
            if len(names) == 2 and "[inputs]" in text:
                pair = f'pairs = [["{names[0]}", "{names[1]}", 0.5]]'
                text = f"{text.rstrip()}\n\n[correlation]\n{pair}\n{copula}\n"
    return text.encode()


CSV_OPS = (
    "bom",
    "separator",
    "decimal_comma",
    "drop_column",
    "extra_column",
    "drop_header",
    "rename_header",
    "text_cell",
    "few_rows",
    "dup_rows",
    "number",
    "grow_rows",
    "same_rows",
    "blank_lines",
    "utf16",
    "bad_byte",
    "truncate",
    "empty",
    "nul",
    "crlf",
)


def mutate_csv(data: bytes, op: str, seed: int, scale: int = 1) -> bytes:  # noqa: C901
    """``data`` (a CSV file) with one mutation ``op`` drawn with ``seed``."""
    rnd = random.Random(seed)
    out = _bytes_op(op, data, rnd)
    if out is not None:
        return out
    text = data.decode("utf-8", "replace")
    lines = [s for s in text.split("\n") if s != ""]
    body = [i for i, s in enumerate(lines) if not s.startswith("#")]
    head = body[0] if body else None
    rows = body[1:]
    if op == "separator":
        text = text.replace(",", rnd.choice([";", "\t", " ", ", "]))
        return text.encode()
    if op == "decimal_comma":
        return re.sub(r"(\d)\.(\d)", r"\1,\2", text).encode()
    if op in ("drop_column", "extra_column") and body:
        j = rnd.randrange(len(lines[body[0]].split(",")))
        every = rnd.random() < 0.7
        for i in body if every else [_pick(rnd, body)]:
            cells = lines[i].split(",")
            if op == "drop_column" and j < len(cells):
                del cells[j]
            elif op == "extra_column":
                cells.insert(min(j, len(cells)), "7" if i != head else "extra")
            lines[i] = ",".join(cells)
    elif op == "drop_header" and head is not None:
        del lines[head]
    elif op == "rename_header" and head is not None:
        cells = lines[head].split(",")
        j = rnd.randrange(len(cells))
        cells[j] = rnd.choice(["", "zz", cells[(j + 1) % len(cells)], cells[j].upper() + " "])
        lines[head] = ",".join(cells)
    elif op in ("text_cell", "number") and rows:
        i = _pick(rnd, rows)
        cells = lines[i].split(",")
        j = rnd.randrange(len(cells))
        choice = ["abc", "", "1.2.3", "0x10", "1e", "--1", "'1'"] if op == "text_cell" else NUMBERS
        cells[j] = rnd.choice(list(choice))
        lines[i] = ",".join(cells)
    elif op == "few_rows" and head is not None:
        lines = lines[: head + 1] + [lines[i] for i in rows[: rnd.randrange(4)]]
    elif op == "dup_rows" and rows:
        i = _pick(rnd, rows)
        lines.insert(i, lines[i])
    elif op == "grow_rows" and rows:
        k = rnd.choice([10, 100]) * scale
        lines += [lines[i] for i in rows] * k
    elif op == "same_rows" and rows:
        r = lines[_pick(rnd, rows)]
        for i in rows:
            lines[i] = r
    elif op == "blank_lines" and lines:
        lines.insert(rnd.randrange(len(lines) + 1), rnd.choice(["", " ", ",,,", "#"]))
    return ("\n".join(lines) + "\n").encode()


# ---------------------------------------------------------------------------------------------
# targets
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Target:
    """A file mtmc reads and the way to run it.

    Attributes
    ----------
    name : str
        Short name, for counts.
    path : str
        The file, relative to the copy of ``examples/`` (mutated in place for a case).
    kind : str
        ``"toml"`` or ``"csv"``: which mutations apply.
    argv : tuple of str or None
        The CLI arguments (``{file}`` and ``{out}`` filled in); None for a reader.
    reader : str
        For a reader, ``"module:function"`` called with the file's path (and ``args``).
    args : tuple
        Further positional arguments of the reader.
    cost : int
        How many cases of others one case of it is worth (to thin slow ones in a budget).
    """

    name: str
    path: str
    kind: str
    argv: tuple[str, ...] | None = None
    reader: str = ""
    args: tuple[Any, ...] = ()
    cost: int = 1


_RUN = ("run", "{file}", "-n", "20", "--seed", "1", "-q", "-o", "{out}")


def targets() -> list[Target]:
    """Every file kind mtmc reads, each with the command or reader that reads it."""
    out = []
    for f in sorted((EXAMPLES / "studies").glob("*.toml")):
        cost = 3 if f.stem in ("wang2022", "bcs_origin", "aguado2016") else 1
        out.append(Target(f"run:{f.stem}", f"studies/{f.name}", "toml", _RUN, cost=cost))
    for f in sorted((EXAMPLES / "graphs").glob("*.toml")):
        argv = ("graph", "run", "{file}", "-n", "20", "--seed", "1", "--json")
        out.append(Target(f"graph:{f.stem}", f"graphs/{f.name}", "toml", argv))
    sweep = ("--vary", "probe.u_probe=0.001:0.005:3", "--quantity", "d_ac", "-n", "20")
    out += [
        Target(
            "graph-sweep",
            "graphs/bcs_origin.toml",
            "toml",
            ("graph", "sweep", "{file}", *sweep, "--seed", "1", "--json"),
        ),
        Target(
            "verify-simulate",
            "studies/aguado2017.toml",
            "toml",
            ("verify", "simulate", "{file}", "-n", "20", "--seed", "1", "--json"),
            cost=3,
        ),
        Target(
            "verify-plan",
            "studies/aguado2016.toml",
            "toml",
            ("verify", "plan", "{file}", "-o", "{root}/data", "--json"),
        ),
        Target(
            "artefact",
            "artefacts/wang2022_five_ball.toml",
            "toml",
            reader="mtmc.artefact.artefact:load_artefact",
        ),
        Target(
            "assertions",
            "graphs/ball_centre.pl",
            "csv",
            ("graph", "run", "{file}", "-n", "20", "--seed", "1", "--json"),
        ),
        Target(
            "positioning",
            "studies/positioning_x.csv",
            "csv",
            ("positioning", "evaluate", "{file}", "-n", "20", "--seed", "1", "--json"),
        ),
        Target(
            "identify",
            "data/identify.csv",
            "csv",
            ("verify", "identify", "{file}", "--study", "{root}/studies/aguado2017.toml", "--json"),
        ),
        Target("points", "data/points.csv", "csv", ("artefact", "fit", "{file}", "--json")),
        Target("gravity", "data/gravity.csv", "csv", ("artefact", "gravity", "{file}", "--json")),
        Target(
            "comp:isg",
            "data/isg.txt",
            "csv",
            reader="mtmc.verification.compensation:load_compensation",
            args=("isg",),
        ),
        Target(
            "comp:etalon",
            "data/etalon.txt",
            "csv",
            reader="mtmc.verification.compensation:load_compensation",
            args=("etalon",),
        ),
        Target(
            "comp:csv",
            "data/comp.csv",
            "csv",
            reader="mtmc.verification.compensation:load_compensation",
            args=("csv",),
        ),
    ]
    return out


def make_tree(root: Path) -> None:
    """A copy of ``examples/`` under ``root``, with the data files the CSV targets read."""
    import numpy as np

    from mtmc.graph import assertions, load_graph
    from mtmc.study import load_study
    from mtmc.verification.compensation import compensation_table, dumps_plain_csv

    for sub in ("studies", "graphs", "artefacts"):
        shutil.copytree(EXAMPLES / sub, root / sub)
    data = root / "data"
    data.mkdir()
    graph = load_graph(EXAMPLES / "graphs" / "ball_centre.toml")
    (root / "graphs" / "ball_centre.pl").write_text(assertions.dumps_assertions(graph))
    st: Any = getattr(load_study(EXAMPLES / "studies" / "aguado2017.toml"), "study")  # noqa: B009
    ver = st.verification()
    x = ver.readings()
    rows = ["# commanded X Y Z (mm), tracker readings (mm)", "X,Y,Z,x_lt,y_lt,z_lt"]
    rows += [",".join(f"{v:.6f}" for v in (*q, *p)) for q, p in zip(ver.q, x, strict=True)]
    (data / "identify.csv").write_text("\n".join(rows) + "\n")
    rng = np.random.default_rng(1)
    d = rng.normal(size=(25, 3))
    d[:, 2] = np.abs(d[:, 2])
    pts = 10.0 + 12.7 * d / np.linalg.norm(d, axis=1, keepdims=True)
    (data / "points.csv").write_text(
        "x,y,z\n" + "\n".join(",".join(f"{v:.6f}" for v in p) for p in pts) + "\n"
    )
    (data / "gravity.csv").write_text(
        "orientation,ball,x,y,z\nH,1,0,0,0\nH,2,100,0,0\nV,1,0.003,0,0.004\nV,2,100,-0.001,0\n"
        "O,1,0.001,0.002,0\nO,2,100.002,0,0.001\n"
    )
    shutil.copy(FORMATS / "isg_csv_example.txt", data / "isg.txt")
    shutil.copy(FORMATS / "etalon_exchange_example.txt", data / "etalon.txt")
    grid = {ax: np.linspace(0.0, 1000.0, 6) for ax in "XYZ"}
    table = compensation_table(st.truth, grid)
    (data / "comp.csv").write_text(dumps_plain_csv(table))


# ---------------------------------------------------------------------------------------------
# running one case
# ---------------------------------------------------------------------------------------------

OUTCOMES = ("ok", "error", "traceback", "warning", "nonfinite", "hang", "memory")
_NONFINITE = re.compile(r"(?<![\\\w])(nan|inf|infinity)(?!\w)", re.I)


def _nonfinite_json(text: str) -> bool:
    """Whether a JSON text holds NaN or an infinity (written bare, as Python's json does)."""
    found: list[str] = []
    json.loads(text, parse_constant=found.append)
    return bool(found)


class _Timeout(BaseException):
    """Raised by the alarm of a case that runs too long (not an Exception: nothing catches it)."""


@contextlib.contextmanager
def _time_limit(seconds: float) -> Iterator[None]:
    def _raise(*_: Any) -> None:
        raise _Timeout

    previous = signal.signal(signal.SIGALRM, _raise)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


@dataclass(frozen=True)
class Outcome:
    """What one case did: its kind (one of :data:`OUTCOMES`) and a line of detail."""

    kind: str
    detail: str = ""


def _call(target: Target, file: Path, root: Path, out: Path) -> tuple[int, str, str]:
    """Run the target on ``file``: (exit status, stdout, stderr)."""
    if target.argv is None:
        import importlib

        from mtmc.errors import MtmcError

        module, name = target.reader.split(":")
        fn: Callable[..., Any] = getattr(importlib.import_module(module), name)
        try:
            fn(file, *target.args)
        except MtmcError as exc:
            return 2, "", f"mtmc: error: {exc}\n"
        return 0, "", ""
    from mtmc.cli.main import main

    argv = [a.format(file=file, out=out, root=root) for a in target.argv]
    o, e = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(o), contextlib.redirect_stderr(e):
        rc = main(argv)
    stdout = o.getvalue()
    if (out / "result.json").is_file() and _nonfinite_json((out / "result.json").read_text()):
        stdout += "\nresult.json: NaN"
    return rc, stdout, e.getvalue()


def run_case(target: Target, data: bytes, root: Path, timeout: float = 60.0) -> Outcome:
    """Write ``data`` as the target's file under ``root`` and classify what the target did."""
    file = root / target.path
    original = file.read_bytes() if file.exists() else None
    file.write_bytes(data)
    out = Path(tempfile.mkdtemp(dir=root, prefix="out-"))
    shutil.rmtree(out)
    try:
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            try:
                with _time_limit(timeout):
                    rc, stdout, stderr = _call(target, file, root, out)
            except _Timeout:
                return Outcome("hang", f"over {timeout:g} s")
            except MemoryError as exc:
                return Outcome("memory", repr(exc)[:200])
            except Exception as exc:  # a traceback: what is counted
                tb = exc.__traceback__
                while tb is not None and tb.tb_next is not None:
                    tb = tb.tb_next
                where = f"{tb.tb_frame.f_code.co_filename}:{tb.tb_lineno}" if tb else ""
                where = where.split("/src/")[-1]
                return Outcome("traceback", f"{type(exc).__name__}: {str(exc)[:150]} @ {where}")
        leaked = [w for w in seen if not issubclass(w.category, (DeprecationWarning,))]
        if leaked:
            w = leaked[0]
            where = str(w.filename).split("/src/")[-1]
            return Outcome("warning", f"{w.category.__name__}: {str(w.message)[:120]} @ {where}")
        if rc == 2:
            lines = stderr.splitlines()
            if len(lines) == 1 and lines[0].startswith("mtmc: error: "):
                return Outcome("error", lines[0][:200])
            return Outcome("traceback", f"exit 2 with {len(lines)} lines: {stderr[:200]!r}")
        if rc != 0:
            return Outcome("traceback", f"exit {rc}: {stderr[-200:]!r}")
        m = _NONFINITE.search(stdout)
        if m:
            return Outcome("nonfinite", stdout[max(0, m.start() - 80) : m.end() + 20])
        return Outcome("ok")
    finally:
        shutil.rmtree(out, ignore_errors=True)
        if original is None:
            file.unlink(missing_ok=True)
        else:
            file.write_bytes(original)


def mutate(target: Target, data: bytes, ops: list[tuple[str, int]], scale: int = 1) -> bytes:
    """``data`` with each mutation of ``ops`` in turn."""
    fn = mutate_toml if target.kind == "toml" else mutate_csv
    for op, seed in ops:
        data = (mutate_numbers if op in NUMBER_OPS else fn)(data, op, seed, scale)
    return data


def ops_for(target: Target) -> tuple[str, ...]:
    """The mutations that apply to the target's format."""
    return (*TOML_OPS, *NUMBER_OPS) if target.kind == "toml" else (*CSV_OPS, "odd_digits")


# ---------------------------------------------------------------------------------------------
# a campaign
# ---------------------------------------------------------------------------------------------


def campaign(cases: int, seed: int, timeout: float, scale: int, show: int) -> Counter[str]:
    """Run ``cases`` random cases; print the counts by outcome and the failures."""
    rnd = random.Random(seed)
    counts: Counter[str] = Counter()
    failures: Counter[tuple[str, str, str]] = Counter()
    with tempfile.TemporaryDirectory(prefix="mtmc-fuzz-") as tmp:
        root = Path(tmp)
        make_tree(root)
        tlist = targets()
        weights = [1.0 / t.cost for t in tlist]
        t0 = time.monotonic()
        for n in range(cases):
            target = rnd.choices(tlist, weights)[0]
            k = 1 if rnd.random() < 0.8 else 2
            ops = [(rnd.choice(ops_for(target)), rnd.randrange(2**32)) for _ in range(k)]
            data = mutate(target, (root / target.path).read_bytes(), ops, scale)
            res = run_case(target, data, root, timeout)
            counts[res.kind] += 1
            if res.kind not in ("ok", "error"):
                key = (res.kind, target.name, re.sub(r"\d+", "N", res.detail)[:160])
                if failures[key] == 0 and show:
                    print(f"[{n}] {res.kind} {target.name} {ops}: {res.detail}", flush=True)
                failures[key] += 1
        took = time.monotonic() - t0
    print(f"{cases} cases in {took:.0f} s: " + ", ".join(f"{k} {counts[k]}" for k in OUTCOMES))
    for (kind, name, detail), c in failures.most_common():
        print(f"{c:5d} {kind:10s} {name:22s} {detail}")
    return counts


def main(argv: list[str] | None = None) -> int:
    """Run a campaign (``--cases``, ``--seed``, ``--timeout``, ``--scale``, ``--memory`` GiB)."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cases", type=int, default=500)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--timeout", type=float, default=60.0)
    p.add_argument("--scale", type=int, default=1, help="multiplies the sizes of grown arrays")
    p.add_argument("--memory", type=float, default=4.0, help="address-space limit, GiB")
    p.add_argument("--quiet", action="store_true", help="counts only")
    a = p.parse_args(argv)
    import resource

    lim = int(a.memory * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (lim, lim))
    counts = campaign(a.cases, a.seed, a.timeout, a.scale, 0 if a.quiet else 1)
    bad = sum(counts[k] for k in OUTCOMES if k not in ("ok", "error"))
    print(json.dumps({"cases": a.cases, **{k: counts[k] for k in OUTCOMES}}))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
