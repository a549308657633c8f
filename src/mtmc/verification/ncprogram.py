"""NC programs that move a machine through a measurement plan, and the measuring time.

A :class:`~mtmc.verification.workspace.MeasurementPlan` becomes

- an ISO (Fanuc-style) G-code program (:func:`iso_program`): ``O`` number, ``G21 G90 G94``,
  one ``G01`` block per move with the feed ``F`` (mm/min), a dwell ``G04 P<ms>`` (or
  ``G04 X<s>``/``U<s>``) at every verification point, ``M00`` between the passes of two
  reflector offsets, ``M30``;
- a Heidenhain conversational program (:func:`heidenhain_program`): ``BEGIN PGM``,
  ``L X+.. Y+.. Z+.. R0 F..``, the dwell cycle ``CYCL DEF 9.0 DWELL TIME`` /
  ``CYCL DEF 9.1 DWELL <s>`` at every point, ``STOP`` between passes, ``END PGM``;
- the points table the tracker software reads beside the program (:func:`points_table`):
  one row per measurement with its index, point, offset and nominal axis positions.

Aguado et al. 2016 (§4.2) name the inputs: the program's head, the letter of the dwell
word and the stop time per point. :func:`estimate_time` gives the measuring time as the
dwell time (points × offsets × dwell) and the travel time of the moves, separately, with
a trapezoidal velocity profile per move (:func:`trapezoid_time`). Files are written
atomically (:mod:`mtmc.io`).

Positions in programs and tables are in mm (linear axes) and degrees (rotary axes), as
controllers read them; the plan holds mm and rad.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.document import Fields, Source, check_number, loads_toml, read_text
from mtmc.errors import InputError, TopologyError
from mtmc.io import write_text_atomic
from mtmc.kinematics.topology import is_linear, is_rotary
from mtmc.verification.workspace import MeasurementPlan, read_workspace

__all__ = [
    "DIALECTS",
    "NCSettings",
    "TimeEstimate",
    "dumps_program",
    "estimate_time",
    "heidenhain_program",
    "iso_program",
    "load_plan_study",
    "loads_plan_study",
    "nc_from_dict",
    "points_table",
    "read_nc",
    "trapezoid_time",
    "write_programs",
]

#: The NC dialects written: ISO/Fanuc G-code and Heidenhain conversational.
DIALECTS = ("iso", "heidenhain")
#: File suffix of each dialect.
SUFFIX = {"iso": ".nc", "heidenhain": ".h"}
_DWELL_WORDS = ("P", "X", "U")
_TIME_MODELS = ("path", "axes")
_PGM_NAME = re.compile(r"^[A-Za-z0-9_]{1,24}$")


def _positive(v: Any, name: str, *, allow_zero: bool = False) -> float:
    return check_number(v, lambda m: InputError(m, field=name), 0.0, open_low=not allow_zero)


@dataclass(frozen=True)
class NCSettings:
    """How the NC program is written and what the machine does at each point.

    Parameters
    ----------
    feed : float
        Programmed feed ``F`` of every move, mm/min, > 0.
    dwell : float
        Stop time at every verification point, s, >= 0 (Aguado et al. 2016: 6 s to let
        the tracker settle and average).
    dialects : tuple of str
        Which programs to write: ``"iso"`` and/or ``"heidenhain"``.
    dwell_word : {"P", "X", "U"}
        ISO dwell address: ``P`` in milliseconds (an integer, Fanuc), ``X`` or ``U`` in
        seconds.
    program : int
        ISO program number (the ``O`` word), 1 to 9999.
    name : str
        Heidenhain program name (``BEGIN PGM <name> MM``): letters, digits, ``_``.
    decimals : int
        Decimals of the coordinates (0 to 6).
    preamble : tuple of str
        Lines written after the program header (work offset, tool call, ...), the "head
        of the CNC program" of Aguado et al. 2016; written as given.
    acceleration : float
        Path acceleration and deceleration for the time estimate, mm/s², > 0.
    time_model : {"path", "axes"}
        ``"path"``: every move at the feed along its straight path; ``"axes"``: every
        axis on its own (feed and acceleration per axis), the slowest axis sets the time
        of the move. See :func:`estimate_time`.
    axis_feed, axis_acceleration : mapping of str to float
        For ``"axes"``: per axis letter, feed (mm/min, or rad/min for a rotary axis) and
        acceleration (mm/s² or rad/s²); an axis left out takes ``feed`` and
        ``acceleration``.
    output : str
        File stem of the written files (``<output>.nc``, ``<output>.h``,
        ``<output>_points.csv``).

    Raises
    ------
    InputError
        On a non-positive feed or acceleration, a negative dwell, an unknown dialect,
        dwell word or time model, a program number or name out of range.
    """

    feed: float
    dwell: float = 6.0
    dialects: tuple[str, ...] = ("iso",)
    dwell_word: str = "P"
    program: int = 1000
    name: str = "MTMCVERIF"
    decimals: int = 3
    preamble: tuple[str, ...] = ()
    acceleration: float = 500.0
    time_model: str = "path"
    axis_feed: Mapping[str, float] = field(default_factory=dict)
    axis_acceleration: Mapping[str, float] = field(default_factory=dict)
    output: str = "verification"

    def __post_init__(self) -> None:
        object.__setattr__(self, "feed", _positive(self.feed, "feed"))
        object.__setattr__(self, "dwell", _positive(self.dwell, "dwell", allow_zero=True))
        object.__setattr__(self, "acceleration", _positive(self.acceleration, "acceleration"))
        dia = (self.dialects,) if isinstance(self.dialects, str) else tuple(self.dialects)
        if not dia or any(d not in DIALECTS for d in dia) or len(set(dia)) != len(dia):
            raise InputError(
                f"expected dialects among {', '.join(DIALECTS)}, each once, got {dia}",
                field="format",
            )
        object.__setattr__(self, "dialects", dia)
        if self.dwell_word not in _DWELL_WORDS:
            raise InputError(
                f"expected the dwell word P (ms), X or U (s), got {self.dwell_word!r}",
                field="dwell_word",
            )
        if (
            isinstance(self.program, bool)
            or not isinstance(self.program, int)
            or not (1 <= self.program <= 9999)
        ):
            raise InputError(
                f"expected a program number 1 to 9999, got {self.program!r}", field="program"
            )
        if not isinstance(self.name, str) or not _PGM_NAME.match(self.name):
            raise InputError(
                f"expected a program name of 1 to 24 letters, digits or _, got {self.name!r}",
                field="name",
            )
        if isinstance(self.decimals, bool) or self.decimals not in range(7):
            raise InputError(f"expected 0 to 6 decimals, got {self.decimals!r}", field="decimals")
        if self.time_model not in _TIME_MODELS:
            raise InputError(
                f"expected time_model 'path' or 'axes', got {self.time_model!r}",
                field="time_model",
            )
        for attr in ("axis_feed", "axis_acceleration"):
            vals = {str(k): _positive(v, f"{attr}.{k}") for k, v in getattr(self, attr).items()}
            object.__setattr__(self, attr, vals)
        object.__setattr__(self, "preamble", tuple(str(s) for s in self.preamble))
        if not isinstance(self.output, str) or not self.output or "/" in self.output:
            raise InputError(f"expected a file stem, got {self.output!r}", field="output")


def _display(plan: MeasurementPlan) -> NDArray[np.float64]:
    """Commanded positions in controller units: mm, and degrees for rotary axes."""
    scale = np.array([180.0 / np.pi if is_rotary(a) else 1.0 for a in plan.axes])
    out: NDArray[np.float64] = np.asarray(plan.moves) * scale
    return out


def _comment_iso(text: str) -> str:
    # Fanuc comments: no parentheses inside, upper case
    return "(" + text.upper().replace("(", "[").replace(")", "]") + ")"


def _walk(
    plan: MeasurementPlan, fmt: Callable[[float], str]
) -> Iterator[tuple[str, int, list[str]]]:
    """The program's events in order: a pass starts, a move, a dwell at a point.

    Yields ``("pass", k, [])`` when the pass of offset ``k`` starts, ``("move", i,
    words)`` with the axis words (``"X12.500"``) of the axes whose written value changes
    (all of them for the first move; a move that changes none is left out), and
    ``("dwell", point, [])`` after a move that reaches a verification point.
    """
    pos = _display(plan)
    last: list[str] | None = None
    pass_ = -1
    for i in range(pos.shape[0]):
        k = int(plan.move_offset[i])
        if k != pass_:
            yield "pass", k, []
            pass_ = k
        text = [fmt(v) for v in pos[i]]
        words = [
            f"{a}{t}"
            for j, (a, t) in enumerate(zip(plan.axes, text, strict=True))
            if last is None or t != last[j]
        ]
        last = text
        if words:
            yield "move", i, words
        if plan.move_point[i] >= 0:
            yield "dwell", int(plan.move_point[i]), []


def iso_program(plan: MeasurementPlan, settings: NCSettings) -> str:
    """The ISO (Fanuc-style) G-code program of a plan.

    Structure::

        %
        O1000 (MTMC VOLUMETRIC VERIFICATION)
        (... header comments: axes, units, points, offsets, dwell ...)
        G21 G90 G94
        <preamble>
        (OFFSET 1 OF 1: REFLECTOR X0.000 Y0.000 Z0.000 MM)
        G01 X0.000 Y0.000 Z0.000 F2000.0
        G04 P6000
        G01 Z400.000
        G04 P6000
        ...
        M30
        %

    ``G21`` metric, ``G90`` absolute, ``G94`` feed per minute. Every move is a ``G01``
    block with the axes that change (all of them in the first block); the feed is
    written once (modal). A dwell follows each move that reaches a verification point,
    none follows an overshoot (pre-positioning) move. Between the passes of two offsets
    an ``M00`` stops the program for the reflector to be moved.

    Parameters
    ----------
    plan : MeasurementPlan
        Points and moves.
    settings : NCSettings
        Feed, dwell, dwell word, program number, decimals, preamble.

    Returns
    -------
    str
        The program, one block per line (LF line ends).
    """
    nd = settings.decimals
    out = [
        "%",
        f"O{settings.program:04d} " + _comment_iso("mtmc volumetric verification"),
        _comment_iso(f"axes {' '.join(plan.axes)}, units mm" + _deg_note(plan)),
        _comment_iso(
            f"{plan.n_points} points, {plan.n_offsets} offsets, {plan.n_measurements} "
            f"measurements, {plan.kind}"
        ),
        _comment_iso(f"dwell {settings.dwell:g} s per point, feed {settings.feed:g} mm/min"),
        "G21 G90 G94",
        *settings.preamble,
    ]
    dwell = (
        f"G04 P{round(settings.dwell * 1000.0)}"
        if settings.dwell_word == "P"
        else f"G04 {settings.dwell_word}{settings.dwell:.3f}"
    )
    first = True
    for kind, k, words in _walk(plan, lambda v: f"{v:.{nd}f}"):
        if kind == "pass":
            if k > 0:
                out.append("M00 " + _comment_iso(f"move the reflector to offset {k + 1}"))
            o = [f"{v:.{nd}f}" for v in plan.offsets[k]]
            out.append(
                _comment_iso(
                    f"offset {k + 1} of {plan.n_offsets}: reflector X{o[0]} Y{o[1]} Z{o[2]} mm"
                )
            )
        elif kind == "move":
            out.append("G01 " + " ".join(words) + (f" F{settings.feed:.1f}" if first else ""))
            first = False
        elif settings.dwell > 0:
            out.append(dwell)
    out += ["M30", "%"]
    return "\n".join(out) + "\n"


def _deg_note(plan: MeasurementPlan) -> str:
    rot = [a for a in plan.axes if is_rotary(a)]
    return f" ({' '.join(rot)} in deg)" if rot else ""


def _hh(v: float, nd: int) -> str:
    s = f"{v:+.{nd}f}"
    return "+0" + s[2:] if s.startswith("-") and float(s) == 0.0 else s


def heidenhain_program(plan: MeasurementPlan, settings: NCSettings) -> str:
    """The Heidenhain conversational program of a plan.

    Structure (block numbers from 0)::

        0 BEGIN PGM MTMCVERIF MM
        1 ; MTMC VOLUMETRIC VERIFICATION
        ...
        5 L X+0.000 Y+0.000 Z+0.000 R0 F2000
        6 CYCL DEF 9.0 DWELL TIME
        7 CYCL DEF 9.1 DWELL 6
        8 L Z+400.000 R0 F2000
        ...
        n END PGM MTMCVERIF MM

    Every move is an ``L`` block (straight line, no radius compensation ``R0``) with the
    axes that change; cycle 9 (dwell time, active as soon as it is defined) follows each
    move that reaches a verification point; ``STOP`` between the passes of two offsets.

    Parameters
    ----------
    plan : MeasurementPlan
        Points and moves.
    settings : NCSettings
        Feed, dwell, program name, decimals, preamble.

    Returns
    -------
    str
        The program, one block per line (LF line ends).
    """
    nd = settings.decimals
    body = [
        f"BEGIN PGM {settings.name} MM",
        "; MTMC VOLUMETRIC VERIFICATION",
        f"; AXES {' '.join(plan.axes)}, UNITS MM{_deg_note(plan).upper()}",
        f"; {plan.n_points} POINTS, {plan.n_offsets} OFFSETS, {plan.n_measurements} "
        f"MEASUREMENTS, {plan.kind.upper()}",
        f"; DWELL {settings.dwell:g} S PER POINT, FEED {settings.feed:g} MM/MIN",
        *settings.preamble,
    ]
    feed = f"F{settings.feed:g}"
    for kind, k, words in _walk(plan, lambda v: _hh(v, nd)):
        if kind == "pass":
            if k > 0:
                body += [f"; MOVE THE REFLECTOR TO OFFSET {k + 1}", "STOP"]
            o = [_hh(v, nd) for v in plan.offsets[k]]
            body.append(
                f"; OFFSET {k + 1} OF {plan.n_offsets}: REFLECTOR X{o[0]} Y{o[1]} Z{o[2]} MM"
            )
        elif kind == "move":
            body.append("L " + " ".join(words) + f" R0 {feed}")
        elif settings.dwell > 0:
            body += ["CYCL DEF 9.0 DWELL TIME", f"CYCL DEF 9.1 DWELL {settings.dwell:g}"]
    body.append(f"END PGM {settings.name} MM")
    return "\n".join(f"{n} {line}" for n, line in enumerate(body)) + "\n"


def dumps_program(plan: MeasurementPlan, settings: NCSettings, dialect: str) -> str:
    """The program of one dialect (``"iso"`` or ``"heidenhain"``).

    Raises
    ------
    InputError
        On an unknown dialect.
    """
    if dialect == "iso":
        return iso_program(plan, settings)
    if dialect == "heidenhain":
        return heidenhain_program(plan, settings)
    raise InputError(
        f"expected a dialect among {', '.join(DIALECTS)}, got {dialect!r}", field="format"
    )


def points_table(plan: MeasurementPlan, settings: NCSettings | None = None) -> str:
    """The table of measurements the tracker software reads beside the program (CSV).

    Comment lines (``#``) say what the columns are; then a header row and one row per
    measurement in measuring order: ``measurement`` (1-based index in the program),
    ``point`` (1-based index of the verification point), ``offset`` (1-based index of the
    reflector offset), the nominal axis positions (mm; deg for a rotary axis) and the
    reflector offset ``offset_x, offset_y, offset_z`` (mm).

    Parameters
    ----------
    plan : MeasurementPlan
    settings : NCSettings, optional
        For the decimals and the program names in the comments.

    Returns
    -------
    str
        The CSV text.

    Examples
    --------
    >>> plan = MeasurementPlan(("X", "Y"), [[0.0, 0.0], [10.0, 0.0]])
    >>> print(points_table(plan))  # doctest: +NORMALIZE_WHITESPACE
    # mtmc verification points: 2 points x 1 offsets = 2 measurements (points)
    # axes X Y: nominal axis positions, mm; offset_x, offset_y, offset_z: reflector offset, mm
    measurement,point,offset,X,Y,offset_x,offset_y,offset_z
    1,1,1,0.000,0.000,0.000,0.000,0.000
    2,2,1,10.000,0.000,0.000,0.000,0.000
    """
    nd = settings.decimals if settings is not None else 3
    scale = np.array([180.0 / np.pi if is_rotary(a) else 1.0 for a in plan.axes])
    q = plan.measurement_positions * scale
    off = plan.measurement_offsets
    n = plan.n_points
    lines = [
        f"# mtmc verification points: {plan.n_points} points x {plan.n_offsets} offsets = "
        f"{plan.n_measurements} measurements ({plan.kind})",
        f"# axes {' '.join(plan.axes)}: nominal axis positions, mm{_deg_note(plan)}; "
        "offset_x, offset_y, offset_z: reflector offset, mm",
    ]
    if settings is not None:
        progs = ", ".join(f"{settings.output}{SUFFIX[d]}" for d in settings.dialects)
        lines.append(
            f"# programs: {progs} (O{settings.program:04d} / {settings.name}); dwell "
            f"{settings.dwell:g} s per measurement"
        )
    if plan.seed is not None:
        lines.append(f"# cloud seed: {plan.seed}")
    lines.append(
        ",".join(["measurement", "point", "offset", *plan.axes, "offset_x", "offset_y", "offset_z"])
    )
    for m in range(q.shape[0]):
        vals = [f"{v:.{nd}f}" for v in (*q[m], *off[m])]
        lines.append(",".join([str(m + 1), str(m % n + 1), str(m // n + 1), *vals]))
    return "\n".join(lines) + "\n"


def write_programs(
    plan: MeasurementPlan, settings: NCSettings, folder: str | Path
) -> dict[str, Path]:
    """Write the programs of ``settings.dialects`` and the points table, atomically.

    Parameters
    ----------
    plan : MeasurementPlan
    settings : NCSettings
    folder : path-like
        An existing folder.

    Returns
    -------
    dict
        ``{"iso": path, "heidenhain": path, "points": path}`` (the dialects written).

    Raises
    ------
    FileNotFoundError
        If the folder does not exist.
    """
    d = Path(folder)
    out: dict[str, Path] = {}
    for dialect in settings.dialects:
        out[dialect] = write_text_atomic(
            d / f"{settings.output}{SUFFIX[dialect]}", dumps_program(plan, settings, dialect)
        )
    out["points"] = write_text_atomic(
        d / f"{settings.output}_points.csv", points_table(plan, settings)
    )
    return out


# ---------------------------------------------------------------------------------------
# Measuring time


def trapezoid_time(
    distance: npt.ArrayLike, speed: npt.ArrayLike, acceleration: npt.ArrayLike
) -> NDArray[np.float64]:
    """Time of a point-to-point move with a trapezoidal velocity profile.

    Accelerating at ``a`` from rest to the speed ``v``, cruising, decelerating at ``a``
    to rest: a move of length ``d >= v**2 / a`` takes ``t = d / v + v / a``; a shorter
    one never reaches ``v`` (a triangular profile) and takes ``t = 2 sqrt(d / a)``. The
    two agree at ``d = v**2 / a``.

    Parameters
    ----------
    distance : array_like
        Move lengths ``d`` >= 0 (mm or rad).
    speed : array_like
        Maximum speeds ``v`` > 0 (per second).
    acceleration : array_like
        Accelerations ``a`` > 0 (per second squared).

    Returns
    -------
    ndarray
        Times in s, broadcast shape of the inputs.

    Examples
    --------
    >>> float(trapezoid_time(500.0, 50.0, 500.0))   # 500/50 + 50/500
    10.1
    >>> float(trapezoid_time(1.0, 50.0, 500.0))     # 2 sqrt(1/500)
    0.0894427190999916
    """
    d = np.asarray(distance, dtype=np.float64)
    v = np.asarray(speed, dtype=np.float64)
    a = np.asarray(acceleration, dtype=np.float64)
    if np.any(d < 0) or np.any(~(v > 0)) or np.any(~(a > 0)):
        raise InputError("expected distance >= 0, speed > 0 and acceleration > 0", field="move")
    return np.where(d >= v * v / a, d / v + v / a, 2.0 * np.sqrt(d / a))


@dataclass(frozen=True)
class TimeEstimate:
    """The measuring time of a plan: dwell and travel apart.

    Attributes
    ----------
    n_measurements : int
        Points × offsets.
    n_moves : int
        Moves timed (the first positioning move, from wherever the machine is, is not).
    dwell_s : float
        ``n_measurements × dwell``.
    travel_s : float
        Sum of the move times.
    total_s : float
        ``dwell_s + travel_s`` (the operator's reflector changes at the ``stops`` are
        not included).
    path_length_mm : float
        Length of the tool path over the linear axes.
    stops : int
        Program stops for reflector changes (offsets − 1).
    model : str
        ``"path"`` or ``"axes"``.
    """

    n_measurements: int
    n_moves: int
    dwell_s: float
    travel_s: float
    total_s: float
    path_length_mm: float
    stops: int
    model: str

    def to_dict(self) -> dict[str, Any]:
        """The estimate as a plain dict (seconds, and hours for the total)."""
        return {
            "measurements": self.n_measurements,
            "moves": self.n_moves,
            "dwell_s": self.dwell_s,
            "travel_s": self.travel_s,
            "total_s": self.total_s,
            "total_h": self.total_s / 3600.0,
            "path_length_mm": self.path_length_mm,
            "stops": self.stops,
            "model": self.model,
        }


def estimate_time(plan: MeasurementPlan, settings: NCSettings) -> TimeEstimate:
    """Estimate the measuring time of a plan: dwell time plus travel time.

    Dwell: ``T_dwell = n k t_dwell`` (``n`` points, ``k`` offsets). Travel: the sum over
    the moves of the trapezoidal move time (:func:`trapezoid_time`), the first move (from
    wherever the machine stands) left out:

    - ``time_model = "path"`` (interpolated ``G01`` moves): the tool moves along the
      straight path of length ``L = ||Δq||`` over the linear axes at the programmed feed
      ``v = F / 60`` with the path acceleration ``a``: ``t = L/v + v/a`` or
      ``2 sqrt(L/a)``. Rotary axes may not move in this model.
    - ``time_model = "axes"`` (independent axes): axis ``j`` moves ``|Δq_j|`` with its
      own speed ``v_j`` and acceleration ``a_j``; the move takes
      ``max_j t(|Δq_j|, v_j, a_j)``, the slowest axis. A rotary axis needs its own
      feed (rad/min) and acceleration (rad/s²).

    Neither model includes the controller's look-ahead, jerk limits, the settling of the
    servo loop or the operator's reflector changes: the travel time is a lower bound of
    the time a real machine takes for the same moves.

    Parameters
    ----------
    plan : MeasurementPlan
    settings : NCSettings
        Feed, dwell, acceleration, time model and the per-axis values.

    Returns
    -------
    TimeEstimate

    Raises
    ------
    InputError
        With the ``"path"`` model when a rotary axis moves; with the ``"axes"`` model when
        a rotary axis has no feed or acceleration of its own; on a per-axis value for an
        axis the plan does not have.

    Examples
    --------
    >>> from mtmc.verification.workspace import mesh
    >>> plan = MeasurementPlan(("X", "Y", "Z"), mesh([0, 0, 0], [2500, 1500, 1200], step=100))
    >>> est = estimate_time(plan, NCSettings(feed=2000.0, dwell=6.0))
    >>> est.n_measurements, round(est.dwell_s / 3600.0, 2)
    (5408, 9.01)
    """
    q = np.asarray(plan.moves)
    dq = np.abs(np.diff(q, axis=0))
    linear = np.array([is_linear(a) for a in plan.axes])
    length = float(np.sum(np.linalg.norm(dq[:, linear], axis=1))) if dq.size else 0.0
    for attr in ("axis_feed", "axis_acceleration"):
        for k in getattr(settings, attr):
            if k not in plan.axes:
                raise InputError(
                    f"axis {k} is not an axis of the plan ({' '.join(plan.axes)})",
                    field=f"{attr}.{k}",
                )
    if settings.time_model == "path":
        moves_rot = ~linear & (np.any(dq > 0, axis=0) if dq.size else False)
        moving = np.flatnonzero(moves_rot)
        if moving.size:
            raise InputError(
                f"the 'path' time model is for linear axes: rotary axis "
                f"{plan.axes[moving[0]]} moves; use time_model = 'axes' with a feed and an "
                "acceleration for it",
                field="time_model",
            )
        seg = np.linalg.norm(dq[:, linear], axis=1)
        t = trapezoid_time(seg, settings.feed / 60.0, settings.acceleration)
    else:
        for a in plan.axes:
            for attr in ("axis_feed", "axis_acceleration"):
                if is_rotary(a) and a not in getattr(settings, attr):
                    raise InputError(
                        f"rotary axis {a} needs its own {attr.split('_')[1]} in the 'axes' "
                        "model (the path feed is in mm/min)",
                        field=f"{attr}.{a}",
                    )
        v = np.array([settings.axis_feed.get(a, settings.feed) / 60.0 for a in plan.axes])
        acc = np.array(
            [settings.axis_acceleration.get(a, settings.acceleration) for a in plan.axes]
        )
        t = trapezoid_time(dq, v, acc).max(axis=1) if dq.size else np.zeros(0)
    travel = float(np.sum(t))
    dwell = plan.n_measurements * settings.dwell
    return TimeEstimate(
        n_measurements=plan.n_measurements,
        n_moves=int(dq.shape[0]),
        dwell_s=dwell,
        travel_s=travel,
        total_s=dwell + travel,
        path_length_mm=length,
        stops=plan.n_offsets - 1,
        model=settings.time_model,
    )


# ---------------------------------------------------------------------------------------
# The [nc] table of a study file

_NC_KEYS = (
    "format",
    "feed",
    "dwell",
    "dwell_word",
    "program",
    "name",
    "decimals",
    "preamble",
    "acceleration",
    "time_model",
    "axis_feed",
    "axis_acceleration",
    "output",
)


def _axis_table(nc: Fields, key: str, axes: Sequence[str] | None) -> dict[str, float]:
    t = nc.table(key, required=False)
    if t is None:
        return {}
    out = {}
    for a in t.data:
        if axes is not None and a not in axes:
            raise t.error(f"axis {a} is not an axis of the workspace ({' '.join(axes)})", a)
        scale = math.pi / 180.0 if is_rotary(a) else 1.0
        out[a] = t.number(a, low=0.0, open_low=True) * scale
    return out


def read_nc(nc: Fields, axes: Sequence[str] | None = None) -> NCSettings:
    """Read an ``[nc]`` table of a study file into :class:`NCSettings`.

    The table (``docs/verification-planning.md``)::

        [nc]
        format = ["iso", "heidenhain"]   # or one of them as a string
        feed = 2000              # mm/min
        dwell = 6                # s per point
        dwell_word = "P"         # ISO: "P" (ms), "X" or "U" (s)
        program = 1000           # ISO O-number
        name = "MTMCVERIF"       # Heidenhain program name
        decimals = 3
        preamble = ["G54"]       # lines after the program header
        acceleration = 500       # mm/s², for the time estimate
        time_model = "path"      # or "axes"
        output = "verification"  # file stem
        [nc.axis_feed]           # "axes" model: mm/min (deg/min for rotary axes)
        X = 20000
        [nc.axis_acceleration]   # mm/s² (deg/s²)
        X = 1000

    Parameters
    ----------
    nc : mtmc.document.Fields
        The table.
    axes : sequence of str, optional
        The plan's axes, to check the per-axis tables.

    Returns
    -------
    NCSettings

    Raises
    ------
    InputError
        Naming the file, the line and the field.
    """
    nc.only(_NC_KEYS)
    fmt = nc.data.get("format", "iso")
    dialects = (fmt,) if isinstance(fmt, str) else nc.texts("format")
    for d in dialects:
        if d not in DIALECTS:
            raise nc.error(f"expected a format among {', '.join(DIALECTS)}, got {d!r}", "format")
    if len(set(dialects)) != len(dialects):
        raise nc.error(f"a format is named twice in {list(dialects)}", "format")
    preamble = nc.data.get("preamble", [])
    if isinstance(preamble, str):
        preamble = [preamble]
    if not isinstance(preamble, list) or not all(isinstance(s, str) for s in preamble):
        raise nc.error(f"expected an array of strings, got {preamble!r}", "preamble")
    name = nc.text("name", "MTMCVERIF")
    if not _PGM_NAME.match(name):
        raise nc.error(f"expected 1 to 24 letters, digits or _, got {name!r}", "name")
    output = nc.text("output", "verification")
    if not output or "/" in output or "\\" in output:
        raise nc.error(f"expected a file stem without a folder, got {output!r}", "output")
    kw: dict[str, Any] = {
        "feed": nc.number("feed", low=0.0, open_low=True),
        "dwell": nc.number("dwell", 6.0, low=0.0),
        "dialects": tuple(dialects),
        "dwell_word": nc.text("dwell_word", "P", choices=_DWELL_WORDS),
        "name": name,
        "decimals": nc.integer("decimals", 3, minimum=0),
        "preamble": tuple(preamble),
        "acceleration": nc.number("acceleration", 500.0, low=0.0, open_low=True),
        "time_model": nc.text("time_model", "path", choices=_TIME_MODELS),
        "axis_feed": _axis_table(nc, "axis_feed", axes),
        "axis_acceleration": _axis_table(nc, "axis_acceleration", axes),
        "output": output,
    }
    program = nc.integer("program", 1000, minimum=1)
    if program > 9999:
        raise nc.error(f"expected a program number 1 to 9999, got {program}", "program")
    if kw["decimals"] > 6:
        raise nc.error(f"expected 0 to 6 decimals, got {kw['decimals']}", "decimals")
    return NCSettings(program=program, **kw)


def nc_from_dict(
    data: dict[str, Any],
    file: str = "<study>",
    *,
    text: str | None = None,
    axes: Sequence[str] | None = None,
) -> NCSettings:
    """Read an ``[nc]`` table given as a dict (see :func:`read_nc`).

    Parameters
    ----------
    data : dict
        The parsed TOML of the whole study (with an ``nc`` table).
    file : str
        The file name for the messages.
    text : str, optional
        The TOML text, for the line numbers in the messages.
    axes : sequence of str, optional
        As :func:`read_nc`.

    Returns
    -------
    NCSettings

    Raises
    ------
    InputError
        As :func:`read_nc`; if there is no ``[nc]`` table.
    """
    top = Fields(Source.from_text(text or "", file), data)
    nc = top.table("nc")
    assert nc is not None
    return read_nc(nc, axes)


# ---------------------------------------------------------------------------------------
# A planning study: machine, [workspace] and [nc]


def _machine_axes(top: Fields) -> tuple[str, ...] | None:
    """The axes of the study's ``machine`` (a library name or a topology), if it has one."""
    from mtmc.kinematics.library import library_machine, library_names
    from mtmc.kinematics.topology import parse_topology

    if "machine" not in top.data:
        return None
    raw = top.data["machine"]
    if isinstance(raw, dict):
        sub = top.table("machine")
        assert sub is not None
        if "topology" not in raw:
            raise sub.error('expected the machine\'s topology, e.g. topology = "XFYZ"', "topology")
        spec, where, key = sub.text("topology"), sub, "topology"
    else:
        spec, where, key = top.text("machine"), top, "machine"
    if spec.strip().lower() in library_names():
        return library_machine(spec).axes
    try:
        return parse_topology(spec).axes
    except TopologyError as exc:
        raise where.error(
            f"{exc.message}; nor is it a library name ({', '.join(library_names())})", key
        ) from None


def loads_plan_study(text: str, file: str = "<study>") -> tuple[MeasurementPlan, NCSettings]:
    """Read the plan of a verification study from TOML text.

    Reads the study's ``machine`` (optional: a library name or a topology string such as
    ``"XFYZ"``, or a table with ``topology``; it fixes the axes and their order), its
    ``[workspace]`` table (:func:`~mtmc.verification.workspace.read_workspace`) and its
    ``[nc]`` table (:func:`read_nc`). Other keys of the study are left to the study's own
    loader.

    Parameters
    ----------
    text : str
        The TOML text.
    file : str
        The file name for the messages.

    Returns
    -------
    tuple of (MeasurementPlan, NCSettings)

    Raises
    ------
    ParseError
        If the text is not TOML (with line and column).
    InputError
        On any wrong field, naming the file, the line and the field.
    """
    top = loads_toml(text, file)
    axes = _machine_axes(top)
    ws = top.table("workspace")
    nc = top.table("nc")
    assert ws is not None
    assert nc is not None
    plan = read_workspace(ws, axes)
    return plan, read_nc(nc, plan.axes)


def load_plan_study(path: str | Path) -> tuple[MeasurementPlan, NCSettings]:
    """Read the plan of a verification study file (see :func:`loads_plan_study`).

    Raises
    ------
    InputError
        If the file cannot be read, or as :func:`loads_plan_study`.
    """
    return loads_plan_study(read_text(path, "study file"), str(path))
