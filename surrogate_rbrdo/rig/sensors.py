"""Sensors and the acquisition chain of the virtual rig (sources of every figure: docs/rig.md).

Six eddy-current displacement probes (x and y at the front bearing, the rear bearing and the tool
tip), a once-per-revolution keyphasor, and for impact tests an impact-hammer force channel and
two accelerometers (x, y) on the tool, digitised by one multiplexed ADC. Per *installation* (a
campaign) each channel draws its true gain error, probe bandwidth and timing skew
(:meth:`SensorSet.install`); per *record* the noise is drawn.

A probe maps the displacement ``x(t)`` to volts ``S (1 + ε) (g + x)`` through a first-order
low-pass (its driver's bandwidth), adds white noise, and the ADC samples it at
``t_n + delay + skew`` (the nominal ``delay`` is written into the record, the ``skew`` is
not), rounds to ``bits`` and clips at its range. The record's calibration is the *nominal*
one: ``value = counts · lsb / S − g_nominal``.

>>> s = SensorSet()
>>> round(s.daq.lsb_V * 1e3, 4), round(s.daq.lsb_V / s.probe.sensitivity_V_per_m * 1e9, 1)
(0.3052, 38.8)
"""

from __future__ import annotations

import dataclasses
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive, check_range
from surrogate_rbrdo.rig.records import Calibration, ChannelSpec, SensorLocation

PROBE_TARGETS = ("front", "rear", "tool")
#: the scale of an eddy-current probe system's sensitivity temperature coefficient (1/K, one
#: SD), 0.05 %/K (a 15 K warm-up: 0.75 %): below an inductive analog distance sensor's data
#: sheet's "temperature drift ≤ ±0.15 %/K of full-scale value" (KJT NBB5-18GM60-I3, the one
#: sheet figure found), and of the order of an API 670 8 mm system's scale-factor tolerance
#: over its probe temperature range (about ±10 % over 155 K, ≤ 0.065 %/K; quoted from
#: memory, not checked against the sheet) — docs/rig.md
PROBE_TEMPCO_SD_PER_K = 5e-4


@dataclass(frozen=True)
class ProbeModel:
    """Eddy-current displacement probe system (probe + driver)."""

    sensitivity_V_per_m: float = 7870.0       # 200 mV/mil, API 670 / 8 mm probe systems
    gain_error_sd: float = 0.02                 # calibrated on the shaft material
    noise_rms_m: float = 50e-9                  # broadband, in the 0–5 kHz band
    bandwidth_hz: float = 10_000.0              # −3 dB of the driver (first-order)
    bandwidth_sd: float = 0.10                  # relative scatter of the bandwidth
    gap_m: float = 1.0e-3                       # nominal mean gap (DC, removed by calibration)
    gap_sd_m: float = 25e-6                     # install scatter of the gap
    #: SD of each probe system's sensitivity temperature coefficient (1/K; drawn per channel
    #: per installation, :data:`PROBE_TEMPCO_SD_PER_K` the data-sheet scale): the gain is
    #: ``(1 + ε)(1 + α ΔT)`` at a probe temperature rise ``ΔT`` — the bearing's outer ring's
    #: in the soak and, with ``tempco_sweep``, at each steady speed's thermal equilibrium
    #: (``rig.thermal``). 0 (default): no drift, the rig's records as before the option.
    tempco_sd_per_K: float = 0.0
    tempco_sweep: bool = True

    def __post_init__(self) -> None:
        for n in ("sensitivity_V_per_m", "bandwidth_hz", "gap_m"):
            check_positive(f"probe.{n}", getattr(self, n))
        if not isinstance(self.tempco_sweep, bool):
            raise ValueError(f"probe.tempco_sweep = {self.tempco_sweep!r} is not allowed: "
                             "true or false")
        for n in ("gain_error_sd", "noise_rms_m", "bandwidth_sd", "gap_sd_m", "tempco_sd_per_K"):
            check_positive(f"probe.{n}", getattr(self, n), allow_zero=True)


