"""The measured-data format: one record = channels of samples, their calibration and provenance.

A :class:`Record` is what a test rig writes and what every consumer (1x demodulation, FRFs,
identification, the discrepancy workflow) reads — whether it came from the virtual rig or from a
user's own measurement (``rig.importers``). Samples are stored as integer ADC counts with a
linear calibration ``value = counts * scale + offset`` (SI units), or as floats with
``scale = 1, offset = 0`` when a file holds physical values already. The format on disk
(``rig.store``) and every field are documented in ``docs/measured-data.md``.

>>> import numpy as np
>>> ch = ChannelSpec("front_x", "displacement", "m", SensorLocation("front", "x", 100.0),
...                  Calibration(scale=1e-8, offset=0.0, counts_min=-32768, counts_max=32767))
>>> rec = Record("r0", "steady", 10_000.0, (ch,), np.array([[0, 100, -100]], dtype=np.int16),
...              speed_rpm=6000.0)
>>> rec.values("front_x").tolist()
[0.0, 1e-06, -1e-06]
>>> rec.n_samples, rec.duration_s
(3, 0.0003)
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_finite, check_positive

FORMAT_NAME = "surrogate_rbrdo.rig.record"
FORMAT_VERSION = 1
#: what a channel measures, and the SI unit its calibrated values are in
QUANTITIES = {"displacement": "m", "force": "N", "keyphasor": "V", "acceleration": "m/s^2",
              "velocity": "m/s", "voltage": "V", "temperature": "K"}
#: test kinds: constant speed, speed ramps, impact (hammer) tests, and a steady record taken
#: during a thermal soak (a speed held from a cold start, ``rig.thermal``)
KINDS = ("steady", "runup", "rundown", "impact", "soak")
DIRECTIONS = ("x", "y", "")


class RecordError(ValueError):
    """Bad measured data: names the source (file or record id), the field and what is wrong."""

    def __init__(self, source: str, field_name: str, message: str) -> None:
        self.source, self.field = source, field_name
        super().__init__(f"{source}: {field_name}: {message}")


@dataclass(frozen=True)
class SensorLocation:
    """Where a sensor looks: a named target (``front``, ``rear``, ``tool``, a bearing or node
    name), its direction (``x``, ``y`` or ``""`` for scalar channels) and its axial position
    along the rotor axis in the model's coordinates (mm, from the left end; NaN if unknown)."""

    target: str
    direction: str = ""
    position_mm: float = math.nan

    def __post_init__(self) -> None:
        check_choice("location.direction", self.direction, DIRECTIONS)
        if not isinstance(self.target, str):
            raise ValueError(f"location.target = {self.target!r} is not allowed: must be a str")


@dataclass(frozen=True)
class Calibration:
    """Linear calibration ``value = counts * scale + offset`` in the channel's SI unit.

    ``counts_min``/``counts_max`` are the converter's limits (samples there are clipped);
    ``None`` for float data without known limits.
    """

    scale: float = 1.0
    offset: float = 0.0
    counts_min: int | None = None
    counts_max: int | None = None

    def __post_init__(self) -> None:
        check_finite("calibration.scale", self.scale)
        if self.scale == 0.0:
            raise ValueError("calibration.scale = 0.0 is not allowed: must be non-zero")
        check_finite("calibration.offset", self.offset)
        if (self.counts_min is None) != (self.counts_max is None) or (
                self.counts_min is not None and not self.counts_min < self.counts_max):
            raise ValueError(
                f"calibration.counts_min/max = ({self.counts_min}, {self.counts_max}) is not "
                "allowed: give both (min < max) or neither")


