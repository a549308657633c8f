"""A positioning test of ISO 230-2: targets, runs in both directions, deviations; the CSV reader.

A test approaches each target position ``P_i`` (``i = 1 … m``) ``n`` times in each
direction (runs ``j = 1 … n``, ↑ the positive and ↓ the negative direction) and records
the positional deviation ``x_ij = P_ij - P_i``: the actual position reached minus the
target. :class:`PositioningTest` holds them as an array of shape ``(m, n, 2)``, the last
axis the direction (0: ↑, 1: ↓).

Units: the deviations stay in the unit of the test (``unit``: µm by default, or mm for a
linear axis; arcseconds or µrad for a rotary axis), since every parameter of ISO 230-2 is
stated in it; targets are in mm (deg for a rotary axis).

The CSV file (:func:`load_positioning_csv`) has one row per reading under the header
``target,run,direction,deviation`` (``columns`` maps other names, a vendor's export);
``direction`` is one of the words of :data:`DIRECTION_WORDS` (``+``/``-``, ``up``/``down``,
``Forward``/``Reverse``, ``fwd``/``bwd``, ``1``/``-1``, …; case-insensitive), or of the
``directions`` mapping given; other columns are ignored; lines starting with ``#`` are
comments; the separator is a comma, a semicolon or a tab.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from mtmc.csvtable import CsvTable, read_csv, read_pairs, read_units
from mtmc.document import MAX_DEG, MAX_MM, MAX_RAD, read_text
from mtmc.errors import InputError

__all__ = [
    "COLUMNS",
    "DEVIATION_UNITS",
    "DIRECTION_WORDS",
    "PositioningTest",
    "load_positioning_csv",
    "loads_positioning_csv",
    "parse_directions",
    "parse_units",
    "reading_times",
]

#: The columns of a positioning CSV file, as :func:`load_positioning_csv` names them.
COLUMNS = ("target", "run", "direction", "deviation")
#: Deviation units by the unit of the targets: mm (linear axis), deg (rotary axis).
DEVIATION_UNITS: Mapping[str, tuple[str, ...]] = {
    "mm": ("um", "mm"),
    "deg": ("arcsec", "urad"),
}
#: The words of the positive (``up``) and negative (``down``) direction that a file may use
#: without a ``directions`` mapping (compared case-insensitively): the signs, arrows and
#: numbers, and the words of the common laser and controller exports.
DIRECTION_WORDS: Mapping[str, tuple[str, ...]] = {
    "up": ("+", "+1", "1", "↑", "up", "pos", "positive", "forward", "fwd", "fw", "f"),
    "down": (
        "-",
        "−",
        "-1",
        "−1",
        "↓",
        "down",
        "neg",
        "negative",
        "reverse",
        "rev",
        "backward",
        "bwd",
        "bw",
        "back",
        "b",
        "r",
    ),
}
_SIDES = {"up": 0, "down": 1, "+": 0, "-": 1, "↑": 0, "↓": 1}
_DIRECTIONS = {w: _SIDES[side] for side, words in DIRECTION_WORDS.items() for w in words}


def parse_directions(
    mapping: str | Mapping[str, str] | None, field: str = "directions"
) -> dict[str, int]:
    """The direction of each word a file may use: the defaults and ``mapping`` over them.

    Parameters
    ----------
    mapping : str, mapping or None
        The file's words: ``{"Hin": "up", "Rück": "down"}`` or the text
        ``"Hin=up,Rück=down"``; each side ``up`` (or ``+``, ``↑``) or ``down`` (``-``,
        ``↓``). A word given here takes the place of the same word of
        :data:`DIRECTION_WORDS`.
    field : str
        The field named in an error.

    Returns
    -------
    dict of str to int
        Lower-case word to 0 (↑) or 1 (↓).

    Examples
    --------
    >>> d = parse_directions("Hin=up,Rück=down")
    >>> d["hin"], d["rück"], d["forward"], d["-1"]
    (0, 1, 0, 1)

    Raises
    ------
    InputError
        On a pair that is not ``WORD=up`` or ``WORD=down``.
    """
    out = dict(_DIRECTIONS)
    if mapping is None:
        return out
    pairs: list[tuple[str, str]]
    if isinstance(mapping, str):
        pairs = read_pairs(mapping, field, "WORD=up or WORD=down", "Forward=up")
    else:
        pairs = [(str(k), str(v)) for k, v in mapping.items()]
    for word, side in pairs:
        w, sd = word.strip().lower(), side.strip().lower()
        if not w or sd not in _SIDES:
            raise InputError(
                f"expected WORD=up or WORD=down (the positive or the negative direction), "
                f"got {word.strip()!r} = {side.strip()!r}",
                field=field,
            )
        out[w] = _SIDES[sd]
    return out


def parse_units(text: str) -> tuple[str, str]:
    """The units ``(target, deviation)`` of ``"mm,um"``, ``"um"``, ``"deg,arcsec"``, ``"urad"``.

    One unit alone is that of the deviations; the targets are then in mm (``um``,
    ``mm``) or deg (``arcsec``, ``urad``).

    Examples
    --------
    >>> parse_units("um"), parse_units("deg,urad")
    (('mm', 'um'), ('deg', 'urad'))

    Raises
    ------
    InputError
        On an unknown unit or a deviation unit that does not go with the target unit.
    """
    return read_units(text, DEVIATION_UNITS, ("TARGET", "DEVIATION"))


@dataclass(frozen=True, eq=False)
class PositioningTest:
    """The readings of a positioning test (ISO 230-2): ``m`` targets, ``n`` runs, ↑ and ↓.

    Parameters
    ----------
    targets : array_like, shape (m,)
        Target positions ``P_i``, strictly increasing, in ``target_unit``.
    deviations : array_like, shape (m, n, 2)
        Positional deviations ``x_ij`` (actual minus target) in ``unit``:
        ``deviations[i, j, 0]`` of run ``j`` in the positive direction (↑),
        ``deviations[i, j, 1]`` in the negative direction (↓).
    unit : str, default "um"
        Unit of the deviations (``um``, ``mm``; ``arcsec``, ``urad`` for a rotary axis).
    target_unit : str, default "mm"
        Unit of the targets (``mm``; ``deg`` for a rotary axis).
    runs : tuple of int, optional
        The labels of the runs as the file gives them (default ``1 … n``).
    source : str, default "<test>"
        Where the readings come from (a file name), for messages.

    Raises
    ------
    InputError
        On shapes that do not fit, fewer than two targets or two runs, targets not
        strictly increasing, values that are not finite, units that do not go together.
    """

    targets: NDArray[np.float64]
    deviations: NDArray[np.float64]
    unit: str = "um"
    target_unit: str = "mm"
    runs: tuple[int, ...] = ()
    source: str = "<test>"

    def __post_init__(self) -> None:
        if self.unit not in DEVIATION_UNITS.get(self.target_unit, ()):
            parse_units(f"{self.target_unit},{self.unit}")  # raises, naming the known units
        p = np.array(self.targets, dtype=np.float64)
        x = np.array(self.deviations, dtype=np.float64)
        if p.ndim != 1 or p.size < 2:
            raise InputError(
                f"expected at least two target positions, shape (m,), got shape {p.shape}",
                file=self.source,
                field="target",
            )
        if x.ndim != 3 or x.shape[0] != p.size or x.shape[2] != 2 or x.shape[1] < 2:
            raise InputError(
                f"expected deviations of shape (m, n, 2) with m = {p.size} targets and "
                f"n >= 2 runs, got shape {x.shape}",
                file=self.source,
                field="deviation",
            )
        if not (np.all(np.isfinite(p)) and np.all(np.isfinite(x))):
            raise InputError("expected finite targets and deviations", file=self.source)
        if np.any(np.diff(p) <= 0):
            raise InputError(
                "expected strictly increasing target positions", file=self.source, field="target"
            )
        runs = tuple(int(r) for r in self.runs) or tuple(range(1, x.shape[1] + 1))
        if len(runs) != x.shape[1]:
            raise InputError(
                f"expected {x.shape[1]} run labels, got {len(runs)}", file=self.source, field="run"
            )
        p.setflags(write=False)
        x.setflags(write=False)
        object.__setattr__(self, "targets", p)
        object.__setattr__(self, "deviations", x)
        object.__setattr__(self, "runs", runs)

    @property
    def m(self) -> int:
        """Number of target positions ``m``."""
        return int(self.targets.size)

    @property
    def n(self) -> int:
        """Number of runs ``n`` in each direction."""
        return int(self.deviations.shape[1])

    @property
    def rotary(self) -> bool:
        """Whether the axis is rotary (targets in degrees)."""
        return self.target_unit == "deg"


def reading_times(m: int, n: int) -> NDArray[np.float64]:
    """When each reading of the standard test cycle is taken, as a fraction of the test.

    The standard test cycle of ISO 230-2 runs up through the targets ``P_1 … P_m``, then
    down through ``P_m … P_1``, ``n`` times. The reading at target ``i`` of run ``j`` is
    the ``k``-th of the ``2 m n`` readings, ``k = 2 m j + i`` up and
    ``k = 2 m j + m + (m - 1 - i)`` down (0-based ``i``, ``j``), at the fraction
    ``τ = k / (2 m n - 1)`` of the test.

    Returns
    -------
    ndarray, shape (m, n, 2)
        ``τ`` in [0, 1], laid out as :attr:`PositioningTest.deviations`.

    Examples
    --------
    >>> reading_times(2, 1)[:, 0, :].tolist()
    [[0.0, 1.0], [0.3333333333333333, 0.6666666666666666]]
    """
    i = np.arange(m)[:, None]
    j = np.arange(n)[None, :]
    up = 2 * m * j + i
    down = 2 * m * j + m + (m - 1 - i)
    return np.stack([up, down], axis=-1).astype(np.float64) / (2 * m * n - 1)


#: The largest size of a run number (a test has a handful of runs; this keeps it an int64).
MAX_RUN = 10**9

#: The largest size of a target or a deviation, by its unit (:data:`mtmc.document.MAX_MM`,
#: :data:`mtmc.document.MAX_DEG`).
_LIMITS: Mapping[str, float] = {
    "mm": MAX_MM,
    "um": MAX_MM * 1e3,
    "deg": MAX_DEG,
    "arcsec": MAX_DEG * 3600.0,
    "urad": MAX_RAD * 1e6,
}


def _reading(
    table: CsvTable,
    k: int,
    cells: list[str],
    units: tuple[str, str] = ("mm", "um"),
    directions: Mapping[str, int] = _DIRECTIONS,
) -> tuple[tuple[float, int, int], float]:
    """``((target, run, direction), deviation)`` of one row; errors name line ``k``."""
    target = table.number(cells, "target", _LIMITS[units[0]], k)
    deviation = table.number(cells, "deviation", _LIMITS[units[1]], k)
    run_text = table.cell(cells, "run")
    try:
        run = int(run_text) if len(run_text) <= 12 else None
    except ValueError:
        run = None
    if run is None or abs(run) > MAX_RUN:
        raise InputError(
            f"expected a whole run number of at most {MAX_RUN} in size, got {run_text[:40]!r}",
            file=table.file,
            line=k,
            field=table.names["run"],
        )
    d_text = table.cell(cells, "direction")
    d = directions.get(d_text.lower())
    if d is None:
        ups = ", ".join(w for w, v in directions.items() if v == 0)
        downs = ", ".join(w for w, v in directions.items() if v == 1)
        raise InputError(
            f"expected a direction, got {d_text!r}: positive {ups}; negative {downs} "
            "(a mapping such as --directions Hin=up,Rück=down names others)",
            file=table.file,
            line=k,
            field=table.names["direction"],
        )
    return (target, run, d), deviation


def _side(d: int) -> str:
    return "up" if d == 0 else "down"


def _missing(
    t_idx: NDArray[np.intp],
    r_idx: NDArray[np.intp],
    d_arr: NDArray[np.intp],
    targets: NDArray[np.float64],
    runs: NDArray[np.int64],
) -> tuple[float, int, int]:
    """The first missing ``(target, run, direction)`` of readings known to be incomplete.

    Found from the rows alone (a count per target, then the runs of that one target), so
    that the work and memory are those of the file, not of the product of its labels.
    """
    per_target = np.bincount(t_idx, minlength=targets.size)
    i = int(np.flatnonzero(per_target < 2 * runs.size)[0])
    here = t_idx == i
    have = np.zeros((runs.size, 2), dtype=bool)
    have[r_idx[here], d_arr[here]] = True
    j, d = (int(v) for v in np.argwhere(~have)[0])
    return float(targets[i]), int(runs[j]), d


def loads_positioning_csv(
    text: str,
    file: str = "<csv>",
    *,
    columns: Mapping[str, str] | None = None,
    units: str | tuple[str, str] = ("mm", "um"),
    directions: str | Mapping[str, str] | None = None,
) -> PositioningTest:
    """Read a positioning test from CSV text (see :func:`load_positioning_csv`)."""
    t_unit, d_unit = parse_units(units if isinstance(units, str) else ",".join(units))
    words = parse_directions(directions)
    table = read_csv(text, file, COLUMNS, columns)
    lines = table.lines
    rows = len(lines)
    tgt = np.empty(rows)
    run = np.empty(rows, dtype=np.int64)
    drc = np.empty(rows, dtype=np.intp)
    dev = np.empty(rows)
    for r, (k, cells) in enumerate(table.rows):
        (tgt[r], run[r], drc[r]), dev[r] = _reading(table, k, cells, (t_unit, d_unit), words)
    targets, t_idx = np.unique(tgt, return_inverse=True)
    runs, r_idx = np.unique(run, return_inverse=True)
    flat = (t_idx.astype(np.int64) * runs.size + r_idx) * 2 + drc
    keys, first_of = np.unique(flat, return_index=True)
    if keys.size < rows:  # the first line that repeats a reading, and the line it repeats
        repeat = np.ones(rows, dtype=bool)
        repeat[first_of] = False
        second = int(np.flatnonzero(repeat)[0])
        first = int(first_of[np.searchsorted(keys, flat[second])])
        raise InputError(
            f"a second reading at target {tgt[second]:g}, run {run[second]}, direction "
            f"{_side(int(drc[second]))} (the first is on line {lines[first][0]})",
            file=file,
            line=lines[second][0],
        )
    if rows != targets.size * runs.size * 2:
        t, rr, d = _missing(t_idx, r_idx, drc, targets, runs)
        raise InputError(
            f"no reading at target {t:g} {t_unit}, run {rr}, direction {_side(d)}: every "
            f"target needs every run in both directions ({targets.size} targets and "
            f"{runs.size} runs need {2 * targets.size * runs.size} readings, the file has "
            f"{rows})",
            file=file,
        )
    x = np.empty((targets.size, runs.size, 2))
    x[t_idx, r_idx, drc] = dev
    return PositioningTest(
        targets=targets,
        deviations=x,
        unit=d_unit,
        target_unit=t_unit,
        runs=tuple(int(v) for v in runs),
        source=file,
    )


def load_positioning_csv(
    path: str | Path,
    *,
    columns: Mapping[str, str] | None = None,
    units: str | tuple[str, str] = ("mm", "um"),
    directions: str | Mapping[str, str] | None = None,
) -> PositioningTest:
    """Read a positioning test from a CSV file: one reading per row.

    Parameters
    ----------
    path : str or Path
        The file: a header line naming at least the columns ``target``, ``run``,
        ``direction`` and ``deviation`` (case-insensitive, in any order, other columns
        ignored), then one row per reading. Comments start with ``#``.
    columns : mapping, optional
        The file's name of each column: ``{"target": "Position", "deviation": "Error"}``.
    units : str or (str, str), default ("mm", "um")
        Units of the targets and the deviations (:func:`parse_units`): ``"mm,um"``,
        ``"mm,mm"``, ``"deg,arcsec"``, ``"deg,urad"``.
    directions : str or mapping, optional
        The file's words for the two directions beyond :data:`DIRECTION_WORDS`
        (:func:`parse_directions`): ``{"Hin": "up", "Rück": "down"}``.

    Returns
    -------
    PositioningTest
        Targets sorted, runs sorted by label.

    Raises
    ------
    InputError
        Naming the file, the line and the column: a missing column, a field that is not a
        number, an unknown direction, a reading given twice, a target without every run
        in both directions, an unreadable file.
    """
    text = read_text(path, "positioning file")
    return loads_positioning_csv(
        text, str(path), columns=columns, units=units, directions=directions
    )
