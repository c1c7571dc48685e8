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


@pytest.mark.known_answer
def test_report_writes_every_figure_and_its_numbers_match_the_truth(tmp_path):
    """The figures exist; the summary's numbers are the truth's: the run-up's and run-down's
    critical speeds bracket the truth's, the impact tests' first mode is the truth's (its
    modal analysis at standstill) within 0.5 % in frequency and 20 % in damping."""
    from surrogate_rbrdo.reporting.plots_rig import write_rig_report
    from surrogate_rbrdo.spindle import critical_speeds
    from surrogate_rbrdo.spindle.modal import modal_analysis

    truth = reference_truth()
    opts = CampaignOptions(speeds_rpm=(5000.0, 15000.0, 21000.0), repeats=3, duration_s=0.2,
                           runup=(20500.0, 23000.0, 1.5), impacts_per_direction=2,
                           impact_duration_s=0.5)
    res = run_campaign(truth, opts, tmp_path, rng=np.random.default_rng(2))
    summary = write_rig_report(res, truth, tmp_path)
    for name in ("bode", "polar", "orbit", "campbell_runup", "frf_tool_x", "waterfall_runup"):
        assert (tmp_path / "figures" / f"{name}.png").stat().st_size > 10_000
    assert json.loads((tmp_path / "rig_summary.json").read_text()) == summary
    prov = open_dataset(res.dataset).load(res.impacts[0]).provenance
    st = truth.apply(*(prov["truth_draws"][k] for k in ("build", "tool", "run")))
    cs = critical_speeds(st.model(), np.linspace(20500.0, 23000.0, 11), st.theta[0])
    assert summary["critical_speeds_rundown_rpm"][0] < cs[0] < summary[
        "critical_speeds_runup_rpm"][0]
    md = modal_analysis(st.model(), 0.0, st.theta[0])
    f0, z0 = md.frequency_hz[0], md.damping_ratio[0]
    got = np.asarray(summary["impact_modes_hz"])
    k = int(np.argmin(np.abs(got - f0)))
    assert abs(got[k] / f0 - 1) < 5e-3
    assert abs(summary["impact_damping_ratios"][k] / z0 - 1) < 0.2


def test_rng_state_matters_and_a_fresh_seed_reproduces(tmp_path):
    """Two campaigns from one generator differ; a fresh generator of the same seed repeats the
    first (which is how a campaign resumes)."""
    opts = CampaignOptions(speeds_rpm=(8000.0,), repeats=1, duration_s=0.1, runup=None,
                           impacts_per_direction=0)
    rng = np.random.default_rng(1)
    a = run_campaign(reference_truth(), opts, tmp_path / "a", rng=rng)
    b = run_campaign(reference_truth(), opts, tmp_path / "b", rng=rng)
    c = run_campaign(reference_truth(), opts, tmp_path / "c", rng=np.random.default_rng(1))
    assert not np.array_equal(a.phasors.array("re_m"), b.phasors.array("re_m"))
    np.testing.assert_array_equal(a.phasors.array("re_m"), c.phasors.array("re_m"))


def test_massless_housing_campaign_runs_its_ramps(tmp_path):
    """A housing stage without mass (the effect's default m_kg = 0) is simulated in time too
    (it failed at the run-up after writing every steady record)."""
    truth = reference_truth(hidden=[{"name": "housing", "k_N_per_m": 5e8}])
    opts = CampaignOptions(speeds_rpm=(8000.0,), repeats=1, duration_s=0.1,
                           runup=(8000.0, 9000.0, 0.2), impacts_per_direction=1,
                           impact_duration_s=0.1)
    res = run_campaign(truth, opts, tmp_path, rng=np.random.default_rng(0))
    assert res.n_records == 5 and len(res.ramps) == 2      # steady, run-up, run-down, 2 hits


def test_every_run_is_checked_for_stability():
    """A run whose own truth is unstable is refused, naming the run (not only run 0)."""
    from surrogate_rbrdo.core.errors import ModelError
    from surrogate_rbrdo.rig.campaign import _check_run, _precheck

    opts = CampaignOptions(speeds_rpm=(20000.0, 22000.0, 24000.0), runup=None)
    stable = reference_truth().state(np.random.SeedSequence(0), build=0, tool=0, run=0)
    red = _precheck(stable, opts)
    _check_run(stable, opts, red, 0, 0, 0)
    bad = reference_truth(hidden=[{"name": "cross_coupling", "kappa": 0.3}]).state(
        np.random.SeedSequence(0), build=0, tool=0, run=7)
    with pytest.raises(ModelError, match="build 0, tool 0, run 7 is unstable"):
        _check_run(bad, opts, _precheck(bad, opts), 0, 0, 7)


def test_report_with_bearing_probes_only(tmp_path):
    from surrogate_rbrdo.reporting.plots_rig import write_rig_report
    from surrogate_rbrdo.rig.sensors import SensorSet

    opts = CampaignOptions(speeds_rpm=(8000.0, 16000.0), repeats=2, duration_s=0.2,
                           runup=None, impacts_per_direction=1, impact_duration_s=0.5,
                           sensors=SensorSet(targets=("front", "rear")))
    truth = reference_truth()
    res = run_campaign(truth, opts, tmp_path, rng=np.random.default_rng(0))
    write_rig_report(res, truth, tmp_path)
    assert (tmp_path / "figures" / "frf_front_x.png").is_file()


def test_worker_processes_write_the_same_files(tmp_path):
    """``n_jobs = 2`` simulates the steady runs and the ramps on joblib workers (the hits share
    one simulation per speed and direction, here): every record file, the index and the 1x
    table are byte for byte those of one process (each record has its own stream)."""
    truth = reference_truth(hidden=[{"name": "housing", "k_N_per_m": 6e8, "m_kg": 20.0}])
    for name, jobs in (("one", 1), ("two", 2)):
        run_campaign(truth, OPTS, tmp_path / name, rng=np.random.default_rng(4), n_jobs=jobs)
    files = sorted(p.relative_to(tmp_path / "one")
                   for p in (tmp_path / "one").rglob("*") if p.suffix in (".npz", ".csv", ".jsonl"))
    assert len(files) == 6 + 2 + 2 + 1 + 1
    for f in files:
        assert (tmp_path / "one" / f).read_bytes() == (tmp_path / "two" / f).read_bytes(), f
    with pytest.raises(ValueError, match="n_jobs = 0 is not allowed"):
        run_campaign(truth, OPTS, tmp_path / "bad", rng=np.random.default_rng(4), n_jobs=0)


def test_runs_made_on_workers_fail_in_order_after_the_ones_before_are_handed_on():
    """With ``[rig] n_jobs > 1`` a worker returns its unstable run's ``ModelError``: the main
    process hands on (writes) every run before it, then raises that run's error — not a later
    failing run's, and not before the earlier runs, as one process would."""
    from surrogate_rbrdo.core.errors import ModelError
    from surrogate_rbrdo.rig.campaign import _raising

    got = []
    with pytest.raises(ModelError, match="run 2"):
        for res in _raising(iter([0, 1, ModelError("run 2"), ModelError("run 3"), 4])):
            got.append(res)
    assert got == [0, 1]
