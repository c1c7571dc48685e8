"""Deterministic constraints ``g_det(x) <= 0`` built from per-design FE quantities.

The FE model supplies, for a batch of designs, a :class:`DeterministicModel`: any callable
``deterministic(x) -> Mapping[str, ndarray]`` with ``x`` of shape ``(P, d)`` returning (SI units)

* ``"von_mises_pa"``: shape ``(P,)``, peak von Mises stress in Pa;
* ``"omega_n1"``: shape ``(P,)``, first natural frequency in rad/s (paper guard);
* ``"critical_speeds"``: shape ``(P, k)``, critical speeds in rad/s, NaN for "none"
  (separation guard).

Only the keys needed by the selected constraints are read. Each call counts ``P`` true-model
calls in the optimiser's accounting.

>>> import numpy as np
>>> opts = DeterministicOptions(resonance="paper", omega_max=100.0)
>>> model = lambda x: {"von_mises_pa": 465e6 * x[:, 0], "omega_n1": 150.0 * x[:, 0]}
>>> con = DeterministicConstraints(opts, model)
>>> con.names
('stress', 'resonance')
>>> con(np.array([[1.0], [0.5]])).round(3)
array([[-0.5  , -0.25 ],
       [-0.75 ,  0.375]])
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_positive

RESONANCE_GUARDS = ("paper", "separation", "none")


class DeterministicModel(Protocol):
    """``deterministic(x (P, d)) -> {"von_mises_pa": (P,), "omega_n1": (P,), ...}``."""

    def __call__(self, x: np.ndarray) -> Mapping[str, np.ndarray]: ...


@dataclass(frozen=True)
class DeterministicOptions:
    """Which deterministic constraints to impose, and their limits (SI units).

    Parameters
    ----------
    stress : bool
        Impose ``σ_VM / σ_yield − 1 <= 0``.
    yield_strength_pa : float
        σ_yield (paper: 930 MPa).
    resonance : {"paper", "separation", "none"}
        ``"paper"``: ``1 − ω_n1 / (factor · Ω_max) <= 0``. ``"separation"`` (API 684-style):
        for every operating speed ``n_op``, ``margin − min_k |n_k − n_op| / n_op <= 0`` over
        the critical speeds ``n_k`` (so every critical speed near ``n_op`` is kept at least
        ``margin`` away; far ones never bind). ``"none"``: no resonance guard.
    omega_max : float
        Ω_max in rad/s (paper guard).
    factor : float
        Frequency factor of the paper guard (1.2).
    operating_speeds : tuple of float
        Rated and/or maximum speed in rad/s (separation guard), one constraint each.
    margin : float
        Required relative separation (e.g. 0.15 for 15 %).
    """

    stress: bool = True
    yield_strength_pa: float = 930e6
    resonance: str = "paper"
    omega_max: float = 24_000 * 2 * np.pi / 60
    factor: float = 1.2
    operating_speeds: tuple[float, ...] = ()
    margin: float = 0.15

    def __post_init__(self) -> None:
        check_positive("yield_strength_pa", self.yield_strength_pa)
        check_choice("resonance", self.resonance, RESONANCE_GUARDS)
        check_positive("omega_max", self.omega_max)
        check_positive("factor", self.factor)
        check_positive("margin", self.margin)
        object.__setattr__(self, "operating_speeds", tuple(float(s) for s in
                                                           self.operating_speeds))
        for i, s in enumerate(self.operating_speeds):
            check_positive(f"operating_speeds[{i}]", s)
        if self.resonance == "separation" and not self.operating_speeds:
            raise ValueError("operating_speeds = () is not allowed with resonance='separation':"
                             " give at least one operating speed in rad/s")

    @property
    def names(self) -> tuple[str, ...]:
        """Constraint names in column order."""
        out = ("stress",) if self.stress else ()
        if self.resonance == "paper":
            out += ("resonance",)
        elif self.resonance == "separation":
            out += tuple(f"separation_{i}" for i in range(len(self.operating_speeds)))
        return out


@dataclass(frozen=True)
class DeterministicConstraints:
    """Callable ``x (P, d) -> g_det (P, n_det)``, feasible where ``<= 0``."""

    options: DeterministicOptions
    model: Callable[[np.ndarray], Mapping[str, np.ndarray]] | None = None

    def __post_init__(self) -> None:
        if self.names and self.model is None:
            raise ValueError(
                f"deterministic constraints {list(self.names)} need a deterministic model "
                "(callable x -> dict of FE quantities); got None"
            )

    @property
    def names(self) -> tuple[str, ...]:
        return self.options.names

    def __call__(self, x: np.ndarray) -> np.ndarray:
        p = x.shape[0]
        if not self.names:
            return np.empty((p, 0))
        q = self.model(x)
        o = self.options
        cols = []
        if o.stress:
            cols.append(_get(q, "von_mises_pa", p) / o.yield_strength_pa - 1.0)
        if o.resonance == "paper":
            cols.append(1.0 - _get(q, "omega_n1", p) / (o.factor * o.omega_max))
        elif o.resonance == "separation":
            crit = np.asarray(q["critical_speeds"], dtype=float).reshape(p, -1)
            for n_op in o.operating_speeds:
                sep = np.abs(crit - n_op) / n_op
                sep = np.where(np.isnan(sep), np.inf, sep)
                nearest = sep.min(axis=1) if sep.shape[1] else np.full(p, np.inf)
                # no critical speed at all: a large finite slack keeps G finite
                cols.append(o.margin - np.minimum(nearest, 1e6))
        return np.column_stack(cols)


def _get(q: Mapping[str, np.ndarray], key: str, p: int) -> np.ndarray:
    if key not in q:
        raise ValueError(f"deterministic model did not return {key!r}; got {sorted(q)}")
    v = np.asarray(q[key], dtype=float).reshape(-1)
    if v.shape != (p,):
        raise ValueError(f"deterministic quantity {key!r} has shape {v.shape}, expected ({p},)")
    return v
