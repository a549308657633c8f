"""Study kind ``positioning``: an ISO 230-2 positioning test with its uncertainty.

The study names the CSV file of the readings (:func:`mtmc.positioning.load_positioning_csv`)
and the influences on the test (:class:`mtmc.positioning.UncertaintyModel`): the air and
material in ``[environment]``, the laser in ``[instrument]``, the Type A evaluation in
``[uncertainty]``, tolerances in ``[tolerances]`` (``docs/positioning.md``). The run is
:func:`mtmc.positioning.evaluate_uncertainty`: each of the twelve parameters of the axis
(``A`` … ``B_mean``) becomes a quantity with its Monte Carlo values, the GUM beside them
and its budget, headed by its estimate from the readings (ISO 230-2's definition) and, where
``[tolerances]`` gives a limit, the decision by the engine's JCGM 106 rule
(:mod:`mtmc.uncertainty.decision`); the tables give the parameters (the estimate, the Monte
Carlo's U, interval and mean, the GUM's U, what U covers), the statistics at each target, and
the pitch-error compensation table with the residual it leaves; ``positioning`` in
``result.json`` holds the readings for the report's plot, what U covers, the runs Grubbs'
test flags (kept), and the notes on where the GUM and the Monte Carlo disagree and why.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from mtmc.document import Fields, Source
from mtmc.errors import InputError
from mtmc.study.base import ProgressFn, Study
from mtmc.study.observations import input_record, read_distribution
from mtmc.study.options import ADAPTIVE, NAN_POLICY, mc_run_record
from mtmc.study.result import Quantity, Reported, StudyResult, Table, quantity
from mtmc.study.settings import RunSettings
from mtmc.study.spec import register_kind
from mtmc.uncertainty.tolerance import round_to_uncertainty

__all__ = ["PositioningStudy", "positioning_study", "summary", "unit_label"]

#: How the units of the deviations are printed.
_LABELS = {"um": "µm", "mm": "mm", "arcsec": "arcsec", "urad": "µrad", "deg": "deg"}

_ENV_KEYS = {
    "air_temperature_C": "air_temperature",
    "air_pressure_hPa": "air_pressure",
    "humidity_pct": "humidity",
    "co2_ppm": "co2",
    "material_temperature_C": "material_temperature",
    "expansion_ppm_per_K": "expansion",
    "air_temperature_change_C": "air_temperature_change",
    "air_pressure_change_hPa": "air_pressure_change",
    "drift": "drift",
}
_INSTRUMENT_KEYS = {
    "equation_error_ppm": "equation_error",
    "wavelength_error_ppm": "wavelength_error",
    "misalignment_urad": "misalignment",
}


def unit_label(unit: str) -> str:
    """The printed form of a unit of :mod:`mtmc.positioning` (``um`` → ``µm``)."""
    return _LABELS.get(unit, unit)


@dataclass(frozen=True)
class PositioningStudy(Study):
    """A positioning test and the model of its uncertainty (kind ``positioning``).

    Attributes
    ----------
    test : PositioningTest
        The readings.
    model : UncertaintyModel
        The influences.
    axis : str
        The axis letter (names the compensation table, ``EXX``).
    tolerances : mapping of str to float
        Upper limits of parameters, by symbol, in the deviation unit.
    guard_band : float or "U"
        The guard band ``w`` in the deviation unit, or ``"U"``: each parameter's ``U``.
    """

    kind = "positioning"
    run_options = frozenset({ADAPTIVE, NAN_POLICY})
    test: Any
    model: Any
    axis: str = "X"
    tolerances: Mapping[str, float] = field(default_factory=dict)
    guard_band: float | str = 0.0

    def execute(self, settings: RunSettings, progress: ProgressFn | None) -> StudyResult:
        """Run the model by Monte Carlo and the GUM and tabulate it (module docstring)."""
        from mtmc.positioning import (
            SYMBOLS,
            apply_compensation,
            coverage,
            disagreement_notes,
            evaluate,
            evaluate_uncertainty,
            outliers,
            pitch_compensation,
        )
        from mtmc.positioning.parameters import NAMES
        from mtmc.positioning.uncertainty import INPUT_UNITS

        test = self.test
        unit = unit_label(test.unit)
        engine = settings.engine
        res = evaluate_uncertainty(
            test,
            self.model,
            engine.pop("trials"),
            settings.seed,
            p=engine.pop("p"),
            progress=progress,
            **engine,
        )
        quantities: list[Quantity] = []
        samples: dict[str, Any] = {}
        for sym in SYMBOLS:
            mc = res.monte_carlo(sym)
            g = res.gum_result(sym)
            q = quantity(sym, unit, mc, g, settings)
            # the headline is the parameter as ISO 230-2 defines it, from the readings,
            # rounded to the digits its Monte Carlo U supports (JCGM 100 §7.2.6)
            y = res.estimate(sym)
            q = replace(q, reported=Reported(*_rounded(y, q.mc.U, settings.ndig)))
            if sym in self.tolerances:
                q = replace(q, conformity=self._decide(sym, y, q, mc, g))
            quantities.append(q)
            if settings.samples:
                samples[sym] = mc.samples
        # a constant parameter (passed None, "not applicable") is no disagreement
        validated = {
            q.name: q.validation is None or q.validation.passed is not False for q in quantities
        }
        notes = disagreement_notes(res, validated)
        readings = res.readings
        covers_line, covers = coverage(res)
        param_rows = tuple(
            (
                q.name,
                NAMES[q.name],
                unit,
                res.estimate(q.name),
                q.mc.U,
                q.mc.coverage_interval[0],
                q.mc.coverage_interval[1],
                q.mc.estimate,
                q.gum.U if q.gum else "",
                "" if q.validation is None else q.validation.verdict,
                covers[q.name],
                float(getattr(readings, q.name)),
            )
            for q in quantities
        )
        tables = [
            Table(
                "parameters",
                f"Parameters of ISO 230-2 ({unit}): the estimate is the definition applied to "
                "the readings; U and the interval are the Monte Carlo's, the MC mean beside. "
                + covers_line,
                (
                    "symbol",
                    "parameter",
                    "unit",
                    "estimate",
                    "U (MC)",
                    "MC interval low",
                    "MC interval high",
                    "MC mean",
                    "GUM U",
                    "GUM by JCGM 101 §8",
                    "U covers",
                    "readings as recorded",
                ),
                param_rows,
            ),
            _targets_table(test, readings, unit),
        ]
        tables.extend(
            _compensation_tables(test, self.axis, unit, pitch_compensation, apply_compensation)
        )
        inputs = [
            input_record(
                name,
                d,
                INPUT_UNITS.get(
                    name,
                    unit if name in ("drift", "resolution") or name.startswith("typeA") else "1",
                ),
            )
            for name, d in res.inputs.items()
        ]
        means = evaluate(test)
        extra = {
            "positioning": {
                "axis": self.axis,
                "data": test.source,
                "unit": unit,
                "target_unit": unit_label(test.target_unit),
                "targets": test.targets,
                "deviations": test.deviations,
                "mean_up": means.mean_up,
                "mean_down": means.mean_down,
                "s_up": means.s_up,
                "s_down": means.s_down,
                "runs": list(test.runs),
                "type_a": self.model.type_a,
                "notes": notes,
                "covers": covers_line,
                "covers_by": covers,
                "warnings": [o.text(unit_label(test.target_unit), unit) for o in outliers(test)],
            }
        }
        return self._result(
            settings,
            run=mc_run_record(settings, res.mc),
            quantities=tuple(quantities),
            tables=tuple(tables),
            inputs=tuple(inputs),
            extra=extra,
            samples=samples,
        )

    def _decide(self, sym: str, y: float, q: Quantity, mc: Any, g: Any) -> dict[str, Any]:
        """The conformity entry of a parameter: ``Y ≤ T`` by the engine's rule (JCGM 106).

        The rule decides on the estimate of the parameter from the readings (the value
        ISO 230-2 defines, :meth:`PositioningUncertainty.estimate`); ``p_c = Pr(Y ≤ T)``
        is that of the Monte Carlo values, the GUM's beside it. A guard band makes the
        rule guarded acceptance with ``w`` the band (``"U"``: the parameter's Monte
        Carlo U).
        """
        from mtmc.uncertainty.decision import conformance_probability, conformity

        tol = self.tolerances[sym]
        w = q.mc.U if self.guard_band == "U" else float(self.guard_band)
        guarded = self.guard_band == "U" or w != 0.0
        c = conformity(
            mc,
            None,
            tol,
            rule="guarded" if guarded else "simple",
            guard_band=w if guarded else None,
            estimate=y,
        )
        out = c.to_dict()
        out["gum_p_c"], _, out["gum_basis"] = conformance_probability(g, None, tol)
        return out


def _rounded(y: float, big_u: float, ndig: int) -> tuple[str, str]:
    """``y`` and ``U`` to the digits ``U`` supports (JCGM 100 §7.2.6); ``U = 0``: 6 digits."""
    if big_u > 0:
        return round_to_uncertainty(y, big_u, ndig)
    return f"{y:.6g}", "0"


def _targets_table(test: Any, p: Any, unit: str) -> Table:
    rows = tuple(
        (
            float(test.targets[i]),
            float(p.mean_up[i]),
            float(p.mean_down[i]),
            float(p.mean[i]),
            float(p.reversal[i]),
            float(p.s_up[i]),
            float(p.s_down[i]),
            float(p.R_i_up[i]),
            float(p.R_i_down[i]),
            float(p.R_i[i]),
        )
        for i in range(test.m)
    )
    t_unit = unit_label(test.target_unit)
    return Table(
        "targets",
        f"Statistics at each target from the readings ({unit})",
        (
            f"P_i / {t_unit}",
            "x̄_i↑",
            "x̄_i↓",
            "x̄_i",
            "B_i",
            "s_i↑",
            "s_i↓",
            "R_i↑",
            "R_i↓",
            "R_i",
        ),
        rows,
    )


def _compensation_tables(test: Any, axis: str, unit: str, pitch: Any, apply: Any) -> list[Table]:
    from mtmc.positioning import SYMBOLS, evaluate

    table = pitch(test, axis)
    curve = table.curves[0]
    residual = apply(test, table, axis)
    before, after = evaluate(test), evaluate(residual)
    rows = tuple(
        (
            float(test.targets[i]),
            float(before.mean[i]),
            -float(before.mean[i]),
            float(after.mean_up[i]),
            float(after.mean_down[i]),
        )
        for i in range(test.m)
    )
    t_unit = unit_label(test.target_unit)
    comp = Table(
        "compensation",
        f"Pitch-error compensation table {curve.name}: the mean bidirectional deviation at "
        f"each target ({unit}; write it with mtmc positioning evaluate --compensation), and "
        "the residual means after it",
        (
            f"position / {t_unit}",
            f"error {curve.name}",
            "correction",
            "residual x̄_i↑",
            "residual x̄_i↓",
        ),
        rows,
    )
    res_rows = tuple(
        (s, unit, float(getattr(before, s)), float(getattr(after, s))) for s in SYMBOLS
    )
    resid = Table(
        "compensation_residual",
        "The parameters before and after the compensation table (from the readings): what is "
        "left is the reversal and the scatter",
        ("symbol", "unit", "before", "after"),
        res_rows,
    )
    return [comp, resid]


def _read_model(top: Fields) -> tuple[dict[str, Any], str]:
    """The keywords of :class:`UncertaintyModel` from the study's tables, and the data units."""
    kw: dict[str, Any] = {}
    env = top.table("environment", required=False)
    if env is not None:
        env.only((*_ENV_KEYS, "material_compensated"))
        for key, name in _ENV_KEYS.items():
            if env.has(key):
                kw[name] = read_distribution(env, key)
        if env.has("material_compensated"):
            kw["material_compensated"] = env.flag("material_compensated")
    ins = top.table("instrument", required=False)
    if ins is not None:
        ins.only(
            (
                *_INSTRUMENT_KEYS,
                "equation",
                "wavelength_nm",
                "dead_path_mm",
                "resolution",
                "datum_mm",
            )
        )
        for key, name in _INSTRUMENT_KEYS.items():
            if ins.has(key):
                kw[name] = read_distribution(ins, key)
        if ins.has("equation"):
            from mtmc.positioning import EQUATIONS

            kw["equation"] = ins.text("equation", choices=EQUATIONS)
        if ins.has("wavelength_nm"):
            kw["wavelength_nm"] = ins.number("wavelength_nm")  # its range: the equation's
        for key in ("dead_path_mm", "resolution"):
            if ins.has(key):
                kw[key] = ins.number(key, low=0.0)
        if ins.has("datum_mm"):
            kw["datum_mm"] = ins.number("datum_mm")
    unc = top.table("uncertainty", required=False)
    if unc is not None:
        from mtmc.positioning import TYPE_A

        unc.only(("type_a",))
        kw["type_a"] = unc.text("type_a", "means", choices=TYPE_A)
    return kw, top.text("units", "mm,um")


