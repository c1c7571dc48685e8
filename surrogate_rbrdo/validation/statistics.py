"""Paired comparison of two designs measured on the same replications (the paper's Table 7).

Each replication ``i`` gives one value ``a_i`` for the baseline and one value ``b_i`` for the
optimised design, measured under the same assembly/run conditions (common conditions make the
pair). :func:`paired_comparison` reports, for the differences ``d_i = b_i − a_i``:

* the paired t-test (Student 1908): ``t = d̄ / (s_d / √n)``, ``n − 1`` degrees of freedom, and
  the t interval of the mean difference;
* Cohen's effect size for paired samples **d_z = d̄ / s_d** (Cohen 1988, §2.3.5; the "d" of
  G*Power's matched-pairs test) with an exact confidence interval from the noncentral t
  distribution (Cumming & Finch 2001), and, for comparison with papers that report it, the
  average-SD form **d_av = d̄ / ((s_a + s_b)/2)** (Lakens 2013, Eq. 10). The paper's Table 7
  does not say which d it reports; d_z grows with the correlation of the pairs and d_av does
  not, so the two can differ by far more than sampling error;
* the Wilcoxon signed-rank test (exact for n ≤ 50 without ties, scipy) as the check that does
  not assume normal differences;
* bootstrap (BCa) intervals of the mean difference and of the relative change
  ``mean(b)/mean(a) − 1`` (Efron & Tibshirani 1993, ch. 14), resampling pairs; the relative
  change is NaN unless every baseline value is positive;
* a power statement: the smallest d_z the test detects with power 0.8 at this n, and the power
  at the observed d_z is *not* reported (post-hoc power is a function of the p-value, Hoenig &
  Heisey 2001).

>>> import numpy as np
>>> a = np.array([0.7, -1.6, -0.2, -1.2, -0.1, 3.4, 3.7, 0.8, 0.0, 2.0])  # Student's sleep data
>>> b = np.array([1.9, 0.8, 1.1, 0.1, -0.1, 4.4, 5.5, 1.6, 4.6, 3.4])
>>> r = paired_comparison(a, b, rng=np.random.default_rng(0), n_boot=2000)
>>> round(r.t, 4), r.df, round(r.p_value, 6), round(r.d_z, 4)
(4.0621, 9, 0.002833, 1.2846)
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy import optimize, stats

from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_int, check_range


@dataclass(frozen=True)
class PairedComparison:
    """Result of :func:`paired_comparison` (differences are ``after − before``)."""

    name: str
    n: int
    mean_before: float
    mean_after: float
    mean_diff: float
    sd_diff: float
    diff_ci: tuple[float, float]
    t: float
    df: int
    p_value: float
    d_z: float
    d_z_ci: tuple[float, float]
    d_av: float
    wilcoxon_statistic: float
    wilcoxon_p: float
    bootstrap_diff_ci: tuple[float, float]
    relative_change: float
    bootstrap_relative_ci: tuple[float, float]
    min_detectable_d_z: float
    confidence: float
    alpha: float

    def to_dict(self) -> dict[str, object]:
        return asdict(self)


def _check_pairs(before: np.ndarray, after: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a = np.asarray(before, dtype=float)
    b = np.asarray(after, dtype=float)
    if a.ndim != 1 or a.shape != b.shape:
        raise ValueError(f"before/after have shapes {a.shape}/{b.shape}: need two 1-D arrays "
                         "of the same length (one value per replication)")
    if a.size < 3:
        raise ValueError(f"n = {a.size} replications is not allowed: need at least 3 pairs")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise ValueError("before/after contain NaN or inf: every replication needs a value")
    return a, b


def paired_power(n: int, d_z: float, *, alpha: float = 0.05) -> float:
    """Power of the two-sided paired t-test with ``n`` pairs at true effect ``d_z``.

    Exact under normal differences: the statistic is noncentral t with ``n − 1`` degrees of
    freedom and noncentrality ``d_z √n``.

    >>> round(paired_power(20, 0.5), 4)   # G*Power 3.1, matched pairs: 0.5645
    0.5645
    """
    n = check_int("n", n, minimum=2)
    alpha = check_range("alpha", alpha, 0.0, 1.0, inclusive=False)
    df, nc = n - 1, float(d_z) * np.sqrt(n)
    tc = stats.t.ppf(1.0 - alpha / 2.0, df)
    # P(T > tc) + P(T < -tc); the far tail underflows to NaN in scipy's nct for |nc| >~ 15
    tails = np.nan_to_num([stats.nct.sf(tc, df, nc), stats.nct.sf(tc, df, -nc)], nan=0.0)
    return float(tails.sum())


def min_detectable_d_z(n: int, *, power: float = 0.8, alpha: float = 0.05) -> float:
    """Smallest ``d_z`` the two-sided paired t-test detects with ``power`` at ``n`` pairs.

    >>> round(min_detectable_d_z(20), 3)   # G*Power 3.1: 0.660
    0.66
    """
    power = check_range("power", power, alpha, 1.0, inclusive=False)
    n = check_int("n", n, minimum=2)
    hi = 30.0 / np.sqrt(n)   # noncentrality 30: power 1 to double precision for any df >= 1
    return float(optimize.brentq(lambda d: paired_power(n, d, alpha=alpha) - power, 0.0, hi))


def _d_z_ci(t: float, n: int, confidence: float) -> tuple[float, float]:
    """Exact CI of d_z by inverting the noncentral t distribution of ``t``."""
    df, q = n - 1, (1.0 - confidence) / 2.0

    def cdf(nc: float) -> float:
        # P(T <= t | nc) falls from 1 to 0 as nc grows; scipy returns NaN deep in the tails
        c = stats.nct.cdf(t, df, nc)
        return c if np.isfinite(c) else (0.0 if nc > t else 1.0)

    def nc_at(p: float) -> float:
        lo, hi = t - 10.0 - abs(t), t + 10.0 + abs(t)
        return optimize.brentq(lambda nc: cdf(nc) - p, lo, hi)

    return nc_at(1.0 - q) / np.sqrt(n), nc_at(q) / np.sqrt(n)


def paired_comparison(before, after, *, rng: np.random.Generator, name: str = "",
                      confidence: float = 0.95, alpha: float = 0.05, n_boot: int = 9999
                      ) -> PairedComparison:
    """Paired t-test, d_z (with exact CI), d_av, Wilcoxon, bootstrap CIs and a power statement.

    Parameters
    ----------
    before, after : array_like, shape (n,)
        One value per replication for the two designs (same replication order).
    rng : numpy.random.Generator
        Resampling of the bootstrap.
    confidence : float
        Level of every interval.
    alpha : float
        Significance level of the power statement.
    n_boot : int
        Bootstrap resamples.
    """
    rng = require_rng(rng)
    a, b = _check_pairs(before, after)
    confidence = check_range("confidence", confidence, 0.0, 1.0, inclusive=False)
    n_boot = check_int("n_boot", n_boot, minimum=100)
    d = b - a
    n = d.size
    sd = float(d.std(ddof=1))
    if sd == 0.0:
        raise ValueError("before/after differ by the same amount in every replication: the "
                         "paired tests need a non-zero spread of the differences")
    tt = stats.ttest_rel(b, a)
    ci = tt.confidence_interval(confidence_level=confidence)
    t = float(tt.statistic)
    w = stats.wilcoxon(b, a)
    boot_kw = dict(paired=True, confidence_level=confidence, n_resamples=n_boot, rng=rng,
                   method="BCa")
    bd = stats.bootstrap((a, b), lambda x, y, axis=-1: np.mean(y - x, axis=axis), **boot_kw)
    if np.all(a > 0):   # a relative change needs a positive baseline (amplitudes, P_f > 0)
        br = stats.bootstrap((a, b), lambda x, y, axis=-1: np.mean(y, axis=axis)
                             / np.mean(x, axis=axis) - 1.0, **boot_kw).confidence_interval
        rel, rel_ci = float(b.mean() / a.mean() - 1.0), (float(br.low), float(br.high))
    else:
        rel, rel_ci = float("nan"), (float("nan"), float("nan"))
    s_av = 0.5 * (a.std(ddof=1) + b.std(ddof=1))
    return PairedComparison(
        name=name, n=n, mean_before=float(a.mean()), mean_after=float(b.mean()),
        mean_diff=float(d.mean()), sd_diff=sd, diff_ci=(float(ci.low), float(ci.high)),
        t=t, df=n - 1, p_value=float(tt.pvalue), d_z=float(d.mean() / sd),
        d_z_ci=tuple(float(v) for v in _d_z_ci(t, n, confidence)),
        d_av=float(d.mean() / s_av) if s_av > 0 else float("nan"),
        wilcoxon_statistic=float(w.statistic), wilcoxon_p=float(w.pvalue),
        bootstrap_diff_ci=(float(bd.confidence_interval.low),
                           float(bd.confidence_interval.high)),
        relative_change=rel, bootstrap_relative_ci=rel_ci,
        min_detectable_d_z=min_detectable_d_z(n, alpha=alpha), confidence=confidence,
        alpha=alpha)
