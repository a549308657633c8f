"""The gravity effect on the artefact between mounting orientations (eqs. 1–2).

Wang, Cheung and Kong (2022, §2.2, §3.1) measure the ball centres on a CMM with the
artefact horizontal (H, the reference), tilted by 10° (O) and vertical (V), three times
each, and compare the mean centres:

- ``Δx_{i,KH} = x̄_{i,K} - x̄_{i,H}`` (likewise y, z), ``K = O, V`` (eq. 1);
- ``Δx̄_KH = (1/N) Σ_i |Δx_{i,KH}|`` (eq. 1: the mean of the magnitudes);
- ``Δd_{i,KH} = sqrt(Δx² + Δy² + Δz²)`` and ``Δd̄_KH = (1/N) Σ_i Δd_{i,KH}`` (eq. 2).

The measurements come from a CSV file with the columns ``orientation,ball,x,y,z``
(orientation ``H``, ``O`` or ``V``; ball a name; centres in mm; one row per measurement,
repetitions as repeated rows; a header row is required).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from mtmc.document import MAX_MM, read_text
from mtmc.errors import InputError
from mtmc.frozen import frozen_floats

__all__ = ["GravityEffect", "gravity_effect", "load_gravity"]

_F = NDArray[np.float64]
ORIENTATIONS = ("H", "O", "V")
COLUMNS = ("orientation", "ball", "x", "y", "z")


@dataclass(frozen=True, eq=False)
class GravityEffect:
    """Eqs. 1–2 for each tilted orientation against the horizontal one.

    Attributes
    ----------
    balls : tuple of str
        Ball names, in order of first appearance.
    orientations : tuple of str
        The compared orientations (``"O"``, ``"V"`` where present).
    delta : ndarray, shape (K, N, 3)
        ``(Δx, Δy, Δz)_{i,KH}``, mm.
    delta_d : ndarray, shape (K, N)
        ``Δd_{i,KH}``, mm.
    mean_abs : ndarray, shape (K, 3)
        ``(Δx̄, Δȳ, Δz̄)_KH``, the mean magnitudes over the balls, mm.
    mean_d : ndarray, shape (K,)
        ``Δd̄_KH``, mm.
    counts : dict
        Measurements per (orientation, ball).
    """

    balls: tuple[str, ...]
    orientations: tuple[str, ...]
    delta: _F
    delta_d: _F
    mean_abs: _F
    mean_d: _F
    counts: dict[tuple[str, str], int]


def gravity_effect(rows: list[tuple[str, str, float, float, float]]) -> GravityEffect:
    """Eqs. 1–2 from measured centres.

    Parameters
    ----------
    rows : list of (orientation, ball, x, y, z)
        One per measurement, mm; every ball measured at least once in ``H`` and in each
        other orientation present.

    Returns
    -------
    GravityEffect

    Raises
    ------
    InputError
        If ``H`` is missing, an orientation is unknown, or a ball lacks an orientation.

    Examples
    --------
    >>> g = gravity_effect([("H", "1", 0, 0, 0), ("V", "1", 0.003, 0, 0.004),
    ...                     ("H", "2", 1, 0, 0), ("V", "2", 1, -0.001, 0)])
    >>> g.delta_d[0].tolist(), round(float(g.mean_d[0]), 6), g.mean_abs[0].round(6).tolist()
    ([0.005, 0.001], 0.003, [0.0015, 0.0005, 0.002])
    """
    balls: list[str] = []
    sums: dict[tuple[str, str], list[float]] = {}
    counts: dict[tuple[str, str], int] = {}
    for o, b, x, y, z in rows:
        if o not in ORIENTATIONS:
            raise InputError(f"expected orientation H, O or V, got {o!r}", field="orientation")
        if b not in balls:
            balls.append(b)
        s = sums.setdefault((o, b), [0.0, 0.0, 0.0])
        s[0] += x
        s[1] += y
        s[2] += z
        counts[(o, b)] = counts.get((o, b), 0) + 1
    present = [o for o in ORIENTATIONS if any(k[0] == o for k in counts)]
    if "H" not in present or len(present) < 2:
        raise InputError(
            "expected measurements in the horizontal reference H and in O and/or V, got "
            f"{', '.join(present) or 'none'}",
            field="orientation",
        )
    others = tuple(o for o in present if o != "H")

    def mean(o: str, b: str) -> _F:
        if (o, b) not in counts:
            raise InputError(f"ball {b} has no measurement in orientation {o}", field="ball")
        return np.array(sums[(o, b)]) / counts[(o, b)]

    delta = np.array([[mean(o, b) - mean("H", b) for b in balls] for o in others])
    dd = np.sqrt(np.einsum("kni,kni->kn", delta, delta))
    return GravityEffect(
        tuple(balls),
        others,
        frozen_floats(delta),
        frozen_floats(dd),
        frozen_floats(np.abs(delta).mean(axis=1)),
        frozen_floats(dd.mean(axis=1)),
        counts,
    )


def load_gravity(path: str | Path) -> GravityEffect:
    """Read CMM measurements from a CSV file and compute eqs. 1–2.

    Parameters
    ----------
    path : str or Path
        A CSV file with the header ``orientation,ball,x,y,z`` (mm); ``#`` lines skipped.

    Returns
    -------
    GravityEffect

    Raises
    ------
    InputError
        Naming the file and line of a bad row or header.
    """
    p = Path(path)
    text = read_text(p, "measurements")
    rows: list[tuple[str, str, float, float, float]] = []
    header = None
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        fields = [f.strip() for f in next(csv.reader([line]))]
        if header is None:
            if tuple(f.lower() for f in fields) != COLUMNS:
                raise InputError(
                    f"expected the header {','.join(COLUMNS)}, got {line!r}",
                    file=str(p),
                    line=lineno,
                )
            header = fields
            continue
        try:
            if len(fields) != 5:
                raise ValueError
            x, y, z = (float(v) for v in fields[2:])
            if not all(math.isfinite(v) for v in (x, y, z)):
                raise ValueError
        except ValueError:
            raise InputError(
                f"expected orientation,ball,x,y,z with finite coordinates, got {line!r}",
                file=str(p),
                line=lineno,
            ) from None
        for name, v in zip("xyz", (x, y, z), strict=True):
            if abs(v) > MAX_MM:
                raise InputError(
                    f"expected a coordinate at most {MAX_MM:g} mm in size, got {v!r}",
                    file=str(p),
                    line=lineno,
                    field=name,
                )
        o = fields[0].upper()
        if o not in ORIENTATIONS:
            raise InputError(
                f"expected orientation H, O or V, got {fields[0]!r}", file=str(p), line=lineno
            )
        rows.append((o, fields[1], x, y, z))
    try:
        return gravity_effect(rows)
    except InputError as exc:
        raise InputError(exc.message, file=str(p), field=exc.field) from None
