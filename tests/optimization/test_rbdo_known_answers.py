"""RBDO to published optima, comparing like with like.

* FORM-based solver (SLSQP on the formulation with ``estimator="form"``,
  ``reliability_measure="beta"``: the reliability-index approach) against the published FORM
  optima — Youn & Choi (σ = 0.3, β_t = 3 and σ = 0.6, β_t = 2), Kuschel & Rackwitz's short
  column (β_t = 2.5), Wu et al.'s cantilever (β_t = 3, FORM exact) — to 0.1 %, which tells the
  FORM optimum from the exact-probability one (0.35–1.4 % apart on Youn & Choi), and against an
  independent nested-SLSQP FORM optimum (``rbdo_references``; the all-normal short column at
  β_t = 3, whose published optimum we could not find).
* Exact-probability solver (SLSQP on the common-sample quantile of crude MC, conservative
  Clopper–Pearson bound): one design judged by both acceptance criteria of issue 13 — within
  1 % of the published optimum *and* reliable to 1.05 × P_target by an independent MC of 10⁶
  samples — and closer to the independent exact-probability optimum (1-D quadratures) than the
  FORM optimum is.
* The FORM optimum of Youn & Choi is *not* reliable to 1.05 × P_target (G₁ is curved); its
  exact P_f is checked to be what the quadrature says, so that the two criteria are never mixed.

Sources and the measured table: ``docs/optimization.md``.
"""

import numpy as np
import pytest

from surrogate_rbrdo.formulations import DeterministicOptions, FormulationOptions, make_formulation
from surrogate_rbrdo.optimization import NSGA2Options, SLSQPOptions, run_nsga2, run_slsqp
from surrogate_rbrdo.optimization.postprocess import select_compromise
from surrogate_rbrdo.optimization.rbdo_benchmarks import (
    cantilever,
    short_column,
    youn_choi,
    youn_choi_pf,
)
from surrogate_rbrdo.optimization.rbdo_references import (
    exact_optimum,
    form_optimum_nested,
    mc_recheck,
    reliability_index,
)

pytestmark = pytest.mark.known_answer
NO_DET = DeterministicOptions(stress=False, resonance="none")


def formulation(bench, seed=0, **opts):
    return make_formulation(
        "rbdo", response=bench.cost, inputs=bench.inputs, limit=None,
        extra_reliability=bench.constraints, rng=np.random.default_rng(seed),
        options=FormulationOptions(p_target=bench.p_target, deterministic=NO_DET,
                                   **{"n_theta": 100, **opts}))


def form_optimum(bench):
    form = formulation(bench, estimator="form", reliability_measure="beta",
                       estimator_options={"fd_scheme": "central", "tol_g": 1e-10})
    return run_slsqp(form, bench.lower, bench.upper, rng=np.random.default_rng(1)).X[0]


def exact_solver(bench, n_theta, seed=0):
    form = formulation(bench, seed=seed, n_theta=n_theta, reliability_measure="quantile",
                       pf_bound="upper")
    return run_slsqp(form, bench.lower, bench.upper, rng=np.random.default_rng(1),
                     options=SLSQPOptions(fd_step=1e-4))


def cost_of(bench, x):
    return float(np.mean(bench.cost(np.asarray(x)[None, :], bench.inputs.mean[None, :])))


@pytest.mark.parametrize("bench", [youn_choi(0.3, 3.0), youn_choi(0.6, 2.0), short_column()],
                         ids=lambda b: b.name)
def test_form_solver_reaches_the_published_form_optimum(bench):
    """To 0.1 % in the design: the exact-probability optimum of Youn & Choi is 0.35–1.4 % away,
    so this tolerance tells the two apart."""
    x = form_optimum(bench)
    np.testing.assert_allclose(x, bench.published_x, rtol=1e-3)
    assert cost_of(bench, x) == pytest.approx(bench.published_cost, rel=1e-3)
    ref = exact_optimum(bench)
    if ref is not None:
        assert np.max(np.abs(ref / np.asarray(bench.published_x) - 1)) > 3e-3


@pytest.mark.parametrize("sigma, beta_t", [(0.3, 3.0), (0.6, 2.0)])
def test_form_optimum_of_youn_choi_is_not_reliable_to_1_05(sigma, beta_t):
    """Like with like: at the FORM optimum G₁'s exact P_f is 1.10 x (σ = 0.3) and 1.12 x
    (σ = 0.6) the target by quadrature, which an independent MC of 10⁶ samples confirms."""
    bench = youn_choi(sigma, beta_t)
    x = form_optimum(bench)
    exact = youn_choi_pf(x, sigma)[:2] / bench.p_target
    assert exact[0] > 1.05 and exact[1] < 1.0
    mc = mc_recheck(bench, x)
    se = np.sqrt(exact[0] / bench.p_target / 1e6)
    assert abs(mc[0] - exact[0]) < 4 * se


def test_form_solver_matches_an_independent_form_optimum():
    """Youn & Choi σ = 0.6 against nested SLSQP design-point searches (no estimator of the
    toolkit): same point to 0.01 %, FORM β = (2, 2, 4.436) as published."""
    bench = youn_choi(0.6, 2.0)
    ref = form_optimum_nested(bench)
    x = form_optimum(bench)
    np.testing.assert_allclose(x, ref, rtol=1e-4)
    assert reliability_index(bench, x, 2) == pytest.approx(4.436, abs=0.002)


