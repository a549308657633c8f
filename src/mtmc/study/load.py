"""Results read back from their folders, and plain Monte Carlo results made study results.

:func:`load_result` reads the ``result.json`` (and ``samples/*.npy``) of a result folder
that :func:`mtmc.write_result` or ``mtmc run`` wrote and returns the frozen
:class:`~mtmc.study.result.StudyResult` that was written: the same summaries, bit for bit
(JSON floats are written with ``repr`` and read back exactly), with the arrays of the
histograms, convergence curves, regions and fields as arrays again.

:func:`study_result` turns the result of :func:`mtmc.monte_carlo` (one output, or
named outputs), with the :func:`mtmc.gum` result of the same model where there is one,
into a :class:`~mtmc.study.result.StudyResult` of kind ``monte_carlo``, so that
:func:`mtmc.write_result` and :func:`mtmc.render_report` take it as they take a study's.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from mtmc.document import InputFile
from mtmc.errors import InputError
from mtmc.frozen import frozen_floats
from mtmc.report.folder import read_folder
from mtmc.study.result import (
    BudgetLine,
    Convergence,
    GumSummary,
    Histogram,
    MonteCarloSummary,
    PointField,
    Quantity,
    Region,
    Reported,
    StudyResult,
    Table,
    ValidationSummary,
    quantity,
    region,
)
from mtmc.study.settings import RunSettings
from mtmc.uncertainty.propagation import GumResult
from mtmc.uncertainty.results import MonteCarloResult, MonteCarloResults

__all__ = ["load_result", "study_result"]

#: The keys of ``result.json`` that are :class:`StudyResult` fields of their own; every
#: other key (but ``format``) is the kind's ``extra``.
_TOP = ("quantities", "regions", "tables", "fields", "inputs")


def _dof(obj: Any) -> Any:
    """``obj`` with every ``dof`` that JSON holds as ``null`` made ``∞`` again.

    Degrees of freedom are infinite where a standard uncertainty is exactly known; JSON
    has no infinity and ``result.json`` writes them as ``null`` (docs/results-format.md).
    """
    if isinstance(obj, dict):
        return {k: math.inf if k == "dof" and v is None else _dof(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_dof(v) for v in obj]
    return obj


def _input_files(provenance: Mapping[str, Any] | None, path: Path) -> tuple[InputFile, ...]:
    """The files the study named, as ``provenance.json`` lists them (none without one)."""
    listed = (provenance or {}).get("input_files", [])
    try:
        return tuple(
            InputFile(
                key=tuple(k if isinstance(k, int) else str(k) for k in f["key"]),
                given=str(f["given"]),
                source=str(f["source"]),
                sha256=str(f["sha256"]),
                copy=None if f["copy"] is None else str(f["copy"]),
            )
            for f in listed
        )
    except (KeyError, TypeError) as exc:
        raise InputError(
            f"expected input_files entries with key, given, source, copy and sha256 ({exc})",
            file=str(path),
            field="input_files",
        ) from None


def _quantity(d: Mapping[str, Any]) -> Quantity:
    gum, validation, conformity = d["gum"], d["validation"], d.get("conformity")
    return Quantity(
        name=d["name"],
        unit=d["unit"],
        mc=MonteCarloSummary.from_dict(d["monte_carlo"]),
        gum=None if gum is None else GumSummary.from_dict(gum),
        validation=None if validation is None else ValidationSummary.from_dict(validation),
        budget=tuple(BudgetLine.from_dict(b) for b in d["budget"]),
        histogram=Histogram.from_dict(d["histogram"]),
        convergence=Convergence.from_dict(d["convergence"]),
        reported=Reported.from_dict(d["reported"]),
        conformity=None if conformity is None else _dof(conformity),
    )


def _region(d: Mapping[str, Any]) -> Region:
    arrays = ("centre", "cov", "semi_axes", "axes", "scatter")
    return Region(
        name=d["name"],
        labels=(d["labels"][0], d["labels"][1]),
        unit=d["unit"],
        k=d["k"],
        k_chi2=d["k_chi2"],
        p=d["p"],
        **{key: frozen_floats(d[key]) for key in arrays},
    )


def _table(d: Mapping[str, Any]) -> Table:
    return Table(
        name=d["name"],
        title=d["title"],
        columns=tuple(d["columns"]),
        rows=tuple(tuple(r) for r in d["rows"]),
    )


def _field(d: Mapping[str, Any]) -> PointField:
    axes = tuple(d["axes"])
    return PointField(
        name=d["name"],
        title=d["title"],
        points=frozen_floats(d["points"]),
        values=frozen_floats(d["values"]),
        unit=d["unit"],
        labels=tuple(d["labels"]),
        axes=(axes[0], axes[1], axes[2]),
        magnification=d["magnification"],
    )


def load_result(folder: str | os.PathLike[str]) -> StudyResult:
    """The :class:`StudyResult` written into a result folder.

    Parameters
    ----------
    folder : path-like
        A folder written by :func:`mtmc.write_result` or ``mtmc run``
        (``docs/results-format.md``).

    Returns
    -------
    StudyResult
        Equal to the one written: ``load_result(write_result(r, d)).to_dict() ==
        r.to_dict()``, and the same numbers, bit for bit, in every field; the samples
        from ``samples/NAME.npy`` where the run kept them; ``input_files`` from
        ``provenance.json`` (each with the ``copy`` in the folder). Infinite degrees of freedom
        (a ``dof`` of a quantity or an input), written as ``null``, are ``inf`` again;
        other non-finite numbers (written as ``null``) stay None.

    Raises
    ------
    InputError
        Naming the file (and field): no ``result.json``, not JSON, not an mtmc result, a
        value not of ``docs/results-format.md``, a link to outside the folder, a FIFO, or
        samples whose ``.npy`` header does not match the file or the trials
        (:func:`mtmc.report.folder.read_folder`).
    """
    d = Path(folder)
    path = d / "result.json"
    read = read_folder(d)  # every file checked (mtmc.report.folder), the samples read
    doc = read.result
    try:
        kw: dict[str, Any] = {
            "quantities": tuple(_quantity(q) for q in doc.get("quantities", [])),
            "regions": tuple(_region(r) for r in doc.get("regions", [])),
            "tables": tuple(_table(t) for t in doc.get("tables", [])),
            "fields": tuple(_field(f) for f in doc.get("fields", [])),
            "inputs": tuple(_dof(x) for x in doc.get("inputs", [])),
        }
        skip = {"extra", "samples", "input_files", *_TOP}
        named = [f.name for f in dataclasses.fields(StudyResult) if f.name not in skip]
        for name in named:
            kw[name] = doc[name]
    except KeyError as exc:
        raise InputError(
            f"not an mtmc result: no {exc.args[0]!r} where a result needs one "
            "(docs/results-format.md)",
            file=str(path),
        ) from None
    except (TypeError, IndexError, AttributeError, ValueError) as exc:
        raise InputError(
            f"not an mtmc result: a value of the wrong type ({exc}) (docs/results-format.md)",
            file=str(path),
        ) from None
    known = {"format", *_TOP, *named}
    kw["extra"] = {k: v for k, v in doc.items() if k not in known}
    kw["samples"] = read.samples
    kw["input_files"] = _input_files(read.provenance, d / "provenance.json")
    return StudyResult(**kw)


def study_result(
    result: MonteCarloResult | MonteCarloResults,
    gum: GumResult | Mapping[str, GumResult] | None = None,
    *,
    name: str = "y",
    unit: str = "1",
    title: str = "Monte Carlo result",
    p: float = 0.95,
    interval: str = "symmetric",
    ndig: int = 2,
    samples: bool = False,
) -> StudyResult:
    """A :class:`StudyResult` of kind ``monte_carlo`` from the result of :func:`mtmc.monte_carlo`.

    Parameters
    ----------
    result : MonteCarloResult or MonteCarloResults
        One output (called ``name``) or named outputs; their samples must have been
        kept (the histogram and convergence of a quantity are drawn from them). A vector
        output gives one quantity per component (``NAME[i]``) and, for two components,
        the JCGM 102 §7.7 coverage ellipse.
    gum : GumResult or mapping of str to GumResult, optional
        The GUM result of the same model (by output name for named outputs), shown
        beside the Monte Carlo with the JCGM 101 §8 verdict.
    name, unit : str
        The output's name and unit (for a single output; named outputs keep their
        names and take ``unit``).
    title : str
        The result's title.
    p : float
        Coverage probability of the intervals.
    interval : {"symmetric", "shortest"}
        The Monte Carlo interval that gives ``U`` (JCGM 101 §7.7).
    ndig : int
        Significant digits of ``u`` (JCGM 101 §7.9.2).
    samples : bool
        Keep the values in the result (written as ``samples/NAME.npy``).

    Returns
    -------
    StudyResult
        With ``study_file`` and ``study_sha256`` empty (no study file), the run's seed
        (None where the values came from elsewhere) and number of trials.

    Raises
    ------
    InputError
        If the samples of an output were not kept, or ``gum`` names an output the
        result does not have.
    """
    outputs: dict[str, MonteCarloResult] = (
        dict(result.outputs) if isinstance(result, MonteCarloResults) else {name: result}
    )
    if isinstance(gum, GumResult):
        gums: dict[str, GumResult] = {next(iter(outputs)): gum}
    else:
        gums = dict(gum or {})
    for key in gums:
        if key not in outputs:
            raise InputError(
                f"the GUM result names output {key!r}; the Monte Carlo result has "
                f"{', '.join(outputs)}",
                field="gum",
            )
    first = next(iter(outputs.values()))
    settings = RunSettings(trials=first.trials, seed=first.seed, p=p, interval=interval, ndig=ndig)
    quantities: list[Quantity] = []
    regions: list[Region] = []
    kept: dict[str, Any] = {}
    for out_name, mc in outputs.items():
        if mc.samples is None:
            raise InputError(
                f"the samples of output {out_name!r} were not kept; a study result needs "
                "them (run with keep=[...] or the default keep='auto')",
                field=out_name,
            )
        g = gums.get(out_name)
        if mc.dim == 0:
            quantities.append(quantity(out_name, unit, mc, g, settings))
        else:
            for i in range(mc.dim):
                gi = None if g is None else g.component(i)
                quantities.append(quantity(f"{out_name}[{i}]", unit, mc.component(i), gi, settings))
            if mc.dim == 2:
                reg = region(out_name, (f"{out_name}[0]", f"{out_name}[1]"), unit, mc.samples, p)
                if reg is not None:
                    regions.append(reg)
        if samples:
            kept[out_name] = mc.samples
    return StudyResult(
        kind="monte_carlo",
        title=title,
        study_file="",
        study_sha256="",
        seed=first.seed,  # type: ignore[arg-type]  # None: the values came from elsewhere
        trials=first.trials,
        p=p,
        quantities=tuple(quantities),
        regions=tuple(regions),
        samples=kept,
    )
