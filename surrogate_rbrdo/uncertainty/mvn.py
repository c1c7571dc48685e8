"""Multivariate normal random vector with a Cholesky isoprobabilistic transform."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from surrogate_rbrdo.uncertainty.base import _SampleMixin, as_batch


def _check_corr(corr: np.ndarray, dim: int) -> np.ndarray:
    c = np.asarray(corr, dtype=float)
    if c.shape != (dim, dim):
        raise ValueError(f"corr has shape {c.shape}: must be ({dim}, {dim})")
    if not np.all(np.isfinite(c)):
        raise ValueError("corr contains a non-finite value: must be finite")
    if not np.allclose(c, c.T, atol=1e-12):
        raise ValueError("corr is not symmetric: must equal its transpose")
    if not np.allclose(np.diag(c), 1.0, atol=1e-12):
        raise ValueError(f"corr has diagonal {np.diag(c).tolist()}: must be all ones")
    if np.any(np.abs(c) > 1.0 + 1e-12):
        raise ValueError("corr has an entry with |value| > 1: correlations must lie in [-1, 1]")
    return c


def cholesky_pd(name: str, mat: np.ndarray) -> np.ndarray:
    """Lower Cholesky factor of a symmetric positive-definite matrix, or a clear ValueError.

    >>> cholesky_pd("cov", np.array([[4.0, 0.0], [0.0, 1.0]]))
    array([[2., 0.],
           [0., 1.]])
    >>> cholesky_pd("cov", np.array([[1.0, 2.0], [2.0, 1.0]]))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: cov is not positive definite (smallest eigenvalue -1): must be ...
    """
    try:
        return np.linalg.cholesky(mat)
    except np.linalg.LinAlgError:
        lam = float(np.linalg.eigvalsh(mat).min())
        raise ValueError(
            f"{name} is not positive definite (smallest eigenvalue {lam:.3g}): "
            "must be symmetric positive definite"
        ) from None


@dataclass(frozen=True, eq=False)
class MultivariateNormal(_SampleMixin):
    """Normal random vector ``θ ~ N(mean, cov)``; transform ``θ = mean + L u`` (``cov = L Lᵀ``).

    Give exactly one of ``cov`` or ``std`` (optionally with ``corr``; no ``corr`` means
    independent components). The covariance must be positive definite.

    Parameters
    ----------
    mean : array_like, shape (m,)
    cov : array_like, shape (m, m), optional
    std : array_like, shape (m,), optional (keyword only)
    corr : array_like, shape (m, m), optional (keyword only)

    Examples
    --------
    >>> mvn = MultivariateNormal([1.0, 2.0], std=[0.1, 0.2], corr=[[1.0, 0.5], [0.5, 1.0]])
    >>> mvn.cov.round(4).tolist()
    [[0.01, 0.01], [0.01, 0.04]]
    >>> u = np.array([[0.0, 0.0], [1.0, -1.0]])
    >>> np.allclose(mvn.to_standard(mvn.from_standard(u)), u)
    True
    >>> mvn.sample(3, rng=np.random.default_rng(0)).shape
    (3, 2)
    """

    mean: np.ndarray
    cov: np.ndarray | None = None
    std: np.ndarray | None = field(default=None, kw_only=True)
    corr: np.ndarray | None = field(default=None, kw_only=True)
    chol: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        mean = np.atleast_1d(np.asarray(self.mean, dtype=float))
        if mean.ndim != 1 or mean.size == 0 or not np.all(np.isfinite(mean)):
            raise ValueError(f"mean = {self.mean!r} is not allowed: must be a finite 1-D array")
        m = mean.size
        if (self.cov is None) == (self.std is None):
            raise ValueError("give exactly one of cov or std (optionally with corr)")
        if self.cov is not None:
            if self.corr is not None:
                raise ValueError("corr is only allowed together with std, not with cov")
            cov = np.asarray(self.cov, dtype=float)
            if cov.shape != (m, m) or not np.all(np.isfinite(cov)):
                raise ValueError(f"cov has shape {cov.shape}: must be a finite ({m}, {m}) array")
            if not np.allclose(cov, cov.T, rtol=1e-10, atol=1e-14):
                raise ValueError("cov is not symmetric: must equal its transpose")
            std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
        else:
            std = np.atleast_1d(np.asarray(self.std, dtype=float))
            if std.shape != (m,) or not np.all(np.isfinite(std)) or np.any(std <= 0):
                raise ValueError(
                    f"std = {self.std!r} is not allowed: must be {m} finite numbers > 0"
                )
            corr = np.eye(m) if self.corr is None else _check_corr(self.corr, m)
            cov = corr * np.outer(std, std)
        chol = cholesky_pd("cov", cov)
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "cov", cov)
        object.__setattr__(self, "std", std)
        object.__setattr__(self, "corr", cov / np.outer(std, std))
        object.__setattr__(self, "chol", chol)
        for a in (mean, cov, std, self.corr, chol):
            a.setflags(write=False)

    @property
    def dim(self) -> int:
        """Number of components ``m``."""
        return int(self.mean.size)

    def from_standard(self, u: np.ndarray) -> np.ndarray:
        """``θ = mean + L u`` for a batch ``u`` of shape ``(n, m)``."""
        u = as_batch("u", u, self.dim)
        return self.mean + u @ self.chol.T

    def to_standard(self, theta: np.ndarray) -> np.ndarray:
        """``u = L⁻¹ (θ − mean)`` for a batch ``θ`` of shape ``(n, m)``."""
        theta = as_batch("theta", theta, self.dim)
        return scipy.linalg.solve_triangular(self.chol, (theta - self.mean).T, lower=True).T
