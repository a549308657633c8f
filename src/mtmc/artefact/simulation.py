"""An artefact study: the file, the simulation, the Monte Carlo and the GUM beside it.

A study (``docs/artefact.md``, e.g. ``examples/studies/wang2022.toml``) names an artefact,
a machine with its probe offset and its (chosen) geometric errors, the real setup errors,
the probing (patch, repeatability, calibrated or free radius), the plan of rotary poses
and repetitions, and which uncertainty sources vary from trial to trial.

:func:`simulate_artefact` probes the artefact on the modelled machine, noise-free, with the full
chain (:meth:`~mtmc.artefact.model.FiducialSetup.measure`), analyses it
(:func:`~mtmc.artefact.analysis.analyse`), then runs :func:`mtmc.uncertainty.monte_carlo`
over a vectorised model of the same analysis whose inputs are

- ``probe``: ``iid(normal(0, 1), R·P·N·n·3)``, the probing noise of every coordinate of every
  point, scaled by the per-axis repeatability along the machine's linear axes and carried
  into ``W`` by the axis map ``A`` (layout: repetition, pose, ball, point, axis, C order);
- ``cmm``: ``mvnormal(0, V)``, the calibrated centres' errors (artefact frame; ``V`` of
  :meth:`~mtmc.artefact.artefact.Artefact.centre_covariance`);
- ``repeat`` (optional): ``iid(normal(0, 1), R·P·N·3)``, the machine's repeatability: one
  shift of the linear axes per probing of a ball;
- ``setup`` (optional): ``iid(normal(0, 1), 3 + 3N)``, the setup errors varying about the
  injected ones.

The fitted centre of each trial is the noise-free one plus the fit's linear map applied to
the point displacements (:func:`~mtmc.artefact.probing.fit_sensitivity`; the difference
from a converged fit, 2·10⁻⁴ µm here, is shown by the tests, and ``exact_fit=True`` runs
the full Gauss–Newton fit for every trial instead). Everything after the centres —
identification, distances, ``r_max``, ``r_avg``, the rigid best fit — is evaluated
exactly, trial by trial in one batch, so the non-linear outputs keep their bias: the MC
mean is reported beside the noise-free value.

The GUM (:func:`mtmc.uncertainty.gum`) propagates the covariance of the centres (exact:
they are linear in the inputs) and of the calibration through the same analysis.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mtmc.artefact.analysis import ANALYSIS_OUTPUTS, Analysis, analyse
from mtmc.artefact.artefact import SHIPPED, Artefact, load_artefact, pairs, shipped_artefact
from mtmc.artefact.model import FiducialSetup, Measurement, identify_setup, setup_error_names
from mtmc.artefact.probing import PAPER_REPEATABILITY_UM, patch_offsets
from mtmc.document import MAX_DEG, MAX_MM, MAX_UM, MAX_URAD, Fields, check_length, finite
from mtmc.errors import InputError
from mtmc.geometry.fits import fit_sphere
from mtmc.kinematics import Machine
from mtmc.kinematics.functions import PolynomialFunction
from mtmc.kinematics.library import library_machine
from mtmc.kinematics.topology import is_linear

__all__ = [
    "SAMPLED_OUTPUTS",
    "ArtefactResult",
    "ArtefactStudy",
    "GumOutput",
    "gum_outputs",
    "read_artefact_study",
    "simulate_artefact",
    "study_model",
]

_F = NDArray[np.float64]
UM = 1e-3  # mm per um

#: The outputs whose Monte Carlo values :func:`simulate_artefact` keeps (the rest keep moments):
#: the setup errors and Table 2's ``r_max`` and ``r_avg`` per pose, a few numbers a trial.
SAMPLED_OUTPUTS = ("setup", "r_max_measured", "r_avg_measured", "r_max_model", "r_avg_model")
URAD = 1e-6  # rad per urad
#: The most poses ``[plan] poses_deg`` may list, and the most repetitions of each.
MAX_POSES = 1000
MAX_REPETITIONS = 1000


@dataclass(frozen=True, eq=False)
class ArtefactStudy:
    """Everything a simulation of the fiducial measurement needs.

    Attributes
    ----------
    title : str
        A label.
    setup : FiducialSetup
        Machine (with the probe offset), mounted artefact, probed patch.
    poses : ndarray, shape (P, R_axes)
        Rotary positions, rad, columns :attr:`FiducialSetup.rotary` (mtmc's ISO 841 sign).
    repetitions : int
        Repetitions ``R`` of the whole plan.
    errors : mapping
        The machine's geometric errors (ISO 230 names; numbers in mm/rad or error
        functions), chosen for the study.
    setup_errors : ndarray, shape (3 + 3N,)
        The real setup errors ``ΔE`` (eq. 18), mm.
    repeatability : ndarray, shape (3,)
        Probing repeatability along the linear axes, mm (standard deviations).
    free_radius : bool
        Fit the radius too (default: the calibrated radius).
    cmm : bool
        Vary the calibrated centres with the CMM covariance.
    machine_repeatability : ndarray, shape (3,), or None
        Per-probing repeatability of the linear axes, mm.
    setup_u : float or None
        Standard deviation of the setup errors about ``setup_errors``, mm.
    file : str
        Where the study was read from.
    """

    title: str
    setup: FiducialSetup
    poses: _F
    repetitions: int = 3
    errors: Mapping[str, Any] = field(default_factory=dict)
    setup_errors: _F | None = None
    repeatability: _F = field(default_factory=lambda: np.array(PAPER_REPEATABILITY_UM) * UM)
    free_radius: bool = False
    cmm: bool = True
    machine_repeatability: _F | None = None
    setup_u: float | None = None
    file: str = ""

    def __post_init__(self) -> None:
        n = self.setup.artefact.n_balls
        E = np.zeros(3 + 3 * n) if self.setup_errors is None else self.setup_errors
        E = np.asarray(E, dtype=np.float64)
        if E.shape != (3 + 3 * n,):
            raise InputError(f"expected {3 + 3 * n} setup errors", field="setup_errors")
        object.__setattr__(self, "setup_errors", E)
        object.__setattr__(self, "poses", self.setup.check_poses(self.poses))
        if self.repetitions < 1:
            raise InputError("expected at least one repetition", field="repetitions")

    @property
    def names(self) -> tuple[str, ...]:
        """Setup-error names (eq. 18)."""
        return setup_error_names(self.setup.artefact.names)


# ----------------------------------------------------------------------------------------
# the model


@dataclass(frozen=True, eq=False)
class _Prepared:
    meas: Measurement
    pinv: _F
    Jp: _F
    J: _F
    Kp: _F  # (R P N, 3, 3n): standard normals of the points -> centre shift
    Arep: _F  # (P, 3, 3): standard normals of a probing shift -> centre shift
    cal: _F  # (N, 3) mounted calibrated centres


def _prepare(study: ArtefactStudy) -> _Prepared:
    s = study.setup
    meas = s.measure(study.poses, study.errors, study.setup_errors, free_radius=study.free_radius)
    P, N = meas.centres.shape[:2]
    R = study.repetitions
    J1 = s.setup_jacobian(study.poses)
    J = np.tile(J1, (R, 1))
    pinv = np.asarray(np.linalg.pinv(J), dtype=np.float64)
    Jp = s.probe_jacobian(study.poses)
    A = meas.axis_map  # (P, 3, 3)
    AS = A * study.repeatability[None, None, :]  # axis noise (std normal) -> W
    k = meas.points.shape[2]
    K = meas.sensitivity.reshape(P, N, 3, k, 3)
    # (P, N, 3, k, 3): d centre / d (standard normal of point k, axis i)
    Kp1 = np.einsum("pnckj,pji->pncki", K, AS)
    Kp = np.broadcast_to(Kp1.reshape(1, P * N, 3, 3 * k), (R, P * N, 3, 3 * k))
    Arep = (
        A * study.machine_repeatability[None, None, :]
        if study.machine_repeatability is not None
        else np.zeros_like(A)
    )
    return _Prepared(
        meas,
        pinv,
        Jp,
        J1,
        np.ascontiguousarray(Kp.reshape(R * P * N, 3, 3 * k)),
        Arep,
        s.artefact.mounted_centres(),
    )


def study_model(
    study: ArtefactStudy,
    *,
    exact_fit: bool = False,
    split: bool = False,
    noise: str = "points",
) -> tuple[Callable[..., dict[str, _F]], dict[str, Any], _Prepared]:
    """The vectorised Monte Carlo model of a study and its inputs.

    Parameters
    ----------
    study : ArtefactStudy
    exact_fit : bool
        Fit every trial's points with :func:`mtmc.geometry.fit_sphere` (slow) instead of
        the fit's linear map.
    split : bool
        Return the per-pose outputs one pose at a time
        (:meth:`~mtmc.artefact.analysis.Analysis.by_pose`): the engine then keeps the
        covariance within each pose only, ``P`` times less work than across all poses.
    noise : {"points", "centres"}
        ``"points"``: draw the noise of every coordinate of every probed point (input
        ``probe`` of ``R·P·N·n·3`` standard normals). ``"centres"``: draw, for each fit,
        three standard normals times the Cholesky factor of its centre covariance
        ``K' K'ᵀ`` (``R·P·N·3`` values): the same Gaussian law of the centres as the
        linearised fit of Gaussian points, ``n`` times fewer random numbers.

    Returns
    -------
    model : callable
        ``model(probe, cmm=..., repeat=..., setup=...)`` returning the outputs of
        :data:`~mtmc.artefact.analysis.ANALYSIS_OUTPUTS`, each ``(m, d)`` in mm.
    inputs : dict
        The inputs for :func:`mtmc.uncertainty.monte_carlo`.
    prepared : object
        The noise-free measurement and the maps the model uses.
    """
    from mtmc.uncertainty.distributions import IID, MultivariateNormal, Normal

    pr = _prepare(study)
    meas = pr.meas
    P, N, k = meas.points.shape[:3]
    R = study.repetitions
    art = study.setup.artefact
    if noise not in ("points", "centres"):
        raise InputError(f"expected noise 'points' or 'centres', got {noise!r}", field="noise")
    if exact_fit and noise != "points":
        raise InputError("an exact fit needs the noise of the points", field="noise")
    per = k * 3 if noise == "points" else 3
    inputs: dict[str, Any] = {"probe": IID(Normal(0.0, 1.0), R * P * N * per)}
    # centres: the Cholesky factor of each fit's centre covariance K' K'^T (same law); only
    # for that noise, so that a study with no per-point noise (a per-probing repeatability
    # alone, ``repeatability_um = [0, 0, 0]``) runs with the noise of the points
    L = (
        np.linalg.cholesky(np.matmul(pr.Kp, pr.Kp.transpose(0, 2, 1)))
        if noise == "centres"
        else None
    )
    if study.cmm:
        inputs["cmm"] = MultivariateNormal(np.zeros(3 * N), art.centre_covariance())
    if study.machine_repeatability is not None:
        inputs["repeat"] = IID(Normal(0.0, 1.0), R * P * N * 3)
    if study.setup_u is not None:
        inputs["setup"] = IID(Normal(0.0, 1.0), 3 + 3 * N)
    KpT = np.ascontiguousarray(pr.Kp[: P * N].transpose(0, 2, 1))  # the same for every r
    AS = meas.axis_map * study.repeatability[None, None, :]
    model = _StudyModel(study, pr, L, KpT, AS, per, exact_fit, split)
    return model, inputs, pr


@dataclass(frozen=True, eq=False)
class _StudyModel:
    """The model of :func:`study_model` (module-level: worker processes and Dask get it)."""

    study: ArtefactStudy
    pr: _Prepared
    L: _F | None
    KpT: _F
    AS: _F
    per: int
    exact_fit: bool
    split: bool

    def __call__(
        self,
        probe: _F,
        cmm: _F | None = None,
        repeat: _F | None = None,
        setup: _F | None = None,
    ) -> dict[str, _F]:
        study, pr, L, KpT, AS, per = self.study, self.pr, self.L, self.KpT, self.AS, self.per
        meas = pr.meas
        P, N, k = meas.points.shape[:3]
        R = study.repetitions
        art = study.setup.artefact
        c0 = meas.centres
        m = probe.shape[0]
        z = probe.reshape(m, R * P * N, per)
        if L is not None:
            dc = np.matmul(z.transpose(1, 0, 2), L.transpose(0, 2, 1))  # (RPN, m, 3)
            centres = c0[None, None] + dc.transpose(1, 0, 2).reshape(m, R, P, N, 3)
        elif self.exact_fit:
            eps = np.einsum("pij,mrpnkj->mrpnki", AS, z.reshape(m, R, P, N, k, 3))
            pts = meas.points[None, None] + eps
            fit = fit_sphere(
                pts.reshape(-1, k, 3),
                None if study.free_radius else np.full(m * R * P * N, art.radius),
            )
            centres = fit.geometry.centre.reshape(m, R, P, N, 3)  # type: ignore[union-attr]
        else:
            # the fits' linear maps, one thin product per (pose, ball) over all trials and
            # repetitions: (m R, 3n) @ (3n, 3), in slices that BLAS runs on one thread
            zf = z.reshape(m * R, P * N, per)
            dc = np.empty((m * R, P * N, 3))
            for i in range(P * N):
                _thin_matmul(zf[:, i], KpT[i], dc[:, i])
            centres = c0[None, None] + dc.reshape(m, R, P, N, 3)
        if repeat is not None:
            centres = centres + np.einsum(
                "pij,mrpnj->mrpni", pr.Arep, repeat.reshape(m, R, P, N, 3)
            )
        if setup is not None and study.setup_u is not None:
            dE = setup * study.setup_u  # (m, 3 + 3N)
            dm = -_thin_matmul(dE, pr.J.T, np.empty((m, pr.J.shape[0]))).reshape(m, 1, P, N, 3)
            centres = centres + dm
        cal = pr.cal[None]
        if cmm is not None:
            cal = cal + cmm.reshape(m, N, 3) @ art.rotation.T
        a = analyse(centres, cal, pr.pinv, pr.Jp)
        return a.by_pose() if self.split else a.flat()


#: The most multiply-adds ``m·k·n`` of a product that OpenBLAS (the BLAS of NumPy's and
#: SciPy's wheels) runs on one thread; above it, on all its threads.
_BLAS_ONE_THREAD = 4 * 65536


def _thin_matmul(a: _F, b: _F, out: _F) -> _F:
    """``a @ b`` into ``out`` for a tall ``a`` ``(r, k)`` and a thin ``b`` ``(k, n)``.

    The rows go in slices of a multiple of 64 rows, each at most :data:`_BLAS_ONE_THREAD`
    multiply-adds, so that BLAS runs every slice on one thread whatever its thread
    setting: a block of trials is already the unit of parallelism, and on a loaded
    machine BLAS threads that wait for each other made the artefact's 45 products per
    block 20 times slower than one thread. A slice starts on a multiple of 64 rows, where
    a product of all rows on one thread starts a micro-kernel too, so every row is summed
    as in that product (the same bits with OpenBLAS; tested to rounding). A product of
    all rows on several threads may cut them elsewhere and differ in the last bit.

    Parameters
    ----------
    a : ndarray, shape (r, k)
    b : ndarray, shape (k, n)
    out : ndarray, shape (r, n)
        Written and returned.

    Returns
    -------
    ndarray, shape (r, n)
        ``out``.
    """
    k, n = b.shape
    step = max(64, _BLAS_ONE_THREAD // max(1, k * n) // 64 * 64)
    for i in range(0, a.shape[0], step):
        np.matmul(a[i : i + step], b, out=out[i : i + step])
    return out


def _centre_covariance(study: ArtefactStudy, pr: _Prepared) -> _F:
    """Covariance of the measured centres (R P N 3), mm²: exact, they are linear."""
    P, N = pr.meas.centres.shape[:2]
    R = study.repetitions
    n = R * P * N
    V = np.zeros((n, 3, n, 3))
    blocks = np.matmul(pr.Kp, pr.Kp.transpose(0, 2, 1))  # (n, 3, 3)
    rep = np.matmul(pr.Arep, pr.Arep.transpose(0, 2, 1))  # (P, 3, 3)
    rep = np.broadcast_to(rep[None, :, None], (R, P, N, 3, 3)).reshape(n, 3, 3)
    idx = np.arange(n)
    V[idx, :, idx, :] = blocks + rep
    V = V.reshape(3 * n, 3 * n)
    if study.setup_u is not None:
        JJ = np.tile(pr.J, (R, 1))
        V = V + study.setup_u**2 * JJ @ JJ.T
    return V


def gum_outputs(study: ArtefactStudy, pr: _Prepared | None = None) -> dict[str, Any]:
    """The GUM (first-order) uncertainties of the analysis outputs, mm.

    The centres are linear in the probing noise, the repeatability and the setup
    errors, so their covariance is exact; it and the calibration's covariance are
    propagated through :func:`~mtmc.artefact.analysis.analyse` by
    :func:`mtmc.uncertainty.gum`.

    Returns
    -------
    dict
        Output name to ``(estimate, u)`` arrays, shapes ``(d,)``.
    """
    from mtmc.uncertainty.distributions import MultivariateNormal
    from mtmc.uncertainty.propagation import gum

    pr = _prepare(study) if pr is None else pr
    P, N = pr.meas.centres.shape[:2]
    R = study.repetitions
    art = study.setup.artefact
    c0 = pr.meas.centres
    Vm = _centre_covariance(study, pr)
    inputs: dict[str, Any] = {"dm": MultivariateNormal(np.zeros(Vm.shape[0]), Vm)}
    if study.cmm:
        inputs["cmm"] = MultivariateNormal(np.zeros(3 * N), art.centre_covariance())
    sizes: dict[str, int] = {}

    def model(dm: _F, cmm: _F | None = None) -> _F:
        m = dm.shape[0]
        centres = c0[None, None] + dm.reshape(m, R, P, N, 3)
        cal = pr.cal[None]
        if cmm is not None:
            cal = cal + cmm.reshape(m, N, 3) @ art.rotation.T
        out = analyse(centres, cal, pr.pinv, pr.Jp).flat()
        sizes.update({k: v.shape[1] for k, v in out.items()})
        return np.concatenate([out[k] for k in ANALYSIS_OUTPUTS], axis=1)

    g = gum(model, inputs)
    res: dict[str, Any] = {}
    start = 0
    for name in ANALYSIS_OUTPUTS:
        d = sizes[name]
        res[name] = _gum_slice(g, start, start + d)
        start += d
    return res


@dataclass(frozen=True, eq=False)
class GumOutput:
    """The GUM of one output of :data:`~mtmc.artefact.analysis.ANALYSIS_OUTPUTS`.

    Unpacks as ``(estimate, u)``. Attributes: ``estimate``, ``u``, ``dof``, shapes ``(d,)``
    (mm, mm, effective degrees of freedom), cut from the
    :class:`~mtmc.uncertainty.propagation.GumResult` ``result`` of all outputs at ``start``.
    """

    estimate: _F
    u: _F
    dof: _F
    result: Any
    start: int

    def __iter__(self) -> Any:
        return iter((self.estimate, self.u))

    def __getitem__(self, i: int) -> _F:
        return (self.estimate, self.u)[i]

    def component(self, i: int) -> Any:
        """Component ``i`` as a scalar :class:`~mtmc.uncertainty.propagation.GumResult`."""
        return self.result.component(self.start + i)


def _gum_slice(g: Any, a: int, b: int) -> GumOutput:
    return GumOutput(g.estimate_vector[a:b], g.u_vector[a:b], g.dof_vector[a:b], g, a)


# ----------------------------------------------------------------------------------------
# results


@dataclass(frozen=True, eq=False)
class ArtefactResult:
    """A simulated artefact study: the noise-free values, the MC and the GUM.

    Attributes
    ----------
    study : ArtefactStudy
    measurement : Measurement
        The noise-free probing.
    nominal : Analysis
        The analysis of the noise-free centres (``M = 1``).
    identification : SetupIdentification
        The noise-free identification, its covariance ``J⁺ V J⁺ᵀ`` from the covariance
        ``V`` of ``ΔF`` (the centres' and the calibration's): the GUM of eq. 20.
    mc_mean, mc_u : dict of str to ndarray
        Monte Carlo mean and standard uncertainty of each output of
        :data:`~mtmc.artefact.analysis.ANALYSIS_OUTPUTS` (flattened, mm).
    gum_u : dict of str to ndarray
        GUM standard uncertainties of the same outputs, mm.
    trials : int
    seed : int or None
    gum : dict of str to GumOutput
        The GUM of each output (estimate, ``u``, ``k``, degrees of freedom), empty without
        the GUM.
    samples : dict of str to ndarray
        The Monte Carlo values of the outputs of :data:`SAMPLED_OUTPUTS`, ``(M, d)`` mm,
        in trial order (for histograms and coverage intervals).
    """

    study: ArtefactStudy
    measurement: Measurement
    nominal: Analysis
    identification: Any
    mc_mean: Mapping[str, _F]
    mc_u: Mapping[str, _F]
    gum_u: Mapping[str, _F]
    trials: int
    seed: int | None
    gum: Mapping[str, GumOutput] = field(default_factory=dict)
    samples: Mapping[str, _F] = field(default_factory=dict)

    def pose_labels(self) -> list[dict[str, float]]:
        """Each pose's rotary positions in degrees, keyed ``b_deg``, ``c_deg`` ..."""
        axes = self.study.setup.rotary
        return [
            {
                f"{a.lower()}_deg": float(np.round(np.degrees(v), 12))
                for a, v in zip(axes, row, strict=True)
            }
            for row in self.study.poses
        ]

    def to_json(self) -> dict[str, Any]:
        """The JSON of ``mtmc artefact simulate --json`` (µm)."""

        def eu(name: str, i: int, nominal: _F) -> dict[str, float]:
            out = {
                "estimate": float(self.mc_mean[name][i] / UM),
                "u": float(self.mc_u[name][i] / UM),
                "noise_free": float(nominal.reshape(-1)[i] / UM),
            }
            if name in self.gum_u:
                out["gum_u"] = float(self.gum_u[name][i] / UM)
            return out

        poses = []
        for i, lab in enumerate(self.pose_labels()):
            row: dict[str, Any] = dict(lab)
            row["r_max_um"] = eu("r_max_measured", i, self.nominal.r_max_measured)
            row["r_avg_um"] = eu("r_avg_measured", i, self.nominal.r_avg_measured)
            row["r_max_model_um"] = eu("r_max_model", i, self.nominal.r_max_model)
            row["r_avg_model_um"] = eu("r_avg_model", i, self.nominal.r_avg_model)
            poses.append(row)
        setup = {
            n: eu("setup", j, self.nominal.setup)
            | {"injected": float(self.study.setup_errors[j] / UM)}  # type: ignore[index]
            for j, n in enumerate(self.study.names)
        }
        names = self.study.setup.artefact.names
        vol = self.nominal.volumetric[0]
        return {
            "title": self.study.title,
            "trials": self.trials,
            "seed": self.seed,
            "units": "um",
            "poses": poses,
            "setup_errors": setup,
            "pairs": [f"{names[i]}-{names[j]}" for i, j in pairs(len(names))],
            "volumetric_um": (vol / UM).tolist(),
            "table3_um": (self.nominal.table3[0] / UM).tolist(),
            "volumetric_mean_um": float(np.linalg.norm(vol, axis=2).mean() / UM),
        }


