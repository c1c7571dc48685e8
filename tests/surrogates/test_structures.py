"""Surrogate structures: the global Kriging on a tiny DOE end to end (independent prediction
path, θ-block cache, options validation, FE-call accounting, on-disk cache), the "fe"
structure and the structure/response checks; one return type for all."""

from __future__ import annotations

import re

import numpy as np
import pytest

from surrogate_rbrdo.core.counting import CallCounter
from surrogate_rbrdo.core.protocols import LimitState
from surrogate_rbrdo.sampling.fe import fe_cache
from surrogate_rbrdo.spindle.evaluate import (
    AtSpeedAmplitudeResponse,
    PointwiseAtSpeed,
    ResponseSpec,
)
from surrogate_rbrdo.spindle.reference import reference_spindle
from surrogate_rbrdo.surrogates.structured import (
    STRUCTURES,
    FEOptions,
    FullModel,
    GlobalOptions,
    ResonanceOptions,
    SurrogateModel,
    TrainedSurrogate,
    train_surrogate,
)
from surrogate_rbrdo.surrogates.transformed import TransformedKriging
from surrogate_rbrdo.uncertainty import MultivariateNormal

INPUTS = MultivariateNormal([1.0, 1.0], std=[0.0605, 0.0641])
LIMIT = LimitState(19.5e-6)
TINY = GlobalOptions(n_doe=14, n_start=1, n_jobs=1, backend="sequential")


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    cache = tmp_path_factory.mktemp("fe_cache")
    counter = CallCounter()
    tr = train_surrogate(reference_spindle(), INPUTS, LIMIT, TINY, rng=np.random.default_rng(3),
                         cache=fe_cache(cache), counter=counter)
    return tr.model, tr, counter, cache


def _joint(x, t):
    return np.column_stack([np.repeat(x, len(t), axis=0), np.tile(t, (len(x), 1))])


def test_tiny_pipeline_response_matches_smt_predict_values(trained):
    sur, tr, counter, _ = trained
    assert isinstance(sur, TransformedKriging) and isinstance(sur, SurrogateModel)
    assert sur.n_train == 14 and tr.info["n_train"] == 14
    assert tr.fe_calls == 14 == counter.calls and tr.fe_cache_hits == 0
    rng = np.random.default_rng(0)
    x = TINY.bounds(reference_spindle(), INPUTS)[:3]
    x = x[:, 0] + rng.random((4, 3)) * (x[:, 1] - x[:, 0])
    t = INPUTS.sample(7, rng=rng)
    y = sur.response(x, t)
    assert y.shape == (4, 7)
    # independent path: smt's own predict_values on the joint points, then exp (log transform)
    ref = np.exp(sur.model.model_.predict_values(_joint(x, t)).reshape(4, 7))
    np.testing.assert_allclose(y, ref, rtol=1e-8, atol=0)
    assert np.all((y > 1e-8) & (y < 1e-3))  # metres, physically plausible range


def test_training_points_are_interpolated(trained):
    sur, *_ = trained
    Z, logy = sur.model.X_train_, sur.model.y_train_
    y = np.array([sur.response(z[None, :3], z[None, 3:])[0, 0] for z in Z])
    np.testing.assert_allclose(np.log(y), logy, atol=1e-6)


def test_theta_block_cache_keyed_on_identity(trained):
    sur, *_ = trained
    t = INPUTS.sample(5, rng=np.random.default_rng(1))
    x = np.array([[2000.0, 500.0, 65.0]])
    before = sur.theta_block_builds
    a = sur.response(x, t)
    b = sur.response(x + [[10.0, 0.0, 0.0]], t)
    assert sur.theta_block_builds == before + 1          # second call reused the block
    c = sur(x, t.copy())                                 # equal values, new object: rebuilt
    assert sur.theta_block_builds == before + 2
    np.testing.assert_array_equal(a, c)
    assert not np.array_equal(a, b)


def test_predict_lognormal_moments(trained):
    sur, *_ = trained
    Z = _joint(np.array([[1500.0, 600.0, 60.0]]), INPUTS.sample(3, rng=np.random.default_rng(2)))
    p = sur.predict(Z)
    mu = sur.model.model_.predict_values(Z).ravel()
    s2 = np.maximum(sur.model.model_.predict_variances(Z).ravel(), 0.0)
    np.testing.assert_allclose(p.mean, np.exp(mu + s2 / 2), rtol=1e-10)
    np.testing.assert_allclose(p.std, np.exp(mu + s2 / 2) * np.sqrt(np.expm1(s2)), rtol=1e-10)


def test_cache_makes_rerun_free(trained):
    _, _, _, cache = trained
    c2 = CallCounter()
    tr2 = train_surrogate(reference_spindle(), INPUTS, LIMIT, TINY, rng=np.random.default_rng(3),
                          cache=fe_cache(cache), counter=c2)
    assert c2.calls == 0 and tr2.fe_calls == 0 and tr2.fe_cache_hits == 14 == c2.cached
    np.testing.assert_array_equal(tr2.model.model.y_train_, trained[0].model.y_train_)


