"""The fiducial artefact: calibrated ball centres, their CMM uncertainty, the mounting.

An artefact is ``N`` balls (fiducials) whose centres and diameter were calibrated on a
coordinate measuring machine (CMM), in the artefact's own frame, and a mounting (position
and orientation of that frame on the machine's last part-side body). Wang, Cheung and
Kong (2022) use five balls (their Table 1, shipped as ``wang2022_five_ball.toml``).

The CMM's uncertainty is given as a length formula, ``u(L) = a + L / D`` µm (L in mm; the
paper's ``a = 0.25 µm``, ``D = 300 mm``). A length formula is not a covariance; mtmc reads
it as two independent parts (stated in ``docs/artefact.md``):

- each centre coordinate has an independent error of standard deviation ``a / sqrt(2)``,
  so that the difference of two centres along any direction has ``u = a``;
- a common scale error ``s`` with ``u(s) = 1 / D`` (µm per mm), acting about the centroid
  ``c̄`` of the centres: ``e_i = s (c_i - c̄)``.

Hence ``Cov(c_i, c_j) = (a² / 2) δ_ij I₃ + u(s)² (c_i - c̄)(c_j - c̄)ᵀ`` and, for the
distance ``L_ij = |c_i - c_j|``, ``u(L_ij) = sqrt(a² + (L_ij / D)²)``: the two parts
combined in quadrature (JCGM 100 §5.1.2) rather than added, which is at most the printed
sum (0.47 µm instead of 0.65 µm at L = 120 mm).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import InputError
from mtmc.frozen import frozen_floats

__all__ = [
    "Artefact",
    "distances",
    "load_artefact",
    "loads_artefact",
    "pairs",
    "shipped_artefact",
]

_F = NDArray[np.float64]


def pairs(n: int) -> tuple[tuple[int, int], ...]:
    """The ``n (n - 1) / 2`` ball pairs ``(i, j)``, ``i < j``, in row order.

    Parameters
    ----------
    n : int
        Number of balls.

    Returns
    -------
    tuple of (int, int)
        0-based indices; for five balls (1,2) (1,3) (1,4) (1,5) (2,3) ... (4,5) in the
        1-based numbering of the paper.

    Examples
    --------
    >>> pairs(3)
    ((0, 1), (0, 2), (1, 2))
    """
    return tuple((i, j) for i in range(n) for j in range(i + 1, n))


def distances(centres: npt.ArrayLike) -> _F:
    """Inter-fiducial distances ``|c_i - c_j|`` for every pair of :func:`pairs`, batched.

    Parameters
    ----------
    centres : array_like, shape (..., N, 3)
        Ball centres, mm.

    Returns
    -------
    ndarray, shape (..., N (N - 1) / 2)
        mm.

    Examples
    --------
    >>> distances([[0, 0, 0], [3, 4, 0], [0, 0, 1]]).tolist()
    [5.0, 1.0, 5.0990195135927845]
    """
    c = np.asarray(centres, dtype=np.float64)
    n = c.shape[-2]
    if n < 2:
        return np.zeros((*c.shape[:-2], 0))
    # ball i against the balls after it, in the order of pairs(): slices, not an index
    d = np.concatenate([c[..., i : i + 1, :] - c[..., i + 1 :, :] for i in range(n - 1)], -2)
    return np.asarray(np.sqrt(d[..., 0] ** 2 + d[..., 1] ** 2 + d[..., 2] ** 2), np.float64)


@dataclass(frozen=True, eq=False)
class Artefact:
    """Calibrated balls on a fixture.

    Parameters
    ----------
    names : tuple of str
        Ball names (``"1" ... "5"``).
    centres : ndarray, shape (N, 3)
        CMM-calibrated centres in the artefact frame, mm.
    diameter : float
        Calibrated ball diameter, mm.
    cmm_a_um : float
        Constant part ``a`` of the CMM uncertainty ``u(L) = a + L / D``, µm.
    cmm_divisor_mm : float
        ``D`` of the CMM uncertainty, mm (``L / D`` in µm with L in mm).
    position : ndarray, shape (3,)
        Mounting: origin of the artefact frame in the frame of the machine's last
        part-side body, mm.
    rotation : ndarray, shape (3, 3)
        Mounting: orientation of the artefact frame in that body (columns: the artefact's
        axes), orthonormal.
    name : str
        A label.
    """

    names: tuple[str, ...]
    centres: _F
    diameter: float
    cmm_a_um: float = 0.25
    cmm_divisor_mm: float = 300.0
    position: _F = field(default_factory=lambda: np.zeros(3))
    rotation: _F = field(default_factory=lambda: np.eye(3))
    name: str = ""

    def __post_init__(self) -> None:
        c = np.asarray(self.centres, dtype=np.float64)
        if c.ndim != 2 or c.shape[1] != 3 or c.shape[0] < 2 or not np.all(np.isfinite(c)):
            raise InputError(
                f"expected at least 2 finite ball centres of shape (N, 3), got {c.shape}",
                field="centres",
            )
        if len(self.names) != c.shape[0] or len(set(self.names)) != len(self.names):
            raise InputError(
                f"expected {c.shape[0]} distinct ball names, got {list(self.names)}",
                field="names",
            )
        for key in ("diameter", "cmm_divisor_mm"):
            v = getattr(self, key)
            if not (np.isfinite(v) and v > 0):
                raise InputError(f"expected a number > 0, got {v!r}", field=key)
        if not (np.isfinite(self.cmm_a_um) and self.cmm_a_um >= 0):
            raise InputError(f"expected a number >= 0, got {self.cmm_a_um!r}", field="cmm_a_um")
        p = np.asarray(self.position, dtype=np.float64)
        r = np.asarray(self.rotation, dtype=np.float64)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise InputError(f"expected 3 finite numbers, got {self.position!r}", field="position")
        if r.shape != (3, 3) or not np.allclose(r.T @ r, np.eye(3), atol=1e-9):
            raise InputError("expected an orthonormal 3 x 3 rotation", field="rotation")
        if np.linalg.det(r) < 0:
            raise InputError("expected a proper rotation (det = +1)", field="rotation")
        object.__setattr__(self, "names", tuple(self.names))
        object.__setattr__(self, "centres", frozen_floats(c))
        object.__setattr__(self, "position", frozen_floats(p))
        object.__setattr__(self, "rotation", frozen_floats(r))
        object.__setattr__(self, "diameter", float(self.diameter))

    @property
    def n_balls(self) -> int:
        """Number of balls ``N``."""
        return int(self.centres.shape[0])

    @property
    def radius(self) -> float:
        """Calibrated ball radius, mm."""
        return 0.5 * self.diameter

    def mounted_centres(self) -> _F:
        """Ball centres in the frame of the last part-side body, ``R c_i + t``, shape (N, 3)."""
        return self.centres @ self.rotation.T + self.position

    def mounted(self, position: npt.ArrayLike, rotation: npt.ArrayLike | None = None) -> Artefact:
        """The same artefact with another mounting.

        Parameters
        ----------
        position : array_like, shape (3,)
            mm.
        rotation : array_like, shape (3, 3), optional
            Default: the identity.

        Returns
        -------
        Artefact
        """
        return Artefact(
            self.names,
            self.centres,
            self.diameter,
            self.cmm_a_um,
            self.cmm_divisor_mm,
            np.asarray(position, dtype=np.float64),
            np.eye(3) if rotation is None else np.asarray(rotation, dtype=np.float64),
            self.name,
        )

    def length_uncertainty(self, length: npt.ArrayLike) -> _F:
        """The printed CMM formula ``u(L) = a + L / D``, µm (L in mm).

        Examples
        --------
        >>> shipped_artefact().length_uncertainty([0.0, 120.0]).tolist()
        [0.25, 0.65]
        """
        return self.cmm_a_um + np.asarray(length, dtype=np.float64) / self.cmm_divisor_mm

    def centre_covariance(self) -> _F:
        """Covariance of the calibrated centres (artefact frame), shape (3N, 3N), mm².

        ``Cov(c_i, c_j) = (a² / 2) δ_ij I₃ + u(s)² (c_i - c̄)(c_j - c̄)ᵀ`` with
        ``u(s) = 10⁻³ / D`` (a relative scale error; see the module notes). Rows in the
        order ``x₁ y₁ z₁ x₂ ...``.
        """
        n = self.n_balls
        a = self.cmm_a_um * 1e-3
        us = 1e-3 / self.cmm_divisor_mm
        d = (self.centres - self.centres.mean(axis=0)).reshape(-1)
        return 0.5 * a * a * np.eye(3 * n) + us * us * np.outer(d, d)

    def distance_uncertainty(self) -> _F:
        """``u(L_ij) = sqrt(a² + (L_ij / D)²)`` for each pair, µm: the stated covariance model.

        Examples
        --------
        >>> np.round(shipped_artefact().distance_uncertainty()[:2], 3).tolist()
        [0.466, 0.509]
        """
        d = distances(self.centres)
        return np.sqrt(self.cmm_a_um**2 + (d / self.cmm_divisor_mm) ** 2)


def loads_artefact(text: str, file: str = "<artefact>") -> Artefact:
    """Read an artefact from TOML text (format: ``docs/artefact.md``).

    Keys: ``name``, ``description``, ``diameter`` (mm), ``[cmm]`` with ``a_um`` and
    ``divisor_mm``, and one ``[[ball]]`` per ball with ``name`` and ``centre`` (mm).

    Raises
    ------
    ParseError
        If the text is not TOML.
    InputError
        On a missing or malformed field, naming the file, line and field.
    """
    from mtmc.document import MAX_MM, Fields, loads_toml

    top = loads_toml(text, file)
    src, data = top.source, top.data
    top.only(("name", "description", "diameter", "cmm", "ball"))
    diameter = top.number("diameter", low=0.0, high=MAX_MM, open_low=True)
    cmm = top.table("cmm", required=False)
    a_um, divisor = 0.25, 300.0
    if cmm is not None:
        cmm.only(("a_um", "divisor_mm"))
        a_um = cmm.number("a_um", a_um, low=0.0)
        divisor = cmm.number("divisor_mm", divisor, low=0.0, open_low=True)
    balls = data.get("ball")
    if not isinstance(balls, list) or len(balls) < 2:
        raise top.error("expected at least two [[ball]] tables", "ball")
    if len(balls) > MAX_BALLS:
        raise top.error(f"expected at most {MAX_BALLS} [[ball]] tables, got {len(balls)}", "ball")
    names, centres = [], []
    for k, raw in enumerate(balls):
        if not isinstance(raw, dict):
            raise src.error("expected a [[ball]] table", ("ball", k))
        f = Fields(src, raw, ("ball", k))
        f.only(("name", "centre"))
        name = f.text("name")
        if name in names:
            raise f.error(f"ball {name!r} given twice", "name")
        names.append(name)
        centres.append(_triple(f, "centre"))
    return Artefact(
        tuple(names),
        np.array(centres),
        float(diameter),
        float(a_um),
        float(divisor),
        name=str(top.text("name", "")),
    )


def _triple(f: Any, key: str) -> list[float]:
    """Three finite numbers from field ``key`` of a :class:`~mtmc.document.Fields`."""
    from mtmc.document import MAX_MM

    return list(f.numbers(key, 3, limit=MAX_MM, what="three finite numbers [x, y, z] (mm)"))


#: The most balls an artefact file may have.
MAX_BALLS = 100


def load_artefact(path: str | Path) -> Artefact:
    """Read an artefact file (see :func:`loads_artefact`).

    Raises
    ------
    InputError
        If the file cannot be read, or on a bad field (file, line, field named).
    """
    from mtmc.document import read_text

    p = Path(path)
    return loads_artefact(read_text(p, "artefact file"), file=str(p))


SHIPPED = ("wang2022_five_ball",)


def shipped_artefact(name: str = "wang2022_five_ball") -> Artefact:
    """A shipped artefact: ``wang2022_five_ball`` (Wang, Cheung and Kong 2022, Table 1).

    Examples
    --------
    >>> a = shipped_artefact()
    >>> a.n_balls, a.diameter, float(a.centres[1, 1])
    (5, 9.997, 0.864597)
    """
    if name not in SHIPPED:
        raise InputError(f"unknown artefact {name!r}; shipped: {', '.join(SHIPPED)}", field="name")
    res = resources.files("mtmc").joinpath("data", "artefacts", f"{name}.toml")
    return loads_artefact(res.read_text(encoding="utf-8"), file=f"{name}.toml")
