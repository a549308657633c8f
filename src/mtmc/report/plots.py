"""The plots of the report, as inline SVG text, drawn from the entries of ``result.json``.

Each function takes the JSON-ready dictionaries of a result folder (a quantity, a region,
a sweep) and returns one ``<svg>`` element as text (Matplotlib, no pyplot, fonts left to
the browser). Every value is drawn in the unit its entry states, the unit the study is
written in and its tables show (``docs/results-format.md``, the unit rule); the
distributions of a quantity as deviations from its estimate.
"""

from __future__ import annotations

import io
import itertools
import re
from typing import Any

import numpy as np

__all__ = [
    "convergence_svg",
    "display_unit",
    "field_figure",
    "field_svg",
    "graph_svg",
    "histogram_svg",
    "machine_svg",
    "region_svg",
    "sweep_svg",
    "vector_magnification",
]


def display_unit(unit: str) -> tuple[float, str]:
    """The factor and unit a value in ``unit`` is shown in: the unit itself, factor 1.

    A result holds its numbers in the unit of its study (``um`` written ``µm``), and its
    plots show them in that unit, as its tables do: a plot and the table of one quantity
    never differ in unit.

    Examples
    --------
    >>> display_unit("mm"), display_unit("µm"), display_unit("um"), display_unit("rad")
    ((1.0, 'mm'), (1.0, 'µm'), (1.0, 'µm'), (1.0, 'rad'))
    """
    return 1.0, _SYMBOL.get(unit, unit)


def per_unit(label: str, power: str = "") -> str:
    """The `` / unit`` of an axis label (ISO 80000-1: quantity / unit), ``""`` for none.

    A unit written with a solidus or a product is put in parentheses, so that a division
    of the quantity by it (and a power of it) reads one way only.

    Examples
    --------
    >>> per_unit("µm"), per_unit("µm/m"), per_unit("µm/m", "⁻¹"), per_unit("1")
    (' / µm', ' / (µm/m)', ' / (µm/m)⁻¹', '')
    """
    if label in ("", "1"):
        return ""
    if any(c in label for c in "/·* "):
        label = f"({label})"
    return f" / {label}{power}"


#: SI symbols of the units a study file may spell in ASCII.
_SYMBOL = {"um": "µm", "urad": "µrad"}

#: Units of length per mm: the error vectors of a field are drawn among its points, in mm.
_PER_MM = {"mm": 1.0, "µm": 1e3, "um": 1e3, "nm": 1e6, "m": 1e-3}


def _vectors_mm(f: dict[str, Any]) -> Any:
    """The vectors of a field of error vectors, ``(n, 3)``, in the mm of its points."""
    vec = np.asarray(f["values"], dtype=np.float64).reshape(-1, 3)
    return vec / _PER_MM.get(str(f.get("unit", "mm")), 1.0)


#: The least gap between two tick labels of an axis, and between a text and the figure's
#: edge, in points.
_GAP = 2.0


def _ticks_touch(axis: Any, renderer: Any) -> bool:
    """Whether two neighbouring tick labels of a linear ``axis`` come closer than ``_GAP``.

    The labels are those its locator and formatter give for the view, measured in the
    font of tick labels where the axis puts them; no tick is drawn.
    """
    from matplotlib import rcParams
    from matplotlib.font_manager import FontProperties

    lo, hi = sorted(axis.get_view_interval())
    eps = 1e-9 * max(abs(lo), abs(hi), hi - lo)
    locs = [v for v in axis.get_major_locator()() if lo - eps <= v <= hi + eps]
    texts = axis.get_major_formatter().format_ticks(locs)
    x = axis.axis_name == "x"
    prop = FontProperties(size=rcParams["xtick.labelsize" if x else "ytick.labelsize"])
    xy = [(v, 0.0) if x else (0.0, v) for v in locs]
    at = axis.axes.transData.transform(xy)[:, 0 if x else 1]
    ends = []
    for c, text in zip(at, texts, strict=True):
        w, h, _ = renderer.get_text_width_height_descent(text, prop, ismath=False)
        half = (w if x else h) / 2.0
        ends.append((c - half, c + half))
    ends.sort()
    gap = _GAP * renderer.points_to_pixels(1.0)
    return any(b[0] - a[1] < gap for a, b in itertools.pairwise(ends))


