"""The first-order candidate columns of ``calibration.linearise`` against finite differences."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy.calibration import linearise
from surrogate_rbrdo.discrepancy.candidates import library
from surrogate_rbrdo.discrepancy.fit import fit
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.nuisance import NuisanceOptions
from surrogate_rbrdo.discrepancy.observables import ComplexBlock, MeasuredData
from surrogate_rbrdo.discrepancy.problem import Problem
from surrogate_rbrdo.discrepancy.sweeps import Sweep
from surrogate_rbrdo.discrepancy.synthetic import default_channels
from surrogate_rbrdo.spindle.effects import SpeedSoftening


@pytest.mark.known_answer
def test_a_candidate_column_leaves_the_priors_alone(spindle):
    """A candidate effect changes the data, not the nuisance's prior pseudo-observations: its
    column is the derivative of the data part (a central difference of the model with the
    effect added) and zero on the prior rows, even where the fit left the priors off their
    means (a column carrying ``prior residual / step`` there once swamped the signature)."""
    sp, g = spindle
    ch = default_channels(g)
    sw = Sweep.unbalance(np.linspace(3000, 22000, 9))
    fm = ForwardModel(g, sp.effects, ch, (0.0, 350.0))
    rng = np.random.default_rng(3)
    y = fm.response(sw, np.ones((1, 2)), np.ones((1, 2)))[0] @ np.array([5e-6, 5e-6j])
    gain = 1 + 0.04 * np.arange(y.shape[1]) / y.shape[1]          # channels' gains differ
    rec = y[None] * gain * (1 + 1e-3 * (rng.normal(size=(8,) + y.shape)
                                        + 1j * rng.normal(size=(8,) + y.shape)))
    data = MeasuredData((ComplexBlock.from_repeats("unbalance_1x", sw, ch, rec),))
    prob = Problem(fm, data, None, NuisanceOptions(gain_sd=0.02))
    par = prob.parametrisation()
    base = fit(prob, par, par.x0())
    assert np.abs(par.prior_residuals(base.x)).max() > 0.3       # the priors are pulled
    cand = library(("speed_softening",), ("front", "rear"))[0]
    lin = linearise(prob, base, (cand,))
    (c, variants), = lin.candidates
    v = next(v for v in variants if v.scope == () and dict(v.shape)["exponent"] == 2.0)
    u = tuple(x[0] for x in base.evaluation.unbalance)
    rows = par.rows(base.x[None])
    h = 1e-5
    y0, y1, y2 = (prob.data_vector(replace(rows, extras=[rows.extras[0] + (
        SpeedSoftening(a=a, exponent=2.0),)]), u)[0] for a in (0.0, h, 2 * h))
    fd = (4 * y1 - 3 * y0 - y2) / (2 * h)                   # one-sided, second order
    col = v.columns[:, 0]
    assert np.allclose(col[prob.n_obs - prob.n_prior:], 0.0)
    assert np.linalg.norm(col[:fd.size] - fd) < 1e-2 * np.linalg.norm(fd)
