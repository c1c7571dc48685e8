"""smt Kriging (ordinary Kriging: constant trend) with squared-exponential or Matérn 5/2 kernel.

smt standardises inputs and output itself (mean and ``ddof=1`` standard deviation of the training
data); the wrappers pass raw inputs. Training is seeded through smt's ``seed`` option with an
integer drawn from the generator given at construction, and BLAS is pinned to
``options.blas_threads`` threads in ``fit`` and ``predict``.

>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> X = rng.random((12, 1)); y = np.sin(6 * X[:, 0])
>>> m = KrgSE(rng=np.random.default_rng(1)).fit(X, y)
>>> pred = m.predict(X[:3])
>>> bool(np.allclose(pred.mean, y[:3], atol=1e-6)), pred.std.shape
(True, (3,))
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.protocols import Prediction
from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive
from surrogate_rbrdo.surrogates._common import (
    SurrogateWrapper,
    blas_threads,
    check_predict_input,
    seed_from,
)
from surrogate_rbrdo.surrogates.registry import SURROGATES


@dataclass(frozen=True)
class KrigingOptions:
    """Options of the smt Kriging wrappers (the TOML schema of ``[surrogate]``).

    Attributes
    ----------
    theta0 : float or tuple of float
        Initial correlation parameter(s), in smt's units (normalised inputs): one value for
        every dimension, or one per dimension.
    theta_lower, theta_upper : float
        Bounds of the correlation parameters in the likelihood optimisation.
    n_start : int
        Number of multistart points of the hyperparameter optimisation.
    hyper_opt : {"TNC", "Cobyla", "NoOp"}
        smt optimiser; ``"NoOp"`` keeps ``theta0`` (fixed hyperparameters).
    nugget : float
        Diagonal regularisation of the correlation matrix.
    blas_threads : int
        BLAS threads during fit/predict (0: do not touch the thread pools).
    """

    theta0: float | tuple[float, ...] = 1e-2
    theta_lower: float = 1e-6
    theta_upper: float = 20.0
    n_start: int = 10
    hyper_opt: str = "TNC"
    nugget: float = 100.0 * np.finfo(float).eps
    blas_threads: int = 1

    def __post_init__(self) -> None:
        if np.ndim(self.theta0) == 0:
            check_positive("theta0", self.theta0)
        else:
            object.__setattr__(self, "theta0", tuple(float(t) for t in self.theta0))
            for i, t in enumerate(self.theta0):
                check_positive(f"theta0[{i}]", t)
        check_positive("theta_lower", self.theta_lower)
        check_positive("theta_upper", self.theta_upper)
        if not self.theta_lower < self.theta_upper:
            raise ValueError(
                f"theta_upper = {self.theta_upper!r} is not allowed: must be > theta_lower = "
                f"{self.theta_lower!r}"
            )
        check_int("n_start", self.n_start, minimum=1)
        check_choice("hyper_opt", self.hyper_opt, ("TNC", "Cobyla", "NoOp"))
        check_positive("nugget", self.nugget)
        check_int("blas_threads", self.blas_threads, minimum=0)


class _SmtKriging(SurrogateWrapper):
    """Common code of the smt KRG wrappers; subclasses fix ``corr``."""

    options_cls = KrigingOptions
    corr: str = ""

    def _theta0(self, D: int) -> list[float]:
        t0 = self.options.theta0
        if np.ndim(t0) == 0:
            return [float(t0)] * D
        if len(t0) != D:
            raise ValueError(f"theta0 has {len(t0)} values is not allowed: the data have "
                             f"{D} input dimensions")
        return list(t0)

    def fit(self, X: np.ndarray, y: np.ndarray) -> _SmtKriging:
        """Fit on ``X`` (n, D) and ``y`` (n,); returns ``self``."""
        from smt.surrogate_models import KRG  # heavy (~1 s import): only when fitting

        rng, X, y = self._start_fit(X, y)
        o = self.options
        D = X.shape[1]
        model = KRG(
            corr=self.corr,
            poly="constant",
            theta0=self._theta0(D),
            theta_bounds=[o.theta_lower, o.theta_upper],
            n_start=o.n_start,
            hyper_opt=o.hyper_opt,
            nugget=o.nugget,
            seed=seed_from(rng),
            print_global=False,
        )
        model.set_training_values(X, y)
        with blas_threads(self._threads()):
            model.train()
        self._store_fit(model, X, y)
        return self

    def predict(self, X: np.ndarray, *, return_std: bool = True) -> Prediction:
        """Mean and standard deviation at ``X`` (n, D): 1-D arrays of length n.

        ``return_std=False`` skips the variance (most of the cost; ``std`` is then NaN).
        """
        X = check_predict_input(X, self.n_features_in_)
        with blas_threads(self._threads()):
            mean = self.model_.predict_values(X).ravel()
            if not return_std:
                return Prediction(mean=mean, std=np.full_like(mean, np.nan))
            var = self.model_.predict_variances(X).ravel()
        return Prediction(mean=mean, std=np.sqrt(np.maximum(var, 0.0)))


@SURROGATES.register("krg_se")
class KrgSE(_SmtKriging):
    """smt ``KRG``: ordinary Kriging, squared-exponential kernel ``exp(-Σ θ_j d_j²)``.

    Parameters
    ----------
    options : KrigingOptions, optional
    rng : numpy.random.Generator
        Seeds the hyperparameter multistart.
    """

    corr = "squar_exp"


@SURROGATES.register("krg_matern52")
class KrgMatern52(_SmtKriging):
    """smt ``KRG``: ordinary Kriging, product Matérn 5/2 kernel (smt's definition).

    ``r = Π_j (1 + √5 l_j + 5/3 l_j²) · exp(-√5 Σ_j l_j)``, ``l_j = θ_j |d_j|``.
    """

    corr = "matern52"
