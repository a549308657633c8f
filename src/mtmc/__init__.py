"""mtmc — machine-tool Monte Carlo.

How uncertain is a measurement on a machine tool? mtmc answers by Monte Carlo simulation
(JCGM 101) with the GUM law of propagation (JCGM 100) beside it, over measurement graphs
(touch-probe measurements, rotary-axis location), kinematic machine models with ISO 230
geometric errors, and, later, laser-tracker verification and fiducial artefacts.

The public API is re-exported here; everything else may change between versions.
"""

from __future__ import annotations

from mtmc import errors
from mtmc.errors import *  # noqa: F403
from mtmc.geometry import *  # noqa: F403
from mtmc.graph import *  # noqa: F403
from mtmc.kinematics import *  # noqa: F403
from mtmc.uncertainty import *  # noqa: F403

__version__ = "0.1.0"

# Imported after the version, which the result folders record. ``mtmc.report`` is the
# function that renders a result (the module stays importable as ``mtmc.report``).
from mtmc.report import report  # noqa: E402
from mtmc.study import (  # noqa: E402
    StudyResult,
    load_study,
    loads_study,
    register_kind,
    study_kinds,
    write_result,
)

__all__ = ["__version__", "errors", "report"]
__all__ += [
    "StudyResult",
    "load_study",
    "loads_study",
    "register_kind",
    "study_kinds",
    "write_result",
]
for _mod in ("errors", "uncertainty", "geometry", "graph", "kinematics"):
    __all__ += list(__import__(f"mtmc.{_mod}", fromlist=["__all__"]).__all__)
del _mod
