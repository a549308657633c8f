"""Machine kinematics with ISO 230 geometric errors.

Topology strings (``wCBXfYZt``, ``XFYZ``), ISO 230-1 / 230-7 error names, error generation
functions (Aguado et al. 2016, §4.3), batched forward kinematics with errors and its
Jacobian, the equation of motion written out with SymPy, Aguado's error coefficients mapped
to ISO 230, a library of common configurations, and a drawing of the kinematic chain. This
package knows nothing of instruments or files.
"""

from mtmc.kinematics import (
    aguado,
    draw,
    error_terms,
    functions,
    library,
    machine,
    parameters,
    symbolic,
    topology,
)
from mtmc.kinematics.aguado import *  # noqa: F403
from mtmc.kinematics.draw import *  # noqa: F403
from mtmc.kinematics.error_terms import *  # noqa: F403
from mtmc.kinematics.functions import *  # noqa: F403
from mtmc.kinematics.library import *  # noqa: F403
from mtmc.kinematics.machine import *  # noqa: F403
from mtmc.kinematics.parameters import *  # noqa: F403
from mtmc.kinematics.symbolic import *  # noqa: F403
from mtmc.kinematics.topology import *  # noqa: F403

__all__: list[str] = [
    *aguado.__all__,
    *draw.__all__,
    *error_terms.__all__,
    *functions.__all__,
    *library.__all__,
    *machine.__all__,
    *parameters.__all__,
    *symbolic.__all__,
    *topology.__all__,
]
