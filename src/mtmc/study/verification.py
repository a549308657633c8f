"""Study kind ``verification``: a laser-tracker volumetric verification (Aguado et al.).

The file is a verification study (``docs/verification.md``), read by
:func:`mtmc.verification.definition.read_verification_study` and run by
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
from numpy.typing import NDArray

from mtmc.document import Fields
from mtmc.study.base import ProgressFn, Study
from mtmc.study.result import PointField, StudyResult, Table, quantity
from mtmc.study.settings import RunSettings
from mtmc.study.spec import register_kind

__all__ = ["VerificationKindStudy", "file_unit"]

#: The unit and factor of an error parameter given in the code's mm or rad.
_ERROR_UNITS = {"mm": ("µm", 1e3), "rad": ("µrad", 1e6)}
#: µm per mm: the volumetric errors, computed in mm, are given in µm.
_UM = _ERROR_UNITS["mm"][1]


def file_unit(unit: str) -> tuple[str, float]:
    """The unit a verification study writes a value of the code's ``unit`` in, and its factor.

    Lengths (mm) in µm and angles (rad) in µrad, as the study file gives the machine's
    errors (``docs/results-format.md``, the unit rule); every command shows them so.

    Examples
    --------
    >>> file_unit("mm"), file_unit("rad")
    (('µm', 1000.0), ('µrad', 1000000.0))
    """
    return _ERROR_UNITS[unit]


@dataclass(frozen=True)
class VerificationKindStudy(Study):
    """A verification study, read and validated by :mod:`mtmc.verification` (kind ``verification``).

    Attributes
    ----------
    study : VerificationStudy
        The validated study of :func:`mtmc.verification.definition.read_verification_study`.
    points, tracker : str, optional
        The point set and tracker position simulated (``mtmc verify simulate --points``,
        ``--tracker``); None, as a study file runs: the study's defaults.
    """

    kind = "verification"
    no_adaptive = (
        "it simulates a fixed number of whole verifications, each an identification of the "
        "machine's error coefficients"
    )
    study: Any
    points: str | None = None
    tracker: str | None = None

    def execute(self, settings: RunSettings, progress: ProgressFn | None) -> StudyResult:
        """Simulate the verification and tabulate it (module docstring)."""
        from mtmc.verification.identify import parameter_unit
        from mtmc.verification.simulate import POINT_STATS, VE_NAMES
        from mtmc.verification.visibility import study_visibility, visibility_warnings

        s = self.study
        ver = s.verification(self.points, self.tracker)
        warnings = visibility_warnings(
            study_visibility(s, self.points, [self.tracker or s.default_tracker]),
            s.machine.axes,
        )
        mc = s.simulate(
            settings.trials,
            settings.seed,
            points=self.points,
            tracker=self.tracker,
            progress=progress,
            **settings.parallel,
        )
        # the file gives the machine's errors in µm and µrad (its travel in mm): the
        # errors are shown in those units, each value of the code's mm or rad times the
        # exact factor (docs/results-format.md, the unit rule)
        quantities = tuple(
            quantity(
                f"volumetric_error.{name}",
                "mm",
                mc.ve_result(name),
                None,
                settings,
            ).in_unit("µm", _UM)
            for name in VE_NAMES
        )
        ref = np.asarray(mc.reference.estimate, dtype=np.float64)[0]
        coef_rows = []
        for i, name in enumerate(mc.names):
            unit, f = file_unit(parameter_unit(s.machine, name))
            coef_rows.append(
                (
                    name,
                    unit,
                    f * float(ref[i]) if i < ref.size else "",
                    f * float(mc.coef_estimate[i]),
                    f * float(mc.coef_u[i]),
                    f * float(mc.gum.u[i]),
                )
            )
        errors, stats = POINT_STATS
        point_um = {
            w: {k: {"estimate": _UM * e, "u": _UM * u} for k, (e, u) in mc.point_mean_ve(w).items()}
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
                tuple(coef_rows),
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
            values=_UM * np.asarray(mc.point_u, dtype=np.float64),
            unit="µm",
        )
        bias = PointField(
            name="compensation_bias",
            title="Mean error left after compensation at each point",
            points=np.asarray(points, dtype=np.float64),
            values=_UM * np.asarray(mc.comp_bias, dtype=np.float64),
            unit="µm",
            magnification=1000.0,
        )
        return self._result(
            settings,
            quantities=quantities,
            tables=tables,
            fields=(field, bias),
            inputs=_inputs(s, ver.tracker, np.asarray(s.machine.tool_position(ver.q))),
            extra={
                "verification": {
                    "note": s.note,
                    "machine": str(s.machine.topology),
                    "point_mean_ve_um": point_um,
                    "point_set": self.points or s.default_points,
                    "tracker": self.tracker or s.default_tracker,
                    "points": int(ver.n_points),
                    "point_u_gum_um": {
                        "max": _UM * float(np.max(mc.gum.point_u)),
                        "mean": _UM * float(np.mean(mc.gum.point_u)),
                    },
                },
                "warnings": warnings,
            },
        )


def _inputs(s: Any, tracker: Any, points: NDArray[np.float64]) -> tuple[dict[str, Any], ...]:
    """The uncertain inputs the study file fixes, as ``inputs`` of ``result.json``.

    The tracker's noise on each spherical coordinate of every reading (Aguado et al. 2016
    eqs. 22-24: ``u_L = a + b·L``, ``u_α = c + e/L``, ``u_β = d + e/L``, ``u`` its mean
    over the ranges ``L`` of the points), and where the study gives them the machine's
    repeatability, the reflector offset and the tracker pose. Lengths in mm, angles in rad.
    """
    noise = s.noise
    L = np.linalg.norm(points - np.asarray(tracker.position, dtype=np.float64), axis=1)
    n = int(points.shape[0])
    span = f"L from {L.min():.0f} to {L.max():.0f} mm"
    e = f" + {noise.transverse_a:g}/L" if noise.transverse_a else ""
    u_L = float(np.mean(noise.u_spherical(L)[:, 0]))
    # u_α = c + e/L is linear in 1/L: its mean over the points is its value at the
    # harmonic mean of the ranges
    _, u_a, u_b = (float(u) for u in noise.u_spherical(1.0 / np.mean(1.0 / L)))
    rows: list[tuple[str, str, float, str]] = [
        (
            "tracker range L",
            f"normal(0, {noise.radial_a:g} + {noise.radial_b:g}·L), {span}",
            u_L,
            "mm",
        ),
        ("tracker azimuth α", f"normal(0, {noise.azimuth:g}{e})", u_a, "rad"),
        ("tracker elevation β", f"normal(0, {noise.elevation:g}{e})", u_b, "rad"),
    ]
    if s.repeatability > 0:
        rows.append(
            ("machine repeatability", f"normal(0, {s.repeatability:g})", s.repeatability, "mm")
        )
    if s.reflector_u > 0:
        rows.append(("reflector offset", f"normal(0, {s.reflector_u:g})", s.reflector_u, "mm"))
    if not s.pose:
        for name, u, unit in zip(
            ("rx", "ry", "rz", "tx", "ty", "tz"), s.pose_u, ("rad",) * 3 + ("mm",) * 3, strict=True
        ):
            if u > 0:
                rows.append((f"tracker pose {name}", f"normal(0, {u:g})", float(u), unit))
    return tuple(
        {
            "name": name + (f" (each of the {n} readings)" if i < 3 else ""),
            "distribution": text,
            "estimate": 0.0,
            "u": float(u),
            "unit": unit,
        }
        for i, (name, text, u, unit) in enumerate(rows)
    )


@register_kind("verification", "a laser-tracker volumetric verification (Aguado et al.)")
def read_verification_kind(top: Fields) -> VerificationKindStudy:
    """Validate a ``verification`` study file (reader: :mod:`mtmc.verification.definition`)."""
    from mtmc.verification.definition import RUN_KEYS, read_verification_study

    settings = RunSettings.read(top, default_trials=1000, extra=RUN_KEYS)
    study = read_verification_study(top)
    return VerificationKindStudy(
        title=study.title or "Laser-tracker verification",
        source=top.source,
        settings=settings,
        study=study,
    )