def _joined(res: Any, attr: str, n_poses: int) -> dict[str, _F]:
    """Per-output arrays (flattened, pose-major) from the per-pose outputs of a run."""
    out = {}
    for k in ANALYSIS_OUTPUTS:
        if k in res.outputs:
            out[k] = np.asarray(getattr(res[k], attr), dtype=np.float64).reshape(-1)
        else:
            parts = [getattr(res[f"{k}/{p}"], attr) for p in range(n_poses)]
            out[k] = np.concatenate([np.atleast_1d(np.asarray(v, np.float64)) for v in parts])
    return out


def simulate_artefact(
    study: ArtefactStudy,
    trials: int | None,
    seed: int | None = None,
    *,
    exact_fit: bool = False,
    gum_too: bool = True,
    noise: str = "points",
    **engine: Any,
) -> ArtefactResult:
    """Simulate a study: noise-free chain, Monte Carlo (and the GUM beside it).

    Parameters
    ----------
    study : ArtefactStudy
    trials : int or None
        Monte Carlo trials (None with ``adaptive=True`` among ``engine``).
    seed : int, optional
        The seed (None: fresh entropy, recorded in the result).
    exact_fit : bool
        Converged sphere fits in every trial (slow; see :func:`study_model`).
    gum_too : bool
        Also compute the GUM uncertainties.
    noise : {"points", "centres"}
        How the probing noise is drawn (see :func:`study_model`).
    **engine
        Passed to :func:`mtmc.uncertainty.monte_carlo` (``workers``, ``executor``,
        ``scheduler``, ``progress``, ``block_size``, ``nan_policy``; ``adaptive``, ``ndig``,
        ``p`` and ``kind`` for the adaptive procedure of JCGM 101 §7.9).

    Returns
    -------
    ArtefactResult
    """
    from mtmc.uncertainty.montecarlo import monte_carlo

    model, inputs, pr = study_model(study, exact_fit=exact_fit, split=True, noise=noise)
    P, N = pr.meas.centres.shape[:2]
    R = study.repetitions
    nominal = analyse(pr.meas.centres[None, None].repeat(R, axis=1), pr.cal, pr.pinv, pr.Jp)
    n, s = trials, seed
    kept = [f"{k}/{p}" for k in SAMPLED_OUTPUTS if k != "setup" for p in range(P)]
    res = monte_carlo(model, inputs, trials=n, seed=s, keep=["setup", *kept], **engine)
    mean = _joined(res, "estimate_vector", P)
    u = _joined(res, "u_vector", P)
    samples = {
        k: np.stack([np.asarray(res[f"{k}/{p}"].samples, np.float64) for p in range(P)], axis=1)
        for k in SAMPLED_OUTPUTS
        if k != "setup"
    }
    samples["setup"] = np.asarray(res["setup"].samples, np.float64)
    for v in samples.values():
        v.setflags(write=False)
    gum_u: dict[str, _F] = {}
    gum_all: dict[str, GumOutput] = {}
    Vm = _centre_covariance(study, pr)
    if gum_too:
        gum_all = gum_outputs(study, pr)
        gum_u = {k: v.u for k, v in gum_all.items()}
    dF = (pr.cal[None, None] - pr.meas.centres[None]).repeat(R, axis=0).reshape(-1)
    VF = Vm
    if study.cmm:  # dF = calibrated - measured: the calibration's covariance, every row
        art = study.setup.artefact
        Rb = np.kron(np.eye(N), art.rotation)
        Vc = Rb @ art.centre_covariance() @ Rb.T
        T = np.tile(np.eye(3 * N), (R * P, 1))
        VF = Vm + T @ Vc @ T.T
    ident = identify_setup(np.tile(pr.J, (R, 1)), dF, study.names, VF)
    return ArtefactResult(
        study, pr.meas, nominal, ident, mean, u, gum_u, res.trials, res.seed, gum_all, samples
    )


