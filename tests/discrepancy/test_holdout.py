"""The held-out check's predictive χ² and deviance: residuals against the noise plus the
training fit's prediction uncertainty (and, for the deviance, its log-determinant)."""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy.candidates import candidate
from surrogate_rbrdo.discrepancy.fit import fit
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.holdout import predictive_chi2, residuals
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
    assert np.sum(np.array(gains) > 0) < 20
