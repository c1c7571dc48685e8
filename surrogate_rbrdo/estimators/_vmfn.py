"""Von Mises–Fisher–Nakagami mixtures for cross-entropy importance sampling in standard space.

A point ``u = r a`` is described by its direction ``a = u/‖u‖`` on the unit sphere and its
radius ``r = ‖u‖``; each component draws the direction from a von Mises–Fisher distribution
``vMF(μ, κ)`` and the radius from a Nakagami distribution ``Nakagami(n, Ω)`` (Wang & Song 2016,
*Structural Safety* 59; Papaioannou, Geyer & Straub 2019, *Reliability Engineering & System
Safety* 191, 106564). The density in ``u`` is ``f_R(r) f_A(a) / r^{m−1}``. The standard normal
itself is the component ``κ = 0`` (uniform directions), ``n = m/2``, ``Ω = m`` (the χ
distribution), so ``φ`` is one member of the family. Unlike a Gaussian mixture, the number of
parameters per component grows like ``m``, not ``m²``, and a component concentrates on a
*direction* — what a failure domain far from the origin looks like in many dimensions.

Fit: weighted EM, with the closed-form updates of the mean direction, Banerjee et al.'s (2005,
*JMLR* 6) approximation ``κ ≈ R̄(m − R̄²)/(1 − R̄²)`` and the moment estimates of the Nakagami
parameters (``Ω = E[r²]``, ``n = Ω²/Var(r²)``, at least 1/2). Sampling of vMF directions:
Wood (1994, *Comm. Stat. Simul.* 23).

>>> mix = standard_normal_vmfn(3)
>>> u = np.array([[0.3, -1.0, 2.0]])
>>> bool(np.isclose(mix.logpdf(u)[0], -0.5 * u @ u.T - 1.5 * np.log(2 * np.pi)))
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import special

from surrogate_rbrdo.estimators._gmm import _ess, _lse, e_step

#: smallest concentration handled by the general formula (below: the uniform limit)
KAPPA_MIN = 1e-8


@dataclass(frozen=True)
class VMFNMixture:
    """``Σ π_k vMF(μ_k, κ_k) × Nakagami(n_k, Ω_k)``: ``weights (K,)``, ``mu (K, m)`` (unit
    rows), ``kappa, shape, omega (K,)``."""

    weights: np.ndarray
    mu: np.ndarray
    kappa: np.ndarray
    shape: np.ndarray
    omega: np.ndarray

    def component_logpdf(self, u: np.ndarray) -> np.ndarray:
        """``log π_k + log q_k(u)`` for every row and component, shape ``(n, K)``."""
        m = u.shape[1]
        r = np.maximum(np.linalg.norm(u, axis=1), 1e-300)
        a = u / r[:, None]
        lr = np.log(r)
        out = (np.log(self.weights)[None, :] + _log_vmf_norm(self.kappa, m)[None, :]
               + self.kappa[None, :] * (a @ self.mu.T))
        n, om = self.shape[None, :], self.omega[None, :]
        out += (np.log(2.0) + n * np.log(n / om) - special.gammaln(n) + (2 * n - 1) * lr[:, None]
                - n * r[:, None] ** 2 / om)
        return out - (m - 1) * lr[:, None]

    def logpdf(self, u: np.ndarray) -> np.ndarray:
        """Log-density at the rows of ``u``."""
        return _lse(self.component_logpdf(u))

    def sample(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """Draw ``n`` points."""
        m = self.mu.shape[1]
        comp = rng.choice(self.weights.size, size=n, p=self.weights)
        u = np.empty((n, m))
        for k in np.unique(comp):
            idx = np.flatnonzero(comp == k)
            a = sample_vmf(self.mu[k], float(self.kappa[k]), idx.size, rng)
            r2 = rng.gamma(self.shape[k], self.omega[k] / self.shape[k], size=idx.size)
            u[idx] = np.sqrt(r2)[:, None] * a
        return u

    def with_defensive(self, a: float) -> VMFNMixture:
        """``(1 − a)·self + a·φ`` (``φ`` as the member ``κ = 0, n = m/2, Ω = m``)."""
        if a <= 0:
            return self
        m = self.mu.shape[1]
        e1 = np.zeros((1, m))
        e1[0, 0] = 1.0
        return VMFNMixture(np.append((1 - a) * self.weights, a), np.vstack([self.mu, e1]),
                           np.append(self.kappa, 0.0), np.append(self.shape, m / 2.0),
                           np.append(self.omega, float(m)))


def standard_normal_vmfn(m: int) -> VMFNMixture:
    """The standard normal ``N(0, I_m)`` as a one-component vMFN mixture."""
    e1 = np.zeros((1, m))
    e1[0, 0] = 1.0
    return VMFNMixture(np.ones(1), e1, np.zeros(1), np.array([m / 2.0]), np.array([float(m)]))


def _log_vmf_norm(kappa: np.ndarray, m: int) -> np.ndarray:
    """``log C_m(κ)``, ``C_m = κ^{m/2−1} / ((2π)^{m/2} I_{m/2−1}(κ))``; the uniform density on the
    sphere, ``Γ(m/2) / (2 π^{m/2})``, for ``κ → 0``."""
    nu = 0.5 * m - 1.0
    k = np.maximum(np.asarray(kappa, dtype=float), KAPPA_MIN)
    ive = special.ive(nu, k)
    with np.errstate(divide="ignore"):
        # log I_ν(κ); where ive underflows (small κ, large ν) the first term of its series
        log_iv = np.where(ive > 0, np.log(np.where(ive > 0, ive, 1.0)) + k,
                          nu * np.log(0.5 * k) - special.gammaln(nu + 1.0))
    general = nu * np.log(k) - 0.5 * m * np.log(2 * np.pi) - log_iv
    uniform = special.gammaln(0.5 * m) - np.log(2.0) - 0.5 * m * np.log(np.pi)
    return np.where(np.asarray(kappa) > KAPPA_MIN, general, uniform)


def sample_vmf(mu: np.ndarray, kappa: float, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` unit vectors from ``vMF(μ, κ)`` (Wood 1994; uniform for ``κ ≈ 0``).

    >>> a = sample_vmf(np.array([0.0, 0.0, 1.0]), 50.0, 4000, np.random.default_rng(0))
    >>> round(float(a[:, 2].mean()), 2)          # E[μ·a] = coth κ − 1/κ = 0.98
    0.98
    """
    m = mu.size
    z = rng.standard_normal((n, m))
    if kappa <= KAPPA_MIN:
        return z / np.linalg.norm(z, axis=1, keepdims=True)
    if m == 1:          # the "sphere" {−1, +1}: P(a = μ) = e^κ / (e^κ + e^−κ)
        plus = rng.random(n) < 0.5 * (1.0 + np.tanh(kappa))
        return np.where(plus, 1.0, -1.0)[:, None] * mu[None, :]
    b = (m - 1) / (2 * kappa + np.sqrt(4 * kappa**2 + (m - 1) ** 2))
    x0 = (1 - b) / (1 + b)
    c = kappa * x0 + (m - 1) * np.log(1 - x0**2)
    w = np.empty(n)
    todo = np.arange(n)
    while todo.size:
        zz = rng.beta(0.5 * (m - 1), 0.5 * (m - 1), size=todo.size)
        ww = (1 - (1 + b) * zz) / (1 - (1 - b) * zz)
        ok = kappa * ww + (m - 1) * np.log(1 - x0 * ww) - c >= np.log(rng.random(todo.size))
        w[todo[ok]] = ww[ok]
        todo = todo[~ok]
    v = z - np.outer(z @ mu, mu)                  # uniform direction orthogonal to μ
    v /= np.maximum(np.linalg.norm(v, axis=1, keepdims=True), 1e-300)
    return w[:, None] * mu[None, :] + np.sqrt(np.maximum(1 - w**2, 0.0))[:, None] * v


