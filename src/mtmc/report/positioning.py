"""The plot of a positioning test (ISO 230-2) in the report, from ``positioning`` of a result."""

from __future__ import annotations

from typing import Any

import numpy as np

from mtmc.report.plots import _figure, _svg

__all__ = ["positioning_svg"]


def positioning_svg(pos: dict[str, Any]) -> str:
    """Deviations against target position, both directions, with the mean ± 2s bands.

    The plot of ISO 230-2's test report: each reading as a dot (↑ and ↓ apart), the mean
    unidirectional deviations ``x̄_i↑``, ``x̄_i↓`` as lines and ``x̄ ± 2s`` as dashed
    lines, whose outer envelope spans the accuracy A.

    Parameters
    ----------
    pos : dict
        ``positioning`` of ``result.json``: ``targets``, ``deviations`` ``(m, n, 2)``,
        ``mean_up``, ``mean_down``, ``s_up``, ``s_down``, ``unit``, ``target_unit``,
        ``axis``.

    Returns
    -------
    str
        One ``<svg>`` element.
    """
    p = np.asarray(pos["targets"], dtype=np.float64)
    x = np.asarray(pos["deviations"], dtype=np.float64)
    fig = _figure(8.0, 4.2, left=0.1, right=0.97, bottom=0.13, top=0.92)
    ax = fig.add_subplot(1, 1, 1)
    span = float(p[-1] - p[0]) or 1.0
    off = 0.006 * span
    for d, (label, colour, key, marker) in enumerate(
        (("↑ positive direction", "C0", "up", "^"), ("↓ negative direction", "C3", "down", "v"))
    ):
        mean = np.asarray(pos[f"mean_{key}"], dtype=np.float64)
        s = np.asarray(pos[f"s_{key}"], dtype=np.float64)
        shift = -off if d == 0 else off
        pp = np.repeat(p + shift, x.shape[1])
        ax.plot(pp, x[:, :, d].reshape(-1), marker, color=colour, ms=3.5, alpha=0.6, ls="none")
        ax.plot(p, mean, "-", color=colour, lw=1.4, label=f"x̄ {label}")
        ax.plot(p, mean + 2 * s, "--", color=colour, lw=0.9, label=f"x̄ ± 2s {label[0]}")
        ax.plot(p, mean - 2 * s, "--", color=colour, lw=0.9)
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.set_xlabel(f"target position P / {pos['target_unit']}")
    ax.set_ylabel(f"positional deviation x / {pos['unit']}")
    ax.set_title(
        f"Axis {pos['axis']}: {x.shape[1]} runs in each direction at {p.size} targets", fontsize=9
    )
    ax.legend(fontsize=7, ncol=2, loc="best")
    ax.grid(True, lw=0.3, alpha=0.5)
    return _svg(fig, "positioning")
