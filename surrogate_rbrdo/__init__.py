"""surrogate_rbrdo: reliability-based robust design optimisation of spindle-bearing systems.

The public API (``docs/api.md``) is re-exported here, imported on first use (PEP 562), so
``import surrogate_rbrdo`` stays light::

    from surrogate_rbrdo import reference_problem, train_surrogate, SubstructureOptions

The layers (``core`` → ``spindle`` → ``uncertainty``/``doe`` → ``sampling`` → ``surrogates``
→ ``estimators`` → ``formulations`` → ``optimization`` → ``study`` → ``reporting`` →
``runner``) import only downwards.

>>> import surrogate_rbrdo
>>> surrogate_rbrdo.reference_problem().response.label
'amplitude at 24000 rpm'
>>> sorted(surrogate_rbrdo.STRUCTURES)
['fe', 'global', 'resonance', 'substructure']
"""

from importlib import import_module
from typing import Any

__version__ = "0.1.0"

#: public name -> module that defines it
_EXPORTS = {
    # the problem and the physics
    "Problem": "study.problem", "reference_problem": "study.problem",
    "DESIGN_NAMES": "study.problem", "TABLE4_STD": "study.problem",
    "credible_problem": "study.problem", "RESIDUAL_STD": "study.problem",
    "credible_spindle": "spindle.reference", "PeakUnbalanceSpec": "spindle.peak_response",
    "reference_spindle": "spindle.reference", "ResponseSpec": "spindle.evaluate",
    "PeakAmplitudeResponse": "spindle.evaluate", "AtSpeedAmplitudeResponse": "spindle.evaluate",
    "peak_tool_amplitude": "spindle.harmonic", "tool_amplitude": "spindle.harmonic",
    "campbell": "spindle.modal", "design_quantities": "spindle.evaluate",
    # uncertainty, limit state, counting, DOE, FE sampling
    "MultivariateNormal": "uncertainty", "LimitState": "core.protocols",
    "Estimate": "core.protocols", "Prediction": "core.protocols",
    "CallCounter": "core.counting", "CountingResponse": "core.counting",
    "CountingDesigns": "core.counting", "lhs": "doe", "evaluate_points": "sampling",
    "sample_positive": "sampling.fe", "sample_designs": "sampling.fe", "fe_cache": "sampling.fe",
    # surrogates
    "STRUCTURES": "surrogates.structured", "train_surrogate": "surrogates.structured",
    "TrainedSurrogate": "surrogates.structured", "SurrogateModel": "surrogates.structured",
    "GlobalOptions": "surrogates.structured", "ResonanceOptions": "surrogates.structured",
    "SubstructureOptions": "surrogates.structured", "FEOptions": "surrogates.structured",
    "SURROGATES": "surrogates", "KrgSE": "surrogates", "KrigingOptions": "surrogates",
    "GPR": "surrogates", "ak_mcs": "surrogates.active", "AKMCSOptions": "surrogates.active",
    "validation_metrics": "surrogates.validation", "compare_mc": "surrogates.validation",
    "loo_cv": "surrogates.validation", "refine_surrogate": "surrogates.refine",
    "RefineOptions": "surrogates.refine", "fit_design_model": "surrogates.design_model",
    "DesignModelOptions": "surrogates.design_model",
    # estimators, formulations, optimisers
    "ESTIMATORS": "estimators", "get_estimator": "estimators",
    "mc_from_values": "estimators", "FORMULATIONS": "formulations",
    "make_formulation": "formulations", "FormulationOptions": "formulations",
    "DeterministicOptions": "formulations", "OPTIMIZERS": "optimization",
    "run_nsga2": "optimization", "NSGA2Options": "optimization", "run_optuna": "optimization",
    "OptunaOptions": "optimization", "archive_front": "optimization",
    "select_compromise": "optimization", "OptimizationResult": "optimization",
    # the study's stages
    "optimise": "study.stages", "refine": "study.stages", "verify": "study.stages",
    "Optimisation": "study.stages", "Verification": "study.stages",
    "OptimizationOptions": "study.options", "VerificationOptions": "study.options",
    # running experiments from Python
    "run_experiment": "runner.execute",
}

__all__ = ["__version__", *sorted(_EXPORTS)]


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'surrogate_rbrdo' has no attribute {name!r}")
    value = getattr(import_module(f"surrogate_rbrdo.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return __all__