@dataclass(frozen=True)
class DAQModel:
    """A multiplexed ADC: resolution, input range, sample rate, inter-channel delay, skew."""

    bits: int = 16
    range_V: float = 10.0                       # ±range_V
    sample_rate_hz: float = 10_000.0
    interchannel_delay_s: float = 4e-6          # known, written into each channel's delay_s
    skew_sd_s: float = 0.2e-6                   # unknown timing error per channel

    def __post_init__(self) -> None:
        check_int("daq.bits", self.bits, minimum=8)
        if self.bits > 31:
            raise ValueError(f"daq.bits = {self.bits} is not allowed: at most 31")
        check_positive("daq.range_V", self.range_V)
        check_positive("daq.sample_rate_hz", self.sample_rate_hz)
        check_positive("daq.interchannel_delay_s", self.interchannel_delay_s, allow_zero=True)
        check_positive("daq.skew_sd_s", self.skew_sd_s, allow_zero=True)

    @property
    def lsb_V(self) -> float:
        return 2 * self.range_V / 2**self.bits

    @property
    def counts_limits(self) -> tuple[int, int]:
        return -(2 ** (self.bits - 1)), 2 ** (self.bits - 1) - 1

    @property
    def dtype(self) -> type:
        return np.int16 if self.bits <= 16 else np.int32


@dataclass(frozen=True)
class KeyphasorModel:
    """Once-per-revolution pulse: ``high_V`` while the mark passes (``notch_deg`` wide),
    raised-cosine edges ``edge_deg`` wide, the leading edge centred on the shaft's angular
    reference; ``polarity``: ``positive`` (a key: the voltage rises) or ``negative`` (a notch:
    it falls). ``timing``: ``counter`` — the leading edges are also timestamped by a counter
    with a ``counter_clock_hz`` timebase (``Record.events["keyphasor"]``) — or ``sampled``
    (the analog channel only). ``rig.keyphasor`` has the sources."""

    high_V: float = 5.0
    notch_deg: float = 30.0
    edge_deg: float = 10.0
    noise_V: float = 0.01
    polarity: str = "positive"
    timing: str = "counter"
    counter_clock_hz: float = 80e6             # NI USB-621x counter timebase

    def __post_init__(self) -> None:
        check_positive("keyphasor.high_V", self.high_V)
        check_range("keyphasor.notch_deg", self.notch_deg, 1.0, 180.0)
        check_range("keyphasor.edge_deg", self.edge_deg, 0.0, self.notch_deg)
        check_positive("keyphasor.noise_V", self.noise_V, allow_zero=True)
        check_choice("keyphasor.polarity", self.polarity, ("positive", "negative"))
        check_choice("keyphasor.timing", self.timing, ("counter", "sampled"))
        check_positive("keyphasor.counter_clock_hz", self.counter_clock_hz)


@dataclass(frozen=True)
class HammerModel:
    """Instrumented impact hammer: half-sine pulse of ``pulse_ms`` and ``peak_N``."""

    sensitivity_V_per_N: float = 2.25e-3        # 2.25 mV/N, a medium impact hammer
    peak_N: float = 300.0
    peak_sd: float = 0.2
    pulse_ms: float = 0.4                        # hard (steel) tip
    noise_N: float = 0.2
    gain_error_sd: float = 0.01                  # calibration certificate uncertainty

    def __post_init__(self) -> None:
        for n in ("sensitivity_V_per_N", "peak_N", "pulse_ms"):
            check_positive(f"hammer.{n}", getattr(self, n))
        for n in ("peak_sd", "noise_N", "gain_error_sd"):
            check_positive(f"hammer.{n}", getattr(self, n), allow_zero=True)


@dataclass(frozen=True)
class AccelerometerModel:
    """A modal accelerometer on the tool for impact tests (defaults: PCB Piezotronics 352C33
    data sheet — 100 mV/g, ±50 g, broadband resolution 0.00015 g rms over 1 Hz–10 kHz,
    flat ±5 % over 0.5 Hz–10 kHz, mounted resonance ≥ 50 kHz: no dynamics modelled)."""

    sensitivity_V_per_ms2: float = 0.1 / 9.80665
    noise_rms_ms2: float = 0.00015 * 9.80665
    gain_error_sd: float = 0.01                  # calibration certificate uncertainty

    def __post_init__(self) -> None:
        check_positive("accelerometer.sensitivity_V_per_ms2", self.sensitivity_V_per_ms2)
        check_positive("accelerometer.noise_rms_ms2", self.noise_rms_ms2, allow_zero=True)
        check_positive("accelerometer.gain_error_sd", self.gain_error_sd, allow_zero=True)


