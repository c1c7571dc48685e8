"""Identification of bearing coefficients from (virtual) measured data.

* :func:`identify` runs SG, MISG, RLS or batch LS (:data:`RECURSIONS`) on a :class:`Regression`
  (batched over records) → :class:`IdentificationResult` (estimates, covariance, trajectory,
  iterations to a tolerance, flags);
* :mod:`.synthetic` reproduces the paper's synthetic rigid rotor (Sect. 3.1) and
  :mod:`.comparison` the fair convergence comparison;
* :func:`condense_reactions` + :func:`identify_phasors` give the eight bearing coefficients of
  the flexible FE rotor from 1× phasors by exact dynamic condensation;
* :func:`fit_uncertainty` turns identified vectors into the :class:`IdentifiedUncertainty` the
  study uses (speed trend, physical scatter with the identification error taken out,
  systematic uncertainty, normality tests; ``uncertainty.json`` via :func:`save_uncertainty` /
  :func:`load_uncertainty`); :func:`identify_campaign` does both steps for a campaign's phasors;
* from measured records (the virtual rig's or a user's): :func:`measured_phasors` (demodulation,
  known corrections, keyphasor refinement), :func:`trial_pairs` (trial-weight runs),
  :func:`identify_records` / :func:`run_identification` (the ``identification`` experiment);
* :func:`impact_damping`: the bearings' damping (η), standstill stiffness and tool mass by
  updating the FE model on impact-test FRFs; :func:`impact_dampings` per installation of a
  dataset (``IdentificationOptions(damping="impact", tool_mass="impact")`` uses them);
* :func:`study_uncertainty`: the study's θ at the response's speed(s) from a run folder or
  ``uncertainty.json`` (what ``[uncertainty] from = …`` calls).

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
from surrogate_rbrdo.identification.damping import impact_dampings
from surrogate_rbrdo.identification.experiment import (
    IdentificationOptions,
    IdentificationRun,
    identify_records,
    run_identification,
)
from surrogate_rbrdo.identification.identify import IdentificationResult, identify
from surrogate_rbrdo.identification.impact import ImpactDamping, ImpactOptions, impact_damping
from surrogate_rbrdo.identification.measured import (
    MeasuredPhasors,
    SensorCorrections,
    measured_phasors,
)
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
    effective_coefficients,
    identify_phasors,
)
from surrogate_rbrdo.identification.physical import ScatterFit, physical_scatter
from surrogate_rbrdo.identification.recursions import MISG, RECURSIONS, RLS, SG, BatchLS
from surrogate_rbrdo.identification.regression import Bounds, Regression
from surrogate_rbrdo.identification.responses import Responses, known_unbalance, trial_pairs
from surrogate_rbrdo.identification.scatter import (
    fit_uncertainty,
    output_variance_share,
    variance_split,
)
from surrogate_rbrdo.identification.study import (
    StudyUncertainty,
    stiffness_block_from,
    study_uncertainty,
)
from surrogate_rbrdo.identification.systematic import (
    SystematicUncertainty,
    systematic_sensitivities,
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
    "IdentificationOptions",
    "IdentificationResult",
    "IdentificationRun",
    "IdentifiedUncertainty",
    "ImpactDamping",
    "ImpactOptions",
    "MeasuredPhasors",
    "NormalityReport",
    "PhasorIdentification",
    "Regression",
    "Responses",
    "ScatterFit",
    "SensorCorrections",
    "StudyUncertainty",
    "SystematicUncertainty",
    "TrendFit",
    "catalog_coefficients",
    "coefficient_names",
    "condense_reactions",
    "effective_coefficients",
    "fit_trend",
    "fit_uncertainty",
    "identify",
    "identify_campaign",
    "identify_phasors",
    "identify_records",
    "impact_damping",
    "impact_dampings",
    "known_unbalance",
    "load_uncertainty",
    "measured_phasors",
    "model_reference",
    "node_at",
    "normality_report",
    "output_variance_share",
    "phasor_time_regression",
    "physical_scatter",
    "run_identification",
    "save_uncertainty",
    "stiffness_block_from",
    "study_uncertainty",
    "study_weights",
    "systematic_sensitivities",
    "trial_pairs",
    "trial_weight_difference",
    "variance_split",
]
