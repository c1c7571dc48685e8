"""Bad measured-data files: every one a RecordError naming the file and the field (the cases
that raised raw tracebacks or vague messages before)."""

import copy
import json

import numpy as np
import pytest
from nptdms import ChannelObject, TdmsWriter

from surrogate_rbrdo.rig.checks import check_record
from surrogate_rbrdo.rig.importers import read_csv, read_tdms, read_uff58, write_uff58
from surrogate_rbrdo.rig.records import ChannelSpec, Record, RecordError, SensorLocation

FS, N = 10_000.0, 5000
T = np.arange(N) / FS
ANG = 0.3 + 2 * np.pi * 100 * T                                   # 6 000 rpm
X = 2.0 * np.exp(0.5j)
COLS = {"front_x": np.real(X * np.exp(1j * ANG)) + 5,
        "front_y": np.real(-1j * X * np.exp(1j * ANG)),
        "keyphasor": np.where(np.mod(ANG, 2 * np.pi) < 0.4, 5.0, 0.0)}
META = {"id": "r", "kind": "steady", "sample_rate_hz": 10000, "speed_rpm": 6000, "channels": [
    {"name": "front_x", "quantity": "displacement", "unit": "m",
     "location": {"target": "front", "direction": "x"}, "calibration": {"scale": 1e-6}},
    {"name": "front_y", "quantity": "displacement", "unit": "m",
     "location": {"target": "front", "direction": "y"}, "calibration": {"scale": 1e-6}},
    {"name": "keyphasor", "quantity": "keyphasor", "unit": "V",
     "location": {"target": "shaft"}}]}


def _write(tmp_path, meta=META, cols=COLS, text=None, sidecar_text=None):
    p = tmp_path / "bad.csv"
    if text is None:
        rows = np.column_stack(list(cols.values()))
        text = ",".join(cols) + "\n" + "\n".join(",".join(f"{v:.6g}" for v in r) for r in rows)
    p.write_text(text)
    (tmp_path / "bad.json").write_text(sidecar_text if sidecar_text is not None
                                       else json.dumps(meta))
    return p


def _meta(**upd):
    m = copy.deepcopy(META)
    for k, v in upd.items():
        if v is None:
            m.pop(k)
        else:
            m[k] = v
    return m


def test_the_good_file_reads(tmp_path):
    assert read_csv(_write(tmp_path)).n_samples == N


@pytest.mark.parametrize("case,field", [
    ("sidecar_is_list", "sidecar"),
    ("channel_without_name", r"channels\[0\]\.name"),
    ("channels_dict", "channels"),
    ("speed_missing", "speed_rpm: missing"),
    ("header_only", "data: no data rows"),
    ("flat_keyphasor", "channel 'keyphasor': flat"),
    ("scale_string", r"channels\['front_x'\]"),
    ("delay_string", r"channels\['front_x'\]"),
    ("id_null", "id: missing"),
    ("ragged_profile", "record"),
    ("fs_string", "sample_rate_hz"),
    ("events_not_increasing", "record"),
])
def test_bad_csv_names_file_and_field(tmp_path, case, field):
    meta, cols, text, side = META, COLS, None, None
    if case == "sidecar_is_list":
        side = "[1, 2]"
    elif case == "channel_without_name":
        meta = _meta()
        del meta["channels"][0]["name"]
    elif case == "channels_dict":
        meta = _meta(channels={"front_x": {}})
    elif case == "speed_missing":
        meta = _meta(speed_rpm=None)
    elif case == "header_only":
        text = "front_x,front_y,keyphasor\n"
    elif case == "flat_keyphasor":
        cols = {**COLS, "keyphasor": np.zeros(N)}
    elif case == "scale_string":
        meta = _meta()
        meta["channels"][0]["calibration"] = {"scale": "1e-6"}
    elif case == "delay_string":
        meta = _meta()
        meta["channels"][0]["delay_s"] = "4us"
    elif case == "id_null":
        meta = _meta(id=None)
        meta["id"] = None
    elif case == "ragged_profile":
        meta = _meta(kind="runup", speed_profile=[[0, 0.5], [6000]])
    elif case == "fs_string":
        meta = _meta(sample_rate_hz="10k")
    elif case == "events_not_increasing":
        meta = _meta(events={"keyphasor": [0.1, 0.05]})
    p = _write(tmp_path, meta, cols, text, side)
    with pytest.raises(RecordError, match=rf"bad\.(csv|json).*: {field}"):
        read_csv(p)


