"""Reading a measured circular-test trace from CSV, as a user exports it.

One reading per row: the angle of the point, the direction of contouring, the radial
deviation. The default header is ``angle,direction,deviation`` with the angle in
degrees, the direction ``cw`` or ``ccw`` and the deviation in µm; ``columns`` maps these
names onto the file's own (``{"deviation": "Error"}``), ``units`` gives
``ANGLE,DEVIATION`` (``deg,um``, ``deg,mm``, ``rad,um``, ``rad,mm``), and ``directions``
maps the file's words for a direction (``{"clockwise": "cw"}``). The comma, semicolon
or tab separates fields; blank lines and lines starting with ``#`` are skipped.

**The overrun arcs.** ISO 230-4 lets the path run on before and after the evaluated turn
(the overrun, so that the axes are in steady motion over it); an export may hold those
readings, and a clockwise path may run through negative angles. Each direction's
readings are evaluated over one turn, ``[a₀, a₀ + 360°)``, and the readings outside it
are read and left out (:attr:`CircularTrace.overrun` counts them):

- ``overrun`` given (deg): the arc at the start of the path's travel, ``a₀ = min + overrun``
  counter-clockwise, ``a₀ + 360° = max - overrun`` clockwise (a clockwise path travels
  from its largest angle down);
- not given: the arcs at the two ends are taken as equal, ``a₀ = min + (span - 360°)/2``
  for a path spanning more than one turn, and ``a₀ = min`` otherwise (so that a closing
  reading at ``min + 360°``, the first point read again, is left out).

The evaluated angles are then taken modulo 360°, each angle once per direction.

A rotary-axis test (:func:`load_rotary_csv`) has one row per rotary position: its angle
and the R-test's three displacements ``angle,dx,dy,dz`` or the ballbar's reading
``angle,deviation``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from mtmc.csvtable import read_csv, read_units
from mtmc.document import MAX_DEG, MAX_MM, MAX_RAD
from mtmc.errors import InputError

__all__ = [
    "COLUMNS",
    "CircularTrace",
    "RotaryTrace",
    "loads_circular_csv",
    "load_circular_csv",
    "loads_rotary_csv",
    "load_rotary_csv",
    "parse_units",
]

_F = NDArray[np.float64]

#: The columns of a trace file, as :func:`load_circular_csv` names them.
COLUMNS = ("angle", "direction", "deviation")
_ANGLE = {"deg": math.pi / 180.0, "rad": 1.0}
#: The largest size of an angle and of a deviation, by unit (:mod:`mtmc.document`).
_LIMITS = {"deg": MAX_DEG, "rad": MAX_RAD, "um": MAX_MM * 1e3, "µm": MAX_MM * 1e3, "mm": MAX_MM}
_DEVIATION = {"um": 1e-3, "µm": 1e-3, "mm": 1.0}
_WORDS = {
    "ccw": 1,
    "counterclockwise": 1,
    "counter-clockwise": 1,
    "anticlockwise": 1,
    "cw": -1,
    "clockwise": -1,
}


def parse_units(text: str) -> tuple[str, str]:
    """``"deg,um"`` as ``("deg", "um")``; one unit alone is the deviation's (angle deg).

    Examples
    --------
    >>> parse_units("deg,um"), parse_units("mm")
    (('deg', 'um'), ('deg', 'mm'))
    """
    return read_units(text, {a: tuple(_DEVIATION) for a in _ANGLE}, ("ANGLE", "DEVIATION"))


@dataclass(frozen=True, eq=False)
class CircularTrace:
    """A measured trace: the angles (rad) and radial deviations (mm) of each direction.

    Attributes
    ----------
    theta_ccw, ccw, theta_cw, cw : ndarray or None
        Angles in ``[0, 2π)`` and deviations, mm, by direction (None where absent), each
        sorted by angle.
    unit : str
        The deviation unit of the file.
    source : str
        The file.
    overrun : dict of str to int
        The readings of each direction left out as its overrun arcs (module docstring).
    """

    theta_ccw: _F | None = field(repr=False)
    ccw: _F | None = field(repr=False)
    theta_cw: _F | None = field(repr=False)
    cw: _F | None = field(repr=False)
    unit: str = "um"
    source: str = "<csv>"
    overrun: dict[str, int] = field(default_factory=dict)

    @property
    def deviation(self) -> _F:
        """Both paths' deviations, CCW first, mm: ``(N,)``."""
        parts = [d for d in (self.ccw, self.cw) if d is not None]
        return np.concatenate(parts)


