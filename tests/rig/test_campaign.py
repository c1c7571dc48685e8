"""The campaign: dataset layout, provenance, determinism and resuming at record granularity."""

import json

import numpy as np
import pytest

from surrogate_rbrdo.rig.campaign import CampaignOptions, read_phasors, run_campaign
from surrogate_rbrdo.rig.store import open_dataset
from surrogate_rbrdo.rig.truth import reference_truth

OPTS = CampaignOptions(speeds_rpm=(5000.0, 15000.0, 21000.0), repeats=2, duration_s=0.2,
                       runup=(18000.0, 20000.0, 0.3), impacts_per_direction=1,
                       impact_duration_s=0.2)


def test_campaign_writes_a_complete_dataset_with_provenance(tmp_path):
    truth = reference_truth(hidden=[{"name": "anisotropy", "s": 0.1}])
    seen = []
    res = run_campaign(truth, OPTS, tmp_path, rng=np.random.default_rng(3),
                       progress=lambda i, n, rid: seen.append((i, n)))
    assert res.n_records == 6 + 2 + 2 and seen[-1] == (10, 10)
    ds = open_dataset(res.dataset)
    assert len(ds.select(kind="steady")) == 6 and len(ds.select(kind="impact")) == 2
    rec = ds.load(ds.select(kind="steady", repeat=1)[0])
    assert rec.provenance["hidden_effects"] == [{"name": "anisotropy", "s": 0.1,
                                                 "bearings": []}]
    assert rec.provenance["run"] == 1 and "truth_draws" in rec.provenance
    assert rec.data.dtype == np.int16
    info = json.loads((res.dataset / "dataset.json").read_text())
    assert info["truth"]["hidden"][0]["name"] == "anisotropy"
    assert (tmp_path / "phasors.csv").read_text().count("\n") == 1 + 6 * 6
    back = read_phasors(tmp_path / "phasors.csv")
    np.testing.assert_array_equal(back.array("re_m"), res.phasors.array("re_m"))
    assert back.rows[0][:4] == res.phasors.rows[0][:4]


def test_resume_rewrites_only_missing_records_identically(tmp_path):
    truth = reference_truth()
    run_campaign(truth, OPTS, tmp_path / "a", rng=np.random.default_rng(9))
    full = open_dataset(tmp_path / "a" / "dataset")
    # interrupt: drop two records and the completion mark
    victim = full.index[3]
    (tmp_path / "a" / "dataset" / victim["file"]).unlink()
    (tmp_path / "a" / "dataset" / "records" / "b0_t0_runup.npz").unlink()
    (tmp_path / "a" / "dataset" / "dataset.json").unlink()
    res = run_campaign(truth, OPTS, tmp_path / "a", rng=np.random.default_rng(9))
    assert res.n_written == 2
    fresh = run_campaign(truth, OPTS, tmp_path / "b", rng=np.random.default_rng(9))
    a, b = open_dataset(res.dataset), open_dataset(fresh.dataset)
    for rid in (victim["id"], "b0_t0_runup", "b0_t0_r00_s00"):
        np.testing.assert_array_equal(a.load(rid).data, b.load(rid).data)


def test_options_are_checked():
    with pytest.raises(ValueError, match="speeds_rpm"):
        CampaignOptions(speeds_rpm=(2000.0, 1000.0))
    with pytest.raises(ValueError, match="runup"):
        CampaignOptions(runup=(2000.0, 1000.0, 5.0))


def test_report_writes_every_figure(tmp_path):
    pytest.importorskip("sdypy.EMA")
    from surrogate_rbrdo.reporting.plots_rig import write_rig_report

    truth = reference_truth()
    opts = CampaignOptions(speeds_rpm=(5000.0, 15000.0, 21000.0), repeats=3, duration_s=0.2,
                           runup=(20500.0, 23000.0, 1.5), impacts_per_direction=2,
                           impact_duration_s=0.5)
    res = run_campaign(truth, opts, tmp_path, rng=np.random.default_rng(2))
    summary = write_rig_report(res, truth, tmp_path)
    for name in ("bode", "polar", "orbit", "campbell_runup", "frf_tool_x", "waterfall_runup"):
        assert (tmp_path / "figures" / f"{name}.png").stat().st_size > 10_000
    assert summary["critical_speeds_runup_rpm"] and summary["impact_modes_hz"]
    assert json.loads((tmp_path / "rig_summary.json").read_text()) == summary


def test_report_with_bearing_probes_only(tmp_path):
    pytest.importorskip("sdypy.EMA")
    from surrogate_rbrdo.reporting.plots_rig import write_rig_report
    from surrogate_rbrdo.rig.sensors import SensorSet

    opts = CampaignOptions(speeds_rpm=(8000.0, 16000.0), repeats=2, duration_s=0.2,
                           runup=None, impacts_per_direction=1, impact_duration_s=0.5,
                           sensors=SensorSet(targets=("front", "rear")))
    truth = reference_truth()
    res = run_campaign(truth, opts, tmp_path, rng=np.random.default_rng(0))
    write_rig_report(res, truth, tmp_path)
    assert (tmp_path / "figures" / "frf_front_x.png").is_file()
