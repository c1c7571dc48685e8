"""Pitman–Morgan test of paired spreads: against an independent correlation test, the
inversion of its interval, and simulation."""

import numpy as np
import pytest
from scipy import stats

from surrogate_rbrdo.validation.paired_spread import (
    min_detectable_sd_ratio,
    paired_spread,
    pitman_morgan_t,
    variance_ratio_ci,
)

A = np.array([12.1, 9.8, 15.3, 11.0, 8.7, 14.2, 10.5, 13.9, 9.1, 12.8])
B = np.array([10.2, 9.9, 12.0, 10.1, 9.0, 11.8, 9.7, 11.5, 9.3, 10.6])


@pytest.mark.known_answer
def test_statistic_is_the_sum_difference_correlation_test():
    # var(a) = var(b) iff corr(a + b, b - a) = 0: Pearson's test of that correlation (scipy)
    r, p = stats.pearsonr(A + B, B - A)
    t, df, pv = pitman_morgan_t(A, B)
    assert df == A.size - 2
    assert t == pytest.approx(r * np.sqrt(df) / np.sqrt(1 - r * r), rel=1e-12)
    assert pv == pytest.approx(p, rel=1e-10)
    assert t < 0      # B spreads less


@pytest.mark.known_answer
def test_interval_ends_are_where_the_test_just_rejects():
    F = B.var(ddof=1) / A.var(ddof=1)
    r = np.corrcoef(A, B)[0, 1]
    lo, hi = variance_ratio_ci(F, r, A.size, 0.95)
    tc = stats.t.ppf(0.975, A.size - 2)
    for lam in (lo, hi):      # B / sqrt(λ) has the ratio λ removed: |t| = t_crit exactly
        t, _, _ = pitman_morgan_t(A, B / np.sqrt(lam))
        assert abs(t) == pytest.approx(tc, rel=1e-9)
    assert lo < F < hi


def test_interval_coverage_bivariate_normal():
    rng = np.random.default_rng(11)
    ratio, rho, n, hits, reps = 0.6, 0.5, 12, 0, 2000
    cov = np.array([[1.0, rho * ratio], [rho * ratio, ratio**2]])
    for _ in range(reps):
        a, b = rng.multivariate_normal([0.0, 0.0], cov, size=n).T
        lo, hi = variance_ratio_ci(b.var(ddof=1) / a.var(ddof=1), np.corrcoef(a, b)[0, 1],
                                   n, 0.95)
        hits += lo <= ratio**2 <= hi
    assert 0.935 <= hits / reps <= 0.965     # exact under normality; SE 0.5 %


def test_power_statement_by_simulation():
    n, r = 20, 0.3
    q = min_detectable_sd_ratio(n, r)
    rng = np.random.default_rng(12)
    cov = np.array([[1.0, r * q], [r * q, q * q]])
    rej = np.mean([pitman_morgan_t(*rng.multivariate_normal([0, 0], cov, size=n).T)[2] < 0.05
                   for _ in range(4000)])
    assert rej == pytest.approx(0.8, abs=0.04)     # Fisher-z approximation


def test_paired_spread_fields():
    r = paired_spread(A, B, rng=np.random.default_rng(1), n_boot=2000)
    assert r.ratio == pytest.approx(B.std(ddof=1) / A.std(ddof=1))
    assert r.ratio_ci[0] < r.ratio < r.ratio_ci[1]
    lo, hi = r.bootstrap_relative_ci
    assert lo < r.relative_change < hi
    assert r.correlation == pytest.approx(np.corrcoef(A, B)[0, 1])


def test_bad_input():
    with pytest.raises(ValueError, match="at least 4"):
        paired_spread(A[:3], B[:3], rng=np.random.default_rng(0))
    with pytest.raises(ValueError, match="without spread"):
        pitman_morgan_t(A, np.full(A.size, 3.0))
    with pytest.raises(ValueError, match="rng"):
        paired_spread(A, B, rng=None)
