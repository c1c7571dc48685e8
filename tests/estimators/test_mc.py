"""Crude Monte Carlo and ``mc_from_values``: formulas, intervals and bad input."""

import warnings

import numpy as np
import pytest
from scipy import stats

from surrogate_rbrdo.core import LimitState, ModelError
from surrogate_rbrdo.estimators import MonteCarlo, mc_from_values
from surrogate_rbrdo.estimators.problems import correlated_normal, linear_standard

pytestmark = pytest.mark.known_answer


def test_eqs_12_to_14_against_numpy():
    y = np.random.default_rng(0).normal(size=(4, 57))
    est = mc_from_values(y, LimitState(0.5))
    np.testing.assert_allclose(est.mean, y.mean(1))
    np.testing.assert_allclose(est.std, y.std(1, ddof=1))
    np.testing.assert_allclose(est.pf, (y > 0.5).mean(1))
    np.testing.assert_allclose(est.mean_se, y.std(1, ddof=1) / np.sqrt(57))
    p = (y > 0.5).mean(1)
    np.testing.assert_allclose(est.pf_se, np.sqrt(p * (1 - p) / 57))
    assert est.n_calls == y.size


def test_failure_below_and_ties_are_safe():
    est = mc_from_values(np.array([[1.0, 2.0, 3.0]]), LimitState(2.0, failure_if="below"))
    assert est.pf[0] == pytest.approx(1 / 3)
    est = mc_from_values(np.array([[1.0, 2.0, 3.0]]), LimitState(2.0))
    assert est.pf[0] == pytest.approx(1 / 3)


@pytest.mark.parametrize("k, n", [(0, 1000), (3, 1000), (1000, 1000), (17, 50)])
def test_clopper_pearson_matches_scipy(k, n):
    y = np.r_[np.ones(k), np.zeros(n - k)][None, :]
    ci = mc_from_values(y, LimitState(0.5), ci_level=0.9).pf_ci[0]
    ref = stats.binomtest(k, n).proportion_ci(confidence_level=0.9, method="exact")
    np.testing.assert_allclose(ci, [ref.low, ref.high], rtol=1e-8, atol=1e-14)


def test_zero_failures_gives_zero_and_an_upper_bound():
    prob = linear_standard(beta=4.753424, dim=3)   # P_f = 1e-6
    est = MonteCarlo(10_000).estimate(prob.response, prob.inputs, prob.limit, prob.x,
                                      rng=np.random.default_rng(0))
    assert est.pf[0] == 0.0 and est.pf_se[0] == 0.0
    assert est.pf_ci[0, 0] == 0.0
    # exact one-sided 97.5 % bound: 1 - 0.025**(1/N) ~ 3.69/N, and it covers the truth
    assert est.pf_ci[0, 1] == pytest.approx(1 - 0.025 ** (1 / 10_000), rel=1e-9)
    assert est.pf_ci[0, 1] > prob.pf_exact[0]


def test_single_sample_gives_nan_std_without_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        est = mc_from_values(np.array([[1.0], [2.0]]), LimitState(1.5))
    assert np.isnan(est.std).all() and np.isnan(est.std_se).all()
    np.testing.assert_array_equal(est.pf, [0.0, 1.0])


def test_constant_response_has_zero_std():
    est = mc_from_values(np.ones((2, 10)), LimitState(2.0))
    np.testing.assert_array_equal(est.std, 0.0)
    np.testing.assert_array_equal(est.std_se, 0.0)


@pytest.mark.parametrize("y, match", [
    (np.zeros((2, 0)), "N >= 1"),
    (np.zeros((0, 5)), "one design"),
    (np.zeros(5), "must be \\(P, N\\)"),
])
def test_bad_values(y, match):
    with pytest.raises(ValueError, match=match):
        mc_from_values(y, LimitState(0.0))


def test_nan_values_name_design_and_sample():
    y = np.zeros((3, 4))
    y[2, 1] = np.nan
    with pytest.raises(ModelError, match="design 2, theta sample 1"):
        mc_from_values(y, LimitState(0.0))


def test_bad_ci_level():
    with pytest.raises(ValueError, match="ci_level"):
        mc_from_values(np.zeros((1, 3)), LimitState(0.0), ci_level=1.0)


def test_zero_sample_size_option():
    with pytest.raises(ValueError, match="n_samples = 0"):
        MonteCarlo(n_samples=0)


def test_known_answers_linear_several_designs():
    prob = linear_standard(beta=2.5, dim=4, shifts=(0.0, 0.5, 1.0, 2.5))
    est = MonteCarlo(40_000).estimate(prob.response, prob.inputs, prob.limit, prob.x,
                                      rng=np.random.default_rng(11))
    assert np.all(np.abs(est.pf - prob.pf_exact) <= 4 * est.pf_se)
    assert np.all(np.abs(est.mean - prob.mean_exact) <= 4 * est.mean_se)
    assert np.all(np.abs(est.std - prob.std_exact) <= 4 * est.std_se)
    # the delta-method SE of s agrees with the normal-theory value sigma / sqrt(2(N-1))
    np.testing.assert_allclose(est.std_se, 1 / np.sqrt(2 * 39_999), rtol=0.05)


def test_known_answers_correlated_normal():
    prob = correlated_normal()
    est = MonteCarlo(40_000).estimate(prob.response, prob.inputs, prob.limit, prob.x,
                                      rng=np.random.default_rng(12))
    assert np.all(np.abs(est.pf - prob.pf_exact) <= 4 * est.pf_se)
    assert np.all(np.abs(est.mean - prob.mean_exact) <= 4 * est.mean_se)
    assert np.all(np.abs(est.std - prob.std_exact) <= 4 * est.std_se)


def test_common_random_numbers():
    prob = linear_standard(beta=2.0, dim=2, shifts=(0.0, 0.3))
    u = np.random.default_rng(1).standard_normal((5000, 2))
    mc = MonteCarlo()
    a = mc.estimate(prob.response, prob.inputs, prob.limit, prob.x,
                    rng=np.random.default_rng(1), u=u)
    b = mc.estimate(prob.response, prob.inputs, prob.limit, prob.x[::-1],
                    rng=np.random.default_rng(2), u=u)
    np.testing.assert_array_equal(a.pf, b.pf[::-1])   # same u -> identical, whatever the rng
    assert a.diagnostics["n_failures"][1] >= a.diagnostics["n_failures"][0]
    assert a.n_calls == 2 * 5000


def test_vectorised_over_many_designs():
    y = np.random.default_rng(0).normal(size=(100, 1000))
    est = mc_from_values(y, LimitState(2.0))
    assert est.pf.shape == (100,) and est.pf_ci.shape == (100, 2)
