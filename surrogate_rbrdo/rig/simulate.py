"""Records of the three kinds of test, from a truth state through the sensors.

* :func:`steady_records` — constant speed after the transient has decayed: the response is the
  exact steady state of the linear model, ``x(t) = Re(X e^{iφ(t)})`` with ``X`` the FE harmonic
  solution (``spindle.harmonic.unbalance_response``, all speeds of a run in one vectorised
  solve). ``rig.integrate`` integrated from rest converges to the same samples (tested ≤ 1e-6);
  the residual transient after a settling time ``T`` is ``e^{−σT}`` of the free response
  (slowest σ = ζω ≈ 7.7 1/s for the reference spindle: 2e-17 after 5 s) and is not added.
* :func:`runup_record` — a speed ramp integrated by ``rig.integrate`` (frozen-matrix segments),
  started from rest 5 s before the ramp at the start speed (the exact jump makes the wait free).
* :func:`impact_record` — a hammer hit at the tool, at standstill or at a constant speed (then
  the record holds the response to the hit only: the synchronous response, which the
  keyphasor's 1x phasor removes, is left out), integrated exactly at ``oversample`` × the
  sample rate and decimated through a linear-phase anti-aliasing filter. The model is linear
  and hits differ by their peak force only: :func:`impact_response` (a 1 N hit) is simulated
  once per speed and direction and scaled by each hit's drawn peak.

Each channel then goes through its sensor (gain, driver low-pass, gap), the ADC's timing (known
delay + unknown skew), noise and quantisation/clipping (``rig.sensors``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy.signal import decimate

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.rig.integrate import IntegratorOptions, SpeedProfile, simulate
from surrogate_rbrdo.rig.keyphasor import angle_crossings, counter_events
from surrogate_rbrdo.rig.keyphasor import keyphasor_volts as kp_volts
from surrogate_rbrdo.rig.records import Record
from surrogate_rbrdo.rig.sensors import Installation, SensorSet
from surrogate_rbrdo.rig.statespace import first_order, reduction
from surrogate_rbrdo.rig.truth import Truth
from surrogate_rbrdo.spindle.assembly import RPM, SpindleModel, build_model
from surrogate_rbrdo.spindle.harmonic import unbalance_response
from surrogate_rbrdo.spindle.modal import modal_analysis

#: ramps: error-controlled segments, Ritz basis below 10 kHz (docs/rig.md)
RAMP_OPTIONS = IntegratorOptions()
#: impacts: constant speed, exact (the free decay after the hit in closed form)
IMPACT_OPTIONS = IntegratorOptions()


@dataclass(frozen=True)
class ProbeLayout:
    """FE nodes the probes look at: front bearing, rear bearing, tool tip."""

    nodes: dict[str, int]
    positions_mm: dict[str, float]

    @classmethod
    def of(cls, model: SpindleModel) -> ProbeLayout:
        """``front`` = the bearing nearest the tool tip, ``rear`` = the farthest one."""
        bz = model.z[model.bearing_nodes]
        dist = np.abs(bz - model.z[model.tool_node])
        nodes = {"front": int(model.bearing_nodes[np.argmin(dist)]),
                 "rear": int(model.bearing_nodes[np.argmax(dist)]),
                 "tool": int(model.tool_node)}
        return cls(nodes, {k: float(model.z[v] * 1e3) for k, v in nodes.items()})

    def dofs(self, sensors: SensorSet) -> np.ndarray:
        return np.array([4 * self.nodes[n.split("_")[0]] + (n.endswith("_y"))
                         for n in sensors.probe_channels])


def check_stable(model: SpindleModel, theta: np.ndarray, speeds_rpm: np.ndarray) -> None:
    """Raise :class:`ModelError` if a mode of the truth has negative damping at one of the
    speeds: no steady state exists there, so the rig cannot measure one."""
    for s in np.asarray(speeds_rpm, float):
        m = modal_analysis(model, float(s), theta[0])
        if np.any(m.damping_ratio < 0):
            k = int(np.argmin(m.damping_ratio))
            raise ModelError(
                f"the truth is unstable at {s:.6g} rpm: the {m.frequency_hz[k]:.4g} Hz "
                f"{m.whirl[k]} mode has damping ratio {m.damping_ratio[k]:.3g} (cross-coupling "
                "too strong for the damping?); no steady state to measure")


def check_nominal_stable(truth: Truth, speeds_rpm: np.ndarray) -> None:
    """:func:`check_stable` for the truth without its variability (θ = 1): a check before a
    campaign (which checks every drawn truth again)."""
    model = build_model(truth.geometry, truth.all_effects, theta_bearings=truth.theta_bearings)
    check_stable(model, np.ones((1, len(truth.theta_bearings))), speeds_rpm)


def keyphasor_volts(sensors: SensorSet, angle: np.ndarray) -> np.ndarray:
    """Noise-free keyphasor voltage at shaft angles ``angle`` (:func:`rig.keyphasor.
    keyphasor_volts` of ``sensors.keyphasor``)."""
    return kp_volts(sensors.keyphasor, angle)


def keyphasor_channel(sensors: SensorSet, angle: np.ndarray, rng: np.random.Generator
                      ) -> np.ndarray:
    """The keyphasor's analog voltage at the shaft angles of its samples, with noise."""
    v = kp_volts(sensors.keyphasor, angle)
    if sensors.noise and sensors.keyphasor.noise_V > 0:
        v = v + rng.normal(0, sensors.keyphasor.noise_V, v.shape)
    return v


