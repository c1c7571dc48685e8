"""The model's side: Monte Carlo moments, moments the study already has, bands."""

import numpy as np
import pytest

from surrogate_rbrdo.uncertainty import Independent, Uniform
from surrogate_rbrdo.validation.model import ModelSpec, Moments, predict_model


def _linear(x, theta):
    return x[:, :1] * theta[:, 0][None, :]


def _curves(x, theta, speeds):
    return x[0] * theta[:, :1] * (np.asarray(speeds)[None, :] / 1000.0)


SPEC = ModelSpec({"peak": _linear}, Independent([Uniform(0.0, 1.0)]), n_samples=20000,
                 curves=_curves)


@pytest.mark.known_answer
def test_moments_and_band_of_a_closed_form_model():
    p = predict_model(SPEC, {"a": [2.0], "b": [4.0]}, delta_lim_m=3.0, confidence=0.95,
                      rng=np.random.default_rng(0), speeds_rpm=[1000.0, 2000.0],
                      band_samples=20000)
    b = p.moments["b"]["peak"]           # y = 4 U(0, 1): μ 2, σ 4/√12, P(y > 3) = 1/4
    assert b.mean_ci[0] < 2.0 < b.mean_ci[1]
    assert b.std_ci[0] < 4 / np.sqrt(12) < b.std_ci[1]
    assert b.pf_ci[0] < 0.25 < b.pf_ci[1]
    assert p.moments["a"]["peak"].pf == 0.0
    np.testing.assert_allclose(p.band_mean["b"], [2.0, 4.0], rtol=0.02)
    np.testing.assert_allclose(p.band_std["b"], np.array([1, 2]) * 4 / np.sqrt(12), rtol=0.02)
    assert p.n_calls == 2 * 20000 + 2 * 2 * 20000


def test_known_moments_are_used_as_given():
    known = Moments(1000, 1.0, 0.1, (0.8, 1.2), 0.5, 0.05, (0.4, 0.6), 0.1, (0.08, 0.12), 100)
    spec = ModelSpec({"peak": _linear}, Independent([Uniform(0.0, 1.0)]), n_samples=500,
                     known={"a": {"peak": known}})
    p = predict_model(spec, {"a": [2.0], "b": [4.0]}, delta_lim_m=3.0, confidence=0.95,
                      rng=np.random.default_rng(0))
    assert p.moments["a"]["peak"] is known
    assert p.n_calls == 500                    # only design b was estimated
    assert p.moments["b"]["peak"].n == 500


@pytest.mark.parametrize(("kw", "match"), [
    ({"responses": {}}, "responses"),
    ({"responses": {"max": _linear}}, "quantities"),
    ({"n_samples": 5}, "n_samples"),
])
def test_bad_spec(kw, match):
    args = {"responses": {"peak": _linear}, "inputs": Independent([Uniform(0.0, 1.0)])} | kw
    with pytest.raises(ValueError, match=match):
        ModelSpec(**args)
