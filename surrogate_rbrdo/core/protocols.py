"""Protocols and result types shared across the package.

Shapes (the contract every implementation keeps):

* a **design batch** ``x`` has shape ``(P, d)`` (``P`` designs, ``d`` design variables);
* a **θ batch** has shape ``(N, m)`` (``N`` samples of ``m`` random parameters);
* a :class:`Response` maps ``(x, theta)`` to ``y`` of shape ``(P, N)``: every design paired
  with every θ sample (so common random numbers across designs come for free);
* an :class:`Estimate` holds one value per design: arrays of shape ``(P,)``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_finite


@runtime_checkable
class Response(Protocol):
    """A (vectorised) model ``y(x, θ)``.

    ``__call__(x, theta)`` takes ``x`` of shape ``(P, d)`` and ``theta`` of shape ``(N, m)`` and
    returns ``y`` of shape ``(P, N)``. Responses without design variables accept ``x`` of shape
    ``(P, 0)``.
    """

    def __call__(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class LimitState:
    """Failure definition: ``y > threshold`` (``failure_if="above"``) or ``y < threshold``.

    >>> ls = LimitState(19.5e-6)
    >>> ls.g(np.array([10e-6, 25e-6])) > 0   # g > 0 is safe
    array([ True, False])
    """

    threshold: float
    failure_if: str = "above"

    def __post_init__(self) -> None:
        check_finite("threshold", self.threshold)
        check_choice("failure_if", self.failure_if, ("above", "below"))

    def g(self, y: np.ndarray) -> np.ndarray:
        """Limit-state function: safe where ``g >= 0``, failed where ``g < 0``.

        Failure is ``y > threshold`` (above) so ``g = threshold - y``; ties count as safe.
        """
        y = np.asarray(y, dtype=float)
        return self.threshold - y if self.failure_if == "above" else y - self.threshold

    def failed(self, y: np.ndarray) -> np.ndarray:
        """Boolean failure indicator."""
        return self.g(y) < 0


@dataclass(frozen=True)
class Estimate:
    """Immutable result of an estimator, one entry per design (arrays of shape ``(P,)``).

    Attributes
    ----------
    mean, std, pf : ndarray
        Estimates of μ_y, σ_y and P_f. NaN where the method does not give the quantity.
    mean_se, std_se, pf_se : ndarray
        Standard errors of the three estimates (NaN where they do not apply).
    pf_ci : ndarray, shape (P, 2)
        Confidence interval for P_f (level in ``diagnostics["ci_level"]``).
    n_calls : int
        Number of model evaluations (θ points evaluated, summed over designs).
    method : str
        Registry name of the estimator.
    diagnostics : mapping
        Method-specific extras (FORM: ``beta``, ``u_star``, ``theta_star``, ``alpha``,
        ``converged``; IS: effective sample size; ...).
    """

    mean: np.ndarray
    std: np.ndarray
    pf: np.ndarray
    mean_se: np.ndarray
    std_se: np.ndarray
    pf_se: np.ndarray
    pf_ci: np.ndarray
    n_calls: int
    method: str
    diagnostics: Mapping[str, Any] = field(default_factory=dict)

    @property
    def pf_cov(self) -> np.ndarray:
        """Coefficient of variation of the P_f estimate (``pf_se / pf``)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.pf > 0, self.pf_se / self.pf, np.nan)

    def to_dict(self) -> dict[str, Any]:
        """Plain-python view (lists instead of arrays), for JSON output."""

        def conv(v: Any) -> Any:
            if isinstance(v, np.ndarray):
                return v.tolist()
            if isinstance(v, Mapping):
                return {k: conv(w) for k, w in v.items()}
            if isinstance(v, (np.floating, np.integer, np.bool_)):
                return v.item()
            return v

        return {
            k: conv(getattr(self, k))
            for k in (
                "mean", "std", "pf", "mean_se", "std_se", "pf_se", "pf_ci",
                "n_calls", "method", "diagnostics",
            )
        }


class Estimator(Protocol):
    """Estimates μ_y, σ_y and P_f of a response for a batch of designs.

    ``estimate(response, inputs, limit, x, *, rng, u=None) -> Estimate`` where ``inputs`` is a
    random vector from :mod:`surrogate_rbrdo.uncertainty`, ``x`` has shape ``(P, d)`` and ``u``
    is an optional fixed standard-normal sample (common random numbers) used instead of draws.
    """

    def estimate(
        self,
        response: Response,
        inputs: Any,
        limit: LimitState,
        x: np.ndarray,
        *,
        rng: np.random.Generator,
        u: np.ndarray | None = None,
    ) -> Estimate: ...


@dataclass(frozen=True)
class Prediction:
    """Surrogate prediction: mean and standard deviation with the same shape."""

    mean: np.ndarray
    std: np.ndarray


class Surrogate(Protocol):
    """``fit(X, y) -> self`` and ``predict(X) -> Prediction``; fitted attributes end in ``_``."""

    def fit(self, X: np.ndarray, y: np.ndarray) -> Surrogate: ...

    def predict(self, X: np.ndarray) -> Prediction: ...
