"""Surrogate structures of ``y(x, θ)`` built from FE evaluations of a spindle, in a registry.

========================= ===============================================================
``"global"``              one Kriging of ``t(y)`` over (x, θ) (static LHS or AK-MCS)
``"resonance"``           critical speed + resonance height + flank + background sub-models
``"substructure"``        Kriging of the condensed rotor over x, bearings and θ exact
``"fe"``                  no surrogate: the FE model itself (the ground truth)
========================= ===============================================================

Each has one frozen options dataclass (``GlobalOptions``, ``ResonanceOptions``,
``SubstructureOptions``, ``FEOptions``); :func:`train_surrogate` returns a
:class:`TrainedSurrogate` for every one of them.

>>> sorted(STRUCTURES)
['fe', 'global', 'resonance', 'substructure']
"""

from surrogate_rbrdo.surrogates.structured.base import (
    STRUCTURES,
    SamplingOptions,
    Structure,
    SurrogateModel,
    TrainedSurrogate,
    register_structure,
    structure_of,
    surrogate_options,
    train_surrogate,
)
from surrogate_rbrdo.surrogates.structured.full import FEOptions, FullModel
from surrogate_rbrdo.surrogates.structured.global_kriging import GlobalOptions
from surrogate_rbrdo.surrogates.structured.joint import JointDOEOptions
from surrogate_rbrdo.surrogates.structured.resonance import (
    RESONANCE_OUTPUTS,
    ResonanceSurrogate,
    fit_resonance_surrogate,
)
from surrogate_rbrdo.surrogates.structured.resonance_train import (
    ResonanceOptions,
    band_points,
    sample_resonance,
)
from surrogate_rbrdo.surrogates.structured.substructure import (
    SubstructureSurrogate,
    fit_substructure_surrogate,
)
from surrogate_rbrdo.surrogates.structured.substructure_train import SubstructureOptions

__all__ = [
    "RESONANCE_OUTPUTS", "STRUCTURES", "FEOptions", "FullModel", "GlobalOptions",
    "JointDOEOptions", "ResonanceOptions", "ResonanceSurrogate", "SamplingOptions",
    "Structure", "SubstructureOptions", "SubstructureSurrogate", "SurrogateModel",
    "TrainedSurrogate", "band_points", "fit_resonance_surrogate", "fit_substructure_surrogate",
    "register_structure", "sample_resonance", "structure_of", "surrogate_options",
    "train_surrogate",
]
