"""The densities and the control-variate estimate of importance sampling at design points.

All log-densities here omit the common constant ``−(m/2) log 2π`` (``log φ(v) = −‖v‖²/2``).

* :class:`MixtureDraws` — stage 1: a deterministic mixture of ``N(u_k, I)`` at the design
  points (shares ``π_k ∝ Φ(−β_k)``) and a defensive *shell* (the standard normal outside the
  ball of radius ``R``), built on one standard-normal sample (common random numbers).
* :class:`ScaledGaussians` — stage 2: at each design point, a Gaussian fitted to the stage-1
  tail samples *in the FORM geometry*: a mean along ``α_k = u_k/β_k``, one spread along ``α_k``
  and one across it (three parameters: stable with a few hundred weighted samples in any
  dimension). It is the sample-based adaptive IS of Bucher (1988, *Structural Safety* 5,
  119–126), restricted as the cross-entropy update (Rubinstein & Kroese 2017, §8.2) of that
  family: on a curved limit state the optimal density is narrower than ``N(u*, I)`` along
  ``α`` and, for a convex (concave) surface, narrower (wider) across it.
* :func:`cv_estimate` — IS with the design points' half-spaces as control variates.

>>> _largest_remainder(10, np.array([0.5, 0.3, 0.2])).tolist()
[5, 3, 2]
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import special, stats

from surrogate_rbrdo.estimators._gmm import _ess
from surrogate_rbrdo.estimators._tail import pareto_khat

#: the shell is used where it can be expected to find this many failures of a second region
MIN_SHELL_HITS = 5.0


def is_weights_estimate(fail: np.ndarray, logw: np.ndarray) -> tuple[float, float, float]:
    """``(pf, se, ess)`` from failure indicators and log-weights of a plain IS sample.

    The mean of the weights can exceed 1 when P_f is close to 1 (review of issue 13: 1.0027
    for P_f = Φ(4)); ``pf`` is clipped to 1, a projection onto ``[0, 1]`` that can only move
    the estimate closer to any probability, ``se`` is that of the unclipped mean.

    >>> is_weights_estimate(np.array([True, True]), np.log(np.array([1.2, 1.0])))[0]
    1.0
    """
    n = fail.size
    w = np.where(fail, np.exp(np.where(fail, logw, 0.0)), 0.0)
    pf = min(float(w.mean()), 1.0)
    se = float(w.std(ddof=1) / np.sqrt(n)) if n > 1 else np.nan
    return pf, se, _ess(w)


@dataclass(frozen=True)
class ControlVariateResult:
    """Control-variate IS estimate of a tail probability and its diagnostics."""

    p: float
    se: float
    coef: np.ndarray
    ess: float
    khat: float
    n_disagree: int


def cv_estimate(tail: np.ndarray, half: np.ndarray, logw: np.ndarray, beta: Any,
                w_floor: float) -> ControlVariateResult:
    """P(tail) by IS with the half-space indicators ``half`` ``(N,)`` or ``(N, K)`` (known means
    ``Φ(−|β_k|)``) as control variates (least-squares coefficients, cross-fitted on two halves
    of the sample; Rubinstein & Kroese 2017, §5.3).

    ``pf_se`` is the sample standard error of ``Y − c·C``, floored by
    ``w_floor · √(p̃(1 − p̃)/N)``, ``p̃ = 1/(N + 2)`` (Laplace's rule for an event not seen in
    ``N`` trials) with ``w_floor`` the largest weight at a design point: where no sample fell
    in the region where the tail and the half-spaces disagree, the unseen disagreement still
    counts.

    >>> rng = np.random.default_rng(0)
    >>> ustar = np.array([3.0, 0.0])
    >>> v = rng.standard_normal((500, 2)) + ustar
    >>> logw = -v @ ustar + 0.5 * ustar @ ustar
    >>> half = v @ ustar >= ustar @ ustar
    >>> r = cv_estimate(half.copy(), half, logw, 3.0, np.exp(-4.5))   # linear: exact
    >>> bool(np.isclose(r.p, special.ndtr(-3.0))), r.n_disagree, bool(0 < r.se / r.p < 0.02)
    (True, 0, True)
    """
    n = tail.size
    half = half.reshape(n, -1)
    beta = np.atleast_1d(np.asarray(beta, dtype=float))
    w = np.exp(logw)
    y = np.where(tail, w, 0.0)
    c = np.where(half, w[:, None], 0.0)
    mu = special.ndtr(-np.abs(beta))
    # cross-fitted coefficients (two folds, each corrected with the other's): a coefficient
    # fitted on the points it corrects biases the estimate towards them and shrinks its error
    # (measured on the four-branch system: 0.19 SE of bias, scatter 1.2 x the reported SE)
    fold = np.arange(n) % 2
    r = y.copy()
    for f in (0, 1) if n >= 8 else ():
        r[fold == f] -= (c[fold == f] - mu) @ _cv_coef(y[fold != f], c[fold != f])
    p = float(r.mean())
    coef = _cv_coef(y, c)
    se = float(r.std(ddof=1) / np.sqrt(n)) if n > 1 else np.nan
    p_tilde = 1.0 / (n + 2.0)
    floor = float(w_floor * np.sqrt(p_tilde * (1.0 - p_tilde) / n))
    return ControlVariateResult(min(max(p, 0.0), 1.0), max(se, floor), coef, _ess(y),
                                pareto_khat(y), int(np.count_nonzero(tail != half.any(1))))


def _cv_coef(y: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Least-squares control-variate coefficients of ``y`` on the columns of ``c``."""
    coef = np.zeros(c.shape[1])
    use = c.var(axis=0, ddof=1) > 0 if len(y) > 1 else np.zeros(c.shape[1], bool)
    if use.any():
        cc = np.atleast_2d(np.cov(c[:, use], rowvar=False, ddof=1))
        cy = np.array([np.cov(c[:, k], y, ddof=1)[0, 1] for k in np.flatnonzero(use)])
        coef[use] = np.linalg.lstsq(cc, cy, rcond=1e-12)[0]
    return coef