@pytest.mark.slow
def test_all_normal_short_column_at_beta_3_against_an_independent_form_optimum():
    """The all-normal short column at β_t = 3 (no published optimum verified): the FORM solver
    against nested SLSQP to 0.05 %, and the exact-probability solver reliable by MC."""
    bench = short_column("normal", 3.0)
    np.testing.assert_allclose(form_optimum(bench), form_optimum_nested(bench), rtol=5e-4)
    x = exact_solver(bench, 400_000).X[0]
    assert np.all(mc_recheck(bench, x) <= 1.05)


def test_exact_probability_design_meets_both_criteria():
    """One design, both acceptance criteria of issue 13 (Youn & Choi σ = 0.3, β_t = 3): within
    1 % of the published optimum and reliable to 1.05 x P_target by an independent MC of 10⁶
    samples (every chance constraint) and by quadrature — where the FORM optimum is not
    (previous test): the criteria tell the two optima apart by their reliability."""
    bench = youn_choi(0.3, 3.0)
    res = exact_solver(bench, 400_000)
    x = res.X[0]
    np.testing.assert_allclose(x, bench.published_x, rtol=0.01)
    assert np.all(mc_recheck(bench, x) <= 1.05)
    assert np.all(youn_choi_pf(x, 0.3)[:2] <= 1.05 * bench.p_target)
    np.testing.assert_allclose(x, exact_optimum(bench), rtol=0.01)
    assert len(res.archive) >= 5 and res.n_surrogate_calls > 0


def test_exact_probability_design_youn_choi_sigma_06():
    """σ = 0.6, β_t = 2: the exact-probability design is within 1 % of the independent
    exact-probability optimum (quadrature) and reliable by an independent MC of 10⁶ samples.
    It is 1.4 % from the published FORM optimum, whose own exact P_f is 1.12 x P_target: here no
    design can meet both 'within 1 % of the published optimum' and 'MC within 1.05 x P_target'
    (docs/optimization.md)."""
    bench = youn_choi(0.6, 2.0)
    x = exact_solver(bench, 100_000).X[0]
    ref = exact_optimum(bench)
    np.testing.assert_allclose(x, ref, rtol=0.01)
    assert np.all(mc_recheck(bench, x) <= 1.05)
    assert np.max(np.abs(ref / np.asarray(bench.published_x) - 1)) > 0.01


def test_cantilever_one_design_meets_both_criteria():
    """FORM is exact for the cantilever (g linear in normals): the FORM solver's design is within
    0.2 % of the published optimum (area to 0.01 %: a flat valley) and of the closed-form exact
    optimum, and reliable by an independent MC of 10⁶ samples."""
    bench = cantilever()
    x = form_optimum(bench)
    np.testing.assert_allclose(x, bench.published_x, rtol=2e-3)
    assert np.prod(x) == pytest.approx(bench.published_cost, rel=1e-4)
    np.testing.assert_allclose(x, exact_optimum(bench), rtol=1e-3)
    assert np.all(mc_recheck(bench, x) <= 1.05)


def test_short_column_one_design_meets_both_criteria():
    """Kuschel & Rackwitz's short column (lognormal Y, β_t = 2.5): the FORM design is within
    0.1 % of the published optimum and reliable by an independent MC of 10⁶ samples."""
    bench = short_column()
    x = form_optimum(bench)
    np.testing.assert_allclose(x, bench.published_x, rtol=1e-3)
    assert np.all(mc_recheck(bench, x) <= 1.05)


@pytest.mark.slow
@pytest.mark.parametrize("sigma, beta_t", [(0.3, 3.0), (0.6, 2.0)])
def test_exact_probability_solver_youn_choi_1e6(sigma, beta_t):
    bench = youn_choi(sigma, beta_t)
    ref = exact_optimum(bench)
    x = exact_solver(bench, 1_000_000, seed=3).X[0]
    np.testing.assert_allclose(x, ref, rtol=0.005)
    assert np.all(mc_recheck(bench, x, n=4_000_000) <= 1.05)


@pytest.mark.slow
def test_sample_average_constraint_suffers_the_optimisers_curse():
    """Without the bound, the sample-average optimum sits on the sample's boundary: over
    seeds its exact P_f scatters around the target (here by ~8 % for 10⁵ samples), so some
    designs exceed it; the conservative bound keeps every one of them below."""
    bench = youn_choi(0.3, 3.0)
    worst = {}
    for bound in ("estimate", "upper"):
        ratios = []
        for seed in range(3):
            form = formulation(bench, seed=seed, n_theta=100_000,
                               reliability_measure="quantile", pf_bound=bound)
            x = run_slsqp(form, bench.lower, bench.upper, rng=np.random.default_rng(1),
                          options=SLSQPOptions(fd_step=1e-4)).X[0]
            ratios.append(youn_choi_pf(x, 0.3)[:2].max() / bench.p_target)
        worst[bound] = max(ratios)
    assert worst["estimate"] > 1.0 > worst["upper"]


@pytest.mark.slow
def test_nsga2_on_the_conservative_formulation():
    """NSGA-II (pop 60 x 100) on the conservative quantile formulation: cost within 1 % of the
    exact-probability optimum and the design reliable (quadrature)."""
    bench = youn_choi(0.3, 3.0)
    ref = exact_optimum(bench)
    form = formulation(bench, n_theta=100_000, reliability_measure="quantile", pf_bound="upper")
    res = run_nsga2(form, bench.lower, bench.upper, rng=np.random.default_rng(1),
                    options=NSGA2Options(pop_size=60, n_gen=100))
    x = select_compromise(res).x
    assert x.sum() == pytest.approx(ref.sum(), rel=0.01)
    assert np.all(youn_choi_pf(x, 0.3)[:2] <= 1.05 * bench.p_target)
