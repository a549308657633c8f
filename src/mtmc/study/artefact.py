"""Study kind ``artefact``: a fiducial-artefact study of Wang, Cheung and Kong (2022).

The file is an artefact study (``docs/artefact.md``) with ``kind = "artefact"``: it is
read by :func:`mtmc.artefact.study.read_artefact_study` and run by
:func:`mtmc.artefact.study.simulate_artefact` (the noise-free chain, Monte Carlo over the probing,
CMM and repeatability noise, the GUM beside it). The result holds the tables of the
paper — Table 2 per pose (``r_max``, ``r_avg`` of the measured and the modelled centres),
the identified setup errors (eq. 18) — each with the Monte Carlo mean and ``u`` and the
GUM ``u``, and the error vectors of Fig. 7 at the probed balls.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from mtmc.document import Fields
from mtmc.study.base import PointField, ProgressFn, Quantity, Study, StudyResult, Table, quantity
from mtmc.study.spec import RunSettings, register_kind
from mtmc.uncertainty.results import MonteCarloResult

__all__ = ["ArtefactKindStudy"]

#: mm per µm: the artefact results are in µm.
_UM = 1e-3


@dataclass(frozen=True)
class ArtefactKindStudy(Study):
    """An artefact study, read and validated by :mod:`mtmc.artefact` (kind ``artefact``).

    Attributes
    ----------
    study : ArtefactStudy
        The validated study of :func:`mtmc.artefact.study.read_artefact_study`.
    """

    kind = "artefact"
    study: Any

    def execute(self, settings: RunSettings, progress: ProgressFn | None) -> StudyResult:
        """Simulate the study (:func:`mtmc.artefact.study.simulate_artefact`) and tabulate it."""
        from mtmc.artefact.study import simulate_artefact

        res = simulate_artefact(
            self.study,
            trials=settings.trials,
            seed=settings.seed,
            progress=progress,
            **settings.parallel,
        )
        j = res.to_json()
        rows = []
        for pose in j["poses"]:
            angles = [v for k, v in pose.items() if k.endswith("_deg")]
            cells: list[Any] = list(angles)
            for key in ("r_max_um", "r_avg_um", "r_max_model_um", "r_avg_model_um"):
                e = pose[key]
                cells += [e["noise_free"], e["estimate"], e["u"], e.get("gum_u", "")]
            rows.append(tuple(cells))
        angle_cols = [f"{k[: -len('_deg')]} / deg" for k in j["poses"][0] if k.endswith("_deg")]
        cols: list[str] = list(angle_cols)
        for key in ("r_max", "r_avg", "r_max_model", "r_avg_model"):
            cols += [
                f"{key} noise-free / µm",
                f"{key} MC mean / µm",
                f"{key} MC u / µm",
                f"{key} GUM u / µm",
            ]
        setup_rows = tuple(
            (
                name,
                e["injected"],
                e["noise_free"],
                e["estimate"],
                e["u"],
                e.get("gum_u", ""),
            )
            for name, e in j["setup_errors"].items()
        )
        tables = (
            Table("poses", "Distance errors per pose (Table 2)", tuple(cols), tuple(rows)),
            Table(
                "setup_errors",
                "Identified setup errors (eq. 18)",
                (
                    "error",
                    "injected / µm",
                    "identified noise-free / µm",
                    "MC mean / µm",
                    "MC u / µm",
                    "GUM u / µm",
                ),
                setup_rows,
            ),
        )
        meas = res.measurement
        pos = np.asarray(meas.commanded, dtype=np.float64)  # (P, N, 3) axis positions, mm
        vol = np.asarray(res.nominal.volumetric[0], dtype=np.float64)  # (P, N, 3), mm
        vec = np.linalg.solve(meas.axis_map[:, None], vol[..., None])[..., 0]
        labels = tuple(
            ", ".join(f"{k[0]} = {v:g}°" for k, v in lab.items()) + f", ball {n + 1}"
            for lab in res.pose_labels()
            for n in range(pos.shape[1])
        )
        field = PointField(
            name="volumetric",
            title="Volumetric errors at the balls, pose by pose (Fig. 7)",
            points=pos.reshape(-1, 3),
            values=np.asarray(vec, dtype=np.float64).reshape(-1, 3),
            unit="mm",
            labels=labels,
            axes=tuple(self.study.setup.linear)[:3],
            magnification=10_000.0,
        )
        extra = {"artefact": {"volumetric_mean_um": j["volumetric_mean_um"], "units": "um"}}
        return self._result(
            settings,
            quantities=_quantities(res, settings),
            tables=tables,
            fields=(field,),
            extra=extra,
        )


def _quantities(res: Any, settings: RunSettings) -> tuple[Quantity, ...]:
    """Table 2's ``r_max``, ``r_avg`` per pose and the setup errors as quantities.

    Their Monte Carlo values (the measured centres, ①) with the GUM beside them.

    Names: ``r_max.b-5_c-5`` (the pose's rotary positions in degrees), ``setup.dpx``.
    """
    out = []
    labels = ["_".join(f"{k[0]}{v:g}" for k, v in lab.items()) for lab in res.pose_labels()]
    items: list[tuple[str, str, int]] = [
        (f"{short}.{lab}", key, p)
        for short, key in (("r_max", "r_max_measured"), ("r_avg", "r_avg_measured"))
        for p, lab in enumerate(labels)
    ]
    items += [(f"setup.{name}", "setup", i) for i, name in enumerate(res.study.names)]
    for name, key, i in items:
        mc = MonteCarloResult.from_samples(res.samples[key][:, i], seed=res.seed)
        g = res.gum[key].component(i) if key in res.gum else None
        out.append(quantity(name, "mm", mc, g, settings))
    return tuple(out)


@register_kind("artefact", "a fiducial artefact probed at rotary poses (Wang, Cheung and Kong)")
def load_artefact_kind(top: Fields) -> ArtefactKindStudy:
    """Validate an ``artefact`` study file (reader: :mod:`mtmc.artefact.study`)."""
    from mtmc.artefact.study import read_artefact_study

    settings = RunSettings.read(top, default_trials=10_000)
    study = read_artefact_study(top)
    return ArtefactKindStudy(
        title=study.title or "Fiducial artefact",
        source=top.source,
        settings=settings,
        study=study,
    )
