"""Models with a physical domain (``OutsideDomainError``) and limit states never reached.

Model: ``y = 1/θ`` with θ ~ N(1, 0.3²), defined only for θ > 0 (a compliance from a stiffness
factor); θ ≤ 0 has probability Φ(−1/0.3) = 4.29e-4.
"""

import numpy as np
import pytest
from scipy import special

from surrogate_rbrdo.core import CountingResponse, LimitState
from surrogate_rbrdo.core.errors import ModelError, OutsideDomainError
from surrogate_rbrdo.estimators import ESTIMATORS, FORM, evaluate_in_domain, get_estimator
from surrogate_rbrdo.uncertainty import MultivariateNormal

INPUTS = MultivariateNormal([1.0], std=[0.3])
P_OUT = float(special.ndtr(-1.0 / 0.3))


def compliance(x, theta, *, with_rows=True):
    t = theta[:, 0]
    bad = np.flatnonzero(t <= 0)
    if bad.size:
        raise OutsideDomainError("theta <= 0", rows=bad if with_rows else None)
    return np.broadcast_to(1.0 / t, (x.shape[0], t.size)).copy()


def compliance_no_rows(x, theta):
    return compliance(x, theta, with_rows=False)


def softening(x, theta):
    """``y = 1 − θ`` for θ > 0: below 1 everywhere in the domain; ``y > 2`` would need θ < −1."""
    t = theta[:, 0]
    bad = np.flatnonzero(t <= 0)
    if bad.size:
        raise OutsideDomainError("theta <= 0", rows=bad)
    return np.broadcast_to(1.0 - t, (x.shape[0], t.size)).copy()


@pytest.mark.parametrize("resp", [compliance, compliance_no_rows], ids=["rows", "bisection"])
def test_evaluate_in_domain_isolates_the_points_outside(resp):
    theta = np.array([[1.0], [-0.5], [2.0], [0.0], [0.5], [-2.0], [4.0]])
    counting = CountingResponse(resp)
    y, inside, calls = evaluate_in_domain(counting, np.zeros((2, 0)), theta)
    assert inside.tolist() == [True, False, True, False, True, False, True]
    np.testing.assert_allclose(y[:, inside], [[1.0, 0.5, 2.0, 0.25]] * 2)
    assert np.isnan(y[:, ~inside]).all()
    assert calls == counting.counter.calls == 2 * 4


def test_other_model_errors_propagate():
    def nan_model(x, theta):
        return np.full((x.shape[0], theta.shape[0]), np.nan)

    with pytest.raises(ModelError, match="responses must be finite"):
        evaluate_in_domain(nan_model, np.zeros((1, 0)), np.ones((3, 1)))


@pytest.mark.known_answer
def test_mc_counts_points_outside_as_failures():
    """P(y > 4 or outside) = P(0 < θ < 0.25) + P(θ ≤ 0) = Φ((0.25 − 1)/0.3) exactly."""
    est = get_estimator("mc", n_samples=400_000).estimate(
        compliance, INPUTS, LimitState(4.0), np.zeros((1, 0)), rng=np.random.default_rng(0))
    exact = special.ndtr((0.25 - 1.0) / 0.3)
    assert abs(est.pf[0] - exact) <= 4 * est.pf_se[0]
    n_out = est.diagnostics["n_outside_domain"][0]
    assert abs(n_out / 400_000 - P_OUT) < 4 * np.sqrt(P_OUT / 400_000)


@pytest.mark.parametrize("name", sorted(ESTIMATORS))
def test_every_estimator_runs_when_points_fall_outside(name):
    """y > 4 happens for 0 < θ < 0.25 (and outside): no estimator may crash, and those with a
    P_f land near Φ((0.25 − 1)/0.3) = 6.2e-3 or report a bound."""
    est = get_estimator(name).estimate(compliance, INPUTS, LimitState(4.0), np.zeros((1, 0)),
                                       rng=np.random.default_rng(1))
    exact = special.ndtr((0.25 - 1.0) / 0.3)
    if name == "fosm":          # linearisation at the mean: y ≈ 1 − (θ − 1), never the tail
        return
    assert 0.3 * exact < est.pf[0] < 3 * exact, est.pf


@pytest.mark.known_answer
@pytest.mark.parametrize("name", ["form", "sorm", "is"])
def test_form_based_estimators_bound_a_limit_state_beyond_the_domain(name):
    """y = 1 − θ > 2 never happens for θ > 0: the search walks towards θ → 0 and meets the
    domain's edge at u = −1/0.3 = −3.33 with G still positive. FORM reports the bound
    Φ(−3.33): first order, along its path (the physical P_f is 0; that of 'fail or outside' is
    P(θ ≤ 0) = Φ(−3.33), which the bound equals here)."""
    est = get_estimator(name).estimate(softening, INPUTS, LimitState(2.0),
                                       np.zeros((1, 0)), rng=np.random.default_rng(0))
    d = est.diagnostics
    assert d["status"][0] == "not_reached" and d["pf_bound"][0] == "upper"
    assert est.pf[0] == pytest.approx(P_OUT, rel=0.02)
    assert est.pf_ci[0, 0] == 0.0 and est.pf_ci[0, 1] == est.pf[0]


@pytest.mark.parametrize("name", ["subset", "ais"])
def test_multilevel_estimators_reach_the_domain_edge_as_failure(name):
    """The same limit state for subset/ais: the failure event is then 'outside the domain',
    P(θ ≤ 0) = 4.3e-4, which they estimate within 4 of their standard errors."""
    est = get_estimator(name).estimate(softening, INPUTS, LimitState(2.0),
                                       np.zeros((1, 0)), rng=np.random.default_rng(2))
    assert est.diagnostics["status"][0] == "converged"
    assert abs(est.pf[0] - P_OUT) <= 4 * est.pf_se[0]
    assert est.diagnostics["n_outside_domain"][0] > 0


def test_mean_point_outside_the_domain_is_an_error():
    inputs = MultivariateNormal([-1.0], std=[0.3])
    with pytest.raises(ModelError, match="mean point"):
        FORM().estimate(compliance, inputs, LimitState(4.0), np.zeros((1, 0)),
                        rng=np.random.default_rng(0))


@pytest.mark.known_answer
def test_form_recognises_convergence_limited_by_the_fd_gradient():
    """Regression (issue 13): the short column with all-normal inputs at (b, h) = (1.524, 13.78)
    (mean point failing) stalled at β = −5.06, G = −1e-13 with an alignment of 1.5e-6 and was
    reported as 'line search stalled'. It is converged: same β with central differences."""
    corr = np.eye(3)
    corr[1, 2] = corr[2, 1] = 0.5
    inputs = MultivariateNormal([5.0, 2000.0, 500.0], std=[0.5, 400.0, 100.0], corr=corr)

    def column(x, t):
        b, h = x[:, :1], x[:, 1:2]
        y, m, p = t[:, 0][None], t[:, 1][None], t[:, 2][None]
        return 1 - 4 * m / (b * h**2 * y) - (p / (b * h * y)) ** 2

    x = np.array([[1.52362315, 13.77559657]])
    lim = LimitState(0.0, "below")
    est = FORM().estimate(column, inputs, lim, x, rng=np.random.default_rng(0))
    ref = FORM(fd_scheme="central").estimate(column, inputs, lim, x,
                                             rng=np.random.default_rng(0))
    assert est.diagnostics["converged"][0]
    assert est.diagnostics["beta"][0] == pytest.approx(ref.diagnostics["beta"][0], abs=1e-6)
    assert est.diagnostics["beta"][0] == pytest.approx(-5.0636, abs=1e-3)