#: The most intervals of a linear axis: Matplotlib's automatic count gives a 5-inch axis
#: ten, each tick an object to build and a label to lay out, more than a reader reads;
#: eight keeps a step of 0.005 over a range of 0.031 (six gave 0.01: three labels).
_BINS = 8


def _at_most(bins: int) -> Any:
    """Ticks at most ``bins`` intervals apart, at Matplotlib's steps (1, 2, 2.5, 5, 10)."""
    from matplotlib.ticker import MaxNLocator

    return MaxNLocator(nbins=bins, steps=[1, 2, 2.5, 5, 10])


def _thin(fig: Any, renderer: Any) -> None:
    """Fewer ticks on each linear axis of ``fig`` whose tick labels touch, until none do."""
    from matplotlib.ticker import AutoLocator

    for ax in fig.axes:
        if ax.name != "rectilinear":
            continue
        ax.apply_aspect()  # an axes of equal aspect takes its drawn size
        for axis in (ax.xaxis, ax.yaxis):
            if axis.get_scale() != "linear":
                continue
            if type(axis.get_major_locator()) is AutoLocator:
                bins = min(_BINS, max(int(axis.get_tick_space()), 1))
                axis.set_major_locator(_at_most(bins))
            bins = len(axis.get_major_locator()())
            while bins > 2 and _ticks_touch(axis, renderer):
                bins -= 1
                axis.set_major_locator(_at_most(bins))


def _view_3d(ax: Any, labels: tuple[str, str, str], size: float) -> None:
    """Ticks and labels of a 3-D view that leave each other room at ``size`` points.

    The labels of a 3-D view move with its projection, where :func:`_fit` does not measure
    them: at most four intervals an axis, the tick labels a point smaller than the axis'
    labels, and those set off from them.
    """
    for axis, text in zip((ax.xaxis, ax.yaxis, ax.zaxis), labels, strict=True):
        axis.set_major_locator(_at_most(4))
        axis.set_label_text(text, fontsize=size)
        axis.labelpad = size
    ax.tick_params(labelsize=size - 1.0, pad=0.0)


def _fit(fig: Any) -> None:
    """Make every text of ``fig`` legible and keep it inside the figure, at its size.

    Measured on the figure (Agg's metrics of DejaVu Sans, the font the SVG names): a
    linear axis takes at most ``_BINS`` intervals, and fewer where its tick labels touch
    (``-0.0075`` beside ``-0.0050``) until they do not; the margins grow by what sticks
    out of the figure (an axis label, the ``1e8`` of an offset), after which the ticks
    are looked at again. A browser test holds every report of the demo to it.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.transforms import Bbox

    canvas: Any = FigureCanvasAgg(fig)
    renderer = canvas.get_renderer()
    _thin(fig, renderer)
    # what can stick out: the axes' ticks, labels and offsets, a 3-D view, a colour bar
    # (a legend stays inside its axes)
    parts = [
        part.get_tightbbox(renderer)
        for ax in fig.axes
        for part in ((ax.xaxis, ax.yaxis, ax.title) if ax.name == "rectilinear" else (ax,))
    ]
    box = Bbox.union([b for b in parts if b is not None and b.width > 0])
    w, h = fig.get_size_inches() * fig.dpi  # pixels, as the boxes
    pad = _GAP * renderer.points_to_pixels(1.0)
    out = (pad - box.x0, box.x1 - w + pad, pad - box.y0, box.y1 - h + pad)
    if max(out) > 0.0:
        sp = fig.subplotpars
        fig.subplots_adjust(
            left=sp.left + max(out[0], 0.0) / w,
            right=sp.right - max(out[1], 0.0) / w,
            bottom=sp.bottom + max(out[2], 0.0) / h,
            top=sp.top - max(out[3], 0.0) / h,
        )
        _thin(fig, renderer)


def _svg(fig: Any, salt: str) -> str:
    import matplotlib

    _fit(fig)
    buf = io.StringIO()
    # a salt per plot of a page keeps the ids of its clip paths apart from the other
    # SVGs of the page, and the same from one rendering to the next
    with matplotlib.rc_context({"svg.fonttype": "none", "svg.hashsalt": salt}):
        fig.savefig(buf, format="svg", metadata={"Date": None})
    text = buf.getvalue()
    start = text.find("<svg")
    return re.sub(r"<!--.*?-->", "", text[start:], flags=re.S).strip()


def _figure(w: float, h: float, **margins: float) -> Any:
    """A figure with fixed margins (fractions of its size).

    A layout engine or a tight bounding box would draw each figure twice more.
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(w, h))
    fig.subplots_adjust(**margins)
    return fig


