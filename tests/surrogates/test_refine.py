"""Refinement at the optimiser's designs: design selection, FE error before the refit
(checked against an independent FE evaluation), interpolation after it, options."""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.core.counting import CallCounter
from surrogate_rbrdo.core.protocols import LimitState
from surrogate_rbrdo.sampling.fe import fe_cache
from surrogate_rbrdo.spindle.evaluate import PeakAmplitudeResponse
from surrogate_rbrdo.spindle.reference import reference_spindle
from surrogate_rbrdo.surrogates import refine as refine_module
from surrogate_rbrdo.surrogates.refine import RefineOptions, refine_surrogate, select_designs
from surrogate_rbrdo.surrogates.structured import (
    GlobalOptions,
    ResonanceOptions,
    train_surrogate,
)
from surrogate_rbrdo.uncertainty import MultivariateNormal

INPUTS = MultivariateNormal([1.0, 1.0], std=[0.0605, 0.0641])
LIMIT = LimitState(19.5e-6)
CFG = GlobalOptions(n_doe=16, n_start=1, n_jobs=1, backend="sequential")
BOUNDS = np.array([[1000.0, 3000.0], [300.0, 750.0], [50.0, 80.0]])


# ------------------------------------------------------------------ select_designs
def test_priority_first_then_front_ends_then_spread():
    front = np.array([[1000.0, 300.0 + 50 * i, 50.0 + 3 * i] for i in range(10)])
    comp = [front[4]]
    X = select_designs(comp, {"f": front}, BOUNDS, 4)
    np.testing.assert_array_equal(X[0], front[4])
    np.testing.assert_array_equal(X[1], front[0])
    np.testing.assert_array_equal(X[2], front[9])
    # the fourth is the front point farthest from the three: index 2 or 7 (equal distance)
    d = [np.min(np.abs(np.array([4, 0, 9]) - i)) for i in range(10)]
    assert any(np.array_equal(X[3], front[i]) for i in range(10) if d[i] == max(d))


def test_near_duplicates_are_skipped_and_count_is_capped():
    a = np.array([2000.0, 500.0, 65.0])
    near = a + np.array([1.0, 0.1, 0.01])           # far below 2 % of the box
    X = select_designs([a, near, a], {}, BOUNDS, 5)
    assert X.shape == (1, 3)
    front = np.array([[1000.0, 300.0, 50.0], [3000.0, 750.0, 80.0], [2000.0, 400.0, 60.0]])
    assert select_designs([a], {"f": front}, BOUNDS, 2).shape == (2, 3)


# ------------------------------------------------------------------ refine_surrogate
@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    return train_surrogate(reference_spindle(), INPUTS, LIMIT, CFG, rng=np.random.default_rng(4),
                           cache=fe_cache(tmp_path_factory.mktemp("fe")))


def test_refine_reports_the_error_against_independent_fe_and_interpolates(trained):
    sp = reference_spindle()
    X = np.array([[3000.0, 480.0, 72.0], [2000.0, 380.0, 60.0]])
    theta = INPUTS.sample(3, rng=np.random.default_rng(1))
    counter = CallCounter()
    new, st = refine_surrogate(trained, sp, X, theta, LIMIT, rng=np.random.default_rng(2),
                               counter=counter)
    # independent FE evaluation of the same designs x θ
    y_fe = PeakAmplitudeResponse(sp)(X, theta)
    np.testing.assert_allclose(st["mean_um_fe"], y_fe.mean(axis=1) * 1e6, rtol=1e-9)
    y_old = trained.model.response(X, theta)
    np.testing.assert_allclose(st["mean_um_surrogate"], y_old.mean(axis=1) * 1e6, rtol=1e-6)
    err = np.abs(y_old.mean(1) - y_fe.mean(1)) / y_fe.mean(1)
    assert st["max_rel_err_mean"] == pytest.approx(err.max(), rel=1e-6)
    assert st["refit"] and st["fe_points"] == 6 == counter.calls
    assert new.model.n_train == trained.model.n_train + 6 and new.fe_calls == 16 + 6
    # the refitted Kriging interpolates the new FE points
    np.testing.assert_allclose(new.model.response(X, theta), y_fe, rtol=1e-3)


