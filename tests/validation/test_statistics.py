"""Paired statistics against published values and independent simulations."""

import numpy as np
import pytest

from surrogate_rbrdo.validation import (
    min_detectable_d_z,
    paired_comparison,
    paired_power,
)

# Student (1908) / R datasets::sleep: extra sleep (h) of 10 patients under two drugs
DRUG1 = np.array([0.7, -1.6, -0.2, -1.2, -0.1, 3.4, 3.7, 0.8, 0.0, 2.0])
DRUG2 = np.array([1.9, 0.8, 1.1, 0.1, -0.1, 4.4, 5.5, 1.6, 4.6, 3.4])


@pytest.mark.known_answer
def test_sleep_data_against_r_t_test():
    # R: t.test(extra ~ group, data = sleep, paired = TRUE): t = -4.0621, df = 9,
    # p-value = 0.002833, 95 % CI -2.4598858 -0.7001142, mean difference -1.58 (1 - 2)
    r = paired_comparison(DRUG1, DRUG2, rng=np.random.default_rng(1), n_boot=2000)
    assert r.t == pytest.approx(4.0621, abs=1e-4)
    assert r.df == 9
    assert r.p_value == pytest.approx(0.002833, abs=1e-6)
    assert r.diff_ci == pytest.approx((0.7001142, 2.4598858), abs=1e-6)
    assert r.mean_diff == pytest.approx(1.58)


@pytest.mark.known_answer
def test_effect_sizes_by_hand():
    r = paired_comparison(DRUG1, DRUG2, rng=np.random.default_rng(1), n_boot=2000)
    # R: sd(sleep$extra[1:10]) = 1.789010, sd(sleep$extra[11:20]) = 2.002249,
    # sd of the differences 1.229995
    assert r.sd_diff == pytest.approx(1.229995, abs=1e-6)
    assert r.d_z == pytest.approx(1.58 / 1.229995, rel=1e-6)
    assert r.d_av == pytest.approx(1.58 / ((1.789010 + 2.002249) / 2), rel=1e-6)
    assert r.d_z_ci[0] < r.d_z < r.d_z_ci[1]
    # the baseline has non-positive values: no relative change
    assert np.isnan(r.relative_change)


@pytest.mark.known_answer
def test_wilcoxon_exact_all_positive():
    # n = 6 distinct positive differences: the exact two-sided p is 2 / 2**6
    before = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
    after = before + np.array([0.1, 0.4, 0.2, 0.8, 1.6, 3.2])
    r = paired_comparison(before, after, rng=np.random.default_rng(2), n_boot=2000)
    assert r.wilcoxon_statistic == 0.0
    assert r.wilcoxon_p == pytest.approx(2 / 64)
    assert r.relative_change == pytest.approx(after.mean() / before.mean() - 1)
    lo, hi = r.bootstrap_relative_ci
    assert lo < r.relative_change < hi


@pytest.mark.known_answer
def test_power_against_gpower_and_simulation():
    # G*Power 3.1, "Means: difference from constant (one sample case)" / matched pairs:
    # d_z = 0.5, n = 20, α = 0.05 two-tailed -> power 0.5645; n = 20, power 0.8 -> d_z 0.660
    assert paired_power(20, 0.5) == pytest.approx(0.5645, abs=1e-4)
    assert min_detectable_d_z(20) == pytest.approx(0.660, abs=1e-3)
    # independent check by simulation of the t-test itself
    from scipy import stats

    rng = np.random.default_rng(3)
    d = rng.normal(0.7, 1.0, size=(20000, 12))
    p = stats.ttest_1samp(d, 0.0, axis=1).pvalue
    assert np.mean(p < 0.05) == pytest.approx(paired_power(12, 0.7), abs=0.012)


def test_d_z_interval_covers_at_nominal_rate():
    rng = np.random.default_rng(4)
    hits = 0
    reps = 300
    for _ in range(reps):
        a = rng.normal(10.0, 1.0, 8)
        b = a + rng.normal(0.8, 0.5, 8)          # true d_z = 1.6
        r = paired_comparison(a, b, rng=rng, n_boot=200)
        hits += r.d_z_ci[0] <= 1.6 <= r.d_z_ci[1]
    # 95 % nominal; binomial SE at 300 reps is 1.3 %
    assert 0.91 <= hits / reps <= 0.99


@pytest.mark.parametrize(("before", "after", "match"), [
    ([1.0, 2.0], [1.0, 2.0], "at least 3 pairs"),
    ([1.0, 2.0, 3.0], [1.0, 2.0], "same length"),
    ([1.0, np.nan, 3.0], [1.0, 2.0, 3.0], "NaN"),
    ([1.0, 2.0, 3.0], [2.0, 3.0, 4.0], "same amount"),
])
def test_bad_input(before, after, match):
    with pytest.raises(ValueError, match=match):
        paired_comparison(before, after, rng=np.random.default_rng(0))


def test_rng_required():
    with pytest.raises(ValueError, match="rng"):
        paired_comparison(DRUG1, DRUG2, rng=None)
