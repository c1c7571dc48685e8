"""Physics-structured surrogate: the SDOF flank shape against the closed-form unbalance
response, the combination rule, sub-model interpolation (checked through smt's own predict),
the separable grid path, config validation and a tiny FE run (counted, cached apart)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from surrogate_rbrdo.core.counting import CallCounter
from surrogate_rbrdo.core.protocols import LimitState
from surrogate_rbrdo.sampling.fe import fe_cache
from surrogate_rbrdo.spindle.evaluate import ResponseSpec
from surrogate_rbrdo.spindle.reference import reference_spindle
from surrogate_rbrdo.surrogates.structured import (
    GlobalOptions,
    ResonanceOptions,
    ResonanceSurrogate,
    band_points,
    fit_resonance_surrogate,
    surrogate_options,
    train_surrogate,
)
from surrogate_rbrdo.surrogates.structured.sdof import (
    combine,
    combine_bg_only,
    rho,
    rho_env,
    select_local,
    select_nc,
    zeta_from_ratio,
)
from surrogate_rbrdo.uncertainty import MultivariateNormal

N_MAX = 24000.0


def _sdof_unbalance(omega, k=4e7, M=12.0, zeta=0.004, me=1e-5):
    """|X| of M x'' + c x' + k x = m e ω² e^{iωt} (complex arithmetic, independent of rho)."""
    c = 2 * zeta * np.sqrt(k * M)
    return np.abs(me * omega**2 / (k - M * omega**2 + 1j * c * omega))


@pytest.mark.known_answer
@pytest.mark.parametrize("zeta", [0.002, 0.004, 0.05])
def test_rho_is_the_normalised_sdof_unbalance_response(zeta):
    k, M = 4e7, 12.0
    wn = np.sqrt(k / M)
    w = wn * np.linspace(0.2, 2.0, 200001)
    amp = _sdof_unbalance(w, k, M, zeta)
    r_pk = 1 / np.sqrt(1 - 2 * zeta**2)
    peak = _sdof_unbalance(wn * r_pk, k, M, zeta)
    r = w / wn
    assert np.allclose(rho(r, zeta), amp / peak, rtol=1e-9, atol=0)
    # the sampled maximum is at r_pk (to the grid step) and does not exceed the peak
    assert abs(r[np.argmax(amp)] - r_pk) < 1e-5 and amp.max() <= peak * (1 + 1e-12)
    # A_top / A_res at r = 0.98: the flank ratio the surrogate inverts
    i = np.argmin(np.abs(r - 0.98))
    assert rho(r[i], zeta) == pytest.approx(amp[i] / peak, rel=1e-6)


@pytest.mark.known_answer
def test_rho_env_is_running_max_and_zeta_inverts_rho():
    r = np.linspace(0.5, 1.5, 100001)
    for z in (0.003, 0.02):
        assert np.allclose(rho_env(r, z), np.maximum.accumulate(rho(r, z)), atol=1e-9)
    rr, zz = np.meshgrid([0.5, 0.9, 0.97, 0.99, 1.03, 1.5], [1e-4, 0.003, 0.01, 0.05])
    assert np.allclose(zeta_from_ratio(rho(rr, zz), rr), zz, rtol=1e-9)


@pytest.mark.known_answer
def test_combination_rule_known_values():
    ares, bg = np.array(30e-6), np.array(1e-6)
    # resonance in the range: the resonance height itself
    assert combine(np.array(20000.0), ares, 0.003, bg, N_MAX) == pytest.approx(30e-6)
    # resonance above the range (r = n_max / n_c = 0.98): A_res · ρ(r, ζ) written out
    r = 0.98
    expect = 30e-6 * (r**2 / np.sqrt((1 - r**2) ** 2 + (2 * 0.003 * r) ** 2)) \
        * 2 * 0.003 * np.sqrt(1 - 0.003**2)
    assert combine(np.array(N_MAX / r), ares, 0.003, bg, N_MAX) == pytest.approx(expect)
    # far below: the background wins; no background: the flank
    assert combine(np.array(N_MAX / 0.6), ares, 0.003, bg, N_MAX) == pytest.approx(1e-6)
    assert combine(np.array(N_MAX / 0.6), ares, 0.003, None, N_MAX) < 1e-6
    # between r = 1 and the peak ratio 1/sqrt(1-2ζ²) the envelope is still the flank (< A_res)
    assert combine(np.array(N_MAX), ares, 0.003, None, N_MAX) < 30e-6
    assert combine(np.array(N_MAX / 1.0001), ares, 0.003, None, N_MAX) == pytest.approx(30e-6)
    # broadcasting over a (P, N) grid with scalar ζ
    g = combine(np.full((2, 3), 20000.0), np.full((2, 3), 3e-5), 0.003, None, N_MAX)
    assert g.shape == (2, 3) and np.allclose(g, 3e-5)


