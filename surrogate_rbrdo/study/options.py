"""Options of the study's optimisation and verification stages (also their TOML tables).

The optimiser is chosen by name from ``optimization.OPTIMIZERS`` (``"nsga2"``, ``"optuna"``,
``"slsqp"``, any registered one); its options dataclass is the annotation of its ``options``
parameter, and ``pop_size`` / ``n_gen`` / ``eliminate_duplicates`` (where it has them) plus
``optimizer_options`` fill it. ``single_objective_optimizer`` (with
``single_objective_options``) takes the single-objective runs (``rbdo``, ``deterministic``),
e.g. SLSQP on the sample-average P_f beside NSGA-II for the fronts.

>>> o = OptimizationOptions(optimizer="optuna", pop_size=10, n_gen=3)
>>> type(o.optimizer_config()).__name__, o.optimizer_config().pop_size
('OptunaOptions', 10)
>>> o = OptimizationOptions(single_objective_optimizer="slsqp",
...                         reliability_measure="quantile")
>>> [type(o.optimizer_config(n)).__name__ for n in ("rbrdo", "rbdo")]
['NSGA2Options', 'SLSQPOptions']
>>> OptimizationOptions(weights=(0.5,))
Traceback (most recent call last):
...
ValueError: weights = [0.5] is not allowed: need two weights (μ, σ)
"""

from __future__ import annotations

import dataclasses
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import UnionType
from typing import Any

from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive, check_range
from surrogate_rbrdo.estimators import ESTIMATORS, get_estimator
from surrogate_rbrdo.formulations import FORMULATIONS
from surrogate_rbrdo.formulations.options import check_reliability
from surrogate_rbrdo.formulations.reliability import quantile_rank
from surrogate_rbrdo.optimization import OPTIMIZERS


def optimizer_options_class(name: str) -> type:
    """The options dataclass of the optimiser registered as ``name`` (the annotation of its
    ``options`` parameter)."""
    func = OPTIMIZERS.get(name)
    hint = typing.get_type_hints(func).get("options")
    args = typing.get_args(hint) if isinstance(hint, UnionType) or typing.get_origin(
        hint) is typing.Union else (hint,)
    for a in args:
        if dataclasses.is_dataclass(a):
            return a
    raise ValueError(f"optimizer {name!r} has no options dataclass in its signature")


def _check_p_target(name: str, p: float) -> None:
    """A target probability of failure in (0, 0.5): at 0.5 and above β_t <= 0, the median
    design or worse, which no reliability constraint means."""
    check_range(name, p, 0.0, 1.0, inclusive=False)
    if p >= 0.5:
        raise ValueError(f"{name} = {p!r} is not allowed: must be below 0.5 (a failure "
                         "target of 50 % or more is β_t <= 0, the median design or worse, "
                         "not a reliability requirement)")


def _estimator_fields(name: str) -> list[str]:
    """The options ``get_estimator(name, ...)`` accepts (its dataclass's init fields)."""
    return sorted(f.name for f in dataclasses.fields(ESTIMATORS.get(name)) if f.init)


def _n_obj(formulation: str) -> int:
    return len(FORMULATIONS.get(formulation).objective_names)


