"""Unit and contract tests of the formulation registry."""

import numpy as np
import pytest

from surrogate_rbrdo.core import LimitState
from surrogate_rbrdo.formulations import (
    FORMULATIONS,
    DeterministicConstraints,
    DeterministicOptions,
    FormulationOptions,
    make_formulation,
)
from surrogate_rbrdo.uncertainty import MultivariateNormal

NO_DET = DeterministicOptions(stress=False, resonance="none")


def resp(x, theta):
    """y = x0 * θ0 + x1 * θ1 (P, N)."""
    return x @ theta.T


def inputs():
    return MultivariateNormal(np.array([1.0, 2.0]), std=np.array([0.5, 0.1]))


def det_model(x):
    return {"von_mises_pa": 500e6 * x[:, 0], "omega_n1": 3000.0 * x[:, 1],
            "critical_speeds": np.column_stack([1000.0 * x[:, 0], np.full(len(x), np.nan)])}


def build(name, rng=None, **opts):
    det = opts.pop("deterministic", NO_DET)
    return make_formulation(
        name, response=resp, inputs=inputs(), limit=LimitState(2.5),
        options=FormulationOptions(deterministic=det, **opts),
        rng=np.random.default_rng(0) if rng is None else rng, deterministic=det_model)


@pytest.mark.parametrize("name", sorted(FORMULATIONS))
def test_contract_shapes_and_determinism(name):
    form = build(name, n_theta=200, p_target=0.1, deterministic=DeterministicOptions())
    x = np.random.default_rng(1).uniform(0.5, 1.5, size=(7, 2))
    ev = form.evaluate(x)
    assert ev.F.shape == (7, form.n_obj) == (7, len(form.objective_names))
    assert ev.G.shape == (7, form.n_con) == (7, len(form.constraint_names))
    assert np.all(np.isfinite(ev.F)) and np.all(np.isfinite(ev.G))
    assert ev.n_model_calls == 7
    # a design's value does not depend on the batch it is evaluated in (CRN), up to the
    # rounding of the matmul response (BLAS blocks by batch size)
    ev1 = form.evaluate(x[3:4])
    np.testing.assert_allclose(ev1.F[0], ev.F[3], rtol=1e-12)
    np.testing.assert_allclose(ev1.G[0], ev.G[3], rtol=1e-12, atol=1e-12)


def test_objectives_match_closed_form_moments():
    form = build("rbrdo", n_theta=200_000, p_target=0.1)
    x = np.array([[1.0, 1.0], [0.2, 2.0]])
    ev = form.evaluate(x)
    mu = x @ np.array([1.0, 2.0])
    sd = np.sqrt((x * np.array([0.5, 0.1])) ** 2 @ np.ones(2))
    np.testing.assert_allclose(ev.F[:, 0], mu, atol=4 * sd.max() / np.sqrt(2e5))
    np.testing.assert_allclose(ev.F[:, 1], sd, rtol=0.01)
    from scipy.stats import norm

    pf = norm.sf((2.5 - mu) / sd)
    np.testing.assert_allclose(ev.G[:, 0], pf / 0.1 - 1.0, atol=0.05)
    assert ev.n_surrogate_calls == 2 * 200_000


def test_deterministic_uses_nominal_theta():
    form = build("deterministic", n_theta=50)
    ev = form.evaluate(np.array([[1.0, 1.0], [2.0, 0.0]]))
    np.testing.assert_allclose(ev.F[:, 0], [3.0, 2.0])
    assert ev.n_surrogate_calls == 2 and np.isnan(ev.estimate.std).all()


def test_deterministic_designs_against_the_worst_stated_case():
    cases = np.array([[1.0, 2.0], [2.0, 0.5], [0.0, 3.0]])
    form = make_formulation("deterministic", response=resp, inputs=inputs(),
                            limit=LimitState(2.5), rng=np.random.default_rng(0),
                            options=FormulationOptions(deterministic=NO_DET, n_theta=10),
                            design_theta=cases)
    x = np.array([[1.0, 1.0], [2.0, 0.0], [0.0, 1.0]])
    ev = form.evaluate(x)
    np.testing.assert_allclose(ev.F[:, 0], [3.0, 4.0, 3.0])    # max over the rows of x θᵀ
    assert ev.n_surrogate_calls == 9


@pytest.mark.parametrize("bad", [np.ones(2), np.ones((2, 3)), np.empty((0, 2)),
                                 np.array([[1.0, np.nan]])])
def test_design_theta_shape_is_checked(bad):
    with pytest.raises(ValueError, match="design_theta has shape"):
        make_formulation("deterministic", response=resp, inputs=inputs(),
                         limit=LimitState(2.5), rng=np.random.default_rng(0),
                         options=FormulationOptions(deterministic=NO_DET), design_theta=bad)


def test_common_random_numbers_across_formulations():
    a, b = build("rdo", n_theta=64), build("rbrdo", n_theta=64)
    np.testing.assert_array_equal(a.u, b.u)
    x = np.array([[0.7, 1.2]])
    np.testing.assert_array_equal(a.evaluate(x).F, b.evaluate(x).F)
    c = build("rdo", rng=np.random.default_rng(1), n_theta=64)
    assert not np.array_equal(a.u, c.u)


