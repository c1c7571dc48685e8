"""Headline claims about the credible reference problem, each checked against the FE model.

The problem: y = peak tool-tip amplitude over 1 000–24 000 rpm of ``credible_spindle()``;
θ = stiffness scatter around the speed trend + ISO 21940-11 unbalance per plane, magnitude
uniform over the tolerance disk and random phase (``ThetaSpec()``); the practice checks
(``PracticeConstraints``) and the API separation guard (``ResonanceGuard``). The fast tests
use the exact coupling (``PeakUnbalanceResponse``, verified against the FE peak search in
``test_peak_coupling.py``); the slow ones repeat the claim with the FE peak search itself.
The numbers are measured by ``benchmarks/fe_credible_problem.py`` (docs/reference-spindle.md).
"""

import numpy as np
import pytest

from surrogate_rbrdo.optimization.pareto import nondominated
from surrogate_rbrdo.spindle.modal import critical_speeds
from surrogate_rbrdo.spindle.peak_coupling import peak_tool_amplitude_unbalance
from surrogate_rbrdo.spindle.peak_response import PeakUnbalanceResponse, ThetaSpec
from surrogate_rbrdo.spindle.practice import PracticeConstraints
from surrogate_rbrdo.spindle.reference import credible_spindle
from surrogate_rbrdo.spindle.separation import ResonanceGuard, forward_critical_speeds
from surrogate_rbrdo.study.checks import campbell_critical_speeds
from surrogate_rbrdo.uncertainty.spindle_theta import theta_random_vector

CR = credible_spindle()
SPEC = ThetaSpec()


def _theta(n, seed):
    return theta_random_vector(SPEC).sample(n, rng=np.random.default_rng(seed))


def _feasible_grid():
    b = CR.design_map.bounds
    X = np.array([[f, l, d] for f in np.linspace(*b[0], 6) for l in np.linspace(*b[1], 10)
                  for d in np.linspace(*b[2], 7)])
    X = X[np.all(PracticeConstraints(CR)(X) <= 0, axis=1)]
    return X[ResonanceGuard(CR)(X)[:, 0] <= 0]


@pytest.fixture(scope="module")
def scan():
    X = _feasible_grid()
    y = PeakUnbalanceResponse(CR, SPEC)(X, _theta(500, 0)) * 1e6
    return X, y


@pytest.mark.known_answer
def test_the_baseline_has_its_first_critical_speed_inside_the_operating_range():
    """Baseline [570 N, 500 mm, 65 mm]: one forward critical speed at ~21 800 rpm (the damped
    Campbell diagram, an independent eigenproblem, agrees) and the API guard fails."""
    m = CR.model(CR.baseline)
    crit = forward_critical_speeds(m, 36000.0).speeds_rpm
    assert np.sum((crit > 1000) & (crit < 24000)) == 1
    campbell = critical_speeds(m, np.linspace(1000.0, 24000.0, 24))
    np.testing.assert_allclose(crit[crit < 24000], campbell, rtol=1e-4)
    assert ResonanceGuard(CR)(CR.baseline[None])[0, 0] > 0


def test_a_crossing_inside_the_range_is_in_y():
    """Every sample of the baseline peaks at its resonance, and y is the FE peak there."""
    th = _theta(40, 3)
    resp = PeakUnbalanceResponse(CR, SPEC)
    crit = forward_critical_speeds(CR.model(CR.baseline), 24000.0).speeds_rpm[0]
    speeds = resp.peak_speeds(CR.baseline[None], th)[0]
    assert np.all(np.abs(speeds / crit - 1) < 0.02)
    m = CR.model(CR.baseline)
    k, U = resp.unbalance(m, th[:2])
    fe = peak_tool_amplitude_unbalance(m, k, U).amplitude
    np.testing.assert_allclose(resp(CR.baseline[None], th[:2])[0], fe, rtol=1e-3)


def test_no_mu_sigma_trade_off_under_random_unbalance(scan):
    """Fewer than 10 non-dominated feasible designs (here at most 3): σ ∝ μ, because the
    dominant plane's residual magnitude scales y (σ/μ ≈ 1/√8 of the tolerance disk)."""
    X, y = scan
    mu, sd = y.mean(1), y.std(1, ddof=1)
    assert len(X) >= 10
    assert np.flatnonzero(nondominated(np.column_stack([mu, sd]))).size <= 3
    assert np.corrcoef(mu, sd)[0, 1] > 0.95
    assert 0.3 < np.median(sd / mu) < 0.5


def test_a_one_percent_reliability_constraint_is_inactive_for_physical_limits(scan):
    """At the least-μ feasible design P_f = 0 for δ_lim ≥ 1 µm (its largest y is < 1 µm)."""
    X, y = scan
    best = np.argmin(y.mean(1))
    y_best = PeakUnbalanceResponse(CR, SPEC)(X[best][None], _theta(2000, 7))[0] * 1e6
    assert y_best.max() < 1.0
    assert np.mean(y_best > 1.0) == 0.0


def test_the_feasible_optimum_crosses_no_critical_speed_in_the_range(scan):
    """The least-μ feasible design (the one every RBRDO/RDO/RBDO run converges to) has no
    damped critical speed inside 1 000–24 000 rpm on its FE Campbell diagram (an eigenproblem
    independent of the guard's), its first one lies beyond the API margin (≥ 1.26 n_max for
    AF ≥ 10.6): its y is a flank response, not a resonance."""
    X, y = scan
    best = X[np.argmin(y.mean(1))]
    crit = campbell_critical_speeds(CR, best[None], n_speeds=18)[0]
    assert crit.size and np.all(crit > 24000.0)
    assert crit[0] >= 1.26 * 24000.0
    exact = forward_critical_speeds(CR.model(best), 36000.0)
    np.testing.assert_allclose(exact.speeds_rpm[0], crit[0], rtol=1e-3)
    assert exact.amplification[0] > 10.6


@pytest.mark.slow
def test_no_trade_off_and_inactive_constraint_by_the_fe_peak_search(scan):
    """The same two claims with the FE model's own peak search on fresh θ: the least-μ design
    of the scan has the least σ too among the five lowest-μ designs, and max y < 1 µm."""
    X, y = scan
    pick = np.argsort(y.mean(1))[:5]
    y_fe = PeakUnbalanceResponse(CR, SPEC, method="direct")(X[pick], _theta(300, 11)) * 1e6
    mu, sd = y_fe.mean(1), y_fe.std(1, ddof=1)
    assert np.flatnonzero(nondominated(np.column_stack([mu, sd]))).size <= 2
    assert y_fe[np.argmin(mu)].max() < 1.0
