"""Impact tests at speed: the fast path against the FE model and against the time domain."""

from __future__ import annotations

import numpy as np
import pytest

import surrogate_rbrdo.rig.simulate as sim
from surrogate_rbrdo.rig.frf import h1_frf
from surrogate_rbrdo.rig.impacts import (
    ImpactPlan,
    expected_frfs,
    frf_exact,
    hammer_spectrum,
    sample_frfs,
)
from surrogate_rbrdo.rig.sensors import SensorSet
from surrogate_rbrdo.rig.simulate import ProbeLayout, impact_record, impact_response
from surrogate_rbrdo.rig.truth import reference_truth


@pytest.fixture(scope="module")
def state():
    tr = reference_truth()
    return tr.state(np.random.SeedSequence(3), build=0, tool=0, run=0)


@pytest.mark.known_answer
def test_hammer_spectrum_is_the_half_sine_fourier_transform():
    """Against a quadrature of ``∫ P sin(πt/τ) e^{−iωt} dt`` (and ``2Pτ/π`` at DC)."""
    tau, P = 0.4e-3, 300.0
    t = np.linspace(0.0, tau, 20001)
    f = np.array([0.0, 300.0, 1250.0, 2500.0, 4000.0])
    num = np.trapezoid(P * np.sin(np.pi * t / tau)[None] * np.exp(
        -2j * np.pi * f[:, None] * t[None]), t, axis=1)
    assert np.allclose(hammer_spectrum(f, P, tau), num, rtol=1e-7, atol=1e-12)
    assert hammer_spectrum(np.array([0.0]), P, tau)[0] == pytest.approx(2 * P * tau / np.pi)


@pytest.mark.known_answer
def test_time_domain_hit_at_speed_gives_the_fast_path_frf(state):
    """A hit at 12 000 rpm integrated in the time domain (noise off), H1 without exponential
    window, equals ``expected_frfs`` (the dense FE solve at (ω, Ω) through the sensors) to the
    record's truncation and the anti-aliasing filter's ripple; at speed the cross FRF (y probe,
    x hit) is not zero — the gyroscopic coupling — and differs from standstill."""
    sensors = SensorSet(noise=False)
    inst = sensors.install(np.random.default_rng(0))
    model = state.model()
    rec = impact_record(model, state.theta, sensors, inst, np.random.default_rng(1),
                        rid="hit", provenance={}, direction="x", speed_rpm=12_000.0)
    assert rec.speed_rpm == 12_000.0
    est = h1_frf([rec], sensors.probe_channels, exp_window_end=None)
    f = np.arange(100.0, 1401.0, 50.0)
    idx = np.searchsorted(est.freq_hz, f)
    got = est.H[:, idx].T
    ref = expected_frfs(model, state.theta, 12_000.0, f, sensors, inst, "x")
    scale = np.max(np.abs(ref), axis=0)
    assert np.max(np.abs(got - ref) / scale) < 0.02
    tool_y = sensors.probe_channels.index("tool_y")
    still = expected_frfs(model, state.theta, 0.0, f, sensors, inst, "x")
    assert np.max(np.abs(ref[:, tool_y])) > 0.05 * np.max(np.abs(ref[:, tool_y - 1]))
    assert np.max(np.abs(ref - still)) > 0.05 * np.max(np.abs(still))


def test_fast_path_noise_has_the_stated_variance(state):
    """Many hits: the mean is the expected FRF and the spread of each line matches the probe
    noise's DFT over the hammer spectrum, ``σ √(Δt T / 2) / |F|`` per component (the force's
    noise and the peak scatter are second order here)."""
    sensors = SensorSet()
    inst = sensors.install(np.random.default_rng(2))
    model = state.model()
    f = np.array([200.0, 600.0, 1000.0])
    H = sample_frfs(model, state.theta, 10_000.0, f, sensors, inst, np.random.default_rng(4),
                    direction="y", n_hits=4000)
    ref = expected_frfs(model, state.theta, 10_000.0, f, sensors, inst, "y")
    lsb = sensors.daq.lsb_V / sensors.probe.sensitivity_V_per_m
    sx = np.sqrt((sensors.probe.noise_rms_m**2 + lsb**2 / 12) * 1e-4 / 2)
    F = np.abs(hammer_spectrum(f, sensors.hammer.peak_N, sensors.hammer.pulse_ms * 1e-3))
    # E[1/P²] of the peak scatter (SD 0.2) raises the variance by ~ (1 + 3 * 0.04)
    expect = sx / F * np.sqrt(1 + 3 * sensors.hammer.peak_sd**2) / inst.gain["hammer"]
    sd = H.real.std(axis=0)
    assert np.allclose(np.median(sd / expect[:, None], axis=1), 1.0, atol=0.08)
    assert np.allclose(H.mean(axis=0), ref, atol=4 * np.max(expect) / np.sqrt(4000))


