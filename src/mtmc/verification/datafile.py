"""The measured data of an identification: a CSV of axis positions and tracker readings.

Two layouts, told apart by the header (``#`` lines and blank lines are skipped):

- **coordinates**: the axis columns (``X,Y,Z`` …, mm or rad, in the machine's axis order
  or any order) and ``x_lt,y_lt,z_lt``: the reflector in the frame of one tracker, mm.
- **lengths per station** (multilateration): the axis columns and one ``L_NAME`` column per
  station, ``NAME`` a tracker position of the study (``[tracker.positions.NAME]``): the
  length from that station to the reflector, mm. Three or more stations; the points
  follow from the lengths and the stations' positions by
  :func:`~mtmc.instruments.trilaterate` (started from the nominal tool positions, which
  settles the mirror ambiguity of three stations), in the machine's base frame.
  With four or more stations the stations' positions can come from the same lengths
  (``self_calibrate=True``, :func:`~mtmc.instruments.self_calibrate`): the study's
  positions then only start the iteration, and the points are in the station datum frame,
  whose nominal pose (from the study's positions) starts the identification's pose.

Examples
--------
>>> rows = ["X,Y,Z,x_lt,y_lt,z_lt", "0,0,0,1,2,3", "10,0,0,11,2,3"]
>>> d = loads_identification_csv(chr(10).join(rows), ("X", "Y", "Z"), {}, "d.csv")
>>> d.kind, d.q.tolist(), d.readings[1].tolist()
('coordinates', [[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]], [11.0, 2.0, 3.0])
"""

from __future__ import annotations

import csv
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from mtmc.document import MAX_MM, read_text
from mtmc.errors import InputError
from mtmc.instruments.laser_tracker import LaserTracker
from mtmc.instruments.multilateration import datum_pose, self_calibrate, trilaterate
from mtmc.kinematics.machine import Machine

__all__ = [
    "IdentificationData",
    "load_identification_csv",
    "loads_identification_csv",
    "measured_points",
]

_F = NDArray[np.float64]

COORDINATES: tuple[str, ...] = ("x_lt", "y_lt", "z_lt")

# a plain decimal number: ASCII digits, one point, an optional exponent (no ``1_0``,
# no other scripts' digits, no decimal comma, no ``nan`` or ``inf``)
_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")


@dataclass(frozen=True)
class IdentificationData:
    """Rows of an identification CSV.

    Attributes
    ----------
    kind : {"coordinates", "lengths"}
    q : ndarray, shape (N, n_axes)
        Commanded axis positions, in the machine's axis order.
    readings : ndarray, shape (N, 3) or (N, S)
        Tracker-frame coordinates (mm), or the lengths from each station (mm).
    stations : tuple of str
        The station names of the length columns (empty for coordinates).
    """

    kind: str
    q: _F
    readings: _F
    stations: tuple[str, ...] = ()


def _rows(text: str) -> list[tuple[int, list[str]]]:
    out = []
    for i, line in enumerate(text.splitlines()):
        if line.strip() and not line.lstrip().startswith("#"):
            out.append((i + 1, [c.strip(" \t") for c in next(csv.reader([line]))]))
    return out


