"""Kriging surrogates (smt, scikit-learn) in a registry, fast batch prediction, validation.

>>> sorted(SURROGATES)
['gpr', 'krg_matern52', 'krg_se']
"""

from surrogate_rbrdo.surrogates.fast import ProductKernelPredictor, ThetaBlock
from surrogate_rbrdo.surrogates.gpr import GPR, GPROptions
from surrogate_rbrdo.surrogates.kriging import KrgMatern52, KrgSE, KrigingOptions
from surrogate_rbrdo.surrogates.registry import SURROGATES

__all__ = [
    "GPR", "GPROptions", "KrgMatern52", "KrgSE", "KrigingOptions", "ProductKernelPredictor",
    "SURROGATES", "ThetaBlock",
]