def histogram_svg(q: dict[str, Any]) -> str:
    """Histogram of the Monte Carlo values, their coverage intervals and the GUM's PDF.

    The GUM's PDF is the normal one of y and u, or with a finite ν_eff the t distribution
    with ν_eff degrees of freedom scaled by u (the one its interval y ± t_p(ν_eff) u is of).

    Parameters
    ----------
    q : dict
        A quantity of ``result.json``.

    Returns
    -------
    str
        One ``<svg>`` element.
    """
    scale, label = display_unit(q["unit"])
    mc = q["monte_carlo"]
    ref = mc["estimate"]
    edges = (np.asarray(q["histogram"]["edges"]) - ref) * scale
    density = np.asarray(q["histogram"]["density"]) / scale
    fig = _figure(5.2, 3.1, left=0.13, right=0.98, bottom=0.15, top=0.97)
    ax = fig.add_subplot(1, 1, 1)
    ax.stairs(density, edges, fill=True, alpha=0.45, color="C0", label="Monte Carlo")
    kind = mc["interval"]
    other = "symmetric" if kind == "shortest" else "shortest"
    lo, hi = ((np.asarray(mc[kind]) - ref) * scale).tolist()
    ax.axvspan(lo, hi, color="C2", alpha=0.12, label=f"{kind} {100 * mc['p']:g} % interval")
    for v in ((np.asarray(mc[other]) - ref) * scale).tolist():
        ax.axvline(v, color="C3", ls="--", lw=1.0)
    ax.plot([], [], color="C3", ls="--", label=f"{other} interval")
    g = q.get("gum")
    if g and g["u"] > 0:
        from mtmc.uncertainty.propagation import output_pdf

        x = np.linspace(edges[0], edges[-1], 400)
        dof = g.get("dof")
        pdf = output_pdf(x, (g["estimate"] - ref) * scale, g["u"] * scale, dof)
        name = "normal PDF" if dof is None else f"t PDF, ν_eff = {dof:.3g}"
        ax.plot(x, pdf, "k-", lw=1.1, label=f"GUM: {name}")
    ax.set_xlabel(f"{q['name']} − estimate{per_unit(label)}")
    ax.set_ylabel(f"density{per_unit(label, '⁻¹')}")
    ax.legend(fontsize=7, loc="upper right")
    return _svg(fig, f"histogram:{q['name']}")


_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def _decades(ax: Any) -> None:
    """A log-scale x axis labelled ``10³`` at its decades, without minor ticks.

    Matplotlib's default labels each decade in mathtext and draws eight minor ticks a
    decade: three quarters of the time of a plot, for marks a reader of a convergence
    plot does not read.
    """
    from matplotlib.ticker import FuncFormatter, LogLocator, NullLocator

    ax.xaxis.set_major_locator(LogLocator(base=10.0))
    ax.xaxis.set_minor_locator(NullLocator())
    ax.xaxis.set_major_formatter(
        FuncFormatter(lambda v, _pos: f"10{str(round(np.log10(v))).translate(_SUPERSCRIPT)}")
    )


