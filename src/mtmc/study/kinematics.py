"""Study kind ``kinematics``: uncertain ISO 230 geometric errors through the forward kinematics.

The file names a machine (a library configuration or a topology string), the commanded
poses, and a distribution for each uncertain error (ISO 230-1 and ISO 230-7 names). The
model is the tool position at every pose (:meth:`mtmc.kinematics.Machine.tool_position`,
batched over the trials), run by :func:`mtmc.monte_carlo` and, coordinate by coordinate,
by :func:`mtmc.gum` (JCGM 100 with sensitivities of the same model), compared by the
JCGM 101 §8 validation.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mtmc.document import MAX_DEG, MAX_MM, MAX_RAD, Fields, check_number
from mtmc.errors import InputError, MtmcError
from mtmc.kinematics.library import library_machine, library_names
from mtmc.kinematics.machine import Machine
from mtmc.kinematics.topology import is_rotary
from mtmc.study.base import ProgressFn, Study
from mtmc.study.observations import input_record
from mtmc.study.options import ADAPTIVE, NAN_POLICY, mc_run_record
from mtmc.study.propagate import read_inputs
from mtmc.study.result import PointField, StudyResult, Table, quantity
from mtmc.study.settings import RunSettings
from mtmc.study.spec import register_kind
from mtmc.uncertainty.distributions import Distribution
from mtmc.uncertainty.montecarlo import monte_carlo
from mtmc.uncertainty.propagation import gum
from mtmc.uncertainty.results import MonteCarloResult

__all__ = ["KinematicsStudy", "tool_positions_model"]


def tool_positions_model(
    machine: Machine, poses: NDArray[np.float64]
) -> Callable[..., NDArray[np.float64]]:
    """The tool positions at several poses as a model of the geometric errors.

    Parameters
    ----------
    machine : Machine
        The machine.
    poses : ndarray, shape (P, n_axes)
        Commanded axis positions (mm, rad), in the order of ``machine.axes``.

    Returns
    -------
    callable
        ``model(**errors)``, each error an array ``(m,)``, returning ``(m, 3P)``: x, y, z
        of pose 1, then pose 2, ... (mm). One batched call of
        :meth:`~mtmc.kinematics.Machine.tool_position` per pose.

    Examples
    --------
    >>> m = library_machine("table-table")
    >>> model = tool_positions_model(m, np.zeros((1, 5)))
    >>> model(EX0C=np.array([0.0, 0.01])).shape
    (2, 3)
    """
    return _ToolPositions(machine, np.asarray(poses, dtype=np.float64))


@dataclass(frozen=True, eq=False)
class _ToolPositions:
    """The model of :func:`tool_positions_model`: module-level, so worker processes get it."""

    machine: Machine
    q: NDArray[np.float64]

    def __call__(self, **errors: Any) -> NDArray[np.float64]:
        q = self.q
        return np.hstack([self.machine.tool_position(q[i], errors) for i in range(q.shape[0])])


@dataclass(frozen=True)
class _Component:
    """Column ``j`` of a model's ``(m, d)`` output (picklable)."""

    model: Callable[..., Any]
    j: int

    def __call__(self, **errors: Any) -> NDArray[np.float64]:
        return np.asarray(self.model(**errors))[:, self.j]


def _component(model: Callable[..., Any], j: int) -> Callable[..., NDArray[np.float64]]:
    return _Component(model, j)


