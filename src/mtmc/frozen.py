"""Read-only arrays and mappings for the frozen results and tables of the package.

A frozen dataclass stops rebinding its fields, not writing into them: an array field can
still be changed in place (``r.cov[0, 0] = 0``) and a dict field can gain keys. The results
therefore hold arrays with the ``writeable`` flag cleared and read-only mappings that
pickle (:class:`FrozenMapping`), made here, copied at the boundary so that no caller's
object is frozen or shared. (Module-level tables, never pickled, are
:class:`types.MappingProxyType`.)

Examples
--------
>>> import numpy as np
>>> a = np.zeros(2)
>>> b = frozen_array(a)
>>> b is a, b.flags.writeable, a.flags.writeable
(False, False, True)
>>> m = frozen_mapping({"x": 1.0})
>>> m["y"] = 2.0
Traceback (most recent call last):
...
TypeError: 'FrozenMapping' object does not support item assignment
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from typing import Any, TypeVar

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

__all__ = [
    "FrozenMapping",
    "frozen_array",
    "frozen_floats",
    "frozen_mapping",
    "frozen_value",
    "read_only",
]

K = TypeVar("K")
V = TypeVar("V")


def frozen_array(a: npt.ArrayLike) -> NDArray[Any]:
    """A read-only copy of ``a``.

    Parameters
    ----------
    a : array_like
        Any array or nested sequence.

    Returns
    -------
    ndarray
        A new array, not sharing memory with ``a``, with ``flags.writeable`` False.
    """
    out: NDArray[Any] = np.array(a, copy=True)
    out.setflags(write=False)
    return out


def frozen_floats(a: Any) -> NDArray[np.float64]:
    """A read-only float64 copy of ``a`` (as :func:`frozen_array`, converted to float64).

    Examples
    --------
    >>> b = frozen_floats([1, 2])
    >>> b.dtype.name, b.flags.writeable
    ('float64', False)
    """
    out: NDArray[np.float64] = np.array(a, dtype=np.float64)
    out.setflags(write=False)
    return out


def read_only(value: Any) -> Any:
    """``value`` with its ``writeable`` flag cleared in place, if it is an array; no copy.

    For the arrays a result is made of that were made for it and are shared with
    nothing (no caller holds them); anything else (a number, a geometric primitive,
    read-only already) is returned as it is.

    Examples
    --------
    >>> a = np.zeros(2)
    >>> read_only(a) is a, a.flags.writeable
    (True, False)
    """
    if isinstance(value, np.ndarray):
        value.setflags(write=False)
    return value


def frozen_value(v: Any) -> Any:
    """``v`` with every array made a read-only copy (tuples and mappings looked into).

    Numbers, strings and other objects are returned as they are; a tuple or list becomes a
    tuple, a mapping a read-only mapping.
    """
    if isinstance(v, np.ndarray):
        return frozen_array(v)
    if isinstance(v, tuple | list):
        return tuple(frozen_value(x) for x in v)
    if isinstance(v, Mapping):
        return frozen_mapping({k: frozen_value(x) for k, x in v.items()})
    return v


class FrozenMapping(Mapping[K, V]):
    """A read-only mapping that, unlike :class:`types.MappingProxyType`, pickles.

    Results and compiled models travel to worker processes (``executor="process"``,
    Dask), so their mappings must pickle; item assignment and deletion raise
    ``TypeError``. Built by :func:`frozen_mapping`.
    """

    __slots__ = ("_data",)

    def __init__(self, data: Mapping[K, V]) -> None:
        self._data = dict(data)

    def __getitem__(self, key: K) -> V:
        return self._data[key]

    def __iter__(self) -> Iterator[K]:
        return iter(self._data)

    def __len__(self) -> int:
        return len(self._data)

    def __repr__(self) -> str:
        return f"FrozenMapping({self._data!r})"

    def __reduce__(self) -> tuple[Any, ...]:
        return (FrozenMapping, (self._data,))


def frozen_mapping(m: Mapping[K, V]) -> Mapping[K, V]:
    """A read-only copy of ``m`` (a :class:`FrozenMapping`).

    Parameters
    ----------
    m : mapping
        The entries; copied, so later changes to ``m`` do not show.

    Returns
    -------
    mapping
        Readable like a dict and picklable; item assignment and deletion raise
        ``TypeError``.
    """
    return m if isinstance(m, FrozenMapping) else FrozenMapping(m)
