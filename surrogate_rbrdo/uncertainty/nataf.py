"""Independent and Nataf-correlated vectors of scalar marginals.

The Nataf transform maps ``u ~ N(0, I)`` to ``z = L₀ u`` (``R₀ = L₀ L₀ᵀ`` the fictitious
correlation of the underlying normals) and then ``θ_i = F_i⁻¹(Φ(z_i))``. ``R₀`` is found so that
``θ`` has the requested (Pearson) correlation ``corr``: each entry solves a 1-D equation whose
double integral is evaluated by Gauss-Hermite quadrature. A correlation that no ``R₀`` attains, or
a ``R₀`` that is not positive definite, raises ``ValueError``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize

from surrogate_rbrdo.uncertainty.base import _SampleMixin, as_batch
from surrogate_rbrdo.uncertainty.marginals import Normal, _Marginal
from surrogate_rbrdo.uncertainty.mvn import _check_corr, cholesky_pd

_GH_X, _GH_W = np.polynomial.hermite_e.hermegauss(48)
_GH_W = _GH_W / _GH_W.sum()


def _check_marginals(marginals: Sequence[_Marginal]) -> tuple[_Marginal, ...]:
    ms = tuple(marginals)
    if not ms:
        raise ValueError("marginals is empty: give at least one marginal")
    for i, mg in enumerate(ms):
        if not isinstance(mg, _Marginal):
            raise ValueError(
                f"marginals[{i}] = {mg!r} is not allowed: must be Normal, LogNormal or Uniform"
            )
    return ms


def _corr_of_normals(mi: _Marginal, mj: _Marginal, rho0: float) -> float:
    """Pearson correlation of ``(θ_i, θ_j)`` when their normals have correlation ``rho0``."""
    z1 = _GH_X[:, None]
    z2 = rho0 * _GH_X[:, None] + np.sqrt(1.0 - rho0**2) * _GH_X[None, :]
    a = (mi.ppf_normal(z1) - mi.mean[0]) / mi.std[0]
    b = (mj.ppf_normal(z2) - mj.mean[0]) / mj.std[0]
    return float(np.sum(_GH_W[:, None] * _GH_W[None, :] * a * b))


def fictitious_correlation(mi: _Marginal, mj: _Marginal, rho: float) -> float:
    """Correlation ``rho0`` of the underlying normals that gives ``corr(θ_i, θ_j) = rho``.

    >>> round(fictitious_correlation(Normal(0, 1), Normal(5, 2), 0.3), 12)
    0.3
    """
    if rho == 0.0 or (isinstance(mi, Normal) and isinstance(mj, Normal)):
        return float(rho)
    lim = 1.0 - 1e-10
    lo, hi = _corr_of_normals(mi, mj, -lim), _corr_of_normals(mi, mj, lim)
    if not lo <= rho <= hi:
        raise ValueError(
            f"corr = {rho!r} is not attainable by Nataf for marginals {mi!r} and {mj!r}: "
            f"must lie in [{lo:.4f}, {hi:.4f}]"
        )
    return float(optimize.brentq(lambda r: _corr_of_normals(mi, mj, r) - rho, -lim, lim,
                                 xtol=1e-13))


class _MarginalVector(_SampleMixin):
    """Shared parts of vectors built from marginals: moments and per-marginal maps to and
    from standard normal space (the correlation, if any, is handled by the subclass)."""

    marginals: Sequence[_Marginal]

    @property
    def dim(self) -> int:
        return len(self.marginals)

    @property
    def mean(self) -> np.ndarray:
        return np.array([m.mean[0] for m in self.marginals])

    @property
    def std(self) -> np.ndarray:
        return np.array([m.std[0] for m in self.marginals])

    def _from_normals(self, z: np.ndarray) -> np.ndarray:
        return np.column_stack([m.ppf_normal(z[:, i]) for i, m in enumerate(self.marginals)])

    def _to_normals(self, theta: np.ndarray) -> np.ndarray:
        theta = as_batch("theta", theta, self.dim)
        return np.column_stack(
            [m.cdf_normal_inv(theta[:, i]) for i, m in enumerate(self.marginals)]
        )


@dataclass(frozen=True)
class Independent(_MarginalVector):
    """Vector of independent marginals.

    >>> from surrogate_rbrdo.uncertainty.marginals import Uniform
    >>> iv = Independent([Normal(0.0, 1.0), Uniform(0.0, 1.0)])
    >>> iv.from_standard(np.zeros((1, 2))).tolist()
    [[0.0, 0.5]]
    """

    marginals: Sequence[_Marginal]

    def __post_init__(self) -> None:
        object.__setattr__(self, "marginals", _check_marginals(self.marginals))

    @property
    def cov(self) -> np.ndarray:
        return np.diag(self.std**2)

    def from_standard(self, u: np.ndarray) -> np.ndarray:
        return self._from_normals(as_batch("u", u, self.dim))

    def to_standard(self, theta: np.ndarray) -> np.ndarray:
        return self._to_normals(theta)


@dataclass(frozen=True, eq=False)
class Nataf(_MarginalVector):
    """Marginals coupled by a Gaussian copula with target Pearson correlation ``corr``.

    Attributes ``corr0`` (fictitious normal correlation) and ``chol0`` are computed once.

    >>> from surrogate_rbrdo.uncertainty.marginals import LogNormal
    >>> nat = Nataf([LogNormal(0.0, 0.5), LogNormal(0.0, 0.5)], [[1.0, 0.4], [0.4, 1.0]])
    >>> rho0 = np.log1p(0.4 * np.expm1(0.25)) / 0.25      # closed form for two lognormals
    >>> bool(abs(nat.corr0[0, 1] - rho0) < 1e-9)
    True
    """

    marginals: Sequence[_Marginal]
    corr: np.ndarray
    corr0: np.ndarray = field(init=False, repr=False, compare=False)
    chol0: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        ms = _check_marginals(self.marginals)
        corr = _check_corr(self.corr, len(ms))
        r0 = np.eye(len(ms))
        for i in range(len(ms)):
            for j in range(i):
                r0[i, j] = r0[j, i] = fictitious_correlation(ms[i], ms[j], float(corr[i, j]))
        chol0 = cholesky_pd("the Nataf fictitious correlation corr0", r0)
        object.__setattr__(self, "marginals", ms)
        object.__setattr__(self, "corr", corr)
        object.__setattr__(self, "corr0", r0)
        object.__setattr__(self, "chol0", chol0)

    @property
    def cov(self) -> np.ndarray:
        return self.corr * np.outer(self.std, self.std)

    def from_standard(self, u: np.ndarray) -> np.ndarray:
        return self._from_normals(as_batch("u", u, self.dim) @ self.chol0.T)

    def to_standard(self, theta: np.ndarray) -> np.ndarray:
        return np.linalg.solve(self.chol0, self._to_normals(theta).T).T
