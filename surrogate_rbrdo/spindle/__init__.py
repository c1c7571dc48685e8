"""FE spindle model: Timoshenko rotor, bearings with preload/speed laws, switchable effects.

Typical use::

    from surrogate_rbrdo.spindle import reference_spindle, peak_tool_amplitude
    sp = reference_spindle()
    model = sp.model(sp.baseline)
    peak = peak_tool_amplitude(model, theta=[[1.0, 1.0], [0.95, 1.05]])
"""

from surrogate_rbrdo.spindle.assembly import SpindleModel, build_model
from surrogate_rbrdo.spindle.effects import EFFECTS, Effect, effect_from_dict
from surrogate_rbrdo.spindle.geometry import DesignMap, SpindleGeometry
from surrogate_rbrdo.spindle.harmonic import (
    PeakOptions,
    PeakResult,
    peak_tool_amplitude,
    tool_amplitude,
    unbalance_response,
)
from surrogate_rbrdo.spindle.modal import (
    campbell,
    critical_speeds,
    first_natural_frequency,
    modal_analysis,
)
from surrogate_rbrdo.spindle.peak_coupling import (
    peak_tool_amplitude_coupled,
    peak_tool_amplitude_unbalance,
)
from surrogate_rbrdo.spindle.peak_response import (
    PeakUnbalanceResponse,
    PeakUnbalanceSpec,
    ThetaSpec,
)
from surrogate_rbrdo.spindle.practice import PracticeConstraints, PracticeSpec
from surrogate_rbrdo.spindle.reference import (
    ReferenceSpindle,
    credible_spindle,
    reference_spindle,
)
from surrogate_rbrdo.spindle.separation import ResonanceGuard, forward_critical_speeds
from surrogate_rbrdo.spindle.stress import max_von_mises

__all__ = [
    "EFFECTS",
    "DesignMap",
    "Effect",
    "PeakOptions",
    "PeakResult",
    "PeakUnbalanceResponse",
    "PeakUnbalanceSpec",
    "PracticeConstraints",
    "PracticeSpec",
    "ReferenceSpindle",
    "ResonanceGuard",
    "SpindleGeometry",
    "SpindleModel",
    "ThetaSpec",
    "build_model",
    "campbell",
    "credible_spindle",
    "critical_speeds",
    "effect_from_dict",
    "first_natural_frequency",
    "forward_critical_speeds",
    "max_von_mises",
    "modal_analysis",
    "peak_tool_amplitude",
    "peak_tool_amplitude_coupled",
    "peak_tool_amplitude_unbalance",
    "reference_spindle",
    "tool_amplitude",
    "unbalance_response",
]
