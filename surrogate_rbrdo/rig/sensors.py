"""Sensors and the acquisition chain of the virtual rig (sources of every figure: docs/rig.md).

Six eddy-current displacement probes (x and y at the front bearing, the rear bearing and the tool
tip), a once-per-revolution keyphasor and an impact-hammer force channel, digitised by one
multiplexed ADC. Per *installation* (a campaign) each channel draws its true gain error,
probe bandwidth and timing skew (:meth:`SensorSet.install`); per *record* the noise is drawn.

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

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive, check_range
from surrogate_rbrdo.rig.records import Calibration, ChannelSpec, SensorLocation

PROBE_TARGETS = ("front", "rear", "tool")


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

    def __post_init__(self) -> None:
        for n in ("sensitivity_V_per_m", "bandwidth_hz", "gap_m"):
            check_positive(f"probe.{n}", getattr(self, n))
        for n in ("gain_error_sd", "noise_rms_m", "bandwidth_sd", "gap_sd_m"):
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
    """Once-per-revolution pulse: ``high_V`` while the notch passes (``notch_deg`` wide),
    raised-cosine edges ``edge_deg`` wide, centred on the shaft's angular reference."""

    high_V: float = 5.0
    notch_deg: float = 30.0
    edge_deg: float = 10.0
    noise_V: float = 0.01

    def __post_init__(self) -> None:
        check_positive("keyphasor.high_V", self.high_V)
        check_range("keyphasor.notch_deg", self.notch_deg, 1.0, 180.0)
        check_range("keyphasor.edge_deg", self.edge_deg, 0.0, self.notch_deg)
        check_positive("keyphasor.noise_V", self.noise_V, allow_zero=True)


@dataclass(frozen=True)
class HammerModel:
    """Instrumented impact hammer: half-sine pulse of ``pulse_ms`` and ``peak_N``."""

    sensitivity_V_per_N: float = 2.25e-3        # 2.25 mV/N, a medium impact hammer
    peak_N: float = 300.0
    peak_sd: float = 0.2
    pulse_ms: float = 0.4                        # hard (steel) tip
    noise_N: float = 0.2

    def __post_init__(self) -> None:
        for n in ("sensitivity_V_per_N", "peak_N", "pulse_ms"):
            check_positive(f"hammer.{n}", getattr(self, n))
        check_positive("hammer.peak_sd", self.peak_sd, allow_zero=True)
        check_positive("hammer.noise_N", self.noise_N, allow_zero=True)


@dataclass(frozen=True)
class Installation:
    """The drawn (hidden) state of each channel: gain error, bandwidth, skew, gap."""

    gain: dict[str, float]
    bandwidth_hz: dict[str, float]
    skew_s: dict[str, float]
    gap_m: dict[str, float]

    def to_dict(self) -> dict[str, Any]:
        return {"gain": self.gain, "bandwidth_hz": self.bandwidth_hz, "skew_s": self.skew_s,
                "gap_m": self.gap_m}


@dataclass(frozen=True)
class SensorSet:
    """All sensors of the rig and the acquisition chain; ``noise=False`` switches every random
    error off (noise, gain/bandwidth/skew/gap scatter) but keeps quantisation and clipping."""

    probe: ProbeModel = ProbeModel()
    daq: DAQModel = DAQModel()
    keyphasor: KeyphasorModel = KeyphasorModel()
    hammer: HammerModel = HammerModel()
    targets: tuple[str, ...] = PROBE_TARGETS
    noise: bool = True
    extra: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "targets", tuple(self.targets))
        for t in self.targets:
            check_choice("sensors.targets[]", t, PROBE_TARGETS)

    @property
    def probe_channels(self) -> tuple[str, ...]:
        return tuple(f"{t}_{d}" for t in self.targets for d in ("x", "y"))

    def channel_names(self, kind: str) -> tuple[str, ...]:
        """Channel order of a record: probes, keyphasor (rotating tests) or hammer (impact)."""
        return self.probe_channels + (("hammer",) if kind == "impact" else ("keyphasor",))

    def install(self, rng: np.random.Generator) -> Installation:
        """Draw each channel's gain error, bandwidth, timing skew and gap."""
        p, d = self.probe, self.daq
        names = self.probe_channels + ("keyphasor", "hammer")
        on = 1.0 if self.noise else 0.0
        gain = {n: float(1 + on * rng.normal(0, p.gain_error_sd)) for n in names}
        bw = {n: float(p.bandwidth_hz * (1 + on * rng.normal(0, p.bandwidth_sd))) for n in names}
        skew = {n: float(on * rng.normal(0, d.skew_sd_s)) for n in names}
        gap = {n: float(p.gap_m + on * rng.normal(0, p.gap_sd_m)) for n in names}
        gain["keyphasor"] = 1.0
        return Installation(gain, bw, skew, gap)

    def channel_specs(self, kind: str, positions_mm: dict[str, float]) -> tuple[ChannelSpec, ...]:
        """Channel specs (nominal calibration, known delays) of a record of ``kind``."""
        lo, hi = self.daq.counts_limits
        out = []
        for i, name in enumerate(self.channel_names(kind)):
            delay = i * self.daq.interchannel_delay_s
            if name in ("keyphasor", "hammer"):
                qty, unit = ("keyphasor", "V") if name == "keyphasor" else ("force", "N")
                scale = self.daq.lsb_V / (1.0 if name == "keyphasor"
                                          else self.hammer.sensitivity_V_per_N)
                loc = SensorLocation("shaft" if name == "keyphasor" else "tool",
                                     "" if name == "keyphasor" else "x",
                                     positions_mm.get("tool", np.nan) if name == "hammer"
                                     else np.nan)
                out.append(ChannelSpec(name, qty, unit, loc, Calibration(scale, 0.0, lo, hi),
                                       delay))
                continue
            target, direction = name.split("_")
            cal = Calibration(self.daq.lsb_V / self.probe.sensitivity_V_per_m,
                              -self.probe.gap_m, lo, hi)
            out.append(ChannelSpec(
                name, "displacement", "m", SensorLocation(target, direction,
                                                          positions_mm[target]),
                cal, delay, info={"sensor": "eddy-current probe",
                                  "sensitivity_V_per_m": self.probe.sensitivity_V_per_m,
                                  "adc_bits": self.daq.bits, "adc_range_V": self.daq.range_V}))
        return tuple(out)

    def digitise(self, volts: np.ndarray) -> np.ndarray:
        """Round volts to counts of the ADC and clip at its limits (any shape)."""
        lo, hi = self.daq.counts_limits
        return np.clip(np.rint(volts / self.daq.lsb_V), lo, hi).astype(self.daq.dtype)

    def lowpass(self, name: str, inst: Installation, freq_hz: np.ndarray) -> np.ndarray:
        """Complex first-order response of channel ``name``'s driver at ``freq_hz``."""
        return 1.0 / (1.0 + 1j * np.asarray(freq_hz) / inst.bandwidth_hz[name])

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)
