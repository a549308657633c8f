"""Fiducial artefacts: probed balls, setup errors and volumetric errors at rotary poses.

Wang, Cheung and Kong (2022): a few CMM-calibrated balls on a fixture, probed on a
five-axis machine at several rotary poses, give the probe's and the fiducials' setup
errors (eqs. 16–20) and the machine's volumetric errors where the workpiece sits, with
their uncertainties by Monte Carlo (:func:`mtmc.uncertainty.monte_carlo`) and by the GUM.
The maths, the departures from the printed equations and the paper's tables beside
mtmc's are in ``docs/artefact.md``.
"""

from mtmc.artefact.artefact import (
    Artefact,
    distances,
    load_artefact,
    loads_artefact,
    pairs,
    shipped_artefact,
)
from mtmc.artefact.model import (
    FiducialSetup,
    Measurement,
    SetupIdentification,
    identify_setup,
    paper_jacobian,
    setup_error_names,
)
from mtmc.artefact.probing import (
    PAPER_REPEATABILITY_UM,
    SphereFit,
    fit_points,
    fit_sensitivity,
    load_points,
    patch_offsets,
    patch_points,
)

__all__ = [
    "PAPER_REPEATABILITY_UM",
    "Artefact",
    "FiducialSetup",
    "SetupIdentification",
    "Measurement",
    "SphereFit",
    "distances",
    "fit_points",
    "fit_sensitivity",
    "identify_setup",
    "load_artefact",
    "load_points",
    "loads_artefact",
    "paper_jacobian",
    "pairs",
    "patch_offsets",
    "patch_points",
    "setup_error_names",
    "shipped_artefact",
]
