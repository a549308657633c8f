"""Small batched vector kernels shared by the geometry and the graph ops."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def cross(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a × b`` over the last axis, shapes ``(..., 3)`` broadcast against each other.

    Written out component by component: several times faster than ``np.cross`` on
    ``(M, 3)`` arrays.

    Examples
    --------
    >>> cross(np.array([[1.0, 0.0, 0.0]]), np.array([0.0, 1.0, 0.0]))
    array([[0., 0., 1.]])
    """
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out