@dataclass(frozen=True)
class KinematicsStudy(Study):
    """A machine, its poses and its uncertain geometric errors (kind ``kinematics``).

    Attributes
    ----------
    machine : Machine
    machine_name : str
        The library name or topology string of the file.
    poses : ndarray, shape (P, n_axes)
        Commanded axis positions, mm and rad.
    errors : dict of str to Distribution
        The uncertain errors (mm, rad).
    poses_given : tuple of tuple of float
        The poses as the file gives them (rotary axes in ``angles``).
    angles : str
        ``"deg"`` or ``"rad"``: the unit of the rotary axes in the file.
    """

    kind = "kinematics"
    run_options = frozenset({ADAPTIVE, NAN_POLICY})
    machine: Machine
    machine_name: str
    poses: NDArray[np.float64]
    errors: dict[str, Distribution]
    poses_given: tuple[tuple[float, ...], ...]
    angles: str

    def execute(self, settings: RunSettings, progress: ProgressFn | None) -> StudyResult:
        """Monte Carlo and GUM of the tool positions (module docstring)."""
        model = tool_positions_model(self.machine, self.poses)
        mc = monte_carlo(
            model, self.errors, seed=settings.seed, progress=progress, **settings.engine
        )
        vals = np.asarray(mc.samples)
        quantities = []
        for i in range(self.poses.shape[0]):
            for j, c in enumerate("xyz"):
                col = 3 * i + j
                g = gum(_component(model, col), self.errors, p=settings.p)
                q_mc = MonteCarloResult(
                    samples=vals[:, col], trials=mc.trials, seed=mc.seed, omitted=mc.omitted
                )
                quantities.append(quantity(f"pose{i + 1}.{c}", "mm", q_mc, g, settings))
        axes = self.machine.axes
        pose_rows = tuple((i + 1, *p) for i, p in enumerate(self.poses_given))
        units = [f"{a} / {self.angles if is_rotary(a) else 'mm'}" for a in axes]
        inputs = tuple(
            {
                **input_record(n, d),
                "unit": "rad" if self.machine.error_term(n).angular else "mm",
            }
            for n, d in self.errors.items()
        )
        nominal = model()  # (1, 3P): the tool positions with every error at zero
        u = mc.u_vector.reshape(-1, 3)
        field = PointField(
            name="u_tool",
            title="Standard uncertainty of the tool position at each pose, √(u²x + u²y + u²z)",
            points=np.asarray(nominal, dtype=np.float64).reshape(-1, 3),
            values=np.sqrt((u**2).sum(axis=1)),
            unit="mm",
            labels=tuple(f"pose {i + 1}" for i in range(self.poses.shape[0])),
        )
        extra = {"machine": {"name": self.machine_name, "topology": str(self.machine.topology)}}
        return self._result(
            settings,
            run=mc_run_record(settings, mc),
            quantities=tuple(quantities),
            tables=(Table("poses", "Commanded poses", ("pose", *units), pose_rows),),
            fields=(field,),
            inputs=inputs,
            extra=extra,
            samples={"tool_positions": mc.samples} if settings.samples else {},
        )


def _pose_limits(machine: Machine, angles: str) -> list[float]:
    """The largest size of each coordinate of a pose: mm, or deg / rad for a rotary axis."""
    rot = MAX_DEG if angles == "deg" else MAX_RAD
    return [rot if is_rotary(a) else MAX_MM for a in machine.axes]


def _check_error_size(et: Fields, name: str, d: Distribution, machine: Machine) -> None:
    """Refuse an error whose mean or standard deviation is beyond a machine's (mm, rad)."""
    angular = bool(machine.error_term(name).angular)
    limit, unit = (MAX_RAD, "rad") if angular else (MAX_MM, "mm")
    mean, std = float(d.mean), float(d.std)
    if abs(mean) > limit or (math.isfinite(std) and std > limit):
        raise et.error(
            f"expected an error of mean and standard deviation at most {limit:g} {unit} in "
            f"size, got {d}",
            name,
        )


@register_kind("kinematics", "ISO 230 geometric errors through a machine's forward kinematics")
def read_kinematics_study(top: Fields) -> KinematicsStudy:
    """Validate a ``kinematics`` study file (see ``docs/study-format.md``)."""
    top.only(("kind", "title", "machine", "poses", "angles", "errors", "run"))
    name = top.text("machine")
    try:
        machine = (
            library_machine(name)
            if name.strip().lower() in library_names()
            else Machine.from_topology(name)
        )
    except MtmcError as exc:
        raise top.error(
            f"{exc.message} (or one of the library: {', '.join(library_names())})", "machine"
        ) from None
    angles = top.text("angles", "deg", choices=("deg", "rad"))
    raw = top.data.get("poses")
    n = machine.n_axes
    if not isinstance(raw, list) or not raw:
        raise top.error(
            f"expected an array of poses, each {n} numbers ({', '.join(machine.axes)})", "poses"
        )
    poses = []
    given = []
    for i, pose in enumerate(raw):
        if not isinstance(pose, list) or len(pose) != n:
            raise top.error(
                f"pose {i + 1}: expected {n} numbers ({', '.join(machine.axes)}), got {pose!r}",
                "poses",
            )

        def err(msg: str, _i: int = i) -> InputError:
            return top.error(f"pose {_i + 1}: {msg}", "poses")

        row = [
            check_number(v, err, -lim, lim)
            for v, lim in zip(pose, _pose_limits(machine, angles), strict=True)
        ]
        given.append(tuple(row))
        poses.append(
            [
                math.radians(v) if angles == "deg" and is_rotary(a) else v
                for a, v in zip(machine.axes, row, strict=True)
            ]
        )
    et = top.table("errors")
    assert et is not None
    errors = read_inputs(et)
    accepted = machine.accepted_error_names
    for e in errors:
        if e not in accepted:
            raise et.error(
                f"{e!r} is not an error of {machine.topology}; "
                f"expected one of {', '.join(accepted)}",
                e,
            )
        _check_error_size(et, e, errors[e], machine)
    return KinematicsStudy(
        title=top.text("title", f"{name}: geometric errors through the kinematics"),
        source=top.source,
        settings=RunSettings.read(top),
        machine=machine,
        machine_name=name,
        poses=np.array(poses, dtype=np.float64),
        errors=errors,
        poses_given=tuple(given),
        angles=angles,
    )
