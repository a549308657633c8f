"""Monte Carlo uncertainty engine (JCGM 101) with the GUM (JCGM 100) beside it.

PDFs, seeded sampling in blocks, Monte Carlo (fixed and adaptive), summaries and coverage
intervals, GUM propagation, the JCGM 101 §8 validation, and expression models. This
package knows nothing of machines or geometry.
"""

# The modules are bound under private names; each module is named for what it holds
# (``decision``: conformity decisions; ``formula``: model formulas; ``propagation``: the
# GUM's law of propagation), so that ``conformity``, ``expression`` and ``gum`` are the
# functions alone.
from mtmc.uncertainty import copula as _copula
from mtmc.uncertainty import decision as _decision
from mtmc.uncertainty import distributions as _distributions
from mtmc.uncertainty import formula as _formula
from mtmc.uncertainty import joint as _joint
from mtmc.uncertainty import montecarlo as _montecarlo
from mtmc.uncertainty import propagation as _propagation
from mtmc.uncertainty import results as _results
from mtmc.uncertainty import sampling as _sampling
from mtmc.uncertainty import sensitivity as _sensitivity
from mtmc.uncertainty import tolerance as _tolerance
from mtmc.uncertainty import typea as _typea
from mtmc.uncertainty.copula import *  # noqa: F403
from mtmc.uncertainty.decision import *  # noqa: F403
from mtmc.uncertainty.distributions import *  # noqa: F403
from mtmc.uncertainty.formula import *  # noqa: F403
from mtmc.uncertainty.joint import *  # noqa: F403
from mtmc.uncertainty.montecarlo import *  # noqa: F403
from mtmc.uncertainty.propagation import *  # noqa: F403
from mtmc.uncertainty.results import *  # noqa: F403
from mtmc.uncertainty.sampling import *  # noqa: F403
from mtmc.uncertainty.sensitivity import *  # noqa: F403
from mtmc.uncertainty.tolerance import *  # noqa: F403
from mtmc.uncertainty.typea import *  # noqa: F403

__all__: list[str] = [
    *_decision.__all__,
    *_copula.__all__,
    *_distributions.__all__,
    *_formula.__all__,
    *_propagation.__all__,
    *_joint.__all__,
    *_montecarlo.__all__,
    *_results.__all__,
    *_sampling.__all__,
    *_sensitivity.__all__,
    *_tolerance.__all__,
    *_typea.__all__,
]
