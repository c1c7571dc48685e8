"""Estimators of μ_y, σ_y and P_f, in the registry :data:`ESTIMATORS`.

Every estimator is a frozen dataclass of its options with
``estimate(response, inputs, limit, x, *, rng, u=None) -> Estimate``:

========== ====================================================================================
``mc``     crude Monte Carlo (Eqs. 12-14), Clopper-Pearson interval
``is``     importance sampling at the design points (two stages, half-space control variates)
``ais``    adaptive IS: improved cross-entropy with vMFN (or Gaussian) mixtures
``form``   FORM by iHL-RF with finite-difference gradients
``sorm``   SORM (Breitung / Hohenbichler-Rackwitz) from the FORM design point
``subset`` subset simulation (Au & Beck) with conditional sampling in u space
``fosm``   first-order second-moment: μ, σ and the Cornell index
========== ====================================================================================

>>> sorted(ESTIMATORS)
['ais', 'form', 'fosm', 'is', 'mc', 'sorm', 'subset']
"""

from surrogate_rbrdo.estimators.registry import ESTIMATORS, get_estimator  # noqa: I001
from surrogate_rbrdo.estimators.mc import MonteCarlo, mc_from_values
from surrogate_rbrdo.estimators.form import FORM
from surrogate_rbrdo.estimators.fosm import FOSM
from surrogate_rbrdo.estimators.importance import ImportanceSampling
from surrogate_rbrdo.estimators.adaptive import CrossEntropyIS
from surrogate_rbrdo.estimators.sorm import SORM
from surrogate_rbrdo.estimators.subset import SubsetSimulation
from surrogate_rbrdo.estimators._tail import EstimatorWarning
from surrogate_rbrdo.estimators._common import clopper_pearson, evaluate_in_domain
from surrogate_rbrdo.estimators.mc import mc_with_outside

__all__ = [
    "ESTIMATORS", "FORM", "FOSM", "SORM", "CrossEntropyIS", "EstimatorWarning",
    "ImportanceSampling", "MonteCarlo", "SubsetSimulation", "clopper_pearson",
    "evaluate_in_domain", "get_estimator", "mc_from_values", "mc_with_outside",
]