@dataclass(frozen=True)
class OptimizationOptions:
    """``[optimization]``: the RBRDO levels, the comparison strategies and the optimiser.

    Attributes
    ----------
    p_targets : tuple of float
        RBRDO runs, one per target probability of failure, in (0, 1) (may be empty when
        ``strategies`` is not).
    strategies : tuple of str
        Further formulations (``FORMULATIONS``: ``rdo``, ``rbdo``, ``deterministic``) run at
        ``strategy_p_target``.
    strategy_p_target : float
    weights : (float, float)
        ASF weights (μ, σ) of the compromise design.
    n_theta : int
        Size of the common-random-number θ sample every formulation sees.
    estimator : str
        ``ESTIMATORS`` name (``mc``: the fast path on the CRN sample).
    estimator_options : mapping
        Keyword options of the estimator (``get_estimator(estimator, **estimator_options)``).
    reliability_measure : {"probability", "beta", "quantile"}
        How each chance constraint is written (``FormulationOptions``): ``P_f/P_target − 1``,
        ``β_t − β`` or the ``P_target``-quantile of the limit state on the CRN sample.
    pf_bound : {"estimate", "upper"}
        Constrain the P_f estimate, or (conservative) the upper end of its 95 % interval.
    optimizer : str
        ``OPTIMIZERS`` name (``nsga2``, ``optuna``, ``slsqp`` for single-objective runs).
    single_objective_optimizer : str or None
        Optimiser of the ``rbdo`` and ``deterministic`` runs (default: ``optimizer``).
    single_objective_options : mapping
        Further fields of its options dataclass.
    pop_size, n_gen : int
        Population and generations (every optimiser here has them).
    n_jobs : int
        Runs side by side in worker processes.
    eliminate_duplicates : bool
        NSGA-II (pymoo) duplicate elimination.
    optimizer_options : mapping
        Further fields of the optimiser's options dataclass (e.g. ``crossover_prob``).
    """

    p_targets: tuple[float, ...] = (0.10, 0.05, 0.01)
    strategies: tuple[str, ...] = ("rdo", "rbdo", "deterministic")
    strategy_p_target: float = 0.05
    weights: tuple[float, ...] = (0.5, 0.5)
    n_theta: int = 1000
    estimator: str = "mc"
    estimator_options: Mapping[str, Any] = field(default_factory=dict)
    reliability_measure: str = "probability"
    pf_bound: str = "estimate"
    optimizer: str = "nsga2"
    single_objective_optimizer: str | None = None
    single_objective_options: Mapping[str, Any] = field(default_factory=dict)
    pop_size: int = 100
    n_gen: int = 200
    n_jobs: int = 2
    eliminate_duplicates: bool = True
    optimizer_options: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for k in ("p_targets", "strategies", "weights"):
            object.__setattr__(self, k, tuple(getattr(self, k)))
        if not self.p_targets and not self.strategies:
            raise ValueError("p_targets = [] is not allowed with strategies = []: give at least "
                             "one run")
        for i, p in enumerate(self.p_targets):
            _check_p_target(f"p_targets[{i}]", p)
        if len(set(self.p_targets)) != len(self.p_targets):
            raise ValueError(f"p_targets = {list(self.p_targets)} is not allowed: contains "
                             "duplicates")
        _check_p_target("strategy_p_target", self.strategy_p_target)
        for i, s in enumerate(self.strategies):   # the RBRDO runs are the p_targets
            if s == "rbrdo":
                raise ValueError(f"strategies[{i}] = 'rbrdo' is not allowed: the RBRDO runs are "
                                 "set by p_targets (one per level); strategies are the other "
                                 f"formulations {sorted(set(FORMULATIONS) - {'rbrdo'})}")
            check_choice(f"strategies[{i}]", s, sorted(FORMULATIONS))
        if len(set(self.strategies)) != len(self.strategies):
            raise ValueError(f"strategies = {list(self.strategies)} is not allowed: contains "
                             "duplicates")
        if len(self.weights) != 2:
            raise ValueError(f"weights = {list(self.weights)} is not allowed: need two "
                             "weights (μ, σ)")
        for i, w in enumerate(self.weights):
            check_positive(f"weights[{i}]", w)
        check_choice("estimator", self.estimator, sorted(ESTIMATORS))
        object.__setattr__(self, "estimator_options", dict(self.estimator_options))
        self._check_estimator()
        check_choice("optimizer", self.optimizer, sorted(OPTIMIZERS))
        if self.single_objective_optimizer is not None:
            check_choice("single_objective_optimizer", self.single_objective_optimizer,
                         sorted(OPTIMIZERS))
        object.__setattr__(self, "single_objective_options",
                           dict(self.single_objective_options))
        check_int("n_theta", self.n_theta, minimum=2)
        check_int("pop_size", self.pop_size, minimum=2)
        check_int("n_gen", self.n_gen, minimum=1)
        check_int("n_jobs", self.n_jobs, minimum=1)
        if not isinstance(self.eliminate_duplicates, bool):
            raise ValueError(f"eliminate_duplicates = {self.eliminate_duplicates!r} is not "
                             "allowed: must be true or false")
        object.__setattr__(self, "optimizer_options", dict(self.optimizer_options))
        self._check_reliability()
        for name, _ in self.runs:   # every field of the optimisers' options, checked now
            self._check_run(name)

    def memory_bytes(self) -> dict[str, float]:
        """Peak bytes (``core.memory``): each run evaluates ``pop_size × n_theta`` responses
        (~8 arrays of 8 B; ``min(n_jobs, runs)`` runs at once) and keeps an archive of
        ``pop_size × n_gen`` individuals (~16 values each, kept twice) per run.

        >>> m = OptimizationOptions(pop_size=10 ** 8, n_gen=10 ** 8, n_theta=40).memory_bytes()
        >>> max(m, key=m.get)
        'pop_size*n_gen'
        """
        k = len(self.runs)
        return {"pop_size*n_theta": 64.0 * self.pop_size * self.n_theta * min(self.n_jobs, k),
                "pop_size*n_gen": 256.0 * self.pop_size * self.n_gen * k}

    def _check_estimator(self) -> None:
        """Build the estimator once now, so a bad option is refused before any work, named
        ``estimator_options.<key>``."""
        opts = self.estimator_options
        unknown = sorted(set(map(str, opts)) - set(_estimator_fields(self.estimator)))
        if unknown:
            raise ValueError(f"estimator_options has unknown key(s) {unknown} for estimator "
                             f"{self.estimator!r}; allowed: {_estimator_fields(self.estimator)}")
        try:
            get_estimator(self.estimator, **opts)
        except (ValueError, TypeError) as exc:
            key = str(exc).split(" ", 1)[0]
            if key in opts:
                raise ValueError(f"estimator_options.{exc}") from None
            raise ValueError(f"estimator_options = {dict(opts)!r} is not allowed for "
                             f"estimator {self.estimator!r}: {exc}") from None

    def _check_reliability(self) -> None:
        check_reliability(self.reliability_measure, self.pf_bound, self.estimator)
        if self.reliability_measure == "quantile":
            for pt in sorted({p for n, p in self.runs if FORMULATIONS.get(n).reliability}):
                if quantile_rank(self.n_theta, pt, self.pf_bound, 0.95) < 1:
                    raise ValueError(f"n_theta = {self.n_theta} is not allowed with "
                                     f"reliability_measure = 'quantile', pf_bound = "
                                     f"{self.pf_bound!r} and P_target = {pt}: fewer than one "
                                     "failure allowed (raise n_theta)")

    def _check_run(self, formulation: str) -> None:
        opt = self.optimizer_name(formulation)
        key = "single_objective_optimizer" if self._single(formulation) else "optimizer"
        if getattr(OPTIMIZERS.get(opt), "single_objective", False):
            if _n_obj(formulation) > 1:
                raise ValueError(f"{key} = {opt!r} is not allowed with the {formulation} runs: "
                                 "it minimises one objective (set single_objective_optimizer "
                                 f"= {opt!r} for rbdo/deterministic and keep a multi-objective"
                                 " optimizer)")
            if FORMULATIONS.get(formulation).reliability and \
                    self.reliability_measure == "probability" and self.estimator == "mc":
                raise ValueError(f"{key} = {opt!r} is not allowed with reliability_measure = "
                                 "'probability' and estimator = 'mc': the sample P_f is a "
                                 "staircase in x (zero gradient); use reliability_measure = "
                                 "'quantile' (or 'beta' with estimator = 'form')")
        self.optimizer_config(formulation)

    @property
    def runs(self) -> tuple[tuple[str, float], ...]:
        """``(formulation, p_target)`` of every run: RBRDO per level, then the strategies."""
        return (tuple(("rbrdo", p) for p in self.p_targets)
                + tuple((s, self.strategy_p_target) for s in self.strategies))

    def _single(self, formulation: str) -> bool:
        """Whether ``single_objective_optimizer`` takes ``formulation``'s runs."""
        return self.single_objective_optimizer is not None and _n_obj(formulation) == 1

    def optimizer_name(self, formulation: str = "rbrdo") -> str:
        """The optimiser of the runs of ``formulation``."""
        if self._single(formulation):
            return self.single_objective_optimizer
        return self.optimizer

    def optimizer_config(self, formulation: str = "rbrdo") -> Any:
        """The options dataclass of the optimiser of ``formulation``'s runs, filled from
        these options."""
        name = self.optimizer_name(formulation)
        single = self._single(formulation)
        where = "single_objective_options" if single else "optimizer_options"
        extra = self.single_objective_options if single else self.optimizer_options
        cls = optimizer_options_class(name)
        names = {f.name for f in dataclasses.fields(cls)}
        common = {"pop_size": self.pop_size, "n_gen": self.n_gen,
                  "eliminate_duplicates": self.eliminate_duplicates}
        kw = {k: v for k, v in common.items() if k in names}
        unknown = sorted(set(extra) - names)
        if unknown:
            raise ValueError(f"{where} has unknown key(s) {unknown} for optimizer "
                             f"{name!r}; allowed: {sorted(names)}")
        clash = sorted(set(extra) & set(common))
        if clash:
            raise ValueError(f"{where}.{clash[0]} is not allowed: set it in "
                             "[optimization] itself")
        try:
            return cls(**kw, **extra)
        except ValueError as exc:
            key = str(exc).split(" ", 1)[0]
            if key in extra:
                raise ValueError(f"{where}.{exc}") from None
            raise

    def optimizer_function(self, formulation: str = "rbrdo") -> Callable[..., Any]:
        """The registered optimiser of ``formulation``'s runs."""
        return OPTIMIZERS.get(self.optimizer_name(formulation))