def _synthetic(n=48, seed=0):
    rng = np.random.default_rng(seed)
    Z = rng.random((n, 5)) * [2000, 450, 30, 0.5, 0.5] + [1000, 300, 50, 0.75, 0.75]
    u = (Z - [1000, 300, 50, 0.75, 0.75]) / [2000, 450, 30, 0.5, 0.5]
    nc = N_MAX * np.exp(0.35 * (u[:, 2] - u[:, 1]) + 0.05 * u[:, 3])
    ares = 30e-6 * np.exp(0.3 * u[:, 2] - 0.2 * u[:, 0])
    zeta = 0.003 * np.exp(0.2 * u[:, 4])
    atop = ares * rho(N_MAX / nc, zeta)
    bg = 0.8e-6 * np.exp(0.5 * u[:, 0])
    y = combine(nc, ares, zeta, bg, N_MAX)
    return Z, np.column_stack([nc, ares, atop, y])


@pytest.fixture(scope="module")
def synth():
    Z, Q = _synthetic()
    cfg = ResonanceOptions(n_start=1, res_zeta_min_points=5,
                          res_zeta_r_min=0.7, res_bg_r_max=0.95, res_ares_r_min=0.0)
    return fit_resonance_surrogate(Z, Q, cfg, rng=np.random.default_rng(1), n_max_rpm=N_MAX), Z, Q


def test_sub_models_interpolate_their_training_data(synth):
    sur, Z, Q = synth
    assert set(sur.subs) == {"nc", "ares", "bg", "zeta"}
    r = N_MAX / Q[:, 0]
    targets = {"nc": Q[:, 0], "ares": Q[:, 1], "bg": Q[:, 3],
               "zeta": zeta_from_ratio(Q[:, 2] / Q[:, 1], r)}
    for k, s in sur.subs.items():
        rows = sur.rows[k]
        smt_pred = s.model.model_.predict_values(Z[rows]).ravel()   # smt's own path
        assert np.allclose(np.exp(smt_pred), targets[k][rows], rtol=1e-5), k
    assert sur.rows["bg"].size == int(np.sum(r <= 0.95))
    # the recovered ζ at the flank points is the one the data were made with
    u4 = (Z[sur.rows["zeta"], 4] - 0.75) / 0.5
    assert np.allclose(targets["zeta"][sur.rows["zeta"]], 0.003 * np.exp(0.2 * u4), rtol=1e-7)


def test_grid_response_equals_combination_of_smt_predictions(synth):
    sur, Z, _ = synth
    rng = np.random.default_rng(5)
    x = Z[:4, :3] + rng.normal(0, 1, (4, 3))
    theta = 1.0 + 0.05 * rng.standard_normal((6, 2))
    grid = sur.response(x, theta)
    joint = np.column_stack([np.repeat(x, 6, axis=0), np.tile(theta, (4, 1))])
    smt = {k: np.exp(s.model.model_.predict_values(joint).ravel()) for k, s in sur.subs.items()}
    ref = combine(smt["nc"], smt["ares"], smt["zeta"], smt["bg"], N_MAX).reshape(4, 6)
    assert grid.shape == (4, 6) and np.allclose(grid, ref, rtol=1e-7)
    assert np.allclose(sur.response_points(joint).reshape(4, 6), ref, rtol=1e-7)
    # θ blocks cached per sub-model: a second call with the same θ object builds none
    builds = sur.theta_block_builds
    sur(x[:2], theta)
    assert sur.theta_block_builds == builds
    # training points: the combined response reproduces y (every sub-model interpolates)
    both = np.intersect1d(sur.rows["bg"], sur.rows["zeta"])
    assert both.size >= 1
    assert np.allclose(sur.response_points(Z[both]), _synthetic()[1][both, 3], rtol=1e-4)


