"""Identification of bearing coefficients from (virtual) measured data.

Recursions (SG, MISG, RLS, batch LS) behind :func:`identify`; regressions from the paper's
synthetic rigid rotor and from the flexible FE rotor by exact dynamic condensation; the
uncertainty model (speed trend, scatter, MVN, normality tests) the study consumes.
"""

from surrogate_rbrdo.identification.identify import IdentificationResult, identify
from surrogate_rbrdo.identification.recursions import MISG, RECURSIONS, RLS, SG, BatchLS
from surrogate_rbrdo.identification.regression import Bounds, Regression

__all__ = [
    "MISG",
    "RECURSIONS",
    "RLS",
    "SG",
    "BatchLS",
    "Bounds",
    "IdentificationResult",
    "Regression",
    "identify",
]