def _m_step(u: np.ndarray, wr: np.ndarray) -> VMFNMixture:
    """Weighted M-step: ``wr (n, K)`` = weight × responsibility. The concentration is capped
    (``R̄ ≤ 1 − 10⁻⁶``) and the Nakagami shape kept in ``[1/2, 10⁴]``."""
    m = u.shape[1]
    r = np.maximum(np.linalg.norm(u, axis=1), 1e-300)
    a = u / r[:, None]
    nk = wr.sum(axis=0)
    s = wr.T @ a                                              # (K, m)
    norm = np.linalg.norm(s, axis=1)
    mu = s / np.maximum(norm, 1e-300)[:, None]
    rbar = np.clip(norm / nk, 0.0, 1.0 - 1e-6)
    # Banerjee et al.'s approximation; exact (tanh κ = R̄) on the two-point "sphere" of m = 1
    kappa = np.arctanh(rbar) if m == 1 else rbar * (m - rbar**2) / (1 - rbar**2)
    r2 = r * r
    omega = (wr.T @ r2) / nk
    var = (wr.T @ r2**2) / nk - omega**2
    shape = np.clip(omega**2 / np.maximum(var, 1e-300), 0.5, 1e4)
    return VMFNMixture(nk / nk.sum(), mu, kappa, shape, omega)