def test_inverted_keyphasor_is_read_by_its_leading_edge(tmp_path):
    """A notch (negative-going pulse): the falling edge is the reference, found from the
    pulse train's minority state; the 1x phase is the same as with the positive pulse."""
    from surrogate_rbrdo.rig.demod import demodulate

    pos = demodulate(read_csv(_write(tmp_path))).get("front_x")
    neg_kp = 5.0 - np.where(np.mod(ANG, 2 * np.pi) < 0.4, 5.0, 0.0)
    neg = demodulate(read_csv(_write(tmp_path, cols={**COLS, "keyphasor": neg_kp})))
    assert abs(np.angle(neg.get("front_x") / pos)) < np.radians(0.5)


def _uff(tmp_path, lengths=(1000, 1000), meta=None):
    recs = []
    for n in lengths:
        recs.append(np.sin(np.arange(n) * 0.1))
    chans = (ChannelSpec("a", "displacement", "m", SensorLocation("tool", "x")),
             ChannelSpec("f", "force", "N", SensorLocation("tool", "x")))
    rec = Record("u", "impact", FS, chans, np.vstack([recs[0], recs[0]]), speed_rpm=0.0)
    p = write_uff58(rec, tmp_path / "u.uff")
    if lengths[1] != lengths[0]:
        import pyuff

        sets = pyuff.UFF(str(p)).read_sets()
        sets[1]["data"] = sets[1]["data"][:lengths[1]]
        sets[1]["x"] = sets[1]["x"][:lengths[1]]
        p.unlink()
        pyuff.UFF(str(p)).write_sets(sets, mode="add")
    if meta is not None:
        (tmp_path / "u.json").write_text(json.dumps(meta))
    return p


def test_bad_uff_and_tdms_files(tmp_path):
    with pytest.raises(RecordError, match=r"u\.uff: channels: have different lengths"):
        read_uff58(_uff(tmp_path, (1000, 900)))
    p = _uff(tmp_path)
    meta = json.loads((tmp_path / "u.json").read_text())
    (tmp_path / "u.json").write_text(json.dumps({**meta, "sample_rate_hz": "10000"}))
    with pytest.raises(RecordError, match=r"u\.uff: sample_rate_hz: = '10000'"):
        read_uff58(p)
    g = tmp_path / "g.tdms"
    g.write_bytes(b"junkjunkjunk" * 10)
    (tmp_path / "g.json").write_text(json.dumps(meta))
    with pytest.raises(RecordError, match=r"g\.tdms: file: not a readable TDMS"):
        read_tdms(g, group="g")
    t = tmp_path / "len.tdms"
    with TdmsWriter(str(t)) as w:
        w.write_segment([ChannelObject("g", "a", np.ones(100), properties={"wf_increment": 1e-4}),
                         ChannelObject("g", "f", np.ones(90), properties={"wf_increment": 1e-4})])
    (tmp_path / "len.json").write_text(json.dumps(meta))
    with pytest.raises(RecordError, match=r"len\.tdms: channels: have different lengths"):
        read_tdms(t, group="g")


def test_provenance_with_numpy_values_and_flat_keyphasor_named_by_file():
    ch = ChannelSpec("keyphasor", "keyphasor", "V", SensorLocation("shaft"))
    rec = Record("r", "steady", FS, (ch,), np.zeros((1, 100)), speed_rpm=6000.0,
                 provenance={"seed": np.int64(3), "theta": np.array([1.0, 0.9])})
    assert rec.provenance == {"seed": 3, "theta": [1.0, 0.9]}
    with pytest.raises(RecordError, match=r"run9\.csv: channel 'keyphasor': flat"):
        check_record(rec, source="run9.csv")
