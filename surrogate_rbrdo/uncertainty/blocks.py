"""A random vector made of independent blocks, each a random vector of its own.

``θ = [θ₁, θ₂, …]`` with the blocks mutually independent (e.g. correlated bearing stiffness
factors, a :class:`~surrogate_rbrdo.uncertainty.mvn.MultivariateNormal`, next to unbalance
magnitudes and phases, an :class:`~surrogate_rbrdo.uncertainty.nataf.Independent`). The
isoprobabilistic transform acts block by block on the matching columns of ``u``, so the joint
transform is exact whenever each block's is.

>>> from surrogate_rbrdo.uncertainty.mvn import MultivariateNormal
>>> from surrogate_rbrdo.uncertainty.marginals import Uniform
>>> from surrogate_rbrdo.uncertainty.nataf import Independent
>>> v = BlockIndependent((MultivariateNormal([1.0, 1.0], std=[0.015, 0.033]),
...                       Independent([Uniform(0.0, 360.0)])))
>>> v.dim, v.from_standard(np.zeros((1, 3))).tolist()
(3, [[1.0, 1.0, 180.0]])
>>> u = v.standard_sample(4, rng=np.random.default_rng(0))
>>> bool(np.allclose(v.to_standard(v.from_standard(u)), u))
True
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.linalg import block_diag

from surrogate_rbrdo.uncertainty.base import RandomVector, _SampleMixin, as_batch


@dataclass(frozen=True, eq=False)
class BlockIndependent(_SampleMixin):
    """Independent blocks ``blocks`` (each a :class:`RandomVector`), columns in order."""

    blocks: Sequence[RandomVector]

    def __post_init__(self) -> None:
        blocks = tuple(self.blocks)
        if not blocks:
            raise ValueError("blocks is empty: give at least one random vector")
        for i, b in enumerate(blocks):
            if not isinstance(b, RandomVector):
                raise ValueError(f"blocks[{i}] = {b!r} is not allowed: must be a random vector "
                                 "(dim, mean, cov, sample, from_standard, to_standard)")
        object.__setattr__(self, "blocks", blocks)

    @property
    def dim(self) -> int:
        return int(sum(b.dim for b in self.blocks))

    @property
    def mean(self) -> np.ndarray:
        return np.concatenate([np.asarray(b.mean, dtype=float) for b in self.blocks])

    @property
    def cov(self) -> np.ndarray:
        return block_diag(*[np.asarray(b.cov, dtype=float) for b in self.blocks])

    def _slices(self) -> list[slice]:
        edges = np.cumsum([0] + [b.dim for b in self.blocks])
        return [slice(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:], strict=True)]

    def from_standard(self, u: np.ndarray) -> np.ndarray:
        u = as_batch("u", u, self.dim)
        return np.column_stack([b.from_standard(u[:, s])
                                for b, s in zip(self.blocks, self._slices(), strict=True)])

    def to_standard(self, theta: np.ndarray) -> np.ndarray:
        theta = as_batch("theta", theta, self.dim)
        return np.column_stack([b.to_standard(theta[:, s])
                                for b, s in zip(self.blocks, self._slices(), strict=True)])