def _read_tolerances(top: Fields) -> tuple[dict[str, float], float | str]:
    from mtmc.positioning import SYMBOLS

    tol = top.table("tolerances", required=False)
    if tol is None:
        return {}, 0.0
    tol.only((*SYMBOLS, "guard_band"))
    out = {s: float(tol.number(s, low=0.0)) for s in SYMBOLS if tol.has(s)}
    guard: float | str = 0.0
    if tol.has("guard_band"):
        g = tol.data["guard_band"]
        if isinstance(g, str):
            guard = tol.text("guard_band", choices=("U",))
        else:
            guard = float(tol.number("guard_band", low=0.0))
    return out, guard


def _read_directions(top: Fields) -> dict[str, str] | None:
    """``[directions]``: the file's word of each direction, ``Hin = "up"``, ``Rück = "down"``."""
    t = top.table("directions", required=False)
    if t is None:
        return None
    out = {}
    for key in t.data:
        out[str(key)] = t.text(key, choices=("up", "down", "+", "-"))
    return out


def _model_error(top: Fields, exc: InputError) -> InputError:
    """An error of :class:`UncertaintyModel` at the study key that gave the field."""
    name = exc.field or ""
    for table, mapping in (("environment", _ENV_KEYS), ("instrument", _INSTRUMENT_KEYS)):
        inv = {v: k for k, v in mapping.items()}
        if name in inv:
            return top.source.error(exc.message, (table, inv[name]))
    if name in ("dead_path_mm", "wavelength_nm", "resolution"):  # the model's other checks
        return top.source.error(exc.message, ("instrument", name))
    return top.source.error(exc.message, ())