def convergence_svg(q: dict[str, Any]) -> str:
    """The estimate and ``u`` from the first ``m`` trials, against ``m`` (log scale)."""
    scale, label = display_unit(q["unit"])
    c = q["convergence"]
    m = np.asarray(c["m"])
    est = (np.asarray(c["estimate"]) - q["monte_carlo"]["estimate"]) * scale
    u = np.asarray(c["u"]) * scale
    unit = per_unit(label)
    fig = _figure(5.2, 2.6, left=0.14, right=0.98, bottom=0.18, top=0.96, wspace=0.5)
    a1, a2 = fig.subplots(1, 2)
    a1.semilogx(m, est, "C0.-", ms=3, lw=0.8)
    a1.axhline(0.0, color="k", lw=0.6)
    a1.set_xlabel("trials m")
    a1.set_ylabel(f"estimate − final{unit}")
    a2.semilogx(m, u, "C1.-", ms=3, lw=0.8)
    g = q.get("gum")
    if g:
        a2.axhline(g["u"] * scale, color="k", ls="--", lw=0.8, label="GUM u")
        a2.legend(fontsize=7)
    a2.set_xlabel("trials m")
    a2.set_ylabel(f"u{unit}")
    for ax in (a1, a2):
        _decades(ax)
    return _svg(fig, f"convergence:{q['name']}")


def region_svg(r: dict[str, Any]) -> str:
    """A coverage ellipse (Monte Carlo and Gaussian) over the first trials as dots."""
    from matplotlib.patches import Ellipse

    scale, label = display_unit(r["unit"])
    centre = np.asarray(r["centre"])
    pts = (np.asarray(r["scatter"]) - centre) * scale
    axes = np.asarray(r["axes"])
    semi = np.asarray(r["semi_axes"]) * scale
    angle = float(np.degrees(np.arctan2(axes[1, 1], axes[0, 1])))
    fig = _figure(3.6, 3.4, left=0.2, right=0.97, bottom=0.14, top=0.97)
    ax = fig.add_subplot(1, 1, 1)
    ax.plot(pts[:, 0], pts[:, 1], ".", ms=2, color="C0", alpha=0.5)
    ax.add_patch(
        Ellipse((0, 0), 2 * semi[1], 2 * semi[0], angle=angle, fill=False, color="C3", lw=1.4)
    )
    gs = semi * r["k_chi2"] / r["k"]
    ax.add_patch(
        Ellipse((0, 0), 2 * gs[1], 2 * gs[0], angle=angle, fill=False, color="k", ls="--", lw=0.9)
    )
    ax.plot([], [], color="C3", label=f"Monte Carlo, k = {r['k']:.3f}")
    ax.plot([], [], color="k", ls="--", label=f"Gaussian, k = {r['k_chi2']:.3f}")
    ext = 1.15 * max(float(semi.max()), float(np.abs(pts).max()) if pts.size else 0.0, 1e-300)
    ax.set_xlim(-ext, ext)
    ax.set_ylim(-ext, ext)
    ax.set_aspect("equal")
    unit = per_unit(label)
    ax.set_xlabel(f"{r['labels'][0]}{unit}")
    ax.set_ylabel(f"{r['labels'][1]}{unit}")
    ax.legend(fontsize=6, loc="upper right")
    return _svg(fig, f"region:{r['name']}")


def graph_svg(toml_text: str, name: str | None = None) -> str:
    """The drawing of a measurement graph (:func:`mtmc.graph.draw_graph`) from its TOML text."""
    import tempfile
    from pathlib import Path

    import matplotlib

    from mtmc.graph.draw import draw_graph
    from mtmc.graph.toml_format import loads_graph

    graph = loads_graph(toml_text, file=name)
    with tempfile.TemporaryDirectory() as d, matplotlib.rc_context({"svg.hashsalt": "graph"}):
        path = Path(d) / "graph.svg"
        draw_graph(graph, path)
        text = path.read_text(encoding="utf-8")
    start = text.find("<svg")
    return re.sub(r"<!--.*?-->", "", text[start:], flags=re.S).strip()


