"""The polar plot of a circular test (ISO 230-4) in the report, from ``circular`` of a result."""

from __future__ import annotations

from typing import Any

import numpy as np

from mtmc.report.plots import _figure, _svg

__all__ = ["circular_svg", "rotary_svg"]


def circular_svg(circ: dict[str, Any]) -> str:
    """The trace of each direction on a polar plot, its deviation magnified.

    The plot a ballbar user reads: the nominal circle as the reference ring, each
    direction's trace at the reference radius plus its radial deviation magnified, the
    least-squares circle (LSC) and the two concentric circles of the minimum zone (MZ) of
    the counter-clockwise trace, and where the study gives an upper limit of ``G_lsc`` the
    tolerance band of that width centred on the LSC.

    Parameters
    ----------
    circ : dict
        ``circular`` of ``result.json``: ``theta_deg``, ``direction``, ``trace_um``,
        ``circles`` (``lsc``, ``mz``, ``mz_width`` per direction, µm), ``limits``,
        ``radius``, ``plane``.

    Returns
    -------
    str
        One ``<svg>`` element.
    """
    theta = np.radians(np.asarray(circ["theta_deg"], dtype=np.float64))
    d = np.asarray(circ["direction"], dtype=np.float64)
    dev = np.asarray(circ["trace_um"], dtype=np.float64)
    circles = circ["circles"]
    g_upper = (circ.get("limits", {}).get("G_lsc") or {}).get("upper")
    span = max(float(np.ptp(dev)), float(g_upper or 0.0), 1e-9)
    # the reference ring at 1, the deviations scaled so that the widest span is 0.5
    mag = 0.5 / span
    centre = 0.5 * (float(dev.max()) + float(dev.min()))
    t = np.linspace(0.0, 2.0 * np.pi, 721)

    def ring(r: Any, angle: Any) -> tuple[Any, Any]:
        rr = 1.0 + mag * (np.asarray(r) - centre)
        return rr * np.cos(angle), rr * np.sin(angle)

    fig = _figure(6.0, 6.0, left=0.04, right=0.96, bottom=0.04, top=0.92)
    ax = fig.add_subplot(1, 1, 1)
    ax.plot(*ring(np.full(t.size, centre), t), color="0.6", lw=0.6, label="nominal circle")
    for sign, colour, label in ((1.0, "C0", "CCW"), (-1.0, "C3", "CW")):
        idx = d == sign
        if not np.any(idx):
            continue
        order = np.argsort(np.mod(theta[idx], 2.0 * np.pi))
        th = np.mod(theta[idx], 2.0 * np.pi)[order]
        x, y = ring(dev[idx][order], th)
        ax.plot(np.append(x, x[0]), np.append(y, y[0]), color=colour, lw=1.2, label=label)
    first = circles.get("ccw") or circles.get("cw")
    c, a, b = (float(v) for v in first["lsc"])
    lsc = c + a * np.cos(t) + b * np.sin(t)
    ax.plot(*ring(lsc, t), "--", color="k", lw=0.8, label="LSC")
    cm, am, bm = (float(v) for v in first["mz"])
    half = 0.5 * float(first["mz_width"])
    mid = cm + am * np.cos(t) + bm * np.sin(t)
    ax.plot(*ring(mid + half, t), ":", color="C2", lw=1.0, label="MZ circles")
    ax.plot(*ring(mid - half, t), ":", color="C2", lw=1.0)
    if g_upper:
        lo_x, lo_y = ring(lsc - 0.5 * g_upper, t)
        hi_x, hi_y = ring(lsc + 0.5 * g_upper, t)
        ax.fill(
            np.concatenate([hi_x, lo_x[::-1]]),
            np.concatenate([hi_y, lo_y[::-1]]),
            color="C1",
            alpha=0.12,
            lw=0,
            label=f"tolerance G ≤ {g_upper:g} µm about the LSC",
        )
    ax.set_aspect("equal")
    ax.set_axis_off()
    ax.set_title(
        f"{circ['plane']}, R = {circ['radius']:g} mm: the radial deviation magnified, "
        f"{2.0 * span:.3g} µm to the nominal circle's radius",
        fontsize=8,
    )
    ax.legend(fontsize=7, loc="lower right")
    return _svg(fig, "circular")


def rotary_svg(circ: dict[str, Any]) -> str:
    """A rotary-axis test's readings against the rotary angle.

    Parameters
    ----------
    circ : dict
        ``circular`` of ``result.json`` of a rotary test: ``rotary`` (``machine``,
        ``axis``, ``angle_deg``, ``instrument``) and the R-test's ``displacement_um``
        ``(n, 3)`` or the ballbar's ``reading_um`` ``(n,)``: at the inputs' estimates
        (exact kinematics) or as measured.

    Returns
    -------
    str
        One ``<svg>`` element.
    """
    rot = circ["rotary"]
    a = np.asarray(rot["angle_deg"], dtype=np.float64)
    fig = _figure(8.0, 4.2, left=0.1, right=0.97, bottom=0.13, top=0.92)
    ax = fig.add_subplot(1, 1, 1)
    if "reading_um" in circ:
        r = np.asarray(circ["reading_um"], dtype=np.float64)
        ax.plot(a, r, "o-", color="C0", ms=3.0, lw=1.1, label="ballbar reading")
        ax.set_ylabel("change of the bar's length / µm")
        what = f"ballbar along {tuple(rot.get('direction', ()))}"
    else:
        e = np.asarray(circ["displacement_um"], dtype=np.float64)
        for k, (name, colour) in enumerate((("x", "C0"), ("y", "C3"), ("z", "C2"))):
            ax.plot(a, e[:, k], "o-", color=colour, ms=3.0, lw=1.1, label=f"δ{name}")
        ax.set_ylabel("displacement of the sphere / µm")
        what = "R-test"
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.set_xlabel(f"{rot['axis']} / deg")
    ax.set_title(
        f"{rot['machine']}: {rot['axis']}-axis test, {what}, {a.size} positions", fontsize=9
    )
    ax.legend(fontsize=7, loc="best")
    ax.grid(True, lw=0.3, alpha=0.5)
    return _svg(fig, "rotary")