def test_plan_lines_and_bad_input():
    p = ImpactPlan()
    assert p.speeds_rpm == (0.0, 10_000.0, 20_000.0)
    assert not np.any(np.abs(p.lines(20_000.0) - 20_000.0 / 60) <= p.exclude_hz)
    with pytest.raises(ValueError, match="impacts.directions"):
        ImpactPlan(directions=("z",))
    with pytest.raises(ValueError, match="impacts.freqs_hz"):
        ImpactPlan(freqs_hz=(10.0,))


@pytest.mark.known_answer
def test_frf_exact_is_reciprocal_at_standstill_and_gyroscopic_at_speed(state):
    """Maxwell reciprocity ``H_ij = H_ji`` holds at standstill; at speed the gyroscopic matrix
    is skew, so ``H_xy(Ω) = H_yx(−Ω)``: for an isotropic rotor ``H_yx = −H_xy`` (Lalanne &
    Ferraris 1998, ch. 2: the system matrix at Ω is the transpose of that at −Ω)."""
    model = state.model()
    tool = 4 * ProbeLayout.of(model).nodes["tool"]
    f = np.array([300.0, 800.0])
    xx0 = frf_exact(model, state.theta, 0.0, f, tool, np.array([tool + 1]))
    yx0 = frf_exact(model, state.theta, 0.0, f, tool + 1, np.array([tool]))
    assert np.allclose(xx0, yx0, rtol=1e-9, atol=1e-20)
    assert np.max(np.abs(xx0)) < 1e-6 * np.max(np.abs(frf_exact(
        model, state.theta, 0.0, f, tool, np.array([tool]))))


def test_hits_share_one_simulation_and_it_must_match(state):
    """Hits of one speed and direction differ by their peak force only: a record made from a
    shared :func:`impact_response` is the record simulated on its own (same stream), and a
    response of another direction or speed is refused."""
    sensors = SensorSet()
    inst = sensors.install(np.random.default_rng(0))
    model = state.model()
    shared = impact_response(model, state.theta, sensors, inst, direction="y",
                             speed_rpm=10_000.0, duration_s=0.2)
    for seed in (1, 2):
        kw = dict(rid="hit", provenance={}, direction="y", speed_rpm=10_000.0, duration_s=0.2)
        alone = impact_record(model, state.theta, sensors, inst, np.random.default_rng(seed),
                              **kw)
        made = impact_record(model, state.theta, sensors, inst, np.random.default_rng(seed),
                             response=shared, **kw)
        assert np.array_equal(alone.data, made.data)
        assert alone.provenance["peak_N"] == made.provenance["peak_N"]
    with pytest.raises(ValueError, match="response was simulated for"):
        impact_record(model, state.theta, sensors, inst, np.random.default_rng(1), rid="hit",
                      provenance={}, direction="x", speed_rpm=10_000.0, duration_s=0.2,
                      response=shared)


@pytest.mark.known_answer
def test_a_shared_hit_scaled_by_its_peak_is_the_hit_simulated_at_that_peak(state, monkeypatch):
    """Known answer (linearity): the response to a hammer pulse of peak ``P`` is ``P`` times
    the response to the same pulse of 1 N, through the integrator, the force's hold, the
    decimation filter, the drivers and the delays — the hit simulated with the pulse's peak
    set to ``P`` (``hammer_pulse`` patched) against the shared 1 N response scaled by ``P``,
    at standstill and at 20 000 rpm, on every channel with a signal above round-off."""
    sensors = SensorSet()
    inst = sensors.install(np.random.default_rng(0))
    model, peak, pulse = state.model(), 237.31, sim.hammer_pulse
    for speed, d in ((0.0, "x"), (20_000.0, "y")):
        kw = dict(direction=d, speed_rpm=speed, duration_s=0.2)
        one = impact_response(model, state.theta, sensors, inst, **kw)
        monkeypatch.setattr(sim, "hammer_pulse",
                            lambda t, th, pk, w: pulse(t, th, pk * peak, w))
        big = impact_response(model, state.theta, sensors, inst, **kw)
        monkeypatch.setattr(sim, "hammer_pulse", pulse)
        rms = np.sqrt(np.mean(big.x**2, axis=1))
        live = rms > 1e-9 * rms.max()
        err = np.max(np.abs(peak * one.x - big.x), axis=1)
        assert live.sum() >= 3 and np.all(err[live] <= 1e-12 * rms[live])
