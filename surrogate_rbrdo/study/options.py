"""Options of the study's optimisation and verification stages (also their TOML tables).

The optimiser is chosen by name from ``optimization.OPTIMIZERS`` (``"nsga2"``, ``"optuna"``,
any registered one); its options dataclass is the annotation of its ``options`` parameter, and
``pop_size`` / ``n_gen`` / ``eliminate_duplicates`` (where it has them) plus
``optimizer_options`` fill it.

>>> o = OptimizationOptions(optimizer="optuna", pop_size=10, n_gen=3)
>>> type(o.optimizer_config()).__name__, o.optimizer_config().pop_size
('OptunaOptions', 10)
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
from surrogate_rbrdo.estimators import ESTIMATORS
from surrogate_rbrdo.formulations import FORMULATIONS
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


@dataclass(frozen=True)
class OptimizationOptions:
    """``[optimization]``: the RBRDO levels, the comparison strategies and the optimiser.

    Attributes
    ----------
    p_targets : tuple of float
        RBRDO runs, one per target probability of failure, in (0, 1).
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
    optimizer : str
        ``OPTIMIZERS`` name (``nsga2``, ``optuna``).
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
    optimizer: str = "nsga2"
    pop_size: int = 100
    n_gen: int = 200
    n_jobs: int = 2
    eliminate_duplicates: bool = True
    optimizer_options: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for k in ("p_targets", "strategies", "weights"):
            object.__setattr__(self, k, tuple(getattr(self, k)))
        if not self.p_targets:
            raise ValueError("p_targets = [] is not allowed: give at least one")
        for i, p in enumerate(self.p_targets):
            check_range(f"p_targets[{i}]", p, 0.0, 1.0, inclusive=False)
        if len(set(self.p_targets)) != len(self.p_targets):
            raise ValueError(f"p_targets = {list(self.p_targets)} is not allowed: contains "
                             "duplicates")
        check_range("strategy_p_target", self.strategy_p_target, 0.0, 1.0, inclusive=False)
        for i, s in enumerate(self.strategies):
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
        check_choice("optimizer", self.optimizer, sorted(OPTIMIZERS))
        check_int("n_theta", self.n_theta, minimum=2)
        check_int("pop_size", self.pop_size, minimum=2)
        check_int("n_gen", self.n_gen, minimum=1)
        check_int("n_jobs", self.n_jobs, minimum=1)
        if not isinstance(self.eliminate_duplicates, bool):
            raise ValueError(f"eliminate_duplicates = {self.eliminate_duplicates!r} is not "
                             "allowed: must be true or false")
        object.__setattr__(self, "optimizer_options", dict(self.optimizer_options))
        self.optimizer_config()  # every field of the optimiser's options, checked now

    @property
    def runs(self) -> tuple[tuple[str, float], ...]:
        """``(formulation, p_target)`` of every run: RBRDO per level, then the strategies."""
        return (tuple(("rbrdo", p) for p in self.p_targets)
                + tuple((s, self.strategy_p_target) for s in self.strategies))

    def optimizer_config(self) -> Any:
        """The optimiser's options dataclass, filled from these options."""
        cls = optimizer_options_class(self.optimizer)
        names = {f.name for f in dataclasses.fields(cls)}
        common = {"pop_size": self.pop_size, "n_gen": self.n_gen,
                  "eliminate_duplicates": self.eliminate_duplicates}
        kw = {k: v for k, v in common.items() if k in names}
        unknown = sorted(set(self.optimizer_options) - names)
        if unknown:
            raise ValueError(f"optimizer_options has unknown key(s) {unknown} for optimizer "
                             f"{self.optimizer!r}; allowed: {sorted(names)}")
        clash = sorted(set(self.optimizer_options) & set(common))
        if clash:
            raise ValueError(f"optimizer_options.{clash[0]} is not allowed: set it in "
                             "[optimization] itself")
        try:
            return cls(**kw, **self.optimizer_options)
        except ValueError as exc:
            key = str(exc).split(" ", 1)[0]
            if key in self.optimizer_options:
                raise ValueError(f"optimizer_options.{exc}") from None
            raise

    def optimizer_function(self) -> Callable[..., Any]:
        """The registered optimiser."""
        return OPTIMIZERS.get(self.optimizer)


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
    """

    n_theta: int = 10_000
    pf_method: str = "mc"
    is_samples: int = 2000
    n_jobs: int = 2
    chunk: int = 250

    def __post_init__(self) -> None:
        check_int("n_theta", self.n_theta, minimum=2)
        check_choice("pf_method", self.pf_method, ("mc", "is"))
        check_int("is_samples", self.is_samples, minimum=10)
        check_int("n_jobs", self.n_jobs, minimum=1)
        check_int("chunk", self.chunk, minimum=1)


__all__ = ["OptimizationOptions", "VerificationOptions", "optimizer_options_class"]
