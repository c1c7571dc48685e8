"""Bearing coefficients of the FE rotor from 1× phasors: against the FE model's own solution."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.identification import BatchLS, identify
from surrogate_rbrdo.identification.condensation import (
    condense_reactions,
    node_at,
    phasor_time_regression,
    trial_weight_difference,
)
from surrogate_rbrdo.identification.phasor import catalog_coefficients, identify_phasors
from surrogate_rbrdo.spindle import reference_spindle, unbalance_response
from surrogate_rbrdo.spindle.assembly import RPM
from surrogate_rbrdo.spindle.effects import Anisotropy, CrossCoupling

SPEEDS = np.array([5000.0, 15000.0, 24000.0])


@pytest.fixture(scope="module")
def model():
    """Reference spindle, Table-3 softening, rear bearing 10 % anisotropic: 8 distinct values."""
    sp = reference_spindle()
    return sp.model(sp.baseline, effects=sp.effects + (Anisotropy(bearings=("rear",), s=0.1),))


def _phasors(m, nodes, speeds=SPEEDS):
    q = unbalance_response(m, speeds)[0]
    return q[:, list(nodes), :2].reshape(len(speeds), -1)


@pytest.mark.known_answer
def test_noise_free_recovers_the_eight_coefficients(model):
    cr = condense_reactions(model, SPEEDS)
    truth = catalog_coefficients(model, SPEEDS)
    res = identify_phasors(cr, _phasors(model, model.bearing_nodes), SPEEDS, catalog=truth)
    is_k = np.array(["_k_" in n for n in res.names])
    err = np.abs(res.estimate / truth - 1.0)
    assert err[:, is_k].max() < 1e-8 and err[:, ~is_k].max() < 1e-6     # issue: 1e-4 / 1 %
    assert res.ok.all()
    assert truth[0, 4] != truth[0, 5]                                    # yy and zz differ


@pytest.mark.known_answer
def test_probes_away_from_bearings_expand_exactly(model):
    """Exact without noise; with probes 167 mm inboard of each bearing the same probe noise
    costs k about 2x more at 5 000 and 15 000 rpm (docs/identification.md has the table)."""
    probes = [node_at(model, 266.667), node_at(model, 433.333)]
    on = condense_reactions(model, SPEEDS)
    off = condense_reactions(model, SPEEDS, probe_nodes=probes)
    truth = catalog_coefficients(model, SPEEDS)
    q_on, q_off = _phasors(model, model.bearing_nodes), _phasors(model, probes)
    sigma = 1e-3 * np.abs(q_on).mean(axis=1, keepdims=True)          # same probe noise (m)
    res = identify_phasors(off, q_off, SPEEDS, phasor_sd=sigma)
    assert np.allclose(res.estimate, truth, rtol=1e-6)
    ref = identify_phasors(on, q_on, SPEEDS, phasor_sd=sigma)
    assert np.all(off.expansion_condition > 2 * on.expansion_condition)
    assert np.all(res.std[:2, [0, 4]] > 1.5 * ref.std[:2, [0, 4]])


@pytest.mark.known_answer
def test_trial_weight_runs_remove_an_unknown_residual_unbalance(model):
    U0 = [(int(model.unbalance_nodes[0]), 3e-5 * np.exp(0.7j)),
          (int(model.unbalance_nodes[1]), 1e-5 * np.exp(-2.0j))]
    trial = (int(model.unbalance_nodes[1]), 2e-5 + 0j)
    def run(unb):
        m = replace(model, unbalance_nodes=np.array([n for n, _ in unb]),
                    unbalance=np.array([u for _, u in unb]))
        return _phasors(m, model.bearing_nodes)
    dq = trial_weight_difference(run(U0 + [trial]), run(U0))
    cr = condense_reactions(model, SPEEDS, unbalance=[trial])
    res = identify_phasors(cr, dq, SPEEDS)
    assert np.allclose(res.estimate, catalog_coefficients(model, SPEEDS), rtol=1e-6)
    wrong = identify_phasors(condense_reactions(model, SPEEDS), run(U0), SPEEDS)
    assert not np.allclose(wrong.estimate, catalog_coefficients(model, SPEEDS), rtol=1e-2)


@pytest.mark.known_answer
def test_covariance_matches_monte_carlo(model):
    cr = condense_reactions(model, SPEEDS[2:])
    q = _phasors(model, model.bearing_nodes, SPEEDS[2:])
    std = 1e-3 * np.abs(q)
    lin = identify_phasors(cr, q, SPEEDS[2:], phasor_sd=std)
    rng = np.random.default_rng(0)
    n = 20000
    noise = (rng.normal(size=(n, 4)) + 1j * rng.normal(size=(n, 4))) * std   # sd per part
    mc = identify_phasors(cr, q + noise, np.full(n, SPEEDS[2]))
    assert np.allclose(np.std(mc.estimate, axis=0), lin.std[0], rtol=0.03)
    c_mc = np.cov(mc.estimate.T)[0, 4] / np.prod(np.std(mc.estimate, axis=0)[[0, 4]])
    c_lin = lin.covariance[0, 0, 4] / (lin.std[0, 0] * lin.std[0, 4])
    assert c_mc == pytest.approx(c_lin, abs=0.03)


@pytest.mark.known_answer
def test_cross_coupling_shows_up_as_a_damping_error():
    """With k_xy = κ k and near-circular forward orbits (y ≈ −i x), r/x = k + iΩc − i κ k:
    the diagonal model reads ĉ = c − κ k / Ω."""
    sp = reference_spindle()
    kappa = 0.002
    m = sp.model(sp.baseline, effects=sp.effects + (CrossCoupling(kappa=kappa),))
    speed = np.array([12000.0])
    res = identify_phasors(condense_reactions(m, speed), _phasors(m, m.bearing_nodes, speed),
                           speed)
    K, C = m.bearing_coefficients(speed[None] * RPM)
    k, c = K[0, 0, 0, 0, 0], C[0, 0, 0, 0, 0]
    assert res.estimate[0, 0] == pytest.approx(k, rel=0.05)
    assert res.estimate[0, 2] == pytest.approx(c - kappa * k / (speed[0] * RPM), rel=0.05)


def test_time_samples_give_the_phasor_solution(model):
    cr = condense_reactions(model, SPEEDS)
    x, r = cr.reactions(_phasors(model, model.bearing_nodes), SPEEDS)
    reg = phasor_time_regression(x, r, SPEEDS, n_samples=200)
    est = identify(reg, BatchLS(), theta0=[2e8, 800.0]).estimate.reshape(3, 2, 2, 2)
    truth = catalog_coefficients(model, SPEEDS).reshape(3, 2, 2, 2)     # (S, b, k|c, dir)
    assert np.allclose(est, truth.transpose(0, 1, 3, 2), rtol=1e-7)


def test_bad_data_is_flagged_or_refused(model):
    cr = condense_reactions(model, SPEEDS)
    q = _phasors(model, model.bearing_nodes)
    q[1, 1] = 0.0                                        # front journal: no y motion at 15 000
    cat = catalog_coefficients(model, SPEEDS)
    res = identify_phasors(cr, q, SPEEDS, catalog=cat * 3.0)   # truth = k_catalog / 3 < 0.5
    assert res.unexcited[1].tolist() == [False, True, False, True, False, False, False, False]
    assert np.isnan(res.estimate[1, 1]) and not res.ok[1]
    # outside the box: flagged, kept as identified (never clipped)
    assert res.outside_box[0].all() and np.allclose(res.estimate[0], cat[0], rtol=1e-6)
    assert "outside the box" in res.flags(0)[0] and res.usable(range(8))[0]
    assert res.flag_names()[1, 1] == "unexcited"
    with pytest.raises(ModelError, match="records flagged"):
        res.raise_if_flagged()
    with pytest.raises(ValueError, match="cannot determine"):
        condense_reactions(model, SPEEDS, probe_nodes=[0])
    with pytest.raises(ValueError, match="were not condensed"):
        identify_phasors(cr, q[:1], [7000.0])
    with pytest.raises(ValueError, match="no FE node within"):
        node_at(model, 123.4)


@pytest.mark.known_answer
def test_noise_only_direction_is_flagged_by_its_snr(model):
    """Review item 6: a journal direction that carries only noise (|x| ~ its noise) gave
    k_zz 1 400–4 800 x the truth with ok = True. With the noise level known, |x| < 5 σ_x is
    'unexcited' (the ratio r/x is then noise)."""
    speed = np.array([12000.0])
    cr = condense_reactions(model, speed)
    q = np.repeat(_phasors(model, model.bearing_nodes, speed), 4, axis=0)
    rng = np.random.default_rng(0)
    sd = 0.03e-9
    q = q + sd * (rng.standard_normal(q.shape) + 1j * rng.standard_normal(q.shape))
    q[:, 1] = sd * (rng.standard_normal(4) + 1j * rng.standard_normal(4))   # front y: noise
    res = identify_phasors(cr, q, np.repeat(speed, 4), phasor_sd=sd)
    assert res.unexcited[:, 1].all() and res.unexcited[:, 3].all()
    assert not res.unexcited[:, [0, 4, 5]].any() and not res.ok.any()
    assert np.isnan(res.estimate[:, 1]).all()


@pytest.mark.known_answer
def test_a_speed_near_a_pole_of_the_condensed_rotor_is_flagged(model):
    """The reference rotor with its journals pinned has a natural frequency at ~22 621 rpm
    (docs/identification.md): records there are flagged, records far from it are not."""
    sp = np.array([10000.0, 22600.0])
    cr = condense_reactions(model, sp)
    assert cr.pole_ratio[0] < 10 < 30 < cr.pole_ratio[1]
    res = identify_phasors(cr, _phasors(model, model.bearing_nodes, sp), sp)
    assert res.near_pole.tolist() == [False, True]
