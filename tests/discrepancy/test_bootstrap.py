"""The bootstrap's statistics (``calibration.simulate_null``) against the textbook computation,
and the blocked evaluations (rows of a linearisation, of the Woodbury coupling) against one
block."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy import calibration, forward
from surrogate_rbrdo.discrepancy.calibration import (
    _apply,
    _data_whitening,
    linearise,
    simulate_null,
)
from surrogate_rbrdo.discrepancy.candidates import library
from surrogate_rbrdo.discrepancy.fit import fit
from surrogate_rbrdo.discrepancy.noise import NoiseModel
from surrogate_rbrdo.discrepancy.nuisance import NuisanceOptions
from surrogate_rbrdo.discrepancy.problem import Problem

from .conftest import baseline_1x

NAMES = ("speed_softening", "cross_coupling", "anisotropy", "housing", "tool_interface")


@pytest.fixture(scope="module")
def linearised(spindle):
    fm, data = baseline_1x(spindle, seed=11)
    prob = Problem(fm, data, None, NuisanceOptions())
    par = prob.parametrisation()
    base = fit(prob, par, par.x0())
    return prob, base, linearise(prob, base, library(NAMES, fm.bearing_names))


def _direct(prob, lin, n_draws, seed, chunk):
    """Per draw: whiten every column, project the nuisance out by QR, and take the largest
    ``(uᵀr)²/uᵀu`` over a candidate's one-column variants (one-sided where its strength is)
    and ``rᵀ P_U r`` over its several-column ones; the same for the generic columns."""
    rng = np.random.default_rng(seed)
    noise = NoiseModel.of(prob, lin.nuisance[:, :lin.n_theta], _data_whitening(prob)[0])
    cand, gen = [], []
    for start in range(0, n_draws, chunk):
        e, W, wr = noise.draw(min(chunk, n_draws - start), rng)
        for b in range(e.shape[0]):
            Wb = (W[b], wr[b])
            Q, _ = np.linalg.qr(_apply(Wb, lin.nuisance))
            ew = _apply(Wb, e[b][:, None])[:, 0]
            r = ew - Q @ (Q.T @ ew)

            def lr(M, one_sided, Q=Q, Wb=Wb, r=r):
                U = _apply(Wb, M)
                U = U - Q @ (Q.T @ U)
                if M.shape[1] > 1:
                    Qu, _ = np.linalg.qr(U)
                    return float(np.sum((Qu.T @ r) ** 2))
                num, uu = float(U[:, 0] @ r), float(U[:, 0] @ U[:, 0])
                if uu <= 1e-12 * float(np.sum(_apply(Wb, M) ** 2)):   # absorbed: nothing
                    return 0.0
                return 0.0 if one_sided and num <= 0 else num**2 / uu

            cand.append([max(lr(v.columns, c.one_sided[0]) for v in vs)
                         for c, vs in lin.candidates])
            gen.append(max(lr(lin.generic[:, [j]], False)
                           for j in range(lin.generic.shape[1])))
    return np.array(cand), np.array(gen)


@pytest.mark.known_answer
def test_bootstrap_statistics_equal_the_whitened_projection_per_draw(linearised):
    prob, _, lin = linearised
    assert any(v.columns.shape[1] > 1 for _, vs in lin.candidates for v in vs)
    assert sum(len(vs) for _, vs in lin.candidates) > len(lin.candidates)
    null = simulate_null(prob, lin, n_draws=30, rng=np.random.default_rng(4), chunk=7)
    cand, gen = _direct(prob, lin, 30, 4, 7)
    assert null.names == tuple(c.name for c, _ in lin.candidates)
    assert np.allclose(null.candidates, cand, rtol=1e-8, atol=1e-10)
    assert np.allclose(null.generic, gen, rtol=1e-8, atol=1e-10)
    assert np.all(null.candidates >= 0.0)


def test_blocked_evaluations_equal_one_block(linearised, monkeypatch):
    """The linearisation's rows in blocks of 5 and the coupling in blocks of one row give the
    same columns as one block each."""
    prob, base, lin = linearised
    cands = tuple(c for c, _ in lin.candidates)
    monkeypatch.setattr(calibration, "ROW_BLOCK", 5)
    monkeypatch.setattr(forward, "COUPLE_BLOCK_BYTES", 1)
    small = linearise(prob, base, cands)
    for (c, vs), (c2, vs2) in zip(lin.candidates, small.candidates, strict=True):
        assert c.name == c2.name and len(vs) == len(vs2)
        for v, v2 in zip(vs, vs2, strict=True):
            assert np.array_equal(v.columns, v2.columns)


@pytest.mark.known_answer
def test_a_generic_column_the_nuisance_absorbs_explains_nothing(linearised):
    """A generic column in the span of the nuisance (3 N₀ + N₁) adds nothing once the nuisance
    is refitted: its statistic is 0 in every draw (not the rounding of a 0/0); nudged out of
    the span by 1e-3 of another column it is a statistic again, equal to the direct one."""
    prob, _, lin = linearised
    N = lin.nuisance
    for eps, zero in ((0.0, True), (1e-3, False)):
        g0 = lin.generic[:, [0]] * np.linalg.norm(N[:, 0]) / np.linalg.norm(lin.generic[:, 0])
        extra = 3.0 * N[:, [0]] + N[:, [1]] + eps * g0
        l2 = replace(lin, generic=extra, generic_labels=("dup",),
                     generic_bounds=None if lin.generic_bounds is None
                     else np.array([[-np.inf, np.inf]]))
        null = simulate_null(prob, l2, n_draws=20, rng=np.random.default_rng(4), chunk=7)
        _, gen = _direct(prob, l2, 20, 4, 7)
        assert np.all(np.isfinite(null.generic))
        if zero:
            assert np.all(null.generic == 0.0) and np.all(gen == 0.0)
        else:
            assert np.all(null.generic > 0.0)
            assert np.allclose(null.generic, gen, rtol=1e-6)
