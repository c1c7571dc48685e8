"""FORM and FOSM against closed-form answers, and FORM's failure modes."""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy import optimize, special

from surrogate_rbrdo.core import LimitState, ModelError
from surrogate_rbrdo.estimators import FORM, FOSM
from surrogate_rbrdo.estimators.problems import (
    correlated_normal,
    linear_standard,
    lognormal_nataf,
    paraboloid,
    series_four_branch,
)
from surrogate_rbrdo.uncertainty import MultivariateNormal

pytestmark = pytest.mark.known_answer
RNG = np.random.default_rng(0)


def form(prob, **kw):
    return FORM(**kw).estimate(prob.response, prob.inputs, prob.limit, prob.x, rng=RNG)


@pytest.mark.parametrize("prob", [
    linear_standard(beta=3.0, dim=3, shifts=(0.0, 1.0, -2.0)),
    linear_standard(beta=5.0, dim=10),
    linear_standard(beta=-1.0, dim=2),                      # mean point fails: P_f = 0.84
    correlated_normal(),
    lognormal_nataf(),
], ids=lambda p: p.name)
def test_form_exact_on_linear_limit_states(prob):
    est = form(prob)
    assert est.diagnostics["converged"].all()
    beta_exact = -special.ndtri(prob.pf_exact)
    np.testing.assert_allclose(est.diagnostics["beta"], beta_exact, atol=1e-6)
    np.testing.assert_allclose(est.pf, prob.pf_exact, rtol=1e-5)
    np.testing.assert_allclose(est.diagnostics["importance_factors"].sum(1), 1.0, atol=1e-9)
    # design point lies on the limit state, in both spaces
    th = est.diagnostics["theta_star"]
    for i in range(prob.x.shape[0]):
        y = prob.response(prob.x[i:i + 1], th[i:i + 1])[0, 0]
        assert y == pytest.approx(prob.limit.threshold, abs=1e-6)
    np.testing.assert_allclose(prob.inputs.to_standard(th), est.diagnostics["u_star"],
                               atol=1e-9)


def test_form_linear_alpha_is_the_normal_vector():
    prob = linear_standard(beta=3.0, dim=3)
    alpha = np.arange(1.0, 4.0) / np.linalg.norm(np.arange(1.0, 4.0))
    np.testing.assert_allclose(form(prob).diagnostics["alpha"][0], alpha, atol=1e-7)


def test_form_error_visible_on_curved_limit_state():
    prob = paraboloid(beta=3.0, kappa=0.3, dim=5)
    est = form(prob, fd_scheme="central")
    assert est.diagnostics["beta"][0] == pytest.approx(3.0, abs=1e-6)
    assert est.pf[0] > 3 * prob.pf_exact[0]          # FORM ignores curvature: 4x too large


def test_form_misses_branches_of_series_system():
    prob = series_four_branch(6.0)
    est = form(prob)
    assert est.diagnostics["beta"][0] == pytest.approx(3.0, abs=1e-5)
    assert est.pf[0] < 0.5 * prob.pf_exact[0]


def test_form_limit_state_never_reached_gives_a_bound_not_an_error():
    # y = -(u1^2 + u2^2): failure y > 1 never happens (G = 1 + |u|^2 >= 1)
    inputs = MultivariateNormal(np.zeros(2), cov=np.eye(2))

    def resp(x, t):
        return -np.sum(t**2, axis=1)[None, :]

    est = FORM().estimate(resp, inputs, LimitState(1.0), np.zeros((1, 0)), rng=RNG)
    d = est.diagnostics
    assert d["status"][0] == "not_reached" and d["pf_bound"][0] == "upper"
    assert not d["converged"][0] and "not reached" in d["message"][0]
    assert est.pf[0] == pytest.approx(special.ndtr(-FORM().beta_max))
    assert np.isnan(est.pf_ci[0]).all()      # a first-order value, not a rigorous interval


@pytest.mark.known_answer
def test_form_converges_next_to_its_limit_state():
    """Regression (review of issue 13): a design 1e-10 from its limit state, ``G(0)`` at the
    round-off of ``y ≈ 1.3``, stalled ("line search stalled", β = 6.5e-10, G = 2e-16) because
    convergence was judged relative to ``|G(0)|``. Independent reference: at that distance the
    linearisation is exact, β = 1e-10 / ‖∇_u y(0)‖ with ∇_u y = 0.1·(θ₁, θ₀, 0.6 θ₂) at θ = 1;
    FORM converges within its distance tolerance ``tol_g`` (1e-8 in standard space)."""
    inputs = MultivariateNormal(np.ones(3), cov=0.01 * np.eye(3))

    def resp(x, t):
        return (t[:, 0] * t[:, 1] + 0.3 * t[:, 2] ** 2)[None, :]

    est = FORM().estimate(resp, inputs, LimitState(1.3 + 1e-10), np.zeros((1, 0)), rng=RNG)
    assert est.diagnostics["converged"][0]
    beta_ref = 1e-10 / np.linalg.norm([0.1, 0.1, 0.06])
    assert est.diagnostics["beta"][0] == pytest.approx(beta_ref, abs=FORM().tol_g)


def _curved():
    """y = u₁ + u₂/2 + u₂²/5 > 3: one iHL-RF step from the origin does not reach the design point
    (the paraboloid's first step lands on it exactly, and is then accepted at max_iter)."""
    inputs = MultivariateNormal(np.zeros(2), cov=np.eye(2))
    return SimpleNamespace(
        inputs=inputs, limit=LimitState(3.0), x=np.zeros((1, 0)),
        response=lambda x, t: (t[:, 0] + 0.5 * t[:, 1] + 0.2 * t[:, 1] ** 2)[None, :])


