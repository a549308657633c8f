"""Study kind ``artefact``: a fiducial-artefact study of Wang, Cheung and Kong (2022).

The file is an artefact study (``docs/artefact.md``) with ``kind = "artefact"``: it is
read by :func:`mtmc.artefact.simulation.read_artefact_study` and run by
:func:`mtmc.artefact.simulation.simulate_artefact` (the noise-free chain, Monte Carlo over
the probing, CMM and repeatability noise, the GUM beside it). The result holds the tables of the
paper — Table 2 per pose (``r_max``, ``r_avg`` of the measured and the modelled centres),
the identified setup errors (eq. 18) — each with the Monte Carlo mean and ``u`` and the
GUM ``u``, and the error vectors of Fig. 7 at the probed balls.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from mtmc.document import Fields
from mtmc.study.base import ProgressFn, Study
from mtmc.study.options import ADAPTIVE, NAN_POLICY, run_record
from mtmc.study.result import PointField, Quantity, StudyResult, Table, quantity
from mtmc.study.settings import RunSettings
from mtmc.study.spec import register_kind
from mtmc.uncertainty.montecarlo import adaptive_block_size
from mtmc.uncertainty.results import MonteCarloResult

__all__ = ["ArtefactKindStudy"]

#: µm per mm: the artefact study is written in µm and its results are given in µm, each
#: value of the code's mm times this exact factor (docs/results-format.md, the unit rule).
_UM = 1e3


@dataclass(frozen=True)
class ArtefactKindStudy(Study):
    """An artefact study, read and validated by :mod:`mtmc.artefact` (kind ``artefact``).

    Attributes
    ----------
    study : ArtefactStudy
        The validated study of :func:`mtmc.artefact.simulation.read_artefact_study`.
    noise, gum
        The ``noise`` and ``gum_too`` of :func:`mtmc.artefact.simulation.simulate_artefact`
        (``mtmc artefact simulate --noise``, ``--no-gum``); a study file runs with the
        defaults.
    on_simulated : callable, optional
        Called with the :class:`~mtmc.artefact.simulation.ArtefactResult` of a run, before it
        is tabulated (the command line draws Fig. 7 from it).
    """

    kind = "artefact"
    run_options = frozenset({ADAPTIVE, NAN_POLICY})
    study: Any
    noise: str = "points"
    gum: bool = True
    on_simulated: Any = dataclasses.field(default=None, compare=False, repr=False)

    def execute(self, settings: RunSettings, progress: ProgressFn | None) -> StudyResult:
        """Simulate the study (:func:`~mtmc.artefact.simulation.simulate_artefact`), tabulate it."""
        from mtmc.artefact.simulation import simulate_artefact

        res = simulate_artefact(
            self.study,
            seed=settings.seed,
            progress=progress,
            gum_too=self.gum,
            noise=self.noise,
            **settings.engine,
        )
        if self.on_simulated is not None:
            self.on_simulated(res)
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
                "Identified setup errors (eq. 18). They are not the injected ones where the "
                "machine has errors: the fiducials' setup errors take up the mean of the "
                "volumetric errors over the poses, the probe's the part common to all balls; "
                "with no machine error the injected values come back (docs/artefact.md)",
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
        vec = meas.in_axes(vol)
        labels = tuple(
            ", ".join(f"{k[0]} = {v:g}°" for k, v in lab.items()) + f", ball {n + 1}"
            for lab in res.pose_labels()
            for n in range(pos.shape[1])
        )
        field = PointField(
            name="volumetric",
            title="Volumetric errors at the balls, pose by pose (Fig. 7)",
            points=pos.reshape(-1, 3),
            values=_UM * np.asarray(vec, dtype=np.float64).reshape(-1, 3),
            unit="µm",
            labels=labels,
            axes=tuple(self.study.setup.linear)[:3],
            magnification=10_000.0,
        )
        extra = {"artefact": {"volumetric_mean_um": j["volumetric_mean_um"], "units": "um"}}
        # the engine keeps the finite trials only: the others were left out
        omitted = res.trials - len(res.samples["setup"])
        return self._result(
            settings,
            run=run_record(settings, res.trials, omitted, blocks=_blocks(res.trials, settings)),
            quantities=_quantities(res, settings),
            tables=tables,
            fields=(field,),
            inputs=_inputs(self.study),
            extra=extra,
        )


def _normal(name: str, mean_mm: float, sd_mm: float) -> dict[str, Any]:
    """An input row of the artefact study: a normal law of a length, given in mm, in µm."""
    return {
        "name": name,
        "distribution": f"normal({_UM * mean_mm:g}, {_UM * sd_mm:g})",
        "estimate": _UM * float(mean_mm),
        "u": _UM * float(sd_mm),
        "unit": "µm",
    }


def _inputs(study: Any) -> tuple[dict[str, Any], ...]:
    """The uncertain inputs the study file fixes, as ``inputs`` of ``result.json``, in µm.

    The probing repeatability along each linear axis at every probed point; where the
    study asks for them, the CMM covariance of the calibrated centres (Table 1: ``a`` and
    the scale ``L/D``; ``u`` left out, it differs from one coordinate to the next, the
    range is in the text), the machine's repeatability per probing and the setup errors
    about their values.
    """
    setup = study.setup
    art = setup.artefact
    axes = tuple(setup.linear)[:3]
    P, N, R = len(study.poses), int(art.n_balls), int(study.repetitions)
    probed = R * P * N
    points = probed * len(setup.offsets)
    out: list[dict[str, Any]] = [
        _normal(f"probing repeatability, {a} (each of the {points} points)", 0.0, s)
        for a, s in zip(axes, study.repeatability, strict=True)
    ]
    if study.cmm:
        sd = _UM * np.sqrt(np.diag(art.centre_covariance()))
        out.append(
            {
                "name": f"calibrated centres ({3 * N} coordinates)",
                "distribution": f"normal(0, V_CMM), u(L) = √({art.cmm_a_um:g}² + "
                f"(L/{art.cmm_divisor_mm:g})²) µm for a distance L in mm; u of a coordinate "
                f"from {sd.min():.3g} to {sd.max():.3g} µm",
                "estimate": 0.0,
                "u": None,
                "unit": "µm",
            }
        )
    if study.machine_repeatability is not None:
        out += [
            _normal(f"machine repeatability, {a} (each of the {probed} probings)", 0.0, s)
            for a, s in zip(axes, study.machine_repeatability, strict=True)
        ]
    if study.setup_u is not None:
        values = np.zeros(3 + 3 * N) if study.setup_errors is None else study.setup_errors
        out += [
            _normal(f"setup error {name}", v, study.setup_u)
            for name, v in zip(study.names, values, strict=True)
        ]
    return tuple(out)


def _blocks(trials: int, settings: RunSettings) -> int | None:
    """The blocks of an adaptive run of ``trials`` (JCGM 101 §7.9.4 a)), else None."""
    return trials // adaptive_block_size(settings.p) if settings.adaptive else None


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
        out.append(quantity(name, "mm", mc, g, settings).in_unit("µm", _UM))
    return tuple(out)


@register_kind("artefact", "a fiducial artefact probed at rotary poses (Wang, Cheung and Kong)")
def read_artefact_kind(top: Fields) -> ArtefactKindStudy:
    """Validate an ``artefact`` study file (reader: :mod:`mtmc.artefact.simulation`)."""
    from mtmc.artefact.simulation import read_artefact_study

    settings = RunSettings.read(top, default_trials=10_000)
    study = read_artefact_study(top)
    return ArtefactKindStudy(
        title=study.title or "Fiducial artefact",
        source=top.source,
        settings=settings,
        study=study,
    )
