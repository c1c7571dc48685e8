"""Validation on the virtual rig (``docs/validation.md``): paired replicated experiments of
several designs on the rig's truth, Table 7's paired statistics, and model vs measurement.

* the experiment: :mod:`~.replicas` (truth family, pairing), :mod:`~.measure` (one
  replication), :mod:`~.campaign` (:func:`validate_designs`), :mod:`~.options`;
* statistics: :mod:`~.statistics` (paired t, d_z, Wilcoxon, bootstrap, power),
  :mod:`~.paired_binary` (McNemar, Newcombe), :mod:`~.paired_spread` (Pitman–Morgan),
  :mod:`~.table7`;
* the model's side: :mod:`~.model` (:class:`ModelSpec`), :mod:`~.agreement` (verdicts);
* output: :mod:`~.tables` (CSV/JSON), :mod:`~.report` (markdown); figures in
  ``reporting.plots_validation``.
"""

from surrogate_rbrdo.validation.agreement import Verdict
from surrogate_rbrdo.validation.campaign import (
    DesignResult,
    ValidationResult,
    add_model,
    measure_designs,
    validate_designs,
)
from surrogate_rbrdo.validation.model import (
    ModelPrediction,
    ModelSpec,
    Moments,
    SpindleCurves,
    predict_model,
    spindle_model_spec,
)
from surrogate_rbrdo.validation.options import ValidationOptions
from surrogate_rbrdo.validation.paired_binary import PairedProportions, paired_proportions
from surrogate_rbrdo.validation.paired_spread import PairedSpread, paired_spread
from surrogate_rbrdo.validation.replicas import TruthFamily, reference_family, replica_states
from surrogate_rbrdo.validation.statistics import (
    PairedComparison,
    min_detectable_d_z,
    paired_comparison,
    paired_power,
)
from surrogate_rbrdo.validation.table7 import Comparison, Table7Row, table7_rows
from surrogate_rbrdo.validation.tables import write_tables

__all__ = [
    "Comparison",
    "DesignResult",
    "ModelPrediction",
    "ModelSpec",
    "Moments",
    "PairedComparison",
    "PairedProportions",
    "PairedSpread",
    "SpindleCurves",
    "Table7Row",
    "TruthFamily",
    "ValidationOptions",
    "ValidationResult",
    "Verdict",
    "add_model",
    "measure_designs",
    "min_detectable_d_z",
    "paired_comparison",
    "paired_power",
    "paired_proportions",
    "paired_spread",
    "predict_model",
    "reference_family",
    "replica_states",
    "spindle_model_spec",
    "table7_rows",
    "validate_designs",
    "write_tables",
]
