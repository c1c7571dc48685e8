"""The held-out check's predictive χ² and deviance: residuals against the noise plus the
training fit's prediction uncertainty (and, for the deviance, its log-determinant)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy.candidates import candidate
from surrogate_rbrdo.discrepancy.fit import fit
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.holdout import held_out_gap, predictive_chi2, residuals
from surrogate_rbrdo.discrepancy.nuisance import Slot
from surrogate_rbrdo.discrepancy.observables import ComplexBlock, MeasuredData
from surrogate_rbrdo.discrepancy.problem import KNOWN_DOF, Problem, _whitened
from surrogate_rbrdo.discrepancy.search import fit_nuisance
from surrogate_rbrdo.discrepancy.sweeps import Sweep
from surrogate_rbrdo.discrepancy.synthetic import default_channels

U = np.array([4e-6 * np.exp(0.7j), 9e-6 * np.exp(-2.0j)])


def _null_draws(spindle, n, seed=3):
    """The forward model and ``n`` (training, held-out) problems of the base model's own 1x
    response at 12 speeds to 24 000 rpm with Gaussian noise of known covariance (1 % of the
    response per cell), the top two speeds held out (beyond the first critical speed)."""
    sp, g = spindle
    ch = default_channels(g)
    fm = ForwardModel(g, sp.effects, ch, (0.0, 350.0))
    sw = Sweep.unbalance(np.linspace(2000.0, 24000.0, 12))
    y = fm.response(sw, np.ones((1, 2)), np.ones((1, 2)))[0] @ U
    sd = 0.01 * np.abs(y) + 1e-9                       # 1 % of the response, per cell
    cov = (sd**2 / 2)[..., None, None] * np.eye(2)     # of [Re, Im]
    held = np.zeros(12, dtype=bool)
    held[-2:] = True
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        z = sd / np.sqrt(2) * (rng.normal(size=y.shape) + 1j * rng.normal(size=y.shape))
        data = MeasuredData((ComplexBlock("unbalance_1x", sw, ch, y + z, cov, KNOWN_DOF),))
        out.append((Problem(fm, data, {"unbalance_1x": ~held}),
                    Problem(fm, data, {"unbalance_1x": held})))
    return fm, out


@pytest.mark.slow
@pytest.mark.known_answer
def test_predictive_chi2_of_the_true_model_has_the_mean_of_its_dof(spindle):
    """Known answer: for the true model, Gaussian noise of known covariance and a fit on the
    training speeds, the held-out residual is (to first order) normal with the covariance of
    the prediction error, so its predictive χ² is χ²ₘ, mean ``m`` (the held-out real
    observables). The extrapolated speeds sit beyond the first critical speed, where the plain
    noise-whitened χ² is larger by what the parameter uncertainty propagates there."""
    fm, draws = _null_draws(spindle, 40)
    m = 2 * 2 * len(fm.channels)
    pred, plain = [], []
    for train, ho in draws:
        f = fit_nuisance(train)
        pred.append(predictive_chi2(train, ho, f))
        r = residuals(ho, f.par, f.x, tuple(u[0] for u in f.evaluation.unbalance))
        plain.append(float(np.sum(_whitened(r[0][None], ho.whiten[0]) ** 2)))
    print(f"predictive χ² mean {np.mean(pred):.2f} (m = {m}), noise-only {np.mean(plain):.1f}")
    # the mean of 40 χ²ₘ draws has the SD sqrt(2m / 40): within 3 SD of m
    assert abs(np.mean(pred) - m) < 3 * np.sqrt(2 * m / 40)
    assert np.mean(plain) > np.mean(pred)


@pytest.mark.parametrize("name", ["gyroscopics", "speed_softening"])
def test_the_held_out_deviance_does_not_reward_a_candidate_that_fits_noise(spindle, name):
    """Under the null (the data are the base model plus noise), a candidate fitted on the
    training speeds can only fit noise, and on average it predicts the held-out speeds worse
    (its extra parameter's estimation error), so its held-out deviance should improve in a
    minority of draws. The predictive χ² alone counts the candidate's wider prediction
    covariance as a gain (a larger model's covariance is never smaller) and improved in 23/40
    (gyroscopics) and 31/40 (softening) draws; its log-determinant charges that spread."""
    fm, draws = _null_draws(spindle, 40)
    c = candidate(name, fm.bearing_names)
    gains = []
    for train, ho in draws:
        b = fit_nuisance(train)
        par = b.par.with_slots((Slot(c, ()),))
        x0 = par.x0()
        x0[:b.x.size] = b.x
        f = fit(train, par, x0)
        gains.append(predictive_chi2(train, ho, b, deviance=True)
                     - predictive_chi2(train, ho, f, deviance=True))
    # a fair coin gives more than 26 of 40 with probability 0.02: far fewer are expected
    n_up = int(np.sum(np.array(gains) > 0))
    print(f"{name}: held-out deviance improved in {n_up}/40 null draws, median gain "
          f"{np.median(gains):.2f}")                     # the figure docs/discrepancy.md quotes
    assert n_up < 20


def _gyro_fit(spindle):
    """A gyroscopics fit on the training speeds of one null draw, its held-out problems and
    the column index of ``g``."""
    fm, draws = _null_draws(spindle, 1, seed=11)
    train, ho = draws[0]
    b = fit_nuisance(train)
    par = b.par.with_slots((Slot(candidate("gyroscopics", fm.bearing_names), ()),))
    x0 = par.x0()
    x0[:b.x.size] = b.x
    return train, ho, fit(train, par, x0), par.names.index("gyroscopics.g")


@pytest.mark.known_answer
def test_an_unseen_parameter_is_known_to_its_range_in_the_prediction(spindle):
    """Known answer: with its training column exactly zero, a parameter is uncorrelated with
    the rest and its prediction variance is the most an estimate confined to its range can
    have, (b − a)²/4 (Popoviciu; g in [−1, 1]: 1), not the infinity a Wald interval takes, nor
    the 0 it used to become."""
    _, _, f, j = _gyro_fit(spindle)
    J = f.jac.copy()
    J[:, j] = 0.0
    S = replace(f, jac=J).covariance(bounded=True)
    assert S[j, j] == pytest.approx(1.0, rel=1e-9)
    assert np.all(S[j, np.arange(S.shape[0]) != j] == 0.0)
    assert np.isinf(replace(f, jac=J).covariance()[j, j])


@pytest.mark.known_answer
def test_unseen_and_barely_seen_parameters_give_the_same_predictive_deviance(spindle):
    """A parameter training does not see and one it sees 1e-6 as strongly are the same
    parameter to the data: the held-out deviance (which sees the parameter fully: its
    held-out derivative is recomputed) must not jump between them. The rule used to treat the
    first as exact (variance 0) and the second as unknown (variance 1e12 times its seen
    one)."""
    train, ho, f, j = _gyro_fit(spindle)
    dev = {}
    for scale in (0.0, 1e-6, 1.0):
        J = f.jac.copy()
        J[:, j] *= scale
        dev[scale] = predictive_chi2(train, ho, replace(f, jac=J), deviance=True)
    assert dev[0.0] == pytest.approx(dev[1e-6], rel=1e-4)
    # and the column matters when it is seen: the comparison is not vacuous
    assert abs(dev[1.0] - dev[0.0]) > 1e-3


@pytest.mark.known_answer
def test_the_held_out_gap_splits_into_its_parts(spindle):
    """Known answers for :func:`held_out_gap` on the base model's own 1x response with noise:
    the noise-only χ² and the observation count of all held-out speeds are the sums of the
    interleaved and extrapolated parts'; the predictive χ² of each part is at most its
    noise-only χ² (the prediction covariance ``I + J Σ Jᵀ + …`` is ``≥ I``); a correction that
    is the residual itself leaves no gap, and then no predictive χ² is claimed."""
    sp, g = spindle
    ch = default_channels(g)
    fm = ForwardModel(g, sp.effects, ch, (0.0, 350.0))
    sw = Sweep.unbalance(np.linspace(2000.0, 24000.0, 12))
    y = fm.response(sw, np.ones((1, 2)), np.ones((1, 2)))[0] @ U
    sd = 0.01 * np.abs(y) + 1e-9
    cov = (sd**2 / 2)[..., None, None] * np.eye(2)
    rng = np.random.default_rng(5)
    z = sd / np.sqrt(2) * (rng.normal(size=y.shape) + 1j * rng.normal(size=y.shape))
    data = MeasuredData((ComplexBlock("unbalance_1x", sw, ch, y + z, cov, KNOWN_DOF),))
    inter, extra = np.zeros(12, bool), np.zeros(12, bool)
    inter[[2, 6]], extra[-2:] = True, True
    train = Problem(fm, data, {"unbalance_1x": ~(inter | extra)})
    parts = {"interleaved": Problem(fm, data, {"unbalance_1x": inter}),
             "extrapolated": Problem(fm, data, {"unbalance_1x": extra})}
    held = Problem(fm, data, {"unbalance_1x": inter | extra})
    f = fit_nuisance(train)
    g_all = held_out_gap(train, held, parts, f)
    gi, ge = g_all.parts["interleaved"], g_all.parts["extrapolated"]
    assert g_all.n == gi.n + ge.n == 2 * 4 * len(ch)
    assert g_all.chi2 == pytest.approx(gi.chi2 + ge.chi2, rel=1e-12)
    for p in (gi, ge):
        assert p.predictive_chi2_dof <= p.chi2_dof * (1 + 1e-12)
    d = g_all.to_dict()
    assert set(d) >= {"rmse", "max_abs", "chi2_dof", "predictive_chi2_dof", "interleaved",
                      "extrapolated"}
    u = tuple(v[0] for v in f.evaluation.unbalance)
    exact = held_out_gap(train, held, parts, f,
                         correction=lambda p: residuals(p, f.par, f.x, u))
    assert exact.rmse == pytest.approx(0.0, abs=1e-9)
    assert np.isnan(exact.predictive_chi2_dof)
