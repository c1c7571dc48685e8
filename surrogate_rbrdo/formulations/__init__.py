"""Design formulations (deterministic, RDO, RBDO, RBRDO): populations → objectives, constraints.

Usage::

    form = make_formulation("rbrdo", response=surrogate, inputs=mvn, limit=LimitState(19.5e-6),
                            options=FormulationOptions(p_target=0.05), deterministic=fe_quantities,
                            rng=rng)
    ev = form.evaluate(x)          # ev.F (P, 2), ev.G (P, n_con), ev.estimate
"""

from surrogate_rbrdo.formulations import strategies as _strategies  # noqa: F401  (registers)
from surrogate_rbrdo.formulations.base import (
    FORMULATIONS,
    Evaluation,
    Formulation,
    ReliabilityConstraint,
    make_formulation,
)
from surrogate_rbrdo.formulations.constraints import DesignConstraint, block_constraints
from surrogate_rbrdo.formulations.deterministic import (
    RESONANCE_GUARDS,
    DeterministicConstraints,
    DeterministicModel,
    DeterministicOptions,
)
from surrogate_rbrdo.formulations.options import FormulationOptions
from surrogate_rbrdo.formulations.reliability import PF_BOUNDS, RELIABILITY_MEASURES
from surrogate_rbrdo.formulations.strategies import (
    DeterministicFormulation,
    RBDOFormulation,
    RBRDOFormulation,
    RDOFormulation,
)

__all__ = [
    "FORMULATIONS",
    "PF_BOUNDS",
    "RELIABILITY_MEASURES",
    "RESONANCE_GUARDS",
    "DesignConstraint",
    "DeterministicConstraints",
    "DeterministicFormulation",
    "DeterministicModel",
    "DeterministicOptions",
    "Evaluation",
    "Formulation",
    "FormulationOptions",
    "RBDOFormulation",
    "RBRDOFormulation",
    "RDOFormulation",
    "ReliabilityConstraint",
    "block_constraints",
    "make_formulation",
]
