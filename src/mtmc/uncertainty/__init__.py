"""Monte Carlo uncertainty engine (JCGM 101) with the GUM (JCGM 100) beside it.

PDFs, seeded sampling in blocks, Monte Carlo (fixed and adaptive), summaries and coverage
intervals, GUM propagation, the JCGM 101 §8 validation, and expression models. This
package knows nothing of machines or geometry.
"""

from mtmc.uncertainty import distributions, expression, gum, montecarlo, results, sampling, tolerance
from mtmc.uncertainty.distributions import *  # noqa: F403
from mtmc.uncertainty.expression import *  # noqa: F403
from mtmc.uncertainty.gum import *  # noqa: F403
from mtmc.uncertainty.montecarlo import *  # noqa: F403
from mtmc.uncertainty.results import *  # noqa: F403
from mtmc.uncertainty.sampling import *  # noqa: F403
from mtmc.uncertainty.tolerance import *  # noqa: F403

__all__: list[str] = [
    *distributions.__all__,
    *expression.__all__,
    *gum.__all__,
    *montecarlo.__all__,
    *results.__all__,
    *sampling.__all__,
    *tolerance.__all__,
]
