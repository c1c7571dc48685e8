"""Adaptive importance sampling by cross-entropy with Gaussian mixtures (CE-GM).

Levels ``k = 1, 2, …`` draw ``n_per_level`` points from ``h_k`` (``h_1 = φ``), set the
intermediate threshold ``γ_k = max(0, ρ-quantile of G)`` and refit ``h_{k+1}`` to the points with
``G ≤ γ_k``, weighted by ``φ/h_k`` (the cross-entropy update, Rubinstein & Kroese 2004; Gaussian
mixtures as in Geyer, Papaioannou & Straub 2019, *Struct. Safety* 76). The mixture is fitted by
weighted EM with up to ``n_components`` components, their number chosen by BIC, covariances
shrunk towards a well-conditioned target (no collapse in 10-D). Once ``γ_k = 0`` a fresh sample
of ``n_final`` points is drawn from the defensive mixture ``q = (1 − a) h + a N(0, c I)``
(Hesterberg 1995) with ``c ≥ 1`` the mean square radius of ``h`` per dimension, so every failure
branch has a sampling density no thinner than a widened ``φ``. The final estimate is unbiased
for any failure domain (``q`` has full support); starting from ``φ`` the mixture grows over all
branches of a series system instead of locking onto one design point, and when the mean point
fails (``P_f > 0.5``) adaptation stops at once.

``pf_se`` is the standard error of the final, independent sample (the adaptation levels only
choose the density, so the estimate and its error are those of one plain IS run). Its weights'
tail is checked: a Pareto ``k̂ > 0.7`` (:mod:`._tail`; e.g. Gaussian cross-entropy in 100
dimensions, where the weights degenerate) raises an :class:`~._tail.EstimatorWarning`.
Designs that never fail: see ``on_failure``. Points outside the model's physical domain count
as failures (:mod:`._common`).

``mean``/``std`` of ``y`` come from the level-1 sample (plain Monte Carlo, ``n_per_level``
points, or the fixed ``u``); the levels after it use ``rng``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from surrogate_rbrdo.core.protocols import Estimate, LimitState
from surrogate_rbrdo.core.validate import check_choice, check_int, check_range
from surrogate_rbrdo.estimators._common import LimitStateU, log_std_normal, make_estimate
from surrogate_rbrdo.estimators._gmm import GaussianMixture, fit_mixture
from surrogate_rbrdo.estimators._levels import (
    ON_FAILURE,
    LevelResult,
    StallGuard,
    interval,
    run_per_design,
)
from surrogate_rbrdo.estimators._tail import EstimatorWarning, pareto_khat
from surrogate_rbrdo.estimators.importance import KHAT_LIMIT, is_weights_estimate
from surrogate_rbrdo.estimators.registry import ESTIMATORS


@ESTIMATORS.register("ais")
@dataclass(frozen=True)
class CrossEntropyIS:
    """Cross-entropy adaptive importance sampling (Gaussian mixture, defensive component).

    Parameters
    ----------
    n_per_level : int
        Points per adaptation level (level 0 uses ``u`` when given).
    rho : float
        Quantile defining the intermediate thresholds, in (0, 0.5].
    n_final : int
        Points of the final IS estimate.
    n_components : int
        Largest number of mixture components (the BIC picks 1..n_components).
    defensive : float
        Weight ``a`` of the widened standard normal in the final mixture, in [0, 0.999];
        0 switches it off.
    max_levels : int
    on_failure : {"bound", "raise", "nan"}
        When ``max_levels`` is reached (or the thresholds stall) before ``γ = 0``: report the
        IS estimate of ``P(G ≤ γ_last)`` of the last level as an upper bound
        (``status = "not_reached"``), raise ``ModelError``, or give NaN.
    ci_level : float

    Examples
    --------
    >>> from surrogate_rbrdo.estimators.problems import series_four_branch
    >>> prob = series_four_branch(7.0)
    >>> est = CrossEntropyIS().estimate(prob.response, prob.inputs, prob.limit, prob.x,
    ...                                 rng=np.random.default_rng(1))
    >>> bool(abs(est.pf[0] - prob.pf_exact[0]) < 4 * est.pf_se[0])
    True
    """

    n_per_level: int = 1000
    rho: float = 0.1
    n_final: int = 2000
    n_components: int = 4
    defensive: float = 0.1
    max_levels: int = 30
    on_failure: str = "bound"
    ci_level: float = 0.95

    def __post_init__(self) -> None:
        check_int("n_per_level", self.n_per_level, minimum=20)
        if check_range("rho", self.rho, 0.0, 0.5) == 0.0:
            raise ValueError("rho = 0.0 is not allowed: must lie in (0, 0.5]")
        check_int("n_final", self.n_final, minimum=2)
        check_int("n_components", self.n_components, minimum=1)
        check_range("defensive", self.defensive, 0.0, 0.999)
        check_int("max_levels", self.max_levels, minimum=1)
        check_choice("on_failure", self.on_failure, ON_FAILURE)
        check_range("ci_level", self.ci_level, 0.0, 1.0, inclusive=False)

    def _one(self, G: LimitStateU, m: int, u0: np.ndarray | None, rng: np.random.Generator
             ) -> LevelResult:
        h = GaussianMixture(np.ones(1), np.zeros((1, m)), np.eye(m)[None])
        v = u0 if u0 is not None else rng.standard_normal((self.n_per_level, m))
        y0 = None
        level, stall = 0, StallGuard()
        for level in range(1, self.max_levels + 1):
            if level > 1:
                v = h.sample(self.n_per_level, rng)
            g = G(v)
            if y0 is None:
                y0 = G.last_y.copy()
            logw = log_std_normal(v) - h.logpdf(v)
            # "lower": no interpolation between -inf values (points outside the domain)
            gamma = max(float(np.quantile(g, self.rho, method="lower")), 0.0)
            elite = g <= gamma if gamma > 0 else g < 0
            if elite.sum() < 2:
                elite = g <= gamma
            if gamma > 0 and (stall(gamma, level, g) or level == self.max_levels):
                # not reached: IS estimate of P(G <= γ) from this level, an upper bound of P_f
                pf, se, ess = is_weights_estimate(g <= gamma, logw)
                return LevelResult(pf, se, ess, level, False, y0)
            h = fit_mixture(v[elite], logw[elite], self.n_components, rng)
            if gamma == 0.0:
                break
        n, a = self.n_final, self.defensive
        # defensive component N(0, c I), c = mean square radius of h per dimension (>= 1)
        second = h.weights @ (np.sum(h.means**2, axis=1)
                              + np.einsum("kij,kij->k", h.chols, h.chols))
        c = max(1.0, float(second) / m)
        pick = rng.random(n) < a
        v = np.where(pick[:, None], np.sqrt(c) * rng.standard_normal((n, m)), h.sample(n, rng))
        lq = h.logpdf(v)
        if a > 0:
            ld = log_std_normal(v / np.sqrt(c)) - 0.5 * m * np.log(c)
            lq = np.logaddexp(np.log1p(-a) + lq, np.log(a) + ld)
        fail = G(v) < 0
        logw = log_std_normal(v) - lq
        pf, se, _ = is_weights_estimate(fail, logw)
        khat = pareto_khat(np.where(fail, np.exp(np.where(fail, logw, 0.0)), 0.0))
        return LevelResult(pf, se, khat, level, True, y0)

    def estimate(self, response: Any, inputs: Any, limit: LimitState, x: np.ndarray, *,
                 rng: np.random.Generator, u: np.ndarray | None = None) -> Estimate:
        """Adapt and estimate for every design of ``x``."""
        r = run_per_design(
            self, response, inputs, limit, x, rng, u, what="cross-entropy IS",
            why="the thresholds stop decreasing when the response never fails",
            advice="increase max_levels or n_per_level, or pass on_failure='bound' for an "
                   "upper bound")
        mc = r.moments
        khat = np.where(r.status == "converged", r.extra, np.nan)
        heavy = np.flatnonzero(np.nan_to_num(khat, nan=-np.inf) > KHAT_LIMIT)
        if heavy.size:
            warnings.warn(
                f"cross-entropy IS: heavy-tailed final weights for design(s) "
                f"{heavy[:10].tolist()} (Pareto k = {np.round(khat[heavy[:10]], 2).tolist()} > "
                f"{KHAT_LIMIT}): the fitted density misses part of the failure domain (e.g. in "
                "high dimension), pf_se is unreliable; use 'subset'",
                EstimatorWarning, stacklevel=2)
        return make_estimate(
            "ais", r.calls, r.pf.size, mean=mc.mean, std=mc.std, mean_se=mc.mean_se,
            std_se=mc.std_se, pf=r.pf, pf_se=r.se,
            pf_ci=interval(r.pf, r.se, r.status, self.ci_level),
            diagnostics={"ci_level": self.ci_level, "ci_method": "normal", "pareto_k": khat,
                         "levels": r.levels, "converged": r.status == "converged",
                         "status": r.status, "n_outside_domain": r.n_outside},
        )
