"""The HTML report of a result folder, drawn from its files alone.

:func:`render` reads ``result.json`` and ``provenance.json`` of a result folder
(``docs/results-format.md``) and writes ``report.html`` beside them: one static,
self-contained page (the plots inline as SVG, no script or style from the network) from
the Jinja2 template ``templates/report.html.j2``, readable on screen and printed.
:func:`render_index` writes a page linking several reports (``mtmc demo``). The report
knows nothing of how a result was computed: it shows what the files hold.
"""

from __future__ import annotations

import functools
import json
import math
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from mtmc.errors import InputError, MtmcError
from mtmc.io import write_text_atomic

__all__ = ["as_given", "fmt", "html", "render", "render_index"]


def as_given(x: Any) -> str:
    """An input's value as the study wrote it: every digit of a short decimal.

    A float whose shortest round-trip text has at most 12 significant digits (what a
    person types: ``50.000623``) is shown whole; a longer one (a value derived from the
    file, ``0.05773502691896257`` = 0.1/√3) as :func:`fmt` shows it.

    Examples
    --------
    >>> as_given(50.000623), as_given(0.1 / 3**0.5), as_given(2.0), as_given(1e-7)
    ('50.000623', '0.057735', '2', '1e-07')
    """
    if not isinstance(x, float) or isinstance(x, bool) or not math.isfinite(x):
        return fmt(x)
    text = repr(x)
    mantissa = text.split("e")[0].replace("-", "").replace(".", "").strip("0")
    if len(mantissa) > 12:
        return fmt(x)
    return f"{x:.12g}"


def fmt(x: Any, digits: int = 6) -> str:
    """A number as the report prints it: ``digits`` significant digits; None as a dash.

    Examples
    --------
    >>> fmt(0.07541234), fmt(None), fmt(True), fmt(3)
    ('0.0754123', '—', 'yes', '3')
    """
    if x is None:
        return "—"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, int):
        return str(x)
    if isinstance(x, float):
        if not math.isfinite(x):
            return "∞" if x > 0 else ("−∞" if x < 0 else "NaN")
        return f"{x:.{digits}g}"
    return str(x)


def at_place(x: Any, u: Any, ndig: int = 2, *, the_u: bool = False) -> str:
    """A value in the unit of ``u``, to the decimal place of ``u`` at ``ndig`` significant digits.

    JCGM 101 §5.5: ``u(y)`` to one or two significant digits, and the estimate and the
    ends of the coverage interval to the same decimal place. With ``the_u`` the text is
    ``u`` itself so rounded. Where ``u`` is not a positive finite number (a constant
    output) the value is shown as :func:`fmt` shows it.

    Examples
    --------
    >>> at_place(1.0854629, 0.0754861), at_place(0.0754861, 0.0754861, the_u=True)
    ('1.085', '0.075')
    >>> at_place(50.0000012, 0.00522598, 4), at_place(3.2e-06, 0.00668892, 4)
    ('50.000001', '0.000003')
    >>> at_place(2.5, 0.0), at_place(None, 0.1)
    ('2.5', '—')
    """
    from mtmc.uncertainty.tolerance import round_to_uncertainty

    if x is None or isinstance(x, bool):
        return fmt(x)
    try:
        y_text, u_text = round_to_uncertainty(float(x), float(u), ndig)
    except (MtmcError, TypeError, ValueError, OverflowError):
        return fmt(x)
    return u_text if the_u else y_text


#: The quantities of a study whose histogram and convergence its report draws: the first
#: 12, whatever the kind. A reader looks at a few; a kinematics study of 100 poses took 45 s
#: to draw 600 figures, and the artefact study of Wang et al. (36 quantities, 10⁴ trials)
#: took 20.7 s to run and report with 73 figures, 11.8 s with 25. The tables, and the
#: figures over all quantities (the u at each pose, the volumetric errors of Fig. 7), give
#: every one; the report says which are not drawn (``mtmc report FOLDER --plots all``
#: draws them).
MAX_PLOTTED = 12


def plotted_from_text(text: str | None) -> int | str | None:
    """The ``--plots`` of a command as :func:`render` takes it: a whole number, or ``"all"``.

    Examples
    --------
    >>> plotted_from_text("3"), plotted_from_text("all"), plotted_from_text(None)
    (3, 'all', None)

    Raises
    ------
    InputError
        On any other text (``"-1"``, ``"1.5"``, a digit of another script).
    """
    value = int(text) if text is not None and text.isascii() and text.isdigit() else text
    plotted_count({}, value)  # the one check of the value, and its message
    return value


