"""The measured-data format: construction, validation and the native round trip."""

import json
import math

import numpy as np
import pytest

from surrogate_rbrdo.rig.records import (
    Calibration,
    ChannelSpec,
    Record,
    RecordError,
    SensorLocation,
)
from surrogate_rbrdo.rig.store import DatasetWriter, open_dataset, read_record, write_record


def _record(n=100, dtype=np.int16, rid="r1"):
    rng = np.random.default_rng(0)
    chans = (
        ChannelSpec("front_x", "displacement", "m", SensorLocation("front", "x", 100.0),
                    Calibration(3.9e-8, 1e-6, -32768, 32767), delay_s=4e-6,
                    info={"probe": "8 mm eddy current"}),
        ChannelSpec("keyphasor", "keyphasor", "V", SensorLocation("shaft"),
                    Calibration(3.05e-4, 0.0, -32768, 32767)),
    )
    data = rng.integers(-1000, 1000, size=(2, n)).astype(dtype)
    return Record(rid, "steady", 10_000.0, chans, data, speed_rpm=6000.0,
                  provenance={"source": "test", "seed": 3})


def test_native_round_trip_is_identical(tmp_path):
    rec = _record()
    back = read_record(write_record(rec, tmp_path / "r1.npz"))
    assert back.data.dtype == np.int16
    np.testing.assert_array_equal(back.data, rec.data)
    assert back.metadata() == rec.metadata()
    np.testing.assert_array_equal(back.values("front_x"), rec.values("front_x"))


def test_ramp_profile_round_trip(tmp_path):
    rec = _record()
    ramp = Record("u", "runup", 10_000.0, rec.channels, rec.data,
                  speed_profile=np.array([[0.0, 0.01], [1000.0, 2000.0]]))
    back = read_record(write_record(ramp, tmp_path / "u.npz"))
    assert math.isnan(back.speed_rpm)
    np.testing.assert_allclose(back.speed_at(np.array([0.005])), [1500.0])


def test_values_apply_calibration():
    rec = _record()
    np.testing.assert_allclose(rec.values("front_x"), rec.data[0] * 3.9e-8 + 1e-6)


@pytest.mark.parametrize("field,value,match", [
    ("sample_rate_hz", None, "sample_rate_hz: missing"),
    ("sample_rate_hz", -5.0, "sample_rate_hz"),
    ("kind", "sweep", "kind"),
])
def test_bad_metadata_names_file_and_field(tmp_path, field, value, match):
    path = write_record(_record(), tmp_path / "r1.npz")
    with np.load(path) as z:
        meta, data = json.loads(str(z["meta"])), z["data"]
    meta[field] = value
    np.savez(path, data=data, meta=np.array(json.dumps(meta)))
    with pytest.raises(RecordError, match=match) as exc:
        read_record(path)
    assert str(path) in str(exc.value)


def test_missing_channel_named():
    with pytest.raises(RecordError, match="channel 'tool_x'.*missing"):
        _record().values("tool_x")


def test_unit_must_be_si():
    with pytest.raises(ValueError, match="unit = 'um'"):
        ChannelSpec("a", "displacement", "um", SensorLocation("front", "x"))


def test_dataset_streams_and_resumes(tmp_path):
    w = DatasetWriter(tmp_path / "ds", {"title": "t"})
    for i in range(3):
        w.write(_record(rid=f"r{i}"), labels={"repeat": i})
    # an interrupted campaign: a half-written index line, no dataset.json
    with open(tmp_path / "ds" / "index.jsonl", "a") as fh:
        fh.write('{"id": "r3", "ki')
    with pytest.raises(RecordError, match="dataset.json"):
        open_dataset(tmp_path / "ds")
    w2 = DatasetWriter(tmp_path / "ds", {"title": "t"})
    assert w2.done() == {"r0", "r1", "r2"}
    w2.finish({"n": 3})
    ds = open_dataset(tmp_path / "ds")
    assert [r["id"] for r in ds.select(kind="steady", repeat=1)] == ["r1"]
    assert [r.id for r in ds] == ["r0", "r1", "r2"]


def test_events_round_trip_natively_and_are_checked(tmp_path):
    rec = _record()
    ev = Record(rec.id, rec.kind, rec.sample_rate_hz, rec.channels, rec.data,
                speed_rpm=rec.speed_rpm, events={"keyphasor": [0.001, 0.011, 0.021]})
    back = read_record(write_record(ev, tmp_path / "e.npz"))
    np.testing.assert_array_equal(back.events["keyphasor"], ev.events["keyphasor"])
    assert back.metadata() == ev.metadata()
    with pytest.raises(ValueError, match=r"events\['keyphasor'\]"):
        Record("r", "steady", 1e4, rec.channels, rec.data, events={"keyphasor": [0.2, 0.1]})
