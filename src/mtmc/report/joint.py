"""The plot of two outputs of one model together: trials and coverage ellipses (JCGM 102).

Drawn from the ``joint`` entry of ``result.json`` alone (``docs/results-format.md``): the
first trials as dots and the two coverage regions of JCGM 102 — the Monte Carlo ellipse
(§7.7.2: the sample covariance, ``k_p`` the ``p``-quantile of the Mahalanobis distances
of the trials) and the GUM ellipse (§6.5.2.3: ``U_y = C U_x Cᵀ``, ``k_p² = χ²₂(p)``) —
each about its own estimate, as deviations from the Monte Carlo estimate.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mtmc.report.plots import _figure, _svg, display_unit, per_unit

__all__ = ["joint_svg"]


def _boundary(e: dict[str, Any], n: int = 241) -> NDArray[np.float64]:
    """``n`` points on the ellipse ``centre + Σ_i cos/sin(t) semi_axes_i axes[:, i]``."""
    t = np.linspace(0.0, 2.0 * np.pi, n)
    circle = np.stack([np.cos(t), np.sin(t)], axis=1) * np.asarray(e["semi_axes"])
    pts: NDArray[np.float64] = np.asarray(e["centre"]) + circle @ np.asarray(e["axes"]).T
    return pts


def joint_svg(joint: dict[str, Any]) -> str:
    """Trials of two outputs with their Monte Carlo and GUM coverage ellipses, as SVG.

    Parameters
    ----------
    joint : dict
        The ``joint`` entry of ``result.json`` of a study of two outputs, with a
        ``region`` (its ``scatter``, ``monte_carlo`` and ``gum`` ellipses).

    Returns
    -------
    str
        One ``<svg>`` element. Each axis is in the unit of its output, as its tables
        give it, as the deviation from the Monte Carlo estimate.
    """
    region = joint["region"]
    names, units = joint["outputs"], joint["units"]
    shown = [display_unit(u) for u in units]
    scale = np.array([f for f, _ in shown])
    origin = np.asarray(region["monte_carlo"]["centre"])
    pts = (np.asarray(region["scatter"]) - origin) * scale
    mc = (_boundary(region["monte_carlo"]) - origin) * scale
    gum = (_boundary(region["gum"]) - origin) * scale
    fig = _figure(3.8, 3.5, left=0.2, right=0.97, bottom=0.14, top=0.97)
    ax = fig.add_subplot(1, 1, 1)
    ax.plot(pts[:, 0], pts[:, 1], ".", ms=2, color="C0", alpha=0.5)
    p = 100 * float(joint["p"])
    ax.plot(
        mc[:, 0],
        mc[:, 1],
        color="C3",
        lw=1.4,
        label=f"Monte Carlo {p:g} %, k = {region['monte_carlo']['k']:.3f}",
    )
    ax.plot(
        gum[:, 0],
        gum[:, 1],
        color="k",
        ls="--",
        lw=0.9,
        label=f"GUM {p:g} %, k = {region['gum']['k']:.3f}",
    )
    ax.plot([0.0], [0.0], "+", color="C3", ms=6)
    centre_gum = (np.asarray(region["gum"]["centre"]) - origin) * scale
    ax.plot([centre_gum[0]], [centre_gum[1]], "x", color="k", ms=5)
    if units[0] == units[1]:
        ax.set_aspect("equal", adjustable="datalim")
    for axis, name, (_, label) in zip((ax.set_xlabel, ax.set_ylabel), names, shown, strict=True):
        axis(f"{name} − estimate{per_unit(label)}")
    ax.legend(fontsize=6, loc="upper right")
    return _svg(fig, "joint")