def test_predict_moments_and_loo(synth):
    sur, Z, Q = synth
    p = sur.predict(Z[:10])
    med = sur.response_points(Z[:10])
    assert np.all(p.std >= 0) and np.all(p.mean >= med * (1 - 1e-12))
    y_true, y_loo = sur.loo_points()
    assert np.array_equal(y_true, Q[:, 3]) and y_loo.shape == y_true.shape
    assert np.all(np.isfinite(y_loo)) and not np.allclose(y_loo, y_true, rtol=1e-6)


def test_band_points_lie_on_the_boundaries():
    Z, Q = _synthetic(60, seed=3)
    bounds = np.array([[1000, 3000], [300, 750], [50, 80], [0.75, 1.25], [0.75, 1.25]], float)
    cfg = ResonanceOptions(res_n_band=8, res_band=0.03, res_band_n_start=1,
                           res_band_pool=4000, res_n_band_lim=5, res_band_lim=0.05)
    pts = band_points(Z, Q[:, 0], bounds, N_MAX, cfg, rng=np.random.default_rng(2))
    assert pts.shape == (8, 5)

    def truth(P):
        u = (P - bounds[:, 0]) / (bounds[:, 1] - bounds[:, 0])
        nc = N_MAX * np.exp(0.35 * (u[:, 2] - u[:, 1]) + 0.05 * u[:, 3])
        return nc, 30e-6 * np.exp(0.3 * u[:, 2] - 0.2 * u[:, 0])

    nc, _ = truth(pts)
    assert np.all(np.abs(N_MAX / nc - 1) <= 0.03 + 2e-3)
    # distinct, and spread (greedy maximin): no two closer than 0.05 of the unit box
    u = (pts - bounds[:, 0]) / (bounds[:, 1] - bounds[:, 0])
    d = np.sqrt(((u[:, None] - u[None]) ** 2).sum(-1)) + np.eye(8)
    assert d.min() > 0.05
    thr = 30e-6
    lim = band_points(Z, Q[:, 0], bounds, N_MAX, cfg, rng=np.random.default_rng(2),
                      amp_res_m=Q[:, 1], threshold_m=thr)
    nc, ares = truth(lim)
    assert lim.shape == (5, 5)
    assert np.all(N_MAX / nc >= 1 - 2e-3) and np.all(np.abs(np.log(ares / thr)) <= 0.06)


@pytest.mark.parametrize("over, match", [
    ({"structure": "bogus"}, r"structure = 'bogus' is not allowed.*global.*resonance"),
    ({"structure": "resonance", "active_learning": True},
     r"unknown key surrogate.active_learning; allowed: \[.*'res_band'"),
    ({"structure": "resonance", "transform": "none"}, r"unknown key surrogate.transform"),
    ({"res_band": 0.0}, "res_band = 0.0"),
    ({"res_n_band": -1}, "res_n_band = -1"),
    ({"res_bg_r_max": 1.5}, "res_bg_r_max = 1.5"),
    ({"res_nc_local": -0.1}, "res_nc_local = -0.1"),
    ({"res_ares_local": -0.1}, "res_ares_local = -0.1"),
    ({"res_bg_only_r": 0.97}, r"res_bg_only_r = 0.97 is not allowed.*res_bg_r_max = 0.95"),
])
def test_config_validation(over, match):
    with pytest.raises(ValueError, match=match):
        surrogate_options({"structure": "resonance", **over}, ResponseSpec(), "surrogate")


