"""The deterministic strategy's design basis on the credible problem (issue 17): the API RP 684
unbalance cases at the ISO 21940-11 limit, checked against the FE model's own peak search."""

import numpy as np
import pytest

from surrogate_rbrdo.core import LimitState
from surrogate_rbrdo.formulations import DeterministicOptions, FormulationOptions, make_formulation
from surrogate_rbrdo.study import credible_problem, unbalance_design_cases

PROBLEM = credible_problem()
NO_DET = FormulationOptions(n_theta=4, deterministic=DeterministicOptions(stress=False,
                                                                          resonance="none"))
#: two feasible designs of the box and the baseline (a critical speed inside the range)
X = np.array([[237.5, 390.0, 74.0], [219.5, 302.4, 73.9], [570.0, 500.0, 65.0]])


def test_the_cases_are_both_planes_at_their_limit_in_phase_and_in_couple():
    th = PROBLEM.design_theta
    assert PROBLEM.theta_names == ("k_front", "k_rear", "u_frac[0]", "u_frac[1]", "phase_deg[1]")
    np.testing.assert_array_equal(th, [[1, 1, 1, 1, 0], [1, 1, 1, 1, 180]])
    with pytest.raises(ValueError, match="PeakUnbalanceSpec"):
        unbalance_design_cases(PROBLEM.inputs, object())


@pytest.mark.known_answer
def test_deterministic_objective_is_the_fe_response_at_the_stated_unbalance():
    """Known answer: the deterministic formulation's objective (the exact fast path in the loop)
    equals the larger of the FE peak-search responses to the two stated unbalance cases, and
    no design can lower it by cancelling the planes: it is at least each plane's response at
    its limit alone (at every speed max(|a + b|, |a − b|) ≥ max(|a|, |b|))."""
    form = make_formulation(
        "deterministic", response=PROBLEM.fe_response("condensed"), inputs=PROBLEM.inputs,
        limit=PROBLEM.limit, rng=np.random.default_rng(0), design_theta=PROBLEM.design_theta,
        options=NO_DET)
    got = form.evaluate(X).F[:, 0]
    fe = PROBLEM.fe_response("direct")
    y_cases = fe(X, PROBLEM.design_theta)
    np.testing.assert_allclose(got, y_cases.max(axis=1), rtol=1e-4)
    single = np.array([[1, 1, 1, 0, 0], [1, 1, 0, 1, 0]], dtype=float)   # one plane at a time
    y_single = fe(X, single)
    assert np.all(got >= y_single.max(axis=1) * (1 - 1e-6))


def test_the_median_basis_is_the_old_nominal():
    """Without design cases the deterministic strategy evaluates the image of u = 0: both
    planes at r = 1/√2 of their tolerance, relative phase 180°."""
    form = make_formulation("deterministic", response=PROBLEM.fe_response("condensed"),
                            inputs=PROBLEM.inputs, limit=LimitState(1e-6),
                            rng=np.random.default_rng(0), options=NO_DET)
    np.testing.assert_allclose(form.theta_nominal, [[1, 1, 2 ** -0.5, 2 ** -0.5, 180]],
                               atol=1e-9)
