"""Paired failure indicators: P_f of two designs measured on the same replications.

Each replication ``i`` gives a failure indicator for the baseline (``before_i``) and for the
other design (``after_i``). The 2x2 table of pairs,

=================  ===============  ==============
                   after fails      after safe
=================  ===============  ==============
**before fails**   ``both``         ``before_only``
**before safe**    ``after_only``   ``neither``
=================  ===============  ==============

gives the two failure fractions (each with its exact Clopper–Pearson interval), their
difference ``P_after − P_before`` with Newcombe's (1998, *Stat. Med.* 17:2635, method 10)
hybrid-score interval for paired proportions, and **McNemar's exact test** (McNemar 1947): under
"no difference" each discordant pair is as likely to fall either way, so ``before_only`` is
``Binomial(before_only + after_only, 1/2)``. The effect size is Cohen's ``g`` (Cohen 1988,
ch. 5): the share of discordant pairs in which the *after* design fails, minus 1/2 (−0.5: every
discordant pair favours the after design).

The power statement: the smallest baseline P_f that the exact test detects with the given power
when the other design never fails (every discordant pair one way) — for ``n = 20`` at
α = 0.05, at least 6 of the 20 baselines must fail (``2·0.5⁶ < 0.05``), so P_f,before must be
about 0.37 or more (``P(Bin(20, p) >= 6) = 0.8`` at ``p = 0.366``).

>>> import numpy as np
>>> before = np.array([1, 1, 1, 1, 1, 1, 1, 0, 0, 0], bool)
>>> after = np.array([0, 0, 0, 0, 0, 0, 1, 0, 0, 1], bool)
>>> r = paired_proportions(before, after)
>>> r.before_only, r.after_only, round(r.mcnemar_p, 4)     # 2 * P(X <= 1), X ~ Bin(7, 1/2)
(6, 1, 0.125)
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy import optimize, stats

from surrogate_rbrdo.core.validate import check_int, check_range


@dataclass(frozen=True)
class PairedProportions:
    """Result of :func:`paired_proportions` (differences are ``after − before``)."""

    name: str
    n: int
    both: int
    before_only: int
    after_only: int
    neither: int
    p_before: float
    p_after: float
    p_before_ci: tuple[float, float]
    p_after_ci: tuple[float, float]
    diff: float
    diff_ci: tuple[float, float]
    relative_change: float
    mcnemar_p: float
    cohens_g: float
    min_detectable_p_before: float
    confidence: float
    alpha: float
    power: float

    def to_dict(self) -> dict[str, object]:
        return asdict(self)


def _indicators(name: str, v) -> np.ndarray:
    a = np.asarray(v)
    if a.ndim != 1 or not (a.dtype == bool or np.all(np.isin(a, (0, 1)))):
        raise ValueError(f"{name} = {v!r} is not allowed: need a 1-D array of failure "
                         "indicators (bool or 0/1), one per replication")
    return a.astype(bool)


def clopper_pearson_ci(k: int, n: int, confidence: float) -> tuple[float, float]:
    """Exact binomial interval of ``k`` failures in ``n`` (valid at 0 and ``n``).

    >>> [round(v, 4) for v in clopper_pearson_ci(0, 20, 0.95)]
    [0.0, 0.1684]
    """
    ci = stats.binomtest(int(k), int(n)).proportion_ci(confidence, method="exact")
    return float(ci.low), float(ci.high)


def wilson_ci(k: int, n: int, confidence: float) -> tuple[float, float]:
    """Wilson score interval of a proportion ``k/n`` (the building block of method 10).

    >>> [round(v, 4) for v in wilson_ci(3, 10, 0.95)]
    [0.1078, 0.6032]
    """
    ci = stats.binomtest(int(k), int(n)).proportion_ci(confidence, method="wilson")
    return float(ci.low), float(ci.high)


def newcombe_paired_ci(both: int, before_only: int, after_only: int, neither: int,
                       confidence: float = 0.95) -> tuple[float, float]:
    """Newcombe's method 10 interval of ``P_after − P_before`` for paired binary data.

    Wilson intervals ``(l₁, u₁)`` of ``P_before`` and ``(l₂, u₂)`` of ``P_after`` are combined
    with the phi coefficient ``φ`` of the 2x2 table (0 if a margin is empty):
    ``Δ − √((p₂−l₂)² − 2φ(p₂−l₂)(u₁−p₁) + (u₁−p₁)²)`` to
    ``Δ + √((u₂−p₂)² − 2φ(u₂−p₂)(p₁−l₁) + (p₁−l₁)²)``.

    >>> lo, hi = newcombe_paired_ci(0, 0, 0, 20)         # nothing fails: an interval around 0
    >>> round(lo, 4), round(hi, 4)
    (-0.1611, 0.1611)
    """
    a, b, c, d = (int(v) for v in (both, before_only, after_only, neither))
    n = a + b + c + d
    p1, p2 = (a + b) / n, (a + c) / n
    l1, u1 = wilson_ci(a + b, n, confidence)
    l2, u2 = wilson_ci(a + c, n, confidence)
    margins = np.array([a + b, c + d, a + c, b + d], float)
    phi = (a * d - b * c) / np.sqrt(np.prod(margins)) if np.all(margins > 0) else 0.0
    lo = (p2 - l2) ** 2 - 2 * phi * (p2 - l2) * (u1 - p1) + (u1 - p1) ** 2
    hi = (u2 - p2) ** 2 - 2 * phi * (u2 - p2) * (p1 - l1) + (p1 - l1) ** 2
    delta = p2 - p1
    return float(delta - np.sqrt(max(lo, 0.0))), float(delta + np.sqrt(max(hi, 0.0)))


def mcnemar_exact_p(before_only: int, after_only: int) -> float:
    """Two-sided exact McNemar p-value (1 when there is no discordant pair).

    >>> mcnemar_exact_p(6, 0)      # 2 / 2**6
    0.03125
    """
    b, c = int(before_only), int(after_only)
    if b + c == 0:
        return 1.0
    return float(min(1.0, 2.0 * stats.binom.cdf(min(b, c), b + c, 0.5)))


def mcnemar_power(n: int, p_before_only: float, p_after_only: float, *,
                  alpha: float = 0.05) -> float:
    """Exact power of the two-sided exact McNemar test with ``n`` pairs when a pair is
    discordant "before fails only" with probability ``p_before_only`` and "after fails only"
    with ``p_after_only``.

    >>> round(mcnemar_power(20, 0.5, 0.0), 4)       # P(Bin(20, 0.5) >= 6)
    0.9793
    """
    n = check_int("n", n, minimum=1)
    alpha = check_range("alpha", alpha, 0.0, 1.0, inclusive=False)
    q = float(p_before_only) + float(p_after_only)
    if not (0.0 <= p_before_only and 0.0 <= p_after_only and q <= 1.0):
        raise ValueError(f"p_before_only = {p_before_only}, p_after_only = {p_after_only} are "
                         "not allowed: need probabilities with a sum <= 1")
    if q == 0.0:
        return 0.0
    k = np.arange(n + 1)
    pk = stats.binom.pmf(k, n, q)
    total = 0.0
    for kk in k[1:]:
        j = np.arange(kk + 1)
        pval = np.minimum(1.0, 2.0 * stats.binom.cdf(np.minimum(j, kk - j), kk, 0.5))
        total += pk[kk] * stats.binom.pmf(j, kk, p_before_only / q)[pval <= alpha].sum()
    return float(total)


def min_detectable_p_before(n: int, *, power: float = 0.8, alpha: float = 0.05) -> float:
    """Smallest baseline P_f that the exact McNemar test detects with ``power`` at ``n`` pairs
    when the other design never fails; NaN if no P_f <= 1 is detectable (tiny ``n``).

    >>> round(min_detectable_p_before(20), 3)
    0.366
    """
    n = check_int("n", n, minimum=1)
    power = check_range("power", power, 0.0, 1.0, inclusive=False)
    if mcnemar_power(n, 1.0, 0.0, alpha=alpha) < power:
        return float("nan")
    return float(optimize.brentq(
        lambda p: mcnemar_power(n, p, 0.0, alpha=alpha) - power, 1e-9, 1.0, xtol=1e-6))


def paired_proportions(fail_before, fail_after, *, name: str = "", confidence: float = 0.95,
                       alpha: float = 0.05, power: float = 0.8) -> PairedProportions:
    """Failure fractions of two designs on the same replications, compared pair by pair.

    Parameters
    ----------
    fail_before, fail_after : array_like of bool, shape (n,)
        Failure indicator of each replication for the baseline and the other design.
    confidence : float
        Level of every interval.
    alpha, power : float
        Significance level and power of the power statement.
    """
    a = _indicators("fail_before", fail_before)
    b = _indicators("fail_after", fail_after)
    if a.shape != b.shape or a.size < 1:
        raise ValueError(f"fail_before/fail_after have shapes {a.shape}/{b.shape}: need two "
                         "non-empty arrays of the same length")
    confidence = check_range("confidence", confidence, 0.0, 1.0, inclusive=False)
    n = a.size
    both, b_only = int(np.sum(a & b)), int(np.sum(a & ~b))
    a_only, neither = int(np.sum(~a & b)), int(np.sum(~a & ~b))
    k1, k2 = both + b_only, both + a_only
    disc = b_only + a_only
    return PairedProportions(
        name=name, n=n, both=both, before_only=b_only, after_only=a_only, neither=neither,
        p_before=k1 / n, p_after=k2 / n, p_before_ci=clopper_pearson_ci(k1, n, confidence),
        p_after_ci=clopper_pearson_ci(k2, n, confidence), diff=(k2 - k1) / n,
        diff_ci=newcombe_paired_ci(both, b_only, a_only, neither, confidence),
        relative_change=(k2 / k1 - 1.0) if k1 > 0 else float("nan"),
        mcnemar_p=mcnemar_exact_p(b_only, a_only),
        cohens_g=(a_only / disc - 0.5) if disc else float("nan"),
        min_detectable_p_before=min_detectable_p_before(n, power=power, alpha=alpha),
        confidence=confidence, alpha=alpha, power=power)