# ----------------------------------------------------------------------------------------
# the study file


def _error_value(f: Any, name: str, machine: Machine, key: str) -> Any:
    """An error of ``[machine.errors]``, in µm or µrad: a number, or a polynomial's coefficients.

    Each number at most :data:`~mtmc.document.MAX_UM` (µm) or
    :data:`~mtmc.document.MAX_URAD` (µrad) in size, as the verification's errors.
    """
    term = machine.error_term(name)
    unit, limit = (URAD, MAX_URAD) if term.angular else (UM, MAX_UM)
    v = f.data[key]
    if isinstance(v, bool):
        raise f.error(f"expected a number or an array of coefficients, got {v!r}", key)
    if isinstance(v, int | float):
        return f.number(key, low=-limit, high=limit) * unit
    if (
        isinstance(v, list)
        and v
        and all(isinstance(x, int | float) and not isinstance(x, bool) for x in v)
    ):
        if term.kind != "component":
            raise f.error(f"{term.name} is a {term.kind} error, a constant: expected a number", key)
        v = f.numbers(key, len(v), limit=limit, what="polynomial coefficients")
        scale = 1.0 if is_linear(term.axis) else 180.0 / math.pi  # per deg^k -> per rad^k
        coeffs = [c * unit * scale**i for i, c in enumerate(v)]
        return PolynomialFunction(np.array(coeffs))
    raise f.error(
        f"expected a number (um or urad) or an array of polynomial coefficients, got {v!r}",
        key,
    )


