"""Validation on the virtual rig: replicated experiments and paired statistics (Table 7)."""

from surrogate_rbrdo.validation.statistics import (
    PairedComparison,
    min_detectable_d_z,
    paired_comparison,
    paired_power,
)

__all__ = ["PairedComparison", "min_detectable_d_z", "paired_comparison", "paired_power"]