@dataclass(frozen=True)
class ChannelSpec:
    """One channel: name, quantity, unit, location, calibration and its sampling delay.

    ``delay_s`` is the known delay of this channel's samples behind the record's time axis
    (multiplexed converters sample channels one after the other); readers correct for it.
    ``info`` holds free sensor metadata (model, serial, nominal sensitivity ...).
    """

    name: str
    quantity: str
    unit: str
    location: SensorLocation
    calibration: Calibration = Calibration()
    delay_s: float = 0.0
    info: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not (isinstance(self.name, str) and self.name):
            raise ValueError(f"channel.name = {self.name!r} is not allowed: a non-empty str")
        check_choice(f"channel {self.name!r}.quantity", self.quantity, QUANTITIES)
        if self.unit != QUANTITIES[self.quantity]:
            raise ValueError(
                f"channel {self.name!r}.unit = {self.unit!r} is not allowed: a "
                f"{self.quantity} channel is in {QUANTITIES[self.quantity]!r} (SI)")
        check_finite(f"channel {self.name!r}.delay_s", self.delay_s)


@dataclass(frozen=True, eq=False)
class Record:
    """One measurement: ``data[c]`` holds the samples of ``channels[c]`` at ``sample_rate_hz``.

    Parameters
    ----------
    id : str
        Unique within a dataset.
    kind : str
        ``steady`` (constant speed), ``runup``/``rundown`` (speed ramp), ``impact`` or
        ``soak`` (constant speed during a thermal soak, with a temperature channel).
    sample_rate_hz : float
    channels : tuple of ChannelSpec
    data : ndarray (n_channels, n_samples)
        Integer counts (int16/int32) or floats; calibrated by each channel's calibration.
    speed_rpm : float
        Nominal constant speed (steady, soak), 0 for impact tests, NaN for ramps.
    speed_profile : ndarray (2, P), optional
        ``[time_s, speed_rpm]`` breakpoints of a ramp (linear in between).
    provenance : mapping
        JSON-able: source, truth effects and parameters, seeds, sensor draws ...
    events : mapping of str to ndarray, optional
        Event channels: increasing times (s, on the record's time axis) of discrete events,
        e.g. ``events["keyphasor"]``, the leading edges of the once-per-revolution pulse
        timestamped by a counter (readers prefer it to the sampled keyphasor channel).
    """

    id: str
    kind: str
    sample_rate_hz: float
    channels: tuple[ChannelSpec, ...]
    data: np.ndarray
    speed_rpm: float = math.nan
    speed_profile: np.ndarray | None = None
    provenance: Mapping[str, Any] = field(default_factory=dict)
    events: Mapping[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "channels", tuple(self.channels))
        object.__setattr__(self, "events", _check_events(self.id, self.events))
        check_choice(f"record {self.id!r}.kind", self.kind, KINDS)
        check_positive(f"record {self.id!r}.sample_rate_hz", self.sample_rate_hz)
        data = np.asarray(self.data)
        if data.ndim != 2 or data.shape[0] != len(self.channels):
            raise ValueError(
                f"record {self.id!r}.data has shape {data.shape}: must be (n_channels = "
                f"{len(self.channels)}, n_samples)")
        if not (np.issubdtype(data.dtype, np.integer) or np.issubdtype(data.dtype, np.floating)):
            raise ValueError(f"record {self.id!r}.data dtype {data.dtype} is not allowed: "
                             "integer counts or floats")
        names = [c.name for c in self.channels]
        if len(set(names)) != len(names):
            raise ValueError(f"record {self.id!r}.channels = {names}: names must be unique")
        if self.speed_profile is not None:
            prof = np.asarray(self.speed_profile, dtype=float)
            if prof.ndim != 2 or prof.shape[0] != 2 or prof.shape[1] < 2 or np.any(
                    np.diff(prof[0]) <= 0) or not np.all(np.isfinite(prof)):
                raise ValueError(f"record {self.id!r}.speed_profile must be (2, P >= 2) finite "
                                 "[time_s, speed_rpm] with increasing times")
            object.__setattr__(self, "speed_profile", prof)
        object.__setattr__(self, "data", data)
        try:
            prov = json.loads(json.dumps(dict(self.provenance), default=_plain))
        except (TypeError, ValueError) as exc:
            raise ValueError(f"record {self.id!r}.provenance is not JSON-able: {exc}") from None
        object.__setattr__(self, "provenance", prov)

    # ------------------------------------------------------------------ access
    @property
    def n_samples(self) -> int:
        return int(self.data.shape[1])

    @property
    def duration_s(self) -> float:
        return self.n_samples / self.sample_rate_hz

    @property
    def time_s(self) -> np.ndarray:
        """Sample times (s) of the record's time axis (before each channel's delay)."""
        return np.arange(self.n_samples) / self.sample_rate_hz

    @property
    def channel_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.channels)

    def index(self, name: str) -> int:
        try:
            return self.channel_names.index(name)
        except ValueError:
            raise RecordError(f"record {self.id!r}", f"channel {name!r}",
                              f"missing; channels are {list(self.channel_names)}") from None

    def channel(self, name: str) -> ChannelSpec:
        return self.channels[self.index(name)]

    def values(self, name: str) -> np.ndarray:
        """Calibrated samples of channel ``name`` (float64, SI unit of the channel)."""
        c = self.index(name)
        cal = self.channels[c].calibration
        return self.data[c].astype(float) * cal.scale + cal.offset

    def find(self, quantity: str, target: str | None = None, direction: str | None = None
             ) -> tuple[ChannelSpec, ...]:
        """Channels of a quantity, optionally at a target and in a direction."""
        return tuple(c for c in self.channels if c.quantity == quantity
                     and (target is None or c.location.target == target)
                     and (direction is None or c.location.direction == direction))

    def speed_at(self, t_s: np.ndarray) -> np.ndarray:
        """Nominal speed (rpm) at times ``t_s``: the profile, else the constant speed."""
        t = np.asarray(t_s, dtype=float)
        if self.speed_profile is not None:
            return np.interp(t, self.speed_profile[0], self.speed_profile[1])
        return np.full(t.shape, self.speed_rpm)

    def metadata(self) -> dict[str, Any]:
        """Everything but the samples, as plain JSON-able data (``store`` writes it)."""
        return {
            "format": FORMAT_NAME, "version": FORMAT_VERSION, "id": self.id, "kind": self.kind,
            "sample_rate_hz": self.sample_rate_hz, "n_samples": self.n_samples,
            "dtype": str(self.data.dtype),
            "speed_rpm": None if math.isnan(self.speed_rpm) else self.speed_rpm,
            "speed_profile": None if self.speed_profile is None
            else self.speed_profile.tolist(),
            "channels": [channel_to_dict(c) for c in self.channels],
            "provenance": dict(self.provenance),
            "events": {k: v.tolist() for k, v in self.events.items()},
        }


