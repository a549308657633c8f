"""Monte Carlo uncertainty engine (JCGM 101) with the GUM (JCGM 100) beside it.

PDFs, seeded sampling in blocks, Monte Carlo (fixed and adaptive), summaries and coverage
intervals, GUM propagation, the JCGM 101 §8 validation, and expression models. This
package knows nothing of machines or geometry.
"""

# The modules are bound under private names: the star imports below rebind the public
# names ``expression`` and ``gum`` to the functions of the same name.
from mtmc.uncertainty import distributions as _distributions
from mtmc.uncertainty import expression as _expression
from mtmc.uncertainty import gum as _gum
from mtmc.uncertainty import montecarlo as _montecarlo
from mtmc.uncertainty import results as _results
from mtmc.uncertainty import sampling as _sampling
from mtmc.uncertainty import tolerance as _tolerance
from mtmc.uncertainty.distributions import *  # noqa: F403
from mtmc.uncertainty.expression import *  # noqa: F403
from mtmc.uncertainty.gum import *  # noqa: F403
from mtmc.uncertainty.montecarlo import *  # noqa: F403
from mtmc.uncertainty.results import *  # noqa: F403
from mtmc.uncertainty.sampling import *  # noqa: F403
from mtmc.uncertainty.tolerance import *  # noqa: F403

__all__: list[str] = [
    *_distributions.__all__,
    *_expression.__all__,
    *_gum.__all__,
    *_montecarlo.__all__,
    *_results.__all__,
    *_sampling.__all__,
    *_tolerance.__all__,
]
