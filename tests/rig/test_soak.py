"""The thermal soak in the rig campaign: records, labels, temperatures, the warmed response,
no change to the rest of a campaign, resuming, the reader and the config."""

import dataclasses
import json
import shutil

import numpy as np
import pytest

from surrogate_rbrdo.core.schema import parse
from surrogate_rbrdo.discrepancy.experiment import data_from_folder
from surrogate_rbrdo.discrepancy.measured import soak_blocks
from surrogate_rbrdo.rig.campaign import CampaignOptions, footprint, run_campaign
from surrogate_rbrdo.rig.config import RigTable, rig_plan
from surrogate_rbrdo.rig.demod import demodulate
from surrogate_rbrdo.rig.phasors import expected_phasors
from surrogate_rbrdo.rig.sensors import DAQModel, KeyphasorModel, ProbeModel, SensorSet
from surrogate_rbrdo.rig.simulate import ProbeLayout
from surrogate_rbrdo.rig.store import open_dataset, read_record
from surrogate_rbrdo.rig.thermal import SoakPlan
from surrogate_rbrdo.rig.truth import _child, reference_truth

TIMES = (0.0, 900.0, 3600.0)
PLAN = SoakPlan(times_s=TIMES, runs=3, rule="resonance")   # the one-speed soak
SPEEDS = (8000.0, 12000.0, 16000.0, 20000.0)
REPEATS = 5                     # the reader's 1x block needs 5


def _opts(soak=PLAN, sensors=None, speeds=SPEEDS):
    return CampaignOptions(speeds_rpm=speeds, repeats=REPEATS, duration_s=1.0, runup=None,
                           impacts_per_direction=0, sensors=sensors or SensorSet(), soak=soak)


def _thermal():
    return reference_truth(hidden=[{"name": "thermal_preload", "b": 0.5}])


@pytest.fixture(scope="module")
def soaked(tmp_path_factory):
    """A noisy campaign on a truth whose preload grows with temperature."""
    out = tmp_path_factory.mktemp("soaked")
    seen = []
    res = run_campaign(_thermal(), _opts(), out, rng=np.random.default_rng(1),
                       progress=lambda i, n, rid: seen.append((i, n, rid)))
    assert seen[-1] == (REPEATS * 4 + 9, REPEATS * 4 + 9, "b0_t0_soak2_k02")
    return res


def _root_and_inst(res, sensors):
    """The campaign's root seed and sensor installation, rebuilt from ``dataset.json``."""
    info = json.loads((res.dataset / "dataset.json").read_text())
    root = np.random.SeedSequence(int(info["seed"]["entropy"]),
                                  spawn_key=tuple(info["seed"]["spawn_key"]))
    inst = sensors.install(np.random.default_rng(_child(root, 9)))
    assert inst.to_dict() == info["installation"]
    return root, inst


def _expected(truth, res, sensors, row, speed):
    """The noise-free 1x of a soak record: its run's state warmed to 1 − exp(−t/τ)."""
    root, inst = _root_and_inst(res, sensors)
    lab = row["labels"]
    st = truth.state(root, build=lab["build"], tool=lab["tool"], run=lab["run"])
    w = st.warming(1.0 - np.exp(-lab["time_s"] / truth.thermal.time_constant_s))
    return expected_phasors(w.model(), w.theta, np.array([speed]), sensors, inst)[0]


def test_soak_records_have_their_kind_labels_channels_and_speed(soaked):
    ds = open_dataset(soaked.dataset)
    rows = ds.select(kind="soak")
    ids = [f"b0_t0_soak{j}_k{k:02d}" for j in range(3) for k in range(3)]
    assert [r["id"] for r in rows] == ids == list(soaked.soaks)
    assert json.loads((soaked.root / "summary.json").read_text())["soak"] == ids
    assert soaked.n_records == REPEATS * 4 + 9 == footprint(_opts()).n_records
    held = rows[0]["speed_rpm"]
    assert [r["labels"] for r in rows] == [
        {"build": 0, "tool": 0, "run": REPEATS + 1 + j, "soak": j, "time_s": t,
         "speed_rpm": held} for j in range(3) for t in TIMES]
    steady = ds.load(ds.select(kind="steady")[0])
    rec = ds.load(rows[0])
    assert rec.kind == "soak" and rec.channel_names == steady.channel_names + ("T_front",)
    spec = rec.channel("T_front")
    front = ProbeLayout.of(_thermal().state(np.random.SeedSequence(0), build=0, tool=0,
                                            run=0).model()).positions_mm["front"]
    assert (spec.quantity, spec.unit, spec.location.target) == ("temperature", "K", "front")
    assert spec.location.position_mm == pytest.approx(front)
    # the speed held: the sweep's largest mean (over runs) of the largest channel amplitude
    p = soaked.phasors
    amp = np.zeros((REPEATS, 4))
    for r, s, a in zip(p.array("run"), p.array("speed_rpm"), p.array("amplitude_m"),
                       strict=True):
        i = SPEEDS.index(s)
        amp[r, i] = max(amp[r, i], a)
    assert {r["speed_rpm"] for r in rows} == {SPEEDS[int(np.argmax(amp.mean(0)))]}


