"""Adaptive importance sampling: improved cross-entropy (iCE) with a flexible mixture.

The improved cross-entropy method of Papaioannou, Geyer & Straub (2019, *Reliability
Engineering & System Safety* 191, 106564) adapts the IS density ``h`` to a sequence of smooth
approximations of the optimal density, ``φ(u) Φ(−G(u)/σ_j)``: level ``j`` draws
``n_per_level`` points from ``h_j`` (``h_1 = φ``), chooses ``σ_{j+1} < σ_j`` so that the
coefficient of variation of the ratios ``Φ(−G/σ_{j+1}) / Φ(−G/σ_j)`` equals ``cov_target``
(1.5, the paper's value), and refits ``h`` to the points weighted by
``φ/h_j · Φ(−G/σ_{j+1})`` (weighted maximum likelihood: the cross-entropy update). It stops
when the coefficient of variation of ``1[G ≤ 0] / Φ(−G/σ_j)`` is below ``cov_target`` (the
smoothed target has become the failure domain) and refits ``h`` to the failures. Unlike the
quantile-based multilevel CE every sample carries information, and the smooth weights keep
all regions the samples have seen.

The family of ``h`` is ``density``: ``"vmfn"`` (default), a mixture of von Mises–Fisher ×
Nakagami components in polar coordinates (:mod:`._vmfn`; Wang & Song 2016; Papaioannou et al.
2019), whose parameters grow like ``m`` and which stays reliable in many dimensions, or
``"gm"``, a Gaussian mixture (Geyer, Papaioannou & Straub 2019, *Structural Safety* 76;
:mod:`._gmm`), whose covariances degrade beyond a few tens of dimensions. The number of
components (≤ ``n_components``) is chosen by the BIC at every fit.

A fit can leave out a failure branch, which is then never sampled again (the four-branch
series system: a straight branch lost in 5 of 100 runs, each reported 3–8 SE low without
a warning). Before the final sample, ``probe`` (:mod:`._ce_probe`) looks for such branches from
the first level's standard-normal points nearest failure: a design-point search from each one
the final density would not visit, and every relevant design point the final density misses
joins it as ``N(u*, I)`` (``diagnostics["n_missed_branches"]``, ``"probe_calls"``).

``pf_se`` is the standard error of a final, independent sample of ``n_final`` points from the
defensive mixture ``(1 − a) h + a φ̃`` (Hesterberg 1995; ``φ̃ = φ`` for vMFN, ``N(0, c I)``
with ``c ≥ 1`` the mean square radius of ``h`` per dimension for the Gaussian mixture): the
adaptation levels only choose the density, so the estimate and its error are those of one
plain IS run, unbiased for any failure domain. Its weights' tail is checked: a Pareto
``k̂ > 0.7`` (:mod:`._tail`) raises an :class:`~._tail.EstimatorWarning`. Designs that never
fail: see ``on_failure``. Points outside the model's physical domain are not failures
(:mod:`._common`).

``mean``/``std`` of ``y`` come from the level-1 sample (plain Monte Carlo, ``n_per_level``
points, or the fixed ``u``); the levels after it use a generator seeded once per call from
``rng``, the same for every design (common random numbers, :func:`._levels.run_per_design`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import optimize, special

from surrogate_rbrdo.core.protocols import Estimate, LimitState
from surrogate_rbrdo.core.validate import check_choice, check_int, check_range
from surrogate_rbrdo.estimators._ce_probe import DensityMix, ProbeResult, augment, probe_missed
from surrogate_rbrdo.estimators._common import LimitStateU, log_std_normal, make_estimate
from surrogate_rbrdo.estimators._gmm import GaussianMixture, fit_mixture
from surrogate_rbrdo.estimators._is_density import is_weights_estimate
from surrogate_rbrdo.estimators._levels import (
    ON_FAILURE,
    LevelResult,
    StallGuard,
    interval,
    run_per_design,
)
from surrogate_rbrdo.estimators._tail import EstimatorWarning, pareto_khat
from surrogate_rbrdo.estimators._vmfn import fit_vmfn, standard_normal_vmfn
from surrogate_rbrdo.estimators.form import FORM
from surrogate_rbrdo.estimators.importance import KHAT_LIMIT
from surrogate_rbrdo.estimators.registry import ESTIMATORS

DENSITIES = ("vmfn", "gm")
#: quantile of G monitored to detect a failure domain that is never reached
MONITOR_QUANTILE = 0.1


def next_sigma(g: np.ndarray, sigma: float, target: float) -> float:
    """``σ' ∈ (0, σ)`` with ``CoV[Φ(−G/σ')/Φ(−G/σ)] = target`` over the finite ``g`` (``σ = inf``
    stands for the constant ``Φ(0)``). The CoV grows as ``σ'`` shrinks: found by bisection in
    ``log σ'``, in logs (no underflow); the smallest ``σ'`` tried when even it stays below
    ``target``.

    >>> g = np.linspace(-1.0, 5.0, 200)
    >>> s = next_sigma(g, np.inf, 1.5)
    >>> r = special.ndtr(-g / s)
    >>> round(float(r.std() / r.mean()), 3)
    1.5
    """
    g = g[np.isfinite(g)]
    scale = float(np.max(np.abs(g))) if g.size and np.max(np.abs(g)) > 0 else 1.0
    hi = np.log(min(sigma, 100.0 * scale))
    lo = np.log(1e-9 * scale)           # σ' not below 1e-9 of the scale of G
    if hi <= lo:
        return float(np.exp(hi))

    def log_phi(s: float) -> np.ndarray:
        return special.log_ndtr(np.clip(-g / s, -1e100, 1e100))

    base = np.log(0.5) if not np.isfinite(sigma) else log_phi(sigma)

    def miss(log_s: float) -> float:
        lr = log_phi(np.exp(log_s)) - base
        r = np.exp(lr - np.max(lr))
        return float(np.std(r) / np.mean(r)) - target

    if miss(lo) <= 0:
        return float(np.exp(lo))
    if miss(hi) >= 0:
        return float(np.exp(hi))
    return float(np.exp(optimize.brentq(miss, lo, hi, xtol=1e-8)))


def smooth_cov(g: np.ndarray, sigma: float) -> float:
    """CoV of ``1[G ≤ 0]/Φ(−G/σ)`` over the sample (``inf`` without failures; ``Φ(−G/σ) ≥ 1/2``
    at the failures, so no division by an underflow).

    >>> smooth_cov(np.array([-1.0, -2.0, 3.0, 4.0]), np.inf)
    1.0
    """
    fail = g <= 0
    if not fail.any():
        return np.inf
    r = np.zeros(g.size)
    r[fail] = 1.0 / (0.5 if not np.isfinite(sigma) else special.ndtr(-g[fail] / sigma))
    return float(np.std(r) / np.mean(r))


@ESTIMATORS.register("ais")
@dataclass(frozen=True)
class CrossEntropyIS:
    """Improved cross-entropy adaptive importance sampling (vMFN or Gaussian mixture).

    Parameters
    ----------
    n_per_level : int
        Points per adaptation level (level 1 uses ``u`` when given).
    cov_target : float
        Target coefficient of variation of the smoothing weights (``δ*``), > 0.
    n_final : int
        Points of the final, independent IS estimate.
    density : {"vmfn", "gm"}
        Family of the IS density: von Mises–Fisher–Nakagami or Gaussian mixture.
    n_components : int
        Largest number of mixture components (the BIC picks 1..n_components).
    defensive : float
        Weight ``a`` of the defensive component in the final mixture, in [0, 0.999].
    max_levels : int
    on_failure : {"bound", "raise", "nan"}
        When no sample has failed after ``max_levels`` levels (or the monitored 10 % quantile of
        ``G`` stopped decreasing): report the IS estimate of ``P(G ≤ γ)`` of the last level, ``γ``
        that quantile (> 0), as an upper bound (``status = "not_reached"``), raise
        ``ModelError``, or give NaN.
    ci_level : float
    probe : bool
        Search for failure branches the adapted density misses and add them to the final
        density (:mod:`._ce_probe`; a few design-point searches at most).

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
    cov_target: float = 1.5
    n_final: int = 2000
    density: str = "vmfn"
    n_components: int = 4
    defensive: float = 0.1
    max_levels: int = 30
    on_failure: str = "bound"
    ci_level: float = 0.95
    probe: bool = True

    def __post_init__(self) -> None:
        check_int("n_per_level", self.n_per_level, minimum=20)
        if check_range("cov_target", self.cov_target, 0.0, 100.0) == 0.0:
            raise ValueError("cov_target = 0.0 is not allowed: must lie in (0, 100]")
        check_int("n_final", self.n_final, minimum=2)
        check_choice("density", self.density, DENSITIES)
        check_int("n_components", self.n_components, minimum=1)
        check_range("defensive", self.defensive, 0.0, 0.999)
        check_int("max_levels", self.max_levels, minimum=1)
        check_choice("on_failure", self.on_failure, ON_FAILURE)
        check_range("ci_level", self.ci_level, 0.0, 1.0, inclusive=False)
        if not isinstance(self.probe, bool):
            raise ValueError(f"probe = {self.probe!r} is not allowed: must be True or False")

    def _fit(self, v: np.ndarray, logw: np.ndarray, rng: np.random.Generator) -> Any:
        keep = np.isfinite(logw)
        if self.density == "vmfn":
            return fit_vmfn(v[keep], logw[keep], self.n_components, rng)
        return fit_mixture(v[keep], logw[keep], self.n_components, rng)

    def _one(self, G: LimitStateU, m: int, u0: np.ndarray | None, rng: np.random.Generator
             ) -> LevelResult:
        h = (standard_normal_vmfn(m) if self.density == "vmfn"
             else GaussianMixture(np.ones(1), np.zeros((1, m)), np.eye(m)[None]))
        v = u0 if u0 is not None else rng.standard_normal((self.n_per_level, m))
        sigma, y0, stall, level = np.inf, None, StallGuard(), 0
        for level in range(1, self.max_levels + 1):
            if level > 1:
                v = h.sample(self.n_per_level, rng)
            g = G(v)
            if y0 is None:
                y0, first = G.last_y.copy(), (v, g)
            logw = log_std_normal(v) - h.logpdf(v)
            fail = g <= 0
            if smooth_cov(g, sigma) <= self.cov_target:
                break
            quant = float(np.quantile(g, MONITOR_QUANTILE, method="lower"))
            if not fail.any() and (stall(quant, level, g) or level == self.max_levels):
                # not reached: IS estimate of P(G <= γ), an upper bound of P_f
                pf, se, _ = is_weights_estimate(g <= quant, logw)
                return LevelResult(pf, se, np.full(3, np.nan), level, False, y0)
            sigma = next_sigma(g, sigma, self.cov_target)
            with np.errstate(divide="ignore"):
                h = self._fit(v, logw + special.log_ndtr(-g / sigma), rng)
        if fail.sum() >= 2:           # the cross-entropy update on the failures themselves
            with np.errstate(divide="ignore"):
                h = self._fit(v, np.where(fail, logw, -np.inf), rng)
        q = self._defensive(h, m)
        pf_hint = is_weights_estimate(fail, logw)[0]
        probe = (probe_missed(G, q, *first, pf_hint, self.n_final, FORM(), rng)
                 if self.probe else ProbeResult(np.empty((0, m)), np.empty(0), 0, 0))
        pf, se, khat = self._final(G, augment(q, probe, pf_hint), rng)
        return LevelResult(pf, se, [khat, probe.beta.size, probe.calls], level, True, y0)

    def _defensive(self, h: Any, m: int) -> Any:
        """The final density without the probe's branches: ``(1 − a) h + a φ̃`` (module
        docstring)."""
        a = self.defensive
        if self.density == "vmfn":
            return h.with_defensive(a)
        if a <= 0:
            return h
        # defensive N(0, c I), c = mean square radius of h per dimension (>= 1)
        second = h.weights @ (np.sum(h.means**2, axis=1)
                              + np.einsum("kij,kij->k", h.chols, h.chols))
        c = max(1.0, float(second) / m)
        wide = GaussianMixture(np.ones(1), np.zeros((1, m)), np.sqrt(c) * np.eye(m)[None])
        return DensityMix(np.array([1.0 - a, a]), (h, wide))

    def _final(self, G: LimitStateU, q: Any, rng: np.random.Generator
               ) -> tuple[float, float, float]:
        """The independent final estimate from the density ``q``: ``(pf, se, k̂)``."""
        v = q.sample(self.n_final, rng)
        fail = G(v) < 0
        logw = log_std_normal(v) - q.logpdf(v)
        pf, se, _ = is_weights_estimate(fail, logw)
        khat = pareto_khat(np.where(fail, np.exp(np.where(fail, logw, 0.0)), 0.0))
        return pf, se, khat

    def estimate(self, response: Any, inputs: Any, limit: LimitState, x: np.ndarray, *,
                 rng: np.random.Generator, u: np.ndarray | None = None) -> Estimate:
        """Adapt and estimate for every design of ``x``."""
        r = run_per_design(
            self, response, inputs, limit, x, rng, u, what="cross-entropy IS",
            why="the thresholds stop decreasing when the response never fails",
            advice="increase max_levels or n_per_level, or pass on_failure='bound' for an "
                   "upper bound")
        mc = r.moments
        khat = np.where(r.status == "converged", r.extra[:, 0], np.nan)
        heavy = np.flatnonzero(np.nan_to_num(khat, nan=-np.inf) > KHAT_LIMIT)
        if heavy.size:
            warnings.warn(
                f"cross-entropy IS: heavy-tailed final weights for design(s) "
                f"{heavy[:10].tolist()} (Pareto k = {np.round(khat[heavy[:10]], 2).tolist()} > "
                f"{KHAT_LIMIT}): the fitted density misses part of the failure domain, pf_se is "
                "unreliable; use 'subset'",
                EstimatorWarning, stacklevel=2)
        return make_estimate(
            "ais", r.calls, r.pf.size, mean=mc.mean, std=mc.std, mean_se=mc.mean_se,
            std_se=mc.std_se, pf=r.pf, pf_se=r.se,
            pf_ci=interval(r.pf, r.se, r.status, self.ci_level),
            diagnostics={"ci_level": self.ci_level, "ci_method": "normal", "pareto_k": khat,
                         "levels": r.levels, "converged": r.status == "converged",
                         "status": r.status, "n_outside_domain": r.n_outside,
                         "density": self.density, "n_missed_branches": r.extra[:, 1],
                         "probe_calls": r.extra[:, 2]},
        )