def _plain(x: Any) -> Any:
    """JSON for numpy scalars and arrays in provenance (else a TypeError naming the type)."""
    if isinstance(x, (np.generic, np.ndarray)):
        return x.tolist()
    raise TypeError(f"{type(x).__name__} {x!r} is not JSON-able")


def _check_events(rid: str, events: Mapping[str, Any]) -> dict[str, np.ndarray]:
    if not isinstance(events, Mapping):
        raise ValueError(f"record {rid!r}.events = {events!r} is not allowed: a mapping of "
                         "event names to increasing times (s)")
    out = {}
    for name, times in events.items():
        try:
            t = np.asarray(times, dtype=float)
        except (TypeError, ValueError):
            t = np.array([np.nan])
        if not isinstance(name, str) or t.ndim != 1 or not np.all(np.isfinite(t)) or np.any(
                np.diff(t) <= 0):
            raise ValueError(f"record {rid!r}.events[{name!r}] is not allowed: a list of "
                             "finite, increasing times (s)")
        out[name] = t
    return out


def channel_to_dict(c: ChannelSpec) -> dict[str, Any]:
    loc = c.location
    return {"name": c.name, "quantity": c.quantity, "unit": c.unit,
            "location": {"target": loc.target, "direction": loc.direction,
                         "position_mm": None if math.isnan(loc.position_mm)
                         else loc.position_mm},
            "calibration": {"scale": c.calibration.scale, "offset": c.calibration.offset,
                            "counts_min": c.calibration.counts_min,
                            "counts_max": c.calibration.counts_max},
            "delay_s": c.delay_s, "info": dict(c.info)}