def vector_magnification(f: dict[str, Any]) -> float:
    """The factor the error vectors of a field are drawn magnified by, so that they fit.

    The field's own ``magnification`` when its longest vector then spans between 2 % and
    30 % of the largest extent of the points; otherwise the 1-2-5 number that makes it
    about 8 % of that extent (a vector as long as the workspace hides every other, one of
    a thousandth of it is a dot). Vectors all zero, or points all at one place, keep it.

    Examples
    --------
    >>> f = {"points": [[0, 0, 0], [400, 400, 0]], "values": [[0.004, 0, 0], [0, 0, 0.001]],
    ...      "magnification": 1000.0}
    >>> vector_magnification(f)
    5000.0
    >>> vector_magnification({**f, "magnification": 10000.0})
    10000.0
    """
    pts = np.asarray(f["points"], dtype=np.float64).reshape(-1, 3)
    vec = _vectors_mm(f)
    longest = float(np.linalg.norm(vec, axis=1).max(initial=0.0))
    span = float(np.ptp(pts, axis=0).max()) if pts.size else 0.0
    given = float(f.get("magnification") or 1.0)
    if not (longest > 0 and span > 0 and np.isfinite(longest) and np.isfinite(span)):
        return given
    if 0.02 <= given * longest / span <= 0.3:
        return given
    target = 0.08 * span / longest
    decade = 10.0 ** np.floor(np.log10(target))
    step = max(m for m in (1.0, 2.0, 5.0) if m * decade <= target)
    return float(step * decade)


def _limits(a: Any, b: Any, floor: float) -> tuple[float, float]:
    """Limits holding every value of ``a`` and ``b``, widened by 6 %, at least ``floor`` wide."""
    lo = float(min(np.min(a), np.min(b)))
    hi = float(max(np.max(a), np.max(b)))
    pad = max(0.06 * (hi - lo), 0.5 * max(floor - (hi - lo), 0.0))
    return lo - pad, hi + pad


def field_figure(f: dict[str, Any]) -> Any:
    """The Matplotlib figure of :func:`field_svg`: views xy and xz, and 3D.

    Vectors are drawn magnified by :func:`vector_magnification`, stated over each view,
    and the limits of every view hold the points and the tips of their vectors.
    """
    pts = np.asarray(f["points"], dtype=np.float64).reshape(-1, 3)
    vals = np.asarray(f["values"], dtype=np.float64)
    scale, label = display_unit(f["unit"])
    names = f["axes"]
    fig = _figure(10.5, 3.6, left=0.07, right=0.95, bottom=0.15, top=0.88, wspace=0.4)
    a1 = fig.add_subplot(1, 3, 1)
    a2 = fig.add_subplot(1, 3, 2)
    a3: Any = fig.add_subplot(1, 3, 3, projection="3d")
    span = float(np.ptp(pts, axis=0).max()) if pts.size else 0.0
    floor = 0.1 * span if span > 0 else 1.0  # a flat axis (every z = 0) still gets a range
    if f["kind"] == "vectors":
        mag = vector_magnification(f)
        v = _vectors_mm(f) * mag
        tips = pts + v
        for ax, (i, j) in ((a1, (0, 1)), (a2, (0, 2))):
            ax.quiver(
                pts[:, i],
                pts[:, j],
                v[:, i],
                v[:, j],
                angles="xy",
                scale_units="xy",
                scale=1,
                color="C3",
                width=0.004,
            )
            ax.plot(pts[:, i], pts[:, j], "k.", ms=3)
            ax.set_xlim(*_limits(pts[:, i], tips[:, i], floor))
            ax.set_ylim(*_limits(pts[:, j], tips[:, j], floor))
        a3.quiver(pts[:, 0], pts[:, 1], pts[:, 2], v[:, 0], v[:, 1], v[:, 2], color="C3")
        a3.set_xlim(*_limits(pts[:, 0], tips[:, 0], floor))
        a3.set_ylim(*_limits(pts[:, 1], tips[:, 1], floor))
        a3.set_zlim(*_limits(pts[:, 2], tips[:, 2], floor))
        for ax in (a1, a2, a3):
            ax.set_title(f"vectors × {mag:g}", fontsize=8)
    else:
        c = vals.reshape(-1) * scale
        for ax, (i, j) in ((a1, (0, 1)), (a2, (0, 2))):
            sc = ax.scatter(
                pts[:, i], pts[:, j], c=c, cmap="viridis", s=28, edgecolors="k", linewidths=0.3
            )
        a3.scatter(pts[:, 0], pts[:, 1], pts[:, 2], c=c, cmap="viridis", s=20)
        fig.colorbar(sc, ax=a3, shrink=0.7, pad=0.3, label=f"{f['name']}{per_unit(label)}")
    for ax, (i, j) in ((a1, (0, 1)), (a2, (0, 2))):
        ax.set_xlabel(f"{names[i]} / mm")
        ax.set_ylabel(f"{names[j]} / mm")
        if f["kind"] != "vectors":
            ax.set_aspect("equal", adjustable="datalim")
    _view_3d(a3, (f"{names[0]} / mm", f"{names[1]} / mm", f"{names[2]} / mm"), 7.0)
    return fig


