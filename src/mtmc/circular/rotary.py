"""The uncertainty of a rotary-axis test: R-test or ballbar, simulated or measured.

A rotary axis turns through ``n`` positions while the linear axes keep the nominal tool
point at a point ``p`` of the workpiece frame (:func:`~mtmc.circular.simulate.follow_positions`).
To first order in the errors ``β`` (ISO 230-7 location errors of the axes, the set-up's
offset of the sphere, ...), the tool point is displaced by ``J_k β`` at step ``k``, ``J``
the Jacobian of :meth:`mtmc.kinematics.Machine.jacobian` (exact to second order in the
errors: tested against the exact kinematics in ``tests/circular/test_simulate.py``).

**R-test.** Three sensors read the sphere's displacement along x, y, z of the workpiece
frame::

    d_k = (1 + g) ⊙ (J_k β  or  d_k,measured) + ε_k

with ``g`` each sensor's relative gain error and ``ε_k`` the noise of each reading. The
parameters are the range of ``d`` over the steps along each axis (``range_x``,
``range_y``, ``range_z``).

**Ballbar.** A bar of length ``L`` along the direction ``n`` of the workpiece frame, its
table ball at ``p - L n``, reads the change of the distance between its balls::

    r_k = n · J_k β  or  r_k,measured
          - δL - α (t - 20 °C) L + ε_k + ρ_k

the bar's calibration error, expansion, noise and resolution as in the circular test
(:class:`~mtmc.circular.uncertainty.Ballbar`). The parameter is the range of ``r`` over
the steps (``range``). A bar reads one component of the displacement, and any constant
along ``n`` (the set-up across the bar, its length) is one term: the identification
carries it as ``length``, the constant of the readings.

The errors are identified by linear least squares on the first-order design of the
readings, all trials at once; :func:`separable_terms` chooses, where the study does not,
the errors the test can separate, and :attr:`RotaryModel.notes` says in words what it
cannot (the combinations of :func:`mtmc.verification.identifiability`) and that another
test would.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.circular.uncertainty import Ballbar
from mtmc.errors import IdentifiabilityError, InputError
from mtmc.uncertainty import IID, Distribution, Normal, as_distribution
from mtmc.verification.identify import RANK_TOL, identifiability

__all__ = ["RotaryModel", "rotary_model", "separable_terms", "LENGTH"]

_F = NDArray[np.float64]

#: The name of the constant of a ballbar's readings: its length change.
LENGTH = "length"


def _design(jacobian: _F, direction: _F | None) -> _F:
    """The rows of the readings: ``(3 n, p)`` for an R-test, ``(n, p)`` for a ballbar."""
    if direction is None:
        return np.asarray(jacobian.reshape(-1, jacobian.shape[2]), dtype=np.float64)
    return np.asarray(np.einsum("i,nip->np", direction, jacobian), dtype=np.float64)


def separable_terms(
    matrix: npt.ArrayLike, names: Sequence[str], rank_tol: float = RANK_TOL
) -> tuple[str, ...]:
    """The terms of a design a test separates, taken in order: each kept that adds a rank.

    The columns are scaled to unit norm (the units of the terms differ), and a term is
    kept when the smallest singular value of the kept columns with it stays above
    ``rank_tol`` times the largest, the threshold of
    :func:`mtmc.verification.identifiability`.

    Examples
    --------
    >>> import numpy as np
    >>> separable_terms(np.array([[1.0, 2.0, 0.0], [1.0, 2.0, 1.0]]), ["a", "b", "c"])
    ('a', 'c')
    """
    A = np.asarray(matrix, dtype=np.float64)
    if A.ndim != 2 or A.shape[1] != len(names):
        raise InputError(f"expected a design of shape (N, {len(names)}), got {A.shape}")
    norm = np.linalg.norm(A, axis=0)
    keep: list[int] = []
    for j in range(A.shape[1]):
        if norm[j] == 0:
            continue
        cols = A[:, [*keep, j]] / norm[[*keep, j]]
        s = np.linalg.svd(cols, compute_uv=False)
        if s.size == len(keep) + 1 and s[-1] > rank_tol * s[0]:
            keep.append(j)
    return tuple(names[j] for j in keep)


class RotaryModel:
    """The vectorised model of a rotary-axis test (module docstring): ``model(**x) -> (m, d)``.

    Attributes
    ----------
    instrument : {"rtest", "ballbar"}
    symbols : tuple of str
        The test's parameters: ``range_x``, ``range_y``, ``range_z`` (R-test) or ``range``
        (ballbar).
    outputs : tuple of str
        The parameters, then the identified errors (and ``length`` for a ballbar).
    notes : tuple of str
        What the test cannot separate, in words.
    identifiability : Identifiability
        The SVD report of the identified terms' design.
    complex_safe : bool
        False (ranges are extremes).
    """

    complex_safe = False

    def __init__(
        self,
        jacobian: _F,
        names: tuple[str, ...],
        identify: tuple[str, ...],
        *,
        errors: tuple[str, ...] = (),
        direction: _F | None = None,
        length: float = 0.0,
        measured: _F | None = None,
    ) -> None:
        self.jacobian = jacobian
        self.columns = names
        self.error_names = errors
        self.direction = direction
        self.length = float(length)
        self.measured = measured
        self.instrument = "rtest" if direction is None else "ballbar"
        rows = _design(jacobian, direction)
        self.design = rows
        self._truth_t = np.ascontiguousarray(rows[:, [names.index(k) for k in errors]].T)
        ident_cols = rows[:, [names.index(k) for k in identify]]
        ident_names = tuple(identify)
        if direction is not None:
            ident_cols = np.concatenate([ident_cols, np.ones((rows.shape[0], 1))], axis=1)
            ident_names = (*ident_names, LENGTH)
        rep = identifiability(ident_cols, list(ident_names))
        if not rep.ok or ident_cols.shape[0] <= ident_cols.shape[1]:
            raise IdentifiabilityError(
                "the test cannot separate these errors: " + rep.text(), field="identify"
            )
        self.identified = ident_names
        self.identifiability = rep
        self._ident_cols = ident_cols
        self._pinv_t = np.ascontiguousarray(np.linalg.pinv(ident_cols).T)
        self.symbols: tuple[str, ...] = (
            ("range_x", "range_y", "range_z") if direction is None else ("range",)
        )
        self.outputs = (*self.symbols, *ident_names)
        self.notes = _notes(rows, names, ident_names, direction is not None)

    def residual_rms(self, readings: npt.ArrayLike) -> float:
        """``sqrt(Σ r² / (N - p))`` of readings ``(n, 3)`` or ``(n,)`` about the identified model.

        The scatter of a measured test's readings that the identified errors leave: a Type
        A estimate of the noise of each reading.
        """
        r = np.asarray(readings, dtype=np.float64).reshape(-1)
        A = self._ident_cols
        if r.size != A.shape[0]:
            raise InputError(f"expected {A.shape[0]} readings, got {r.size}", field="readings")
        res = r - A @ (self._pinv_t.T @ r)
        return float(np.sqrt(res @ res / (A.shape[0] - A.shape[1])))

    @property
    def steps(self) -> int:
        """The number of rotary positions ``n``."""
        return int(self.jacobian.shape[0])

    def readings(self, **x: Any) -> _F:
        """The readings of the trials: ``(m, n, 3)`` (R-test) or ``(m, n)`` (ballbar), mm."""
        m = int(np.shape(next(iter(x.values())))[0])
        n = self.steps
        if self.measured is None:
            beta = np.stack([np.asarray(x[k], dtype=np.float64) for k in self.error_names], 1)
            r = beta @ self._truth_t
        else:
            r = np.broadcast_to(self.measured.reshape(-1), (m, self.design.shape[0])).copy()
        if self.direction is None:
            e = r.reshape(m, n, 3)
            gain = np.stack([np.asarray(x[f"gain_{a}"], dtype=np.float64) for a in "xyz"], 1)
            e = e * (1.0 + gain[:, None, :])
            if "noise" in x:
                e = e + np.asarray(x["noise"], dtype=np.float64).reshape(m, n, 3)
            return np.asarray(e, dtype=np.float64)
        length = np.asarray(x["length_error"], dtype=np.float64)
        expansion = np.asarray(x["alpha"], dtype=np.float64) * (
            np.asarray(x["temperature"], dtype=np.float64) - 20.0
        )
        r = r - (length + expansion * self.length)[:, None]
        for key in ("noise", "resolution"):
            if key in x:
                r = r + np.asarray(x[key], dtype=np.float64)
        return np.asarray(r, dtype=np.float64)

    def __call__(self, **x: Any) -> _F:
        """The outputs ``(m, d)`` of the trials of ``x``, in the order of :attr:`outputs`."""
        for v in x.values():
            if np.iscomplexobj(v):
                raise TypeError("the rotary-axis model takes real inputs only")
        r = self.readings(**x)
        m = r.shape[0]
        ranges = r.max(axis=1) - r.min(axis=1)
        est = r.reshape(m, -1) @ self._pinv_t
        return np.concatenate([ranges.reshape(m, -1), est], axis=1)


def _notes(
    rows: _F, names: tuple[str, ...], identified: tuple[str, ...], ballbar: bool
) -> tuple[str, ...]:
    """What the test cannot separate: each term left out, and what its readings are.

    A term is left out of the identification when its column adds no rank to the kept
    ones (:func:`separable_terms`): its readings are then a combination ``Σ c_k a_k`` of
    theirs, and the identification reads it as those terms. The coefficients are in the
    terms' own units (mm and rad: ``-80·EY0C`` is 80 mm of EY0C per rad of EA0C, the
    sphere's height).
    """
    cols = {k: rows[:, names.index(k)] for k in names}
    if ballbar:
        cols[LENGTH] = np.ones(rows.shape[0])
    kept = np.stack([cols[k] for k in identified] or [np.zeros(rows.shape[0])], axis=1)
    coef = np.linalg.lstsq(kept, np.stack([cols[k] for k in names], axis=1), rcond=None)[0]
    notes = []
    for j, name in enumerate(names):
        if name in identified:
            continue
        if not np.any(cols[name]):
            notes.append(f"{name}: not seen by this test, it moves no reading")
            continue
        scale = np.linalg.norm(kept, axis=0) / np.linalg.norm(cols[name])
        big = [
            k for k in np.argsort(-np.abs(coef[:, j] * scale)) if abs(coef[k, j]) * scale[k] >= 1e-3
        ]
        terms = " ".join(f"{coef[k, j]:+.4g}·{identified[k]}" for k in big).lstrip("+")
        notes.append(
            f"{name}: not separable, its readings are those of {terms}; the identification "
            "leaves it out and reads it as those terms"
        )
    if ballbar:
        notes.append(
            "a ballbar reads one component of the displacement, and a constant along its "
            f"direction (its length, the set-up along it) is one term, '{LENGTH}'; an R-test, "
            "or a second bar direction or height, separates more"
        )
    return tuple(notes)


def _bar_direction(direction: Any, length: float) -> _F:
    """The bar's unit direction, with its length checked."""
    nvec = np.asarray(direction, dtype=np.float64).reshape(-1)
    if nvec.size != 3 or not np.all(np.isfinite(nvec)) or not np.linalg.norm(nvec) > 0:
        raise InputError(f"expected a direction [x, y, z], got {direction!r}", field="direction")
    if not (np.isfinite(length) and length > 0):
        raise InputError(f"expected the bar's length > 0 mm, got {length!r}", field="length")
    return np.asarray(nvec / np.linalg.norm(nvec), dtype=np.float64)


