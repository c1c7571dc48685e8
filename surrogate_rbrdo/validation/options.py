"""Options of a validation campaign on the virtual rig (the ``[validation]`` table).

>>> o = ValidationOptions(n_replications=10, speeds_rpm={"start": 1000, "stop": 24000,
...                                                       "step": 500})
>>> len(o.speeds_rpm), o.delta_lim_m
(47, 1.95e-05)
>>> ValidationOptions.from_dict({"n_replications": 5, "peak": {"n_grid": 30}}).peak.n_grid
30
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.core.magnitudes import check_displacement_limit
from surrogate_rbrdo.core.validate import (
    check_choice,
    check_int,
    check_keys,
    check_positive,
    check_range,
)
from surrogate_rbrdo.rig.demod import check_record_lengths
from surrogate_rbrdo.rig.sensors import SensorSet
from surrogate_rbrdo.spindle.harmonic import PeakOptions
from surrogate_rbrdo.validation.replicas import (
    DEFAULT_SHARED,
    LEVELS,
    SHARE_GROUPS,
    check_groups,
)

#: how a steady-state measurement is made: phasors drawn directly (exact for a linear truth,
#: see docs/rig.md "the fast path") or time records simulated and demodulated
METHODS = ("phasors", "records")


def _default_speeds() -> tuple[float, ...]:
    return tuple(np.arange(1000.0, 24000.0 + 1.0, 100.0).tolist())


def _speed_list(value: Any) -> tuple[float, ...]:
    if isinstance(value, Mapping):
        check_keys("validation.speeds_rpm", value, {"start", "stop", "step"})
        if set(value) != {"start", "stop", "step"}:
            raise ValueError(f"speeds_rpm = {dict(value)!r} is not allowed: a table needs "
                             "start, stop and step")
        a, b, s = (float(value[k]) for k in ("start", "stop", "step"))
        value = np.arange(a, b + 0.5 * s, s) if s > 0 and b > a else [np.nan]
    sp = np.asarray(value, dtype=float)
    if sp.ndim != 1 or sp.size < 2 or not np.all(np.isfinite(sp)) or np.any(sp <= 0) \
            or np.any(np.diff(sp) <= 0):
        raise ValueError(f"speeds_rpm = {value!r} is not allowed: a strictly increasing list "
                         "of at least two speeds > 0 (or {start, stop, step})")
    return tuple(sp.tolist())


@dataclass(frozen=True)
class ValidationOptions:
    """What to build, measure and test (defaults: the paper's Sect. 4.3 campaign).

    Attributes
    ----------
    n_replications : int
        Paired replications per design (the paper: 20).
    baseline : str or None
        Name of the design the others are compared with (default: the first one).
    delta_lim_um : float
        Vibration limit δ_lim (µm); failure is ``y > δ_lim``.
    speed_range_rpm : (lo, hi)
        Operating range over which the peak ``y`` is searched.
    speeds_rpm : tuple or {start, stop, step}
        Steady-state speeds of the full-range response (Fig. 8); default every 100 rpm.
    rated_speed_rpm : float
        Speed of the rated-speed measurement (the paper's Table 7: 24 000 rpm).
    peak : PeakOptions
        The dwell search for the peak over the range: the same search as the model's ``y``.
    duration_s : float
        Length of each steady-state record.
    sensors : SensorSet
        Probes and acquisition (one installation for the whole campaign).
    method : "phasors" | "records"
        Steady-state measurements by the fast phasor path or by time records.
    keyphasor_error : bool
        Include the sampled keyphasor's phase error in the phasors (amplitudes do not depend
        on it; off = a counter-timed keyphasor).
    replicate, shared : tuple of str
        Levels drawn anew per replication; draw groups a pair shares (``validation.replicas``).
    ramps : int
        Replications per design with a run-up and a run-down (critical speeds).
    ramp_rpm : (start, end) or None
        Speeds of the ramps (default ``speed_range_rpm``); ``ramp_s`` their duration.
    ramp_channel : str
        Probe channel whose 1x peaks give the critical speeds.
    ramp_segment_s : float
        Frozen-matrix segment of the ramp integration: 20 ms moves the response by 1.5e-4
        against 2.5 ms (docs/rig.md, the integrator's table), nothing a peak speed notices,
        at half the cost of the campaign's 10 ms.
    confidence, alpha, power : float
        Interval level, significance level (tests, verdicts), power of the power statements.
    n_boot : int
        Bootstrap resamples.
    calibration_u : float or None
        Relative standard uncertainty of the amplitude calibration (type B) in the
        model-vs-measurement verdicts; default the probes' ``gain_error_sd``.
    band_samples : int
        θ samples of the model's ±2σ band (Fig. 8).
    campbell_speeds : int
        Speeds of the model's Campbell diagram (Fig. 7), 0 to 1.15 x the top of the range.
    """

    n_replications: int = 20
    baseline: str | None = None
    delta_lim_um: float = 19.5
    speed_range_rpm: tuple[float, float] = (1000.0, 24000.0)
    speeds_rpm: tuple[float, ...] | dict[str, float] = field(default_factory=_default_speeds)
    rated_speed_rpm: float = 24000.0
    peak: PeakOptions = PeakOptions()
    duration_s: float = 1.0
    sensors: SensorSet = SensorSet()
    method: str = "phasors"
    keyphasor_error: bool = False
    replicate: tuple[str, ...] = LEVELS
    shared: tuple[str, ...] = DEFAULT_SHARED
    ramps: int = 1
    ramp_rpm: tuple[float, float] | None = None
    ramp_s: float = 10.0
    ramp_channel: str = "tool_x"
    ramp_segment_s: float = 0.02
    confidence: float = 0.95
    alpha: float = 0.05
    power: float = 0.8
    n_boot: int = 9999
    calibration_u: float | None = None
    band_samples: int = 100
    campbell_speeds: int = 25

    def __post_init__(self) -> None:
        check_int("n_replications", self.n_replications, minimum=4)
        check_displacement_limit("delta_lim_um", self.delta_lim_um)
        lo, hi = self.speed_range_rpm
        if not (0 < lo < hi and np.isfinite(hi)):
            raise ValueError(f"speed_range_rpm = {self.speed_range_rpm} is not allowed: "
                             "need 0 < lo < hi")
        object.__setattr__(self, "speed_range_rpm", (float(lo), float(hi)))
        object.__setattr__(self, "speeds_rpm", _speed_list(self.speeds_rpm))
        check_positive("rated_speed_rpm", self.rated_speed_rpm)
        for name, least in (("n_grid", 2), ("n_candidates", 1), ("n_refine", 3), ("n_zoom", 1)):
            check_int(f"peak.{name}", getattr(self.peak, name), minimum=least)
        check_positive("duration_s", self.duration_s)
        check_choice("method", self.method, METHODS)
        object.__setattr__(self, "replicate", check_groups("replicate", self.replicate, LEVELS))
        object.__setattr__(self, "shared", check_groups("shared", self.shared,
                                                        tuple(SHARE_GROUPS)))
        check_int("ramps", self.ramps, minimum=0)
        if self.ramps > self.n_replications:
            raise ValueError(f"ramps = {self.ramps} is not allowed: at most n_replications "
                             f"= {self.n_replications}")
        a, b = self.ramp_rpm or self.speed_range_rpm
        if not (0 < a < b):
            raise ValueError(f"ramp_rpm = {self.ramp_rpm} is not allowed: need 0 < start < end")
        object.__setattr__(self, "ramp_rpm", (float(a), float(b)))
        check_positive("ramp_s", self.ramp_s)
        check_positive("ramp_segment_s", self.ramp_segment_s)
        check_record_lengths(self.duration_s, (*self.speed_range_rpm, *self.speeds_rpm),
                             self.sensors.daq.sample_rate_hz,
                             (*self.ramp_rpm, self.ramp_s) if self.ramps else None,
                             ramp_field="ramp_s")
        if "tool_x" not in self.sensors.probe_channels:
            raise ValueError(f"sensors.targets = {list(self.sensors.targets)} is not allowed: "
                             "validation measures the tool tip, so 'tool' must be a target")
        check_choice("ramp_channel", self.ramp_channel, self.sensors.probe_channels)
        for name in ("confidence", "alpha", "power"):
            check_range(name, getattr(self, name), 0.0, 1.0, inclusive=False)
        check_int("n_boot", self.n_boot, minimum=100)
        if self.calibration_u is not None:
            check_range("calibration_u", self.calibration_u, 0.0, 1.0)
        check_int("band_samples", self.band_samples, minimum=2)
        check_int("campbell_speeds", self.campbell_speeds, minimum=2)

    @property
    def delta_lim_m(self) -> float:
        """δ_lim in metres."""
        return self.delta_lim_um * 1e-6

    @property
    def u_calibration(self) -> float:
        """Relative calibration uncertainty of a measured amplitude."""
        return self.sensors.probe.gain_error_sd if self.calibration_u is None \
            else float(self.calibration_u)

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], *, sensors: SensorSet | None = None
                  ) -> ValidationOptions:
        """From a ``[validation]`` table (``peak`` a sub-table of :class:`PeakOptions`; the
        sensors come from the rig's config)."""
        names = {f.name for f in dataclasses.fields(cls)} - {"sensors"}
        check_keys("validation", data, names)
        kw = {k: tuple(v) if isinstance(v, list) else v for k, v in data.items()}
        if "peak" in kw:
            pk = dict(kw["peak"])
            check_keys("validation.peak", pk, {f.name for f in dataclasses.fields(PeakOptions)})
            kw["peak"] = PeakOptions(**pk)
        return cls(**kw, **({} if sensors is None else {"sensors": sensors}))