def test_default_structure_is_global():
    assert isinstance(surrogate_options({}, ResponseSpec(), "surrogate"), GlobalOptions)
    o = surrogate_options({"structure": "resonance"}, ResponseSpec(), "surrogate")
    assert type(o).structure == "resonance"


def test_bad_outputs_rejected():
    Z, Q = _synthetic(12)
    Q[0, 1] = -1.0
    with pytest.raises(ValueError, match="finite and positive"):
        fit_resonance_surrogate(Z, Q, ResonanceOptions(),
                                rng=np.random.default_rng(0), n_max_rpm=N_MAX)


def test_tiny_fe_run_counts_band_points_and_caches_apart(tmp_path):
    inputs = MultivariateNormal([1.0, 1.0], std=[0.0605, 0.0641])
    sp = reference_spindle()
    cfg = ResonanceOptions(n_doe=16, res_n_band=4, n_start=1, res_band_n_start=1, n_jobs=1,
                           backend="sequential", res_band=0.1, res_band_pool=2000)
    c = CallCounter()
    tr = train_surrogate(sp, inputs, LimitState(19.5e-6), cfg, rng=np.random.default_rng(4),
                         cache=fe_cache(tmp_path), counter=c)
    sur, info = tr.model, tr.info
    assert isinstance(sur, ResonanceSurrogate)
    assert info["n_lhs"] + info["n_band"] == sur.n_train == tr.fe_calls == c.calls == 20
    r_band = N_MAX / sur.Q_train[16:, 0]
    assert np.all(np.abs(r_band - 1) <= 0.15)   # predicted within 0.1; the 16-point n_c fit
    y = sur.response(np.array([[2000.0, 330.0, 75.0], [2000.0, 650.0, 60.0]]),
                     np.ones((3, 2)))
    assert y.shape == (2, 3) and np.all(y > 0)
    # the scalar (global) path on the same DOE does not read the vector cache entries
    c2 = CallCounter()
    train_surrogate(sp, inputs, LimitState(19.5e-6),
                    GlobalOptions(n_doe=16, n_start=1, n_jobs=1, backend="sequential"),
                    rng=np.random.default_rng(4), cache=fe_cache(tmp_path), counter=c2)
    assert c2.calls == 16


def test_select_nc_and_bg_only_known_values():
    nc = np.array([N_MAX / 0.9, N_MAX / 0.961, N_MAX, N_MAX / 1.039, N_MAX / 1.2])
    loc = np.full(5, 1.0)
    # the local value exactly where the global r̂ lies within the band of 1
    assert select_nc(nc, loc, N_MAX, 0.04).tolist() == [nc[0], 1.0, 1.0, 1.0, nc[4]]
    assert np.array_equal(select_nc(nc, None, N_MAX, 0.04), nc)
    assert np.array_equal(select_nc(nc, loc, N_MAX, 0.0), nc)
    # background alone at and below r = bg_only_r, the combination above; off: unchanged
    y, bg = np.full(5, 7e-6), np.full(5, 2e-6)
    assert combine_bg_only(y, nc, bg, N_MAX, 0.961).tolist() == [2e-6, 2e-6, 7e-6, 7e-6, 7e-6]
    assert np.array_equal(combine_bg_only(y, nc, bg, N_MAX, 0.0), y)
    assert np.array_equal(combine_bg_only(y, nc, None, N_MAX, 0.961), y)


@pytest.fixture(scope="module")
def synth_opts():
    Z, Q = _synthetic(60, seed=4)
    cfg = ResonanceOptions(n_start=1, res_zeta_min_points=5,
                          res_zeta_r_min=0.7, res_bg_r_max=0.95, res_ares_r_min=0.0,
                          res_nc_local=0.15, res_band=0.1, res_bg_only_r=0.9)
    base = replace(cfg, res_nc_local=0.0, res_bg_only_r=0.0)
    sur = fit_resonance_surrogate(Z, Q, cfg, rng=np.random.default_rng(1), n_max_rpm=N_MAX)
    ref = fit_resonance_surrogate(Z, Q, base, rng=np.random.default_rng(1), n_max_rpm=N_MAX)
    return sur, ref, Z, Q


