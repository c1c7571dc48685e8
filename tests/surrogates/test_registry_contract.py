import numpy as np
import pytest

from surrogate_rbrdo.core.protocols import Prediction
from surrogate_rbrdo.doe import lhs
from surrogate_rbrdo.surrogates import SURROGATES, GPROptions, KrigingOptions

from .conftest import BOUNDS5, f5, make


def test_registry_names():
    assert set(SURROGATES) == {"krg_se", "krg_matern52", "gpr"}
    with pytest.raises(ValueError, match="known: gpr, krg_matern52, krg_se"):
        SURROGATES.get("rbf")


@pytest.mark.parametrize("name", ["krg_se", "krg_matern52", "gpr"])
def test_contract(name, fitted5, data5):
    Z, y = data5
    m = fitted5[name]
    assert all(hasattr(m, a) for a in ("X_train_", "y_train_", "n_features_in_"))
    assert m.n_features_in_ == 5
    Zt = lhs(30, BOUNDS5, rng=np.random.default_rng(99))
    p = m.predict(Zt)
    assert isinstance(p, Prediction)
    assert p.mean.shape == (30,) and p.std.shape == (30,)
    assert np.all(p.std >= 0)
    # interpolates the training data (tiny nugget), and is accurate on fresh points
    assert np.allclose(m.predict(Z[:5]).mean, y[:5], atol=1e-4 * np.ptp(y))
    rmse = np.sqrt(np.mean((p.mean - f5(Zt)) ** 2))
    assert rmse < 0.1 * np.std(f5(Zt))


@pytest.mark.parametrize("name", ["krg_se", "gpr"])
def test_seeded_training_reproducible(name, data5):
    Z, y = data5
    a = make(name, np.random.default_rng(1)).fit(Z, y).predict(Z[:3] + 0.01).mean
    b = make(name, np.random.default_rng(1)).fit(Z, y).predict(Z[:3] + 0.01).mean
    assert np.array_equal(a, b)


def test_constructor_only_stores():
    m = SURROGATES["krg_se"](rng=np.random.default_rng(0))
    assert not hasattr(m, "model_")


@pytest.mark.parametrize("name", ["krg_se", "gpr"])
def test_bad_inputs(name, fitted5):
    m = make(name, np.random.default_rng(0))
    with pytest.raises(ValueError, match="dimension"):
        m.fit(np.zeros((3, 5)), np.zeros(3))
    with pytest.raises(ValueError, match="non-finite"):
        m.fit(np.ones((8, 2)) * np.arange(8)[:, None], np.r_[np.nan, np.ones(7)])
    with pytest.raises(ValueError, match="columns"):
        fitted5[name].predict(np.zeros((2, 4)))
    with pytest.raises(ValueError, match="rng"):
        SURROGATES[name](rng=None).fit(np.random.default_rng(0).random((8, 2)), np.ones(8))


def test_options_validated():
    with pytest.raises(ValueError, match="theta_upper"):
        KrigingOptions(theta_lower=1.0, theta_upper=0.5)
    with pytest.raises(ValueError, match="hyper_opt"):
        KrigingOptions(hyper_opt="BFGS")
    with pytest.raises(ValueError, match="n_restarts"):
        GPROptions(n_restarts=-1)


@pytest.mark.parametrize("name", ["krg_se", "krg_matern52"])
def test_fixed_per_dimension_theta0_is_kept(name, data5):
    Z, y = data5
    t0 = (0.3, 0.05, 1.2, 0.01, 2.0)
    m = SURROGATES[name](KrigingOptions(theta0=t0, hyper_opt="NoOp"),
                         rng=np.random.default_rng(0)).fit(Z, y)
    np.testing.assert_allclose(np.ravel(m.model_.optimal_theta), t0, rtol=1e-12)
    with pytest.raises(ValueError, match=r"theta0\[1\] = -1.0 is not allowed"):
        KrigingOptions(theta0=(1.0, -1.0))
    with pytest.raises(ValueError, match="theta0 has 2 values is not allowed"):
        SURROGATES[name](KrigingOptions(theta0=(1.0, 2.0)),
                         rng=np.random.default_rng(0)).fit(Z, y)