def _vec(
    f: Any,
    key: str,
    default: Any = None,
    n: int = 3,
    positive: bool = False,
    limit: float = MAX_MM,
) -> Any:
    """``n`` finite numbers at ``key``, non-negative where asked, each at most ``limit``.

    ``limit`` is in mm, unless the key names another unit (``_deg``, ``_um``).
    """
    if not f.has(key):
        return default
    return np.array(f.numbers(key, n, limit=limit, low=0.0 if positive else None))


def _artefact(top: Any) -> tuple[Artefact, _F]:
    """The ``[artefact]`` table: the artefact, mounted, and the direction of its patches."""
    art_f = top.table("artefact")
    assert art_f is not None
    art_f.only(("file", "shipped", "position", "rotation_deg", "patch_axis"))
    if art_f.has("file") == art_f.has("shipped"):
        raise art_f.error("expected exactly one of file (a path) or shipped (a name)")
    if art_f.has("file"):
        path = top.source.resolve(art_f.text("file"), (*art_f.path, "file"))
        art: Artefact = load_artefact(path)
    else:
        art = shipped_artefact(art_f.text("shipped", choices=SHIPPED))
    pos = _vec(art_f, "position", np.zeros(3))
    rot_deg = _vec(art_f, "rotation_deg", np.zeros(3), limit=MAX_DEG)
    from mtmc.geometry.transforms import matrix_from_euler

    rot = matrix_from_euler(np.radians(rot_deg), "zyx") if np.any(rot_deg) else np.eye(3)
    art = art.mounted(pos, np.asarray(rot).reshape(3, 3))
    axis = _vec(art_f, "patch_axis", np.array([0.0, 0.0, 1.0]))
    if not np.linalg.norm(axis) > 0:
        raise art_f.error("expected a non-zero direction", "patch_axis")
    return art, axis


