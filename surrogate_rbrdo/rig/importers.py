"""Putting measured data into the record format: CSV + sidecar, UFF 58 (pyuff), TDMS (npTDMS).

Each reader returns a checked :class:`~surrogate_rbrdo.rig.records.Record`; problems raise
:class:`~surrogate_rbrdo.rig.records.RecordError` naming the file and the field. The sidecar
(JSON or TOML, same stem as the data file unless given) holds the record's fields other than the
samples (``docs/measured-data.md``), and optionally the record's ``events`` (e.g. keyphasor
counter timestamps) inline or as the name of a one-column text file next to it. UFF 58 and TDMS
values are converted to SI by their unit labels (:data:`UNIT_FACTORS`).

>>> import numpy as np, tempfile, json, pathlib
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> t = np.arange(2000) / 1000.0
>>> kp = np.where(np.mod(t * 10.0, 1.0) < 0.2, 5.0, 0.0)      # 600 rpm keyphasor
>>> x_um = 3.0 * np.cos(2 * np.pi * 10.0 * t)
>>> _ = (d / "run.csv").write_text("front_x,keyphasor\\n" + "\\n".join(
...     f"{a},{b}" for a, b in zip(x_um, kp)))
>>> _ = (d / "run.json").write_text(json.dumps({"id": "run", "kind": "steady",
...     "sample_rate_hz": 1000, "speed_rpm": 600, "channels": [
...     {"name": "front_x", "quantity": "displacement", "calibration": {"scale": 1e-6},
...      "location": {"target": "front", "direction": "x"}},
...     {"name": "keyphasor", "quantity": "keyphasor", "location": {"target": "shaft"}}]}))
>>> rec = read_csv(d / "run.csv")
>>> round(float(rec.values("front_x").max()) * 1e6, 6)
3.0
"""

from __future__ import annotations

import json
import tomllib
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pyuff
from nptdms import ChannelObject, TdmsFile, TdmsWriter

from surrogate_rbrdo.rig.checks import check_record
from surrogate_rbrdo.rig.records import Record, RecordError, record_from_metadata

#: UFF 58 specific data type codes (record 8/9): 1 general, 8 displacement, 11 velocity,
#: 12 acceleration, 13 excitation force
UFF_DATA_TYPE = {"displacement": 8, "velocity": 11, "acceleration": 12, "force": 13,
                 "keyphasor": 1, "voltage": 1}
#: unit labels (lower case) understood per quantity, and their factor to SI; "" means SI, and
#: "v"/"mv" on a sensor channel means raw volts, turned into SI by the sidecar's calibration
UNIT_FACTORS = {
    "displacement": {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "μm": 1e-6, "micron": 1e-6,
                     "nm": 1e-9, "in": 0.0254, "mil": 2.54e-5},
    "velocity": {"m/s": 1.0, "mm/s": 1e-3, "um/s": 1e-6, "µm/s": 1e-6, "in/s": 0.0254},
    "acceleration": {"m/s^2": 1.0, "m/s2": 1.0, "m/s²": 1.0, "mm/s^2": 1e-3,
                     "g": 9.80665},
    "force": {"n": 1.0, "kn": 1e3, "lbf": 4.4482216152605},
    "keyphasor": {},
    "voltage": {},
}
VOLTS = {"v": 1.0, "mv": 1e-3}


def unit_factor(label: str, quantity: str, src: str, where: str) -> float:
    """Factor from a file's unit ``label`` to the SI unit of ``quantity`` (1 for an empty or SI
    label, or for volts: those are calibrated by the sidecar)."""
    key = str(label or "").strip().lower()
    table = {**UNIT_FACTORS[quantity], **VOLTS, "": 1.0}
    if key not in table:
        raise RecordError(src, where, f"unit label {label!r} is not understood for a "
                                      f"{quantity} channel: one of {sorted(k for k in table if k)}"
                                      " (or give SI values with an empty label)")
    return table[key]


