"""Forward critical speeds against the damped Campbell diagram; API separation margins."""

import numpy as np
import pytest

from surrogate_rbrdo.spindle.effects import Anisotropy
from surrogate_rbrdo.spindle.modal import critical_speeds, first_natural_frequency, modal_analysis
from surrogate_rbrdo.spindle.reference import reference_spindle
from surrogate_rbrdo.spindle.separation import (
    ResonanceGuard,
    api_separation_margins,
    forward_critical_speeds,
)

SP = reference_spindle()


@pytest.mark.known_answer
@pytest.mark.parametrize("x", [[2000.0, 500.0, 65.0], [1000.0, 750.0, 50.0],
                               [3000.0, 350.0, 80.0]])
def test_critical_speeds_equal_the_damped_campbell_crossings(x):
    """Independent: 1x crossings of the damped forward modes (state-space eigenproblem)."""
    m = SP.model(np.array(x))
    crit = forward_critical_speeds(m, 40000.0)
    ref = critical_speeds(m, np.linspace(500.0, 40000.0, 40))
    np.testing.assert_allclose(crit.speeds_rpm, ref, rtol=1e-4)
    for s, z in zip(crit.speeds_rpm, crit.damping_ratio, strict=True):
        md = modal_analysis(m, s)
        k = np.argmin(np.where(md.whirl == "forward", np.abs(md.frequency_hz * 60 - s), np.inf))
        assert z == pytest.approx(md.damping_ratio[k], rel=0.05)   # Rayleigh quotient


@pytest.mark.known_answer
def test_api_margins():
    below, above = api_separation_margins(np.array([2.4, 3.0, 10.0, 1000.0]))
    core = 0.17 * (1 - 1 / (np.array([3.0, 10.0]) - 1.5))
    np.testing.assert_allclose(below, [0.0, *np.minimum(0.16, core), 0.16])
    np.testing.assert_allclose(above, [0.0, *np.minimum(0.26, 0.10 + core), 0.26])


def test_guards_on_designs_with_and_without_a_critical_in_range():
    g = ResonanceGuard(SP)
    X = np.array([[2000.0, 500.0, 65.0], [3000.0, 300.0, 80.0]])
    sep = g(X)[:, 0]
    assert sep[0] > 0 > sep[1]                 # 21 780 rpm in range; 39 300 rpm > 1.26 n_max
    m = SP.model(X[1])
    crit = forward_critical_speeds(m, 1.5 * 24000.0)
    assert crit.speeds_rpm.size == 0 and sep[1] == pytest.approx(1 - 1.5)
    paper = ResonanceGuard(SP, "paper")(X)[:, 0]
    np.testing.assert_allclose(paper, [1 - first_natural_frequency(SP.model(x)) / 480.0
                                       for x in X])


def test_anisotropic_bearings_are_refused():
    m = SP.model(SP.baseline, effects=SP.effects + (Anisotropy(s=0.1),))
    with pytest.raises(ValueError, match="isotropic"):
        forward_critical_speeds(m, 30000.0)
    with pytest.raises(ValueError, match="kind"):
        ResonanceGuard(SP, "api")
