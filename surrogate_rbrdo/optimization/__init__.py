"""Optimisers (pymoo NSGA-II, optuna NSGA-II), archives, Pareto post-processing.

pymoo and optuna are imported only inside this sub-package, and only when a run starts.
"""

from surrogate_rbrdo.optimization.batch import run_many
from surrogate_rbrdo.optimization.nsga2 import OPTIMIZERS, NSGA2Options, check_bounds, run_nsga2
from surrogate_rbrdo.optimization.optuna_backend import OptunaOptions, run_optuna
from surrogate_rbrdo.optimization.pareto import (
    asf_compromise,
    feasible_mask,
    feasible_pareto,
    nondominated,
)
from surrogate_rbrdo.optimization.postprocess import (
    Compromise,
    archive_front,
    front_table,
    mbr_table,
    select_compromise,
    strategy_table,
    write_csv,
)
from surrogate_rbrdo.optimization.result import Archive, OptimizationResult
from surrogate_rbrdo.optimization.slsqp import SLSQPOptions, run_slsqp

__all__ = [
    "OPTIMIZERS",
    "Archive",
    "Compromise",
    "archive_front",
    "front_table",
    "mbr_table",
    "run_many",
    "select_compromise",
    "strategy_table",
    "write_csv",
    "NSGA2Options",
    "OptimizationResult",
    "OptunaOptions",
    "SLSQPOptions",
    "asf_compromise",
    "check_bounds",
    "feasible_mask",
    "feasible_pareto",
    "nondominated",
    "run_nsga2",
    "run_optuna",
    "run_slsqp",
]
