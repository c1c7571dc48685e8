"""A Kriging of ``t(y)`` over joint points ``z = [x, θ]`` with a fast CRN-grid response.

:func:`fit_transformed` fits a registered Kriging (``SURROGATES``: ``krg_se``,
``krg_matern52``, ``gpr``) to ``(Z, t(y))`` (:mod:`~surrogate_rbrdo.surrogates.transforms`)
and wraps it in :class:`TransformedKriging`, whose :meth:`~TransformedKriging.response` is the
core ``Response``: designs ``(P, d)`` × a θ sample ``(N, m)`` → ``(P, N)`` in the units of
``y``, through the separable predictor (one θ block per sample, cached on the sample's
identity) — the hot path of an optimiser that evaluates a population on one CRN sample.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.core.protocols import Prediction
from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_choice
from surrogate_rbrdo.surrogates.fast import ProductKernelPredictor
from surrogate_rbrdo.surrogates.gpr import GPROptions
from surrogate_rbrdo.surrogates.kriging import KrigingOptions
from surrogate_rbrdo.surrogates.registry import SURROGATES
from surrogate_rbrdo.surrogates.transforms import TRANSFORMS, forward, inverse
from surrogate_rbrdo.surrogates.validation import LOOSummary, loo_cv


@dataclass(eq=False)
class TransformedKriging:
    """Fitted Kriging of ``t(y)``; ``y`` (e.g. metres) at the interface.

    Calling it (or :meth:`response`) is the core ``Response``. The θ block of the separable
    predictor is cached keyed on the identity of the θ array (``id`` and shape; the array is
    kept referenced so the id cannot be reused): pass the same CRN sample object each time and
    every call costs one design block and one matrix product. Do not modify a θ array in place
    between calls (copy it instead).

    Attributes
    ----------
    model : Surrogate
        The fitted wrapper (``KrgSE``, ...), trained on ``(Z, t(y))``.
    fast : ProductKernelPredictor
    transform : {"log", "none"}
    n_design : int
        Number of leading design columns of ``z`` (the rest is θ).
    info : dict
    theta_block_builds : int
        How many θ blocks were computed (cache misses).
    """

    model: Any
    fast: ProductKernelPredictor
    transform: str
    n_design: int = 3
    info: dict[str, Any] = field(default_factory=dict)
    theta_block_builds: int = 0
    _blocks: dict[tuple[int, tuple[int, ...]], tuple[np.ndarray, Any]] = field(
        default_factory=dict, repr=False)
    max_cached_blocks: int = 4

    @property
    def n_train(self) -> int:
        """Training points (one FE call each)."""
        return int(self.model.y_train_.size)

    def theta_block(self, theta: np.ndarray) -> Any:
        """The (cached) θ block of ``theta``."""
        key = (id(theta), np.shape(theta))
        hit = self._blocks.get(key)
        if hit is not None and hit[0] is theta:
            return hit[1]
        block = self.fast.prepare_theta(theta)
        self.theta_block_builds += 1
        if len(self._blocks) >= self.max_cached_blocks:
            self._blocks.pop(next(iter(self._blocks)))
        self._blocks[key] = (theta, block)
        return block

    def response(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Predicted ``y`` for designs ``x`` (P, d) × θ ``(N, m)`` → ``(P, N)``.

        With the log transform this is ``exp(μ_log)`` (the predictive median).
        """
        t = self.fast.predict_grid(x, self.theta_block(theta)).mean
        return inverse(t, self.transform)

    __call__ = response

    def predict_transformed(self, x: np.ndarray, theta: np.ndarray, *,
                            return_std: bool = True) -> Prediction:
        """Mean and std of ``t(y)`` on the grid (no inverse transform)."""
        return self.fast.predict_grid(x, self.theta_block(theta), return_std=return_std)

    def response_points(self, Z: np.ndarray) -> np.ndarray:
        """``y`` at joint points ``Z = [x, θ]``: the quantity of :meth:`response`."""
        Z = np.atleast_2d(np.asarray(Z, dtype=float))
        return inverse(self.model.predict(Z, return_std=False).mean, self.transform)

    def predict(self, Z: np.ndarray) -> Prediction:
        """Mean and std at joint points ``Z = [x, θ]``.

        ``transform = "log"``: lognormal moments of ``exp(N(μ, s²))``; ``"none"``: the Kriging
        mean and std themselves.
        """
        p = self.model.predict(np.atleast_2d(np.asarray(Z, dtype=float)))
        if self.transform == "none":
            return p
        mean = np.exp(p.mean + 0.5 * p.std**2)
        return Prediction(mean=mean, std=mean * np.sqrt(np.expm1(p.std**2)))

    def loo_summary(self) -> LOOSummary:
        """Closed-form LOO of the Kriging of ``t(y)`` (metrics in ``t`` space), back in ``y``."""
        loo = loo_cv(self.model, method="closed_form")
        return LOOSummary(loo.method, self.n_train, loo.metrics.r2, loo.metrics.rmse,
                          inverse(loo.y_true, self.transform), inverse(loo.y_loo, self.transform),
                          {})

    def training_data(self) -> tuple[np.ndarray, np.ndarray]:
        """The training points and their ``y`` (back-transformed)."""
        return self.model.X_train_, inverse(self.model.y_train_, self.transform)


