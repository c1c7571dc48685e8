"""Contract tests run over every registered estimator: a new one is tested for free."""

import dataclasses
import json

import numpy as np
import pytest

from surrogate_rbrdo.core import CountingResponse, Estimate, LimitState, ModelError
from surrogate_rbrdo.estimators import ESTIMATORS, get_estimator
from surrogate_rbrdo.estimators.problems import linear_standard

NAMES = sorted(ESTIMATORS)
PROB = linear_standard(beta=2.3, dim=2, shifts=(0.0, 0.5))


def run(name, rng_seed=0, response=None, x=None, **kw):
    est = get_estimator(name)
    return est.estimate(response or PROB.response, PROB.inputs, PROB.limit,
                        PROB.x if x is None else x, rng=np.random.default_rng(rng_seed), **kw)


@pytest.mark.parametrize("name", NAMES)
def test_result_shapes_and_types(name):
    res = run(name)
    p = PROB.x.shape[0]
    assert isinstance(res, Estimate)
    assert res.method == name
    for f in ("mean", "std", "pf", "mean_se", "std_se", "pf_se"):
        assert getattr(res, f).shape == (p,), f
    assert res.pf_ci.shape == (p, 2)
    assert isinstance(res.n_calls, int) and res.n_calls > 0


@pytest.mark.parametrize("name", NAMES)
def test_pf_valid_and_accurate_on_linear(name):
    res = run(name)
    assert np.all((res.pf >= 0) & (res.pf <= 1))
    ci_ok = np.isnan(res.pf_ci).all(axis=1) | (
        (res.pf_ci[:, 0] <= res.pf) & (res.pf <= res.pf_ci[:, 1]))
    assert ci_ok.all()
    sampled = np.isfinite(res.pf_se) & (res.pf_se > 0)
    err = np.abs(res.pf - PROB.pf_exact)
    # sampling methods: within 4.5 standard errors; deterministic ones are exact on a linear g
    assert np.all(np.where(sampled, err <= 4.5 * res.pf_se, err <= 1e-4 * PROB.pf_exact))


@pytest.mark.parametrize("name", NAMES)
def test_to_dict_is_json_serialisable(name):
    d = json.loads(json.dumps(run(name).to_dict()))
    assert d["method"] == name and len(d["pf"]) == 2


@pytest.mark.parametrize("name", NAMES)
def test_n_calls_matches_counting_wrapper(name):
    counting = CountingResponse(PROB.response)
    res = run(name, response=counting)
    assert res.n_calls == counting.counter.calls


@pytest.mark.parametrize("name", NAMES)
def test_deterministic_given_rng(name):
    a, b = run(name, rng_seed=3), run(name, rng_seed=3)
    np.testing.assert_array_equal(a.pf, b.pf)
    np.testing.assert_array_equal(a.mean, b.mean)


@pytest.mark.parametrize("name", NAMES)
def test_frozen_options_and_result(name):
    est = get_estimator(name)
    f = dataclasses.fields(est)[0].name
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(est, f, getattr(est, f))
    with pytest.raises(dataclasses.FrozenInstanceError):
        run(name).pf = np.zeros(2)


@pytest.mark.parametrize("name", NAMES)
def test_invalid_options_name_the_field(name):
    for f in dataclasses.fields(ESTIMATORS[name]):
        if not f.init:
            continue
        default = f.default
        bad = "bogus" if isinstance(default, str) else -1
        with pytest.raises(ValueError, match=f.name):
            get_estimator(name, **{f.name: bad})
    with pytest.raises(ValueError, match="unknown option"):
        get_estimator(name, not_an_option=1)


@pytest.mark.parametrize("name", NAMES)
def test_rng_none_rejected(name):
    est = get_estimator(name)
    with pytest.raises(ValueError, match="Generator"):
        est.estimate(PROB.response, PROB.inputs, PROB.limit, PROB.x, rng=None)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("x", [np.zeros(2), np.zeros((0, 1)), np.full((1, 1), np.nan)])
def test_bad_design_batch(name, x):
    with pytest.raises(ValueError, match="x "):
        run(name, x=x)


@pytest.mark.parametrize("name", NAMES)
def test_nan_response_is_a_model_error(name):
    def resp(x, t):
        y = PROB.response(x, t)
        y[:, 0] = np.nan
        return y
    with pytest.raises(ModelError, match="nan"):
        run(name, response=resp)


@pytest.mark.parametrize("name", NAMES)
def test_wrong_response_shape_is_a_model_error(name):
    with pytest.raises(ModelError, match="shape"):
        run(name, response=lambda x, t: PROB.response(x, t).T)


@pytest.mark.parametrize("name", NAMES)
def test_fixed_u_accepted_and_checked(name):
    u = np.random.default_rng(5).standard_normal((2000, 2))
    res = run(name, u=u)
    assert res.pf.shape == (2,)
    with pytest.raises(ValueError, match="u has shape"):
        run(name, u=u[:, :1])


@pytest.mark.parametrize("name", NAMES)
def test_no_design_variables(name):
    prob = linear_standard(beta=2.0, dim=2)
    res = get_estimator(name).estimate(prob.response, prob.inputs, prob.limit,
                                       np.zeros((1, 0)), rng=np.random.default_rng(0))
    assert res.pf.shape == (1,)


def test_limit_state_direction_below():
    # failure y < -2.3 is the mirror image of failure y > 2.3 for symmetric y
    for name in NAMES:
        res = get_estimator(name).estimate(PROB.response, PROB.inputs,
                                           LimitState(-2.3, failure_if="below"), np.zeros((1, 1)),
                                           rng=np.random.default_rng(0))
        exact = PROB.pf_exact[0]
        se = res.pf_se[0] if np.isfinite(res.pf_se[0]) and res.pf_se[0] > 0 else 1e-4 * exact
        assert abs(res.pf[0] - exact) <= 4.5 * se, name


def test_registry_unknown_name_lists_known():
    with pytest.raises(ValueError, match="known: .*mc"):
        get_estimator("no_such_method")