def loads_circular_csv(
    text: str,
    file: str = "<csv>",
    *,
    columns: Mapping[str, str] | None = None,
    units: str = "deg,um",
    directions: Mapping[str, str] | None = None,
    overrun: float | None = None,
) -> CircularTrace:
    """Read a trace from CSV text (module docstring); errors name file, line and column."""
    a_unit, d_unit = parse_units(units)
    if overrun is not None and not (math.isfinite(overrun) and 0.0 <= overrun < 360.0):
        raise InputError(
            f"expected an overrun arc in [0, 360) deg, got {overrun!r}", field="overrun"
        )
    words = dict(_WORDS)
    for word, meaning in (directions or {}).items():
        if meaning.lower() not in ("cw", "ccw"):
            raise InputError(
                f"expected a direction word to map onto cw or ccw, got {meaning!r}",
                field=f"directions.{word}",
            )
        words[word.strip().lower()] = 1 if meaning.lower() == "ccw" else -1
    table = read_csv(text, file, COLUMNS, columns)
    limits = {"angle": _LIMITS[a_unit], "deviation": _LIMITS[d_unit]}
    rows: dict[int, list[tuple[float, float, int, float]]] = {1: [], -1: []}
    for k, cells in table.rows:
        values = {key: table.number(cells, key, limits[key], k) for key in ("angle", "deviation")}
        word = table.cell(cells, "direction").lower()
        if word not in words:
            raise InputError(
                f"expected a direction among {', '.join(sorted(words))} (map others with "
                f"directions), got {table.cell(cells, 'direction')!r}",
                file=file,
                line=k,
                field=table.names["direction"],
            )
        d = words[word]
        deg = values["angle"] * _ANGLE[a_unit] * 180.0 / math.pi
        rows[d].append((deg, values["deviation"] * _DEVIATION[d_unit], k, values["angle"]))
    out: dict[str, _F | None] = {}
    left: dict[str, int] = {}
    for d, name in ((1, "ccw"), (-1, "cw")):
        pts, left[name] = _one_turn(rows[d], d, overrun, file, a_unit, name)
        if rows[d] and len(pts) < 4:
            gone = f" ({left[name]} left out as overrun arcs)" if left[name] else ""
            raise InputError(
                f"expected at least 4 readings {name} within one turn, got {len(pts)}{gone}",
                file=file,
            )
        out[f"theta_{name}"] = np.array([t for t, _ in pts]) if pts else None
        out[name] = np.array([v for _, v in pts]) if pts else None
    if out["ccw"] is None and out["cw"] is None:
        raise InputError("expected readings within one turn, the file has none", file=file)
    return CircularTrace(
        theta_ccw=out["theta_ccw"],
        ccw=out["ccw"],
        theta_cw=out["theta_cw"],
        cw=out["cw"],
        unit=d_unit,
        source=file,
        overrun={k: v for k, v in left.items() if v},
    )


def _one_turn(
    rows: list[tuple[float, float, int, float]],
    d: int,
    overrun: float | None,
    file: str,
    a_unit: str,
    name: str,
) -> tuple[list[tuple[float, float]], int]:
    """The readings of one direction within its evaluated turn (module docstring).

    Returns the ``(θ in [0, 2π), deviation)`` pairs sorted by angle and the number of
    readings left out as overrun.
    """
    if not rows:
        return [], 0
    deg = np.array([r[0] for r in rows])
    lo, hi = float(deg.min()), float(deg.max())
    eps = 1e-9 * max(1.0, abs(lo), abs(hi))
    if overrun is None:
        start = lo + max(0.0, 0.5 * (hi - lo - 360.0))
    else:
        start = lo + overrun if d > 0 else hi - overrun - 360.0

    def inside(a: float) -> bool:
        if overrun is not None and d < 0:  # (end - 360°, end]: travelled down from end
            return start + eps < a <= start + 360.0 + eps
        return start - eps <= a < start + 360.0 - eps

    seen: dict[float, int] = {}
    pts = []
    for a, dev, k, raw in rows:
        if not inside(a):
            continue  # an overrun arc: read, not evaluated
        theta = math.radians(a % 360.0)
        if theta >= 2 * math.pi - 1e-12:
            theta = 0.0
        if theta in seen:
            raise InputError(
                f"a second reading at {raw:g} {a_unit} {name} within the evaluated turn "
                f"(the first, the same angle modulo 360°, is on line {seen[theta]})",
                file=file,
                line=k,
            )
        seen[theta] = k
        pts.append((theta, dev))
    return sorted(pts), len(rows) - len(pts)


