"""Reading a measured circular-test trace from CSV, as a user exports it.

One reading per row: the angle of the point, the direction of contouring, the radial
deviation. The default header is ``angle,direction,deviation`` with the angle in
degrees, the direction ``cw`` or ``ccw`` and the deviation in µm; ``columns`` maps these
names onto the file's own (``{"deviation": "Error"}``), ``units`` gives
``ANGLE,DEVIATION`` (``deg,um``, ``deg,mm``, ``rad,um``, ``rad,mm``), and ``directions``
maps the file's words for a direction (``{"clockwise": "cw"}``). The comma, semicolon
or tab separates fields; blank lines and lines starting with ``#`` are skipped. Angles
outside one turn (the overrun arcs) are left out of the evaluation; within it each
angle may appear once per direction.
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

__all__ = ["COLUMNS", "CircularTrace", "loads_circular_csv", "load_circular_csv", "parse_units"]

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
    """

    theta_ccw: _F | None = field(repr=False)
    ccw: _F | None = field(repr=False)
    theta_cw: _F | None = field(repr=False)
    cw: _F | None = field(repr=False)
    unit: str = "um"
    source: str = "<csv>"

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
) -> CircularTrace:
    """Read a trace from CSV text (module docstring); errors name file, line and column."""
    a_unit, d_unit = parse_units(units)
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
    seen: dict[int, dict[float, tuple[float, int]]] = {1: {}, -1: {}}
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
        theta = values["angle"] * _ANGLE[a_unit]
        if theta < 0 or theta >= 2 * math.pi - 1e-12:
            continue  # an overrun arc: not evaluated
        if theta in seen[d]:
            raise InputError(
                f"a second reading at {values['angle']:g} {a_unit} {'ccw' if d > 0 else 'cw'} "
                f"(the first is on line {seen[d][theta][1]})",
                file=file,
                line=k,
            )
        seen[d][theta] = (values["deviation"] * _DEVIATION[d_unit], k)
    out: dict[str, _F | None] = {}
    for d, name in ((1, "ccw"), (-1, "cw")):
        pts = sorted(seen[d].items())
        if pts and len(pts) < 4:
            raise InputError(
                f"expected at least 4 readings {name} within one turn, got {len(pts)}", file=file
            )
        out[f"theta_{name}"] = np.array([t for t, _ in pts]) if pts else None
        out[name] = np.array([v for _, (v, _) in pts]) if pts else None
    if out["ccw"] is None and out["cw"] is None:
        raise InputError("expected readings within one turn, the file has none", file=file)
    return CircularTrace(
        theta_ccw=out["theta_ccw"],
        ccw=out["ccw"],
        theta_cw=out["theta_cw"],
        cw=out["cw"],
        unit=d_unit,
        source=file,
    )


def load_circular_csv(
    path: str | Path,
    *,
    columns: Mapping[str, str] | None = None,
    units: str = "deg,um",
    directions: Mapping[str, str] | None = None,
) -> CircularTrace:
    """Read a trace from a CSV file (module docstring).

    Raises
    ------
    InputError
        On a missing column, a field that is not a finite number, an unknown direction,
        a repeated angle, or an unreadable file, naming the file, line and column.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read the file: {exc}", file=str(p)) from exc
    return loads_circular_csv(text, str(p), columns=columns, units=units, directions=directions)
