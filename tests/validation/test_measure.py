"""Measuring a replication: noise-free measurements equal the FE response through the probes'
driver low-pass; the time-record path equals the phasor path; ramps bracket the critical
speed."""

import numpy as np
import pytest

from surrogate_rbrdo.rig.sensors import DAQModel, SensorSet
from surrogate_rbrdo.rig.truth import Variability
from surrogate_rbrdo.spindle.assembly import RPM
from surrogate_rbrdo.spindle.harmonic import PeakOptions, peak_tool_amplitude, tool_amplitude
from surrogate_rbrdo.spindle.modal import critical_speeds
from surrogate_rbrdo.validation.measure import measure_criticals, measure_replica
from surrogate_rbrdo.validation.options import ValidationOptions
from surrogate_rbrdo.validation.replicas import reference_family, replica_states

QUIET = SensorSet(noise=False, daq=DAQModel(bits=28))
COARSE = dict(speeds_rpm={"start": 2000, "stop": 24000, "step": 2000},
              peak=PeakOptions(n_grid=12, n_candidates=2, n_refine=7, n_zoom=3))


def _state(x=(2000.0, 500.0, 65.0), seed=1):
    st = replica_states(reference_family(), {"d": list(x)}, 1, seed=np.random.SeedSequence(seed))
    return st["d"][0]


def _lowpass(speeds_rpm, sensors=QUIET):
    return np.abs(1.0 / (1.0 + 1j * np.asarray(speeds_rpm) * RPM / (2 * np.pi)
                         / sensors.probe.bandwidth_hz))


@pytest.mark.known_answer
def test_noise_free_measurement_is_the_fe_response_through_the_probes():
    st = _state()
    o = ValidationOptions(sensors=QUIET, **COARSE)
    inst = QUIET.install(np.random.default_rng(0))
    m = measure_replica(st, o, inst, np.random.default_rng(1))
    sp = np.asarray(o.speeds_rpm)
    fe = tool_amplitude(st.model(), sp, st.theta)[0]
    np.testing.assert_allclose(m.curve, fe * _lowpass(sp), rtol=1e-10)
    rated = tool_amplitude(st.model(), np.array([24000.0]), st.theta)[0, 0]
    assert m.rated == pytest.approx(rated * _lowpass(24000.0), rel=1e-10)
    # the dwell search is the model's own peak search, on measured amplitudes
    pk = peak_tool_amplitude(st.model(), st.theta, options=o.peak)
    assert m.peak == pytest.approx(pk.amplitude[0] * _lowpass(pk.speed_rpm[0]), rel=1e-4)
    assert m.peak_speed_rpm == pytest.approx(pk.speed_rpm[0], rel=1e-4)


def test_time_records_and_phasors_agree():
    st = _state()
    kw = dict(sensors=QUIET, duration_s=0.3, **COARSE)
    inst = QUIET.install(np.random.default_rng(0))
    fast = measure_replica(st, ValidationOptions(**kw), inst, np.random.default_rng(2))
    slow = measure_replica(st, ValidationOptions(method="records", **kw), inst,
                           np.random.default_rng(2))
    # amplitudes: demodulation of the records is exact but for the keyphasor's phase error,
    # which turns all channels together and leaves the orbit size alone
    np.testing.assert_allclose(slow.curve, fast.curve, rtol=2e-4)
    assert slow.peak == pytest.approx(fast.peak, rel=2e-4)
    assert slow.n_records == fast.n_records


def test_noise_scatters_around_the_noise_free_value():
    st = _state()
    o = ValidationOptions(**COARSE)
    inst = o.sensors.install(np.random.default_rng(0))
    quiet = measure_replica(st, ValidationOptions(sensors=QUIET, **COARSE), inst,
                            np.random.default_rng(3))
    noisy = [measure_replica(st, o, inst, np.random.default_rng(k)).curve for k in range(4)]
    gain = 0.5 * (inst.gain["tool_x"] + inst.gain["tool_y"])
    # 1x noise is ~0.73 nm per part in 1 s: tiny against µm amplitudes, but not zero
    dev = np.abs(np.array(noisy) - gain * quiet.curve)
    assert np.all(dev < 0.03 * gain * quiet.curve + 5e-9)
    assert np.any(dev > 0)


def test_ramps_bracket_the_truths_critical_speed():
    st = replica_states(reference_family(variability=Variability.none()),
                        {"d": [2000.0, 500.0, 65.0]}, 1, seed=np.random.SeedSequence(5))["d"][0]
    o = ValidationOptions(sensors=QUIET, ramp_rpm=(19000.0, 24000.0), ramp_s=2.5)
    inst = QUIET.install(np.random.default_rng(0))
    found = measure_criticals(st, 0, o, inst, np.random.default_rng(6))
    truth = critical_speeds(st.model(), np.linspace(19000.0, 24000.0, 6), st.theta[0])
    assert len(found) == 1 and truth.size == 1
    c = found[0]
    # a run-up peak lags above the critical speed, a run-down peak below (2 000 rpm/s)
    assert c.rundown_rpm < truth[0] < c.runup_rpm
    assert c.speed_rpm == pytest.approx(truth[0], rel=0.01)