@dataclass(frozen=True)
class Installation:
    """The drawn (hidden) state of each channel: gain error, bandwidth, skew, gap, and the
    probes' sensitivity temperature coefficients (1/K; empty: none)."""

    gain: dict[str, float]
    bandwidth_hz: dict[str, float]
    skew_s: dict[str, float]
    gap_m: dict[str, float]
    tempco_per_K: dict[str, float] = field(default_factory=dict)

    def warmed(self, rise_K: float) -> Installation:
        """The installation with every probe ``rise_K`` warmer: each gain times
        ``1 + α rise_K`` (itself without tempcos or at no rise).

        >>> inst = Installation({"a": 1.01}, {"a": 1e4}, {"a": 0.0}, {"a": 1e-3}, {"a": 1e-3})
        >>> round(inst.warmed(10.0).gain["a"], 6)
        1.0201
        """
        if not self.tempco_per_K or rise_K == 0:
            return self
        gain = {n: g * (1.0 + self.tempco_per_K.get(n, 0.0) * rise_K)
                for n, g in self.gain.items()}
        return dataclasses.replace(self, gain=gain)

    def to_dict(self) -> dict[str, Any]:
        out = {"gain": self.gain, "bandwidth_hz": self.bandwidth_hz, "skew_s": self.skew_s,
               "gap_m": self.gap_m}
        return {**out, "tempco_per_K": self.tempco_per_K} if self.tempco_per_K else out


