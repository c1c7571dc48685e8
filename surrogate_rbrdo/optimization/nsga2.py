"""NSGA-II through pymoo with the paper's settings, recording every evaluated design.

Paper settings (Sect. 2.2): N_pop = 100, N_gen = 200, SBX crossover p_c = 0.9, polynomial
mutation p_m = 0.25, LHS initial population, infeasible designs ranked behind feasible ones.

How they map onto pymoo 0.6:

* ``SBX(prob=0.9, eta=15)``: ``prob`` is the probability that a *mating* produces crossed
  children (pymoo's per-variable exchange ``prob_var`` keeps its default 0.5).
* polynomial mutation ``PM(eta=20)`` has two probabilities: ``prob`` (is an offspring a mutation
  candidate at all) and ``prob_var`` (is each of its variables mutated). The paper's single
  ``p_m = 0.25`` is read, as in Deb's NSGA-II where p_m is per variable (usually 1/n_var), as
  ``prob=1.0, prob_var=0.25`` (``mutation_mode="per_variable"``, default: 0.75 mutated variables
  per child for d = 3, close to 1/n_var = 1/3). ``mutation_mode="per_individual"`` gives
  ``prob=0.25, prob_var=1/n_var`` instead (one child in four mutated, one variable on average).
* ``sampling=LHS()`` (pymoo's maximin LHS) for the initial population.
* constraints: pymoo's default feasibility-first constraint domination (Deb 2000): a feasible
  design beats an infeasible one, two infeasible ones compare by total violation
  Σ max(G, 0), two feasible ones by rank and crowding. This is what the paper calls
  "penalised ranking" with no penalty factor to tune.
* Single-objective formulations (``rbdo``, ``deterministic``) run through the *same* NSGA-II:
  with one objective the non-dominated rank is the sort order, so it acts as an elitist
  (μ + λ) GA with the same operators and constraint handling.

The run is reproducible to the bit: pymoo draws every random number from one
``numpy.random.default_rng(seed)`` where ``seed`` comes from the caller's Generator.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass

import numpy as np

from surrogate_rbrdo.core.registry import Registry
from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive, check_range
from surrogate_rbrdo.optimization.evaluator import RecordingEvaluator
from surrogate_rbrdo.optimization.lean import lean_nsga2
from surrogate_rbrdo.optimization.result import OptimizationResult

OPTIMIZERS = Registry("optimizer")


@dataclass(frozen=True)
class NSGA2Options:
    """NSGA-II settings (defaults = the paper's).

    >>> NSGA2Options().pymoo_mutation_probs(3)
    (1.0, 0.25)
    >>> NSGA2Options(mutation_mode="per_individual").pymoo_mutation_probs(4)
    (0.25, 0.25)
    >>> NSGA2Options(pop_size=1)
    Traceback (most recent call last):
    ...
    ValueError: pop_size = 1 is not allowed: must be an integer >= 2
    """

    pop_size: int = 100
    n_gen: int = 200
    crossover_prob: float = 0.9
    crossover_eta: float = 15.0
    mutation_prob: float = 0.25
    mutation_eta: float = 20.0
    mutation_mode: str = "per_variable"
    eliminate_duplicates: bool = True
    engine: str = "lean"

    def __post_init__(self) -> None:
        check_int("pop_size", self.pop_size, minimum=2)
        check_int("n_gen", self.n_gen, minimum=1)
        check_range("crossover_prob", self.crossover_prob, 0.0, 1.0)
        check_positive("crossover_eta", self.crossover_eta)
        check_range("mutation_prob", self.mutation_prob, 0.0, 1.0)
        check_positive("mutation_eta", self.mutation_eta)
        check_choice("mutation_mode", self.mutation_mode, ("per_variable", "per_individual"))
        check_choice("engine", self.engine, ("lean", "pymoo"))

    def pymoo_mutation_probs(self, n_var: int) -> tuple[float, float]:
        """``(prob, prob_var)`` passed to pymoo's ``PM``."""
        if self.mutation_mode == "per_variable":
            return 1.0, float(self.mutation_prob)
        return float(self.mutation_prob), 1.0 / n_var


def check_bounds(lower, upper) -> tuple[np.ndarray, np.ndarray]:
    """Validate box bounds; returns float arrays."""
    lo = np.atleast_1d(np.asarray(lower, dtype=float))
    hi = np.atleast_1d(np.asarray(upper, dtype=float))
    if lo.ndim != 1 or lo.shape != hi.shape or lo.size == 0:
        raise ValueError(f"bounds have shapes {lo.shape} and {hi.shape}: need equal (d,)")
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(lo < hi)):
        raise ValueError(f"bounds lower={lo.tolist()}, upper={hi.tolist()} are not allowed: "
                         "need finite lower < upper")
    return lo, hi