def test_refit_keeps_the_physical_length_scales(trained):
    X = np.array([[2500.0, 450.0, 70.0]])
    theta = INPUTS.sample(4, rng=np.random.default_rng(7))
    new, _ = refine_surrogate(trained, reference_spindle(), X, theta, LIMIT,
                              rng=np.random.default_rng(0), hyper="keep")
    old_f, new_f = trained.model.fast, new.model.fast
    # squared exponential exp(-w (Δ/s)²): w / s² is the physical length scale, unchanged
    np.testing.assert_allclose(new_f.weights / new_f.scale**2, old_f.weights / old_f.scale**2,
                               rtol=1e-9)
    refit, _ = refine_surrogate(trained, reference_spindle(), X, theta, LIMIT,
                                rng=np.random.default_rng(0), hyper="refit")
    assert not np.allclose(refit.model.fast.weights / refit.model.fast.scale**2,
                           old_f.weights / old_f.scale**2, rtol=1e-3)


def test_refine_within_tolerance_keeps_the_surrogate(trained):
    X = np.array([[2500.0, 420.0, 66.0]])
    theta = INPUTS.sample(2, rng=np.random.default_rng(5))
    new, st = refine_surrogate(trained, reference_spindle(), X, theta, LIMIT,
                               rng=np.random.default_rng(0), tol=1e9)
    assert new is trained and st["refit"] is False


@pytest.mark.parametrize("kw,match", [
    ({"rounds": -1}, r"refine.rounds = -1 is not allowed"),
    ({"theta": 1}, r"refine.theta = 1 is not allowed"),
    ({"designs": 0}, r"refine.designs = 0 is not allowed"),
    ({"tol": 0.0}, r"refine.tol = 0.0 is not allowed"),
    ({"hyper": "fixed"}, r"refine.hyper = 'fixed' is not allowed"),
])
def test_bad_refine_options(kw, match):
    with pytest.raises(ValueError, match=match):
        RefineOptions(**kw)


def test_band_flags_survive_two_rounds(tmp_path, monkeypatch):
    """Rows added by refinement are ordinary rows in later rounds, not band rows."""
    cfg = ResonanceOptions(n_doe=16, n_start=1, n_jobs=1, backend="sequential", res_n_band=4)
    sur = train_surrogate(reference_spindle(), INPUTS, LIMIT, cfg, rng=np.random.default_rng(4),
                          cache=fe_cache(tmp_path))
    assert sur.model.info["n_lhs"] == 16 and sur.model.info["n_band"] == 4
    seen = []
    real = refine_module.fit_resonance_surrogate

    def spy(Z, Q, cfg_, **kw):
        seen.append(np.asarray(kw["is_band"]).copy())
        return real(Z, Q, cfg_, **kw)

    monkeypatch.setattr(refine_module, "fit_resonance_surrogate", spy)
    X = np.array([[3000.0, 480.0, 72.0]])
    for k in range(2):
        th = INPUTS.sample(2, rng=np.random.default_rng(10 + k))
        sur, _ = refine_surrogate(sur, reference_spindle(), X, th, LIMIT,
                                  rng=np.random.default_rng(k))
    assert [b.size for b in seen] == [22, 24]
    for b in seen:
        assert b[16:20].all() and not b[:16].any() and not b[20:].any()


def test_refine_refuses_structures_that_cannot_take_points(trained):
    from dataclasses import replace

    fe = replace(trained, structure="fe")
    with pytest.raises(ValueError, match=r"structure 'fe' is not allowed in refine_surrogate"):
        refine_surrogate(fe, reference_spindle(), np.array([[2000.0, 465.8, 65.0]]),
                         np.ones((2, 2)), LIMIT, rng=np.random.default_rng(0))
