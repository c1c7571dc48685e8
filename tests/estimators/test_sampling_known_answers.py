"""Known-answer tests of the sampling estimators (IS, adaptive IS, subset simulation, MC).

References: closed forms (linear, correlated normal, Nataf lognormal) and 1-D quadratures of the
parabolic limit state (Breitung 1984) and the four-branch series system (Waarts 2000), see
:mod:`surrogate_rbrdo.estimators.problems`.
"""

import numpy as np
import pytest

from surrogate_rbrdo.estimators import get_estimator
from surrogate_rbrdo.estimators._common import LimitStateU
from surrogate_rbrdo.estimators.problems import (
    correlated_normal,
    linear_standard,
    lognormal_nataf,
    paraboloid,
    series_four_branch,
    two_design_points,
    uniform_sum,
)

pytestmark = pytest.mark.known_answer

PF_1E6 = linear_standard(beta=4.753424, dim=5)       # P_f = 1.0000e-6


def run(name, prob, seed=0, **opts):
    return get_estimator(name, **opts).estimate(prob.response, prob.inputs, prob.limit, prob.x,
                                                rng=np.random.default_rng(seed))


def within(est, prob, k=4.0):
    return np.all(np.abs(est.pf - prob.pf_exact) <= k * est.pf_se)


@pytest.mark.parametrize("prob", [
    linear_standard(beta=3.0, dim=3, shifts=(0.0, 1.0, -1.0)),
    correlated_normal(),
    lognormal_nataf(),
    paraboloid(),
    PF_1E6,
    linear_standard(beta=-1.0, dim=2),
    uniform_sum(),
], ids=lambda p: p.name)
@pytest.mark.parametrize("name", ["is", "ais"])
def test_is_and_ais_within_4_se(name, prob):
    est = run(name, prob, seed=1)
    assert within(est, prob)
    assert np.all(est.pf_cov < 0.2)


def test_is_exact_on_the_linear_anchor_within_1500_calls():
    """The linear 10-D anchor at P_f = 2.9e-7: the half-space control variate makes IS exact
    *by construction* (the target of issue 13 is judged on the curved case below)."""
    prob = linear_standard(beta=5.0, dim=10)
    runs = [run("is", prob, seed=s, n_samples=1370) for s in range(3)]
    assert all(r.n_calls <= 1500 for r in runs)
    assert all(abs(r.pf[0] / prob.pf_exact[0] - 1) < 1e-6 for r in runs)


CURVED_10D = paraboloid(beta=5.0, kappa=0.05, dim=10)      # P_f = 9.97e-8 by quadrature


def test_is_target_on_a_curved_10d_limit_state_reported():
    """Issue 13 target on a curved limit state (the paraboloid, where the hyperplane is a poor
    control): every run reports CoV <= 5 % with <= 1 500 model calls (FORM and the searches
    for further design points included) and covers the exact value within 3 SE."""
    runs = [run("is", CURVED_10D, seed=s, n_samples=1370) for s in range(6)]
    assert all(r.n_calls <= 1500 for r in runs)
    assert all(r.pf_cov[0] <= 0.05 and within(r, CURVED_10D, k=3.0) for r in runs)


@pytest.mark.slow
def test_is_target_on_a_curved_10d_limit_state_empirical():
    """The same over 20 seeds, judged by the run-to-run scatter: CoV <= 5 % at <= 1 500 calls
    (plain post-FORM IS at N(u*, I), as OpenTURNS does it, scatters by 6.3 % at that budget:
    benchmarks/bench_is_small_pf.py)."""
    runs = [run("is", CURVED_10D, seed=s, n_samples=1370) for s in range(20)]
    pf = np.array([r.pf[0] for r in runs])
    assert all(r.n_calls <= 1500 for r in runs)
    assert pf.std(ddof=1) / CURVED_10D.pf_exact[0] <= 0.05
    assert abs(pf.mean() / CURVED_10D.pf_exact[0] - 1) <= 3 * 0.05 / np.sqrt(20)


@pytest.mark.parametrize("prob", [series_four_branch(6.0), two_design_points()],
                         ids=lambda p: p.name)