def positioning_study(
    data: str | Path,
    *,
    source: Source | None = None,
    settings: RunSettings | None = None,
    model: Mapping[str, Any] | None = None,
    units: str = "mm,um",
    columns: Mapping[str, str] | None = None,
    directions: str | Mapping[str, str] | None = None,
    axis: str = "X",
    title: str | None = None,
    tolerances: Mapping[str, float] | None = None,
    guard_band: float | str = 0.0,
) -> PositioningStudy:
    """A positioning study from a CSV file and the keywords of its model.

    The one route from readings to results: ``mtmc run`` builds it from a study file,
    ``mtmc positioning evaluate`` from the command line.

    Parameters
    ----------
    data : path-like
        The CSV file of the readings.
    source : Source, optional
        The study file it comes from (default: a study of the CSV file alone).
    settings : RunSettings, optional
        Trials, seed, p (default: :class:`RunSettings`'s defaults).
    model : mapping, optional
        Keywords of :class:`~mtmc.positioning.UncertaintyModel` (default: the Type A
        inputs alone).
    units, columns, directions, axis, title, tolerances, guard_band
        As the study file's keys.

    Returns
    -------
    PositioningStudy
    """
    from mtmc.positioning import UncertaintyModel, load_positioning_csv
    from mtmc.positioning.uncertainty import check_deviation_ranges

    test = load_positioning_csv(data, columns=columns, units=units, directions=directions)
    if source is None:
        text = f'kind = "positioning"\ndata = {Path(data).as_posix()!r}\n'
        source = Source.from_text(text, str(data), None)
    uncertainty_model = UncertaintyModel(**dict(model or {}))
    check_deviation_ranges(test, uncertainty_model)
    return PositioningStudy(
        title=title or f"Positioning test of axis {axis} (ISO 230-2)",
        source=source,
        settings=settings or RunSettings(),
        test=test,
        model=uncertainty_model,
        axis=axis,
        tolerances=dict(tolerances or {}),
        guard_band=guard_band,
    )