def read_sidecar(path: str | Path) -> dict[str, Any]:
    """Read a JSON or TOML metadata sidecar (an object with the record's fields)."""
    path = Path(path)
    if not path.is_file():
        raise RecordError(str(path), "sidecar", "missing: the metadata sidecar (JSON or TOML "
                                                "with the record's fields) was not found")
    text = path.read_text()
    try:
        meta = tomllib.loads(text) if path.suffix == ".toml" else json.loads(text)
    except (json.JSONDecodeError, tomllib.TOMLDecodeError) as exc:
        raise RecordError(str(path), "sidecar", f"not valid {path.suffix[1:]}: {exc}") from None
    if not isinstance(meta, dict):
        raise RecordError(str(path), "sidecar", f"is a JSON {type(meta).__name__}: must be an "
                                                "object with the record's fields (id, kind, "
                                                "sample_rate_hz, channels, ...)")
    channels = meta.get("channels")
    if channels is not None and not isinstance(channels, list):
        raise RecordError(str(path), "channels", f"is a {type(channels).__name__}: must be a "
                                                 "list of channel objects")
    for i, c in enumerate(channels or []):
        if not isinstance(c, dict) or not isinstance(c.get("name"), str) or not c["name"]:
            raise RecordError(str(path), f"channels[{i}].name", "missing: every channel needs "
                                                                "a name (the CSV column)")
    meta["events"] = _events(meta.get("events"), path)
    return meta


def _events(events: Any, sidecar: Path) -> dict[str, Any]:
    """Inline event times, or a file name (next to the sidecar) of one time per line."""
    if events is None:
        return {}
    if not isinstance(events, dict):
        raise RecordError(str(sidecar), "events", "must map event names to times (s) or to a "
                                                  "file of times")
    out = {}
    for name, v in events.items():
        if isinstance(v, str):
            f = sidecar.parent / v
            try:
                v = np.loadtxt(f, ndmin=1).tolist()
            except (OSError, ValueError) as exc:
                raise RecordError(str(f), f"events[{name!r}]", f"not a readable list of "
                                                               f"times: {exc}") from None
        out[name] = v
    return out


def _sidecar_for(path: Path, sidecar: str | Path | None) -> tuple[dict[str, Any], str]:
    if sidecar is None:
        for suffix in (".json", ".toml"):
            if path.with_suffix(suffix).is_file():
                sidecar = path.with_suffix(suffix)
                break
        else:
            sidecar = path.with_suffix(".json")
    return read_sidecar(sidecar), str(sidecar)


def read_csv(path: str | Path, *, sidecar: str | Path | None = None,
             check: Mapping[str, Any] | None = None) -> Record:
    """A record from a CSV file (header = channel names, optionally quoted; an optional
    ``time_s`` column) and its sidecar. ``check``: keyword arguments of
    :func:`~surrogate_rbrdo.rig.checks.check_record`."""
    path = Path(path)
    src = str(path)
    if not path.is_file():
        raise RecordError(src, "file", "does not exist")
    meta, side = _sidecar_for(path, sidecar)
    with open(path) as fh:
        header = [h.strip().strip('"').strip("'").strip() for h in
                  fh.readline().strip().split(",")]
        if not fh.readline().strip():
            raise RecordError(src, "data", "no data rows below the header")
    try:
        values = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as exc:
        raise RecordError(src, "data", f"not numeric, comma-separated values: {exc}") from None
    if values.shape[1] != len(header):
        raise RecordError(src, "header", f"{len(header)} names for {values.shape[1]} columns")
    cols = dict(zip(header, values.T, strict=True))
    fs = meta.get("sample_rate_hz")
    if "time_s" in cols:
        t = cols.pop("time_s")
        if isinstance(fs, (int, float)) and not isinstance(fs, bool) and fs > 0 and t.size > 1:
            dt = np.diff(t)
            if not np.allclose(dt, 1.0 / fs, rtol=1e-3, atol=0):
                raise RecordError(src, "sample_rate_hz",
                                  f"= {fs} disagrees with the time_s column (step "
                                  f"{np.median(dt):.6g} s = {1 / np.median(dt):.6g} Hz)")
    data = _columns(meta, cols, src, "the CSV columns")
    rec = record_from_metadata(meta, data, f"{src} [sidecar {side}]")
    return check_record(rec, source=src, **dict(check or {}))


