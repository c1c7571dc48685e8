"""Scalar marginal distributions, each a one-dimensional random vector.

Every marginal maps a standard-normal ``u`` to ``θ`` through ``θ = F⁻¹(Φ(u))`` (computed in a
tail-safe closed form) and back. Parametrisations:

* ``Normal(mu, sigma)``: mean ``mu``, standard deviation ``sigma``.
* ``LogNormal(mu, sigma)``: ``ln θ ~ N(mu, sigma²)`` (numpy's convention); use
  :meth:`LogNormal.from_moments` to give the mean and standard deviation of ``θ`` itself.
* ``Uniform(lo, hi)``: uniform on ``[lo, hi]``.

>>> ln = LogNormal.from_moments(2.0, 0.5)
>>> round(float(ln.mean[0]), 12), round(float(ln.std[0]), 12)
(2.0, 0.5)
>>> Uniform(0.0, 2.0).from_standard(np.array([[0.0]])).tolist()
[[1.0]]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import special

from surrogate_rbrdo.core.validate import check_finite, check_positive
from surrogate_rbrdo.uncertainty.base import _SampleMixin, as_batch


class _Marginal(_SampleMixin):
    """Shared vector interface of the scalar marginals (``dim == 1``)."""

    dim = 1

    def _mean(self) -> float:
        raise NotImplementedError

    def _std(self) -> float:
        raise NotImplementedError

    @property
    def mean(self) -> np.ndarray:
        """Mean, shape ``(1,)``."""
        return np.array([self._mean()])

    @property
    def std(self) -> np.ndarray:
        """Standard deviation, shape ``(1,)``."""
        return np.array([self._std()])

    @property
    def cov(self) -> np.ndarray:
        """Variance as a ``(1, 1)`` covariance matrix."""
        return np.array([[self._std() ** 2]])

    def ppf_normal(self, z: np.ndarray) -> np.ndarray:
        """Elementwise ``F⁻¹(Φ(z))`` (any shape)."""
        raise NotImplementedError

    def cdf_normal_inv(self, x: np.ndarray) -> np.ndarray:
        """Elementwise ``Φ⁻¹(F(x))`` (any shape); raises outside the support."""
        raise NotImplementedError

    def from_standard(self, u: np.ndarray) -> np.ndarray:
        """Map a ``(n, 1)`` standard-normal batch to ``θ``."""
        return self.ppf_normal(as_batch("u", u, 1))

    def to_standard(self, theta: np.ndarray) -> np.ndarray:
        """Map a ``(n, 1)`` batch ``θ`` to standard-normal ``u``."""
        return self.cdf_normal_inv(as_batch("theta", theta, 1))


@dataclass(frozen=True)
class Normal(_Marginal):
    """Normal marginal ``N(mu, sigma²)``.

    >>> Normal(1.0, 2.0).from_standard(np.array([[1.0]])).tolist()
    [[3.0]]
    """

    mu: float
    sigma: float

    def __post_init__(self) -> None:
        check_finite("mu", self.mu)
        check_positive("sigma", self.sigma)

    def _mean(self) -> float:
        return float(self.mu)

    def _std(self) -> float:
        return float(self.sigma)

    def ppf_normal(self, z: np.ndarray) -> np.ndarray:
        return self.mu + self.sigma * np.asarray(z, dtype=float)

    def cdf_normal_inv(self, x: np.ndarray) -> np.ndarray:
        return (np.asarray(x, dtype=float) - self.mu) / self.sigma


@dataclass(frozen=True)
class LogNormal(_Marginal):
    """Lognormal marginal: ``ln θ ~ N(mu, sigma²)`` (parameters of the log, not of ``θ``).

    >>> LogNormal(0.0, 1.0).from_standard(np.array([[0.0]])).tolist()   # the median is e^mu
    [[1.0]]
    """

    mu: float
    sigma: float

    def __post_init__(self) -> None:
        check_finite("mu", self.mu)
        check_positive("sigma", self.sigma)

    @classmethod
    def from_moments(cls, mean: float, std: float) -> LogNormal:
        """Lognormal with the given mean and standard deviation of ``θ`` (``mean > 0``)."""
        mean = check_positive("mean", mean)
        std = check_positive("std", std)
        s2 = math.log1p((std / mean) ** 2)
        return cls(math.log(mean) - 0.5 * s2, math.sqrt(s2))

    def _mean(self) -> float:
        return math.exp(self.mu + 0.5 * self.sigma**2)

    def _std(self) -> float:
        return self._mean() * math.sqrt(math.expm1(self.sigma**2))

    def ppf_normal(self, z: np.ndarray) -> np.ndarray:
        return np.exp(self.mu + self.sigma * np.asarray(z, dtype=float))

    def cdf_normal_inv(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        if np.any(x <= 0):
            raise ValueError("theta has a value <= 0: outside the support of LogNormal (> 0)")
        return (np.log(x) - self.mu) / self.sigma


@dataclass(frozen=True)
class Uniform(_Marginal):
    """Uniform marginal on ``[lo, hi]``; ``periodic=True`` marks an angle (a phase) on which
    the response depends periodically with period ``hi − lo`` (``lo ≡ hi``).

    The transform ``θ = lo + (hi − lo) Φ(u)`` puts both ends of the interval at ``u = ±∞``, so
    a periodic response whose worst value lies at ``lo ≡ hi`` has no design point in standard
    space; the design-point estimators (FORM, SORM, IS) condition on periodic columns instead
    (:mod:`surrogate_rbrdo.estimators._periodic`).

    >>> round(float(Uniform(0.0, 1.0).std[0]) ** 2 * 12, 12)
    1.0
    >>> Uniform(0.0, 360.0, periodic=True).periodic
    True
    """

    lo: float
    hi: float
    periodic: bool = False

    def __post_init__(self) -> None:
        check_finite("lo", self.lo)
        check_finite("hi", self.hi)
        if not self.hi > self.lo:
            raise ValueError(f"hi = {self.hi!r} is not allowed: must be > lo = {self.lo!r}")
        if not isinstance(self.periodic, bool):
            raise ValueError(f"periodic = {self.periodic!r} is not allowed: must be True or "
                             "False")

    def _mean(self) -> float:
        return 0.5 * (self.lo + self.hi)

    def _std(self) -> float:
        return (self.hi - self.lo) / math.sqrt(12.0)

    def ppf_normal(self, z: np.ndarray) -> np.ndarray:
        return self.lo + (self.hi - self.lo) * special.ndtr(np.asarray(z, dtype=float))

    def cdf_normal_inv(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        if np.any((x < self.lo) | (x > self.hi)):
            raise ValueError(
                f"theta has a value outside [{self.lo}, {self.hi}]: outside the Uniform support"
            )
        p = (x - self.lo) / (self.hi - self.lo)
        with np.errstate(divide="ignore"):
            return special.ndtri(p)