def _machine(mf: Any) -> Machine:
    """``[machine]`` ``library`` or ``topology``, with the ``probe`` offset."""
    mf.only(("library", "topology", "probe", "errors"))
    if mf.has("library") == mf.has("topology"):
        raise mf.error("expected exactly one of library (a machine name) or topology")
    probe = _vec(mf, "probe", np.zeros(3))
    try:
        if mf.has("library"):
            base = library_machine(mf.text("library"))
            return Machine.from_topology(
                base.topology, tool=probe, pivots=base.pivots, travel=base.travel
            )
        return Machine.from_topology(mf.text("topology"), tool=probe)
    except InputError as exc:
        key = "library" if mf.has("library") else "topology"
        raise mf.error(exc.message, key) from None


def _machine_errors(mf: Any, machine: Machine) -> dict[str, Any]:
    """The optional ``[machine.errors]`` table: the chosen geometric errors, mm and rad."""
    errors: dict[str, Any] = {}
    ef = mf.table("errors", required=False)
    if ef is None:
        return errors
    for key in ef.data:
        try:
            name = machine.error_term(key).name
        except InputError as exc:
            raise ef.error(exc.message, key) from None
        if name in ("EXT", "EYT", "EZT"):
            raise ef.error(f"{name} is the probe's setup error: give it in [setup_errors]", key)
        errors[name] = _error_value(ef, name, machine, key)
    return errors


