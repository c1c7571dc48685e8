"""Synchronous demodulation and run-up tracking against the FE model's known answers."""

import numpy as np
import pytest

from surrogate_rbrdo.rig.demod import (
    critical_speeds_from_ramp,
    demodulate,
    fit_orders,
    track_1x,
)
from surrogate_rbrdo.rig.integrate import SpeedProfile
from surrogate_rbrdo.rig.keyphasor import sampled_phase_bound
from surrogate_rbrdo.rig.sensors import DAQModel, KeyphasorModel, SensorSet
from surrogate_rbrdo.rig.simulate import ProbeLayout, runup_record, steady_records
from surrogate_rbrdo.rig.truth import Variability, reference_truth
from surrogate_rbrdo.spindle import critical_speeds, unbalance_response

from .conftest import seeds


def test_fit_orders_exact_for_dc_and_orders_at_any_samples_per_rev():
    t = np.arange(777) / 10_000.0
    ang = 2 * np.pi * 411.3 * t + 1.0
    y = 1e-3 + np.real(2e-7j * np.exp(1j * ang)) + np.real(5e-8 * np.exp(2j * ang))
    X, res = fit_orders(y, ang, orders=(1, 2))
    np.testing.assert_allclose(X, [2e-7j, 5e-8], atol=1e-18)
    assert res < 1e-15


def _fe(m, st, speeds, sens, inst):
    """FE probe phasors through each channel's driver low-pass (the noise-free truth)."""
    X = unbalance_response(m, speeds, st.theta)[0].reshape(speeds.size, -1)[
        :, ProbeLayout.of(m).dofs(sens)]
    H = np.array([[sens.lowpass(c, inst, s / 60.0) for c in sens.probe_channels]
                  for s in speeds])
    return X * H


@pytest.mark.known_answer
def test_noise_off_records_demodulate_to_the_fe_harmonic_response():
    """Default sensors with the noise off are the FE answer: every probe's 1x amplitude and
    phase at every speed, down to the rear bearing's 0.24 nm at 1 000 rpm (far below one
    16-bit LSB, 38.8 nm: the noise-off records are not quantised)."""
    truth = reference_truth(variability=Variability(bearing_k_cov=0.05))
    st = truth.state(np.random.SeedSequence(3), build=0, tool=0, run=0)
    m = st.model()
    sens = SensorSet(noise=False)
    inst = sens.install(np.random.default_rng(0))
    speeds = np.array([1000.0, 2500.0, 9000.0, 17000.0, 24000.0])
    recs = steady_records(m, st.theta, speeds, sens, inst, seeds(5), duration_s=0.5,
                          ids=[f"r{i}" for i in range(5)], provenance=[{}] * 5)
    ref = _fe(m, st, speeds, sens, inst)
    for i, rec in enumerate(recs):
        p = demodulate(rec)
        assert abs(p.speed_rpm / speeds[i] - 1) < 1e-9
        np.testing.assert_allclose(p.X[:, 0], ref[i], rtol=1e-6)


@pytest.mark.known_answer
@pytest.mark.parametrize("polarity", ["positive", "negative"])
def test_counter_keyphasor_phase_at_whole_samples_per_revolution(polarity):
    """12 000, 15 000, 20 000 and 24 000 rpm are 50, 40, 30 and 25 samples per revolution:
    the sampled keyphasor's edges then fall at one sub-sample position every revolution and
    bias the phase (bounded by half a sample of angle). The default counter keyphasor (80 MHz
    timebase, quantised as with the noise on) gives the 1x phase within 0.01° for every start
    angle; a notch (negative-going pulse) is read by its leading edge the same way."""
    truth = reference_truth(variability=Variability.none())
    st = truth.state(np.random.SeedSequence(0), build=0, tool=0, run=0)
    m = st.model()
    speeds = np.array([12000.0, 15000.0, 18367.0, 20000.0, 24000.0])
    for timing, bound in (("counter", lambda s: 0.01), ("sampled",
                                                        lambda s: sampled_phase_bound(s, 1e4))):
        sens = SensorSet(noise=False, quantise=True, daq=DAQModel(bits=31),
                         keyphasor=KeyphasorModel(polarity=polarity, timing=timing))
        inst = sens.install(np.random.default_rng(0))
        ref = _fe(m, st, speeds, sens, inst)[:, sens.probe_channels.index("tool_x")]
        for rep in range(4):
            recs = steady_records(m, st.theta, speeds, sens, inst, seeds(5, 10 * rep),
                                  duration_s=0.5, ids=list("abcde"), provenance=[{}] * 5)
            for i, rec in enumerate(recs):
                d = np.degrees(np.angle(demodulate(rec).get("tool_x") / ref[i]))
                assert abs(d) < bound(speeds[i]), (timing, speeds[i], d)