def _options(surrogate: str, n_start: int, like: TransformedKriging | None, Z: np.ndarray,
             like_mode: str) -> Any:
    """Kriging options: a fresh multistart, or length scales carried over from ``like``."""
    if like is None or surrogate == "gpr":
        return GPROptions(n_restarts=n_start - 1) if surrogate == "gpr" else \
            KrigingOptions(n_start=n_start)
    f = like.fast
    p = 2.0 if f.kernel == "se" else 1.0
    s_new = np.asarray(Z, dtype=float).std(axis=0, ddof=1)
    w = np.asarray(f.weights) * (s_new / np.asarray(f.scale)) ** p
    check_choice("like_mode", like_mode, ("warm", "keep"))
    d = KrigingOptions()
    return KrigingOptions(theta0=tuple(np.clip(w, d.theta_lower, d.theta_upper)), n_start=1,
                          hyper_opt="NoOp" if like_mode == "keep" else "TNC")


def fit_transformed(Z: np.ndarray, y: np.ndarray, *, rng: np.random.Generator,
                    surrogate: str = "krg_se", transform: str = "log", n_start: int = 5,
                    n_design: int = 3, like: TransformedKriging | None = None,
                    like_mode: str = "warm") -> TransformedKriging:
    """Fit ``surrogate`` to ``(Z, t(y))`` and wrap it (``y > 0`` for the log transform).

    ``like``: a fitted smt-Kriging :class:`TransformedKriging` whose *physical* length scales
    start (``like_mode = "warm"``: one local likelihood optimisation from them) or are kept
    (``"keep"``: no optimisation, the old model conditioned on the new data). smt normalises
    inputs by their sample std ``s``; the kernel weights are rescaled so that ``w / s²``
    (squared exponential) or ``w / s`` (Matérn 5/2) is unchanged. Used by the refinement loop:
    a fresh multistart optimisation on clustered infill points changed the fit far from them,
    and kept length scales made near-duplicate points (θ-weights ~1e-3) ill-conditioned
    (docs/paper-study.md).

    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> Z = rng.random((12, 2))
    >>> k = fit_transformed(Z, np.exp(Z.sum(1)), rng=rng, n_start=1, n_design=1)
    >>> bool(np.allclose(k.response_points(Z), np.exp(Z.sum(1)), rtol=1e-4))
    True
    """
    check_choice("surrogate", surrogate, sorted(SURROGATES))
    check_choice("transform", transform, TRANSFORMS)
    opts = _options(surrogate, n_start, like, Z, like_mode)
    t0 = time.perf_counter()
    model = SURROGATES[surrogate](opts, rng=require_rng(rng)).fit(Z, forward(y, transform))
    fit_s = time.perf_counter() - t0
    fast = ProductKernelPredictor.from_model(model, n_design=n_design)
    info = {"n_train": int(np.size(y)), "fit_time_s": fit_s,
            "hyperparameters": np.asarray(fast.weights).tolist(),
            "surrogate": surrogate, "transform": transform}
    return TransformedKriging(model=model, fast=fast, transform=transform,
                              n_design=n_design, info=info)


__all__ = ["TransformedKriging", "fit_transformed"]
