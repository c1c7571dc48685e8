"""Known answers: closed-form RDO/RBRDO fronts of a toy (published RBDO optima:
test_rbdo_known_answers.py)."""

import numpy as np
import pytest

from surrogate_rbrdo.formulations import DeterministicOptions, FormulationOptions, make_formulation
from surrogate_rbrdo.optimization import (
    NSGA2Options,
    archive_front,
    run_nsga2,
)
from surrogate_rbrdo.optimization.toys import (
    LinearMixToy,
)

pytestmark = pytest.mark.known_answer
NO_DET = DeterministicOptions(stress=False, resonance="none")
TOY = LinearMixToy()  # y = x θ1 + (1 − x) θ2, θ1 ~ N(1, 2²), θ2 ~ N(3, 1²), failure y > 3.5
N_THETA = 50_000
# Tolerances: with N = 5e4 the sample mean and std of y are off by ≲ 4 σ_y/√N ≈ 0.03 and
# 4 σ_y/√(2N) ≈ 0.02; P_f is off by ≲ 4 √(0.09/N) = 0.005, which moves the steep reliability
# boundary x_a by ≲ 0.02 (dP_f/dx ≈ −0.3 there); P_f(x = 1) = 0.106 stays 10 SE below 0.12.
TOL_CURVE = 0.04
TOL_X = 0.03


def toy_run(name, seed=0, p_target=0.1):
    form = make_formulation(
        name, response=TOY.response, inputs=TOY.inputs(), limit=TOY.limit,
        options=FormulationOptions(p_target=p_target, n_theta=N_THETA, deterministic=NO_DET),
        rng=np.random.default_rng(seed))
    return run_nsga2(form, [0.0], [1.0], rng=np.random.default_rng(seed + 100),
                     options=NSGA2Options(pop_size=40, n_gen=40))


def check_on_curve(F):
    """Every front point lies on the analytic curve σ_y(μ_y) = σ(x(μ))."""
    x_of_mu = TOY.x_of_mean(F[:, 0])
    np.testing.assert_allclose(F[:, 1], TOY.std(x_of_mu), atol=TOL_CURVE)


def test_rdo_front_is_the_analytic_pareto_set():
    res = toy_run("rdo")
    idx = archive_front(res)
    F, X = res.archive.F[idx], res.archive.X[idx, 0]
    assert idx.size >= 30
    check_on_curve(F)
    # the Pareto set is x ∈ [x*, 1] with x* = σ2² / (σ1² + σ2²) = 0.2
    assert X.min() == pytest.approx(TOY.x_min_std, abs=TOL_X)
    assert X.max() == pytest.approx(1.0, abs=TOL_X)
    # and it is dense: no gap wider than 0.1 in x
    assert np.diff(np.sort(X)).max() < 0.1


def test_rbrdo_front_is_cut_at_the_analytic_reliability_boundary():
    pt = 0.12
    xa, xb = TOY.reliable_interval(pt)   # μ + β_t σ <= δ on the Pareto set
    assert xb == 1.0 and 0.25 < xa < 0.35  # set up so only the left end is cut (x_a = 0.288)
    res = toy_run("rbrdo", p_target=pt)
    idx = archive_front(res)
    F, X = res.archive.F[idx], res.archive.X[idx, 0]
    check_on_curve(F)
    assert X.min() == pytest.approx(xa, abs=TOL_X)
    assert X.max() == pytest.approx(1.0, abs=TOL_X)
    assert np.all(TOY.pf(X) <= pt + 0.006)
    # the constraint is active at the left end of the front
    left = idx[np.argmin(X)]
    assert res.archive.pf[left] == pytest.approx(pt, abs=0.005)


def test_rdo_and_rbrdo_share_the_sample_and_rbrdo_front_is_a_subset():
    rdo, rbrdo = toy_run("rdo", seed=3), toy_run("rbrdo", seed=3, p_target=0.12)
    f_rdo = rdo.archive.F[archive_front(rdo)]
    f_rb = rbrdo.archive.F[archive_front(rbrdo)]
    # RBRDO points are not dominated by the RDO front by more than the front's resolution
    assert f_rb[:, 0].min() >= f_rdo[:, 0].min() - 0.01
    assert f_rb[:, 1].min() >= f_rdo[:, 1].min() - 1e-3
