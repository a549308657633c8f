"""Batched geometry: points, vectors, lines, planes, circles, spheres and frames.

Every function takes arrays with the trial axis first (a point is ``(M, 3)``, a frame
``(M, 4, 4)``) and computes the whole batch in one pass. Constructions, intersections,
projections, least-squares fits, and homogeneous transforms. This package knows nothing
of randomness or files.
"""

from mtmc.geometry import constructions, fits, primitives, transforms
from mtmc.geometry.constructions import *  # noqa: F403
from mtmc.geometry.fits import *  # noqa: F403
from mtmc.geometry.primitives import *  # noqa: F403
from mtmc.geometry.transforms import *  # noqa: F403

__all__: list[str] = [
    *constructions.__all__,
    *fits.__all__,
    *primitives.__all__,
    *transforms.__all__,
]