@pytest.mark.known_answer
def test_speed_drift_inside_a_steady_record_is_followed():
    """A 1 % linear speed drift over the record (6 000 → 6 060 rpm): the shaft angle from a
    quadratic through the keyphasor edges follows it, so the 1x is the FE response within its
    own change over that speed range (a single constant-speed line lost 2.6 % of amplitude)."""
    truth = reference_truth(variability=Variability.none())
    st = truth.state(np.random.SeedSequence(0), build=0, tool=0, run=0)
    m = st.model()
    sens = SensorSet(noise=False)
    inst = sens.install(np.random.default_rng(0))
    rec = runup_record(m, st.theta, SpeedProfile.ramp(6000.0, 6060.0, 1.0), sens, inst,
                       np.random.default_rng(1), rid="drift", provenance={})
    p = demodulate(rec)
    j = sens.probe_channels.index("tool_x")
    ref = _fe(m, st, np.array([6000.0, 6030.0, 6060.0]), sens, inst)[:, j]
    spread = np.abs(ref / ref[1] - 1).max()
    assert abs(p.get("tool_x") / ref[1] - 1) < spread + 1e-4


@pytest.mark.known_answer
def test_runup_tracking_and_critical_speed_match_the_model():
    """The tracked 1x follows the harmonic solution away from the resonance; the run-up's peak
    lies above the model's critical speed and the run-down's below it (the sweep's lag), both
    within 0.5 % at 500 rpm/s."""
    truth = reference_truth(variability=Variability.none())
    st = truth.state(np.random.SeedSequence(0), build=0, tool=0, run=0)
    m = st.model()
    sens = SensorSet(noise=False)
    inst = sens.install(np.random.default_rng(0))
    model_cs = critical_speeds(m, np.linspace(20000, 23000, 7), st.theta[0])
    assert len(model_cs) == 1
    found = []
    for a, b in ((20000.0, 23000.0), (23000.0, 20000.0)):
        rec = runup_record(m, st.theta, SpeedProfile.ramp(a, b, 6.0), sens, inst,
                           np.random.default_rng(1), rid="u", provenance={})
        tr = track_1x(rec, ("tool_x",), revs_per_block=4)
        sel = np.abs(tr.speed_rpm - model_cs[0]) > 1000
        Xh = unbalance_response(m, np.sort(tr.speed_rpm[sel]), st.theta)[0][:, m.tool_node, 0]
        H = 1 / (1 + 1j * np.sort(tr.speed_rpm[sel]) / 60.0 / sens.probe.bandwidth_hz)
        got = tr.X[0, sel][np.argsort(tr.speed_rpm[sel])]
        np.testing.assert_allclose(got, Xh * H, rtol=0.01)
        cs = critical_speeds_from_ramp(tr, "tool_x")
        assert len(cs) == 1 and cs[0].phase_change_deg > 60
        found.append(cs[0].speed_rpm)
    assert found[1] < model_cs[0] < found[0]
    assert max(abs(f / model_cs[0] - 1) for f in found) < 0.005