def write_csv(record: Record, path: str | Path) -> Path:
    """Write ``record`` as CSV (calibrated SI values, ``time_s`` first) plus a JSON sidecar
    with ``scale = 1, offset = 0`` calibrations (what :func:`read_csv` reads back)."""
    path = Path(path)
    vals = np.array([record.values(n) for n in record.channel_names])
    np.savetxt(path, np.column_stack([record.time_s, vals.T]), delimiter=",",
               header=",".join(("time_s",) + record.channel_names), comments="", fmt="%.17g")
    _write_float_sidecar(record, path.with_suffix(".json"))
    return path


def _columns(meta: Mapping[str, Any], available: Mapping[str, np.ndarray], src: str,
             where: str) -> np.ndarray:
    """The sidecar's channels, in its order, from the file's ``available`` columns (all of one
    length)."""
    names = [c["name"] for c in meta.get("channels") or []]
    for n in names:
        if n not in available:
            raise RecordError(src, f"channel {n!r}", f"missing from {where} {sorted(available)}")
    lengths = {n: np.size(available[n]) for n in names}
    if len(set(lengths.values())) > 1:
        raise RecordError(src, "channels", f"have different lengths {lengths}: one record "
                                           "needs one sample count")
    return np.array([available[n] for n in names], dtype=float).reshape(len(names), -1)


def _uff_sets(path: Path, src: str) -> list[dict[str, Any]]:
    try:
        sets = pyuff.UFF(str(path)).read_sets()
    except Exception as exc:  # pyuff raises bare Exceptions on malformed files
        raise RecordError(src, "file", f"not a readable universal file: {exc}") from None
    if isinstance(sets, dict):        # pyuff returns a lone dataset unwrapped
        sets = [sets]
    return [d for d in sets if isinstance(d, dict) and d.get("type") == 58]


def read_uff58(path: str | Path, *, sidecar: str | Path | None = None,
               check: Mapping[str, Any] | None = None) -> Record:
    """A record from the type-58 time-response datasets of a universal file (pyuff): one
    channel per dataset, named by its ``id1``; the sample rate from the abscissa increment; the
    values converted to SI by the ordinate's unit label (``ordinate_axis_units_lab``)."""
    path = Path(path)
    src = str(path)
    if not path.is_file():
        raise RecordError(src, "file", "does not exist")
    meta, _ = _sidecar_for(path, sidecar)
    sets = _uff_sets(path, src)
    if not sets:
        raise RecordError(src, "datasets", "no type-58 dataset in the file")
    by_name = {str(d.get("id1", "")).strip(): d for d in sets}
    fs_all = {round(1.0 / float(d["abscissa_inc"]), 6) for d in sets
              if float(d.get("abscissa_inc") or 0) > 0}
    if len(fs_all) != 1:
        raise RecordError(src, "abscissa_inc", f"channels disagree on the sample rate, or it "
                                               f"is missing: {sorted(fs_all)} Hz")
    fs = fs_all.pop()
    side_fs = meta.get("sample_rate_hz")
    if side_fs is not None:
        if isinstance(side_fs, bool) or not isinstance(side_fs, (int, float)):
            raise RecordError(src, "sample_rate_hz", f"= {side_fs!r} in the sidecar is not "
                                                     "allowed: a number (Hz)")
        if abs(side_fs / fs - 1) > 1e-6:
            raise RecordError(src, "sample_rate_hz", f"= {side_fs} in the sidecar but {fs} Hz "
                                                     "in the file")
    qty = {c["name"]: c.get("quantity") for c in meta.get("channels") or []}
    values = {}
    for k, d in by_name.items():
        f = unit_factor(d.get("ordinate_axis_units_lab", ""), qty[k], src,
                        f"channel {k!r}") if qty.get(k) in UNIT_FACTORS else 1.0
        values[k] = np.real(np.asarray(d["data"])) * f
    data = _columns(meta, values, src, "the type-58 datasets (by id1)")
    rec = record_from_metadata({**meta, "sample_rate_hz": fs}, data, src)
    return check_record(rec, source=src, **dict(check or {}))


