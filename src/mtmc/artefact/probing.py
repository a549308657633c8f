"""Probing a ball: the point patch, the probe's noise, the centre fit and its linear map.

Wang, Cheung and Kong (2022, §2.3, Fig. 3) probe 30 points "sampled uniformly" in a
6 mm × 6 mm area of each 9.997 mm ball and fit its centre by least squares; the probing
system's repeatability is 0.36, 0.41 and 0.25 µm along x, y and z. mtmc places the 30
points on a 6 × 5 grid of the cell centres of that square (columns 1 mm apart, rows
1.2 mm apart), projected onto the ball along the patch's axis.

The centre is the orthogonal-distance fit of :func:`mtmc.geometry.fit_sphere`, with the
calibrated radius or with a free one. For the Monte Carlo runs, :func:`fit_sensitivity`
gives the fit's linear map from point displacements to the centre (its linearisation at
the noise-free solution): at these noise levels (0.4 µm on a 5 mm ball, 6 mm patch) it
differs from the converged fit by 2·10⁻⁴ µm with the calibrated radius (2·10⁻³ µm with a
free radius), about 0.1 % of the centre's standard uncertainty (shown by the tests).

:func:`load_points` reads real probed points from a CSV file (``x,y,z`` per row, with or
without a header; mm, m or µm) and :func:`fit_points` fits them.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.document import MAX_MM, read_text
from mtmc.errors import InputError
from mtmc.geometry.fits import fit_sphere

__all__ = [
    "PAPER_REPEATABILITY_UM",
    "SphereFit",
    "fit_points",
    "fit_sensitivity",
    "patch_offsets",
    "patch_points",
    "load_points",
]

_F = NDArray[np.float64]

#: Per-axis repeatability of the probing system (x, y, z), µm (Wang et al. 2022, §2.3).
PAPER_REPEATABILITY_UM: tuple[float, float, float] = (0.36, 0.41, 0.25)

#: Length units accepted for point files, to mm.
UNITS = {"mm": 1.0, "m": 1000.0, "um": 1e-3}


def patch_offsets(n_cols: int = 6, n_rows: int = 5, size: float = 6.0) -> _F:
    """In-plane coordinates ``(u, v)`` of the grid of a square patch, shape (n, 2), mm.

    The cell centres of an ``n_cols × n_rows`` grid over a ``size × size`` square
    centred on the patch axis: ``u = -size/2 + (i + 1/2) size / n_cols``, likewise ``v``.

    Examples
    --------
    >>> patch_offsets().shape, patch_offsets()[0].tolist()
    ((30, 2), [-2.5, -2.4])
    """
    if n_cols < 1 or n_rows < 1 or not size > 0:
        raise InputError(
            f"expected a grid of at least 1 x 1 points over a size > 0, got "
            f"{n_cols} x {n_rows} over {size}",
            field="patch",
        )
    u = -0.5 * size + (np.arange(n_cols) + 0.5) * size / n_cols
    v = -0.5 * size + (np.arange(n_rows) + 0.5) * size / n_rows
    uu, vv = np.meshgrid(u, v, indexing="xy")
    return np.column_stack([uu.ravel(), vv.ravel()])


def _frame(axis: npt.ArrayLike) -> _F:
    """Orthonormal (e1, e2, n) as rows, n along ``axis``."""
    n = np.asarray(axis, dtype=np.float64)
    norm = float(np.linalg.norm(n))
    if n.shape != (3,) or not norm > 0 or not np.isfinite(norm):
        raise InputError(f"expected a non-zero direction of 3 numbers, got {axis!r}", field="axis")
    n = n / norm
    ref = np.eye(3)[int(np.argmin(np.abs(n)))]
    e1 = np.cross(ref, n)
    e1 /= np.linalg.norm(e1)
    return np.stack([e1, np.cross(n, e1), n])


def patch_points(
    centre: npt.ArrayLike,
    radius: float,
    axis: npt.ArrayLike = (0.0, 0.0, 1.0),
    offsets: npt.ArrayLike | None = None,
) -> _F:
    """Points of a square patch on a ball, projected along the patch axis.

    Parameters
    ----------
    centre : array_like, shape (3,)
        Ball centre, mm.
    radius : float
        Ball radius, mm.
    axis : array_like, shape (3,)
        Direction from the centre to the middle of the patch.
    offsets : array_like, shape (n, 2), optional
        In-plane coordinates (default :func:`patch_offsets`: 30 points in 6 × 6 mm).

    Returns
    -------
    ndarray, shape (n, 3)
        ``c + u e1 + v e2 + sqrt(R² - u² - v²) n``, mm.

    Raises
    ------
    InputError
        If a point of the patch lies outside the ball's silhouette.

    Examples
    --------
    >>> p = patch_points([0, 0, 0], 4.9985)
    >>> bool(np.allclose(np.linalg.norm(p, axis=1), 4.9985, rtol=0, atol=1e-12))
    True
    """
    uv = patch_offsets() if offsets is None else np.asarray(offsets, dtype=np.float64)
    h2 = radius * radius - np.einsum("ij,ij->i", uv, uv)
    if not np.all(h2 > 0):
        raise InputError(
            f"the patch does not fit on a ball of radius {radius} mm: expected in-plane "
            "offsets within the radius",
            field="patch",
        )
    e = _frame(axis)
    local = np.column_stack([uv, np.sqrt(h2)])
    return np.asarray(centre, dtype=np.float64) + local @ e


def fit_sensitivity(points: npt.ArrayLike, centre: npt.ArrayLike, free_radius: bool = False) -> _F:
    """Linear map from point displacements to the fitted centre, batched over sets.

    For the orthogonal-distance fit at its solution ``c`` (points ``p_k``, unit normals
    ``n_k = (p_k - c) / |p_k - c|``), displacing the points by ``ε_k`` moves the residuals
    by ``n_k · ε_k`` and the fitted parameters by one Gauss–Newton step,
    ``δθ = (JᵀJ)⁻¹ Jᵀ_- (n · ε)`` with ``J_- = [N]`` (known radius) or ``[N 1]``
    (free radius). Returns the centre rows: ``δc = K ε`` with ``ε`` the flattened
    displacements ``x₁ y₁ z₁ x₂ ...``.

    Parameters
    ----------
    points : array_like, shape (B, n, 3) or (n, 3)
        The noise-free points, mm.
    centre : array_like, shape (B, 3) or (3,)
        The fitted centre of each set.
    free_radius : bool
        The map of the free-radius fit instead of the known-radius one.

    Returns
    -------
    ndarray, shape (B, 3, 3n)
        ``∂c / ∂ε`` (dimensionless).
    """
    P = np.asarray(points, dtype=np.float64)
    single = P.ndim == 2
    P = P[None] if single else P
    c = np.asarray(centre, dtype=np.float64).reshape(-1, 3)
    D = P - c[:, None, :]
    N = D / np.linalg.norm(D, axis=2, keepdims=True)
    b, n = P.shape[:2]
    J = np.concatenate([N, np.ones((b, n, 1))], axis=2) if free_radius else N
    G = np.linalg.solve(np.matmul(J.transpose(0, 2, 1), J), J.transpose(0, 2, 1))[:, :3, :]
    K = G[:, :, :, None] * N[:, None, :, :]
    return np.asarray(K.reshape(b, 3, 3 * n), dtype=np.float64)


@dataclass(frozen=True)
class SphereFit:
    """Centre and radius of a ball from probed points, with standard uncertainties.

    Attributes
    ----------
    centre : tuple of float
        mm.
    radius : float
        mm (the given one with a known radius).
    u_centre : tuple of float
        Standard uncertainties of the centre coordinates, ``sqrt(diag(s² (JᵀJ)⁻¹))``, mm.
    u_radius : float
        Standard uncertainty of the radius, mm (0 for a known radius).
    rms : float
        RMS of the orthogonal residuals, mm.
    n : int
        Number of points.
    radius_known : bool
        Whether the radius was given.
    """

    centre: tuple[float, float, float]
    radius: float
    u_centre: tuple[float, float, float]
    u_radius: float
    rms: float
    n: int
    radius_known: bool


def fit_points(points: npt.ArrayLike, radius: float | None = None) -> SphereFit:
    """Fit a ball to probed points: orthogonal-distance least squares, with uncertainties.

    Parameters
    ----------
    points : array_like, shape (n, 3)
        mm; a partial cap of a scan is fine.
    radius : float, optional
        The calibrated radius, mm; None fits it.

    Returns
    -------
    SphereFit

    Raises
    ------
    DegenerateGeometryError, ConvergenceError, InputError
        As :func:`mtmc.geometry.fit_sphere`.

    Examples
    --------
    >>> f = fit_points(patch_points([1.0, 2.0, 3.0], 4.9985), radius=4.9985)
    >>> np.round(f.centre, 9).tolist(), f.n
    ([1.0, 2.0, 3.0], 30)
    """
    P = np.asarray(points, dtype=np.float64)
    fit = fit_sphere(P, None if radius is None else float(radius))
    cov = fit.covariance
    assert cov is not None
    u = np.sqrt(np.clip(np.diagonal(cov[0]), 0.0, None))
    c = fit.geometry.centre[0]  # type: ignore[union-attr]
    r = float(fit.geometry.radius[0])  # type: ignore[union-attr]
    return SphereFit(
        (float(c[0]), float(c[1]), float(c[2])),
        r,
        (float(u[0]), float(u[1]), float(u[2])),
        0.0 if radius is not None else float(u[3]),
        float(fit.rms[0]),
        int(P.shape[0]),
        radius is not None,
    )


def load_points(path: str | Path, units: str = "mm") -> _F:
    """Read probed points from a CSV file: ``x,y,z`` per row, in ``units``; to mm.

    A first row that is not three numbers is taken as a header (e.g. ``x,y,z``); empty
    lines and lines starting with ``#`` are skipped; separators may be commas,
    semicolons, tabs or spaces.

    Parameters
    ----------
    path : str or Path
        The CSV file.
    units : {"mm", "m", "um"}
        Unit of the coordinates in the file.

    Returns
    -------
    ndarray, shape (n, 3)
        mm.

    Raises
    ------
    InputError
        Naming the file and line: a row that is not three finite numbers, an unknown
        unit, an unreadable file.
    """
    if units not in UNITS:
        raise InputError(
            f"expected units mm, m or um, got {units!r}", field="units", file=str(path)
        )
    p = Path(path)
    text = read_text(p, "points file")
    rows: list[tuple[float, float, float]] = []
    first = True
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if "," in line or ";" in line:
            delim = "," if "," in line else ";"
            fields = [f.strip() for f in next(csv.reader(io.StringIO(line), delimiter=delim))]
        else:
            fields = line.split()
        try:
            vals = [float(f) for f in fields]
            ok = len(vals) == 3 and all(abs(v) <= MAX_MM / UNITS[units] for v in vals)
        except ValueError:
            ok = False
        if not ok:
            if first and not rows:
                first = False
                continue  # a header row
            raise InputError(
                f"expected three finite numbers x, y, z of at most {MAX_MM:g} mm, got {line!r}",
                file=str(p),
                line=lineno,
            )
        first = False
        rows.append((vals[0], vals[1], vals[2]))
    if len(rows) < 4:
        raise InputError(
            f"expected at least 4 points to fit a sphere, got {len(rows)}", file=str(p)
        )
    return np.array(rows) * UNITS[units]
