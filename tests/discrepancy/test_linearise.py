"""The first-order candidate columns of ``calibration.linearise`` against finite differences."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy.calibration import (
    _apply,
    _data_whitening,
    linear_statistics,
    linearise,
)
from surrogate_rbrdo.discrepancy.candidates import library
from surrogate_rbrdo.discrepancy.fit import fit
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.nuisance import NuisanceOptions
from surrogate_rbrdo.discrepancy.problem import Problem
from surrogate_rbrdo.discrepancy.synthetic import default_channels
from surrogate_rbrdo.spindle.effects import SpeedSoftening

from .conftest import baseline_1x, campaign_data


@pytest.mark.known_answer
def test_a_candidate_column_leaves_the_priors_alone(spindle):
    """A candidate effect changes the data, not the nuisance's prior pseudo-observations: its
    column is the derivative of the data part (a second-order one-sided difference of the
    model with the effect added) and zero on the prior rows, even where the fit left the
    priors off their means (a column carrying ``prior residual / step`` there once swamped the
    signature)."""
    n_ch = len(default_channels(spindle[1]))
    gain = 1 + 0.04 * np.arange(n_ch) / n_ch                  # the channels' gains differ
    fm, data = baseline_1x(spindle, seed=3, gain=gain)
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


@pytest.mark.known_answer
def test_the_variants_cover_every_shape_the_search_reaches(spindle):
    """The first-order statistic is a maximum over a candidate's variants; the search fits the
    shape anywhere in its range, so the variants' maximum must cover the maximum over that
    range. Known answer: the largest one-parameter likelihood ratio ``(uᵀr)² / uᵀu`` over a
    fine grid of the softening exponent over its whole range (0.5–4, every scope; columns by
    independent finite differences of the model, the nuisance projected out), on 40 residuals
    of pure noise. The variants' statistic must reach it within the loss of a grid
    (|cos| of neighbouring shapes > 0.99: at most 3 %)."""
    fm, data = baseline_1x(spindle, seed=5)
    prob = Problem(fm, data, None, NuisanceOptions())
    par = prob.parametrisation()
    base = fit(prob, par, par.x0())
    cand = library(("speed_softening",), ("front", "rear"))[0]
    lin = linearise(prob, base, (cand,))
    u = tuple(x[0] for x in base.evaluation.unbalance)
    rows = par.rows(base.x[None])
    h = 1e-7
    exponents = np.linspace(*cand.shape_bounds[0], 80)
    extras = [rows.extras[0] + (SpeedSoftening(a=a, exponent=float(p), bearings=s),)
              for s in (("front", "rear"), ("front",), ("rear",)) for p in exponents
              for a in (h,)]
    y0 = prob.data_vector(rows, u)[0]
    y = prob.data_vector(replace(rows.repeat(len(extras)), extras=extras), u)
    n_data = y.shape[1]
    cols = np.zeros((prob.n_obs, len(extras)))
    cols[:n_data] = ((y - y0) / h).T                        # zero on the prior rows
    W = _data_whitening(prob)
    Q, _ = np.linalg.qr(_apply(W, lin.nuisance))
    U = _apply(W, cols)
    U = U - Q @ (Q.T @ U)
    rng = np.random.default_rng(11)
    R = rng.normal(size=(40, prob.n_obs))
    R = R - (R @ Q) @ Q.T
    num = R @ U
    brute = np.max(np.where(num > 0, num**2, 0.0) / np.sum(U * U, axis=0), axis=1)
    got = np.array([linear_statistics(prob, lin, r)[0] for r in R])
    assert np.all(got >= 0.97 * brute)


@pytest.mark.known_answer
def test_the_variants_cover_a_housing_far_from_its_linearisation(spindle):
    """A housing's first-order column hardly depends on its mass (a mass behind an almost rigid
    spring), while the search fits stiffness and mass anywhere in their range. Known answer:
    if the residual is exactly the (whitened, nuisance-orthogonal) change ``g`` of a housing
    between the grid's points (200 kg, the compliance where ``|g|`` is nearest 5 noise sd),
    the best fit of the housing explains all of it: ``Δχ² = |g|²``. The variants' statistic,
    which the bootstrap calibrates, must reach it within the loss of a grid (10 %). The data:
    the small campaign's 1x responses and standstill FRFs to 1.5 kHz (the derivative columns
    alone, the variants before the secants, reached 14.3 of 22.1)."""
    sp, geo = spindle
    data, _ = campaign_data(spindle, seed=3)
    fm = ForwardModel(geo, sp.effects, data.channels, (0.0, 350.0))
    prob = Problem(fm, data, None, NuisanceOptions())
    par = prob.parametrisation()
    base = fit(prob, par, par.x0(), max_nfev=40)
    cand = library(("housing",), ("front", "rear"))[0]
    lin = linearise(prob, base, (cand,))
    u = tuple(x[0] for x in base.evaluation.unbalance)
    rows = par.rows(base.x[None])
    comp = np.geomspace(1e-14, 1e-9, 60)
    extras = [rows.extras[0] + (cand.effect((), {"k_N_per_m": s, "m_kg": 200.0,
                                                 "c_Ns_per_m": 0.0}),) for s in comp]
    y0 = prob.data_vector(rows, u)[0]
    y = prob.data_vector(replace(rows.repeat(len(extras)), extras=extras), u)
    G = np.zeros((prob.n_obs, len(extras)))
    G[:y.shape[1]] = (y - y0).T
    W = _data_whitening(prob)
    Q, _ = np.linalg.qr(_apply(W, lin.nuisance))
    G = _apply(W, G)
    G = G - Q @ (Q.T @ G)
    norms = np.linalg.norm(G, axis=0)
    g = G[:, np.argmin(np.abs(norms - 5.0))]
    assert linear_statistics(prob, lin, g)[0] >= 0.9 * float(g @ g)
