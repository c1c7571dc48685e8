"""Weighted Gaussian mixtures for cross-entropy importance sampling (fit, log-density, sample).

The fit is a weighted EM started from a weighted k-means++ seeding. Each covariance is shrunk
towards a well-conditioned target with weight ``m / (m + ESS)`` (``ESS`` = effective number of
points of the component), so a component fitted to a few heavily weighted points in many
dimensions cannot collapse.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.linalg import solve_triangular


@dataclass(frozen=True)
class GaussianMixture:
    """Mixture ``Σ π_k N(μ_k, L_k L_kᵀ)``: ``weights (K,)``, ``means (K, m)``, ``chols (K, m, m)``.

    >>> gm = GaussianMixture(np.ones(1), np.zeros((1, 2)), np.eye(2)[None])
    >>> round(float(gm.logpdf(np.zeros((1, 2)))[0]), 6)   # log(1 / 2π)
    -1.837877
    """

    weights: np.ndarray
    means: np.ndarray
    chols: np.ndarray

    def component_logpdf(self, v: np.ndarray) -> np.ndarray:
        """``log π_k + log N(v; μ_k, Σ_k)`` for every row and component, shape ``(n, K)``."""
        m = v.shape[1]
        out = np.empty((v.shape[0], self.weights.size))
        for k in range(self.weights.size):
            z = solve_triangular(self.chols[k], (v - self.means[k]).T, lower=True,
                                 check_finite=False)
            out[:, k] = (np.log(self.weights[k]) - 0.5 * np.sum(z * z, axis=0)
                         - np.log(np.diag(self.chols[k])).sum() - 0.5 * m * np.log(2 * np.pi))
        return out

    def logpdf(self, v: np.ndarray) -> np.ndarray:
        """Log-density at the rows of ``v``."""
        return _lse(self.component_logpdf(v))

    def sample(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """Draw ``n`` points."""
        comp = rng.choice(self.weights.size, size=n, p=self.weights)
        z = rng.standard_normal((n, self.means.shape[1]))
        return self.means[comp] + np.einsum("nij,nj->ni", self.chols[comp], z)


def _lse(a: np.ndarray) -> np.ndarray:
    """Row-wise log-sum-exp of a finite ``(n, K)`` array."""
    mx = a.max(axis=1)
    return mx + np.log(np.exp(a - mx[:, None]).sum(axis=1))


def e_step(mix: Any, x: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, float]:
    """Responsibilities ``(n, K)`` of a mixture with ``component_logpdf`` and its weighted
    log-likelihood ``Σ w_i log q(x_i)``."""
    lp = mix.component_logpdf(x)
    ll = _lse(lp)
    return np.exp(lp - ll[:, None]), float(w @ ll)


def _ess(w: np.ndarray) -> float:
    s2 = float(np.sum(w * w))
    return float(w.sum() ** 2 / s2) if s2 > 0 else 0.0


def _shrunk_cov(x: np.ndarray, w: np.ndarray, mean: np.ndarray, target: np.ndarray
                ) -> np.ndarray:
    m = x.shape[1]
    d = x - mean
    cov = (d * (w / w.sum())[:, None]).T @ d
    lam = m / (m + _ess(w))
    return (1 - lam) * cov + lam * target


def _chol(cov: np.ndarray) -> np.ndarray:
    ridge = 1e-9 * max(float(np.trace(cov)) / cov.shape[0], 1e-12)
    for _ in range(10):
        try:
            return np.linalg.cholesky(cov + ridge * np.eye(cov.shape[0]))
        except np.linalg.LinAlgError:
            ridge *= 100
    return np.linalg.cholesky(np.eye(cov.shape[0]))


def fit_mixture(x: np.ndarray, logw: np.ndarray, n_components: int, rng: np.random.Generator,
                n_iter: int = 30) -> GaussianMixture:
    """Weighted EM fit to points ``x`` with log-weights ``logw``; ``K ≤ n_components`` by BIC.

    The BIC uses the effective sample size of the weights, so a single lump is fitted by one
    Gaussian and separated failure branches by several.
    """
    n, m = x.shape
    w = np.exp(logw - logw.max())
    w /= w.sum()
    gmean = w @ x
    gcov = _shrunk_cov(x, w, gmean, np.eye(m))
    best = GaussianMixture(np.ones(1), gmean[None], _chol(gcov)[None])
    n_eff = _ess(w)
    npar = m + m * (m + 1) / 2

    def bic(gm: GaussianMixture) -> float:
        ll = float(w @ gm.logpdf(x)) * n_eff
        return -2.0 * ll + (gm.weights.size * (npar + 1) - 1) * np.log(max(n_eff, 2.0))

    best_bic = bic(best)
    for k in range(2, min(n_components, n) + 1):
        gm = _em(x, w, k, gcov, rng, n_iter)
        b = bic(gm)
        if b >= best_bic:
            break          # more components stopped paying for themselves
        best, best_bic = gm, b
    return best


def _em(x: np.ndarray, w: np.ndarray, k_eff: int, gcov: np.ndarray, rng: np.random.Generator,
        n_iter: int) -> GaussianMixture:
    """Weighted EM with ``k_eff`` components from a weighted k-means++ seeding."""
    n = x.shape[0]
    # weighted k-means++ seeding
    centres = [x[rng.choice(n, p=w)]]
    for _ in range(1, k_eff):
        d2 = np.min([np.sum((x - c) ** 2, axis=1) for c in centres], axis=0) * w
        if d2.sum() <= 0:
            break
        centres.append(x[rng.choice(n, p=d2 / d2.sum())])
    c = np.array(centres)
    resp = np.zeros((n, len(c)))
    resp[np.arange(n), np.argmin(((x[:, None, :] - c[None]) ** 2).sum(-1), axis=1)] = 1.0
    prev = -np.inf
    gm = None
    for _ in range(n_iter):
        wr = w[:, None] * resp
        nk = wr.sum(0)
        keep = nk > 1e-8
        wr, nk = wr[:, keep], nk[keep]
        means = (wr.T @ x) / nk[:, None]
        chols = np.array([_chol(_shrunk_cov(x, wr[:, k], means[k], gcov))
                          for k in range(nk.size)])
        gm = GaussianMixture(nk / nk.sum(), means, chols)
        resp, obj = e_step(gm, x, w)
        if obj - prev < 1e-5 * max(1.0, abs(obj)):
            break
        prev = obj
    return gm
