"""Measuring one replication on the rig: full-range response, peak over the range, rated speed,
and critical speeds from a run-up and a run-down.

Every quantity is what a test engineer gets from the probes, never the truth's own numbers:

* **steady-state 1x phasors** of all probes at a speed list (Fig. 8), demodulated against the
  keyphasor — by the rig's fast path (:func:`rig.phasors.sample_phasors`) or by simulating
  and demodulating time records (``method = "records"``). The fast path is exact in
  distribution for the rig's linear truth (``docs/rig.md``, tested there), and ~300x cheaper.
  The tool-tip amplitude (orbit semi-major axis of ``tool_x``/``tool_y``, the model's ``y``)
  does not depend on the keyphasor's phase error — it turns all channels of a record by the
  same angle and the noise is circular — so leaving that error out (a counter-timed
  keyphasor) changes no amplitude;
* **the peak over the range** (the study's ``y``) by a dwell search: steady-state records on
  the geometric grid of :class:`~surrogate_rbrdo.spindle.harmonic.PeakOptions`, then zooms
  around the highest maxima — the very search the model's ``y`` uses
  (:func:`~surrogate_rbrdo.spindle.harmonic.peak_search`), run on measured amplitudes;
* **the rated-speed amplitude** from its own record;
* **critical speeds**: peaks of the 1x amplitude in a run-up and a run-down
  (:func:`rig.demod.critical_speeds_from_ramp`). A run-up's peak lies above the critical speed
  and a run-down's below, so the estimate is their mean and half their distance bounds its
  sweep-rate error (tested in ``tests/rig/test_demod.py``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from surrogate_rbrdo.rig.demod import critical_speeds_from_ramp, demodulate, track_1x
from surrogate_rbrdo.rig.integrate import SpeedProfile
from surrogate_rbrdo.rig.phasors import sample_phasors
from surrogate_rbrdo.rig.sensors import Installation
from surrogate_rbrdo.rig.simulate import (
    RAMP_OPTIONS,
    ProbeLayout,
    runup_record,
    steady_records,
)
from surrogate_rbrdo.rig.truth import TruthState
from surrogate_rbrdo.spindle.harmonic import orbit_amplitude, peak_search
from surrogate_rbrdo.validation.options import ValidationOptions


@dataclass(frozen=True)
class ReplicaMeasurement:
    """What one replication of one design measured (amplitudes in m, speeds in rpm)."""

    phasors: np.ndarray          # (S, n_probe) complex, at options.speeds_rpm
    curve: np.ndarray            # (S,) tool-tip orbit amplitude
    peak: float                  # peak over the range (the study's y)
    peak_speed_rpm: float
    rated: float                 # amplitude at the rated speed
    n_records: int               # steady-state records taken


@dataclass(frozen=True)
class CriticalSpeedMeasurement:
    """A 1x resonance seen in a replication's ramps (NaN where a ramp did not show it)."""

    replica: int
    speed_rpm: float             # mean of the run-up and run-down peaks (or the one seen)
    runup_rpm: float
    rundown_rpm: float
    amplification_factor: float

    @property
    def both_ramps(self) -> bool:
        """Seen in the run-up and the run-down (a peak seen in one ramp only is usually a
        resonance at a ramp's end, not developed: less reliable)."""
        return bool(np.isfinite(self.runup_rpm) and np.isfinite(self.rundown_rpm))


class _Meter:
    """Steady-state 1x phasors of one truth state, counted; any speeds, in any order."""

    def __init__(self, state: TruthState, options: ValidationOptions, inst: Installation,
                 rng: np.random.Generator) -> None:
        self.model, self.theta = state.model(), state.theta
        self.o, self.inst, self.rng = options, inst, rng
        ch = options.sensors.probe_channels
        self.ix, self.iy = ch.index("tool_x"), ch.index("tool_y")
        self.n_records = 0

    def phasors(self, speeds_rpm: np.ndarray) -> np.ndarray:
        """``(S, n_probe)`` measured phasors at strictly increasing speeds."""
        sp = np.asarray(speeds_rpm, float)
        self.n_records += sp.size
        o = self.o
        if o.method == "phasors":
            return sample_phasors(self.model, self.theta, sp, o.sensors, self.inst, self.rng,
                                  duration_s=o.duration_s,
                                  keyphasor_error=o.keyphasor_error)[0]
        recs = steady_records(self.model, self.theta, sp, o.sensors, self.inst,
                              list(self.rng.spawn(sp.size)), duration_s=o.duration_s,
                              ids=[f"s{i}" for i in range(sp.size)], provenance=[{}] * sp.size)
        return np.array([demodulate(r, o.sensors.probe_channels).X[:, 0] for r in recs])

    def tool(self, X: np.ndarray) -> np.ndarray:
        return orbit_amplitude(X[..., self.ix], X[..., self.iy])

    def amplitude(self, speeds_rpm: np.ndarray, _th: np.ndarray) -> np.ndarray:
        """Tool-tip amplitude at any speeds (the ``amplitude(speeds, θ)`` of
        :func:`peak_search`, one row): each distinct speed is one record."""
        sp = np.asarray(speeds_rpm, float)
        u, inv = np.unique(sp.ravel(), return_inverse=True)
        return self.tool(self.phasors(u))[inv].reshape(1, -1)


