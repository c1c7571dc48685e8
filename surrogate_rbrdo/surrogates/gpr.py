"""scikit-learn Gaussian process regression with a constant × ARD RBF kernel.

Inputs are standardised here the same way smt does it (training mean and ``ddof=1`` standard
deviation per column), the output by ``normalize_y=True``. The kernel is
``c · exp(-½ Σ_j (d_j / l_j)²)`` (a product kernel, so the fast batch predictor applies).

>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> X = rng.random((12, 1)); y = np.sin(6 * X[:, 0])
>>> m = GPR(rng=np.random.default_rng(1)).fit(X, y)
>>> bool(np.allclose(m.predict(X[:3]).mean, y[:3], atol=1e-4))
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.protocols import Prediction
from surrogate_rbrdo.core.validate import check_int, check_positive
from surrogate_rbrdo.surrogates._common import (
    SurrogateWrapper,
    blas_threads,
    check_predict_input,
    seed_from,
)
from surrogate_rbrdo.surrogates.registry import SURROGATES


@dataclass(frozen=True)
class GPROptions:
    """Options of :class:`GPR`.

    Attributes
    ----------
    length_scale_lower, length_scale_upper : float
        Bounds of the ARD length scales (standardised inputs).
    constant_lower, constant_upper : float
        Bounds of the kernel amplitude (normalised output).
    alpha : float
        Jitter added to the kernel diagonal.
    n_restarts : int
        Restarts of the marginal-likelihood optimiser (random starts drawn from the seed).
    blas_threads : int
        BLAS threads during fit/predict (0: do not touch the thread pools).
    """

    length_scale_lower: float = 1e-2
    length_scale_upper: float = 1e3
    constant_lower: float = 1e-3
    constant_upper: float = 1e3
    alpha: float = 1e-10
    n_restarts: int = 3
    blas_threads: int = 1

    def __post_init__(self) -> None:
        for name in ("length_scale_lower", "length_scale_upper", "constant_lower",
                     "constant_upper", "alpha"):
            check_positive(name, getattr(self, name))
        for lo, hi in (("length_scale_lower", "length_scale_upper"),
                       ("constant_lower", "constant_upper")):
            if not getattr(self, lo) < getattr(self, hi):
                raise ValueError(
                    f"{hi} = {getattr(self, hi)!r} is not allowed: must be > {lo} = "
                    f"{getattr(self, lo)!r}"
                )
        check_int("n_restarts", self.n_restarts, minimum=0)
        check_int("blas_threads", self.blas_threads, minimum=0)


@SURROGATES.register("gpr")
class GPR(SurrogateWrapper):
    """scikit-learn ``GaussianProcessRegressor`` with ``ConstantKernel * RBF(ARD)``.

    Parameters
    ----------
    options : GPROptions, optional
    rng : numpy.random.Generator
        Seeds the optimiser restarts.
    """

    options_cls = GPROptions

    def fit(self, X: np.ndarray, y: np.ndarray) -> GPR:
        """Fit on ``X`` (n, D) and ``y`` (n,); returns ``self``."""
        # heavy (~0.8 s import): only when a GPR is fitted
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import RBF, ConstantKernel

        rng, X, y = self._start_fit(X, y)
        o = self.options
        D = X.shape[1]
        offset = X.mean(axis=0)
        scale = X.std(axis=0, ddof=1)
        scale[scale < 100.0 * np.finfo(float).eps] = 1.0
        kernel = ConstantKernel(1.0, (o.constant_lower, o.constant_upper)) * RBF(
            length_scale=np.ones(D), length_scale_bounds=(o.length_scale_lower,
                                                          o.length_scale_upper)
        )
        model = GaussianProcessRegressor(
            kernel=kernel, alpha=o.alpha, normalize_y=True,
            n_restarts_optimizer=o.n_restarts, random_state=seed_from(rng),
        )
        with blas_threads(self._threads()):
            model.fit((X - offset) / scale, y)
        self._store_fit(model, X, y)
        self.X_offset_ = offset
        self.X_scale_ = scale
        return self

    def predict(self, X: np.ndarray, *, return_std: bool = True) -> Prediction:
        """Mean and standard deviation at ``X`` (n, D): 1-D arrays of length n.

        ``return_std=False`` skips the standard deviation (``std`` is then NaN).
        """
        X = check_predict_input(X, self.n_features_in_)
        with blas_threads(self._threads()):
            Xn = (X - self.X_offset_) / self.X_scale_
            if not return_std:
                mean = np.asarray(self.model_.predict(Xn), dtype=float).ravel()
                return Prediction(mean=mean, std=np.full_like(mean, np.nan))
            mean, std = self.model_.predict(Xn, return_std=True)
        return Prediction(mean=np.asarray(mean, dtype=float).ravel(),
                          std=np.asarray(std, dtype=float).ravel())