@pytest.mark.known_answer
def test_temperature_follows_the_thermal_model(soaked):
    """Each run starts near ambient (293.15 K, SD 0.5 K) and rises by
    15 K (Ω/24 000 rpm)^(5/3) (1 − exp(−t/900 s)); a reading's noise is 0.05 K, its
    resolution 0.01 K."""
    ds = open_dataset(soaked.dataset)
    rows = ds.select(kind="soak")
    T = np.array([ds.load(r).values("T_front").mean() for r in rows]).reshape(3, 3)
    speed = rows[0]["speed_rpm"]
    rise = 15.0 * (speed / 24000.0) ** (5 / 3) * (1 - np.exp(-np.array(TIMES) / 900.0))
    assert np.all(np.abs(T[:, 0] - 293.15) < 5 * 0.5)
    np.testing.assert_allclose(T - T[:, :1], np.broadcast_to(rise, T.shape),
                               atol=5 * 0.05 * np.sqrt(2) + 0.01)
    assert np.ptp(ds.load(rows[1]).values("T_front")) == 0.0      # held over the record


@pytest.mark.known_answer
def test_soak_phasor_is_the_warmed_states_response(soaked, tmp_path):
    """Without noise a soak record demodulates to the FE response of its run's state warmed
    to the thermal fraction (to round-off); with noise within 5 nm (the phasor noise is
    0.73 nm per part at 1 s) while the response drifts by more than 30 nm."""
    truth, ideal = _thermal(), SensorSet(noise=False)
    res = run_campaign(truth, _opts(sensors=ideal, speeds=(12000.0, 20000.0)), tmp_path,
                       rng=np.random.default_rng(4))
    ds = open_dataset(res.dataset)
    for row in ds.select(kind="soak"):
        rec = ds.load(row)
        e = _expected(truth, res, ideal, row, rec.speed_rpm)
        np.testing.assert_allclose(demodulate(rec).X[:, 0], e, rtol=1e-9, atol=0)
    ds = open_dataset(soaked.dataset)
    sens = SensorSet()
    got, exp = [], []
    for row in ds.select(kind="soak"):
        rec = ds.load(row)
        got.append(demodulate(rec).X[:, 0])
        exp.append(_expected(truth, soaked, sens, row, rec.speed_rpm))
    got, exp = np.array(got).reshape(3, 3, -1), np.array(exp).reshape(3, 3, -1)
    assert np.abs(got - exp).max() < 5e-9
    assert np.abs(exp[:, -1] - exp[:, 0]).min() > 30e-9


def test_without_a_thermal_effect_nothing_drifts(tmp_path):
    """The reference truth has no effect that follows temperature: a run's soak records have
    one response (noise-free: equal to round-off) while the temperature still rises."""
    res = run_campaign(reference_truth(), _opts(sensors=SensorSet(noise=False),
                                                speeds=(12000.0, 20000.0)),
                       tmp_path, rng=np.random.default_rng(5))
    ds = open_dataset(res.dataset)
    rows = ds.select(kind="soak")
    X = np.array([demodulate(ds.load(r)).X[:, 0] for r in rows]).reshape(3, 3, -1)
    np.testing.assert_allclose(X, np.broadcast_to(X[:, :1], X.shape), rtol=1e-9, atol=0)
    T = np.array([ds.load(r).values("T_front").mean() for r in rows]).reshape(3, 3)
    assert np.all(T[:, -1] - T[:, 0] > 5.0)