@dataclass(frozen=True)
class SensorSet:
    """All sensors of the rig and the acquisition chain.

    ``noise=False`` switches every random error off (noise, gain/bandwidth/skew/gap scatter,
    trigger jitter). ``quantise``: round samples to the ADC's counts (and counter timestamps to
    its timebase); ``None`` (default) follows ``noise`` — so with the noise off the records are
    the FE answer through the sensors' deterministic dynamics (driver low-pass, known delays)
    and clipping, stored as float counts. Quantisation alone is not negligible: an LSB of the
    default 16-bit converter is 38.8 nm, more than the bearings' whole 1x at low speed (0.24 nm
    at 1 000 rpm on the reference spindle); without noise to dither it, the rounding error does
    not average out over a record.
    """

    probe: ProbeModel = ProbeModel()
    daq: DAQModel = DAQModel()
    keyphasor: KeyphasorModel = KeyphasorModel()
    hammer: HammerModel = HammerModel()
    accelerometer: AccelerometerModel = AccelerometerModel()
    targets: tuple[str, ...] = PROBE_TARGETS
    accelerometers: bool = True
    noise: bool = True
    quantise: bool | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "targets", tuple(self.targets))
        for t in self.targets:
            check_choice("sensors.targets[]", t, PROBE_TARGETS)
        if self.quantise is not None and not isinstance(self.quantise, bool):
            raise ValueError(f"sensors.quantise = {self.quantise!r} is not allowed: true, "
                             "false or null (follow noise)")

    @property
    def quantised(self) -> bool:
        """Whether samples are rounded to counts (``quantise``, else ``noise``)."""
        return self.noise if self.quantise is None else self.quantise

    @property
    def probe_channels(self) -> tuple[str, ...]:
        return tuple(f"{t}_{d}" for t in self.targets for d in ("x", "y"))

    @property
    def accel_channels(self) -> tuple[str, ...]:
        """Accelerometers of impact tests (``tool_ax``, ``tool_ay``), if ``accelerometers``."""
        return ("tool_ax", "tool_ay") if self.accelerometers else ()

    def channel_names(self, kind: str) -> tuple[str, ...]:
        """Channel order of a record: probes, then the keyphasor (rotating tests) or the
        accelerometers and the hammer (impact)."""
        if kind == "impact":
            return self.probe_channels + self.accel_channels + ("hammer",)
        return self.probe_channels + ("keyphasor",)

    def install(self, rng: np.random.Generator) -> Installation:
        """Draw each channel's gain error, bandwidth, timing skew and gap, and (with
        ``probe.tempco_sd_per_K`` > 0 and the noise on) each probe's tempco after them: an
        installation without tempcos draws what it drew before the option."""
        p, d = self.probe, self.daq
        names = self.probe_channels + ("keyphasor", "hammer") + self.accel_channels
        on = 1.0 if self.noise else 0.0
        sd = {"hammer": self.hammer.gain_error_sd, "keyphasor": 0.0,
              **{a: self.accelerometer.gain_error_sd for a in self.accel_channels}}
        gain = {n: float(1 + on * rng.normal(0, sd.get(n, p.gain_error_sd))) for n in names}
        bw = {n: float(p.bandwidth_hz * (1 + on * rng.normal(0, p.bandwidth_sd))) for n in names}
        skew = {n: float(on * rng.normal(0, d.skew_sd_s)) for n in names}
        gap = {n: float(p.gap_m + on * rng.normal(0, p.gap_sd_m)) for n in names}
        tempco = ({n: float(rng.normal(0, p.tempco_sd_per_K)) for n in self.probe_channels}
                  if self.noise and p.tempco_sd_per_K > 0 else {})
        return Installation(gain, bw, skew, gap, tempco)

    def channel_specs(self, kind: str, positions_mm: dict[str, float]) -> tuple[ChannelSpec, ...]:
        """Channel specs (nominal calibration, known delays) of a record of ``kind``."""
        lo, hi = self.daq.counts_limits
        lsb, adc = self.daq.lsb_V, {"adc_bits": self.daq.bits, "adc_range_V": self.daq.range_V}
        out = []
        for i, name in enumerate(self.channel_names(kind)):
            delay = i * self.daq.interchannel_delay_s
            tool = positions_mm.get("tool", np.nan)
            if name == "keyphasor":
                spec = ("keyphasor", "V", SensorLocation("shaft"), lsb, 0.0, {
                    "sensor": "keyphasor", "polarity": self.keyphasor.polarity,
                    "timing": self.keyphasor.timing,
                    "counter_clock_hz": self.keyphasor.counter_clock_hz})
            elif name == "hammer":
                spec = ("force", "N", SensorLocation("tool", "x", tool),
                        lsb / self.hammer.sensitivity_V_per_N, 0.0, {
                            "sensor": "impact hammer",
                            "sensitivity_V_per_N": self.hammer.sensitivity_V_per_N})
            elif name in self.accel_channels:
                spec = ("acceleration", "m/s^2", SensorLocation("tool", name[-1], tool),
                        lsb / self.accelerometer.sensitivity_V_per_ms2, 0.0, {
                            "sensor": "accelerometer", "sensitivity_V_per_ms2":
                            self.accelerometer.sensitivity_V_per_ms2})
            else:
                target, direction = name.split("_")
                spec = ("displacement", "m", SensorLocation(target, direction,
                                                            positions_mm[target]),
                        lsb / self.probe.sensitivity_V_per_m, -self.probe.gap_m, {
                            "sensor": "eddy-current probe",
                            "sensitivity_V_per_m": self.probe.sensitivity_V_per_m})
            qty, unit, loc, scale, offset, info = spec
            out.append(ChannelSpec(name, qty, unit, loc, Calibration(scale, offset, lo, hi),
                                   delay, {**info, **adc}))
        return tuple(out)

    def digitise(self, volts: np.ndarray) -> np.ndarray:
        """Volts to ADC counts, clipped at the converter's limits (any shape): rounded to
        integers when :attr:`quantised`, else float64 counts."""
        lo, hi = self.daq.counts_limits
        counts = volts / self.daq.lsb_V
        if not self.quantised:
            return np.clip(counts, lo, hi)
        return np.clip(np.rint(counts), lo, hi).astype(self.daq.dtype)

    def lowpass(self, name: str, inst: Installation, freq_hz: np.ndarray) -> np.ndarray:
        """Complex first-order response of channel ``name``'s driver at ``freq_hz``."""
        return 1.0 / (1.0 + 1j * np.asarray(freq_hz) / inst.bandwidth_hz[name])

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)