@OPTIMIZERS.register("nsga2")
def run_nsga2(formulation, lower, upper, *, rng: np.random.Generator,
              options: NSGA2Options | None = None, progress: bool = False
              ) -> OptimizationResult:
    """Minimise a formulation over the box ``[lower, upper]`` with pymoo's NSGA-II.

    Parameters
    ----------
    formulation : Formulation
        ``evaluate(x) -> Evaluation`` with ``n_obj >= 1`` objectives.
    lower, upper : array_like, shape (d,)
        Design bounds.
    rng : numpy.random.Generator
        One integer seed is drawn from it for pymoo.
    options : NSGA2Options
        ``engine="lean"`` (default) runs the array-based loop of
        :mod:`~surrogate_rbrdo.optimization.lean` (same operators and rules, ~10x less
        per-generation overhead); ``engine="pymoo"`` runs ``pymoo.optimize.minimize``.
    progress : bool
        Show a tqdm bar (one tick per generation).
    """
    # pymoo is imported where NSGA-II runs: ~1.5 s of imports that `rbrdo kinds`, a rejected
    # config and every library user who never optimises would otherwise pay
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.core.problem import Problem
    from pymoo.operators.crossover.sbx import SBX
    from pymoo.operators.mutation.pm import PM
    from pymoo.operators.sampling.lhs import LHS
    from pymoo.optimize import minimize

    options = NSGA2Options() if options is None else options
    if not isinstance(options, NSGA2Options):
        raise ValueError(f"options = {options!r} is not allowed: must be NSGA2Options")
    lo, hi = check_bounds(lower, upper)
    rng = require_rng(rng)
    seed = int(rng.integers(0, 2**32 - 1))
    n_obj, n_con = formulation.n_obj, formulation.n_con
    evaluator = RecordingEvaluator(formulation, progress=progress, total=options.n_gen,
                                   desc=f"NSGA-II {formulation.name}")

    class _Problem(Problem):
        def __init__(self) -> None:
            super().__init__(n_var=lo.size, n_obj=n_obj, n_ieq_constr=n_con, xl=lo, xu=hi)

        def _evaluate(self, X, out, *args, **kwargs):
            F, G = evaluator(X)
            out["F"] = F
            if n_con:
                out["G"] = G

    prob, prob_var = options.pymoo_mutation_probs(lo.size)
    if options.engine == "lean":
        return _run_lean(formulation, evaluator, lo, hi, options, seed, prob, prob_var)
    algorithm = NSGA2(
        pop_size=options.pop_size,
        sampling=LHS(),
        crossover=SBX(prob=options.crossover_prob, eta=options.crossover_eta),
        mutation=PM(prob=prob, prob_var=prob_var, eta=options.mutation_eta),
        eliminate_duplicates=options.eliminate_duplicates,
    )
    t0 = time.perf_counter()
    try:
        res = minimize(_Problem(), algorithm, ("n_gen", options.n_gen), seed=seed,
                       verbose=False, save_history=False, copy_algorithm=False)
    finally:
        evaluator.close_progress()
    archive = evaluator.freeze()
    wall = time.perf_counter() - t0
    pop = res.pop
    X = np.asarray(pop.get("X"), dtype=float)
    F = np.asarray(pop.get("F"), dtype=float).reshape(X.shape[0], n_obj)
    G = (np.asarray(pop.get("G"), dtype=float).reshape(X.shape[0], n_con) if n_con
         else np.empty((X.shape[0], 0)))
    return _result(evaluator, archive, X, F, G, wall, options, seed, prob, prob_var)


def _run_lean(formulation, evaluator, lo, hi, options, seed, prob, prob_var
              ) -> OptimizationResult:
    n_obj, n_con = formulation.n_obj, formulation.n_con
    t0 = time.perf_counter()
    try:
        X, F, G = lean_nsga2(
            evaluator, lo, hi, pop_size=options.pop_size, n_gen=options.n_gen,
            crossover_prob=options.crossover_prob, crossover_eta=options.crossover_eta,
            mutation_prob=prob, mutation_prob_var=prob_var, mutation_eta=options.mutation_eta,
            eliminate_duplicates=options.eliminate_duplicates, seed=seed)
    finally:
        evaluator.close_progress()
    archive = evaluator.freeze()
    wall = time.perf_counter() - t0
    F = F.reshape(X.shape[0], n_obj)
    G = G.reshape(X.shape[0], n_con) if n_con else np.empty((X.shape[0], 0))
    return _result(evaluator, archive, X, F, G, wall, options, seed, prob, prob_var)


def _result(evaluator, archive, X, F, G, wall, options, seed, prob, prob_var
            ) -> OptimizationResult:
    """The result both engines return."""
    return evaluator.result(
        archive, X, F, G, wall,
        {"name": "nsga2", "seed": seed, **asdict(options), "pymoo_mutation_prob": prob,
         "pymoo_mutation_prob_var": prob_var})
