"""Study kind ``verification``: a laser-tracker volumetric verification (Aguado et al.).

The file is a verification study (``docs/verification.md``), read by
:func:`mtmc.verification.study.read_verification_study` and run by
:func:`mtmc.verification.simulate.simulate`: the tracker noise is drawn by Monte Carlo, each
trial identifies the machine's error functions from its readings, and the result gives
the volumetric error before and after compensation (Aguado et al. 2017 §3, Fig. 5–6) and
the calibration uncertainty at every point, drawn as our own map. The
volumetric-error statistics become quantities (Monte Carlo, no GUM: they are maxima and
means over the points), the identified coefficients a table with their GUM ``u``, and the
calibration uncertainty a map over the workspace.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from mtmc.document import Fields
from mtmc.study.base import PointField, ProgressFn, Study, StudyResult, Table, quantity
from mtmc.study.spec import RunSettings, register_kind

__all__ = ["VerificationKindStudy"]


@dataclass(frozen=True)
class VerificationKindStudy(Study):
    """A verification study, read and validated by :mod:`mtmc.verification` (kind ``verification``).

    Attributes
    ----------
    study : VerificationStudy
        The validated study of :func:`mtmc.verification.study.read_verification_study`.
    """

    kind = "verification"
    study: Any

    def execute(self, settings: RunSettings, progress: ProgressFn | None) -> StudyResult:
        """Simulate the verification and tabulate it (module docstring)."""
        from mtmc.verification.identify import parameter_unit
        from mtmc.verification.simulate import POINT_STATS, VE_NAMES
        from mtmc.verification.visibility import study_visibility, visibility_warnings

        s = self.study
        ver = s.verification()
        warnings = visibility_warnings(
            study_visibility(s, None, [s.default_tracker]), s.machine.axes
        )
        mc = s.simulate(settings.trials, settings.seed, progress=progress, **settings.parallel)
        quantities = tuple(
            quantity(
                f"volumetric_error.{name}",
                "mm",
                mc.ve_result(name),
                None,
                settings,
            )
            for name in VE_NAMES
        )
        ref = np.asarray(mc.reference.estimate, dtype=np.float64)[0]
        coef_rows = tuple(
            (
                name,
                parameter_unit(s.machine, name),
                float(ref[i]) if i < ref.size else "",
                float(mc.coef_estimate[i]),
                float(mc.coef_u[i]),
                float(mc.gum.u[i]),
            )
            for i, name in enumerate(mc.names)
        )
        errors, stats = POINT_STATS
        point_um = {
            w: {k: {"estimate": 1e3 * e, "u": 1e3 * u} for k, (e, u) in mc.point_mean_ve(w).items()}
            for w in errors
        }
        point_rows = tuple(
            (w, k, "µm", point_um[w][k]["estimate"], point_um[w][k]["u"])
            for w in errors
            for k in stats
        )
        tables = (
            Table(
                "coefficients",
                "Identified parameters: noise-free, Monte Carlo mean and u, GUM u",
                ("parameter", "unit", "noise-free", "MC mean", "MC u", "GUM u"),
                coef_rows,
            ),
            Table(
                "point_mean_volumetric_error",
                "Each point's error averaged over the verifications: max, mean and min over "
                "the points (u: the standard deviation over the verifications of the error at "
                "the point of the max or min, and of the mean over the points)",
                ("error", "statistic", "unit", "estimate", "u"),
                point_rows,
            ),
        )
        q = ver.q if ver.eval_q is None else ver.eval_q
        points = s.machine.tool_position(q)
        field = PointField(
            name="calibration_u",
            title="Calibration uncertainty at each point, √(u²x + u²y + u²z): the standard "
            "deviation over the verifications of the error left after compensation",
            points=np.asarray(points, dtype=np.float64),
            values=np.asarray(mc.point_u, dtype=np.float64),
            unit="mm",
        )
        bias = PointField(
            name="compensation_bias",
            title="Mean error left after compensation at each point",
            points=np.asarray(points, dtype=np.float64),
            values=np.asarray(mc.comp_bias, dtype=np.float64),
            unit="mm",
            magnification=1000.0,
        )
        return self._result(
            settings,
            quantities=quantities,
            tables=tables,
            fields=(field, bias),
            extra={
                "verification": {
                    "note": s.note,
                    "machine": str(s.machine.topology),
                    "point_mean_ve_um": point_um,
                },
                "warnings": warnings,
            },
        )


@register_kind("verification", "a laser-tracker volumetric verification (Aguado et al.)")
def load_verification_kind(top: Fields) -> VerificationKindStudy:
    """Validate a ``verification`` study file (reader: :mod:`mtmc.verification.study`)."""
    from mtmc.verification.study import RUN_KEYS, read_verification_study

    settings = RunSettings.read(top, default_trials=1000, extra=RUN_KEYS)
    study = read_verification_study(top)
    return VerificationKindStudy(
        title=study.title or "Laser-tracker verification",
        source=top.source,
        settings=settings,
        study=study,
    )