def loads_identification_csv(
    text: str, axes: tuple[str, ...], stations: Mapping[str, object], file: str = "<data>"
) -> IdentificationData:
    """Parse the CSV text (see the module notes).

    Parameters
    ----------
    text : str
    axes : tuple of str
        The machine's axes.
    stations : mapping
        The study's tracker positions by name (only the names are used here).
    file : str
        For the messages.

    Returns
    -------
    IdentificationData

    Raises
    ------
    InputError
        On a missing column, an unknown station, fewer than three stations, a row whose
        cells are not one per header column, or a cell that is not a plain decimal number
        (ASCII digits, ``.`` as the decimal point, an optional exponent) of at most
        ``MAX_MM`` in size (naming the file, line, column and field).
    """
    rows = _rows(text)
    if not rows:
        raise InputError("no header line", file=file)
    head_line, header = rows[0]
    length_cols = [h for h in header if h.startswith("L_")]
    names: tuple[str, ...] = ()
    if all(c in header for c in COORDINATES):
        kind, cols = "coordinates", list(COORDINATES)
    elif length_cols:
        names = tuple(h[2:] for h in length_cols)
        unknown = [n for n in names if n not in stations]
        if unknown:
            raise InputError(
                f"length column of an unknown station {', '.join('L_' + n for n in unknown)}; "
                f"the study's stations: {', '.join(stations) or 'none'}",
                file=file, line=head_line,
            )  # fmt: skip
        if len(names) < 3:
            raise InputError(
                f"multilateration needs lengths from three or more stations, got {len(names)}",
                file=file, line=head_line,
            )  # fmt: skip
        kind, cols = "lengths", length_cols
    else:
        raise InputError(
            f"expected the columns {','.join(axes)} with either {','.join(COORDINATES)} "
            "(tracker-frame coordinates, mm) or L_NAME per station (lengths, mm)",
            file=file, line=head_line,
        )  # fmt: skip
    missing = [a for a in axes if a not in header]
    if missing:
        raise InputError(
            f"missing columns {', '.join(missing)}; expected {','.join(axes)}",
            file=file, line=head_line,
        )  # fmt: skip
    idx = [header.index(c) for c in (*axes, *cols)]
    vals = []
    for ln, cells in rows[1:]:
        if len(cells) != len(header):
            raise InputError(
                f"expected {len(header)} cells, one per header column, got {len(cells)}: "
                f"{','.join(cells)!r}",
                file=file, line=ln,
            )  # fmt: skip
        for j in idx:
            if not _NUMBER.fullmatch(cells[j]):
                raise InputError(
                    f"expected a plain decimal number (digits 0-9, a point, an optional "
                    f"exponent), got {cells[j]!r}",
                    file=file, line=ln, column=j + 1, field=header[j],
                )  # fmt: skip
        vals.append([float(cells[j]) for j in idx])
        for j, v in zip(idx, vals[-1], strict=True):
            if not abs(v) <= MAX_MM:
                raise InputError(
                    f"expected a finite number of at most {MAX_MM:g} in size, got {cells[j]!r}",
                    file=file, line=ln, column=j + 1, field=header[j],
                )  # fmt: skip
    if not vals:
        raise InputError("no data rows", file=file)
    arr = np.array(vals, dtype=np.float64)
    n = len(axes)
    return IdentificationData(kind, arr[:, :n], arr[:, n:], names)


def load_identification_csv(
    path: str | Path, axes: tuple[str, ...], stations: Mapping[str, object]
) -> IdentificationData:
    """Read an identification CSV file (see :func:`loads_identification_csv`).

    Raises
    ------
    InputError
        If the file cannot be read, or as :func:`loads_identification_csv`.
    """
    return loads_identification_csv(read_text(path, "data"), axes, stations, str(path))


def measured_points(
    data: IdentificationData,
    machine: Machine,
    stations: Mapping[str, LaserTracker],
    tracker: LaserTracker,
    *,
    self_calibrated: bool = False,
) -> tuple[_F, LaserTracker]:
    """The measured points ``(N, 3)`` and the nominal frame they are in.

    Coordinates are returned as read, with ``tracker`` (their tracker's nominal pose). From
    lengths, the points are multilaterated from the stations' positions (base frame) and
    returned with the identity pose: the identification's pose then absorbs the small
    rigid motion between the stations' frame and the machine's. With
    ``self_calibrated``, the stations' positions are found from the lengths too (four or
    more stations): the points come in the station datum frame, returned with that
    frame's nominal pose, which the identification's pose corrects.

    Raises
    ------
    InputError
        If the multilateration does not converge, or ``self_calibrated`` is asked of
        coordinates or of fewer than four stations.
    """
    if data.kind == "coordinates":
        if self_calibrated:
            raise InputError(
                "self-calibration needs lengths per station (L_NAME columns), "
                "the data are tracker coordinates",
                field="self_calibrate",
            )
        return data.readings, tracker
    C = np.array([stations[n].position for n in data.stations])
    start = machine.tool_position(data.q)
    if self_calibrated:
        r = self_calibrate(data.readings.T[None], C, points0=start)
        R, origin = datum_pose(C)
        frame = LaserTracker(R, origin, name="station datum (self-calibrated)")
    else:
        r = trilaterate(C, data.readings.T[None], points0=start)
        frame = LaserTracker(np.eye(3), np.zeros(3), name="stations")
    if not bool(r.converged[0]):
        raise InputError(
            f"the multilateration from {len(data.stations)} stations did not converge",
            field="lengths",
        )
    return np.array(r.points[0]), frame