def test_is_finds_several_design_points_and_ais_copes(prob):
    """Several design points: the searches (and the first stage's tail samples) find them all
    — four on the series system, two on the parabola — and IS covers without a warning; ais
    needs no design point."""
    expected = 4 if prob.name.startswith("series") else 2
    for seed in range(3):
        est = run("is", prob, seed=seed)
        assert est.diagnostics["n_design_points"][0] == expected
        assert within(est, prob, k=3.0)
        assert within(run("ais", prob, seed=seed), prob)


def test_ais_unbiased_on_series_system():
    """Mean of 8 independent runs within 4 standard errors of the mean, and honest SEs (the
    k = 7 system: its weaker branch pair carries 21 % of P_f). At most one of the 8 runs
    outside 4 of its SEs: over seeds 0–99, 4 runs had |z| of 4.2 to 8.4 (a branch
    under-sampled, Pareto k̂ < 0.7, no warning; 0 of 100 with the generator as passed before
    the per-design seeding of est5, max |z| 3.4: other draws of the same estimator)."""
    prob = series_four_branch(7.0)
    res = [run("ais", prob, seed=s) for s in range(8)]
    pf = np.array([r.pf[0] for r in res])
    se = np.array([r.pf_se[0] for r in res])
    assert abs(pf.mean() - prob.pf_exact[0]) <= 4 * pf.std(ddof=1) / np.sqrt(8)
    assert np.sum(np.abs(pf - prob.pf_exact[0]) > 4 * se) <= 1
    assert 0.5 < pf.std(ddof=1) / se.mean() < 2.0        # reported SE matches the scatter


def test_is_common_random_numbers():
    prob = linear_standard(beta=3.5, dim=3, shifts=(0.0, 0.5))
    u = np.random.default_rng(4).standard_normal((1000, 3))
    est = get_estimator("is")
    a = est.estimate(prob.response, prob.inputs, prob.limit, prob.x,
                     rng=np.random.default_rng(1), u=u)
    b = est.estimate(prob.response, prob.inputs, prob.limit, prob.x,
                     rng=np.random.default_rng(2), u=u)
    np.testing.assert_array_equal(a.pf, b.pf)
    assert a.diagnostics["n_samples"] == 1000


def test_crude_mc_cannot_reach_1e6_but_is_can():
    mc = run("mc", PF_1E6, n_samples=100_000)
    assert mc.pf[0] == 0.0 and mc.pf_ci[0, 1] > PF_1E6.pf_exact[0]
    est = run("is", PF_1E6)
    assert within(est, PF_1E6) and est.pf_cov[0] < 0.07 and est.n_calls < 2100


@pytest.mark.parametrize("prob", [series_four_branch(6.0), series_four_branch(7.0),
                                  paraboloid(), linear_standard(beta=-1.0, dim=2)],
                         ids=lambda p: p.name)
def test_subset_within_4_se(prob):
    assert within(run("subset", prob, seed=5), prob)


def test_subset_unbiased_at_1e6():
    res = [run("subset", PF_1E6, seed=s) for s in range(25)]
    pf = np.array([r.pf[0] for r in res])
    assert abs(pf.mean() - PF_1E6.pf_exact[0]) <= 4 * pf.std(ddof=1) / 5
    cov = np.array([r.pf_cov[0] for r in res])
    # the reported CoV is that of the scatter (not inflated): within a factor 1.5 of the
    # run-to-run CoV (its own sampling error over 25 runs is about ±20 %)
    assert 1 / 1.5 < cov.mean() / (pf.std(ddof=1) / PF_1E6.pf_exact[0]) < 1.5
    # pf_se is P̂·δ and the log-normal interval contains the estimate
    assert all(r.pf_se[0] == pytest.approx(r.pf[0] * c) for r, c in zip(res, cov, strict=True))
    assert all(r.pf_ci[0, 0] < r.pf[0] < r.pf_ci[0, 1] for r in res)