def _probing(top: Any, machine: Machine, art: Artefact, axis: _F) -> tuple[FiducialSetup, _F, bool]:
    """The optional ``[probing]`` table: the setup, the repeatability (um), ``free``."""
    pf = top.table("probing", required=False)
    cols, rows, size, rep, free = 6, 5, 6.0, np.array(PAPER_REPEATABILITY_UM), False
    if pf is not None:
        pf.only(("columns", "rows", "size_mm", "repeatability_um", "radius"))
        cols = pf.integer("columns", cols, minimum=1, maximum=100)
        rows = pf.integer("rows", rows, minimum=1, maximum=100)
        size = pf.number("size_mm", size, low=0.0, open_low=True)
        rep = _vec(pf, "repeatability_um", rep, positive=True, limit=MAX_UM)
        free = pf.text("radius", "calibrated", choices=("calibrated", "free")) == "free"
    if 0.5 * size * math.sqrt(2.0) >= art.radius:
        raise (pf or top).error(
            f"expected a patch that fits on the ball (radius {art.radius} mm), got {size} mm",
            "size_mm" if pf is not None else None,
        )
    return FiducialSetup(machine, art, axis, patch_offsets(cols, rows, size)), rep, free


def _plan(top: Any, rotary: tuple[str, ...]) -> tuple[_F, int]:
    """The ``[plan]`` table: the rotary poses (rad) and the repetitions."""
    plan = top.table("plan")
    assert plan is not None
    plan.only(("poses_deg", "repetitions"))
    n_rot = len(rotary)
    raw = plan.data.get("poses_deg")
    if isinstance(raw, list):
        check_length(raw, MAX_POSES, lambda msg: plan.error(msg, "poses_deg"))
    if not (
        isinstance(raw, list)
        and raw
        and all(
            isinstance(r, list)
            and len(r) == n_rot
            and all(finite(a) is not None and abs(a) <= MAX_DEG for a in r)
            for r in raw
        )
    ):
        raise plan.error(
            f"expected a list of poses, each [{', '.join(a.lower() for a in rotary)}] in "
            f"degrees, each angle at most {MAX_DEG:g} in size, got {raw!r:.80}",
            "poses_deg",
        )
    poses = np.radians(np.array(raw, dtype=np.float64).reshape(len(raw), n_rot))
    return poses, plan.integer("repetitions", 1, minimum=1, maximum=MAX_REPETITIONS)