@pytest.mark.parametrize("field,value", [
    ("transform", "sqrt"), ("surrogate", "nn"), ("theta_box", "box"), ("n_doe", 3),
    ("theta_sigmas", -1.0), ("backend", "mpi"), ("n_jobs", 0), ("active_learning", "yes"),
    ("theta_bounds", (1.5, 0.5)), ("al_uncertain_frac", 2.0),
])
def test_options_validation_names_field_and_value(field, value):
    with pytest.raises(ValueError, match=rf"{field} = .*{re.escape(str(value)[:3])}.*not allowed"):
        GlobalOptions(**{field: value})


def test_bounds_box_choices():
    sp = reference_spindle()
    b = GlobalOptions(theta_box="sigma", theta_sigmas=2.0).bounds(sp, INPUTS)
    np.testing.assert_allclose(b[3:], [[1 - 0.121, 1 + 0.121], [1 - 0.1282, 1 + 0.1282]])
    b = GlobalOptions(theta_box="bounds").bounds(sp, INPUTS)
    np.testing.assert_allclose(b[3:], [[0.5, 1.5], [0.5, 1.5]])
    np.testing.assert_allclose(b[:3], sp.design_map.bounds)


def test_rejects_options_of_no_structure():
    with pytest.raises(ValueError, match=r"options = \{'n_doe': 10\} is not allowed"):
        train_surrogate(reference_spindle(), INPUTS, LIMIT, {"n_doe": 10},
                        rng=np.random.default_rng(0))


def test_every_structure_has_one_frozen_options_class_with_defaults():
    for name, entry in STRUCTURES.items():
        opts = entry.options()
        assert type(opts).structure == name and entry.summary
        with pytest.raises(AttributeError):
            opts.structure_x = 1            # frozen


# ---------------------------------------------------------------------- response kinds, "fe"
def test_structure_fe_is_the_fe_model_itself():
    sp = reference_spindle()
    inputs = MultivariateNormal([1.0, 1.0], std=[0.06, 0.06])
    counter = CallCounter()
    tr = train_surrogate(sp, inputs, LimitState(1.5e-6), FEOptions(),
                         rng=np.random.default_rng(0), counter=counter,
                         response=ResponseSpec("at_speed", 24000.0))
    fm, info = tr.model, tr.info
    assert isinstance(tr, TrainedSurrogate) and tr.in_loop == "fe"
    assert isinstance(fm, FullModel) and counter.calls == 0 and tr.fe_calls == 0
    X = np.array([[2000.0, 465.8, 65.0], [3000.0, 600.0, 80.0]])
    th = np.array([[1.0, 1.0], [0.95, 1.08]])
    assert isinstance(fm.fe, AtSpeedAmplitudeResponse) and fm.fe.speed_rpm == 24000.0
    assert fm.fe.method == "condensed" == info["fe_method"]    # "auto", at speed
    Z = np.column_stack([np.repeat(X, 2, axis=0), np.tile(th, (2, 1))])
    np.testing.assert_allclose(fm.response_points(Z), fm.response(X, th).ravel(), rtol=1e-12)


def test_global_surrogate_trains_on_the_chosen_response():
    """The DOE values are the at-speed FE amplitudes, not the peak (checks the wiring; the
    at-speed function itself is checked against a dense solve in tests/spindle)."""
    sp = reference_spindle()
    inputs = MultivariateNormal([1.0, 1.0], std=[0.06, 0.06])
    sur = train_surrogate(sp, inputs, LimitState(1.5e-6),
                          GlobalOptions(n_doe=8, n_jobs=1, n_start=1),
                          rng=np.random.default_rng(1),
                          response=ResponseSpec("at_speed", 20000.0)).model
    Z, t = sur.model.X_train_, sur.model.y_train_
    f = PointwiseAtSpeed(sp, 20000.0)
    np.testing.assert_allclose(np.exp(t), [f(z) for z in Z], rtol=1e-10)
    assert sur.info["response"] == "amplitude at 20000 rpm"


def test_resonance_structure_requires_the_peak_response():
    with pytest.raises(ValueError, match=r"structure = 'resonance' is not allowed with "
                                         r"response.kind = 'at_speed'"):
        train_surrogate(reference_spindle(), MultivariateNormal([1.0, 1.0], std=[0.06, 0.06]),
                        LimitState(1e-6), ResonanceOptions(), rng=np.random.default_rng(0),
                        response=ResponseSpec("at_speed", 24000.0))


def test_fe_method_is_checked_and_condensed_needs_the_at_speed_response():
    with pytest.raises(ValueError, match=r"fe_method = 'fast' is not allowed: must be one of "
                                         r"\['auto', 'direct', 'condensed'\]"):
        FEOptions(fe_method="fast")
    with pytest.raises(ValueError, match=r"fe_method = 'condensed' is not allowed with "
                                         r"response.kind = 'peak'"):
        train_surrogate(reference_spindle(), MultivariateNormal([1.0, 1.0], std=[0.06, 0.06]),
                        LimitState(1e-6), FEOptions(fe_method="condensed"),
                        rng=np.random.default_rng(0), response=ResponseSpec())
    tr = train_surrogate(reference_spindle(), None, None, FEOptions(fe_method="direct"),
                         rng=np.random.default_rng(0), response=ResponseSpec("at_speed", 24000.0))
    assert tr.model.fe.method == "direct"


def test_options_of_a_structure_have_no_fields_of_another():
    """Active learning is a field of the global Kriging only: the other structures cannot
    be given it (one options dataclass per structure)."""
    for opts in (FEOptions, ResonanceOptions):
        with pytest.raises(TypeError, match="active_learning"):
            opts(active_learning=True)