def test_subset_pools_independent_runs_at_small_pf():
    """At 2.9e-7 in 10-D one run has δ ≈ 0.5: runs are added until the CoV of their mean is at
    most target_cov; the result is the mean of the same runs made one by one (same generator)
    with the standard error √(Σ SE_r²)/R."""
    prob = linear_standard(beta=5.0, dim=10)
    est = run("subset", prob, seed=2)
    n = int(est.diagnostics["runs"][0])
    assert 2 <= n <= 4 and (est.pf_cov[0] <= 0.3 or n == 4)
    # the runs of one design, one by one from one generator (the estimator seeds each
    # design's generator from `rng`, so the same runs are made here from the design's level)
    sub = get_estimator("subset")
    G = LimitStateU(prob.response, prob.inputs, prob.limit, prob.x[0])
    pooled = sub._one(G, 10, None, np.random.default_rng(5))
    rng = np.random.default_rng(5)
    single = [sub._run(G, 10, None, rng) for _ in range(int(pooled.extra[-1]))]
    assert pooled.pf == pytest.approx(np.mean([r.pf for r in single]), rel=1e-12)
    se = np.sqrt(sum(r.se ** 2 for r in single)) / len(single)
    assert pooled.se == pytest.approx(se, rel=1e-12)
    assert len(single) >= 2
    assert run("subset", prob, seed=2, max_runs=1).diagnostics["runs"][0] == 1


def test_ais_and_subset_moments_from_first_level():
    prob = correlated_normal()
    for name in ("ais", "subset"):
        est = run(name, prob, seed=3)
        assert np.all(np.abs(est.mean - prob.mean_exact) <= 4 * est.mean_se)
        assert np.all(np.abs(est.std - prob.std_exact) <= 4 * est.std_se)


@pytest.mark.parametrize("name", ["mc", "is", "ais", "subset"])
def test_non_normal_inputs_uniform_sum(name):
    prob = uniform_sum()
    est = run(name, prob, seed=7)
    assert within(est, prob)
    if name == "mc":
        assert abs(est.mean[0] - 1.0) <= 4 * est.mean_se[0]
        assert abs(est.std[0] - prob.std_exact[0]) <= 4 * est.std_se[0]


def test_diagnostics_are_read_only():
    est = run("is", uniform_sum())
    with pytest.raises(TypeError):
        est.diagnostics["ess"] = 0
    with pytest.raises(ValueError):
        est.diagnostics["u_star"][0, 0] = 1.0


@pytest.mark.parametrize("name", ["ais", "subset"])
def test_adaptive_methods_bound_designs_that_never_fail(name):
    """A design that never fails gets an upper bound P(G <= γ_last) (status "not_reached"),
    or a ModelError / NaN on request; the search stops early when the thresholds stall."""
    from surrogate_rbrdo.core import LimitState, ModelError
    from surrogate_rbrdo.uncertainty import MultivariateNormal

    inputs = MultivariateNormal(np.zeros(2), cov=np.eye(2))

    def resp(x, t):                       # bounded response that never exceeds the limit
        return np.tanh(t[:, :1].T)

    def go(**opts):
        return get_estimator(name, **opts).estimate(
            resp, inputs, LimitState(2.0), np.zeros((1, 0)), rng=np.random.default_rng(0))

    est = go()
    assert est.diagnostics["status"][0] == "not_reached"
    assert 0.0 < est.pf[0] < 0.5 and est.pf_ci[0, 0] == 0.0 and est.pf_ci[0, 1] >= est.pf[0]
    assert est.n_calls <= 10 * get_estimator(name).n_per_level  # stopped early
    with pytest.raises(ModelError, match="did not reach the failure domain for design 0"):
        go(on_failure="raise")
    assert np.isnan(go(on_failure="nan").pf[0])


@pytest.mark.parametrize("beta", [-3.0, -4.0])
def test_is_when_the_mean_point_fails(beta):
    """P_f = Φ(−β) close to 1: weighting the failures at u* has variance ~ exp(β²) (β = −3
    once gave 0.46 ± 0.06 for 0.9987); the complement estimate must be within 4 SE and tight."""
    prob = linear_standard(beta=beta, dim=3)
    est = run("is", prob, seed=3)
    assert within(est, prob)
    q = 1.0 - prob.pf_exact[0]  # the safe-tail probability the estimate rests on
    assert abs((1.0 - est.pf[0]) / q - 1.0) < 0.2
    assert est.pf_se[0] / q < 0.1