def test_constraint_order_and_values():
    form = build("rbdo", n_theta=100, p_target=0.5, deterministic=DeterministicOptions(
        resonance="paper", omega_max=1000.0, factor=1.0))
    assert form.constraint_names == ("pf", "stress", "resonance")
    ev = form.evaluate(np.array([[0.93, 0.5]]))
    np.testing.assert_allclose(ev.G[0, 1:], [500 * 0.93 / 930 - 1, 1 - 1500 / 1000])


def test_separation_margin_guard():
    opts = DeterministicOptions(stress=False, resonance="separation",
                                operating_speeds=(1000.0, 2000.0), margin=0.15)
    con = DeterministicConstraints(opts, det_model)
    g = con(np.array([[1.1, 0.0], [1.5, 0.0]]))   # critical speeds 1100 and 1500 (+ NaN)
    # 1100 is 10 % from 1000 → violated; 1500 is 25 % from 2000 and 50 % from 1000 → fine
    np.testing.assert_allclose(g, [[0.15 - 0.1, 0.15 - 0.45], [0.15 - 0.5, 0.15 - 0.25]])
    assert con.names == ("separation_0", "separation_1")


@pytest.mark.parametrize("kwargs, match", [
    ({"p_target": 0.0}, "p_target"),
    ({"p_target": 1.0}, "p_target"),
    ({"n_theta": 0}, "n_theta"),
    ({"ci_level": 1.0}, "ci_level"),
])
def test_bad_options(kwargs, match):
    with pytest.raises(ValueError, match=match):
        FormulationOptions(**kwargs)


@pytest.mark.parametrize("kwargs, match", [
    ({"resonance": "api"}, "resonance"),
    ({"resonance": "separation"}, "operating_speeds"),
    ({"yield_strength_pa": -1.0}, "yield_strength_pa"),
    ({"margin": 0.0}, "margin"),
])
def test_bad_deterministic_options(kwargs, match):
    with pytest.raises(ValueError, match=match):
        DeterministicOptions(**kwargs)


class _Spy:
    def __init__(self):
        self.calls = 0

    def standard_sample(self, n, *, rng):
        self.calls += 1
        return rng.standard_normal((n, 2))


def test_unknown_names_fail_before_any_work():
    spy = _Spy()
    with pytest.raises(ValueError, match="unknown formulation 'rbrd'; known: deterministic"):
        make_formulation("rbrd", response=resp, inputs=spy, limit=LimitState(1.0),
                         rng=np.random.default_rng(0))
    with pytest.raises(ValueError, match="known:"):
        make_formulation("rbrdo", response=resp, inputs=spy, limit=LimitState(1.0),
                         options=FormulationOptions(estimator="montecarlo"),
                         rng=np.random.default_rng(0))
    with pytest.raises(ValueError, match="deterministic model"):
        make_formulation("rbrdo", response=resp, inputs=spy, limit=LimitState(1.0),
                         rng=np.random.default_rng(0))   # default g_det but no FE callable
    with pytest.raises(ValueError, match="rng"):
        make_formulation("rdo", response=resp, inputs=spy, limit=LimitState(1.0),
                         options=FormulationOptions(deterministic=NO_DET), rng=None)
    assert spy.calls == 0


@pytest.mark.parametrize("name", ["form", "fosm", "is", "sorm", "subset"])
def test_every_registry_estimator_plugs_in(name):
    """Contract over the estimator registry (ais is covered by the estimators' own tests)."""
    from scipy.stats import norm

    form = build("rbrdo", n_theta=4000, p_target=0.1, estimator=name)
    x = np.array([[1.0, 1.0], [0.2, 1.0]])   # P_f ≈ 0.84 and 0.017
    ev = form.evaluate(x)
    assert ev.G.shape == (2, 1) and np.isfinite(ev.F).all() and np.isfinite(ev.G).all()
    assert ev.estimate.method == name
    # linear response, Gaussian θ: every method gets P_f and the moments about right
    mu = x @ np.array([1.0, 2.0])
    sd = np.sqrt((x * np.array([0.5, 0.1])) ** 2 @ np.ones(2))
    np.testing.assert_allclose(ev.F[:, 0], mu, rtol=0.02)
    np.testing.assert_allclose(ev.F[:, 1], sd, rtol=0.05)
    np.testing.assert_allclose(ev.estimate.pf, norm.sf((2.5 - mu) / sd), rtol=0.3, atol=1e-3)


def test_non_finite_objectives_raise():
    from surrogate_rbrdo.core import ModelError

    form = make_formulation(
        "rdo", response=lambda x, t: np.full((x.shape[0], t.shape[0]), np.nan),
        inputs=inputs(), limit=LimitState(1.0), rng=np.random.default_rng(0),
        options=FormulationOptions(n_theta=10, estimator="fosm", deterministic=NO_DET))
    with pytest.raises((ModelError, ValueError)):
        form.evaluate(np.ones((1, 2)))
