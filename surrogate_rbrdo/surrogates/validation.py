"""Validation of a surrogate against the true model: hold-out metrics, leave-one-out, MC stats.

Metrics (``y`` true, ``ŷ`` predicted, ``n`` points)::

    R²    = 1 - Σ(y - ŷ)² / Σ(y - ȳ)²
    RMSE  = sqrt(mean((y - ŷ)²))
    NRMSE = RMSE / (max(y) - min(y))        (range-normalised)
    max abs error = max |y - ŷ|

>>> import numpy as np
>>> m = validation_metrics(np.array([1.0, 2.0, 3.0]), np.array([1.0, 2.0, 4.0]))
>>> round(m.r2, 3), round(m.rmse, 4), round(m.nrmse, 4), m.max_abs_error
(0.5, 0.5774, 0.2887, 1.0)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from scipy import linalg

from surrogate_rbrdo.core.protocols import LimitState, Surrogate
from surrogate_rbrdo.core.validate import check_choice, check_finite_array


@dataclass(frozen=True)
class ValidationMetrics:
    """Accuracy of predictions against true values (see the module docstring)."""

    r2: float
    rmse: float
    nrmse: float
    max_abs_error: float
    n: int

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def validation_metrics(y_true: np.ndarray, y_pred: np.ndarray) -> ValidationMetrics:
    """R², RMSE, NRMSE (by the range of ``y_true``) and max abs error."""
    yt = check_finite_array("y_true", np.ravel(y_true), ndim=1)
    yp = check_finite_array("y_pred", np.ravel(y_pred), ndim=1)
    if yt.shape != yp.shape or yt.size < 2:
        raise ValueError(
            f"y_pred has shape {yp.shape} is not allowed: must match y_true {yt.shape}, n >= 2"
        )
    res = yt - yp
    ss_tot = np.sum((yt - yt.mean()) ** 2)
    rmse = float(np.sqrt(np.mean(res**2)))
    span = float(np.ptp(yt))
    return ValidationMetrics(
        r2=float(1.0 - np.sum(res**2) / ss_tot) if ss_tot > 0 else float("nan"),
        rmse=rmse,
        nrmse=rmse / span if span > 0 else float("nan"),
        max_abs_error=float(np.max(np.abs(res))),
        n=int(yt.size),
    )


def validate_on_points(surrogate: Surrogate, X_test: np.ndarray,
                       y_test: np.ndarray) -> ValidationMetrics:
    """Metrics of ``surrogate.predict(X_test).mean`` against ``y_test`` (fresh points)."""
    return validation_metrics(y_test, surrogate.predict(X_test).mean)


@dataclass(frozen=True)
class LOOResult:
    """Leave-one-out cross-validation: predictions at each training point without it."""

    y_true: np.ndarray
    y_loo: np.ndarray
    std_loo: np.ndarray
    metrics: ValidationMetrics
    method: str

    @property
    def standardized_residuals(self) -> np.ndarray:
        """``(y - ŷ_loo) / s_loo``: roughly N(0, 1) for a well-calibrated model."""
        return (self.y_true - self.y_loo) / self.std_loo


def loo_cv(surrogate: Any, *, method: str = "closed_form",
           factory: Callable[[], Surrogate] | None = None) -> LOOResult:
    """Leave-one-out cross-validation of a fitted surrogate.

    ``method="closed_form"`` (fitted :class:`KrgSE`/:class:`KrgMatern52`/:class:`GPR`) uses
    Dubrule's (1983) formulas with the hyperparameters *fixed* at their full-data values:
    with ``Q = R⁻¹ - R⁻¹F(FᵀR⁻¹F)⁻¹FᵀR⁻¹`` (``F = 1`` for ordinary Kriging; ``Q = K⁻¹`` for
    the GPR without trend), the LOO residual is ``e_i = (Q y)_i / Q_ii`` and the LOO variance
    ``σ² / Q_ii``. Exact (not an approximation) for fixed hyperparameters, including the
    re-estimated trend, but the input/output normalisation is the full-data one.

    ``method="refit"`` refits ``factory()`` (an unfitted surrogate) ``n`` times, hyperparameters
    included: expensive, for small designs or as a cross-check.
    """
    check_choice("method", method, ("closed_form", "refit"))
    X, y = surrogate.X_train_, surrogate.y_train_
    if method == "refit":
        if factory is None:
            raise ValueError("factory = None is not allowed with method='refit': pass a callable")
        mean, std = np.empty_like(y), np.empty_like(y)
        for i in range(y.size):
            keep = np.arange(y.size) != i
            p = factory().fit(X[keep], y[keep]).predict(X[i:i + 1])
            mean[i], std[i] = p.mean[0], p.std[0]
    else:
        mean, std = _closed_form_loo(surrogate)
    return LOOResult(y_true=y, y_loo=mean, std_loo=std,
                     metrics=validation_metrics(y, mean), method=method)


def _closed_form_loo(surrogate: Any) -> tuple[np.ndarray, np.ndarray]:
    inner = surrogate.model_
    name = type(inner).__name__
    if name == "KRG":
        C = inner.optimal_par["C"]
        Rinv = linalg.cho_solve((C, True), np.eye(C.shape[0]))
        F = inner.F.reshape(C.shape[0], -1)
        RF = Rinv @ F
        Q = Rinv - RF @ np.linalg.solve(F.T @ RF, RF.T)
        yn = np.asarray(inner.y_norma, dtype=float).ravel()
        y_std = float(np.ravel(inner.y_std)[0])
        sigma2 = float(np.ravel(inner.optimal_par["sigma2"])[0])
    elif name == "GaussianProcessRegressor":
        L = inner.L_
        Q = linalg.cho_solve((L, True), np.eye(L.shape[0]))
        y_std = float(np.ravel(inner._y_train_std)[0])
        yn = (surrogate.y_train_ - float(np.ravel(inner._y_train_mean)[0])) / y_std
        sigma2 = y_std**2
    else:
        raise ValueError(
            f"surrogate = {type(surrogate).__name__} is not allowed for the closed form: "
            "use method='refit' with a factory"
        )
    q = np.diag(Q)
    resid = (Q @ yn) / q * y_std
    return surrogate.y_train_ - resid, np.sqrt(sigma2 / q)


@dataclass(frozen=True, eq=False)
class LOOSummary:
    """Leave-one-out of a fitted structure at its training points, in ``y`` units.

    ``method`` names how (``closed_form``: Dubrule's formula on the Kriging of ``t(y)``;
    ``closed_form_combined``: each sub-model's closed form, combined by the structure's rule;
    ``closed_form_condensed``: the Kriging of the condensed rotor, coupled at nominal θ);
    ``r2_fitted``/``rmse_fitted`` are in the space the model was fitted in (``log y`` for the
    structured models); ``sub`` holds each sub-model's own :class:`LOOResult`.
    """

    method: str
    n_train: int
    r2_fitted: float
    rmse_fitted: float
    y_true: np.ndarray
    y_loo: np.ndarray
    sub: dict[str, LOOResult]


@dataclass(frozen=True)
class MCComparison:
    """Surrogate-MC vs true-MC statistics at designs, with the same θ sample.

    Arrays have one entry per design. ``pf_tol = max(1 percentage point, 3 · SE)`` with
    ``SE = sqrt(p(1-p)/N)`` of the true-MC estimate; ``ok_*`` flag the issue's targets
    (μ and σ within ``rel_tol`` = 5 %, P_f within ``pf_tol``).
    """

    x: np.ndarray
    mean_true: np.ndarray
    mean_sur: np.ndarray
    std_true: np.ndarray
    std_sur: np.ndarray
    pf_true: np.ndarray
    pf_sur: np.ndarray
    pf_tol: np.ndarray
    n_theta: int
    rel_tol: float

    @property
    def mean_rel_err(self) -> np.ndarray:
        return np.abs(self.mean_sur - self.mean_true) / np.abs(self.mean_true)

    @property
    def std_rel_err(self) -> np.ndarray:
        return np.abs(self.std_sur - self.std_true) / self.std_true

    @property
    def ok_mean(self) -> np.ndarray:
        return self.mean_rel_err <= self.rel_tol

    @property
    def ok_std(self) -> np.ndarray:
        return self.std_rel_err <= self.rel_tol

    @property
    def ok_pf(self) -> np.ndarray:
        return np.abs(self.pf_sur - self.pf_true) <= self.pf_tol

    def rows(self) -> list[dict[str, Any]]:
        """One dict per design: the table of the issue (write it with any CSV writer)."""
        out = []
        for i in range(self.x.shape[0]):
            out.append({
                **{f"x{j}": float(v) for j, v in enumerate(self.x[i])},
                "mean_true": float(self.mean_true[i]), "mean_sur": float(self.mean_sur[i]),
                "mean_rel_err": float(self.mean_rel_err[i]),
                "std_true": float(self.std_true[i]), "std_sur": float(self.std_sur[i]),
                "std_rel_err": float(self.std_rel_err[i]),
                "pf_true": float(self.pf_true[i]), "pf_sur": float(self.pf_sur[i]),
                "pf_tol": float(self.pf_tol[i]),
                "ok_mean": bool(self.ok_mean[i]), "ok_std": bool(self.ok_std[i]),
                "ok_pf": bool(self.ok_pf[i]),
            })
        return out

    def to_dict(self) -> dict[str, Any]:
        return {"n_theta": self.n_theta, "rel_tol": self.rel_tol, "rows": self.rows()}


def compare_mc(surrogate: Any, x: np.ndarray, theta: np.ndarray, limit: LimitState, *,
               y_true: np.ndarray | None = None, response: Any = None,
               rel_tol: float = 0.05) -> MCComparison:
    """Compare μ_y, σ_y, P_f from surrogate-MC and true-MC at designs ``x`` (P, d).

    Parameters
    ----------
    surrogate : ProductKernelPredictor or Surrogate
        Anything with ``predict_grid(x, theta)`` (used if present) or ``predict(Z)`` on joint
        points ``Z = [x, θ]``.
    x, theta : ndarray, shapes (P, d) and (N, m)
        Designs and the θ sample shared by both estimates (common random numbers).
    limit : LimitState
        Failure definition.
    y_true : ndarray (P, N), optional
        True-model values on the grid (e.g. from :func:`~surrogate_rbrdo.sampling.evaluate_points`).
    response : Response, optional
        Vectorised true model ``response(x, theta) -> (P, N)``, used if ``y_true`` is None.
    """
    x = check_finite_array("x", np.atleast_2d(x), ndim=2)
    theta = check_finite_array("theta", np.atleast_2d(theta), ndim=2)
    P, N = x.shape[0], theta.shape[0]
    if y_true is None:
        if response is None:
            raise ValueError("y_true = None is not allowed without a response: pass one of them")
        y_true = response(x, theta)
    y_true = check_finite_array("y_true", y_true, ndim=2)
    if y_true.shape != (P, N):
        raise ValueError(f"y_true has shape {y_true.shape} is not allowed: must be {(P, N)}")
    if hasattr(surrogate, "predict_grid"):
        y_sur = np.asarray(surrogate.predict_grid(x, theta).mean)
    else:
        Z = np.column_stack([np.repeat(x, N, axis=0), np.tile(theta, (P, 1))])
        y_sur = surrogate.predict(Z).mean.reshape(P, N)
    pf_t = limit.failed(y_true).mean(axis=1)
    se = np.sqrt(pf_t * (1.0 - pf_t) / N)
    return MCComparison(
        x=x, mean_true=y_true.mean(1), mean_sur=y_sur.mean(1),
        std_true=y_true.std(1, ddof=1), std_sur=y_sur.std(1, ddof=1),
        pf_true=pf_t, pf_sur=limit.failed(y_sur).mean(axis=1),
        pf_tol=np.maximum(0.01, 3.0 * se), n_theta=N, rel_tol=float(rel_tol),
    )
