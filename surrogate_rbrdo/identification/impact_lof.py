"""The statistics of an impact fit's jackknife: the lack-of-fit test against the hits' own
scatter and its threshold, and the jackknife covariance's floor
(:func:`~surrogate_rbrdo.identification.impact.jackknife` computes them).

>>> ImpactLackOfFit(1.2, 500, 4, 13.3, 0.01, False, 3).to_dict()["flagged"]
False
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
    """The lack-of-fit test of an impact fit: ``chi2_dof`` against ``threshold`` (the
    ``1 − level`` quantile of ``F(dof, variance_dof)``, or a fixed one), ``hits`` the
    jackknife's replicates."""

    chi2_dof: float
    dof: int
    variance_dof: int
    threshold: float
    level: float | None
    flagged: bool
    hits: int

    def to_dict(self) -> dict:
        return dict(vars(self))


def lack_of_fit_threshold(dof: int, n_hits: int, level: float) -> float:
    """The ``1 − level`` quantile of ``F(dof, 2(n_hits − 1))``: χ²/ν of a right model's
    residuals (``dof`` of them) against H1's variance estimated from ``n_hits`` hits (a complex
    estimate: ``2(n_hits − 1)`` degrees of freedom) exceeds it with probability ``level`` when
    the variance estimate's error is common to all points (the conservative case; independent
    errors between bins make the tail lighter).

    >>> round(lack_of_fit_threshold(10**6, 3, 0.01), 2)   # ≈ 4 / χ²₄(0.01)
    13.28
    >>> round(lack_of_fit_threshold(10**6, 5, 0.01), 2)
    4.86
    """
    return float(stats.f.ppf(1.0 - level, dof, 2 * (n_hits - 1)))


__all__ = ["ImpactLackOfFit", "lack_of_fit_threshold"]
