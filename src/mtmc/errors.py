"""The one exception hierarchy of mtmc.

Every error raised on purpose by mtmc derives from :class:`MtmcError` *and* from the
builtin exception a caller would expect (``ValueError`` for bad input and degenerate
geometry, ``RuntimeError`` for a computation that did not converge), so
``except ValueError`` keeps working. Each error carries where the bad input is as
structured fields (``file``, ``line``, ``column``, ``field``) besides its message, which
says what was expected and what was received; it pickles with those fields, so it
crosses process boundaries intact.

Examples
--------
>>> err = InputError("expected a positive number", file="study.toml", line=12, field="u")
>>> str(err)
'study.toml:12: field u: expected a positive number'
>>> isinstance(err, ValueError), err.line
(True, 12)
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "MtmcError",
    "InputError",
    "ParseError",
    "DistributionError",
    "ExpressionError",
    "DegenerateGeometryError",
    "GraphError",
    "TopologyError",
    "ConvergenceError",
    "IdentifiabilityError",
]


class MtmcError(Exception):
    """Base class of every error mtmc raises on purpose.

    Parameters
    ----------
    message : str
        What went wrong and what was expected, in words.
    file, line, column, field : optional
        Where the bad input is: a file name, a 1-based line and column, and the name of
        the field (a TOML key, a place or transition name, an argument name).
    """

    def __init__(
        self,
        message: str,
        *,
        file: str | None = None,
        line: int | None = None,
        column: int | None = None,
        field: str | None = None,
    ) -> None:
        self.message = message
        self.file = file
        self.line = line
        self.column = column
        self.field = field
        super().__init__(self._format())

    def _format(self) -> str:
        where = ""
        if self.file is not None:
            where = self.file
            if self.line is not None:
                where += f":{self.line}"
                if self.column is not None:
                    where += f":{self.column}"
            where += ": "
        elif self.line is not None:
            where = f"line {self.line}"
            if self.column is not None:
                where += f", column {self.column}"
            where += ": "
        if self.field is not None:
            where += f"field {self.field}: "
        return where + self.message

    def __reduce__(self) -> tuple[Any, ...]:
        kwargs = {
            "file": self.file,
            "line": self.line,
            "column": self.column,
            "field": self.field,
        }
        return (_rebuild, (type(self), self.message, kwargs))

    def __str__(self) -> str:
        return self._format()


def _rebuild(cls: type[MtmcError], message: str, kwargs: dict[str, Any]) -> MtmcError:
    return cls(message, **kwargs)


class InputError(MtmcError, ValueError):
    """A value, file or argument given to mtmc is not what was expected."""


class ParseError(InputError):
    """Text (a study file, a graph file, an expression, a distribution) does not parse."""


class DistributionError(InputError):
    """A distribution is unknown, has the wrong number of parameters, or invalid ones."""


class ExpressionError(ParseError):
    """A model expression is not valid or uses a name or function that is not allowed."""


class DegenerateGeometryError(MtmcError, ValueError):
    """A geometric construction is undefined for the given input.

    Collinear points for a plane, a line parallel to a plane, too few points for a fit,
    a zero-length vector.
    """


class GraphError(InputError):
    """A measurement graph is not valid (not bipartite, cyclic, unmarked input, bad type)."""


class TopologyError(InputError):
    """A machine topology string or configuration is not valid."""


class ConvergenceError(MtmcError, RuntimeError):
    """An iterative computation (adaptive Monte Carlo, a non-linear fit) did not converge."""


class IdentifiabilityError(InputError):
    """Parameters that a measurement cannot separate (a rank-deficient identification).

    ``combinations`` lists, per null direction of the scaled Jacobian, the parameter
    names with their weights.
    """

    def __init__(self, message: str, *, combinations: tuple[str, ...] = (), **where: Any) -> None:
        self.combinations = combinations
        super().__init__(message, **where)


class ConditioningWarning(UserWarning):
    """A construction of the graph is badly conditioned at its nominal configuration.

    Raised as a warning by :func:`mtmc.graph.nominal.check_nominal` (and known there by
    that name); defined here, with the errors, so that the command line can silence it
    without importing the graph package.
    """
