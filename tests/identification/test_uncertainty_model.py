"""Identified vectors → uncertainty model → the study's random vector, with known truths."""

from __future__ import annotations

import json

import numpy as np
import pytest

from surrogate_rbrdo.identification.condensation import condense_reactions
from surrogate_rbrdo.identification.model import (
    IdentifiedUncertainty,
    load_uncertainty,
    model_reference,
    save_uncertainty,
    study_weights,
)
from surrogate_rbrdo.identification.phasor import catalog_coefficients, identify_phasors
from surrogate_rbrdo.identification.scatter import (
    fit_uncertainty,
    output_variance_share,
    variance_split,
)
from surrogate_rbrdo.identification.virtual import phasor_campaign
from surrogate_rbrdo.spindle import reference_spindle
from surrogate_rbrdo.uncertainty import MultivariateNormal

NAMES = ("front_k_yy", "front_k_zz", "rear_k_yy", "rear_k_zz")
SPEEDS = np.repeat(np.linspace(1000.0, 24000.0, 50), 20)


def _arrays(rng, phys=(0.015, 0.033), ident=0.005):
    """Quadratic trends, physical factors shared by yy/zz of a bearing, independent id noise."""
    s2 = (SPEEDS / 24000.0) ** 2
    trend = np.column_stack([3.2e8 * (1 - 0.15 * s2)] * 2 + [2.8e8 * (1 - 0.14 * s2)] * 2)
    e_true = 1 + np.repeat(rng.standard_normal((SPEEDS.size, 2)) * phys, 2, axis=1)
    e_id = ident * rng.standard_normal((SPEEDS.size, 4))
    return trend, trend * e_true, trend * (e_true + e_id)


@pytest.mark.known_answer
def test_scatter_trend_and_split_recovered_from_arrays():
    rng = np.random.default_rng(0)
    trend, truth, values = _arrays(rng)
    cov_rec = np.broadcast_to(np.diag([0.005**2] * 4), (SPEEDS.size, 4, 4)) \
        * (trend[:, :, None] * trend[:, None, :])
    u = fit_uncertainty(values, SPEEDS, NAMES, per_record_cov=cov_rec, truth=truth)
    assert u.names == ("front", "rear")
    assert all(t.law == "quadratic" for t in u.trends)
    # physical std 1.5 % / 3.3 % and 0.5 % identification noise: total √(σp² + σi²)
    expect = np.sqrt(np.array([0.015, 0.015, 0.033, 0.033]) ** 2 + 0.005**2)
    assert np.allclose(np.sqrt(np.diag(u.scatter_cov)), expect, rtol=0.06)
    frac = 0.005**2 / expect**2
    for route in ("measured", "estimated"):
        got = np.array(u.variance_split[route]["identification_fraction"])
        assert np.allclose(got, frac, atol=0.03), route
    # the study's θ: the mean of yy and zz halves the identification variance
    assert np.allclose(np.sqrt(np.diag(u.cov)),
                       np.sqrt(np.array([0.015, 0.033]) ** 2 + 0.005**2 / 2), rtol=0.06)
    # pooled variance = variance of the trend over the speeds + the scatter (Table 4's problem)
    pooled = np.var(trend, axis=0) + np.mean(trend**2, axis=0) * expect**2
    assert np.allclose(np.diag(u.pooled_cov), pooled, rtol=0.1)


def test_physical_scatter_removes_identification_error():
    rng = np.random.default_rng(1)
    _, truth, values = _arrays(rng, ident=0.02)
    u = fit_uncertainty(values, SPEEDS, NAMES, truth=truth, scatter="physical")
    assert np.allclose(np.sqrt(np.diag(u.cov)), [0.015, 0.033], rtol=0.08)
    with pytest.raises(ValueError, match="scatter = 'physical' is not allowed"):
        fit_uncertainty(values, SPEEDS, NAMES, scatter="physical")


@pytest.mark.known_answer
def test_random_vector_known_answer():
    """Constant trends: θ_b = (k̄_yy e_yy + k̄_zz e_zz) / (2 k_ref) is linear in e."""
    rng = np.random.default_rng(2)
    k = np.column_stack([2e8, 3e8]) * (1 + 0.01 * rng.standard_normal((400, 2)))
    n = np.repeat(np.linspace(1000, 24000, 20), 20)
    u = fit_uncertainty(k, n, ("a_k_yy", "a_k_zz"), law="constant")
    rv = u.random_vector(12000.0, reference=[2.5e8], trend_uncertainty=False)
    kbar = k.mean(axis=0)                          # constant trends = column means, so e = k/k̄
    Wd = 0.5 * kbar[None, :] / 2.5e8
    assert rv.mean[0] == pytest.approx(0.5 * kbar.sum() / 2.5e8, rel=1e-12)
    assert np.allclose(rv.cov, Wd @ np.cov(k / kbar, rowvar=False) @ Wd.T, rtol=1e-10)
    wider = u.random_vector(12000.0, reference=[2.5e8])
    assert wider.cov[0, 0] > rv.cov[0, 0]
    absolute = u.random_vector(12000.0)
    assert absolute.mean[0] == pytest.approx(2.5e8 * rv.mean[0])


