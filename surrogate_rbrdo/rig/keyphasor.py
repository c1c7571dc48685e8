"""The once-per-revolution reference: its signal, its counter timestamps, and its edges.

Two ways a DAQ records a keyphasor, both in the format (``docs/measured-data.md``):

* **sampled** — the keyphasor voltage is one more analog channel at the sample rate. Its edge
  lies between samples; :func:`edges_of` finds it by a cubic through four samples. Where the
  samples per revolution are a whole number the edges fall at the same sub-sample position every
  revolution, so the interpolation error does not average out: the shaft angle, and the 1x
  phase of every channel with it, is biased by up to half a sample of angle (the bound of
  :func:`sampled_phase_bound`; measured 0.7° at 12 000 rpm and 3.4° at 24 000 rpm with the
  default 10° edges at 10 kHz);
* **counter** (the rig's default) — a counter/timer input timestamps the leading edge with its
  own timebase, as DAQs and condition-monitoring front ends do (e.g. the NI USB-621x counters:
  32 bit, 80 MHz timebase, NI *USB-6211 Specifications*; Bently Nevada ADRE and B&K LAN-XI tacho
  inputs likewise). The record carries the timestamps as ``events["keyphasor"]``; the phase
  error is the timebase step (12.5 ns: 0.002° at 400 Hz) plus the trigger jitter
  ``σ_V / (dV/dt)`` (noise over slew rate at the threshold; 0.01° at 24 000 rpm with the
  default pulse and 10 mV noise).

A keyphasor's *leading* edge marks the angular reference: the rising edge of a positive pulse
(a key or raised strip) or the falling edge of a negative-going one (a notch seen by a proximity
probe). :func:`edges_of` takes the polarity from the channel's ``info["polarity"]`` or, failing
that, from the pulse train itself: the pulse is the minority state.

>>> fs = 1000.0
>>> ang = 2 * np.pi * 10.0 * np.arange(1000) / fs + 0.1        # 600 rpm
>>> v = np.where(np.mod(ang, 2 * np.pi) < 0.5, 0.0, 5.0)        # a notch: negative-going
>>> e = edges_of(v, fs)
>>> np.round(e[:2] * 10.0, 1).tolist()      # revolutions at the edges: the falling ones
[1.0, 2.0]
"""

from __future__ import annotations

import numpy as np

POLARITIES = ("positive", "negative")


def keyphasor_volts(kp, angle: np.ndarray) -> np.ndarray:
    """Noise-free keyphasor voltage (model ``kp``: a :class:`~.sensors.KeyphasorModel`) at
    shaft angles ``angle``: a pulse whose leading edge is centred on angle 0."""
    a = np.degrees(np.mod(angle + np.radians(kp.edge_deg / 2), 2 * np.pi))  # edge starts here
    e = max(kp.edge_deg, 1e-9)
    s = np.minimum(np.clip(a / e, 0, 1), np.clip((kp.notch_deg + e - a) / e, 0, 1))
    pulse = kp.high_V * 0.5 * (1 - np.cos(np.pi * s))
    return pulse if kp.polarity == "positive" else kp.high_V - pulse


def trigger_jitter_s(kp, omega: np.ndarray) -> np.ndarray:
    """RMS timing jitter of a threshold trigger at mid-edge: noise over slew rate,
    ``σ_V / (V_h π / (2 Δ) · Ω)`` for the raised-cosine edge of width ``Δ`` (rad)."""
    if kp.edge_deg == 0.0 or kp.noise_V == 0.0:
        return np.zeros_like(np.asarray(omega, float))
    slew = kp.high_V * np.pi / (2 * np.radians(kp.edge_deg)) * np.asarray(omega, float)
    return kp.noise_V / slew


def counter_events(kp, crossings_s: np.ndarray, omega: np.ndarray, skew_s: float,
                   rng: np.random.Generator | None, quantise: bool) -> np.ndarray:
    """Counter timestamps of the leading edges at true times ``crossings_s`` (shaft speed
    ``omega`` there): the channel's unknown skew, trigger jitter (if ``rng``) and the
    timebase step (if ``quantise``)."""
    t = np.asarray(crossings_s, float) - skew_s
    if rng is not None:
        t = t + rng.normal(size=t.size) * trigger_jitter_s(kp, omega)
    if quantise:
        t = np.round(t * kp.counter_clock_hz) / kp.counter_clock_hz
    return t


