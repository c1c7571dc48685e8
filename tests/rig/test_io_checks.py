"""Importers (CSV + sidecar, UFF 58, TDMS): round trips; bad data: errors naming file+field."""

import json

import numpy as np
import pytest
import pyuff

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
from surrogate_rbrdo.rig.integrate import SpeedProfile
from surrogate_rbrdo.rig.records import ChannelSpec, Record, RecordError, SensorLocation
from surrogate_rbrdo.rig.sensors import KeyphasorModel, SensorSet
from surrogate_rbrdo.rig.simulate import impact_record, runup_record, steady_records
from surrogate_rbrdo.rig.truth import Variability, reference_truth

from .conftest import seeds

ST = reference_truth(variability=Variability.none()).state(np.random.SeedSequence(4), build=0,
                                                           tool=0, run=0)


def _steady(speed=12000.0, duration=0.2, **sensor_kw):
    sens = SensorSet(**sensor_kw)
    inst = sens.install(np.random.default_rng(0))
    return steady_records(ST.model(), ST.theta, np.array([speed]), sens, inst, seeds(1),
                          duration_s=duration, ids=["r"], provenance=[{"source": "test"}])[0]


@pytest.fixture(scope="module")
def record():
    return _steady()


@pytest.fixture(scope="module")
def sampled_record():
    """A keyphasor without counter timestamps: the sample rate is checked by its pulses."""
    return _steady(keyphasor=KeyphasorModel(timing="sampled"))


def _records():
    """Records whose round trips broke before: a steady one with the noise off (quantised
    float data), a slow one, a full-range run-up (1 000 → 24 000 rpm), an impact."""
    sens = SensorSet()
    inst = sens.install(np.random.default_rng(0))
    m = ST.model()
    ru = runup_record(m, ST.theta, SpeedProfile.ramp(1000.0, 24000.0, 2.0), sens, inst,
                      np.random.default_rng(1), rid="ru", provenance={})
    hit = impact_record(m, ST.theta, sens, inst, np.random.default_rng(3), rid="h",
                        provenance={}, duration_s=0.3)
    return {"steady": _steady(), "noise_off": _steady(2000.0, 0.5, noise=False, quantise=True),
            "runup": ru, "impact": hit}


RECORDS = _records()


@pytest.mark.parametrize("fmt", ["csv", "uff", "tdms"])
@pytest.mark.parametrize("which", list(RECORDS))
def test_round_trip(tmp_path, fmt, which):
    record = RECORDS[which]
    write, read = {"csv": (write_csv, read_csv), "uff": (write_uff58, read_uff58),
                   "tdms": (write_tdms, lambda p: read_tdms(p, group="record"))}[fmt]
    back = read(write(record, tmp_path / f"r.{fmt}"))
    ref = as_float_record(record)
    np.testing.assert_array_equal(back.data, ref.data)
    assert back.metadata() == ref.metadata()


def test_uff_with_one_channel_round_trips(tmp_path):
    one = Record("one", "impact", 10_000.0, (ChannelSpec("f", "force", "N",
                                                         SensorLocation("tool", "x")),),
                 np.random.default_rng(0).normal(size=(1, 1000)), speed_rpm=0.0)
    back = read_uff58(write_uff58(one, tmp_path / "one.uff"))
    np.testing.assert_array_equal(back.data, one.data)


def test_uff_unit_labels_are_applied(tmp_path):
    """A dataset labelled "mm" is millimetres (converted to m); an unknown label is an error
    naming the channel."""
    rec = as_float_record(RECORDS["impact"], ["tool_x", "hammer"])
    p = write_uff58(rec, tmp_path / "u.uff")
    sets = pyuff.UFF(str(p)).read_sets()
    sets[0]["data"] = sets[0]["data"] * 1e3
    sets[0]["ordinate_axis_units_lab"] = "mm"
    p.unlink()
    pyuff.UFF(str(p)).write_sets(sets, mode="add")
    back = read_uff58(p)
    np.testing.assert_allclose(back.values("tool_x"), rec.values("tool_x"), rtol=1e-12)
    sets[0]["ordinate_axis_units_lab"] = "furlong"
    p.unlink()
    pyuff.UFF(str(p)).write_sets(sets, mode="add")
    with pytest.raises(RecordError, match=r"u\.uff: channel 'tool_x': unit label 'furlong'"):
        read_uff58(p)


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


@pytest.mark.parametrize("fs", [12_000, 8_000])
def test_wrong_sample_rate_seen_by_the_keyphasor(tmp_path, record, sampled_record, fs):
    """Without a time column: a sampled keyphasor turns at the wrong speed; counter timestamps
    disagree with the sampled pulses (or run past the record's end)."""
    for rec, field in ((sampled_record, "speed_rpm"), (record, "sample_rate_hz")):
        p = _csv(tmp_path, rec, sample_rate_hz=fs)
        text = p.read_text().splitlines()
        header = text[0].split(",")[1:]
        p.write_text("\n".join([",".join(header)] + [r.split(",", 1)[1] for r in text[1:]]))
        with pytest.raises(RecordError, match=rf"run\.csv: {field}: .*keyphasor"):
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
    t = np.arange(3000) / 10_000.0
    x = 3.0 * np.cos(2 * np.pi * 33.3 * t) + np.random.default_rng(0).normal(0, 0.01, t.size)
    ch = ChannelSpec("x", "displacement", "m", SensorLocation("front", "x"))
    for xx in (np.minimum(x, 2.4), np.round(np.minimum(x, 2.4), 2)):  # flat-topped floats
        flat = Record("c", "impact", 10_000.0, (ch,), xx[None, :], speed_rpm=0.0)
        with pytest.raises(RecordError, match="f.csv: channel 'x': clipped: .* consecutive"):
            check_record(flat, source="f.csv")
    check_record(Record("c", "impact", 10_000.0, (ch,), np.round(x, 2)[None, :],
                        speed_rpm=0.0))


def test_quantised_float_data_is_not_clipping():
    """Coarsely quantised float data (a noise-free record, few decimals) lingers at its peak
    value as at any level near it: no clipping (it was flagged before)."""
    t = np.arange(3000) / 10_000.0
    x = np.round(2.3 * np.cos(2 * np.pi * 33.3 * t), 0)          # 5 levels
    ch = ChannelSpec("x", "displacement", "m", SensorLocation("front", "x"))
    check_record(Record("q", "impact", 10_000.0, (ch,), x[None, :], speed_rpm=0.0))
    check_record(as_float_record(RECORDS["noise_off"]))


def test_full_range_runup_passes_and_a_wrong_profile_fails():
    ru = RECORDS["runup"]
    check_record(ru)
    prof = ru.speed_profile.copy()
    prof[1, 1] = 20000.0                                   # ends 4 000 rpm too low
    bad = Record(ru.id, ru.kind, ru.sample_rate_hz, ru.channels, ru.data, speed_profile=prof,
                 events=ru.events)
    with pytest.raises(RecordError, match="speed_profile: averages .* but the keyphasor"):
        check_record(bad, source="ru.csv")


def test_short_record(record):
    with pytest.raises(RecordError, match=r"f\.csv: duration: 0\.2 s is shorter"):
        check_record(record, source="f.csv", min_duration_s=1.0)
    with pytest.raises(RecordError, match="keyphasor revolutions"):
        check_record(record, source="f.csv", min_revolutions=100)


def test_good_record_passes(record):
    assert check_record(record, require=("front_x", "keyphasor")) is record