def test_local_nc_model_interpolates_its_band_rows(synth_opts):
    sur, ref, Z, Q = synth_opts
    r = N_MAX / Q[:, 0]
    rows = sur.rows["nc_local"]
    assert set(sur.subs) == {"nc", "nc_local", "ares", "bg", "zeta"}
    assert np.array_equal(rows, np.flatnonzero(np.abs(r - 1) <= 0.15)) and rows.size >= 7
    smt_pred = sur.subs["nc_local"].model.model_.predict_values(Z[rows]).ravel()
    assert np.allclose(np.exp(smt_pred), Q[rows, 0], rtol=1e-6)
    assert sur.nc_local_band == 0.1 and sur.bg_only_r == 0.9
    assert ref.nc_local_band == 0.0 and "nc_local" not in ref.subs
    # the other sub-models are fitted exactly as without the options (same child streams)
    for k in ("nc", "ares", "bg", "zeta"):
        assert np.array_equal(sur.subs[k].info["hyperparameters"],
                              ref.subs[k].info["hyperparameters"]), k


def test_options_in_grid_points_and_predict(synth_opts):
    sur, ref, Z, Q = synth_opts
    rng = np.random.default_rng(6)
    x = Z[:5, :3] + rng.normal(0, 1, (5, 3))
    theta = 1.0 + 0.05 * rng.standard_normal((4, 2))
    joint = np.column_stack([np.repeat(x, 4, axis=0), np.tile(theta, (5, 1))])
    smt = {k: np.exp(s.model.model_.predict_values(joint).ravel()) for k, s in sur.subs.items()}
    nc = np.where(np.abs(N_MAX / smt["nc"] - 1) <= 0.1, smt["nc_local"], smt["nc"])
    y = combine(nc, smt["ares"], smt["zeta"], smt["bg"], N_MAX)
    y = np.where(N_MAX / nc <= 0.9, smt["bg"], y)
    assert np.allclose(sur.response(x, theta), y.reshape(5, 4), rtol=1e-7)
    assert np.allclose(sur.response_points(joint), y, rtol=1e-7)
    assert np.allclose(sur.nc_points(joint), nc, rtol=1e-9)
    # at the training points the combined median reproduces y where every sub-model used
    # interpolates: background-only rows (r <= 0.9) and in-band rows of every sub-model
    r = N_MAX / Q[:, 0]
    low = np.flatnonzero(r <= 0.85)
    assert low.size >= 1
    assert np.allclose(sur.response_points(Z[low]), Q[low, 3], rtol=1e-4)
    p = sur.predict(Z[low])
    assert np.allclose(p.mean, Q[low, 3], rtol=1e-4) and np.all(p.std < 1e-3 * p.mean)
    y_true, y_loo = sur.loo_points()
    assert y_loo.shape == y_true.shape and np.all(np.isfinite(y_loo))


def test_select_local_known_values():
    glob = np.array([10e-6, 19e-6, 19.5e-6, 21e-6, 30e-6])
    loc = np.full(5, 1.0)
    c = np.log(19.5e-6)
    # |log(19/19.5)| = 0.026, |log(21/19.5)| = 0.074: inside 0.05 / outside
    assert select_local(glob, loc, c, 0.05).tolist() == [10e-6, 1.0, 1.0, 21e-6, 30e-6]
    assert select_local(glob, loc, c, 0.1).tolist() == [10e-6, 1.0, 1.0, 1.0, 30e-6]
    assert np.array_equal(select_local(glob, None, c, 0.1), glob)
    assert np.array_equal(select_local(glob, loc, c, 0.0), glob)


