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
from surrogate_rbrdo.rig.records import Record, RecordError


def check_record(record: Record, *, source: str | None = None,
                 require: Sequence[str] = (), min_duration_s: float = 0.0,
                 min_revolutions: int = 0, speed_tolerance: float = 0.01,
                 max_clipped_fraction: float = 0.0, flat_top_run: int = 4) -> Record:
    """Raise :class:`RecordError` on bad data, else return ``record`` unchanged.

    Parameters
    ----------
    source : str
        What to name in errors (the file); default the record id.
    require : channel names that must be present.
    min_duration_s : the record must be at least this long.
    min_revolutions : rotating records need this many keyphasor revolutions.
    speed_tolerance : relative disagreement allowed between the nominal speed (``speed_rpm``
        or the profile's mean) and the keyphasor's.
    max_clipped_fraction : fraction of samples allowed at the converter's limits.
    flat_top_run : for float data without known limits, this many equal consecutive samples
        at the channel's extreme count as clipping.
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
        _check_channel(record.data[c], spec, src, max_clipped_fraction, flat_top_run)
    if record.kind != "impact" and "keyphasor" in record.channel_names:
        _check_speed(record, src, min_revolutions, speed_tolerance)
    return record


def _check_channel(x: np.ndarray, spec, src: str, max_frac: float, run: int) -> None:
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
    elif x.size > run:
        for ext in (x.max(), x.min()):
            eq = np.concatenate([[0], (x == ext).astype(np.int8), [0]])
            d = np.diff(eq)
            longest = int(np.max(np.nonzero(d == -1)[0] - np.nonzero(d == 1)[0]))
            if longest >= run and np.ptp(x) > 0:
                raise RecordError(src, where, f"clipped: {longest} consecutive samples flat at "
                                              f"its extreme {ext:.6g}")


def _check_speed(record: Record, src: str, min_revs: int, tol: float) -> None:
    edges = keyphasor_edges(record)
    n_rev = max(edges.size - 1, 0)
    if n_rev < max(min_revs, 1):
        raise RecordError(src, "duration", f"{n_rev} keyphasor revolutions; at least "
                                           f"{max(min_revs, 1)} needed")
    kp_rpm = 60.0 * n_rev / (edges[-1] - edges[0])
    if record.speed_profile is not None:
        nominal = float(np.mean(record.speed_at(edges)))
        field = "speed_profile"
    else:
        nominal, field = record.speed_rpm, "speed_rpm"
    if not np.isfinite(nominal) or abs(kp_rpm / nominal - 1) > tol:
        raise RecordError(src, field, f"= {nominal:.6g} rpm disagrees with the keyphasor "
                                      f"({kp_rpm:.6g} rpm) by more than {tol:.1%}: wrong "
                                      "speed or wrong sample_rate_hz?")
