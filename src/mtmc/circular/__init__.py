"""Circular tests: ISO 230-4 ballbar tests and the rotary-axis tests of five-axis machines.

The parameters of ISO 230-4 from their definitions on batched traces
(:mod:`~mtmc.circular.parameters`), the first-order model ``ΔR = e · n`` and the
identification of the errors it holds (:mod:`~mtmc.circular.model`), the simulation of a
test on a :class:`~mtmc.kinematics.Machine` with the effects a static model lacks and the
instrument (:mod:`~mtmc.circular.simulate`), and the Monte Carlo of a whole test beside
the GUM (:mod:`~mtmc.circular.uncertainty`; a rotary-axis test's model,
R-test or ballbar, in :mod:`~mtmc.circular.rotary`). This package knows nothing of study files,
reports or the command line.
"""

from mtmc.circular import data, model, parameters, rotary, simulate, uncertainty
from mtmc.circular.data import *  # noqa: F403
from mtmc.circular.model import *  # noqa: F403
from mtmc.circular.parameters import *  # noqa: F403
from mtmc.circular.rotary import *  # noqa: F403
from mtmc.circular.simulate import *  # noqa: F403
from mtmc.circular.uncertainty import *  # noqa: F403

__all__: list[str] = [
    *data.__all__,
    *model.__all__,
    *parameters.__all__,
    *rotary.__all__,
    *simulate.__all__,
    *uncertainty.__all__,
]