def measure_replica(state: TruthState, options: ValidationOptions, inst: Installation,
                    rng: np.random.Generator) -> ReplicaMeasurement:
    """Full-range phasors, peak over the range and rated-speed amplitude of one replication."""
    m = _Meter(state, options, inst, rng)
    X = m.phasors(np.asarray(options.speeds_rpm))
    lo, hi = options.speed_range_rpm
    pk, ps = peak_search(m.amplitude, np.zeros((1, 1)), lo, hi, options.peak)
    rated = m.tool(m.phasors(np.array([options.rated_speed_rpm])))[0]
    return ReplicaMeasurement(X, m.tool(X), float(pk[0]), float(ps[0]), float(rated),
                              m.n_records)


def probe_positions(state: TruthState, options: ValidationOptions) -> dict[str, float]:
    """Axial position (mm) of each probe channel on a replication's rotor."""
    pos = ProbeLayout.of(state.model()).positions_mm
    return {c: pos[c.split("_")[0]] for c in options.sensors.probe_channels}


def measure_criticals(state: TruthState, replica: int, options: ValidationOptions,
                      inst: Installation, rng: np.random.Generator
                      ) -> tuple[CriticalSpeedMeasurement, ...]:
    """Critical speeds of one replication from a run-up and a run-down (``options.ramp_*``)."""
    model = state.model()
    a, b = options.ramp_rpm
    integ = replace(RAMP_OPTIONS, segment_s=options.ramp_segment_s)
    found = []
    for k, (s0, s1) in enumerate(((a, b), (b, a))):
        rec = runup_record(model, state.theta, SpeedProfile.ramp(s0, s1, options.ramp_s),
                           options.sensors, inst, rng.spawn(1)[0], rid=f"ramp{k}",
                           provenance={}, options=integ)
        found.append(critical_speeds_from_ramp(track_1x(rec), options.ramp_channel))
    return pair_ramp_peaks(found[0], found[1], replica)


def pair_ramp_peaks(up, down, replica: int, *, tolerance: float = 0.05
                    ) -> tuple[CriticalSpeedMeasurement, ...]:
    """Pair each run-up peak with the nearest run-down peak within ``tolerance`` (relative).

    >>> from surrogate_rbrdo.rig.demod import CriticalSpeed
    >>> u = (CriticalSpeed(10100.0, 1e-5, 170.0, 40.0),)
    >>> d = (CriticalSpeed(9900.0, 1e-5, 170.0, 44.0), CriticalSpeed(20000.0, 1e-6, 90.0, 9.0))
    >>> [(c.speed_rpm, c.runup_rpm, c.rundown_rpm) for c in pair_ramp_peaks(u, d, 0)]
    [(10000.0, 10100.0, 9900.0), (20000.0, nan, 20000.0)]
    """
    out, used = [], set()
    for cu in up:
        dist = [abs(cd.speed_rpm - cu.speed_rpm) if j not in used else np.inf
                for j, cd in enumerate(down)]
        j = int(np.argmin(dist)) if dist else -1
        if j >= 0 and dist[j] <= tolerance * cu.speed_rpm:
            used.add(j)
            cd = down[j]
            out.append(CriticalSpeedMeasurement(
                replica, 0.5 * (cu.speed_rpm + cd.speed_rpm), cu.speed_rpm, cd.speed_rpm,
                0.5 * (cu.amplification_factor + cd.amplification_factor)))
        else:
            out.append(CriticalSpeedMeasurement(replica, cu.speed_rpm, cu.speed_rpm, np.nan,
                                                cu.amplification_factor))
    out += [CriticalSpeedMeasurement(replica, cd.speed_rpm, np.nan, cd.speed_rpm,
                                     cd.amplification_factor)
            for j, cd in enumerate(down) if j not in used]
    return tuple(sorted(out, key=lambda c: c.speed_rpm))