def _content(path):
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def test_a_soak_changes_no_other_file(tmp_path):
    """The records, index lines and 1x table of a campaign are the same with and without a
    soak (the soak draws from streams of its own)."""
    truth = _thermal()
    opts = CampaignOptions(speeds_rpm=(8000.0, 16000.0), repeats=REPEATS, duration_s=0.2,
                           runup=(15000.0, 16000.0, 0.2), impacts_per_direction=1,
                           impact_duration_s=0.2)
    a = run_campaign(truth, opts, tmp_path / "a", rng=np.random.default_rng(7))
    b = run_campaign(truth, dataclasses.replace(opts, soak=PLAN), tmp_path / "b",
                     rng=np.random.default_rng(7))
    assert (tmp_path / "a/phasors.csv").read_bytes() == (tmp_path / "b/phasors.csv").read_bytes()
    lines_a = (a.dataset / "index.jsonl").read_text().splitlines()
    lines_b = (b.dataset / "index.jsonl").read_text().splitlines()
    assert lines_b[:len(lines_a)] == lines_a and len(lines_b) == len(lines_a) + 9
    for row in open_dataset(a.dataset).index:
        ca, cb = _content(a.dataset / row["file"]), _content(b.dataset / row["file"])
        assert ca.keys() == cb.keys()
        for k in ca:
            np.testing.assert_array_equal(ca[k], cb[k])
    assert soak_blocks(a.dataset) == () and data_from_folder(a.root, impacts=False).soaks == ()


def test_resume_skips_the_soak_records_written(soaked, tmp_path):
    copy = tmp_path / "c"
    shutil.copytree(soaked.root, copy)
    for rid in ("b0_t0_soak1_k02", "b0_t0_soak2_k00"):
        (copy / "dataset" / "records" / f"{rid}.npz").unlink()
    (copy / "dataset" / "dataset.json").unlink()
    res = run_campaign(_thermal(), _opts(), copy, rng=np.random.default_rng(1))
    assert res.n_written == 2 and res.soaks == soaked.soaks
    for rid in soaked.soaks:
        np.testing.assert_array_equal(read_record(copy / f"dataset/records/{rid}.npz").data,
                                      read_record(soaked.dataset / f"records/{rid}.npz").data)