def fit_vmfn(u: np.ndarray, logw: np.ndarray, n_components: int, rng: np.random.Generator,
             n_iter: int = 30) -> VMFNMixture:
    """Weighted EM fit to points ``u`` with log-weights ``logw``; ``K ≤ n_components`` chosen by
    the BIC on the effective sample size (``m + 2`` parameters per component), each ``K`` fitted
    from three seedings.

    >>> rng = np.random.default_rng(0)
    >>> u = np.vstack([rng.standard_normal((300, 5)) * 0.3 + 4 * np.eye(5)[0],
    ...                rng.standard_normal((300, 5)) * 0.3 - 4 * np.eye(5)[0]])
    >>> fit = fit_vmfn(u, np.zeros(600), 3, rng)
    >>> fit.weights.size, np.round(np.sort(fit.mu[:, 0]), 2).tolist()
    (2, [-1.0, 1.0])
    """
    w = np.exp(logw - logw.max())
    w /= w.sum()
    n, m = u.shape
    n_eff = max(_ess(w), 2.0)
    best = _m_step(u, w[:, None])

    def bic(mix: VMFNMixture) -> float:
        ll = float(w @ mix.logpdf(u)) * n_eff
        return -2.0 * ll + (mix.weights.size * (m + 3) - 1) * np.log(n_eff)

    best_bic = bic(best)
    for k in range(2, min(n_components, n) + 1):
        # EM from three seedings (a k-means++ seeding can put two centres in one mode)
        mix = min((_em(u, w, k, rng, n_iter) for _ in range(3)), key=bic)
        b = bic(mix)
        if b >= best_bic:
            break
        best, best_bic = mix, b
    return best


def _em(u: np.ndarray, w: np.ndarray, k: int, rng: np.random.Generator,
        n_iter: int) -> VMFNMixture:
    """Weighted EM with ``k`` components, seeded by weighted k-means++ on the directions."""
    n = u.shape[0]
    a = u / np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-300)
    centres = [a[rng.choice(n, p=w)]]
    for _ in range(1, k):
        d = np.min([1.0 - a @ c for c in centres], axis=0).clip(0.0) * w
        if d.sum() <= 0:
            break
        centres.append(a[rng.choice(n, p=d / d.sum())])
    resp = np.zeros((n, len(centres)))
    resp[np.arange(n), np.argmax(a @ np.array(centres).T, axis=1)] = 1.0
    prev, mix = -np.inf, None
    m = u.shape[1]
    for _ in range(n_iter):
        wr = w[:, None] * resp
        # a component needs at least 2(m + 2) effective points (its m + 2 parameters)
        ess = wr.sum(axis=0) ** 2 / np.maximum(np.sum(wr * wr, axis=0), 1e-300)
        keep = ess >= 2 * (m + 2)
        if not keep.any():
            keep = ess == ess.max()
        mix = _m_step(u, wr[:, keep])
        resp, obj = e_step(mix, u, w)
        if obj - prev < 1e-5 * max(1.0, abs(obj)):
            break
        prev = obj
    return mix


__all__ = ["VMFNMixture", "fit_vmfn", "sample_vmf", "standard_normal_vmfn"]