@dataclass(frozen=True)
class MixtureDraws:
    """Stage 1 on one standard-normal sample ``u`` (no new draws: the estimate stays a function
    of ``u``, common random numbers across designs).

    A deterministic mixture (Owen & Zhou 2000): the first ``round(a·N)`` rows go to the
    defensive shell — each keeps its direction ``u/‖u‖`` and its radius quantile
    ``q = P(χ²_m ≥ ‖u‖²)``, uniform and independent of the direction — and the others, in
    consecutive blocks of sizes proportional to ``shares``, are shifted to the centres; every
    point is weighted by the full mixture density (unbiased).
    """

    centres: np.ndarray
    shares: np.ndarray
    radius: float
    a: float

    def points(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Points ``v`` built from ``u`` and the component of each row (``−1``: the shell)."""
        n, m = u.shape
        r2 = np.einsum("ij,ij->i", u, u)
        norm = np.sqrt(r2)[:, None]
        pick = np.arange(n) < int(round(self.a * n))
        main = np.flatnonzero(~pick)
        comp = np.full(n, -1)
        comp[main] = np.repeat(np.arange(self.shares.size),
                               _largest_remainder(main.size, self.shares))
        s_r = float(stats.chi2.sf(self.radius**2, m))
        r = np.sqrt(stats.chi2.isf(stats.chi2.sf(r2, m) * s_r, m))
        shell = r[:, None] * u / np.where(norm > 0, norm, 1.0)
        return np.where(pick[:, None], shell, u + self.centres[np.maximum(comp, 0)]), comp

    def logpdf(self, v: np.ndarray) -> np.ndarray:
        """Log-density of the mixture (without the ``(2π)^{−m/2}`` constant)."""
        m = v.shape[1]
        lphi = -0.5 * np.einsum("ij,ij->i", v, v)
        # log φ(v − c_k) = log φ(v) + c_k·v − ‖c_k‖²/2
        lmain = v @ self.centres.T - 0.5 * np.sum(self.centres**2, axis=1) + lphi[:, None]
        terms = [np.log((1.0 - self.a) * self.shares)[None, :] + lmain]
        if self.a > 0:
            s_r = float(stats.chi2.sf(self.radius**2, m))
            with np.errstate(divide="ignore"):
                lshell = np.where(np.linalg.norm(v, axis=1) >= self.radius,
                                  lphi - np.log(s_r), -np.inf)
            terms.append((np.log(self.a) + lshell)[:, None])
        return special.logsumexp(np.hstack(terms), axis=1)


@dataclass(frozen=True)
class ScaledGaussians:
    """Stage 2: ``Σ π_k N(μ_k α_k, s_k² α_kα_kᵀ + t_k² (I − α_kα_kᵀ))`` (see the module
    docstring). Fields are ``(K,)`` arrays and ``alphas (K, m)``."""

    alphas: np.ndarray
    means: np.ndarray
    s_along: np.ndarray
    s_across: np.ndarray
    shares: np.ndarray

    @classmethod
    def fit(cls, v: np.ndarray, w_tail: np.ndarray, comp: np.ndarray, centres: np.ndarray,
            shares: np.ndarray) -> ScaledGaussians:
        """Weighted moments of the tail samples ``v`` (weights ``w_tail``, zero outside the tail)
        drawn from each component; spreads shrunk towards 1 and the mean towards ``β_k`` with
        weight ``3/(3 + ESS)`` (three parameters per component)."""
        m = v.shape[1]
        beta = np.linalg.norm(centres, axis=1)
        alphas = centres / np.where(beta > 0, beta, 1.0)[:, None]
        mean, s_al, s_ac = beta.copy(), np.ones(beta.size), np.ones(beta.size)
        for k in range(beta.size):
            w = np.where(comp == k, w_tail, 0.0)
            if w.sum() <= 0:
                continue
            w = w / w.sum()
            lam = 3.0 / (3.0 + _ess(w))
            a = v @ alphas[k]
            mu = float(w @ a)
            across = np.sum((v - np.outer(a, alphas[k])) ** 2, axis=1) / max(m - 1, 1)
            mean[k] = (1 - lam) * mu + lam * beta[k]
            s_al[k] = np.sqrt((1 - lam) * float(w @ (a - mu) ** 2) + lam)
            s_ac[k] = np.sqrt((1 - lam) * float(w @ across) + lam) if m > 1 else 1.0
        return cls(alphas, mean, s_al, s_ac, shares)

    def points(self, z: np.ndarray) -> np.ndarray:
        """Points from standard-normal rows ``z``, in blocks proportional to the shares."""
        comp = np.repeat(np.arange(self.shares.size),
                         _largest_remainder(z.shape[0], self.shares))
        al = self.alphas[comp]
        za = np.einsum("ij,ij->i", z, al)
        across = z - za[:, None] * al
        return ((self.means[comp] + self.s_along[comp] * za)[:, None] * al
                + self.s_across[comp][:, None] * across)

    def logpdf(self, v: np.ndarray) -> np.ndarray:
        """Log-density of the mixture (without the ``(2π)^{−m/2}`` constant)."""
        m = v.shape[1]
        a = v @ self.alphas.T                                        # (n, K)
        across2 = np.einsum("ij,ij->i", v, v)[:, None] - a**2
        lp = (np.log(self.shares)[None, :] - 0.5 * ((a - self.means) / self.s_along) ** 2
              - 0.5 * across2 / self.s_across**2 - np.log(self.s_along)
              - (m - 1) * np.log(self.s_across))
        return special.logsumexp(lp, axis=1)


def _largest_remainder(n: int, shares: np.ndarray) -> np.ndarray:
    """Integer counts summing to ``n`` in proportion to ``shares`` (largest remainder)."""
    raw = n * shares / shares.sum()
    counts = np.floor(raw).astype(int)
    counts[np.argsort(raw - counts)[::-1][: n - counts.sum()]] += 1
    return counts


def shell_share(defensive: float, shell: float, beta: float, m: int, n: int) -> float:
    """Share of the sample given to the shell: ``defensive`` where the shell can be expected to
    find at least ``MIN_SHELL_HITS`` failures of a second region as probable as the first
    (``defensive · n · Φ(−|β|) / P(χ²_m ≥ (shell β)²)``), else 0 — in many dimensions or at
    small P_f the shell is nearly all of ``φ`` and finds nothing.

    >>> shell_share(0.3, 0.9, 3.0, 2, 1000), shell_share(0.3, 0.9, 5.0, 10, 1000)
    (0.3, 0.0)
    """
    if defensive <= 0:
        return 0.0
    s_r = float(stats.chi2.sf((shell * beta) ** 2, m))
    hits = defensive * n * float(special.ndtr(-abs(beta))) / s_r if s_r > 0 else 0.0
    return defensive if hits >= MIN_SHELL_HITS else 0.0


__all__ = ["ControlVariateResult", "MixtureDraws", "ScaledGaussians", "cv_estimate",
           "is_weights_estimate", "shell_share"]
