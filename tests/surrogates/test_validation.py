import numpy as np
import pytest

from surrogate_rbrdo.core.protocols import LimitState
from surrogate_rbrdo.doe import lhs
from surrogate_rbrdo.reporting.plots_surrogate import parity_plot
from surrogate_rbrdo.surrogates import ProductKernelPredictor
from surrogate_rbrdo.surrogates.validation import (
    compare_mc,
    loo_cv,
    validate_on_points,
    validation_metrics,
)

from .conftest import BOUNDS5, f5


@pytest.mark.known_answer
def test_metrics_against_sklearn():
    from sklearn.metrics import mean_squared_error, r2_score

    rng = np.random.default_rng(0)
    yt, yp = rng.random(50), rng.random(50)
    m = validation_metrics(yt, yp)
    assert m.r2 == pytest.approx(r2_score(yt, yp))
    assert m.rmse == pytest.approx(np.sqrt(mean_squared_error(yt, yp)))
    assert m.nrmse == pytest.approx(m.rmse / (yt.max() - yt.min()))
    assert m.max_abs_error == pytest.approx(np.max(np.abs(yt - yp)))


def test_validate_on_points(fitted5):
    Zt = lhs(100, BOUNDS5, rng=np.random.default_rng(5))
    m = validate_on_points(fitted5["krg_se"], Zt, f5(Zt))
    assert m.n == 100 and m.r2 > 0.95


@pytest.mark.known_answer
def test_loo_closed_form_equals_explicit_leave_one_out(fitted5):
    """Dubrule's formula vs. dropping each point and re-solving the GLS Kriging system."""
    m = fitted5["krg_se"].model_
    C = m.optimal_par["C"]
    R = C @ C.T
    yn = m.y_norma.ravel()
    n = yn.size
    res = loo_cv(fitted5["krg_se"])
    for i in (0, 7, n - 1):
        k = np.arange(n) != i
        Ri = np.linalg.inv(R[np.ix_(k, k)])
        one = np.ones(n - 1)
        beta = one @ Ri @ yn[k] / (one @ Ri @ one)
        pred = beta + R[i, k] @ Ri @ (yn[k] - beta)
        assert res.y_loo[i] == pytest.approx(m.y_mean[0] + m.y_std[0] * pred, rel=1e-7)


@pytest.mark.known_answer
def test_loo_gpr_closed_form_equals_explicit(fitted5):
    g = fitted5["gpr"]
    K = g.model_.L_ @ g.model_.L_.T
    yn = (g.y_train_ - g.model_._y_train_mean) / g.model_._y_train_std
    res = loo_cv(g)
    i = 3
    k = np.arange(yn.size) != i
    pred = K[i, k] @ np.linalg.solve(K[np.ix_(k, k)], yn[k])
    assert res.y_loo[i] == pytest.approx(g.model_._y_train_mean + g.model_._y_train_std * pred,
                                         rel=1e-7)
    assert res.metrics.r2 > 0.8 and np.all(res.std_loo > 0)


def test_loo_refit_needs_factory(fitted5):
    with pytest.raises(ValueError, match="factory"):
        loo_cv(fitted5["gpr"], method="refit")


def test_compare_mc_grid_and_joint_agree(fitted5):
    rng = np.random.default_rng(2)
    x = rng.uniform([0, -1, 0], [1, 1, 2], size=(5, 3))
    theta = rng.normal(1.0, 0.06, size=(1000, 2))
    Z = np.column_stack([np.repeat(x, 1000, axis=0), np.tile(theta, (5, 1))])
    y_true = f5(Z).reshape(5, 1000)
    limit = LimitState(float(np.median(y_true)))
    fast = ProductKernelPredictor.from_model(fitted5["krg_se"], n_design=3)
    a = compare_mc(fast, x, theta, limit, y_true=y_true)
    b = compare_mc(fitted5["krg_se"], x, theta, limit,
                   response=lambda xx, tt: y_true)
    assert np.allclose(a.mean_sur, b.mean_sur, rtol=1e-8)
    assert np.allclose(a.mean_true, y_true.mean(1))
    assert np.array_equal(a.pf_true, (y_true > limit.threshold).mean(1))
    se = np.sqrt(a.pf_true * (1 - a.pf_true) / 1000)
    assert np.allclose(a.pf_tol, np.maximum(0.01, 3 * se))
    rows = a.rows()
    assert len(rows) == 5 and {"ok_mean", "ok_std", "ok_pf"} <= set(rows[0])
    with pytest.raises(ValueError, match="y_true"):
        compare_mc(fast, x, theta, limit)


def test_parity_plot(tmp_path):
    fig = parity_plot([1.0, 2.0, 3.0], [1.1, 1.9, 3.2], y_std=[0.1] * 3, label="y [m]")
    ax = fig.axes[0]
    assert ax.get_title() and ax.get_xlabel() == "true y [m]"
    lo, hi = ax.get_ylim()
    assert lo <= 1.0 - 0.2 and hi >= 3.2 + 0.2           # every error bar inside the axes
    fig.savefig(tmp_path / "parity.png")
    assert (tmp_path / "parity.png").stat().st_size > 1000
