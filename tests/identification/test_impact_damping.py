"""Bearing damping from the rig's impact tests (``identification.impact``,
``identification.damping``): FRF-based model updating against the rig's known truth (each
build's damping factors, the tool change's mass factor, the run's bearing stiffness), and
``damping = "impact"`` in an identification run."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy import stats

from surrogate_rbrdo.identification import IdentificationOptions, identify_records
from surrogate_rbrdo.identification.experiment import check_source
from surrogate_rbrdo.identification.impact import ImpactOptions, impact_damping
from surrogate_rbrdo.identification.rigtruth import record_state, truth_coefficients
from surrogate_rbrdo.identification.updating import StandstillModel
from surrogate_rbrdo.rig import CampaignOptions, open_dataset, reference_truth, run_campaign
from surrogate_rbrdo.rig.records import RecordError
from surrogate_rbrdo.rig.sensors import AccelerometerModel, HammerModel, SensorSet
from surrogate_rbrdo.spindle import reference_spindle

TRIAL = (0.0, 5e-5, 0.0)


@pytest.fixture(scope="module")
def model():
    sp = reference_spindle()
    return sp.model(sp.baseline)


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    """The rig with its noise off, a random build (damping factors CoV 20 %), tool (mass 3 %)
    and thermal states: 3 speeds (22 000 rpm is 620 rpm from the condensed rotor's pole) × 2
    runs with and without a trial mass, one hit per direction at the tool."""
    path = tmp_path_factory.mktemp("impact_rig")
    truth = reference_truth()
    run_campaign(truth, CampaignOptions(speeds_rpm=(6000.0, 12000.0, 22000.0), repeats=2,
                                        runup=None, impacts_per_direction=1,
                                        trial_unbalance=TRIAL, sensors=SensorSet(noise=False)),
                 path, rng=np.random.default_rng(5))
    ds = open_dataset(path / "dataset")
    return path, truth, ds, [ds.load(r) for r in ds.index if r["kind"] == "impact"]


@pytest.mark.known_answer
def test_noise_free_impacts_give_the_damping_of_an_identification_run(rig, model):
    """``damping = "impact"``, ``tool_mass = "impact"`` on the noise-free rig: η of both
    bearings within 0.5 % (the rig's FRF is within ~3e-4 of its truth's model since the
    recorded force is the one the integrator applied), the standstill stiffness factors within
    0.5 % and the tool mass within 2e-4; the reactions condensed with the weighed tool mass
    give k within 1e-4 at every speed (with the model's nominal tool mass the hidden 3 %
    scatter costs up to 1e-2); every record's c = η̂ k̂ within 1 % of its true c (the issue's
    noise-free bound); the uncertainty model's provenance names the source and η̂ per
    installation."""
    path, truth, ds, recs = rig
    run = identify_records(model, path, IdentificationOptions(
        damping="impact", tool_mass="impact", n_boot=20, max_rel_se=1e9),
        rng=np.random.default_rng(0))
    dmp = run.uncertainty.provenance["damping"]
    assert dmp["source"] == "impact" and list(dmp["installations"]) == ["build=0|tool=0"]
    got = dmp["installations"]["build=0|tool=0"]
    d = recs[0].provenance["truth_draws"]
    np.testing.assert_allclose(got["eta_s"], 4e-6 * np.array(d["build"]["damping_factor"]),
                               rtol=5e-3)
    par = got["parameters"]
    for ax in ("x", "y"):            # the truth's bearings are isotropic here
        np.testing.assert_allclose([par[f"front_stiffness_{ax}"], par[f"rear_stiffness_{ax}"]],
                                   record_state(truth, recs[0].provenance).theta[0], rtol=5e-3)
    assert par["tool_mass"] == pytest.approx(d["tool"]["mass_factor"], rel=2e-4)
    prov = {r["id"]: ds.load(r).provenance for r in ds.index}
    ids = [i.split("|")[1] for i in run.responses.record_ids]
    true = truth_coefficients(truth, [prov[i] for i in ids], run.responses.speed_rpm)
    c = [2, 3, 6, 7]
    est = run.campaign.identification.estimate
    np.testing.assert_allclose(est[:, c], true[:, c], rtol=0.01)
    np.testing.assert_allclose(est[:, [0, 1, 4, 5]], true[:, [0, 1, 4, 5]], rtol=1e-4)
    assert run.provenance["tool_mass_factor"]["factor"] == pytest.approx(
        d["tool"]["mass_factor"], rel=2e-4)
    np.testing.assert_allclose(run.campaign.table["front_c_yy"], est[:, 2])
    eta = np.array(got["eta_s"])
    np.testing.assert_allclose(est[:, c], est[:, [0, 1, 4, 5]] * eta[[0, 0, 1, 1]])


def test_impact_damping_bad_inputs(rig, model, tmp_path):
    _, _, ds, recs = rig
    run_campaign(reference_truth(), CampaignOptions(
        speeds_rpm=(8000.0,), repeats=1, runup=None, impacts_per_direction=0,
        trial_unbalance=TRIAL, sensors=SensorSet(noise=False)), tmp_path,
        rng=np.random.default_rng(1))
    with pytest.raises(ValueError, match="damping = 'impact' is not allowed.*no impact"):
        check_source(tmp_path, IdentificationOptions(damping="impact"))
    steady = [ds.load(r) for r in ds.index if r["kind"] == "steady"]
    with pytest.raises(RecordError, match="hammer"):
        impact_damping(model, steady[:1])
    with pytest.raises(ValueError, match="band_hz"):
        impact_damping(model, recs, ImpactOptions(band_hz=(5.0, 10.0)))
    with pytest.raises(ValueError, match="tool_disk"):
        impact_damping(model, recs, ImpactOptions(tool_disk="no_such_disk"))
    with pytest.raises(ValueError, match="band_hz"):
        ImpactOptions(band_hz=(300.0, 200.0))
    with pytest.raises(ValueError, match="damping"):
        IdentificationOptions(damping="modal")


def test_frf_derivatives_match_finite_differences(model):
    """The FRF fit's analytic Jacobian (bearing stiffness and damping factors, tool mass with
    its mass-proportional damping) against central differences of the accelerance."""
    up = StandstillModel(model, "tool_holder")
    s = 2j * np.pi * np.linspace(200.0, 2000.0, 40) + 4.6
    dof = np.full(s.size, 4 * model.tool_node + 1)
    p = np.log([1.0, 1.1, 0.9, 1.2, 1.02])

    def frf(q):
        return up.accelerance(np.exp(q[:2]), np.exp(q[2:4]), float(np.exp(q[4])), s, dof)

    _, jac = frf(p)
    for k in range(p.size):
        dp = np.zeros(p.size)
        dp[k] = 1e-6
        fd = (frf(p + dp)[0] - frf(p - dp)[0]) / 2e-6
        assert np.max(np.abs(fd - jac[:, k])) < 1e-4 * np.max(np.abs(jac[:, k]))


@pytest.mark.slow
@pytest.mark.known_answer
def test_impact_damping_at_the_rigs_default_noise_over_seeds(tmp_path, model):
    """At the rig's default noise (5 hits per direction, gains, skews, quantisation) over 6
    random builds: η's RMS error below 1 % (front) and 8 % (rear), against 0.36 % and 4.2 %
    measured over 20 seeds by ``benchmarks/bench_identification_impact.py`` — the rear bearing's
    mode is weakly seen at the tool."""
    errs = []
    for seed in range(6):
        path = tmp_path / f"s{seed}"
        run_campaign(reference_truth(), CampaignOptions(
            speeds_rpm=(10000.0,), repeats=1, runup=None, impacts_per_direction=5), path,
            rng=np.random.default_rng(500 + seed))
        ds = open_dataset(path / "dataset")
        recs = [ds.load(r) for r in ds.index if r["kind"] == "impact"]
        eta = 4e-6 * np.array(recs[0].provenance["truth_draws"]["build"]["damping_factor"])
        errs.append(impact_damping(model, recs).eta_s / eta - 1)
    rms = np.sqrt(np.mean(np.square(errs), axis=0))
    assert rms[0] < 0.01 and rms[1] < 0.08, rms


@pytest.mark.known_answer
def test_anisotropic_bearings_are_updated_per_direction(tmp_path, model):
    """A truth whose bearings are 5 % stiffer in one direction and 5 % softer in the other
    (``anisotropy``, s = 0.05; the model's bearings are isotropic), noise off: each direction's
    standstill stiffness factors recover the truth's ``θ (1 ± s)`` within 0.5 % and η within
    2 % (one stiffness for both directions left η 40 % / 100 % off on the shipped campaign:
    the split peaks were fitted as one broad one)."""
    s_an = 0.05
    truth = reference_truth(hidden=[{"name": "anisotropy", "s": s_an}])
    run_campaign(truth, CampaignOptions(speeds_rpm=(10000.0,), repeats=1, runup=None,
                                        impacts_per_direction=1,
                                        sensors=SensorSet(noise=False)),
                 tmp_path, rng=np.random.default_rng(11))
    ds = open_dataset(tmp_path / "dataset")
    recs = [ds.load(r) for r in ds.index if r["kind"] == "impact"]
    d = recs[0].provenance["truth_draws"]
    with pytest.warns(UserWarning, match="one hit in direction"):   # noise-free: one hit
        res = impact_damping(model, recs)
    theta = record_state(truth, recs[0].provenance).theta[0]
    for ax, sign in (("x", 1.0), ("y", -1.0)):
        got = [res.factor(f"{b}_stiffness_{ax}") for b in ("front", "rear")]
        np.testing.assert_allclose(got, theta * (1 + sign * s_an), rtol=5e-3)
    np.testing.assert_allclose(res.eta_s, 4e-6 * np.array(d["build"]["damping_factor"]),
                               rtol=0.02)


def _impacts(path, truth, seed, hits, duration_s=1.0, sensors=None):
    run_campaign(truth, CampaignOptions(speeds_rpm=(10000.0,), repeats=1, runup=None,
                                        impacts_per_direction=hits,
                                        impact_duration_s=duration_s,
                                        sensors=sensors or SensorSet()), path,
                 rng=np.random.default_rng(seed))
    ds = open_dataset(path / "dataset")
    return [ds.load(r) for r in ds.index if r["kind"] == "impact"]


def _scaled(scale):
    """The rig's sensors with the hammer's and the accelerometer's noise scaled by ``scale``
    (skews, gains and quantisation as by default)."""
    return SensorSet(hammer=HammerModel(noise_N=0.2 * scale),
                     accelerometer=AccelerometerModel(noise_rms_ms2=0.00015 * 9.80665 * scale))


@pytest.mark.known_answer
def test_fitted_delays_are_the_rigs_channel_skews_at_low_noise(tmp_path, model):
    """At 0.03× the rig's hammer and accelerometer noise (3 hits of 0.5 s), where a gain-only
    fit read the DAQ's unknown per-channel timing skew (0.2 µs) as model error (χ²/ν up to 21)
    and biased the rear η by −6.5 %: each direction's fitted delay is the truth's skew of the
    hammer channel minus the accelerometer's (``sensor_installation``) within 0.1 µs, the right
    model is not flagged, and η is within 3 % (front 0.5 %)."""
    recs = _impacts(tmp_path, reference_truth(), 6001, 3, 0.5, _scaled(0.03))
    res = impact_damping(model, recs)
    skew = recs[0].provenance["sensor_installation"]["skew_s"]
    for d in ("x", "y"):
        assert abs(res.factor(f"delay_{d}") - (skew["hammer"] - skew[f"tool_a{d}"])) < 1e-7
    assert not res.lack_of_fit.flagged, res.lack_of_fit
    eta = 4e-6 * np.array(recs[0].provenance["truth_draws"]["build"]["damping_factor"])
    assert np.all(np.abs(res.eta_s / eta - 1) < [5e-3, 0.03]), res.eta_s / eta - 1


@pytest.mark.known_answer
def test_lack_of_fit_flags_a_hidden_tool_interface_and_not_a_right_model(tmp_path, model):
    """3 hits of 0.5 s per direction, tests at a 1 % false-alarm level
    (``lack_of_fit_level``): at the rig's default noise a truth the model can represent (the
    default build, tool and thermal draws) passes, and a truth with a tool-interface
    compliance the experimenter's model lacks (k_t = 3e8 N/m, k_r = 5e6 N m/rad, as
    ``experiments/rig_campaign_trial.toml`` hides) is flagged with a warning — the model error
    that made η̂ 21 % low on the shipped campaign without anything saying so; noise-free
    hits (identical: the jackknife sees no scatter) are not flagged and keep an SE."""
    ok = impact_damping(model, _impacts(tmp_path / "ok", reference_truth(), 2001, 3, 0.5))
    assert ok.covariance_kind == "jackknife" and ok.n_replicates == 3
    assert not ok.lack_of_fit.flagged, ok.lack_of_fit
    hidden = reference_truth(hidden=[{"name": "tool_interface", "k_t_N_per_m": 3e8,
                                      "k_r_Nm_per_rad": 5e6}])
    recs = _impacts(tmp_path / "bad", hidden, 2001, 3, 0.5)
    with pytest.warns(UserWarning, match="lack of fit"):
        bad = impact_damping(model, recs)
    assert bad.lack_of_fit.flagged and bad.to_dict()["lack_of_fit"]["flagged"]
    # noise-free hits are identical: no scatter to refer to, the model's accuracy floor holds
    nf = impact_damping(model, _impacts(tmp_path / "nf", reference_truth(), 2001, 3, 0.5,
                                        SensorSet(noise=False)))
    assert not nf.lack_of_fit.flagged and np.all(nf.eta_rel_se > 0), nf.lack_of_fit


@pytest.mark.slow
@pytest.mark.known_answer
def test_model_error_tests_false_alarms_and_power_over_noise_levels(tmp_path, model):
    """Over 10 rigs (3 hits of 0.5 s) at 0.03×, 1× and 10× the rig's hammer and
    accelerometer noise: right models are flagged no more often than a 1 % false-alarm level
    allows (at most 1 of 10 at each level: 2 or more has probability 0.004), and the hidden
    tool interface is flagged in at least 8 of 10 at the default noise (measured on seeds
    4001–4012: 12 of 12). At 10× nothing is asserted: neither test has power there (measured
    1 of 12; docs/identification.md §5b)."""
    hidden = reference_truth(hidden=[{"name": "tool_interface", "k_t_N_per_m": 3e8,
                                      "k_r_Nm_per_rad": 5e6}])
    for label, truth, scale, bound in (("ok", reference_truth(), 0.03, 1),
                                       ("ok", reference_truth(), 1.0, 1),
                                       ("ok", reference_truth(), 10.0, 1),
                                       ("bad", hidden, 1.0, 8)):
        flags = []
        for seed in range(7001, 7011):
            recs = _impacts(tmp_path / f"{label}{scale}_{seed}", truth, seed, 3, 0.5,
                            _scaled(scale))
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                flags.append(impact_damping(model, recs).lack_of_fit.flagged)
        n = int(np.sum(flags))
        assert (n <= bound) if label == "ok" else (n >= bound), (label, scale, flags)


@pytest.mark.slow
@pytest.mark.known_answer
def test_jackknife_standard_error_of_eta_covers_over_seeds(tmp_path, model):
    """The reported SE of η̂ (delete-one-hit jackknife, 5 hits per direction) against the
    build's true η over 20 random rigs at the default noise: the number of rigs whose 95 %
    t(4) interval covers the truth is not below what a true 95 % coverage gives with
    probability 1 % (binomial: at least 16 of 20; the model-based SE from H1's coherence
    covered 0.42 and 0.75 before the delay was fitted)."""
    z = []
    for seed in range(20):
        recs = _impacts(tmp_path / f"s{seed}", reference_truth(), 3000 + seed, 5)
        res = impact_damping(model, recs)
        eta = 4e-6 * np.array(recs[0].provenance["truth_draws"]["build"]["damping_factor"])
        z.append(np.log(res.eta_s / eta) / res.eta_rel_se)
    covered = np.sum(np.abs(z) <= stats.t.ppf(0.975, 4), axis=0)
    assert np.all(stats.binom.cdf(covered, 20, 0.95) >= 0.01), covered
