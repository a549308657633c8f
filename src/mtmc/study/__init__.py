"""Study files: TOML → validated study → run → result folder with provenance.

A study file names its ``kind`` and its parameters (``docs/study-format.md``);
:func:`load_study` validates all of it before anything runs, and every error names the
file, the line and the field. ``load_study(path).run()`` returns a frozen
:class:`StudyResult`; :func:`write_result` writes the result folder
(``docs/results-format.md``) with its HTML report. Kinds register themselves with
:func:`register_kind`: ``propagate``, ``graph``, ``sweep``, ``kinematics``, ``artefact``,
``positioning``, ``circular``.
"""

from mtmc.study import artefact as _artefact  # noqa: F401  (registers artefact)
from mtmc.study import circular as _circular  # noqa: F401  (registers circular)
from mtmc.study import graph as _graph  # noqa: F401  (registers graph and sweep)
from mtmc.study import kinematics as _kinematics  # noqa: F401  (registers kinematics)
from mtmc.study import positioning as _positioning  # noqa: F401  (registers positioning)
from mtmc.study import propagate as _propagate  # noqa: F401  (registers propagate)
from mtmc.study import verification as _verification  # noqa: F401  (registers verification)
from mtmc.study.base import Study
from mtmc.study.load import load_result, study_result
from mtmc.study.render import render_report
from mtmc.study.result import (
    BudgetLine,
    Convergence,
    GumSummary,
    Histogram,
    MonteCarloSummary,
    Quantity,
    Region,
    Reported,
    StudyResult,
    Table,
    ValidationSummary,
)
from mtmc.study.settings import RunSettings
from mtmc.study.spec import (
    StudyKind,
    load_study,
    loads_study,
    register_kind,
    study_kinds,
)
from mtmc.study.write import provenance, write_result

__all__ = [
    "BudgetLine",
    "Convergence",
    "GumSummary",
    "Histogram",
    "MonteCarloSummary",
    "Quantity",
    "Region",
    "Reported",
    "RunSettings",
    "Study",
    "StudyKind",
    "StudyResult",
    "Table",
    "ValidationSummary",
    "load_study",
    "load_result",
    "loads_study",
    "provenance",
    "register_kind",
    "render_report",
    "study_kinds",
    "study_result",
    "write_result",
]
