"""The error-vector plot of Wang, Cheung and Kong (2022), Fig. 7: xy, xz and 3D views.

Each ball at each pose is drawn at its commanded linear-axis position (the machine's
coordinates, mm) with an arrow of its volumetric error (modelled minus calibrated centre,
in the axis directions ``A⁻¹ v``), magnified by a stated factor (the paper's is 10 000).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from mtmc.artefact.simulation import ArtefactResult

__all__ = ["plot_error_vectors"]


def plot_error_vectors(
    result: ArtefactResult, path: str | Path, *, magnification: float = 10_000.0
) -> Path:
    """Draw Fig. 7 into ``path`` (.svg, .png or .pdf), written atomically.

    Parameters
    ----------
    result : ArtefactResult
        A simulated study.
    path : str or Path
        The output file.
    magnification : float
        Factor the error vectors are multiplied by (stated in the title).

    Returns
    -------
    Path
        ``path``.
    """
    from matplotlib import colormaps
    from matplotlib.figure import Figure

    from mtmc.io import atomic_path

    meas = result.measurement
    pos = meas.commanded  # (P, N, 3) axis positions
    v = result.nominal.volumetric[0]  # (P, N, 3) in W
    vec = meas.in_axes(v) * magnification
    labels = result.pose_labels()
    fig = Figure(figsize=(13, 4.4))  # no pyplot: nothing of the process changes
    ax1 = fig.add_subplot(1, 3, 1)
    ax2 = fig.add_subplot(1, 3, 2)
    ax3: Any = fig.add_subplot(1, 3, 3, projection="3d")
    colors = colormaps["tab10"](np.arange(pos.shape[0]) % 10)
    for p in range(pos.shape[0]):
        lab = ", ".join(f"{k[0]} = {val:g}°" for k, val in labels[p].items())
        x, y, z = pos[p].T
        u, w, t = vec[p].T
        ax1.quiver(x, y, u, w, color=colors[p], angles="xy", scale_units="xy", scale=1, label=lab)
        ax2.quiver(x, z, u, t, color=colors[p], angles="xy", scale_units="xy", scale=1)
        ax3.quiver(x, y, z, u, w, t, color=colors[p])
        ax1.plot(x, y, ".", color=colors[p])
        ax2.plot(x, z, ".", color=colors[p])
    names = result.study.setup.linear
    for ax, (a, b), title in (
        (ax1, (0, 1), "(a) xy view"),
        (ax2, (0, 2), "(b) xz view"),
    ):
        ax.set_xlabel(f"{names[a]} (mm)")
        ax.set_ylabel(f"{names[b]} (mm)")
        ax.set_title(title)
        ax.set_aspect("equal", adjustable="datalim")
    ax3.set_xlabel(f"{names[0]} (mm)")
    ax3.set_ylabel(f"{names[1]} (mm)")
    ax3.set_zlabel(f"{names[2]} (mm)")
    ax3.set_title("(c) 3D view")
    ax1.legend(fontsize=6, loc="best")
    mean_um = float(np.linalg.norm(v, axis=2).mean() * 1e3)
    fig.suptitle(
        f"Volumetric errors at {pos.shape[0]} rotary poses, vectors magnified "
        f"{magnification:g} times (mean {mean_um:.2f} µm)"
    )
    fig.tight_layout()
    out = Path(path)
    with atomic_path(out) as tmp:
        fig.savefig(tmp, format=out.suffix.lstrip(".").lower() or "svg")
    return out