def write_uff58(record: Record, path: str | Path) -> Path:
    """Write every channel of ``record`` (calibrated SI values) as a type-58 time response, and
    the JSON sidecar :func:`read_uff58` needs."""
    path = Path(path)
    if path.exists():
        path.unlink()
    uff = pyuff.UFF(str(path))
    dsets = []
    for i, c in enumerate(record.channels):
        dsets.append(pyuff.prepare_58(
            binary=1, func_type=1, id1=c.name, rsp_node=i + 1, rsp_dir=1, ref_node=0,
            ref_dir=0, data=record.values(c.name), x=record.time_s,
            abscissa_spacing=1, abscissa_inc=1.0 / record.sample_rate_hz, abscissa_min=0.0,
            abscissa_spec_data_type=17, ordinate_spec_data_type=UFF_DATA_TYPE[c.quantity],
            ordinate_axis_units_lab=c.unit, abscissa_axis_units_lab="s",
            **{f"{ax}_{k}": 0 for ax in ("orddenom", "z_axis")
               for k in ("spec_data_type", "len_unit_exp", "force_unit_exp", "temp_unit_exp")},
            orddenom_axis_units_lab="", z_axis_axis_units_lab=""))
    uff.write_sets(dsets, mode="add")
    _write_float_sidecar(record, path.with_suffix(".json"))
    return path


def read_tdms(path: str | Path, *, group: str, sidecar: str | Path | None = None,
              check: Mapping[str, Any] | None = None) -> Record:
    """A record from one group of a TDMS file (npTDMS): channels by name, the sample rate from
    each channel's ``wf_increment``, values as scaled by the file and converted to SI by the
    channel's ``unit_string``."""
    path = Path(path)
    src = str(path)
    if not path.is_file():
        raise RecordError(src, "file", "does not exist")
    meta, _ = _sidecar_for(path, sidecar)
    try:
        f = TdmsFile.read(str(path))
    except Exception as exc:  # npTDMS raises ValueError/KeyError/struct.error on bad files
        raise RecordError(src, "file", f"not a readable TDMS file: {exc}") from None
    groups = [g.name for g in f.groups()]
    if group not in groups:
        raise RecordError(src, "group", f"{group!r} not in the file; groups are {groups}")
    g = f[group]
    incs, values = set(), {}
    for c in meta.get("channels") or []:
        n = c["name"]
        if n not in [ch.name for ch in g.channels()]:
            raise RecordError(src, f"channel {n!r}", f"missing from group {group!r}")
        inc = g[n].properties.get("wf_increment")
        if inc is None or not inc > 0:
            raise RecordError(src, f"channel {n!r}.wf_increment",
                              f"= {inc!r}: the sample rate is missing")
        incs.add(round(1.0 / float(inc), 6))
        unit = g[n].properties.get("unit_string", "")
        fac = unit_factor(unit, c.get("quantity"), src, f"channel {n!r}") \
            if c.get("quantity") in UNIT_FACTORS else 1.0
        values[n] = np.asarray(g[n][:], dtype=float) * fac
    if len(incs) != 1:
        raise RecordError(src, "wf_increment", f"channels disagree: {sorted(incs)} Hz")
    data = _columns(meta, values, src, f"group {group!r}")
    rec = record_from_metadata({**meta, "sample_rate_hz": incs.pop()}, data, src)
    return check_record(rec, source=src, **dict(check or {}))


def write_tdms(record: Record, path: str | Path, *, group: str = "record") -> Path:
    """Write ``record`` (calibrated SI values) into a TDMS group, and its JSON sidecar."""
    path = Path(path)
    objs = [ChannelObject(group, c.name, record.values(c.name),
                          properties={"wf_increment": 1.0 / record.sample_rate_hz,
                                      "wf_start_offset": 0.0, "unit_string": c.unit})
            for c in record.channels]
    with TdmsWriter(str(path)) as w:
        w.write_segment(objs)
    _write_float_sidecar(record, path.with_suffix(".json"))
    return path


def _write_float_sidecar(record: Record, path: Path) -> None:
    path.write_text(json.dumps(as_float_record(record).metadata(), indent=1))


def as_float_record(record: Record, channels: Sequence[str] | None = None) -> Record:
    """The record with calibrated float values (``scale = 1``) — what the text formats hold."""
    meta = record.metadata()
    names = list(channels or record.channel_names)
    meta["channels"] = [c for c in meta["channels"] if c["name"] in names]
    for c in meta["channels"]:
        c["calibration"] = {"scale": 1.0, "offset": 0.0, "counts_min": None,
                            "counts_max": None}
    return record_from_metadata(meta, np.array([record.values(n) for n in names]), record.id)