def angle_crossings(angle, omega, t0: float, t1: float) -> np.ndarray:
    """Times in ``[t0, t1)`` where a non-decreasing shaft angle ``angle(t)`` passes a
    multiple of 2π (Newton from a linear guess; ``omega(t) = angle'(t) > 0`` there)."""
    a0, a1 = angle(np.array([t0, t1]))
    k = np.arange(np.ceil(a0 / (2 * np.pi)), np.ceil(a1 / (2 * np.pi)))
    if k.size == 0:
        return np.zeros(0)
    grid = np.linspace(t0, t1, max(64, 4 * k.size))
    t = np.interp(2 * np.pi * k, angle(grid), grid)
    for _ in range(6):
        w = omega(t)
        step = np.where(w > 0, (angle(t) - 2 * np.pi * k) / np.where(w > 0, w, 1.0), 0.0)
        t = np.clip(t - step, t0, t1)
    return t[(t >= t0) & (t < t1)]


def sampled_phase_bound(speed_rpm: float, fs: float) -> float:
    """Largest phase bias (deg) of a sampled keyphasor's edges: half a sample of angle."""
    return 0.5 * 360.0 * speed_rpm / 60.0 / fs


def polarity_of(v: np.ndarray, declared: str | None = None) -> str:
    """``"positive"`` or ``"negative"``: ``declared`` if given, else the pulse is the state
    the signal spends less time in. Raises ``ValueError`` when the duty is too near 50 %."""
    if declared is not None:
        if declared not in POLARITIES:
            raise ValueError(f"info.polarity = {declared!r} is not allowed: one of "
                             f"{list(POLARITIES)}")
        return declared
    lo, hi = np.percentile(v, 1), np.percentile(v, 99)
    high = np.mean(v > 0.5 * (lo + hi))
    if 0.4 <= high <= 0.6:
        raise ValueError(f"the pulse train is high {high:.0%} of the time: its polarity is "
                         "ambiguous; state info.polarity ('positive' or 'negative')")
    return "positive" if high < 0.5 else "negative"


def edges_of(v: np.ndarray, fs: float, delay_s: float = 0.0, polarity: str | None = None
             ) -> np.ndarray:
    """Leading-edge times of a sampled pulse train ``v`` (threshold at mid-swing, cubic
    interpolation between samples), corrected for a known sampling delay."""
    if polarity_of(v, polarity) == "negative":
        v = -np.asarray(v, float)
    lo, hi = np.percentile(v, 1), np.percentile(v, 99)
    thr = 0.5 * (lo + hi)
    k = np.nonzero((v[:-1] < thr) & (v[1:] >= thr))[0]
    frac = (thr - v[k]) / (v[k + 1] - v[k])
    inner = (k >= 1) & (k + 2 < v.size)      # refine on the cubic through samples k-1 .. k+2
    kk = k[inner]
    p = np.stack([v[kk - 1], v[kk], v[kk + 1], v[kk + 2]])
    x = frac[inner]
    for _ in range(4):
        L = [-(x) * (x - 1) * (x - 2) / 6, (x + 1) * (x - 1) * (x - 2) / 2,
             -(x + 1) * x * (x - 2) / 2, (x + 1) * x * (x - 1) / 6]
        dL = [-(3 * x**2 - 6 * x + 2) / 6, (3 * x**2 - 4 * x - 1) / 2,
              -(3 * x**2 - 2 * x - 2) / 2, (3 * x**2 - 1) / 6]
        f = sum(Li * pi for Li, pi in zip(L, p, strict=True)) - thr
        df = sum(Li * pi for Li, pi in zip(dL, p, strict=True))
        x = np.clip(x - f / np.where(df > 0, df, np.inf), 0.0, 1.0)
    frac[inner] = x
    return (k + frac) / fs + delay_s
