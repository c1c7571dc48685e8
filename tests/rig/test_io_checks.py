"""Importers (CSV + sidecar, UFF 58, TDMS): round trips; bad data: errors naming file+field."""

import json

import numpy as np
import pytest

from surrogate_rbrdo.rig.checks import check_record
from surrogate_rbrdo.rig.importers import (
    as_float_record,
    read_csv,
    read_tdms,
    read_uff58,
    write_csv,
    write_tdms,
    write_uff58,
)
from surrogate_rbrdo.rig.records import RecordError
from surrogate_rbrdo.rig.sensors import SensorSet
from surrogate_rbrdo.rig.simulate import steady_records
from surrogate_rbrdo.rig.truth import reference_truth

from .conftest import seeds


@pytest.fixture(scope="module")
def record():
    st = reference_truth().state(np.random.SeedSequence(4), build=0, tool=0, run=0)
    sens = SensorSet()
    inst = sens.install(np.random.default_rng(0))
    return steady_records(st.model(), st.theta, np.array([12000.0]), sens, inst, seeds(1),
                          duration_s=0.2, ids=["r12k"], provenance=[{"source": "test"}])[0]


@pytest.mark.parametrize("fmt", ["csv", "uff", "tdms"])
def test_round_trip(tmp_path, record, fmt):
    if fmt == "uff":
        pytest.importorskip("pyuff")
    if fmt == "tdms":
        pytest.importorskip("nptdms")
    write, read = {"csv": (write_csv, read_csv), "uff": (write_uff58, read_uff58),
                   "tdms": (write_tdms, lambda p: read_tdms(p, group="record"))}[fmt]
    back = read(write(record, tmp_path / f"r.{fmt}"))
    ref = as_float_record(record)
    np.testing.assert_array_equal(back.data, ref.data)
    assert back.metadata() == ref.metadata()


def _csv(tmp_path, record, **meta_changes):
    p = write_csv(record, tmp_path / "run.csv")
    meta = json.loads(p.with_suffix(".json").read_text())
    for k, v in meta_changes.items():
        if v is None:
            meta.pop(k)
        else:
            meta[k] = v
    p.with_suffix(".json").write_text(json.dumps(meta))
    return p


def test_missing_sample_rate_names_file_and_field(tmp_path, record):
    p = _csv(tmp_path, record, sample_rate_hz=None)
    with pytest.raises(RecordError,
                       match=r"run\.csv \[sidecar .*run\.json\]: sample_rate_hz: missing"):
        read_csv(p)


def test_wrong_sample_rate_against_time_column(tmp_path, record):
    p = _csv(tmp_path, record, sample_rate_hz=20_000)
    with pytest.raises(RecordError, match=r"run\.csv: sample_rate_hz: = 20000 disagrees"):
        read_csv(p)


def test_wrong_sample_rate_seen_by_the_keyphasor(tmp_path, record):
    p = _csv(tmp_path, record, sample_rate_hz=12_000)
    text = p.read_text().splitlines()
    header = text[0].split(",")[1:]
    p.write_text("\n".join([",".join(header)] + [r.split(",", 1)[1] for r in text[1:]]))
    with pytest.raises(RecordError, match=r"run\.csv: speed_rpm: .*keyphasor"):
        read_csv(p)


def test_speed_disagreeing_with_keyphasor(tmp_path, record):
    p = _csv(tmp_path, record, speed_rpm=11_000.0)
    with pytest.raises(RecordError, match=r"run\.csv: speed_rpm: = 11000 rpm disagrees"):
        read_csv(p)


def test_missing_channel(tmp_path, record):
    p = write_csv(record, tmp_path / "run.csv")
    lines = p.read_text().splitlines()
    cols = lines[0].split(",")
    keep = [i for i, c in enumerate(cols) if c != "tool_y"]
    p.write_text("\n".join(",".join(r.split(",")[i] for i in keep) for r in lines))
    with pytest.raises(RecordError, match=r"run\.csv: channel 'tool_y': missing"):
        read_csv(p)


def test_nan_sample(tmp_path, record):
    p = write_csv(record, tmp_path / "run.csv")
    lines = p.read_text().splitlines()
    parts = lines[10].split(",")
    parts[1] = "nan"
    lines[10] = ",".join(parts)
    p.write_text("\n".join(lines))
    with pytest.raises(RecordError, match=r"run\.csv: channel 'front_x': NaN/inf sample at "
                                          r"index 9"):
        read_csv(p)


def test_clipped_counts_and_flat_top(record):
    data = record.data.copy()
    data[4, :50] = 32767
    clipped = type(record)(record.id, record.kind, record.sample_rate_hz, record.channels, data,
                           speed_rpm=record.speed_rpm)
    with pytest.raises(RecordError, match="channel 'tool_x': clipped"):
        check_record(clipped, source="f.npz")
    fl = as_float_record(record)
    d = fl.data.copy()
    d[0, 100:110] = d[0].max() + 1e-6
    flat = type(fl)(fl.id, fl.kind, fl.sample_rate_hz, fl.channels, d, speed_rpm=12000.0)
    with pytest.raises(RecordError, match="channel 'front_x': clipped: 10 consecutive"):
        check_record(flat, source="f.csv")


def test_short_record(record):
    with pytest.raises(RecordError, match=r"f\.csv: duration: 0\.2 s is shorter"):
        check_record(record, source="f.csv", min_duration_s=1.0)
    with pytest.raises(RecordError, match="keyphasor revolutions"):
        check_record(record, source="f.csv", min_revolutions=100)


def test_good_record_passes(record):
    assert check_record(record, require=("front_x", "keyphasor")) is record
