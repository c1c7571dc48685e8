"""Identification of bearing coefficients from (virtual) measured data.

* :func:`identify` runs SG, MISG, RLS or batch LS (:data:`RECURSIONS`) on a :class:`Regression`
  (batched over records) → :class:`IdentificationResult` (estimates, covariance, trajectory,
  iterations to a tolerance, flags);
* :mod:`.synthetic` reproduces the paper's synthetic rigid rotor (Sect. 3.1) and
  :mod:`.comparison` the fair convergence comparison;
* :func:`condense_reactions` + :func:`identify_phasors` give the eight bearing coefficients of
  the flexible FE rotor from 1× phasors by exact dynamic condensation;
* :func:`fit_uncertainty` turns identified vectors into the :class:`IdentifiedUncertainty` the
  study uses (speed trend, scatter, normality tests, variance split; ``uncertainty.json`` via
  :func:`save_uncertainty` / :func:`load_uncertainty`); :func:`identify_campaign` does both
  steps for a campaign's phasors.

``docs/identification.md`` has the figures and what they mean.
"""

from surrogate_rbrdo.identification.campaign import CampaignResult, identify_campaign
from surrogate_rbrdo.identification.condensation import (
    CondensedReactions,
    coefficient_names,
    condense_reactions,
    node_at,
    phasor_time_regression,
    trial_weight_difference,
)
from surrogate_rbrdo.identification.identify import IdentificationResult, identify
from surrogate_rbrdo.identification.model import (
    IdentifiedUncertainty,
    load_uncertainty,
    model_reference,
    save_uncertainty,
    study_weights,
)
from surrogate_rbrdo.identification.normality import NormalityReport, normality_report
from surrogate_rbrdo.identification.phasor import (
    PhasorIdentification,
    catalog_coefficients,
    identify_phasors,
)
from surrogate_rbrdo.identification.recursions import MISG, RECURSIONS, RLS, SG, BatchLS
from surrogate_rbrdo.identification.regression import Bounds, Regression
from surrogate_rbrdo.identification.scatter import (
    fit_uncertainty,
    output_variance_share,
    variance_split,
)
from surrogate_rbrdo.identification.trend import TrendFit, fit_trend

__all__ = [
    "MISG",
    "RECURSIONS",
    "RLS",
    "SG",
    "BatchLS",
    "Bounds",
    "CampaignResult",
    "CondensedReactions",
    "IdentificationResult",
    "IdentifiedUncertainty",
    "NormalityReport",
    "PhasorIdentification",
    "Regression",
    "TrendFit",
    "catalog_coefficients",
    "coefficient_names",
    "condense_reactions",
    "fit_trend",
    "fit_uncertainty",
    "identify",
    "identify_campaign",
    "identify_phasors",
    "load_uncertainty",
    "model_reference",
    "node_at",
    "normality_report",
    "output_variance_share",
    "phasor_time_regression",
    "save_uncertainty",
    "study_weights",
    "trial_weight_difference",
    "variance_split",
]