def keyphasor_events(sensors: SensorSet, inst: Installation, crossings_s: np.ndarray,
                     omega: np.ndarray, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """``{"keyphasor": counter timestamps}`` of leading edges at true times ``crossings_s``
    on the record's time axis (nothing for a ``sampled`` keyphasor)."""
    if sensors.keyphasor.timing != "counter":
        return {}
    return {"keyphasor": counter_events(sensors.keyphasor, crossings_s, omega,
                                        inst.skew_s["keyphasor"],
                                        rng if sensors.noise else None, sensors.quantised)}


def _channel_delays(sensors: SensorSet, inst: Installation, kind: str) -> np.ndarray:
    names = sensors.channel_names(kind)
    return np.array([i * sensors.daq.interchannel_delay_s + inst.skew_s[n]
                     for i, n in enumerate(names)])


def steady_records(model: SpindleModel, theta: np.ndarray, speeds_rpm: np.ndarray,
                   sensors: SensorSet, inst: Installation, rngs: list[np.random.Generator],
                   *, duration_s: float = 1.0, ids: list[str], provenance: list[dict[str, Any]],
                   probe_rise_K: np.ndarray | None = None) -> list[Record]:
    """One steady-state record per speed (one run: one θ, one truth state).

    ``rngs[i]`` draws record ``i``'s noise and initial shaft angle. ``probe_rise_K[i]``: the
    probes' temperature rise during record ``i`` (their gains through their tempcos,
    :meth:`~.sensors.Installation.warmed`; None: none).
    """
    layout = ProbeLayout.of(model)
    sp = np.asarray(speeds_rpm, float)
    Q = unbalance_response(model, sp, theta)[0]          # (S, nn, 4)
    X = Q.reshape(sp.size, -1)[:, layout.dofs(sensors)]  # (S, n_probe)
    specs = sensors.channel_specs("steady", layout.positions_mm)
    names = sensors.probe_channels
    fs = sensors.daq.sample_rate_hz
    n = int(round(duration_s * fs))
    t = np.arange(n) / fs
    tau = _channel_delays(sensors, inst, "steady")
    out = []
    for i, s in enumerate(sp):
        rng = rngs[i]
        w = s * RPM
        phi0 = rng.uniform(0, 2 * np.pi)
        ang = phi0 + w * (t[None, :] + tau[:, None])            # (n_ch, n)
        Z = np.array([sensors.lowpass(c, inst, w / (2 * np.pi)) for c in names]) * X[i]
        x = np.abs(Z)[:, None] * np.cos(ang[:-1] + np.angle(Z)[:, None])   # Re(Z e^{iφ})
        warm = inst if probe_rise_K is None else inst.warmed(float(probe_rise_K[i]))
        volts = _volts(sensors, warm, names, x, rng)
        kp = keyphasor_channel(sensors, ang[-1], rng)
        k = np.arange(np.ceil(phi0 / (2 * np.pi)), np.ceil((phi0 + w * t[-1]) / (2 * np.pi)))
        events = keyphasor_events(sensors, inst, (2 * np.pi * k - phi0) / w,
                                  np.full(k.size, w), rng)
        data = sensors.digitise(np.vstack([volts, kp[None, :]]))
        out.append(Record(ids[i], "steady", fs, specs, data, speed_rpm=float(s),
                          provenance={**provenance[i], "initial_angle_rad": phi0},
                          events=events))
    return out


def _dynamics(sensors: SensorSet, inst: Installation, names, x: np.ndarray, fs: float,
              tau: np.ndarray) -> np.ndarray:
    """Driver low-pass and sampling delay of each channel, applied in the frequency domain on a
    mirror-padded record (``x``: (n_ch, n) true signals at the record's time axis)."""
    n = x.shape[1]
    pad = np.concatenate([x, x[:, ::-1]], axis=1)              # even extension: no end jump
    f = np.fft.rfftfreq(2 * n, 1 / fs)
    H = np.array([sensors.lowpass(c, inst, f) if c in sensors.probe_channels
                  else np.ones_like(f) for c in names]) * np.exp(2j * np.pi * f[None, :]
                                                              * tau[:, None])
    return np.fft.irfft(np.fft.rfft(pad, axis=1) * H, 2 * n, axis=1)[:, :n]


def runup_record(model: SpindleModel, theta: np.ndarray, profile: SpeedProfile,
                 sensors: SensorSet, inst: Installation, rng: np.random.Generator, *,
                 rid: str, provenance: dict[str, Any],
                 options: IntegratorOptions = RAMP_OPTIONS) -> Record:
    """A speed-ramp record (kind ``runup`` or ``rundown`` from the profile's direction)."""
    layout = ProbeLayout.of(model)
    fs = sensors.daq.sample_rate_hz
    T = profile.times_s[-1] - profile.times_s[0]
    t = profile.times_s[0] + np.arange(int(round(T * fs))) / fs
    if t.size < 2:
        raise ValueError(f"runup_record: the profile lasts {T} s: shorter than two samples")
    sim = simulate(model, profile, t, layout.dofs(sensors), theta=theta,
                   t0_s=profile.times_s[0] - 5.0, options=options)
    names = sensors.channel_names("runup")
    tau = _channel_delays(sensors, inst, "runup")
    x = _dynamics(sensors, inst, names[:-1], sim.q.T, fs, tau[:-1])
    volts = _volts(sensors, inst, names[:-1], x, rng)
    kp = keyphasor_channel(sensors, profile.angle(t + tau[-1]), rng)
    cross = angle_crossings(profile.angle, profile.omega, t[0], t[-1] + 1.0 / fs)
    events = keyphasor_events(sensors, inst, cross - t[0], profile.omega(cross), rng)
    kind = "runup" if profile.speeds_rpm[-1] >= profile.speeds_rpm[0] else "rundown"
    specs = sensors.channel_specs(kind, layout.positions_mm)
    prof = np.array([np.asarray(profile.times_s) - profile.times_s[0], profile.speeds_rpm])
    return Record(rid, kind, fs, specs, sensors.digitise(np.vstack([volts, kp])),
                  speed_profile=prof, provenance=provenance, events=events)


def _volts(sensors, inst, names, x, rng):
    """Probe voltages ``S (1 + ε) (gap + x)`` plus the probe noise, for true displacements
    ``x`` (n_ch, n) of channels ``names``."""
    S = sensors.probe.sensitivity_V_per_m
    gain = np.array([inst.gain[c] for c in names])[:, None]
    gap = np.array([inst.gap_m[c] for c in names])[:, None]
    v = S * gain * (gap + x)
    if sensors.noise and sensors.probe.noise_rms_m > 0:
        v += rng.normal(0, S * sensors.probe.noise_rms_m, v.shape)
    return v


def hammer_pulse(t: np.ndarray, t_hit: float, peak_N: float, width_s: float) -> np.ndarray:
    """Half-sine force pulse of ``width_s`` starting at ``t_hit``.

    >>> hammer_pulse(np.array([0.0, 0.5, 1.0]), 0.0, 10.0, 1.0).round(6).tolist()
    [0.0, 10.0, 0.0]
    """
    s = (t - t_hit) / width_s
    return np.where((s >= 0) & (s <= 1), peak_N * np.sin(np.pi * np.clip(s, 0, 1)), 0.0)


def held_force(f: np.ndarray, fs_hz: float) -> np.ndarray:
    """The fine force samples ``f`` as the force the integrator applies — their first-order
    hold (piecewise linear between samples: :mod:`~.stepping`) — band-limited and resampled on
    the same grid: the spectrum times ``sinc²(f/fs)`` (the hold's triangle kernel).

    Recording the raw samples instead made the force channel (and the accelerations' direct
    mass term) the half-sine the structure did *not* feel: H1 was 0.1–0.4 % off at 0.5–2 kHz
    (∝ the fine step²), which the impact fit read as 0.05 % of tool mass and 1.3 % of the
    rear bearing's η (docs/identification.md §5b).

    >>> fs = 40_000.0
    >>> t = np.arange(4000) / fs
    >>> f = np.sin(2 * np.pi * 1000.0 * t)                       # whole periods: one bin
    >>> g = held_force(f, fs)
    >>> bool(np.isclose(np.max(np.abs(g)), np.sinc(1000.0 / fs) ** 2, rtol=1e-9))
    True
    """
    F = np.fft.rfft(f)
    return np.fft.irfft(F * np.sinc(np.fft.rfftfreq(f.size, 1.0 / fs_hz) / fs_hz) ** 2, f.size)


@dataclass(frozen=True)
class ImpactResponse:
    """The noise-free channel signals ``x`` (n_ch, n) of an impact record — the probes'
    displacements (m), the accelerations (m/s²) and the force (N) after the anti-aliasing
    filter, the drivers and the channels' delays — for a hit of **1 N peak**, and what they
    were simulated for. The model is linear and the hits of a test differ by their peak force
    only, so one simulation serves every hit at the same speed and direction:
    :func:`impact_record` scales ``x`` by its drawn peak."""

    x: np.ndarray
    direction: str
    speed_rpm: float
    duration_s: float
    t_hit_s: float
    oversample: int


def impact_response(model: SpindleModel, theta: np.ndarray, sensors: SensorSet,
                    inst: Installation, *, direction: str = "x", duration_s: float = 1.0,
                    t_hit_s: float = 0.05, oversample: int = 4, speed_rpm: float = 0.0,
                    options: IntegratorOptions = IMPACT_OPTIONS) -> ImpactResponse:
    """Simulate the :class:`ImpactResponse` of a 1 N-peak hit at the tool tip in
    ``direction`` at ``speed_rpm``: integrated exactly at ``oversample`` × the sample rate
    (``options``: :func:`~.integrate.simulate`'s), decimated through a linear-phase
    anti-aliasing filter, through the drivers and delays."""
    layout = ProbeLayout.of(model)
    fs = sensors.daq.sample_rate_hz
    n = int(round(duration_s * fs))
    tf = np.arange(n * oversample) / (fs * oversample)
    f = hammer_pulse(tf, t_hit_s, 1.0, sensors.hammer.pulse_ms * 1e-3)
    tool = 4 * layout.nodes["tool"]
    fdof = np.array([tool + (direction == "y")])
    acc_dofs = np.array([tool, tool + 1])[:len(sensors.accel_channels)]
    sim = simulate(model, SpeedProfile.constant(speed_rpm), tf, layout.dofs(sensors),
                   theta=theta,
                   unbalance=False, force_dofs=fdof, force=f[:, None], acc_dofs=acc_dofs,
                   options=options)
    # anti-aliasing: linear-phase FIR, zero phase (the delay is compensated, as in DSA boards)
    # the force the integrator applied is the first-order hold of the fine samples; the
    # recorded force and the accelerations' direct (mass) term are that force, band-limited
    held = held_force(f, fs * oversample)
    acc_t = np.zeros((0, tf.size)) if sim.acc is None else (
        sim.acc.T + _feedthrough(model, theta, acc_dofs, fdof) @ (held - f)[None, :])
    fine = np.vstack([sim.q.T, acc_t, held[None, :]])
    coarse = decimate(fine, oversample, ftype="fir", axis=1, zero_phase=True)
    names = sensors.channel_names("impact")
    x = _dynamics(sensors, inst, names, coarse, fs, _channel_delays(sensors, inst, "impact"))
    return ImpactResponse(x, direction, float(speed_rpm), float(duration_s), float(t_hit_s),
                          int(oversample))


def impact_record(model: SpindleModel, theta: np.ndarray, sensors: SensorSet,
                  inst: Installation, rng: np.random.Generator, *, rid: str,
                  provenance: dict[str, Any], direction: str = "x", duration_s: float = 1.0,
                  t_hit_s: float = 0.05, oversample: int = 4, speed_rpm: float = 0.0,
                  response: ImpactResponse | None = None) -> Record:
    """A hammer hit at the tool tip in ``direction`` at ``speed_rpm`` (default standstill):
    all probes, the tool's accelerometers and the force. At speed the gyroscopic coupling and
    the bearings at that speed act; the synchronous response is not in the record (module
    doc). ``response``: the :func:`impact_response` of these arguments, if already simulated
    (the hits of one speed and direction share it); ``None``: simulated here."""
    args = (direction, float(speed_rpm), float(duration_s), float(t_hit_s), int(oversample))
    if response is None:
        response = impact_response(model, theta, sensors, inst, direction=direction,
                                   duration_s=duration_s, t_hit_s=t_hit_s,
                                   oversample=oversample, speed_rpm=speed_rpm)
    got = (response.direction, response.speed_rpm, response.duration_s, response.t_hit_s,
           response.oversample)
    if got != args:
        raise ValueError(f"impact_record {rid}: response was simulated for (direction, "
                         f"speed_rpm, duration_s, t_hit_s, oversample) = {got}: must be {args}")
    layout = ProbeLayout.of(model)
    fs = sensors.daq.sample_rate_hz
    hm = sensors.hammer
    peak = hm.peak_N * (1 + (rng.normal(0, hm.peak_sd) if sensors.noise else 0.0))
    x = peak * response.x
    n = x.shape[1]
    names = sensors.channel_names("impact")
    n_p, n_a = len(sensors.probe_channels), len(sensors.accel_channels)
    volts = _volts(sensors, inst, names[:n_p], x[:n_p], rng)
    acc = sensors.accelerometer
    av = x[n_p:n_p + n_a] * acc.sensitivity_V_per_ms2 * np.array(
        [inst.gain[c] for c in sensors.accel_channels])[:, None]
    fv = x[-1] * hm.sensitivity_V_per_N * inst.gain["hammer"]
    if sensors.noise:
        av = av + rng.normal(0, acc.noise_rms_ms2 * acc.sensitivity_V_per_ms2, av.shape)
        fv = fv + rng.normal(0, hm.noise_N * hm.sensitivity_V_per_N, n)
    specs = sensors.channel_specs("impact", layout.positions_mm)
    specs = specs[:-1] + (_hammer_dir(specs[-1], direction),)
    return Record(rid, "impact", fs, specs, sensors.digitise(np.vstack([volts, av, fv])),
                  speed_rpm=float(speed_rpm), provenance={**provenance, "peak_N": peak,
                                             "direction": direction})


def _feedthrough(model: SpindleModel, theta: np.ndarray, acc_dofs: np.ndarray,
                 force_dofs: np.ndarray) -> np.ndarray:
    """``∂q''/∂f`` at standstill from the force DOFs to the acceleration DOFs (the inverse
    mass matrix's block; massless DOFs condensed as :func:`~.statespace.first_order` does)."""
    n = model.system_matrices(0.0, theta)[0].shape[0]
    red = reduction(model, theta, np.zeros(1), np.zeros((n, 0)), None)
    return first_order(model, theta, 0.0, red).Da[np.ix_(acc_dofs, force_dofs)]


def _hammer_dir(spec, direction):
    return replace(spec, location=replace(spec.location, direction=direction))
