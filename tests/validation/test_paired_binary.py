"""Paired failure indicators: McNemar, Newcombe's interval, power — against hand computations,
statsmodels and simulation."""

import numpy as np
import pytest
from scipy import stats

from surrogate_rbrdo.validation.paired_binary import (
    mcnemar_exact_p,
    mcnemar_power,
    min_detectable_p_before,
    newcombe_paired_ci,
    paired_proportions,
)


def _pairs(both, before_only, after_only, neither):
    before = np.r_[np.ones(both + before_only), np.zeros(after_only + neither)].astype(bool)
    after = np.r_[np.ones(both), np.zeros(before_only), np.ones(after_only),
                  np.zeros(neither)].astype(bool)
    return before, after


@pytest.mark.known_answer
def test_table_and_exact_mcnemar_by_hand():
    before, after = _pairs(2, 9, 1, 8)
    r = paired_proportions(before, after)
    assert (r.both, r.before_only, r.after_only, r.neither) == (2, 9, 1, 8)
    assert r.p_before == pytest.approx(11 / 20) and r.p_after == pytest.approx(3 / 20)
    assert r.diff == pytest.approx(-8 / 20)
    # 10 discordant pairs, 1 against: 2 * (1 + 10) / 2**10
    assert r.mcnemar_p == pytest.approx(2 * 11 / 1024)
    assert r.cohens_g == pytest.approx(1 / 10 - 0.5)
    assert r.relative_change == pytest.approx(3 / 11 - 1)
    # Clopper-Pearson limits of 11/20: Beta quantiles
    assert r.p_before_ci[0] == pytest.approx(stats.beta.ppf(0.025, 11, 10))
    assert r.p_before_ci[1] == pytest.approx(stats.beta.ppf(0.975, 12, 9))


@pytest.mark.known_answer
def test_mcnemar_against_statsmodels():
    sm = pytest.importorskip("statsmodels.stats.contingency_tables")
    for table in ([[2, 9], [1, 8]], [[0, 6], [0, 14]], [[5, 3], [4, 8]], [[0, 0], [0, 20]]):
        (a, b), (c, d) = table
        ref = sm.mcnemar(np.array(table), exact=True).pvalue
        assert mcnemar_exact_p(b, c) == pytest.approx(ref, rel=1e-12)


@pytest.mark.known_answer
def test_newcombe_method_10_by_hand():
    """Newcombe (1998) method 10 written out with independent Wilson limits (statsmodels)."""
    prop = pytest.importorskip("statsmodels.stats.proportion")
    a, b, c, d = 2, 9, 1, 8
    n = a + b + c + d
    p1, p2 = (a + b) / n, (a + c) / n
    l1, u1 = prop.proportion_confint(a + b, n, alpha=0.05, method="wilson")
    l2, u2 = prop.proportion_confint(a + c, n, alpha=0.05, method="wilson")
    phi = (a * d - b * c) / np.sqrt((a + b) * (c + d) * (a + c) * (b + d))
    lo = (p2 - p1) - np.sqrt((p2 - l2) ** 2 - 2 * phi * (p2 - l2) * (u1 - p1) + (u1 - p1) ** 2)
    hi = (p2 - p1) + np.sqrt((u2 - p2) ** 2 - 2 * phi * (u2 - p2) * (p1 - l1) + (p1 - l1) ** 2)
    assert newcombe_paired_ci(a, b, c, d, 0.95) == pytest.approx((lo, hi), abs=1e-12)
    # no pair where the after design fails: φ = 0 and P_after's Wilson interval is [0, u2]
    l1, u1 = prop.proportion_confint(6, 20, alpha=0.05, method="wilson")
    _, u2 = prop.proportion_confint(0, 20, alpha=0.05, method="wilson")
    lo0, hi0 = newcombe_paired_ci(0, 6, 0, 14, 0.95)
    assert lo0 == pytest.approx(-u1, abs=1e-12)
    assert hi0 == pytest.approx(-0.3 + np.hypot(u2, 0.3 - l1), abs=1e-12)


def test_newcombe_coverage():
    rng = np.random.default_rng(5)
    probs = np.array([0.1, 0.3, 0.05, 0.55])      # both, before only, after only, neither
    true = probs[0] + probs[2] - probs[0] - probs[1]
    tables = rng.multinomial(20, probs, size=2000)
    hits = np.mean([lo <= true <= hi for lo, hi in
                    (newcombe_paired_ci(*t, 0.95) for t in tables)])
    # Newcombe reports coverage close to nominal for method 10; 2000 reps: SE 0.5 %
    assert 0.93 <= hits <= 0.99


@pytest.mark.known_answer
def test_power_exact_and_by_simulation():
    # all discordant pairs one way: reject iff at least 6 of them (2 / 2**6 < 0.05)
    assert mcnemar_power(20, 0.5, 0.0) == pytest.approx(stats.binom.sf(5, 20, 0.5))
    p = min_detectable_p_before(20)
    assert stats.binom.sf(5, 20, p) == pytest.approx(0.8, abs=1e-5)
    # a two-sided case by simulating the test itself
    rng = np.random.default_rng(6)
    tables = rng.multinomial(30, [0.05, 0.35, 0.1, 0.5], size=20000)
    rej = np.mean([mcnemar_exact_p(t[1], t[2]) <= 0.05 for t in tables])
    assert rej == pytest.approx(mcnemar_power(30, 0.35, 0.1), abs=0.01)
    assert np.isnan(min_detectable_p_before(4))          # 2 / 2**4 > 0.05: never


@pytest.mark.parametrize(("before", "after", "match"), [
    ([1, 0, 2], [1, 0, 1], "failure indicators"),
    ([1, 0, 1], [1, 0], "same length"),
])
def test_bad_input(before, after, match):
    with pytest.raises(ValueError, match=match):
        paired_proportions(before, after)


def test_power_bad_probabilities():
    with pytest.raises(ValueError, match="sum <= 1"):
        mcnemar_power(10, 0.8, 0.4)