@dataclass(frozen=True)
class VerificationOptions:
    """``[verification]``: the full-FE check of every chosen design.

    Attributes
    ----------
    n_theta : int
        Size of the fresh θ sample of the FE Monte Carlo.
    pf_method : {"mc", "is"}
        ``"is"`` adds an importance-sampling P_f with ``is_samples`` FE calls per design.
    is_samples : int
    n_jobs : int
        Worker processes of the FE Monte Carlo.
    chunk : int
        θ rows per FE task.
    campbell_speeds : int
        Speed grid of the FE Campbell diagram from which each chosen design's damped critical
        speeds up to 1.5 × the top speed are found (0: no check).
    front_designs : int
        Up to this many designs of each RBRDO/RDO front are checked with the FE model too
        (``study.fronts``; 0: none).
    front_n_theta : int
        Size of their fresh θ sample (one sample for all of them).
    """

    n_theta: int = 10_000
    pf_method: str = "mc"
    is_samples: int = 2000
    n_jobs: int = 2
    chunk: int = 250
    campbell_speeds: int = 24
    front_designs: int = 0
    front_n_theta: int = 300

    def __post_init__(self) -> None:
        check_int("n_theta", self.n_theta, minimum=2)
        check_choice("pf_method", self.pf_method, ("mc", "is"))
        check_int("is_samples", self.is_samples, minimum=10)
        check_int("n_jobs", self.n_jobs, minimum=1)
        check_int("chunk", self.chunk, minimum=1)
        check_int("campbell_speeds", self.campbell_speeds, minimum=0)
        if self.campbell_speeds == 1:
            raise ValueError("campbell_speeds = 1 is not allowed: 0 (no check) or >= 2")
        check_int("front_designs", self.front_designs, minimum=0)
        check_int("front_n_theta", self.front_n_theta, minimum=2)

    def memory_bytes(self, n_designs: int = 1, n_dof: int = 8, n_inputs: int = 1,
                     n_fronts: int = 1) -> dict[str, float]:
        """Peak bytes (``core.memory``) of checking ``n_designs`` designs of a model with
        ``n_dof`` degrees of freedom and ``n_inputs`` θ components (the defaults are lower
        bounds; the study passes its own, ``study.memory``): the θ samples and ~4 values per
        design and θ row (FE, surrogate, their difference); the IS estimator's samples of all
        designs at once; the front check of up to ``front_designs`` designs of each of
        ``n_fronts`` fronts; one Campbell eigen-analysis (2·n_dof complex eigenvalues and
        vectors' norms per speed).

        >>> VerificationOptions(pf_method="is", is_samples=10 ** 12).memory_bytes()[
        ...     "is_samples"] > 1e13
        True
        """
        out = {"n_theta": 8.0 * self.n_theta * (n_inputs + 4 * n_designs)}
        if self.pf_method == "is":
            out["is_samples"] = 8.0 * self.is_samples * (n_inputs + 4 * n_designs)
        if self.front_designs:
            out["front_n_theta"] = 8.0 * self.front_n_theta * (
                n_inputs + 4 * self.front_designs * n_fronts)
        if self.campbell_speeds:
            out["campbell_speeds"] = 16.0 * 4 * n_dof * self.campbell_speeds
        return out


__all__ = ["OptimizationOptions", "VerificationOptions", "optimizer_options_class"]