def field_svg(f: dict[str, Any]) -> str:
    """A map (a value per point, as colour) or error vectors (arrows), in xy, xz and 3D.

    Points in mm; values in their own unit, as the field's table gives them. Vectors are
    drawn in the points' mm, magnified by
    :func:`vector_magnification` (Wang, Cheung and Kong 2022, Fig. 7), the factor stated
    over each view, within the limits of every view.
    """
    return _svg(field_figure(f), f"field:{f['name']}")


def machine_svg(name: str) -> str:
    """The kinematic chain of a machine (:func:`mtmc.kinematics.draw_chain`).

    Parameters
    ----------
    name : str
        A configuration of the machine library or a topology string.
    """
    from mtmc.kinematics.draw import draw_chain
    from mtmc.kinematics.library import library_machine, library_names

    spec: Any = library_machine(name) if name.strip().lower() in library_names() else name
    text = draw_chain(spec)
    start = text.find("<svg")
    return re.sub(r"<!--.*?-->", "", text[start:], flags=re.S).strip()


def sweep_svg(sw: dict[str, Any]) -> str:
    """The swept standard uncertainty over a two-parameter grid with the surrogate surface.

    Monte Carlo values as dots, the fitted surrogate ``u = √(c0 + Σ cᵢσᵢ²)`` as a
    surface (Stryczek Fig. 14–15), in the sweep's ``unit`` over the varied parameters in
    its ``grid_unit``, as its table gives them; with one varied parameter, a curve.
    """
    grid = np.asarray(sw["grid"])
    g_unit = display_unit(str(sw.get("grid_unit", "mm")))[1]
    scale, label = display_unit(sw["unit"])
    u = np.asarray(sw["u"]) * scale
    names = sw["names"]
    surface = sw["surface"]  # the surrogate on a fine grid, as the study computed it
    axes = [np.asarray(a) for a in surface["axes"]]
    u_fit = np.asarray(surface["u"]) * scale

    if grid.shape[1] == 2:
        fig = _figure(6.4, 4.6, left=0.0, right=0.95, bottom=0.05, top=1.0)
        ax = fig.add_subplot(1, 1, 1, projection="3d")
        aa, bb = np.meshgrid(axes[0], axes[1], indexing="ij")
        ax.plot_surface(aa, bb, u_fit, cmap="viridis", alpha=0.55, linewidth=0)
        ax.scatter(grid[:, 0], grid[:, 1], u, color="C3", s=12, label="Monte Carlo")
        z = f"u({sw['output']}){per_unit(label)}"
        _view_3d(ax, (f"{names[0]} / {g_unit}", f"{names[1]} / {g_unit}", z), 8.0)
        ax.legend(fontsize=7, loc="upper left")
    else:
        fig = _figure(6.0, 3.4, left=0.12, right=0.98, bottom=0.15, top=0.97)
        ax = fig.add_subplot(1, 1, 1)
        x = grid[:, 0]
        ax.plot(axes[0], u_fit, "k-", lw=1.0, label="surrogate")
        ax.plot(x, u, "C3o", ms=4, label="Monte Carlo")
        ax.set_xlabel(f"{names[0]} / {g_unit}")
        ax.set_ylabel(f"u({sw['output']}){per_unit(label)}")
        ax.legend(fontsize=7)
    return _svg(fig, "sweep")
