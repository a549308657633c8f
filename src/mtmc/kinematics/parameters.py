"""A parameter vector for identification: named errors <-> one flat array of coefficients.

An :class:`ErrorModel` fixes which errors of a machine are modelled and how (a constant,
or an error generation function of the axis position); it maps a parameter vector
``theta`` of shape ``(P,)`` (or ``(M, P)``, one vector per trial) to the errors that
:meth:`Machine.tool_position` takes, back again, and gives the Jacobian of the tool
position with respect to ``theta``, the matrix ``J`` of ``Delta p = J Delta theta``
(Wang, Cheung and Kong 2022, eq. 17; the identification of Aguado et al. 2016).

Examples
--------
>>> from mtmc.kinematics import Machine, LegendreSeries
>>> m = Machine.from_topology("XFYZ")
>>> model = ErrorModel(m, {"EXX": LegendreSeries([0.0] * 3, low=0.0, high=1000.0),
...                        "EC0Y": 0.0})
>>> model.parameter_names
('EXX[0]', 'EXX[1]', 'EXX[2]', 'EC0Y')
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.errors import InputError
from mtmc.kinematics.functions import ErrorFunction
from mtmc.kinematics.machine import Machine

__all__ = ["ErrorModel"]


@dataclass(frozen=True)
class ErrorModel:
    """Which errors a machine model carries, as a flat parameter vector.

    Parameters
    ----------
    machine : Machine
        The machine.
    templates : mapping of str to ErrorFunction or float
        Per error name: an error function (its kind and settings are kept, its
        coefficients become parameters; component errors only), or a number for a
        constant error (one parameter).

    Attributes
    ----------
    error_names : tuple of str
        The normalised error names, in the order given.
    parameter_names : tuple of str
        ``NAME[k]`` for the k-th coefficient of a function, ``NAME`` for a constant.
    """

    machine: Machine
    templates: Mapping[str, ErrorFunction | float]
    error_names: tuple[str, ...] = field(init=False)
    parameter_names: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        names: list[str] = []
        params: list[str] = []
        tmpl: dict[str, ErrorFunction | float] = {}
        for raw, t in self.templates.items():
            term = self.machine.error_term(raw)
            if term.name in tmpl:
                raise InputError(f"error {term.name} given twice", field=raw)
            if isinstance(t, ErrorFunction):
                if term.kind != "component":
                    raise InputError(
                        f"{term.name} is a {term.kind} error: expected a number, not a function",
                        field=raw,
                    )
                if t.coefficients.ndim != 1:
                    raise InputError(
                        "expected a template with coefficients of shape (n,)", field=raw
                    )
                params += [f"{term.name}[{k}]" for k in range(t.n_coefficients)]
            else:
                try:
                    t = float(t)
                except (TypeError, ValueError) as exc:
                    raise InputError(
                        f"expected an error function or a number, got {t!r}", field=raw
                    ) from exc
                params.append(term.name)
            tmpl[term.name] = t
            names.append(term.name)
        object.__setattr__(self, "templates", tmpl)
        object.__setattr__(self, "error_names", tuple(names))
        object.__setattr__(self, "parameter_names", tuple(params))

    @property
    def n_parameters(self) -> int:
        """Length ``P`` of the parameter vector."""
        return len(self.parameter_names)

    def _slices(self) -> list[tuple[str, slice]]:
        out = []
        i = 0
        for n in self.error_names:
            t = self.templates[n]
            k = t.n_coefficients if isinstance(t, ErrorFunction) else 1
            out.append((n, slice(i, i + k)))
            i += k
        return out

    def _theta(self, theta: npt.ArrayLike) -> NDArray[np.float64]:
        th = np.asarray(theta, dtype=np.float64)
        if th.ndim not in (1, 2) or th.shape[-1] != self.n_parameters:
            raise InputError(
                f"expected a parameter vector of shape ({self.n_parameters},) or "
                f"(M, {self.n_parameters}), got shape {th.shape}",
                field="theta",
            )
        return th

    def errors(self, theta: npt.ArrayLike) -> dict[str, Any]:
        """The errors described by a parameter vector.

        Parameters
        ----------
        theta : array_like, shape (P,) or (M, P)
            Parameters in the order of :attr:`parameter_names`.

        Returns
        -------
        dict
            Name -> error function (coefficients ``(n,)`` or ``(M, n)``) or constant
            (``()`` or ``(M,)``), ready for :meth:`Machine.tool_position`.

        Raises
        ------
        InputError
            If ``theta`` has the wrong length.
        """
        th = self._theta(theta)
        out: dict[str, Any] = {}
        for n, sl in self._slices():
            t = self.templates[n]
            if isinstance(t, ErrorFunction):
                out[n] = t.with_coefficients(th[..., sl])
            else:
                out[n] = th[..., sl.start]
        return out

    def vector(self, errors: Mapping[str, Any]) -> NDArray[np.float64]:
        """The parameter vector of a set of errors (the inverse of :meth:`errors`).

        Parameters
        ----------
        errors : mapping
            Name -> error function (of the template's kind and size) or number/array;
            every error of the model must be present.

        Returns
        -------
        ndarray, shape (P,) or (M, P)

        Raises
        ------
        InputError
            On a missing or extra error, or a function of another kind or size.
        """
        given = {self.machine.error_term(k).name: v for k, v in errors.items()}
        extra = sorted(set(given) - set(self.error_names))
        if extra:
            raise InputError(f"error {extra[0]} is not in the model", field=extra[0])
        parts: list[NDArray[np.float64]] = []
        for n in self.error_names:
            if n not in given:
                raise InputError(f"no value for error {n} of the model", field=n)
            t, v = self.templates[n], given[n]
            if isinstance(t, ErrorFunction):
                if type(v) is not type(t) or v.n_coefficients != t.n_coefficients:
                    raise InputError(
                        f"expected a {type(t).__name__} with {t.n_coefficients} coefficients",
                        field=n,
                    )
                parts.append(np.asarray(v.coefficients))
            else:
                parts.append(np.asarray(v, dtype=np.float64)[..., None])
        shape = np.broadcast_shapes(*(p.shape[:-1] for p in parts))
        return np.concatenate([np.broadcast_to(p, (*shape, p.shape[-1])) for p in parts], axis=-1)

    def tool_position(
        self, q: npt.ArrayLike, theta: npt.ArrayLike, *, exact: bool = False
    ) -> NDArray[np.float64]:
        """Tool position ``(M, 3)`` with the errors of ``theta``; see :meth:`Machine.tool_position`.

        Parameters
        ----------
        q : array_like, shape (M, n_axes)
            Axis positions.
        theta : array_like, shape (P,) or (M, P)
            Parameters.
        exact : bool
            Exact rotations for the error angles.

        Returns
        -------
        ndarray, shape (M, 3)
        """
        return self.machine.tool_position(q, self.errors(theta), exact=exact)

    def jacobian(
        self, q: npt.ArrayLike, theta: npt.ArrayLike, *, exact: bool = False
    ) -> NDArray[np.float64]:
        """Jacobian of the tool position with respect to the parameters.

        Parameters
        ----------
        q : array_like, shape (M, n_axes)
            Axis positions.
        theta : array_like, shape (P,) or (M, P)
            Parameters at which to take the derivative.
        exact : bool
            Exact rotations for the error angles.

        Returns
        -------
        ndarray, shape (M, 3, P)
            ``d p / d theta``: the analytic Jacobian w.r.t. the error values
            (:meth:`Machine.jacobian`) times the basis of each error function at the
            position of its axis (chain rule; the functions are linear in their
            coefficients).
        """
        qa = self.machine.positions(q)
        errs = self.errors(theta)
        Je = self.machine.jacobian(qa, errs, names=self.error_names, exact=exact)
        m = Je.shape[0]
        J = np.zeros((m, 3, self.n_parameters))
        cols = {ax: i for i, ax in enumerate(self.machine.axes)}
        qb = np.broadcast_to(qa, (m, qa.shape[1]))
        for i, (n, sl) in enumerate(self._slices()):
            t = self.templates[n]
            if isinstance(t, ErrorFunction):
                B = t.basis(qb[:, cols[self.machine.error_term(n).axis]])
                J[:, :, sl] = Je[:, :, i, None] * B[:, None, :]
            else:
                J[:, :, sl.start] = Je[:, :, i]
        return J
