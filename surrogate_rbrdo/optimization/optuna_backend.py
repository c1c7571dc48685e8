"""Optuna's NSGA-II (``NSGAIISampler`` with ``constraints_func``) as a comparison backend.

Each generation is asked as one batch of ``pop_size`` trials, evaluated in one vectorised call
of the formulation, and told back, so the cost model matches the pymoo backend. Differences
from pymoo's NSGA-II that matter when comparing:

* initial population: optuna draws generation 0 with its random sampler (uniform, not LHS);
* crossover: ``SBXCrossover(eta=15)`` with probability ``crossover_prob`` (0.9),
  variables swapped between children with ``swapping_prob`` (0.5);
* mutation: optuna 5's ``PolynomialMutation(eta=20)`` applied to each parameter with
  probability ``mutation_prob`` = 0.25 (the paper's p_m read per variable, as in the pymoo
  backend's default);
* constraints: reported per trial with ``Trial.set_constraint`` (optuna 5; the older
  ``constraints_func`` is deprecated) and handled by feasibility-first constraint domination as
  in pymoo (Deb 2000), the violation summed over ``G > 0``.

Reproducible to the bit: the sampler's seed is drawn from the caller's Generator.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import asdict, dataclass

import numpy as np

from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_int, check_positive, check_range
from surrogate_rbrdo.optimization.evaluator import RecordingEvaluator
from surrogate_rbrdo.optimization.nsga2 import OPTIMIZERS, check_bounds
from surrogate_rbrdo.optimization.result import OptimizationResult


@dataclass(frozen=True)
class OptunaOptions:
    """Settings of the optuna NSGA-II backend.

    >>> OptunaOptions(pop_size=10, n_gen=5).mutation_prob
    0.25
    """

    pop_size: int = 100
    n_gen: int = 200
    crossover_prob: float = 0.9
    swapping_prob: float = 0.5
    mutation_prob: float = 0.25
    crossover_eta: float = 15.0
    mutation_eta: float = 20.0

    def __post_init__(self) -> None:
        check_int("pop_size", self.pop_size, minimum=2)
        check_int("n_gen", self.n_gen, minimum=1)
        check_range("crossover_prob", self.crossover_prob, 0.0, 1.0)
        check_range("swapping_prob", self.swapping_prob, 0.0, 1.0)
        check_range("mutation_prob", self.mutation_prob, 0.0, 1.0)
        check_positive("crossover_eta", self.crossover_eta)
        check_positive("mutation_eta", self.mutation_eta)


@OPTIMIZERS.register("optuna")
def run_optuna(formulation, lower, upper, *, rng: np.random.Generator,
               options: OptunaOptions | None = None, progress: bool = False
               ) -> OptimizationResult:
    """Minimise a formulation with optuna's NSGA-II; same result type as :func:`run_nsga2`."""
    import optuna  # heavy (with its storage and sampler modules): only when optuna is chosen
    from optuna.samplers import NSGAIISampler
    from optuna.samplers.nsgaii import PolynomialMutation, SBXCrossover

    options = OptunaOptions() if options is None else options
    if not isinstance(options, OptunaOptions):
        raise ValueError(f"options = {options!r} is not allowed: must be OptunaOptions")
    lo, hi = check_bounds(lower, upper)
    rng = require_rng(rng)
    seed = int(rng.integers(0, 2**32 - 1))
    n_obj = formulation.n_obj
    evaluator = RecordingEvaluator(formulation, progress=progress, total=options.n_gen,
                                   desc=f"optuna {formulation.name}")
    dists = {f"x{i}": optuna.distributions.FloatDistribution(float(a), float(b))
             for i, (a, b) in enumerate(zip(lo, hi, strict=True))}
    names = list(dists)
    old_verbosity = optuna.logging.get_verbosity()
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            sampler = NSGAIISampler(
                population_size=options.pop_size,
                mutation=PolynomialMutation(eta=options.mutation_eta),
                mutation_prob=options.mutation_prob,
                crossover=SBXCrossover(eta=options.crossover_eta),
                crossover_prob=options.crossover_prob,
                swapping_prob=options.swapping_prob, seed=seed)
            study = optuna.create_study(directions=["minimize"] * n_obj, sampler=sampler)
            for _ in range(options.n_gen):
                trials = [study.ask(dists) for _ in range(options.pop_size)]
                X = np.array([[t.params[k] for k in names] for t in trials], dtype=float)
                F, G = evaluator(X)
                for t, f, g in zip(trials, F, G, strict=True):
                    for j, gj in enumerate(g):
                        t.set_constraint(f"g{j}", float(gj))
                    study.tell(t, f.tolist() if n_obj > 1 else float(f[0]))
    finally:
        optuna.logging.set_verbosity(old_verbosity)
        evaluator.close_progress()
    archive = evaluator.freeze()
    wall = time.perf_counter() - t0
    last = archive.generation == archive.generation.max()
    X, F, G = archive.X[last], archive.F[last], archive.G[last]
    return evaluator.result(archive, X, F, G, wall,
                            {"name": "optuna", "seed": seed,
                             "optuna_version": optuna.__version__, **asdict(options)})
