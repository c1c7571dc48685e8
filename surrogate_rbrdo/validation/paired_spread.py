"""Paired spreads: is σ_y of one design smaller than the baseline's, on the same replications?

One value per replication and design gives one standard deviation per design, not one per
replication: the paper's "paired t-test on σ_y" (Table 7) has no per-replication σ to pair.
The test for equal variances of *paired* (correlated) samples is **Pitman–Morgan's**
(Pitman 1939, Morgan 1939): ``var(a) = var(b)`` exactly when the sum ``a + b`` and the
difference ``b − a`` are uncorrelated, so the t-test of that correlation (``n − 2`` degrees of
freedom) tests it, with ``F = s_b²/s_a²`` and ``r = corr(a, b)``:

    t = (F − 1) √(n − 2) / (2 √(F (1 − r²))).

Inverting it gives the exact interval of the variance ratio under bivariate normality,
``F (K ∓ √(K² − 1))`` with ``K = 1 + 2 (1 − r²) t²_{1−α/2, n−2} / (n − 2)`` (the square root of
it for the SD ratio). Peak amplitudes are not normal (they scale with a uniformly distributed
unbalance), so a BCa bootstrap interval of ``s_b/s_a − 1`` resampling pairs (Efron &
Tibshirani 1993, ch. 14) is reported beside it as the distribution-free check.

Power statement (approximate, Fisher's z for the sum–difference correlation at the observed
``r``): the SD ratio below which a reduction is detected with the given power.

>>> import numpy as np
>>> a = np.array([1.0, 2.0, 3.0, 4.0, 5.0])
>>> b = np.array([2.0, 1.0, 4.0, 3.0, 7.0])
>>> t, df, p = pitman_morgan_t(a, b)
>>> round(t, 4), df                 # corr(a + b, b − a) = 0.5618 -> t = 1.1762
(1.1762, 3)
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy import special, stats

from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_int, check_range
from surrogate_rbrdo.validation.statistics import _check_pairs


@dataclass(frozen=True)
class PairedSpread:
    """Result of :func:`paired_spread` (ratio = after / before)."""

    name: str
    n: int
    sd_before: float
    sd_after: float
    correlation: float
    ratio: float
    ratio_ci: tuple[float, float]
    relative_change: float
    bootstrap_relative_ci: tuple[float, float]
    t: float
    df: int
    p_value: float
    min_detectable_ratio: float
    confidence: float
    alpha: float
    power: float

    def to_dict(self) -> dict[str, object]:
        return asdict(self)


def pitman_morgan_t(before, after) -> tuple[float, int, float]:
    """Pitman–Morgan statistic ``t`` (> 0 when ``after`` spreads more), ``n − 2`` degrees of
    freedom and the two-sided p-value."""
    a, b = _check_pairs(before, after)
    n = a.size
    va, vb = a.var(ddof=1), b.var(ddof=1)
    if va == 0.0 or vb == 0.0:
        raise ValueError("before/after: a design without spread has no variance ratio")
    F, r = vb / va, float(np.corrcoef(a, b)[0, 1])
    t = (F - 1.0) * np.sqrt(n - 2) / (2.0 * np.sqrt(F * max(1.0 - r * r, 1e-300)))
    return float(t), n - 2, float(2.0 * stats.t.sf(abs(t), n - 2))


def variance_ratio_ci(F: float, r: float, n: int, confidence: float) -> tuple[float, float]:
    """Exact (bivariate-normal) interval of ``σ_b²/σ_a²`` from ``F = s_b²/s_a²`` and ``r``.

    >>> [round(v, 4) for v in variance_ratio_ci(1.0, 0.0, 12, 0.95)]
    [0.269, 3.7168]
    """
    tc = stats.t.ppf(0.5 + 0.5 * confidence, n - 2)
    K = 1.0 + 2.0 * (1.0 - r * r) * tc * tc / (n - 2)
    s = np.sqrt(K * K - 1.0)
    return float(F * (K - s)), float(F * (K + s))


def min_detectable_sd_ratio(n: int, r: float = 0.0, *, power: float = 0.8,
                            alpha: float = 0.05) -> float:
    """SD ratio ``σ_b/σ_a < 1`` that the Pitman–Morgan test detects with ``power`` at ``n``
    pairs correlated by ``r`` (Fisher-z approximation).

    >>> round(min_detectable_sd_ratio(20, 0.0), 3)
    0.507
    """
    n = check_int("n", n, minimum=4)
    power = check_range("power", power, 0.0, 1.0, inclusive=False)
    z = special.ndtri(1.0 - alpha / 2.0) + special.ndtri(power)
    rho = np.tanh(z / np.sqrt(n - 3))
    K = 1.0 + 2.0 * rho**2 * (1.0 - r * r) / (1.0 - rho**2)
    return float(np.sqrt(K - np.sqrt(K * K - 1.0)))


def _sd_ratio(x, y, axis=-1):
    return np.std(y, axis=axis, ddof=1) / np.std(x, axis=axis, ddof=1) - 1.0


def paired_spread(before, after, *, rng: np.random.Generator, name: str = "",
                  confidence: float = 0.95, alpha: float = 0.05, power: float = 0.8,
                  n_boot: int = 9999) -> PairedSpread:
    """Pitman–Morgan test and intervals of the SD ratio of two paired samples.

    Parameters
    ----------
    before, after : array_like, shape (n,)
        One value per replication (same order), ``n >= 4``.
    rng : numpy.random.Generator
        Resampling of the bootstrap.
    """
    rng = require_rng(rng)
    a, b = _check_pairs(before, after)
    if a.size < 4:
        raise ValueError(f"n = {a.size} replications is not allowed: the paired spread test "
                         "needs at least 4 pairs")
    confidence = check_range("confidence", confidence, 0.0, 1.0, inclusive=False)
    n_boot = check_int("n_boot", n_boot, minimum=100)
    t, df, p = pitman_morgan_t(a, b)
    sa, sb = float(a.std(ddof=1)), float(b.std(ddof=1))
    r = float(np.corrcoef(a, b)[0, 1])
    lo, hi = variance_ratio_ci((sb / sa) ** 2, r, a.size, confidence)
    with np.errstate(divide="ignore", invalid="ignore"):   # a resample without spread
        bs = stats.bootstrap((a, b), _sd_ratio, paired=True, confidence_level=confidence,
                             n_resamples=n_boot, rng=rng, method="BCa").confidence_interval
    return PairedSpread(
        name=name, n=a.size, sd_before=sa, sd_after=sb, correlation=r, ratio=sb / sa,
        ratio_ci=(float(np.sqrt(lo)), float(np.sqrt(hi))), relative_change=sb / sa - 1.0,
        bootstrap_relative_ci=(float(bs.low), float(bs.high)), t=t, df=df, p_value=p,
        min_detectable_ratio=min_detectable_sd_ratio(a.size, r, power=power, alpha=alpha),
        confidence=confidence, alpha=alpha, power=power)
