"""The data-driven loop of the paper as one plan (``docs/validation.md``, "The loop end to
end"): a rig campaign → identification → the study's θ → RBRDO → validation of the chosen
designs on the rig → discrepancy when model and rig disagree → the study and validation again
on the updated model. :mod:`~surrogate_rbrdo.loop.plan` checks every part's tables before
any work; :mod:`~surrogate_rbrdo.loop.steps` holds the decisions and plans between the parts
(the ``end_to_end`` experiment kind runs them in order).
"""

from surrogate_rbrdo.loop.plan import EndToEndConfig, LoopPlan, LoopTable, build_loop
from surrogate_rbrdo.loop.steps import (
    IdentifiedTheta,
    Reoptimisation,
    discrepancy_reason,
    identified_theta,
    reoptimisation,
    study_plan,
    validated_designs,
    validation_plan_for,
)

__all__ = ["EndToEndConfig", "IdentifiedTheta", "LoopPlan", "LoopTable", "Reoptimisation",
           "build_loop", "discrepancy_reason", "identified_theta", "reoptimisation",
           "study_plan", "validated_designs", "validation_plan_for"]
