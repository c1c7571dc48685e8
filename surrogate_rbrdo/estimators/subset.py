"""Subset simulation (Au & Beck 2001) with conditional sampling in standard space.

Level 0 is crude Monte Carlo with ``n_per_level`` points. Each following level keeps the
``p0 · N`` points with the smallest ``G`` as seeds, sets ``γ_k`` between the kept and the
rejected values, and grows one Markov chain of length ``1/p0`` from every seed with the
component-wise conditional-sampling kernel of Papaioannou et al. (2015):
``v' = ρ v + √(1−ρ²) ξ``, accepted if ``G(v') ≤ γ_k`` (reversible for ``φ`` restricted to
``{G ≤ γ_k}``, and free of the dimension problems of random-walk Metropolis). When at least
``p0 · N`` points fail, ``P_f = p0^k · (failures / N)``.

The coefficient of variation follows Au & Beck (2001, Eq. 29): per level
``δ_k² = (1−p_k)/(p_k N) (1+γ_k)`` with the chain correlation factor ``γ_k`` estimated from the
chains, summed over levels (levels treated as uncorrelated, as in the paper): ``pf_se`` is
``P_f √Σδ_k²``, a lower bound since the levels are in fact correlated (over 100 runs at
P_f ≈ 3e-7 and 1e-6 it matched the scatter: reported 0.41–0.44, observed 0.40–0.45; the P_f
distribution has a heavy right tail, so short series of runs can look worse).
``diagnostics["pf_cov_upper"] = Σδ_k`` is the fully-correlated bound (Au & Beck 2001). The
interval is ``P_f ± z·SE`` clipped to ``[0, 1]``. ``mean``/``std`` of ``y`` come from level 0.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from surrogate_rbrdo.core.protocols import Estimate, LimitState
from surrogate_rbrdo.core.validate import check_choice, check_int, check_range
from surrogate_rbrdo.estimators._common import (
    LimitStateU,
    make_estimate,
    normal_ci,
)
from surrogate_rbrdo.estimators._levels import StallGuard, run_per_design
from surrogate_rbrdo.estimators.registry import ESTIMATORS


def chain_gamma(ind: np.ndarray, p: float) -> float:
    """Au-Beck correlation factor from indicators ``ind`` of shape ``(n_chains, chain_len)``."""
    nc, ns = ind.shape
    n = nc * ns
    r0 = p * (1 - p)
    if r0 <= 0 or ns < 2:
        return 0.0
    gam = 0.0
    for tau in range(1, ns):
        r = float(np.sum(ind[:, : ns - tau] * ind[:, tau:])) / (n - tau * nc) - p * p
        gam += 2.0 * (1.0 - tau * nc / n) * r / r0
    return max(gam, 0.0)


@ESTIMATORS.register("subset")
@dataclass(frozen=True)
class SubsetSimulation:
    """Subset simulation for small failure probabilities.

    Parameters
    ----------
    n_per_level : int
        Samples per level ``N`` (``p0·N`` and ``1/p0`` must be integers; with ``u`` given, its
        row count is used).
    p0 : float
        Conditional probability of each level, in (0, 0.5].
    rho : float
        Correlation of the conditional-sampling proposal, in [0, 1).
    max_levels : int
    on_failure : {"raise", "nan"}
    ci_level : float

    Examples
    --------
    >>> from surrogate_rbrdo.estimators.problems import linear_standard
    >>> prob = linear_standard(beta=4.5, dim=10)
    >>> est = SubsetSimulation().estimate(prob.response, prob.inputs, prob.limit, prob.x,
    ...                                   rng=np.random.default_rng(3))
    >>> bool(abs(est.pf[0] - prob.pf_exact[0]) < 4 * est.pf_se[0])
    True
    """

    n_per_level: int = 1000
    p0: float = 0.1
    rho: float = 0.8
    max_levels: int = 20
    on_failure: str = "raise"
    ci_level: float = 0.95

    def __post_init__(self) -> None:
        check_int("n_per_level", self.n_per_level, minimum=10)
        check_range("p0", self.p0, 0.01, 0.5)
        if abs(1.0 / self.p0 - round(1.0 / self.p0)) > 1e-9:
            raise ValueError(f"p0 = {self.p0!r} is not allowed: 1/p0 must be an integer")
        check_range("rho", self.rho, 0.0, 0.999)
        check_int("max_levels", self.max_levels, minimum=1)
        check_choice("on_failure", self.on_failure, ("raise", "nan"))
        check_range("ci_level", self.ci_level, 0.0, 1.0, inclusive=False)

    def _one(self, G: LimitStateU, m: int, u0: np.ndarray | None, rng: np.random.Generator
             ) -> tuple[float, float, int, bool, np.ndarray]:
        v = u0 if u0 is not None else rng.standard_normal((self.n_per_level, m))
        n = v.shape[0]
        ns = int(round(1.0 / self.p0))
        nc = max(n // ns, 1)
        g = G(v)
        y0 = G.last_y.copy()
        pf, delta2, delta_sum = 1.0, 0.0, 0.0
        chains = None      # (nc, ns) values of G along the chains of the previous level
        stall = StallGuard()
        s = np.sqrt(1.0 - self.rho**2)
        for level in range(1, self.max_levels + 1):
            nf = int(np.count_nonzero(g < 0))
            final = nf >= nc
            if final:
                p_k, gam = nf / g.size, 0.0
            else:
                order = np.argsort(g, kind="stable")
                gam = 0.5 * (g[order[nc - 1]] + g[order[nc]])
                p_k = nc / g.size
                if stall(gam, level):  # thresholds stopped decreasing: no failure in reach
                    return np.nan, np.nan, np.nan, level, False, y0
            # chain correlation of the indicator of this level's event (Au & Beck 2001, Eq. 27)
            corr = 0.0
            if chains is not None:
                ind = (chains < 0) if final else (chains <= gam)
                corr = chain_gamma(ind.astype(float), p_k)
            d2 = (1 - p_k) / (p_k * g.size) * (1 + corr)
            delta2 += d2
            delta_sum += np.sqrt(d2)
            pf *= p_k
            if final:
                return pf, pf * np.sqrt(delta2), delta_sum, level, True, y0
            cur_v, cur_g = v[order[:nc]], g[order[:nc]]
            chain_v, chain_g = [cur_v], [cur_g]
            for _ in range(ns - 1):
                cand = self.rho * cur_v + s * rng.standard_normal(cur_v.shape)
                gc = G(cand)
                acc = gc <= gam
                cur_v = np.where(acc[:, None], cand, cur_v)
                cur_g = np.where(acc, gc, cur_g)
                chain_v.append(cur_v)
                chain_g.append(cur_g)
            v = np.concatenate(chain_v)                   # (ns*nc, m), step-major
            g = np.concatenate(chain_g)
            chains = np.stack(chain_g, axis=1)            # (nc, ns)
        return np.nan, np.nan, np.nan, self.max_levels, False, y0

    def estimate(self, response: Any, inputs: Any, limit: LimitState, x: np.ndarray, *,
                 rng: np.random.Generator, u: np.ndarray | None = None) -> Estimate:
        """Run subset simulation for every design of ``x``."""
        r = run_per_design(
            self, response, inputs, limit, x, rng, u, what="subset simulation",
            why="P_f < p0^max_levels, or the thresholds stopped decreasing because the "
                "response never fails",
            advice="increase max_levels or pass on_failure='nan'")
        mc = r.moments
        return make_estimate(
            "subset", r.calls, r.pf.size, mean=mc.mean, std=mc.std, mean_se=mc.mean_se,
            std_se=mc.std_se, pf=r.pf, pf_se=r.se, pf_ci=normal_ci(r.pf, r.se, self.ci_level),
            diagnostics={"ci_level": self.ci_level, "ci_method": "normal", "levels": r.levels,
                         "converged": r.converged, "pf_cov_upper": r.extra},
        )
