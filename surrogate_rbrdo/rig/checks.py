"""Quality checks of measured data: every problem names the file (or record) and the field.

>>> import numpy as np
>>> from surrogate_rbrdo.rig.records import ChannelSpec, Record, SensorLocation
>>> ch = ChannelSpec("front_x", "displacement", "m", SensorLocation("front", "x"))
>>> rec = Record("r", "steady", 1000.0, (ch,), np.array([[0.0, np.nan, 1.0]]), speed_rpm=60.0)
>>> check_record(rec, source="run07.csv")
Traceback (most recent call last):
...
surrogate_rbrdo.rig.records.RecordError: run07.csv: channel 'front_x': NaN/inf sample at index 1
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from surrogate_rbrdo.rig.demod import keyphasor_edges
from surrogate_rbrdo.rig.profile import SpeedProfile
from surrogate_rbrdo.rig.records import Record, RecordError


def check_record(record: Record, *, source: str | None = None,
                 require: Sequence[str] = (), min_duration_s: float = 0.0,
                 min_revolutions: int = 0, speed_tolerance: float = 0.01,
                 max_clipped_fraction: float = 0.0, flat_top_run: int = 4,
                 flat_top_ratio: float = 4.0) -> Record:
    """Raise :class:`RecordError` on bad data, else return ``record`` unchanged.

    Parameters
    ----------
    source : str
        What to name in errors (the file); default the record id.
    require : channel names that must be present.
    min_duration_s : the record must be at least this long.
    min_revolutions : rotating records need this many keyphasor revolutions.
    speed_tolerance : relative disagreement allowed between the nominal speed and the
        keyphasor's: ``speed_rpm`` against the mean keyphasor speed; a ``speed_profile``
        against the revolutions the keyphasor counts, block by block (the profile's time
        average over each block, so a run-up is compared with what it really turned).
    max_clipped_fraction : fraction of samples allowed at the converter's limits.
    flat_top_run, flat_top_ratio : for float data without known limits, clipping is a run of
        at least ``flat_top_run`` equal samples at the channel's extreme value *and* that value
        held ``flat_top_ratio`` times as often as the nearest level inside — a clipped signal
        piles up at its limit, a quantised one (few decimals, an ADC's LSB) only lingers there
        as it does at any other level near the peak (an arcsine distribution: ratio ≈ 1.4).
    """
    src = source or f"record {record.id!r}"
    for name in require:
        if name not in record.channel_names:
            raise RecordError(src, f"channel {name!r}",
                              f"missing; channels are {list(record.channel_names)}")
    if record.duration_s < min_duration_s:
        raise RecordError(src, "duration", f"{record.duration_s:.6g} s is shorter than the "
                                           f"{min_duration_s:.6g} s needed")
    for c, spec in enumerate(record.channels):
        _check_channel(record.data[c], spec, src, max_clipped_fraction, flat_top_run,
                       flat_top_ratio)
    if record.kind != "impact" and ("keyphasor" in record.channel_names
                                    or "keyphasor" in record.events):
        _check_speed(record, src, min_revolutions, speed_tolerance)
    return record


def _check_channel(x: np.ndarray, spec, src: str, max_frac: float, run: int,
                   ratio: float) -> None:
    where = f"channel {spec.name!r}"
    if np.issubdtype(x.dtype, np.floating):
        bad = ~np.isfinite(x)
        if bad.any():
            raise RecordError(src, where, f"NaN/inf sample at index {int(np.argmax(bad))}")
    if spec.quantity == "keyphasor":
        return
    cal = spec.calibration
    if cal.counts_min is not None:
        at = (x <= cal.counts_min) | (x >= cal.counts_max)
        frac = float(np.mean(at))
        if frac > max_frac:
            raise RecordError(src, where, f"clipped: {frac:.2%} of the samples at the "
                                          f"converter's limits ({cal.counts_min}, "
                                          f"{cal.counts_max})")
        return
    if x.size <= run or not np.ptp(x) > 0:
        return
    levels, counts = np.unique(x, return_counts=True)
    for ext, n_ext, n_next in ((levels[-1], counts[-1], counts[-2]),
                               (levels[0], counts[0], counts[1])):
        eq = np.concatenate([[0], (x == ext).astype(np.int8), [0]])
        d = np.diff(eq)
        longest = int(np.max(np.nonzero(d == -1)[0] - np.nonzero(d == 1)[0]))
        if longest >= run and n_ext >= ratio * n_next:
            raise RecordError(src, where, f"clipped: {longest} consecutive samples flat at "
                                          f"its extreme {ext:.6g} ({n_ext} samples there, "
                                          f"{n_next} at the next level)")


def _check_events(record: Record, src: str, tol: float) -> None:
    """Counter timestamps must lie inside the record and, with a sampled keyphasor beside
    them, turn at the same speed (else the sample rate is wrong)."""
    e = record.events["keyphasor"]
    dt = 1.0 / record.sample_rate_hz
    if e.size and (e[0] < -dt or e[-1] > record.duration_s + dt):
        raise RecordError(src, "sample_rate_hz", f"= {record.sample_rate_hz:.6g} Hz makes the "
                                                 f"record {record.duration_s:.6g} s long, but "
                                                 f"keyphasor events run from {e[0]:.6g} to "
                                                 f"{e[-1]:.6g} s")
    if "keyphasor" not in record.channel_names or e.size < 2:
        return
    s = keyphasor_edges(record, source=src, events=False)
    if s.size < 3:
        return
    # the sampled edges against the nearest timestamps: on one time axis the slope is 1
    near = e[np.clip(np.searchsorted(e, s), 1, e.size - 1) - 1]
    near = np.where(np.abs(e[np.clip(np.searchsorted(e, s), 0, e.size - 1)] - s)
                    < np.abs(near - s), e[np.clip(np.searchsorted(e, s), 0, e.size - 1)], near)
    slope = np.polyfit(near, s, 1)[0] if np.ptp(near) > 0 else np.inf
    if abs(slope - 1) > tol:
        raise RecordError(src, "sample_rate_hz", f"= {record.sample_rate_hz:.6g} Hz: the "
                                                 f"sampled keyphasor's edges run {slope:.6g} "
                                                 "times as fast as its counter timestamps")


def _check_speed(record: Record, src: str, min_revs: int, tol: float) -> None:
    if "keyphasor" in record.events:
        _check_events(record, src, tol)
    edges = keyphasor_edges(record, source=src)
    n_rev = max(edges.size - 1, 0)
    if n_rev < max(min_revs, 1):
        raise RecordError(src, "duration", f"{n_rev} keyphasor revolutions; at least "
                                           f"{max(min_revs, 1)} needed")
    if record.speed_profile is None:
        if not np.isfinite(record.speed_rpm):
            raise RecordError(src, "speed_rpm", f"missing: a {record.kind} record needs its "
                                                "nominal speed (or a speed_profile)")
        kp_rpm = 60.0 * n_rev / (edges[-1] - edges[0])
        if abs(kp_rpm / record.speed_rpm - 1) > tol:
            raise RecordError(src, "speed_rpm", f"= {record.speed_rpm:.6g} rpm disagrees with "
                                                f"the keyphasor ({kp_rpm:.6g} rpm) by more "
                                                f"than {tol:.1%}: wrong speed or wrong "
                                                "sample_rate_hz?")
        return
    prof = SpeedProfile(tuple(record.speed_profile[0]), tuple(record.speed_profile[1]))
    # blocks of at least 3 revolutions, at most 10 blocks
    step = max(3, n_rev // 10)
    idx = np.unique(np.r_[np.arange(0, n_rev, step), n_rev])
    if idx.size > 2 and idx[-1] - idx[-2] < step:
        idx = np.delete(idx, -2)
    for a, b in zip(idx[:-1], idx[1:], strict=True):
        ta, tb = edges[a], edges[b]
        kp_rpm = 60.0 * (b - a) / (tb - ta)
        nominal = prof.mean_rpm(ta, tb)
        if not nominal > 0 or abs(kp_rpm / nominal - 1) > tol:
            raise RecordError(src, "speed_profile", f"averages {nominal:.6g} rpm over "
                                                    f"{ta:.4g}–{tb:.4g} s but the keyphasor "
                                                    f"turned {kp_rpm:.6g} rpm there (more than "
                                                    f"{tol:.1%} apart): wrong profile or wrong "
                                                    "sample_rate_hz?")
