"""FORM's local-minimum check (review s4, F13-1): a first-order KKT point that is a saddle of
the distance (a limit state concave towards the origin) is not reported as the design point."""

import warnings

import numpy as np
import pytest

from surrogate_rbrdo.core import LimitState
from surrogate_rbrdo.estimators._tail import EstimatorWarning
from surrogate_rbrdo.estimators.form import FORM
from surrogate_rbrdo.uncertainty import MultivariateNormal

B = 3.0   # threshold: the axis point (B, 0, …) is a stationary point of the distance


def paraboloid(kappa):
    """y = u₁ + κ Σ_{i≥2} u_i², failure y > B (concave towards the origin for κ > 0)."""
    return lambda x, t: (t[:, 0] + kappa * np.sum(t[:, 1:] ** 2, axis=1))[None, :]


def exact_beta(kappa):
    """min_s (B − κ s)² + s over s = Σ u_i² ≥ 0: s* = (B − 1/(2κ))/κ when 2κB > 1 (a ring,
    β*² = B/κ − 1/(4κ²)), else the axis point (β* = B)."""
    if kappa > 0 and 2 * kappa * B > 1:
        return float(np.sqrt(B / kappa - 1 / (4 * kappa**2)))
    return B


def run(resp, m, **kw):
    inputs = MultivariateNormal(np.zeros(m), cov=np.eye(m))
    return FORM(**kw).estimate(resp, inputs, LimitState(B), np.zeros((1, 0)),
                               rng=np.random.default_rng(0))


@pytest.mark.known_answer
@pytest.mark.parametrize("kappa, m", [(0.5, 3), (0.5, 6), (0.3, 4)])
def test_saddle_is_left_for_the_ring(kappa, m):
    assert exact_beta(kappa) < B - 0.2          # the axis point is a saddle
    est = run(paraboloid(kappa), m)
    d = est.diagnostics
    assert d["status"][0] == "converged"
    assert d["beta"][0] == pytest.approx(exact_beta(kappa), rel=1e-5)
    # without the check the search stops at the saddle (the bug this guards against)
    d0 = run(paraboloid(kappa), m, check_minimum=False).diagnostics
    assert d0["beta"][0] == pytest.approx(B, rel=1e-5)


@pytest.mark.known_answer
@pytest.mark.parametrize("kappa", [0.0, -0.5, 0.1])   # linear, convex, concave but a minimum
@pytest.mark.parametrize("m", [2, 5])
def test_true_minimum_unchanged_at_the_cost_of_one_poll(kappa, m):
    on, off = run(paraboloid(kappa), m), run(paraboloid(kappa), m, check_minimum=False)
    assert on.diagnostics["beta"][0] == pytest.approx(exact_beta(kappa), rel=1e-6)
    assert on.diagnostics["beta"][0] == off.diagnostics["beta"][0]
    assert on.diagnostics["status"][0] == "converged"
    assert on.n_calls == off.n_calls + 2 * (m - 1)


def test_restart_that_does_not_converge_is_an_upper_bound_with_a_warning():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        d = run(paraboloid(0.5), 3, fallback="none", max_iter=5).diagnostics
    assert d["status"][0] == "unconverged" and d["pf_bound"][0] == "lower"
    assert exact_beta(0.5) <= d["beta"][0] < B
    assert any(issubclass(w.category, EstimatorWarning) and "not a local minimum"
               in str(w.message) for w in caught)


def test_check_minimum_must_be_bool():
    with pytest.raises(ValueError, match="check_minimum = 'yes'"):
        FORM(check_minimum="yes")