def test_soak_blocks_read_the_records_back(soaked, tmp_path):
    (blk,) = soak_blocks(soaked.dataset)
    ds = open_dataset(soaked.dataset)
    rows = ds.select(kind="soak")
    assert blk.speed_rpm == rows[0]["speed_rpm"] and blk.name == f"soak_{blk.speed_rpm:.0f}rpm"
    np.testing.assert_array_equal(blk.times_s, np.tile(TIMES, (3, 1)))
    recs = [ds.load(r) for r in rows]
    np.testing.assert_array_equal(blk.temperature_K.ravel(),
                                  [r.values("T_front").mean() for r in recs])
    names = [c.name for c in blk.channels]
    assert names == sorted(names) and blk.phasors.shape == (3, 3, 6)
    for i, rec in enumerate(recs):
        p = demodulate(rec)
        np.testing.assert_array_equal(blk.phasors[i // 3, i % 3],
                                      [p.X[p.channels.index(n), 0] for n in names])
    data = data_from_folder(soaked.root)              # the campaign folder
    assert data.block("unbalance_1x").channels == blk.channels
    (again,) = data.soaks
    np.testing.assert_array_equal(again.phasors, blk.phasors)
    (again,) = data_from_folder(soaked.dataset).soaks    # a dataset folder
    np.testing.assert_array_equal(again.temperature_K, blk.temperature_K)
    # a run with a record missing: the runs' times differ
    copy = tmp_path / "d"
    shutil.copytree(soaked.dataset, copy)
    (copy / "records" / "b0_t0_soak1_k01.npz").unlink()
    with pytest.raises(ValueError, match="different numbers of records"):
        soak_blocks(copy)


@pytest.mark.parametrize(("soak", "field"), [
    ({"times_s": [0.0, 600.0]}, "rig.campaign.soak.times_s"),
    ({"times_s": [0.0, 600.0, 300.0]}, "rig.campaign.soak.times_s"),
    ({"runs": 2}, "rig.campaign.soak.runs"),
    ({"runs": 3}, "rig.campaign.soak.runs"),             # two speeds: 2 runs at each
    ({"rule": "peak"}, "rig.campaign.soak.rule"),
    ({"speeds_rpm": [9000.0, 9000.0]}, "rig.campaign.soak.speeds_rpm"),
    ({"speeds_rpm": [9000.0, -1.0]}, "rig.campaign.soak.speeds_rpm"),
    ({"speed_rpm": 9000.0, "speeds_rpm": [8000.0, 10000.0]}, "rig.campaign.soak.speed"),
    ({"runs": 3.5}, "rig.campaign.soak.runs"),
    ({"speed_rpm": -1.0}, "rig.campaign.soak.speed_rpm"),
    ({"speed_rpm": "top"}, "rig.campaign.soak.speed_rpm"),
    ({"hours": 1.0}, "rig.campaign.soak.hours"),
])
def test_bad_soak_config_names_the_field(soak, field):
    with pytest.raises(ValueError, match=field.replace(".", r"\.")):
        parse(RigTable, {"campaign": {"soak": soak}}, "rig")


def test_soak_config_forms_and_the_rig_speed_limit():
    assert parse(RigTable, {"campaign": {"soak": {}}}, "rig").campaign.soak == SoakPlan()
    t = parse(RigTable, {"campaign": {"soak": {"speed_rpm": 12000.0, "runs": 5,
                                               "times_s": [0.0, 60.0, 120.0]}}}, "rig")
    assert t.campaign.soak == SoakPlan(12000.0, (0.0, 60.0, 120.0), 5)
    fast = parse(RigTable, {"campaign": {"soak": {"speed_rpm": 40000.0}}}, "rig")
    with pytest.raises(ValueError, match=r"campaign\.soak\.speed_rpm = 40000"):
        rig_plan(fast.config())


@pytest.mark.known_answer
def test_soak_plan_picks_the_resonance():
    """A one-mode response r²/|1 − r² + 2iζr| (ζ = 0.05) peaks at r = 1/√(1 − 2ζ²): the grid
    speed nearest it; an explicit speed is kept; without amplitudes the top speed."""
    speeds = np.linspace(1000.0, 24000.0, 47)
    zeta, wn = 0.05, 14000.0
    r = speeds / wn
    amp = r**2 / np.abs(1 - r**2 + 2j * zeta * r)
    peak = wn / np.sqrt(1 - 2 * zeta**2)
    one = SoakPlan(rule="resonance")
    i = int(np.argmin(np.abs(speeds - peak)))
    assert one.at(speeds, amp).speed_rpm == speeds[i]
    assert SoakPlan(speed_rpm=5000.0).at(speeds, amp).speed_rpm == 5000.0
    assert one.at(speeds).speed_rpm == 24000.0
    with pytest.raises(ValueError, match="one per speed"):
        one.at(speeds, amp[:-1])
    # the default: the two grid speeds either side of it, the runs taken at them in turn
    two = SoakPlan().at(speeds, amp)
    assert two.speeds == (speeds[i - 1], speeds[i + 1]) and two.speeds[0] < peak < two.speeds[1]
    assert [two.speed_of(j) for j in range(4)] == [speeds[i - 1], speeds[i + 1]] * 2
    assert SoakPlan(speeds_rpm=(9000.0, 7000.0)).at(speeds, amp).speeds == (9000.0, 7000.0)


@pytest.mark.parametrize("amp, speed", [(None, 24000.0), ("rising", 24000.0),
                                        ("falling", 1000.0)])
def test_flanks_without_a_resonance_inside_the_sweep_fall_back_to_one_speed(amp, speed):
    """No amplitudes, or the largest at the sweep's last or first speed: no two speeds lie
    either side of a resonance (review s13, M3), so the one-speed soak at that speed, all
    runs there, with a warning naming the speed and the rule."""
    speeds = np.linspace(1000.0, 24000.0, 47)
    a = {None: None, "rising": speeds**2, "falling": 1.0 / speeds}[amp]
    with pytest.warns(UserWarning, match=rf"flanks.*{speed:g} rpm.*rule = 'resonance'"):
        plan = SoakPlan(runs=4).at(speeds, a)
    assert plan.rule == "resonance" and plan.speeds == (speed,)
    assert [plan.speed_of(j) for j in range(4)] == [speed] * 4


def test_three_runs_need_the_one_speed_soak():
    """3 runs, valid before the two-speed default: refused with the default rule naming the
    field, its value and both ways out; the one-speed soak takes them as before."""
    for kw in ({}, {"rule": "flanks"}):
        with pytest.raises(ValueError, match=r"soak\.runs = 3 .*flanks.*runs >= 4.*"
                                             r"rule = 'resonance'.*runs >= 3"):
            SoakPlan(runs=3, **kw)
    with pytest.raises(ValueError, match=r"soak\.runs = 3 .*2 soak\.speeds_rpm.*runs >= 4"):
        SoakPlan(runs=3, speeds_rpm=(9000.0, 10000.0))
    assert SoakPlan(runs=3, rule="resonance").at([1000.0, 2000.0], [1.0, 2.0]).speeds == (
        2000.0,)
    assert SoakPlan(runs=3, speed_rpm=5000.0).speeds == (5000.0,)
    with pytest.raises(ValueError, match=r"soak\.runs = 2 .*>= 3"):
        SoakPlan(runs=2, rule="resonance")


def _tempco_sensors(sd):
    """Sensors whose one random error is the probes' tempco (no noise, gain, bandwidth, skew
    or gap scatter; float counts): records differ only through it."""
    return SensorSet(probe=ProbeModel(gain_error_sd=0.0, noise_rms_m=0.0, bandwidth_sd=0.0,
                                      gap_sd_m=0.0, tempco_sd_per_K=sd),
                     daq=DAQModel(skew_sd_s=0.0), keyphasor=KeyphasorModel(noise_V=0.0),
                     quantise=False)


@pytest.mark.known_answer
@pytest.mark.parametrize("sweep", [True, False])
def test_the_probe_tempco_scales_the_phasors_by_one_plus_alpha_dT(tmp_path, sweep):
    """Two campaigns alike but for the probes' tempco (same seed): each soak record's 1x is
    the one without it times ``1 + α_c ΔT`` exactly, ``ΔT`` the outer ring's true rise
    ``rise(Ω) (1 − e^{−t/τ})``; each steady record's times ``1 + α_c rise(Ω)`` (its speed's
    equilibrium) with ``tempco_sweep``, else unchanged. Without the tempco the installation
    writes what it wrote before the option (no ``tempco_per_K``)."""
    truth = reference_truth()
    # the two speeds given: a 2-speed sweep has no speed either side of its largest amplitude
    plan = SoakPlan(times_s=TIMES, runs=4, speeds_rpm=(12000.0, 20000.0))
    X, inst = {}, {}
    for sd in (0.0, 2e-3):
        s = _tempco_sensors(sd)
        s = dataclasses.replace(s, probe=dataclasses.replace(s.probe, tempco_sweep=sweep))
        res = run_campaign(truth, _opts(soak=plan, sensors=s, speeds=(12000.0, 20000.0)),
                           tmp_path / str(sd), rng=np.random.default_rng(3))
        ds = open_dataset(res.dataset)
        X[sd] = {r["id"]: (r, demodulate(ds.load(r)).X[:, 0]) for r in ds.index}
        inst[sd] = json.loads((res.dataset / "dataset.json").read_text())["installation"]
    assert "tempco_per_K" not in inst[0.0]
    alpha = np.array([inst[2e-3]["tempco_per_K"][c] for c in SensorSet().probe_channels])
    assert np.all(alpha != 0) and {k: v for k, v in inst[2e-3].items()
                                   if k != "tempco_per_K"} == inst[0.0]
    n_soak = 0
    for rid, (row, x0) in X[0.0].items():
        speed = row["speed_rpm"]
        if row["kind"] == "soak":
            n_soak += 1
            dT = truth.thermal.rise_K(speed) * truth.thermal.fraction(row["labels"]["time_s"])
        elif row["kind"] == "steady":
            dT = truth.thermal.rise_K(speed) if sweep else 0.0
        else:
            continue
        np.testing.assert_allclose(X[2e-3][rid][1], x0 * (1 + alpha * dT), rtol=1e-9, atol=0)
    assert n_soak == 4 * len(TIMES)
    # the two-speed soak read back: a block per speed, its 2 runs (soak runs 0, 2 and 1, 3)
    blocks = soak_blocks(tmp_path / "0.002" / "dataset")
    assert [(b.speed_rpm, b.runs) for b in blocks] == [(12000.0, 2), (20000.0, 2)]
    assert [b.meta["runs"] for b in blocks] == [[[0, 0, REPEATS + 1], [0, 0, REPEATS + 3]],
                                                [[0, 0, REPEATS + 2], [0, 0, REPEATS + 4]]]
