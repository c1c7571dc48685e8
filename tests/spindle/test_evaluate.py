"""The spindle as a response: peak amplitude, resonance quantities, first critical speed."""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.spindle.evaluate import (
    PeakAmplitudeResponse,
    PointwisePeak,
    PointwiseResonance,
    first_critical_speed,
    resonance_quantities,
)
from surrogate_rbrdo.spindle.harmonic import peak_tool_amplitude
from surrogate_rbrdo.spindle.modal import critical_speeds
from surrogate_rbrdo.spindle.reference import reference_spindle

from .conftest import build, rigid_rotor_geometry, rigid_rotor_properties

RPM = np.pi / 30


@pytest.mark.known_answer
def test_first_critical_speed_of_a_rigid_rotor_is_sqrt_2k_over_m():
    k = 1e7
    m, _, _, _ = rigid_rotor_properties()
    model = build(rigid_rotor_geometry(k))
    assert first_critical_speed(model) == pytest.approx(np.sqrt(2 * k / m) / RPM, rel=1e-6)


@pytest.mark.parametrize("x", [[3000.0, 490.0, 70.0], [1000.0, 750.0, 50.0],
                               [3000.0, 300.0, 70.0]])
def test_first_critical_speed_matches_the_campbell_crossing(x):
    """Independent path: 1x crossings located on a Campbell grid and refined by brentq."""
    sp = reference_spindle()
    model = sp.model(np.array(x))
    ref = critical_speeds(model, np.linspace(1000.0, 60000.0, 40))[0]
    assert first_critical_speed(model) == pytest.approx(ref, rel=1e-5)


def test_resonance_quantities_are_consistent_with_the_peak_response():
    sp = reference_spindle()
    x = np.array([3000.0, 500.0, 70.0])
    th = np.array([[1.0, 1.0], [0.9, 1.1]])
    q = resonance_quantities(sp, x, th)
    y = PeakAmplitudeResponse(sp)(x[None], th)[0]
    assert np.allclose(q.peak_m, y, rtol=1e-12)
    # in range: the peak is the resonance's height, found near the critical speed
    inside = q.critical_rpm < 24000.0
    assert inside.any()
    assert np.allclose(q.peak_m[inside], q.amp_res_m[inside], rtol=1e-3)
    pk = peak_tool_amplitude(sp.model(x), th)
    assert np.allclose(pk.speed_rpm[inside], q.critical_rpm[inside], rtol=0.01)
    # the flank value is the amplitude at the top speed, below the resonance's height
    assert np.all(q.amp_top_m <= q.amp_res_m)
    z = np.r_[x, th[0]]
    assert PointwiseResonance(sp)(z)[3] == pytest.approx(PointwisePeak(sp)(z), rel=1e-12)


def test_resonance_quantities_bad_window():
    with pytest.raises(ValueError, match="window = 0.7"):
        resonance_quantities(reference_spindle(), np.array([2000.0, 500.0, 65.0]),
                             np.ones((1, 2)), window=0.7)
