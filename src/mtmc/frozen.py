"""Read-only arrays and mappings for the frozen results and tables of the package.

A frozen dataclass stops rebinding its fields, not writing into them: an array field can
still be changed in place (``r.cov[0, 0] = 0``) and a dict field can gain keys. The results
and module-level tables therefore hold arrays with the ``writeable`` flag cleared and
mappings wrapped in :class:`types.MappingProxyType`, made here, copied at the boundary so
that no caller's object is frozen or shared.

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
TypeError: 'mappingproxy' object does not support item assignment
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Any, TypeVar

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

__all__ = ["frozen_array", "frozen_mapping", "frozen_value"]

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


def frozen_mapping(m: Mapping[K, V]) -> Mapping[K, V]:
    """A read-only view of a copy of ``m`` (a :class:`types.MappingProxyType`).

    Parameters
    ----------
    m : mapping
        The entries; copied, so later changes to ``m`` do not show.

    Returns
    -------
    mapping
        Readable like a dict; item assignment and deletion raise ``TypeError``.
    """
    return MappingProxyType(dict(m))