def plotted_count(result: Mapping[str, Any], plotted: int | str | None = None) -> int:
    """How many quantities of ``result`` get a histogram and a convergence plot.

    ``plotted``: the first so many (``None``: :data:`MAX_PLOTTED`), or ``"all"``.

    Examples
    --------
    >>> doc = {"quantities": [{}] * 36}
    >>> plotted_count(doc), plotted_count(doc, 3), plotted_count(doc, "all")
    (12, 3, 36)
    """
    n = len(result.get("quantities", []))
    if plotted is None:
        return min(n, MAX_PLOTTED)
    if plotted == "all":
        return n
    if isinstance(plotted, bool) or not isinstance(plotted, int) or plotted < 0:
        raise InputError(f"expected a whole number >= 0 or 'all', got {plotted!r}", field="plotted")
    return min(n, plotted)


@functools.cache
def _env() -> Any:
    """The Jinja environment of the report's templates, made once a process.

    The environment keeps its compiled templates: compiling ``report.html.j2`` and the
    parts it includes took 0.27-0.36 s a report (a tenth of the time of a report of
    15 figures) when each report made an environment of its own; the page, figures
    aside, now takes 0.02-0.03 s.
    """
    import jinja2

    env = jinja2.Environment(
        loader=jinja2.PackageLoader("mtmc.report", "templates"),
        autoescape=jinja2.select_autoescape(["html", "j2"]),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    env.filters["fmt"] = fmt
    env.filters["as_given"] = as_given
    env.filters["at_place"] = at_place
    env.filters["pct"] = lambda x: "—" if x is None else f"{100 * x:.1f} %"
    from mtmc.report import plots  # NumPy, SciPy, Matplotlib: imported when a report is made

    env.globals["display_unit"] = plots.display_unit
    env.globals["vector_magnification"] = plots.vector_magnification
    env.globals["repr"] = repr
    return env


def _read_json(path: Path) -> dict[str, Any]:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError(
            f"cannot read {path.name}: {exc.strerror or exc}", file=str(path)
        ) from None
    except json.JSONDecodeError as exc:
        raise InputError(f"not valid JSON: {exc.msg}", file=str(path), line=exc.lineno) from None
    if not isinstance(data, dict):
        raise InputError("expected a JSON object", file=str(path))
    return data


def _figures(result: Mapping[str, Any], drawn: int) -> dict[str, str]:
    """The SVG figures of a report page, by their key in the template."""
    from mtmc.report import plots

    figs: dict[str, str] = {}
    for q in result.get("quantities", [])[:drawn]:
        if not q["monte_carlo"]["u"]:  # u = 0 (or not finite): one value, nothing to draw
            continue
        figs[f"histogram:{q['name']}"] = plots.histogram_svg(q)
        figs[f"convergence:{q['name']}"] = plots.convergence_svg(q)
    for r in result.get("regions", []):
        figs[f"region:{r['name']}"] = plots.region_svg(r)
    joint = result.get("joint")
    if joint and joint.get("region") and len(joint["outputs"]) == 2:
        from mtmc.report.joint import joint_svg

        figs["joint"] = joint_svg(joint)
    graph = result.get("graph")
    if graph:
        figs["graph"] = plots.graph_svg(graph["toml"], graph.get("file"))
    for f in result.get("fields", []):
        figs[f"field:{f['name']}"] = plots.field_svg(f)
    machine = result.get("machine")
    if machine:
        figs["machine"] = plots.machine_svg(machine["name"])
    if result.get("sweep"):
        figs["sweep"] = plots.sweep_svg(result["sweep"])
    if result.get("positioning"):
        from mtmc.report.positioning import positioning_svg

        figs["positioning"] = positioning_svg(result["positioning"])
    if result.get("circular"):
        from mtmc.report.circular import circular_svg, rotary_svg

        circ = result["circular"]
        figs["circular"] = rotary_svg(circ) if circ.get("rotary") else circular_svg(circ)
    return figs


def html(
    result: Mapping[str, Any],
    provenance: Mapping[str, Any] | None = None,
    *,
    plotted: int | str | None = None,
) -> str:
    """The report page of a result, as HTML text.

    Parameters
    ----------
    result : mapping
        The content of ``result.json``.
    provenance : mapping, optional
        The content of ``provenance.json``.
    plotted : int or "all", optional
        How many quantities, from the first, get a histogram and a convergence plot
        (:func:`plotted_count`; default :data:`MAX_PLOTTED`).

    Returns
    -------
    str
        A self-contained HTML document.

    Raises
    ------
    InputError
        If ``result`` is not an mtmc result (no ``format`` ``mtmc-result/...``).
    """
    if not str(result.get("format", "")).startswith("mtmc-result/"):
        raise InputError(
            f"expected an mtmc result (format mtmc-result/1), got format {result.get('format')!r}",
            field="format",
        )
    drawn = plotted_count(result, plotted)
    with warnings.catch_warnings():
        # a text with a character DejaVu Sans lacks (a name edited into result.json, a
        # unit in another script): Matplotlib measures it without the glyph and says so;
        # the SVG keeps the text as text (svg.fonttype "none"), which the browser draws
        # in a font that has it
        warnings.filterwarnings(
            "ignore", message="Glyph .* missing from font", category=UserWarning
        )
        figs = _figures(result, drawn)
    template = _env().get_template("report.html.j2")
    # the units of the inputs, where the result gives them (a kinematics study: mm, rad)
    units = {x["name"]: x["unit"] for x in result.get("inputs", []) if x.get("unit")}
    return str(
        template.render(
            r=result,
            prov=provenance or {},
            figs=figs,
            input_units=units,
            max_plotted=drawn,
        )
    )


def render(folder: str | Path, *, plotted: int | str | None = None) -> Path:
    """Write ``report.html`` of a result folder from its ``result.json`` and ``provenance.json``.

    Parameters
    ----------
    folder : str or Path
        The result folder.
    plotted : int or "all", optional
        How many quantities, from the first, get a histogram and a convergence plot
        (default :data:`MAX_PLOTTED`; ``mtmc report FOLDER --plots all``).

    Returns
    -------
    pathlib.Path
        The report file.

    Raises
    ------
    InputError
        If the folder holds no readable ``result.json``, or ``plotted`` is neither a whole
        number >= 0 nor ``"all"``.
    """
    import jinja2
    import numpy as np

    from mtmc.report.folder import read_folder

    plotted_count({}, plotted)  # the option checked before the folder is read
    d = Path(folder)
    read = read_folder(d, samples=False)  # every file checked before the report reads it
    try:
        # values at the ends of the float range (1e308, within the format) overflow in
        # Matplotlib's tick arithmetic, which handles them: no warning for the reader
        with np.errstate(over="ignore", invalid="ignore"):
            page = html(read.result, read.provenance, plotted=plotted)
    except KeyError as exc:  # a result.json edited, or of another version
        raise InputError(
            f"not an mtmc result: no {exc.args[0]!r} where the report needs one "
            f"(docs/results-format.md)",
            file=str(d / "result.json"),
        ) from None
    except jinja2.UndefinedError as exc:
        raise InputError(
            f"not an mtmc result: {exc.message} where the report needs it (docs/results-format.md)",
            file=str(d / "result.json"),
        ) from None
    except (TypeError, IndexError, AttributeError, ValueError) as exc:
        raise InputError(
            f"not an mtmc result: a value the report cannot show ({exc}) (docs/results-format.md)",
            file=str(d / "result.json"),
        ) from None
    # a report.html that is a link (a result folder unpacked from an archive may carry one
    # to anywhere) is replaced, never written through: the report stays in its folder
    return write_text_atomic(d / "report.html", page, follow=False)


def render_index(
    entries: Sequence[tuple[str, str | Path]], path: str | Path, title: str = "mtmc demo"
) -> Path:
    """Write a page linking reports: one row per result folder, with its headline numbers.

    Parameters
    ----------
    entries : sequence of (label, folder)
        The result folders, relative to the page's folder or absolute.
    path : str or Path
        The page (``index.html``).
    title : str
        Its title.

    Returns
    -------
    pathlib.Path
    """
    base = Path(path).parent
    rows = []
    for label, folder in entries:
        f = Path(folder)
        full = f if f.is_absolute() else base / f
        result = _read_json(full / "result.json")
        prov = _read_json(full / "provenance.json") if (full / "provenance.json").is_file() else {}
        rows.append(
            {"label": label, "href": f"{f.as_posix()}/report.html", "r": result, "prov": prov}
        )
    template = _env().get_template("index.html.j2")
    return write_text_atomic(path, str(template.render(title=title, rows=rows)))
