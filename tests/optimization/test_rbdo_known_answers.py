"""RBDO to published optima, comparing like with like.

* FORM-based solver (SLSQP on the formulation with ``estimator="form"``,
  ``reliability_measure="beta"``: the reliability-index approach) against the published FORM
  optima: Youn & Choi (σ = 0.3, β_t = 3 and σ = 0.6, β_t = 2), Kuschel & Rackwitz's short
  column (β_t = 2.5), Wu et al.'s cantilever (β_t = 3, where FORM is exact).
* Exact-probability solver (SLSQP on the common-sample quantile of crude MC, conservative
  Clopper–Pearson bound) against the exact-probability optimum of Youn & Choi, computed here
  independently by SLSQP on 1-D quadratures of the three probabilities (``youn_choi_pf``).
* Reliability of every design re-checked by an independent crude MC of 10⁶ samples (and by the
  quadrature where it exists) against 1.05 × P_target.

Sources and the measured table: ``docs/optimization.md``.
"""

import numpy as np
import pytest
from scipy import optimize, special

from surrogate_rbrdo.estimators import FORM
from surrogate_rbrdo.formulations import DeterministicOptions, FormulationOptions, make_formulation
from surrogate_rbrdo.optimization import NSGA2Options, SLSQPOptions, run_nsga2, run_slsqp
from surrogate_rbrdo.optimization.postprocess import select_compromise
from surrogate_rbrdo.optimization.rbdo_benchmarks import (
    cantilever,
    cantilever_pf,
    short_column,
    youn_choi,
    youn_choi_pf,
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


def mc_recheck(bench, x, n=1_000_000, seed=99):
    """Independent crude MC of every chance constraint at design x: P_f / P_target."""
    theta = bench.inputs.sample(n, rng=np.random.default_rng(seed))
    return np.array([np.mean(c.limit.failed(c.response(x[None, :], theta)[0]))
                     for c in bench.constraints]) / bench.p_target


@pytest.mark.parametrize("bench", [youn_choi(0.3, 3.0), short_column(), cantilever()],
                         ids=lambda b: b.name)
def test_form_solver_reaches_the_published_form_optimum(bench):
    x = form_optimum(bench)
    np.testing.assert_allclose(x, bench.published_x, rtol=0.01)
    cost = x.sum() if bench.name.startswith("youn_choi") else np.prod(x)
    assert cost == pytest.approx(bench.published_cost, rel=0.01)
    ratio = mc_recheck(bench, x)
    if bench.name == "youn_choi_s0.3_b3":
        # like with like: the FORM optimum is not the exact-probability one. G1 is curved: its
        # exact P_f there is 1.10 x the target (quadrature), which MC confirms
        exact = youn_choi_pf(x, 0.3)[:2] / bench.p_target
        assert 1.07 < exact[0] < 1.13 and exact[1] < 1.0
        assert abs(ratio[0] - exact[0]) < 0.09            # 4 SE of the 1e6-sample check
    else:
        assert np.all(ratio <= 1.05)


def test_form_solver_on_youn_choi_sigma_06():
    """Published (Youn & Choi 2004, J. Mech. Des., as quoted): μ* = (3.660, 3.609), cost 7.269,
    β = (2.0, 2.0, 4.436). The FORM optimum has that cost and β₃ with the coordinates exchanged
    (at the quoted point itself FORM gives β₂ = 1.90 < 2: infeasible) — see docs."""
    bench = youn_choi(0.6, 2.0)
    x = form_optimum(bench)
    assert x.sum() == pytest.approx(bench.published_cost, rel=0.001)
    np.testing.assert_allclose(x, bench.published_x[::-1], rtol=0.001)
    beta3 = FORM().estimate(bench.constraints[2].response, bench.inputs, bench.constraints[2]
                            .limit, x[None, :], rng=np.random.default_rng(0))
    assert beta3.diagnostics["beta"][0] == pytest.approx(4.436, abs=0.002)


def exact_youn_choi_optimum(sigma, beta_t):
    """Independent reference: SLSQP on the quadrature probabilities."""
    cons = {"type": "ineq",
            "fun": lambda d: -special.ndtri(np.maximum(youn_choi_pf(d, sigma)[:2], 1e-300))
            - beta_t}
    res = optimize.minimize(np.sum, np.array([3.5, 3.3]), method="SLSQP", constraints=[cons],
                            options={"ftol": 1e-12})
    assert res.success
    return res.x


def test_exact_probability_solver_youn_choi():
    """Conservative common-sample quantile (4·10⁵ samples, Clopper-Pearson 95 %): within 1 %
    of the exact-probability optimum (3.4539, 3.2750), and reliable by quadrature and MC."""
    bench = youn_choi(0.3, 3.0)
    ref = exact_youn_choi_optimum(0.3, 3.0)
    np.testing.assert_allclose(ref, [3.4539, 3.2750], atol=2e-4)
    form = formulation(bench, n_theta=400_000, reliability_measure="quantile", pf_bound="upper")
    res = run_slsqp(form, bench.lower, bench.upper, rng=np.random.default_rng(1),
                    options=SLSQPOptions(fd_step=1e-4))
    x = res.X[0]
    np.testing.assert_allclose(x, ref, rtol=0.01)
    assert np.all(youn_choi_pf(x, 0.3)[:2] <= 1.05 * bench.p_target)
    assert np.all(mc_recheck(bench, x) <= 1.05)
    assert len(res.archive) >= 5 and res.n_surrogate_calls > 0


@pytest.mark.slow
@pytest.mark.parametrize("sigma, beta_t", [(0.3, 3.0), (0.6, 2.0)])
def test_exact_probability_solver_youn_choi_1e6(sigma, beta_t):
    bench = youn_choi(sigma, beta_t)
    ref = exact_youn_choi_optimum(sigma, beta_t)
    form = formulation(bench, n_theta=1_000_000, reliability_measure="quantile",
                       pf_bound="upper", seed=3)
    x = run_slsqp(form, bench.lower, bench.upper, rng=np.random.default_rng(1),
                  options=SLSQPOptions(fd_step=1e-4)).X[0]
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


def test_cantilever_exact_optimum_by_closed_form():
    """FORM is exact for the cantilever (g linear in normals): SLSQP on the closed form gives
    the published optimum, area 9.5204."""
    res = optimize.minimize(
        np.prod, np.array([3.0, 3.0]), method="SLSQP", bounds=[(1, 5), (1, 5)],
        constraints=[{"type": "ineq",
                      "fun": lambda x: -special.ndtri(cantilever_pf(x)[0]) - 3.0}],
        options={"ftol": 1e-12})
    assert np.prod(res.x) == pytest.approx(9.5204, rel=1e-4)
    assert np.prod(form_optimum(cantilever())) == pytest.approx(np.prod(res.x), rel=1e-4)


@pytest.mark.slow
def test_nsga2_on_the_conservative_formulation():
    """NSGA-II (pop 60 x 100) on the conservative quantile formulation: cost within 1 % of the
    exact-probability optimum and the design reliable (quadrature)."""
    bench = youn_choi(0.3, 3.0)
    ref = exact_youn_choi_optimum(0.3, 3.0)
    form = formulation(bench, n_theta=100_000, reliability_measure="quantile", pf_bound="upper")
    res = run_nsga2(form, bench.lower, bench.upper, rng=np.random.default_rng(1),
                    options=NSGA2Options(pop_size=60, n_gen=100))
    x = select_compromise(res).x
    assert x.sum() == pytest.approx(ref.sum(), rel=0.01)
    assert np.all(youn_choi_pf(x, 0.3)[:2] <= 1.05 * bench.p_target)
