"""The RBRDO study as stage functions returning frozen results (``docs/api.md``).

:class:`Problem` / :func:`reference_problem` say what is designed; :func:`optimise`,
:func:`refine` and :func:`verify` are the study's stages after the surrogate
(:func:`~surrogate_rbrdo.surrogates.structured.train_surrogate`) and the g_det design model
(:func:`~surrogate_rbrdo.surrogates.design_model.fit_design_model`).
"""

from surrogate_rbrdo.study.constraints import expression_constraints, spindle_constraints
from surrogate_rbrdo.study.memory import check_study_memory
from surrogate_rbrdo.study.options import OptimizationOptions, VerificationOptions
from surrogate_rbrdo.study.problem import (
    DESIGN_NAMES,
    RESIDUAL_STD,
    TABLE4_STD,
    Problem,
    credible_problem,
    reference_problem,
    unbalance_design_cases,
)
from surrogate_rbrdo.study.stages import (
    Optimisation,
    Refinement,
    Verification,
    chosen_designs,
    formulation,
    merge_calls,
    optimise,
    refine,
    run_label,
    verify,
)

__all__ = [
    "DESIGN_NAMES", "RESIDUAL_STD", "TABLE4_STD", "OptimizationOptions", "Optimisation",
    "Problem", "Refinement", "Verification", "VerificationOptions", "check_study_memory",
    "chosen_designs",
    "credible_problem", "expression_constraints", "formulation", "merge_calls", "optimise",
    "reference_problem", "refine", "run_label", "spindle_constraints",
    "unbalance_design_cases", "verify",
]