def _setup_errors(top: Any, ball_names: tuple[str, ...]) -> _F:
    """The optional ``[setup_errors]`` table: ``ΔE`` (eq. 18), mm (0 where not given)."""
    names = setup_error_names(ball_names)
    E = np.zeros(len(names))
    sf = top.table("setup_errors", required=False)
    if sf is not None:
        sf.only(names)
        for j, nm in enumerate(names):
            E[j] = sf.number(nm, 0.0, low=-MAX_UM, high=MAX_UM) * UM
    return E


def _uncertainty(top: Any) -> tuple[bool, _F | None, float | None]:
    """The optional ``[uncertainty]`` table: ``cmm``, machine repeatability, setup ``u`` (mm)."""
    uf = top.table("uncertainty", required=False)
    cmm, mrep, su = True, None, None
    if uf is not None:
        uf.only(("cmm", "machine_repeatability_um", "setup_errors_um"))
        cmm = uf.flag("cmm", True)
        mrep = _vec(uf, "machine_repeatability_um", None, positive=True, limit=MAX_UM)
        if mrep is not None:
            mrep = mrep * UM
        if uf.has("setup_errors_um"):
            su = uf.number("setup_errors_um", low=0.0, high=MAX_UM, open_low=True) * UM
    return cmm, mrep, su