@register_kind("positioning", "an ISO 230-2 positioning test: parameters with U by GUM and MC")
def read_positioning_study(top: Fields) -> PositioningStudy:
    """Validate a ``positioning`` study file (``docs/positioning.md``)."""
    top.only(
        (
            "kind",
            "title",
            "data",
            "units",
            "columns",
            "directions",
            "axis",
            "environment",
            "instrument",
            "uncertainty",
            "tolerances",
            "run",
        )
    )
    from mtmc.positioning import parse_units

    path = top.source.resolve(top.text("data"), ("data",))
    kw, units = _read_model(top)
    try:
        parse_units(units)
    except InputError as exc:
        raise top.error(exc.message, "units") from None
    cols = top.table("columns", required=False)
    columns: dict[str, str] | None = None
    if cols is not None:
        from mtmc.positioning import COLUMNS

        cols.only(COLUMNS)
        columns = {k: cols.text(k) for k in COLUMNS if cols.has(k)}
    directions = _read_directions(top)
    axis = top.text("axis", "X", choices=tuple("XYZUVWABC"))
    tolerances, guard = _read_tolerances(top)
    settings = RunSettings.read(top)
    try:
        return positioning_study(
            path,
            source=top.source,
            settings=settings,
            model=kw,
            units=units,
            columns=columns,
            directions=directions,
            axis=axis,
            title=top.text("title", None),
            tolerances=tolerances,
            guard_band=guard,
        )
    except InputError as exc:
        if exc.file is not None:
            raise
        raise _model_error(top, exc) from None