def test_form_non_convergence_raises_or_returns_nan():
    prob = _curved()
    est = FORM(max_iter=1, on_failure="nan", fallback="none").estimate(
        prob.response, prob.inputs, prob.limit, prob.x, rng=RNG)
    assert np.isnan(est.pf[0]) and not est.diagnostics["converged"][0]
    assert est.diagnostics["status"][0] == "failed"
    assert est.diagnostics["message"][0] != "converged"


def test_form_iteration_limit_reported():
    prob = _curved()
    with pytest.raises(ModelError, match="maximum number of iterations"):
        form(prob, max_iter=1, fallback="none")


def test_form_fallback_finishes_a_search_iHLRF_left():
    """One iHL-RF iteration, then SLSQP and the ray search: the design point of the curved
    limit state, β = min over u₂ of ‖(3 − u₂/2 − u₂²/5, u₂)‖ by a 1-D bounded minimisation."""
    prob = _curved()
    beta = optimize.minimize_scalar(lambda v: np.hypot(3 - v / 2 - v**2 / 5, v), bounds=(-5, 5),
                                    method="bounded", options={"xatol": 1e-12}).fun
    est = form(prob, max_iter=1)
    assert est.diagnostics["status"][0] == "converged"
    assert est.diagnostics["beta"][0] == pytest.approx(beta, rel=1e-4)


@pytest.mark.parametrize("m, half_angle, beta", [(2, 0.5, 3.0), (4, 0.3, 2.5), (5, 0.05, 3.0)])
def test_form_converges_at_a_kink(m, half_angle, beta):
    """Failure where both a₁·u > β and a₂·u > β (a₁, a₂ at ±θ from u₁): the design point is on
    the kink of ``G = β − min(a₁·u, a₂·u)``, at distance β / cos θ (the two hyperplanes meet
    there and each alone is nearer than its foot on the other). iHL-RF zigzags across the kink
    and stalls; the fallback (SLSQP, then the ray search) finds it."""
    a = np.zeros((2, m))
    a[:, 0], a[:, 1] = np.cos(half_angle), [np.sin(half_angle), -np.sin(half_angle)]
    inputs = MultivariateNormal(np.zeros(m), cov=np.eye(m))
    resp = lambda x, t: (t @ a.T).min(1)[None, :]   # noqa: E731
    est = FORM().estimate(resp, inputs, LimitState(beta), np.zeros((1, 0)), rng=RNG)
    assert est.diagnostics["status"][0] == "converged"
    assert est.diagnostics["beta"][0] == pytest.approx(beta / np.cos(half_angle), rel=1e-6)
    bare = FORM(fallback="none", on_failure="nan").estimate(resp, inputs, LimitState(beta),
                                                             np.zeros((1, 0)), rng=RNG)
    assert bare.diagnostics["status"][0] == "failed"


def test_fosm_exact_on_linear_normal():
    prob = correlated_normal()
    est = FOSM().estimate(prob.response, prob.inputs, prob.limit, prob.x, rng=RNG)
    np.testing.assert_allclose(est.mean, prob.mean_exact, rtol=1e-12)
    np.testing.assert_allclose(est.std, prob.std_exact, rtol=1e-8)
    np.testing.assert_allclose(est.pf, prob.pf_exact, rtol=1e-6)
    assert est.n_calls == 3 * 7
    assert np.isnan(est.pf_se).all() and np.isnan(est.pf_ci).all()


def test_fosm_quadratic_misses_second_order_mean():
    # y = theta^2, theta ~ N(1, 0.1^2): E[y] = 1.01 exactly, FOSM gives 1
    inputs = MultivariateNormal([1.0], cov=[[0.01]])
    est = FOSM().estimate(lambda x, t: (t[:, 0] ** 2)[None, :], inputs, LimitState(2.0),
                          np.zeros((1, 0)), rng=RNG)
    assert est.mean[0] == pytest.approx(1.0, abs=1e-12)
    assert est.std[0] == pytest.approx(0.2, rel=1e-6)


def test_form_reports_a_bound_where_no_search_settles():
    """y = a·u plus a rough term of amplitude 0.02 varying on a scale far below the
    finite-difference step (a stand-in for a noisy solver): no search can settle. Failure needs
    a·u ≥ 3 − 0.02, so the design point is at β* ≥ 2.98; FORM reports a point of the limit state
    (|G| small) whose distance bounds β* from above: P_f (FORM) ≥ the reported value, labelled
    "lower" — not a crash, not a silent number. Without the fallback it raises."""
    a = np.array([0.6, 0.8, 0.0])
    resp = lambda x, t: (t @ a + 0.02 * np.sin(1e4 * t @ [1.0, 1.7, 2.3]))[None, :]  # noqa: E731
    inputs = MultivariateNormal(np.zeros(3), cov=np.eye(3))
    est = FORM().estimate(resp, inputs, LimitState(3.0), np.zeros((1, 0)), rng=RNG)
    d = est.diagnostics
    assert d["status"][0] == "unconverged" and d["pf_bound"][0] == "lower"
    assert not d["converged"][0] and d["beta"][0] >= 2.98
    y = resp(None, d["theta_star"][0][None, :])[0, 0]
    assert y == pytest.approx(3.0, abs=0.01)      # on the limit state, to the rough scale
    assert est.pf[0] == pytest.approx(special.ndtr(-d["beta"][0]))
    with pytest.raises(ModelError, match="did not converge"):
        FORM(fallback="none").estimate(resp, inputs, LimitState(3.0), np.zeros((1, 0)), rng=RNG)