def test_json_round_trip_and_loader_errors(tmp_path):
    rng = np.random.default_rng(3)
    _, _, values = _arrays(rng)
    u = fit_uncertainty(values, SPEEDS, NAMES, law="power", provenance={"source": "test"})
    path = save_uncertainty(u, tmp_path / "uncertainty.json")
    d = json.loads(path.read_text())
    assert d["names"] == ["front", "rear"] and len(d["cov"]) == 2
    assert d["trend"]["front_k_yy"]["law"] == "power"
    v = load_uncertainty(tmp_path)                                   # a run folder works too
    a, b = u.random_vector(15000.0), v.random_vector(15000.0)
    assert isinstance(b, MultivariateNormal)
    assert np.allclose(a.mean, b.mean, rtol=1e-14) and np.allclose(a.cov, b.cov, rtol=1e-12)
    with pytest.raises(ValueError, match="does not exist"):
        load_uncertainty(tmp_path / "nope.json")
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"format": "x"}))
    with pytest.raises(ValueError, match="bad.json: format = 'x'"):
        load_uncertainty(bad)
    del d["factors"]
    with pytest.raises(ValueError, match="missing field 'factors'"):
        IdentifiedUncertainty.from_dict(d)
    with pytest.raises(ValueError, match="reference"):
        u.random_vector(15000.0, reference=[1.0])


def test_study_weights_and_variance_share():
    names, W = study_weights(NAMES, "stiffness")
    assert names == NAMES and np.array_equal(W, np.eye(4))
    with pytest.raises(ValueError, match="no stiffness"):
        study_weights(("front_c_yy",))
    split = variance_split(np.random.default_rng(0).normal(size=(50, 2)))
    assert set(split) == {"total_var"}
    assert output_variance_share([0.0, 1.0], np.eye(2) * 0.03, np.eye(2)) == pytest.approx(0.03)


@pytest.mark.known_answer
def test_fe_campaign_chain_recovers_truth_trend_and_scatter():
    """50 speeds × 20 repeats of the reference spindle (Table-3 power law), physical scatter
    1.5 % / 3.3 %, 0.014 nm phasor noise per part (0.02 nm complex RMS; at 1 000 rpm the rear
    journal moves 0.12 nm): identified trend within 3 SE of the truth's law,
    scatter of θ within 10 %, and the study's θ relative to the model's nominal ≈ 1."""
    sp = reference_spindle()
    m = sp.model(sp.baseline)
    speeds = np.linspace(1000.0, 24000.0, 50)
    camp = phasor_campaign(m, speeds, 20, theta_std=[0.015, 0.033], noise_m=0.014e-9,
                           rng=np.random.default_rng(4))
    res = identify_phasors(condense_reactions(m, speeds), camp.phasors, camp.speeds_rpm,
                           phasor_sd=camp.noise_m,
                           catalog=catalog_coefficients(m, camp.speeds_rpm))
    k = [0, 1, 4, 5]
    ok = ~(res.at_bound[:, k].any(1) | res.unexcited[:, k].any(1))
    assert ok.mean() > 0.99
    u = fit_uncertainty(res.estimate[ok][:, k], camp.speeds_rpm[ok],
                        [res.names[j] for j in k], per_record_cov=res.covariance[ok][:, k][:, :, k],
                        truth=camp.truth[ok][:, k])
    for s in (2000.0, 12000.0, 23000.0):
        ref = catalog_coefficients(m, [s])[0, k]
        se = np.array([t.predict_std(s) for t in u.trends])
        assert np.all(np.abs(u.trend(s) - ref) < 3 * se + 1e-3 * ref)
        rv = u.random_vector(s, reference=model_reference(m, s, u.names))
        assert np.allclose(rv.mean, 1.0, atol=0.01)
    meas = u.variance_split["measured"]
    phys = np.sqrt(meas["physical_var"])
    assert np.allclose(phys, [0.015, 0.015, 0.033, 0.033], rtol=0.1)
    est = np.array(u.variance_split["estimated"]["identification_fraction"])
    # first-order covariances vs the measured split (at 1 000 rpm the noise is 4 % of |x|)
    assert np.allclose(est, meas["identification_fraction"], atol=0.08)


def test_identify_campaign_table_flags_and_model():
    from surrogate_rbrdo.identification import identify_campaign

    sp = reference_spindle()
    m = sp.model(sp.baseline)
    camp = phasor_campaign(m, np.linspace(5000.0, 24000.0, 8), 12, theta_std=[0.015, 0.03],
                           noise_m=1e-11, rng=np.random.default_rng(5))
    ph = camp.phasors.copy()
    ph[3, 0] = 0.0                                   # front x not excited in record 3
    out = identify_campaign(m, camp.speeds_rpm, camp.repeats, ph, phasor_sd=camp.noise_m,
                            truth=camp.truth)
    assert out.n_used == camp.speeds_rpm.size - 1 and not out.table["ok"][3]
    assert "not excited" in out.table["flags"][3] and out.flag_counts["unexcited"] == 1
    assert np.isnan(out.table["front_k_yy"][3])
    assert set(out.table) >= {"speed_rpm", "repeat", "front_k_yy", "rear_c_zz", "ok", "flags"}
    assert out.uncertainty.provenance["records_used"] == out.n_used
    assert out.uncertainty.coefficients == NAMES
    with pytest.raises(ValueError, match="fit_on = 'c'"):
        identify_campaign(m, camp.speeds_rpm, camp.repeats, ph, fit_on="c")
