"""Positioning tests of numerically controlled axes (ISO 230-2) with their uncertainty.

A test (:class:`PositioningTest`, read from a CSV file by :func:`load_positioning_csv`)
gives the parameters of ISO 230-2 from their definitions (:func:`evaluate`: ``A``, ``E``,
``M``, ``R``, ``B`` and their unidirectional forms); an input model of the test
(:class:`UncertaintyModel`: the laser's wavelength, the refractive index of air by an
updated Edlén equation, the material temperature and expansion, misalignment, dead path,
drift, resolution, and the axis' own scatter as Type A inputs) gives their uncertainty by
Monte Carlo and by the GUM through :mod:`mtmc.uncertainty` (:func:`evaluate_uncertainty`);
:func:`pitch_compensation` writes the pitch-error table the test implies. The formulas and
their sources are in ``docs/positioning.md``.
"""

from mtmc.positioning.compensation import apply_compensation, pitch_compensation
from mtmc.positioning.data import (
    COLUMNS,
    DEVIATION_UNITS,
    DIRECTION_WORDS,
    PositioningTest,
    load_positioning_csv,
    loads_positioning_csv,
    parse_directions,
    parse_units,
    reading_times,
)
from mtmc.positioning.edlen import (
    EQUATIONS,
    HENE_WAVELENGTH_NM,
    refractive_index,
    saturation_vapour_pressure,
)
from mtmc.positioning.parameters import (
    OUTLIER_LEVEL,
    SYMBOLS,
    Outlier,
    PositioningParameters,
    axis_parameters,
    evaluate,
    grubbs_critical,
    outliers,
    statistics,
)
from mtmc.positioning.uncertainty import (
    TYPE_A,
    PositioningUncertainty,
    UncertaintyModel,
    coverage,
    disagreement_notes,
    evaluate_uncertainty,
    physical_ranges,
    positioning_model,
)

__all__ = [
    "COLUMNS",
    "DEVIATION_UNITS",
    "DIRECTION_WORDS",
    "EQUATIONS",
    "HENE_WAVELENGTH_NM",
    "OUTLIER_LEVEL",
    "SYMBOLS",
    "TYPE_A",
    "Outlier",
    "PositioningParameters",
    "PositioningTest",
    "PositioningUncertainty",
    "UncertaintyModel",
    "apply_compensation",
    "axis_parameters",
    "coverage",
    "disagreement_notes",
    "evaluate",
    "evaluate_uncertainty",
    "grubbs_critical",
    "load_positioning_csv",
    "loads_positioning_csv",
    "outliers",
    "parse_directions",
    "parse_units",
    "physical_ranges",
    "pitch_compensation",
    "positioning_model",
    "reading_times",
    "refractive_index",
    "saturation_vapour_pressure",
    "statistics",
]