def test_local_ares_model_interpolates_and_is_used_near_the_threshold():
    Z, Q = _synthetic(60, seed=4)
    thr = float(np.median(Q[:, 1]))
    cfg = ResonanceOptions(n_start=1, res_zeta_min_points=5,
                          res_zeta_r_min=0.7, res_bg_r_max=0.95, res_ares_r_min=0.0,
                          res_ares_local=0.3, res_band_lim=0.2)
    with pytest.raises(ValueError, match="threshold_m = None is not allowed"):
        fit_resonance_surrogate(Z, Q, cfg, rng=np.random.default_rng(1), n_max_rpm=N_MAX)
    sur = fit_resonance_surrogate(Z, Q, cfg, rng=np.random.default_rng(1), n_max_rpm=N_MAX,
                                  threshold_m=thr)
    r = N_MAX / Q[:, 0]
    rows = sur.rows["ares_local"]
    assert np.array_equal(rows, np.flatnonzero((r >= 1) & (np.abs(np.log(Q[:, 1] / thr)) <= 0.3)))
    assert rows.size >= 7
    smt_pred = sur.subs["ares_local"].model.model_.predict_values(Z[rows]).ravel()
    assert np.allclose(np.exp(smt_pred), Q[rows, 1], rtol=1e-6)
    assert sur.ares_local_band == 0.2 and sur.ares_local_center == pytest.approx(np.log(thr))
    # grid and points: the local model exactly where the global Â_res is within the band
    rng = np.random.default_rng(8)
    x = Z[:5, :3] + rng.normal(0, 1, (5, 3))
    theta = 1.0 + 0.05 * rng.standard_normal((4, 2))
    joint = np.column_stack([np.repeat(x, 4, axis=0), np.tile(theta, (5, 1))])
    smt = {k: np.exp(s.model.model_.predict_values(joint).ravel()) for k, s in sur.subs.items()}
    a = np.where(np.abs(np.log(smt["ares"] / thr)) <= 0.2, smt["ares_local"], smt["ares"])
    y = combine(smt["nc"], a, smt["zeta"], smt["bg"], N_MAX)
    assert np.allclose(sur.response(x, theta), y.reshape(5, 4), rtol=1e-7)
    assert np.allclose(sur.response_points(joint), y, rtol=1e-7)
    # at its own training rows in the resonant regime (r above the flank) ŷ = A_res exactly
    res = rows[r[rows] > 1.01]
    glob_in = np.abs(np.log(sur.sub_predictions(Z[res])["ares"] / thr)) <= 0.2
    assert glob_in.sum() >= 1
    assert np.allclose(sur.response_points(Z[res[glob_in]]), Q[res[glob_in], 1], rtol=1e-5)


def test_predict_median_is_the_combined_response_with_every_option():
    """``predict`` (delta method, lognormal moments) has its median at ``exp(μ)``:
    ``mean / sqrt(1 + (std/mean)²)`` must be the combined response of ``response_points``
    (local n_c, local A_res and background-only rules all on)."""
    Z, Q = _synthetic(60, seed=4)
    thr = float(np.median(Q[:, 1]))
    cfg = ResonanceOptions(n_start=1, res_zeta_min_points=5,
                          res_zeta_r_min=0.7, res_bg_r_max=0.95, res_ares_r_min=0.0,
                          res_nc_local=0.15, res_band=0.1, res_bg_only_r=0.9,
                          res_ares_local=0.3, res_band_lim=0.2)
    sur = fit_resonance_surrogate(Z, Q, cfg, rng=np.random.default_rng(1), n_max_rpm=N_MAX,
                                  threshold_m=thr)
    assert {"nc_local", "ares_local"} <= set(sur.subs)
    rng = np.random.default_rng(9)
    joint = np.column_stack([Z[:, :3] + rng.normal(0, 1, (60, 3)),
                             1.0 + 0.05 * rng.standard_normal((60, 2))])
    s = sur.sub_predictions(joint)        # every rule is exercised by some point
    assert np.any(np.abs(N_MAX / s["nc"] - 1) <= 0.1)
    assert np.any(np.abs(np.log(s["ares"] / thr)) <= 0.2)
    assert np.any(N_MAX / s["nc"] <= 0.9)
    p = sur.predict(joint)
    median = p.mean / np.sqrt(1.0 + (p.std / p.mean) ** 2)
    np.testing.assert_allclose(median, sur.response_points(joint), rtol=1e-9)
