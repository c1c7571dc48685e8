"""The fast path: the 1x phasors a steady record would demodulate to, without the time domain.

For thousands of scenarios (discrepancy blind tests) the steady-state campaign can be drawn
directly in the phasor domain. What :func:`rig.demod.demodulate` returns for a steady record
of the linear truth is

    X_meas = g (1 + ε) H(Ω) e^{iΩ s} X + n,        n ~ CN(0, 2 σ² / N),

times ``e^{−iδ}``, ``δ`` the record's keyphasor phase error (common to its channels), with
``X`` the FE harmonic response at the probe, ``g(1+ε)`` the channel's true gain,
``H(Ω) = 1/(1 + iΩ/ω_c)`` its driver's low-pass, ``s`` its unknown timing skew (the known delay
is corrected), ``N`` the samples in the whole revolutions used, ``σ² = σ_n² + q²/12`` the
probe noise plus the quantisation noise of an LSB ``q`` (m). :func:`sample_phasors` draws
exactly this.

**When it is equivalent** to demodulating records (tested on the reference truth:
``tests/rig/test_phasors.py``): the truth is linear (no nonlinear effect), the transient has
decayed, the noise is white and at least about one LSB (so quantisation acts as uniform noise),
and nothing clips. The keyphasor's phase error ``δ`` (its edge sampled at 10 kHz, its noise and
skew) is not Gaussian and depends on where the edges fall between samples: the fast path draws it
by simulating the keyphasor channel alone and fitting its edges exactly as the demodulation does
(:func:`keyphasor_phase_errors`, ~1 ms per record, no FE model involved).

>>> s = phasor_noise_sd(50e-9, 38.8e-9, 10_000)
>>> round(s * 1e9, 3)     # nm, per real/imaginary part
0.725
"""

from __future__ import annotations

import numpy as np

from surrogate_rbrdo.rig.demod import ShaftAngle
from surrogate_rbrdo.rig.keyphasor import edges_of
from surrogate_rbrdo.rig.sensors import Installation, SensorSet
from surrogate_rbrdo.rig.simulate import ProbeLayout, keyphasor_channel, keyphasor_events
from surrogate_rbrdo.spindle.assembly import RPM, SpindleModel
from surrogate_rbrdo.spindle.harmonic import unbalance_response


def phasor_noise_sd(noise_rms_m: float, lsb_m: float, n_samples: int) -> float:
    """Standard deviation of the real (and of the imaginary) part of a least-squares 1x
    phasor from ``n_samples`` with white noise ``noise_rms_m`` and quantisation step ``lsb_m``.
    """
    return float(np.sqrt((noise_rms_m**2 + lsb_m**2 / 12.0) * 2.0 / n_samples))


def expected_phasors(model: SpindleModel, theta: np.ndarray, speeds_rpm: np.ndarray,
                     sensors: SensorSet, inst: Installation) -> np.ndarray:
    """Noise-free measured 1x phasors ``(S, n_probe)`` (m) in ``sensors.probe_channels``
    order: the FE response through each channel's gain, low-pass and skew."""
    sp = np.asarray(speeds_rpm, float)
    layout = ProbeLayout.of(model)
    X = unbalance_response(model, sp, theta)[0].reshape(sp.size, -1)[:, layout.dofs(sensors)]
    w = sp[:, None] * RPM
    out = np.empty_like(X)
    for j, c in enumerate(sensors.probe_channels):
        H = sensors.lowpass(c, inst, w[:, 0] / (2 * np.pi))
        out[:, j] = inst.gain[c] * H * np.exp(1j * w[:, 0] * inst.skew_s[c]) * X[:, j]
    return out


def samples_in_revolutions(speeds_rpm: np.ndarray, duration_s: float, fs: float) -> np.ndarray:
    """Samples inside the whole revolutions of a record (what demodulation uses)."""
    rev = 60.0 / np.asarray(speeds_rpm, float)
    n_rev = np.floor(duration_s / rev) - 1        # between the first and the last pulse
    return np.maximum(np.floor(n_rev * rev * fs), 1).astype(int)


def sample_phasors(model: SpindleModel, theta: np.ndarray, speeds_rpm: np.ndarray,
                   sensors: SensorSet, inst: Installation, rng: np.random.Generator, *,
                   n_repeats: int = 1, duration_s: float = 1.0,
                   keyphasor_error: bool = True) -> np.ndarray:
    """Demodulated 1x phasors of ``n_repeats`` steady records per speed, drawn statistically:
    ``(n_repeats, S, n_probe)`` complex (m). ``keyphasor_error=False`` leaves out the
    keyphasor's phase error (100x faster; exact only for an ideal keyphasor)."""
    mean = expected_phasors(model, theta, speeds_rpm, sensors, inst)
    if not sensors.noise:
        return np.broadcast_to(mean, (n_repeats,) + mean.shape).copy()
    lsb_m = sensors.daq.lsb_V / sensors.probe.sensitivity_V_per_m if sensors.quantised else 0.0
    N = samples_in_revolutions(speeds_rpm, duration_s, sensors.daq.sample_rate_hz)
    sd = np.array([phasor_noise_sd(sensors.probe.noise_rms_m, lsb_m, n) for n in N])
    shape = (n_repeats,) + mean.shape
    noise = (rng.normal(size=shape) + 1j * rng.normal(size=shape)) * sd[None, :, None]
    delta = keyphasor_phase_errors(sensors, inst, speeds_rpm, rng, n_repeats=n_repeats,
                                   duration_s=duration_s) if keyphasor_error else 0.0
    # noise is added at the probe's output in volts, so it is on the nominal scale
    return mean[None] * np.exp(-1j * np.asarray(delta))[..., None] + noise


def keyphasor_phase_errors(sensors: SensorSet, inst: Installation, speeds_rpm: np.ndarray,
                           rng: np.random.Generator, *, n_repeats: int = 1,
                           duration_s: float = 1.0) -> np.ndarray:
    """Phase error ``δ = φ̂ − φ`` (rad, ``(n_repeats, S)``) of the keyphasor-derived shaft
    angle at the middle of a record, each record with a random initial angle: the counter
    timestamps (skew, trigger jitter, timebase) or the sampled channel (noise, skew, edges
    found as :func:`rig.demod.demodulate` does), fitted as the demodulation fits them."""
    fs = sensors.daq.sample_rate_hz
    n = int(round(duration_s * fs))
    t = np.arange(n) / fs
    names = sensors.channel_names("steady")
    delay = names.index("keyphasor") * sensors.daq.interchannel_delay_s
    tau = delay + inst.skew_s["keyphasor"]
    kp = sensors.keyphasor
    out = np.empty((n_repeats, len(speeds_rpm)))
    for j, s in enumerate(np.asarray(speeds_rpm, float)):
        w = s * RPM
        for r in range(n_repeats):
            phi0 = rng.uniform(0, 2 * np.pi)
            if kp.timing == "counter":
                k = np.arange(np.ceil(phi0 / (2 * np.pi)),
                              np.ceil((phi0 + w * t[-1]) / (2 * np.pi)))
                e = keyphasor_events(sensors, inst, (2 * np.pi * k - phi0) / w,
                                     np.full(k.size, w), rng)["keyphasor"]
            else:
                v = keyphasor_channel(sensors, phi0 + w * (t + tau), rng)
                e = edges_of(v, fs, delay, kp.polarity)
            tm = 0.5 * (e[0] + e[-1])
            est = ShaftAngle(e, True).angle(np.array([tm]))[0]
            out[r, j] = np.angle(np.exp(1j * (est - (phi0 + w * tm))))
    return out