def load_circular_csv(
    path: str | Path,
    *,
    columns: Mapping[str, str] | None = None,
    units: str = "deg,um",
    directions: Mapping[str, str] | None = None,
    overrun: float | None = None,
) -> CircularTrace:
    """Read a trace from a CSV file (module docstring).

    Raises
    ------
    InputError
        On a missing column, a field that is not a finite number, an unknown direction,
        a repeated angle, or an unreadable file, naming the file, line and column.
    """
    p = Path(path)
    text = _read_text(p)
    return loads_circular_csv(
        text, str(p), columns=columns, units=units, directions=directions, overrun=overrun
    )


def _read_text(p: Path) -> str:
    """The text of a file (UTF-8, a byte-order mark allowed), or a located error."""
    try:
        return p.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read the file: {exc}", file=str(p)) from exc


#: The columns of a rotary-axis test file, by instrument.
ROTARY_COLUMNS = {"rtest": ("angle", "dx", "dy", "dz"), "ballbar": ("angle", "deviation")}


@dataclass(frozen=True, eq=False)
class RotaryTrace:
    """A measured rotary-axis test: the rotary positions and the readings at each.

    Attributes
    ----------
    angle : ndarray, shape (n,)
        The rotary axis' positions, rad, in the order of the file.
    readings : ndarray, shape (n, 3) or (n,)
        The R-test's displacements along x, y, z, or the ballbar's readings, mm.
    instrument : {"rtest", "ballbar"}
    unit : str
        The readings' unit of the file.
    source : str
        The file.
    """

    angle: _F = field(repr=False)
    readings: _F = field(repr=False)
    instrument: str = "rtest"
    unit: str = "um"
    source: str = "<csv>"


def loads_rotary_csv(
    text: str,
    file: str = "<csv>",
    *,
    instrument: str = "rtest",
    columns: Mapping[str, str] | None = None,
    units: str = "deg,um",
) -> RotaryTrace:
    """Read a rotary-axis test from CSV text (module docstring): one row per position.

    Raises
    ------
    InputError
        On a missing column, a field that is not a finite number, a repeated position
        or fewer than 4 rows, naming the file, line and column.
    """
    if instrument not in ROTARY_COLUMNS:
        raise InputError(
            f"expected the instrument rtest or ballbar, got {instrument!r}", field="instrument"
        )
    a_unit, d_unit = parse_units(units)
    names = ROTARY_COLUMNS[instrument]
    table = read_csv(text, file, names, columns)
    seen: dict[float, int] = {}
    angles, values = [], []
    for k, cells in table.rows:
        a = table.number(cells, "angle", _LIMITS[a_unit], k)
        if a in seen:
            raise InputError(
                f"a second reading at {a:g} {a_unit} (the first is on line {seen[a]})",
                file=file,
                line=k,
                field=table.names["angle"],
            )
        seen[a] = k
        angles.append(a * _ANGLE[a_unit])
        values.append([table.number(cells, c, _LIMITS[d_unit], k) for c in names[1:]])
    if len(angles) < 4:
        raise InputError(f"expected at least 4 rotary positions, got {len(angles)}", file=file)
    readings = np.asarray(values, dtype=np.float64) * _DEVIATION[d_unit]
    return RotaryTrace(
        angle=np.asarray(angles, dtype=np.float64),
        readings=readings if instrument == "rtest" else readings[:, 0],
        instrument=instrument,
        unit=d_unit,
        source=file,
    )


def load_rotary_csv(
    path: str | Path,
    *,
    instrument: str = "rtest",
    columns: Mapping[str, str] | None = None,
    units: str = "deg,um",
) -> RotaryTrace:
    """Read a rotary-axis test from a CSV file (:func:`loads_rotary_csv`)."""
    p = Path(path)
    return loads_rotary_csv(
        _read_text(p), str(p), instrument=instrument, columns=columns, units=units
    )