def summary(result: StudyResult) -> dict[str, Any]:
    """The parameters of a positioning result as ``mtmc positioning evaluate --json`` prints them.

    Parameters
    ----------
    result : StudyResult
        Of a ``positioning`` study.

    Returns
    -------
    dict
        ``unit``, ``target_unit``, ``axis``, ``data``, ``trials``, ``seed``, ``p``,
        ``type_a``, ``covers`` (one line: what the U covers), ``notes``, ``warnings``
        (runs far from the others, kept), and ``parameters``: by symbol (``A``,
        ``A_up``, …, ``B_mean``), ``estimate`` (the definition of ISO 230-2 applied to
        the readings, corrected by the model's expected corrections where it has any),
        ``reported`` (estimate and U as text, to the digits U supports), ``U`` (Monte
        Carlo: half the length of its coverage interval), ``u``, ``interval``,
        ``mc_mean`` (the Monte Carlo mean, another number than the estimate), ``covers``
        (what its U covers, or ``"not evaluated: <reason>"``), ``readings`` (the
        definition applied to the readings as recorded), ``gum`` (``u``, ``U``, ``k``),
        ``validated`` (JCGM 101 §8; null where both methods give one value) and its
        ``verdict``, all in the deviation unit; ``conformity`` by symbol where the study
        gives tolerances (the entry of the quantity, the shape of every kind).
    """
    pos = result.extra["positioning"]
    tables = {t.name: t for t in result.tables}
    t = tables["parameters"]
    rows = {row[0]: dict(zip(t.columns, row, strict=True)) for row in t.rows}
    params: dict[str, Any] = {}
    conform: dict[str, Any] = {}
    for q in result.quantities:
        mc, g, row = q.mc, q.gum, rows[q.name]
        params[q.name] = {
            "estimate": row["estimate"],
            "reported": q.reported.to_dict(),
            "U": mc.U,
            "u": mc.u,
            "interval": list(mc.coverage_interval),
            "mc_mean": mc.estimate,
            "covers": row["U covers"],
            "readings": row["readings as recorded"],
            "gum": {
                "u": None if g is None else g.u,
                "U": None if g is None else g.U,
                "k": None if g is None else g.k,
            },
            # JCGM 101 §8: true or false, null where there is nothing to compare (a
            # parameter that both methods give as one value: "not applicable")
            "validated": None if q.validation is None else q.validation.passed,
            "verdict": None if q.validation is None else q.validation.verdict,
        }
        if q.conformity is not None:
            conform[q.name] = q.conformity
    out: dict[str, Any] = {
        "data": pos["data"],
        "axis": pos["axis"],
        "unit": pos["unit"],
        "target_unit": pos["target_unit"],
        "type_a": pos["type_a"],
        "trials": result.trials,
        "seed": result.seed,
        "p": result.p,
        "covers": pos.get("covers"),
        "parameters": params,
        "notes": list(pos["notes"]),
        "warnings": list(pos.get("warnings", [])),
    }
    if conform:
        out["conformity"] = conform
    return out