def channel_from_dict(d: Mapping[str, Any], source: str, index: int = 0) -> ChannelSpec:
    """Inverse of :func:`channel_to_dict`; a missing or bad field raises :class:`RecordError`."""
    if not isinstance(d, Mapping):
        raise RecordError(source, f"channels[{index}]", f"= {d!r} is not allowed: an object "
                                                        "with name, quantity, location ...")
    name = d.get("name")
    if not isinstance(name, str) or not name:
        raise RecordError(source, f"channels[{index}].name", f"= {name!r}: missing or not a "
                                                             "non-empty string")
    where = f"channels[{name!r}]"
    try:
        loc = d.get("location") or {}
        cal = d.get("calibration") or {}
        for part, val in (("location", loc), ("calibration", cal), ("info", d.get("info") or {})):
            if not isinstance(val, Mapping):
                raise ValueError(f"{part} = {val!r} is not allowed: an object")
        pos = loc.get("position_mm")
        return ChannelSpec(
            name=name, quantity=d["quantity"],
            unit=d.get("unit", QUANTITIES.get(d["quantity"], "?")),
            location=SensorLocation(loc.get("target", ""), loc.get("direction", ""),
                                    math.nan if pos is None else _number(pos, "position_mm")),
            calibration=Calibration(_number(cal.get("scale", 1.0), "calibration.scale"),
                                    _number(cal.get("offset", 0.0), "calibration.offset"),
                                    cal.get("counts_min"), cal.get("counts_max")),
            delay_s=_number(d.get("delay_s", 0.0), "delay_s"), info=dict(d.get("info") or {}))
    except KeyError as exc:
        raise RecordError(source, f"{where}.{exc.args[0]}", "missing") from None
    except (ValueError, TypeError) as exc:
        raise RecordError(source, where, str(exc)) from None


def _number(x: Any, name: str) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} = {x!r} is not allowed: a number")
    return float(x)


def record_from_metadata(meta: Mapping[str, Any], data: np.ndarray, source: str) -> Record:
    """Build a :class:`Record` from :meth:`Record.metadata`-shaped data and its samples.

    Every missing or malformed field raises :class:`RecordError` naming ``source`` and the field.
    """
    if not isinstance(meta, Mapping):
        raise RecordError(source, "metadata", f"is a {type(meta).__name__}: must be an object "
                                              "with the record's fields (id, kind, ...)")
    for key in ("id", "kind", "channels"):
        if meta.get(key) is None:
            raise RecordError(source, key, "missing")
    if not isinstance(meta["channels"], list):
        raise RecordError(source, "channels", f"is a {type(meta['channels']).__name__}: must "
                                              "be a list of channel objects")
    fs = meta.get("sample_rate_hz")
    if fs is None:
        raise RecordError(source, "sample_rate_hz", "missing: the sample rate must be given")
    if isinstance(fs, bool) or not isinstance(fs, (int, float)) or not math.isfinite(fs) \
            or fs <= 0:
        raise RecordError(source, "sample_rate_hz", f"= {fs!r} is not allowed: a number > 0")
    channels = tuple(channel_from_dict(c, source, i) for i, c in enumerate(meta["channels"]))
    sp = meta.get("speed_rpm")
    try:
        speed = math.nan if sp is None else _number(sp, "speed_rpm")
        prof = meta.get("speed_profile")
        if prof is not None:
            try:
                prof = np.asarray(prof, dtype=float)
            except (TypeError, ValueError):
                raise ValueError(f"speed_profile = {prof!r} is not allowed: [[t_s...], "
                                 "[rpm...]] of equal lengths") from None
        return Record(
            id=str(meta["id"]), kind=meta["kind"], sample_rate_hz=float(fs), channels=channels,
            data=data, speed_rpm=speed, speed_profile=prof,
            provenance=meta.get("provenance") or {}, events=meta.get("events") or {})
    except (ValueError, TypeError) as exc:
        raise RecordError(source, "record", str(exc)) from None
