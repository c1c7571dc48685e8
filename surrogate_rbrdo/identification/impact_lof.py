"""The statistics of an impact fit's jackknife: the lack-of-fit test against the hits' own
scatter and its threshold, and the jackknife covariance's floor
(:func:`~surrogate_rbrdo.identification.impact.jackknife` computes them).

>>> lof = ImpactLackOfFit(1.2, 500, 4, 15.0, 0.01, (3e-7, -2e-7), 1.5, 10.6, False, 3)
>>> lof.to_dict()["delays_s"], lof.flagged
([3e-07, -2e-07], False)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats


def _at_least(model: np.ndarray, jk: np.ndarray) -> np.ndarray:
    """The jackknife covariance with each variance raised to the model-based one where that is
    larger (noise-free hits are identical: the jackknife sees no scatter, the model-based
    covariance keeps H1's accuracy floor); the jackknife's correlations are kept. Where the
    model-based variance wins, the SE is no longer a jackknife estimate with ``n − 1`` degrees
    of freedom: a ``t(n − 1)`` interval on it is then conservative."""
    dj, dm = np.diag(jk), np.diag(model)
    if not np.all(dj > 0):
        return model
    d = np.sqrt(np.maximum(dj, dm) / dj)
    return jk * d[:, None] * d[None, :]


@dataclass(frozen=True)
class ImpactLackOfFit:
    """The model-error tests of an impact fit (:func:`~surrogate_rbrdo.identification.impact.
    jackknife`).

    ``chi2_dof`` of the FRF residuals against H1's jackknife variance, tested against
    ``threshold`` (the ``1 − level/2`` quantile of ``F(dof, variance_dof)``, or a fixed one);
    ``delay_chi2``: the fitted delays' Mahalanobis distance from 0 against the acquisition's
    stated skew (each channel's SD ``σ_skew``; a delay is the difference of two channels'
    skews: :func:`delay_test`), tested against ``delay_threshold`` (its ``1 − level/2``
    quantile; NaN when not tested) — a delay far outside the chain's specification is model
    error absorbed by the nuisance. ``flagged``: either
    test; ``hits``: the jackknife's replicates.
    """

    chi2_dof: float
    dof: int
    variance_dof: int
    threshold: float
    level: float | None
    delays_s: tuple[float, ...]
    delay_chi2: float
    delay_threshold: float
    flagged: bool
    hits: int

    def to_dict(self) -> dict:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in vars(self).items()}


def delay_test(delay_us: np.ndarray, cov_us2: np.ndarray, skew_sd_s: float | None,
               level: float, n_hits: int) -> tuple[float, float]:
    """``(τ̂ᵀ (Σ_skew + Σ_J)⁻¹ τ̂, its 1 − level quantile)`` for the fitted delays ``τ̂`` (µs)
    of ``nd`` directions with their jackknife covariance ``Σ_J`` (µs², from ``n_hits``
    replicates); ``(nan, nan)`` without a stated skew. Each direction's delay is its
    accelerometer channel's skew minus the hammer channel's, one hammer for all directions:
    ``Σ_skew = σ² (I + 1 1ᵀ)``. Reference: ``nd F(nd, ν)`` with Satterthwaite's dof
    ``ν = (n_hits − 1) / f²``, ``f`` the largest share of a delay's variance that is estimated
    (``Σ_J``; Satterthwaite, *Biometrics Bull.* 2:110, 1946) — ``χ²_nd`` when the stated skew
    dominates, a Hotelling-like heavy tail when the jackknife does (3 hits at 10× the rig's
    noise: a χ²_nd reference flagged 2 of 10 right models).

    >>> stat, thr = delay_test(np.array([0.3, -0.2]), np.diag([0.01, 0.01]), 0.2e-6, 0.005, 5)
    >>> round(stat, 2), round(thr, 2)
    (2.54, 10.77)
    """
    if skew_sd_s is None:
        return float("nan"), float("nan")
    nd = delay_us.size
    prior = (skew_sd_s * 1e6) ** 2 * (np.eye(nd) + np.ones((nd, nd)))
    sig = prior + cov_us2
    stat = float(delay_us @ np.linalg.solve(sig, delay_us))
    f = float(np.max(np.diag(cov_us2) / np.diag(sig)))
    nu = (n_hits - 1) / max(f, 1e-12) ** 2
    return stat, float(nd * stats.f.ppf(1.0 - level, nd, min(nu, 1e9)))


def lack_of_fit_threshold(dof: int, n_hits: int, level: float) -> float:
    """The ``1 − level`` quantile of ``F(dof, 2(n_hits − 1))``: χ²/ν of a right model's
    residuals (``dof`` of them) against H1's variance estimated from ``n_hits`` hits (a complex
    estimate: ``2(n_hits − 1)`` degrees of freedom) exceeds it with probability ``level`` when
    the variance estimate's error is common to all points (the conservative case; independent
    errors between bins make the tail lighter).

    >>> round(lack_of_fit_threshold(10**6, 3, 0.01), 2)   # → 4 / χ²₄(0.01) as ν → ∞
    13.46
    >>> round(lack_of_fit_threshold(10**6, 5, 0.01), 2)
    4.86
    """
    return float(stats.f.ppf(1.0 - level, dof, 2 * (n_hits - 1)))


__all__ = ["ImpactLackOfFit", "delay_test", "lack_of_fit_threshold"]
