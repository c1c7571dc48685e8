"""The random-vector protocol shared by every input model.

A random vector ``θ`` of dimension ``m`` comes with an isoprobabilistic transform
``θ = T(u)`` from standard-normal space (``u ~ N(0, I_m)``). Estimators work in ``u`` space and
map samples with :meth:`RandomVector.from_standard`; a fixed ``u`` sample reused for every design
gives common random numbers.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_int


@runtime_checkable
class RandomVector(Protocol):
    """Protocol: ``dim``, ``mean``, ``cov`` and the five sampling/transform methods.

    Shapes: ``sample`` and ``standard_sample`` return ``(n, dim)``; ``from_standard`` and
    ``to_standard`` map ``(n, dim)`` arrays to ``(n, dim)`` arrays.
    """

    @property
    def dim(self) -> int: ...

    @property
    def mean(self) -> np.ndarray: ...

    @property
    def cov(self) -> np.ndarray: ...

    def sample(self, n: int, *, rng: np.random.Generator) -> np.ndarray: ...

    def standard_sample(self, n: int, *, rng: np.random.Generator) -> np.ndarray: ...

    def from_standard(self, u: np.ndarray) -> np.ndarray: ...

    def to_standard(self, theta: np.ndarray) -> np.ndarray: ...


def standard_normal_sample(n: int, dim: int, *, rng: np.random.Generator) -> np.ndarray:
    """Draw ``n`` standard-normal vectors of dimension ``dim`` (shape ``(n, dim)``).

    >>> standard_normal_sample(4, 2, rng=np.random.default_rng(0)).shape
    (4, 2)
    """
    require_rng(rng)
    n = check_int("n", n, minimum=1)
    return rng.standard_normal((n, dim))


def as_batch(name: str, arr: np.ndarray, dim: int) -> np.ndarray:
    """Return ``arr`` as a float ``(n, dim)`` array (a 1-D array of length ``dim`` is one row)."""
    a = np.asarray(arr, dtype=float)
    if a.ndim == 1 and a.shape[0] == dim:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != dim:
        raise ValueError(f"{name} has shape {np.shape(arr)}: must be (n, {dim})")
    return a


class _SampleMixin:
    """``sample`` and ``standard_sample`` from ``dim`` and ``from_standard``."""

    dim: int

    def standard_sample(self, n: int, *, rng: np.random.Generator) -> np.ndarray:
        """Standard-normal sample ``u`` of shape ``(n, dim)``."""
        return standard_normal_sample(n, self.dim, rng=rng)

    def sample(self, n: int, *, rng: np.random.Generator) -> np.ndarray:
        """Sample ``θ`` of shape ``(n, dim)`` (``from_standard`` of a standard sample)."""
        return self.from_standard(self.standard_sample(n, rng=rng))  # type: ignore[attr-defined]