def read_artefact_study(top: Fields) -> ArtefactStudy:
    """The artefact study of a parsed study file (format: ``docs/artefact.md``).

    One reader per table, in file order: ``[artefact]``, ``[machine]``, ``[probing]``,
    ``[plan]``, ``[setup_errors]``, ``[uncertainty]``; ``[run]`` is the study layer's
    (:meth:`mtmc.study.spec.RunSettings.read`).

    Raises
    ------
    InputError
        On a missing, unknown or malformed field: the message names the file, the line
        and the field, and says what was expected.
    """
    top.only(
        (
            "kind",
            "title",
            "artefact",
            "machine",
            "setup_errors",
            "probing",
            "plan",
            "uncertainty",
            "run",
        )
    )
    top.text("kind", "artefact", choices=("artefact",))  # as ``mtmc run`` reads it
    title = top.text("title", "")
    art, axis = _artefact(top)
    mf = top.table("machine")
    assert mf is not None
    machine = _machine(mf)
    errors = _machine_errors(mf, machine)
    setup, rep, free = _probing(top, machine, art, axis)
    poses, reps = _plan(top, setup.rotary)
    E = _setup_errors(top, art.names)
    cmm, mrep, su = _uncertainty(top)
    return ArtefactStudy(
        title,
        setup,
        poses,
        reps,
        errors,
        E,
        rep * UM,
        free,
        cmm,
        mrep,
        su,
        top.source.file,
    )
