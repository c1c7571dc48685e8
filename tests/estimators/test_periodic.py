"""Periodic inputs (review 3 of issue 13): two unbalances uniform over their tolerance disks with
a uniform relative phase, y = |r₁ + r₂ e^{iφ}| (largest value 2, at φ = 0 ≡ 360°). Before the
fix FORM ran along u_φ → ±∞ (the worst phase sits at both ends of the transform) and raised
"maximum number of iterations" at threshold 1.9; now the phase is conditioned on. References:
crude MC of the closed-form response (4·10⁵ samples) and, above 2, the exact P_f = 0."""

import numpy as np
import pytest

from surrogate_rbrdo.core import LimitState
from surrogate_rbrdo.estimators import ESTIMATORS
from surrogate_rbrdo.estimators._periodic import periodic_columns
from surrogate_rbrdo.uncertainty import Independent, Normal, Uniform
from surrogate_rbrdo.uncertainty.disk import UniformDiskRadius

INPUTS = Independent([UniformDiskRadius(), UniformDiskRadius(), Uniform(0.0, 360.0, periodic=True)])
X = np.zeros((1, 0))


def response(x, t):
    z = t[:, 0] + t[:, 1] * np.exp(1j * np.radians(t[:, 2]))
    return np.broadcast_to(np.abs(z), (x.shape[0], t.shape[0]))


def mc_reference(threshold):
    y = response(X, INPUTS.sample(400_000, rng=np.random.default_rng(11)))[0]
    p = float(np.mean(y > threshold))
    return p, np.sqrt(p * (1 - p) / y.size)


def test_periodic_columns_found():
    assert periodic_columns(INPUTS) == ((2, 0.0, 360.0),)
    assert periodic_columns(Independent([Normal(0.0, 1.0)])) == ()


@pytest.mark.known_answer
@pytest.mark.parametrize("threshold,rtol_form", [(1.0, 0.05), (1.5, 0.3)])
def test_form_sorm_is_on_a_periodic_phase(threshold, rtol_form):
    """FORM within 5 % (1.0) / 30 % (1.5: first order on the curved disk-radius transform);
    SORM within 10 %; IS within 4 combined standard errors of the reference."""
    p_ref, s_ref = mc_reference(threshold)
    lim = LimitState(threshold)
    f = ESTIMATORS["form"]().estimate(response, INPUTS, lim, X, rng=np.random.default_rng(0))
    assert f.pf[0] == pytest.approx(p_ref, rel=rtol_form)
    assert f.diagnostics["pf_quadrature_error"][0] < 0.05 * f.pf[0]
    s = ESTIMATORS["sorm"]().estimate(response, INPUTS, lim, X, rng=np.random.default_rng(0))
    assert s.pf[0] == pytest.approx(p_ref, rel=0.1)
    i = ESTIMATORS["is"]().estimate(response, INPUTS, lim, X, rng=np.random.default_rng(0))
    assert abs(i.pf[0] - p_ref) <= 4 * np.hypot(i.pf_se[0], s_ref)


@pytest.mark.parametrize("name", ["form", "sorm"])
def test_a_saturating_limit_state_gives_the_bound(name):
    """y ≤ 2 everywhere: threshold 2.5 is never reached (bounded radii saturate G)."""
    est = ESTIMATORS[name]().estimate(response, INPUTS, LimitState(2.5), X,
                                      rng=np.random.default_rng(0))
    assert est.diagnostics["status"][0] == "not_reached"
    assert est.diagnostics["pf_bound"][0] == "upper" and est.pf[0] < 1e-20
