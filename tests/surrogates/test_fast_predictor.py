import numpy as np
import pytest

from surrogate_rbrdo.surrogates.fast import ProductKernelPredictor, ThetaBlock


def joint(x, t):
    P, N = x.shape[0], t.shape[0]
    return np.column_stack([np.repeat(x, N, axis=0), np.tile(t, (P, 1))])


@pytest.mark.known_answer
@pytest.mark.parametrize("name", ["krg_se", "krg_matern52"])
def test_agrees_with_smt(name, fitted5):
    m = fitted5[name]
    rng = np.random.default_rng(42)
    x = rng.uniform([0, -1, 0], [1, 1, 2], size=(13, 3))
    t = rng.uniform(0.5, 1.5, size=(17, 2))
    fast = ProductKernelPredictor.from_model(m, n_design=3)
    pred = fast.predict_grid(x, t, return_std=True)
    J = joint(x, t)
    ref_mean = m.model_.predict_values(J).reshape(13, 17)
    ref_var = m.model_.predict_variances(J).reshape(13, 17)
    assert pred.mean.shape == (13, 17) and pred.std.shape == (13, 17)
    rel = np.abs(pred.mean - ref_mean) / np.abs(ref_mean)
    assert rel.max() <= 1e-8
    assert np.allclose(pred.std**2, ref_var, rtol=1e-6, atol=1e-12 * ref_var.max())


@pytest.mark.known_answer
def test_agrees_with_sklearn(fitted5):
    m = fitted5["gpr"]
    rng = np.random.default_rng(43)
    x = rng.uniform([0, -1, 0], [1, 1, 2], size=(6, 3))
    t = rng.uniform(0.5, 1.5, size=(8, 2))
    pred = ProductKernelPredictor.from_model(m, n_design=3).predict_grid(x, t, return_std=True)
    ref_mean, ref_std = m.model_.predict((joint(x, t) - m.X_offset_) / m.X_scale_,
                                         return_std=True)
    assert np.max(np.abs(pred.mean.ravel() - ref_mean) / np.abs(ref_mean)) <= 1e-8
    assert np.allclose(pred.std.ravel(), ref_std, rtol=1e-6)


def test_theta_block_reuse_and_std_placeholder(fitted5):
    fast = ProductKernelPredictor.from_model(fitted5["krg_se"], n_design=3)
    rng = np.random.default_rng(0)
    t = rng.uniform(0.5, 1.5, size=(20, 2))
    block = fast.prepare_theta(t)
    assert isinstance(block, ThetaBlock) and block.Kt.shape == (20, 40)
    for _ in range(2):
        x = rng.uniform([0, -1, 0], [1, 1, 2], size=(5, 3))
        a = fast.predict_grid(x, block)
        b = fast.predict_grid(x, t)
        assert np.array_equal(a.mean, b.mean)
        assert a.std.shape == (5, 20) and np.all(np.isnan(a.std))


def test_variance_chunking_matches(fitted5):
    m = fitted5["krg_matern52"]
    base = ProductKernelPredictor.from_model(m, n_design=3)
    small = ProductKernelPredictor.from_model(m, n_design=3)
    object.__setattr__(small, "chunk_elements", 1)  # one design per chunk
    rng = np.random.default_rng(1)
    x, t = rng.random((4, 3)), rng.uniform(0.5, 1.5, (3, 2))
    assert np.allclose(base.predict_grid(x, t, return_std=True).std,
                       small.predict_grid(x, t, return_std=True).std, rtol=1e-12)


def test_bad_inputs(fitted5):
    fast = ProductKernelPredictor.from_model(fitted5["krg_se"], n_design=3)
    with pytest.raises(ValueError, match="x has 2 columns"):
        fast.predict_grid(np.zeros((2, 2)), np.ones((2, 2)))
    with pytest.raises(ValueError, match="t has 3 columns"):
        fast.prepare_theta(np.ones((2, 3)))
    with pytest.raises(ValueError, match="model"):
        ProductKernelPredictor.from_model(object(), n_design=1)
    with pytest.raises(ValueError, match="n_design"):
        ProductKernelPredictor.from_model(fitted5["krg_se"], n_design=6)


def test_rejects_non_product_sklearn_kernel():
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import Matern

    rng = np.random.default_rng(0)
    X = rng.random((10, 2))
    g = GaussianProcessRegressor(kernel=Matern(nu=2.5), random_state=0).fit(X, X.sum(1))
    with pytest.raises(ValueError, match="RBF"):
        ProductKernelPredictor.from_model(g, n_design=1)