def _instrument(n: int, ballbar: Ballbar | None, gain: Any, noise: float) -> dict[str, Any]:
    """The instrument's inputs: the R-test's gains and noise, or the bar's."""
    inputs: dict[str, Distribution] = {}
    if ballbar is None:
        for a in "xyz":
            inputs[f"gain_{a}"] = as_distribution(gain, field="gain")
        if noise > 0:
            inputs["noise"] = IID(Normal(0.0, float(noise)), 3 * n)
        return inputs
    return ballbar.inputs(n)


def rotary_model(
    jacobian: npt.ArrayLike,
    errors: Mapping[str, Any] | None = None,
    *,
    names: Sequence[str] | None = None,
    identify: Sequence[str] | None = None,
    measured: npt.ArrayLike | None = None,
    gain: Any = 0.0,
    noise: float = 0.0,
    ballbar: Ballbar | None = None,
    direction: npt.ArrayLike | None = None,
    length: float = 0.0,
) -> tuple[RotaryModel, dict[str, Distribution]]:
    """The model of a rotary-axis test and its inputs (module docstring).

    Parameters
    ----------
    jacobian : array_like, shape (n, 3, p)
        ``∂(displacement)/∂(error)`` at each step (:meth:`mtmc.kinematics.Machine.jacobian`
        at the positions of :func:`~mtmc.circular.simulate.follow_positions`).
    errors : mapping of str to Distribution or number, optional
        A simulated test: errors by their ISO 230-7 names, among ``names``.
    names : sequence of str, optional
        The ``p`` columns of ``jacobian`` (default: the keys of ``errors``).
    identify : sequence of str, optional
        The errors identified (default: :func:`separable_terms` of ``names``).
    measured : array_like, optional
        A measured test instead of ``errors``: the displacements ``(n, 3)`` (R-test) or
        the bar's readings ``(n,)``, mm.
    gain : Distribution or number
        R-test: the relative gain error of each sensor (the same PDF for x, y, z,
        independent).
    noise : float
        R-test: the standard deviation of each reading, mm.
    ballbar : Ballbar, optional
        A ballbar test: the bar (its noise and resolution are its own).
    direction : array_like (3,)
        The bar's direction in the workpiece frame (ballbar only).
    length : float
        The bar's length ``L``, mm (ballbar only).

    Returns
    -------
    model : RotaryModel
    inputs : dict of str to Distribution

    Raises
    ------
    InputError
        On shapes, unknown names, or both or neither of ``errors`` and ``measured``.
    IdentifiabilityError
        When the errors to identify are not separable (the message names the combination).
    """
    J = np.asarray(jacobian, dtype=np.float64)
    if (errors is None) == (measured is None):
        raise InputError("expected either errors (a simulated test) or a measured test")
    cols = tuple(names) if names is not None else tuple(errors or {})
    if J.ndim != 3 or J.shape[1] != 3 or J.shape[2] != len(cols):
        raise InputError(
            f"expected a Jacobian of shape (n, 3, {len(cols)}), got {J.shape}", field="jacobian"
        )
    unknown = [k for k in (errors or {}) if k not in cols]
    if unknown:
        raise InputError(f"unknown error {unknown[0]!r}", field=f"errors.{unknown[0]}")
    nvec = None if ballbar is None else _bar_direction(direction, length)
    rows = _design(J, nvec)
    if identify is None:
        identify = separable_terms(
            rows if nvec is None else np.concatenate([np.ones((rows.shape[0], 1)), rows], 1),
            [LENGTH, *cols] if nvec is not None else list(cols),
        )
        identify = tuple(k for k in identify if k != LENGTH)
    ident = tuple(identify)
    bad = [k for k in ident if k not in cols]
    if bad:
        raise InputError(f"unknown error {bad[0]!r} to identify", field="identify")
    meas = None
    if measured is not None:
        meas = np.asarray(measured, dtype=np.float64)
        want = (J.shape[0], 3) if nvec is None else (J.shape[0],)
        if meas.shape != want or not np.all(np.isfinite(meas)):
            raise InputError(f"expected finite readings of shape {want}", field="measured")
    inputs: dict[str, Distribution] = {
        k: as_distribution(v, field=f"errors.{k}") for k, v in (errors or {}).items()
    }
    inputs |= _instrument(J.shape[0], ballbar, gain, noise)
    model = RotaryModel(
        J,
        cols,
        ident,
        errors=tuple(errors or ()),
        direction=nvec,
        length=length,
        measured=meas,
    )
    return model, inputs
