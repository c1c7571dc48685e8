"""Known-answer problems for formulations and optimisers (used by tests and benchmarks).

* :class:`LinearMixToy`: ``y(x, θ) = x θ₁ + (1 − x) θ₂`` with independent normal θ, so μ_y, σ_y
  and P_f are closed form and so are the RDO Pareto set and the RBRDO constraint boundary.
* the published RBDO benchmarks (Youn & Choi, short column, cantilever) are in
  :mod:`~.rbdo_benchmarks`.

>>> toy = LinearMixToy()
>>> round(toy.x_min_std, 3), round(float(toy.std(np.array([toy.x_min_std]))[0]), 4)
(0.2, 0.8944)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq
from scipy.stats import norm

from surrogate_rbrdo.core.protocols import LimitState
from surrogate_rbrdo.uncertainty import MultivariateNormal


@dataclass(frozen=True)
class LinearMixToy:
    """``y = x θ₁ + (1 − x) θ₂``, ``θ_i ~ N(μ_i, σ_i²)`` independent, ``x ∈ [0, 1]``.

    With ``μ₁ < μ₂`` and ``σ₁ > σ₂``, μ_y = x μ₁ + (1 − x) μ₂ falls with ``x`` while
    σ_y = √(x² σ₁² + (1 − x)² σ₂²) is smallest at ``x* = σ₂² / (σ₁² + σ₂²)``: the RDO Pareto set
    is ``x ∈ [x*, 1]``. Failure ``y > δ`` has ``P_f = Φ((μ_y − δ)/σ_y)``, so ``P_f <= P_t`` is
    ``μ_y + β_t σ_y <= δ`` and cuts the Pareto set to ``[x_a, x_b]`` (roots of equality).
    """

    mu: tuple[float, float] = (1.0, 3.0)
    sigma: tuple[float, float] = (2.0, 1.0)
    delta: float = 3.5

    def response(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
        a = x[:, :1]
        return a * theta[:, 0][None, :] + (1.0 - a) * theta[:, 1][None, :]

    def inputs(self):
        return MultivariateNormal(np.array(self.mu), std=np.array(self.sigma))

    @property
    def limit(self) -> LimitState:
        return LimitState(self.delta)

    @property
    def x_min_std(self) -> float:
        s1, s2 = self.sigma
        return s2**2 / (s1**2 + s2**2)

    def mean(self, x: np.ndarray) -> np.ndarray:
        return x * self.mu[0] + (1.0 - x) * self.mu[1]

    def std(self, x: np.ndarray) -> np.ndarray:
        return np.sqrt((x * self.sigma[0]) ** 2 + ((1.0 - x) * self.sigma[1]) ** 2)

    def pf(self, x: np.ndarray) -> np.ndarray:
        return norm.cdf((self.mean(x) - self.delta) / self.std(x))

    def x_of_mean(self, m: np.ndarray) -> np.ndarray:
        return (self.mu[1] - m) / (self.mu[1] - self.mu[0])

    def reliable_interval(self, p_target: float) -> tuple[float, float]:
        """``[x_a, x_b]``: the part of the Pareto set with ``P_f <= p_target``."""
        beta = norm.isf(p_target)

        def h(x):
            return float(self.mean(x) + beta * self.std(x) - self.delta)

        xs = np.linspace(self.x_min_std, 1.0, 2001)
        hv = self.mean(xs) + beta * self.std(xs) - self.delta
        i = int(np.argmin(hv))
        if hv[i] > 0:
            raise ValueError(f"no reliable design for p_target = {p_target}")
        xa = self.x_min_std if hv[0] <= 0 else brentq(h, self.x_min_std, xs[i])
        xb = 1.0 if hv[-1] <= 0 else brentq(h, xs[i], 1.0)
        return xa, xb
