"""First-order second-moment (FOSM) method: mean and standard deviation by linearisation.

``μ_y ≈ y(x, μ_θ)``, ``σ_y² ≈ ∇yᵀ Σ_θ ∇y`` with central differences in θ space (step
``rel_step · σ_i``), and ``P_f ≈ Φ(−β_C)`` with the Cornell index ``β_C = g(μ_y) / σ_y``
(exact for a linear response of normal inputs). One model call of ``2m + 1`` θ points covers all
designs. No standard errors (NaN) and no interval (NaN).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import special

from surrogate_rbrdo.core.protocols import Estimate, LimitState
from surrogate_rbrdo.core.validate import check_positive
from surrogate_rbrdo.estimators._common import check_args, evaluate, make_estimate
from surrogate_rbrdo.estimators.registry import ESTIMATORS


@ESTIMATORS.register("fosm")
@dataclass(frozen=True)
class FOSM:
    """First-order second-moment estimator, vectorised over designs.

    Parameters
    ----------
    rel_step : float
        Central-difference step as a fraction of each input's standard deviation.

    Examples
    --------
    >>> from surrogate_rbrdo.core import LimitState
    >>> from surrogate_rbrdo.uncertainty import MultivariateNormal
    >>> inputs = MultivariateNormal([1.0, 2.0], std=[0.3, 0.4])
    >>> resp = lambda x, t: (t[:, 0] + t[:, 1])[None, :] + x[:, :1]
    >>> est = FOSM().estimate(resp, inputs, LimitState(4.0), np.zeros((1, 1)),
    ...                       rng=np.random.default_rng(0))
    >>> round(float(est.mean[0]), 9), round(float(est.std[0]), 9)
    (3.0, 0.5)
    """

    rel_step: float = 1e-3

    def __post_init__(self) -> None:
        check_positive("rel_step", self.rel_step)

    def estimate(self, response: Any, inputs: Any, limit: LimitState, x: np.ndarray, *,
                 rng: np.random.Generator, u: np.ndarray | None = None) -> Estimate:
        """Linearise around the input mean for every design (``rng`` and ``u`` unused)."""
        x, _ = check_args(inputs, limit, x, rng, u)
        mu = np.asarray(inputs.mean, dtype=float)
        cov = np.asarray(inputs.cov, dtype=float)
        m = mu.size
        h = self.rel_step * np.sqrt(np.diag(cov))
        pts = np.vstack([mu, mu + np.diag(h), mu - np.diag(h)])
        y = evaluate(response, x, pts)
        grad = (y[:, 1:m + 1] - y[:, m + 1:]) / (2.0 * h)
        mean = y[:, 0]
        std = np.sqrt(np.maximum(np.einsum("pi,ij,pj->p", grad, cov, grad), 0.0))
        g = limit.g(mean)
        with np.errstate(divide="ignore", invalid="ignore"):
            inf = np.where(g >= 0, np.inf, -np.inf)
            beta = np.where(std > 0, g / np.where(std > 0, std, 1.0), inf)
        pf = special.ndtr(-beta)
        return make_estimate("fosm", y.size, x.shape[0], mean=mean, std=std, pf=pf,
                             diagnostics={"beta_cornell": beta, "gradient": grad})
