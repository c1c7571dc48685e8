"""Random inputs: random vectors, marginals and the isoprobabilistic transform to ``u`` space.

Every random vector implements :class:`RandomVector`: ``dim``, ``mean``, ``cov``,
``sample(n, rng=...)``, ``standard_sample(n, rng=...)``, ``from_standard(u)`` and
``to_standard(theta)``. A standard sample drawn once and passed to estimators as ``u`` gives
common random numbers across designs.

>>> import numpy as np
>>> mvn = MultivariateNormal([0.0, 1.0], std=[1.0, 2.0])
>>> u = mvn.standard_sample(5, rng=np.random.default_rng(1))
>>> np.allclose(mvn.to_standard(mvn.from_standard(u)), u)
True
"""

from surrogate_rbrdo.uncertainty.base import RandomVector, standard_normal_sample
from surrogate_rbrdo.uncertainty.box import marginal_box
from surrogate_rbrdo.uncertainty.factors import FACTOR_DISTRIBUTIONS, stiffness_factors
from surrogate_rbrdo.uncertainty.marginals import LogNormal, Normal, Uniform
from surrogate_rbrdo.uncertainty.mvn import MultivariateNormal
from surrogate_rbrdo.uncertainty.nataf import Independent, Nataf, fictitious_correlation

__all__ = [
    "FACTOR_DISTRIBUTIONS",
    "Independent",
    "LogNormal",
    "MultivariateNormal",
    "Nataf",
    "Normal",
    "RandomVector",
    "Uniform",
    "fictitious_correlation",
    "marginal_box",
    "standard_normal_sample",
    "stiffness_factors",
]
