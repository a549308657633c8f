r"""Error coefficients written as Aguado writes them, mapped to the ISO 230-1 errors of mtmc.

Aguado et al. 2017 (eqs. 1, 6-9) and Aguado et al. 2016 (eqs. 3, 6-12) write each linear
axis K as a vector and a rotation matrix,

.. math:: \mathbf K = \pm k\,\mathbf e_K + \boldsymbol\delta_K
          - k \sum_{i \ne K} S_{iK}\,\mathbf e_i, \qquad
          \mathbf R_K \approx \mathbf I \pm [\boldsymbol\varepsilon_K]_\times,

with ``+k`` for an axis that moves the tool and ``−k`` for one that moves the part, and nest
them from the frame outwards: a tool-side axis maps ``v`` (in the body it carries) to
``R_K v + K``; a part-side axis maps the part's coordinates the same way, so the tool in
the part's frame is ``R_K⁻¹ (v − K)``. Their δ and ε of a part-side axis are therefore the
motion of the *part*, and its rotation pivots about the moving table's origin ``K``. mtmc's
errors (``docs/conventions.md``) are motions of the tool relative to the workpiece, with a
linear axis's rotation about its pivot ``o`` (the origin by default), the same on both
sides. To first order the two agree when, for a **tool-side** axis,

.. math:: E_{\cdot K} = \boldsymbol\delta_K, \qquad E_{[ABC]K} = \boldsymbol\varepsilon_K,

and for a **part-side** axis

.. math:: E_{\cdot K} = -\boldsymbol\delta_K - k\,(\boldsymbol\varepsilon_K \times \mathbf e_K),
          \qquad E_{[ABC]K} = -\boldsymbol\varepsilon_K,

e.g. for X: ``EXX = −δx,x``, ``EYX = −δy,x − x·εz,x``, ``EZX = −δz,x + x·εy,x`` (ε in the
active form of Aguado et al. 2017, eq. 6). The squareness ``S_iK`` (Aguado writes
``−k·S_iK`` in component ``i`` of axis K) is the tilt of K towards ``i``: on the tool side
the tool moves by ``−k·S_iK`` along ``i``, on the part side by ``+k·S_iK``; it becomes the
ISO squareness ``E[ABC]0K`` about the third direction (e.g. ``EC0Y = S_xy``,
``EB0Z = −S_xz``, ``EA0Z = S_yz``, ``EC0X = S_yx``, ``EB0X = −S_zx``, ``EA0Y = S_zy``).

Aguado et al. 2016, eq. (12), prints ``R(k) = [[1, ECK, −EBK], [−ECK, 1, EAK], [EBK,
−EAK, 1]] = I − [e]×``, the passive form: ``rotation="passive"`` reads its ``EAK, EBK,
ECK`` as ``e`` with ``ε = −e``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Literal

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import InputError, TopologyError
from mtmc.kinematics.topology import AXIS_DIRECTION, Topology, parse_topology

__all__ = ["aguado_error_names", "iso_errors_from_aguado"]

_C = "xyz"
_ISO_T = "XYZ"
_ISO_R = "ABC"


def aguado_error_names(topology: str | Topology) -> tuple[str, ...]:
    """The names :func:`iso_errors_from_aguado` reads for a machine.

    ``d<i><k>`` is δ_{i,k} (``dxx`` positioning of X, ``dyx`` straightness of X along y),
    ``e<i><k>`` is ε_{i,k} (rotation of axis k about i), ``S<i><k>`` the squareness of
    axis k towards i (Aguado's ``S_ik``, written ``−k·S_ik`` in component i).

    Parameters
    ----------
    topology : str or Topology
        The machine (linear axes X, Y, Z only).

    Returns
    -------
    tuple of str

    Examples
    --------
    >>> aguado_error_names("XFYZ")[:8]
    ('dxx', 'dyx', 'dzx', 'exx', 'eyx', 'ezx', 'Syx', 'Szx')
    """
    topo = _topology(topology)
    names: list[str] = []
    for ax in topo.chain:
        k = ax.lower()
        names += [f"d{c}{k}" for c in _C] + [f"e{c}{k}" for c in _C]
        names += [f"S{c}{k}" for c in _C if c != k]
    return tuple(names)


def _topology(topology: str | Topology) -> Topology:
    topo = topology if isinstance(topology, Topology) else parse_topology(topology)
    bad = [ax for ax in topo.chain if ax not in _ISO_T]
    if bad:
        raise TopologyError(
            f"axis {bad[0]}: the mapping of Aguado's coefficients covers the linear axes "
            "X, Y and Z",
            field="topology",
        )
    return topo


def iso_errors_from_aguado(
    topology: str | Topology,
    q: npt.ArrayLike,
    errors: Mapping[str, npt.ArrayLike],
    *,
    rotation: Literal["active", "passive"] = "active",
) -> dict[str, NDArray[np.float64]]:
    """The ISO 230-1 errors of mtmc equal to Aguado's coefficients at positions ``q``.

    Parameters
    ----------
    topology : str or Topology
        The machine, e.g. ``"XFYZ"`` or ``"ZYXF"`` (linear axes X, Y, Z).
    q : array_like, shape (M, n_axes) or (n_axes,)
        Axis positions in the order of ``Topology.axes`` (X Y Z), mm. The part-side
        mapping depends on them (the lever ``k`` of the pivot).
    errors : mapping of str to float or array (M,)
        Aguado's coefficients by :func:`aguado_error_names` (missing ones are zero):
        δ in mm, ε and S in rad, each already evaluated at ``q``.
    rotation : {"active", "passive"}
        ``"active"``: ``R_K = I + [ε]×`` (Aguado et al. 2017, eq. 6); ``"passive"``:
        ``R(k) = I − [e]×`` (Aguado et al. 2016, eq. 12), ``ε = −e``.

    Returns
    -------
    dict of str to ndarray, shape (M,)
        ``EXK EYK EZK EAK EBK ECK`` of every axis and the squareness ``E[ABC]0K`` that
        are not zero, for :meth:`mtmc.kinematics.Machine.tool_position`.

    Raises
    ------
    InputError
        On an unknown name, or ``q`` of the wrong shape.
    TopologyError
        For a rotary or secondary linear axis.

    Examples
    --------
    >>> e = iso_errors_from_aguado("XFYZ", [[100.0, 0.0, 0.0]], {"dyx": 0.002, "ezx": 1e-5})
    >>> {k: round(float(v[0]), 6) for k, v in e.items() if v[0]}
    {'EYX': -0.003, 'ECX': -1e-05}
    """
    topo = _topology(topology)
    known = aguado_error_names(topo)
    unknown = [n for n in errors if n not in known]
    if unknown:
        raise InputError(
            f"unknown coefficient {unknown[0]!r}; this machine has {', '.join(known)}",
            field=unknown[0],
        )
    if rotation not in ("active", "passive"):
        raise InputError(f"expected 'active' or 'passive', got {rotation!r}", field="rotation")
    qa = np.asarray(q, dtype=np.float64)
    qa = qa[None, :] if qa.ndim == 1 else qa
    if qa.ndim != 2 or qa.shape[1] != len(topo.axes):
        raise InputError(
            f"expected q of shape (M, {len(topo.axes)}) in the order {' '.join(topo.axes)}, "
            f"got {qa.shape}",
            field="q",
        )
    m = qa.shape[0]

    def get(name: str) -> NDArray[np.float64]:
        return np.broadcast_to(np.asarray(errors.get(name, 0.0), dtype=np.float64), (m,))

    out: dict[str, NDArray[np.float64]] = {}
    for ax in topo.chain:
        k, d = ax.lower(), AXIS_DIRECTION[ax]
        travel = qa[:, topo.axes.index(ax)]
        delta = np.stack([get(f"d{c}{k}") for c in _C], axis=1)
        eps = np.stack([get(f"e{c}{k}") for c in _C], axis=1)
        if rotation == "passive":
            eps = -eps
        part = topo.side(ax) == "part"
        if part:
            e_k = np.zeros(3)
            e_k[d] = 1.0
            lin = -delta - travel[:, None] * np.cross(eps, e_k)
            ang = -eps
        else:
            lin, ang = delta, eps
        for j in range(3):
            out[f"E{_ISO_T[j]}{ax}"] = lin[:, j]
        for j in range(3):
            out[f"E{_ISO_R[j]}{ax}"] = ang[:, j]
        for i in range(3):
            if i == d or f"S{_C[i]}{k}" not in errors:
                continue
            # the tool moves by -k S (tool side) or +k S (part side) along i; the ISO
            # squareness is a rotation s about the third direction m: k s (e_m x e_K)_i
            slope = get(f"S{_C[i]}{k}") * (1.0 if part else -1.0)
            mth = 3 - i - d
            sigma = float(np.cross(np.eye(3)[mth], np.eye(3)[d])[i])
            out[f"E{_ISO_R[mth]}0{ax}"] = slope / sigma
    return out
