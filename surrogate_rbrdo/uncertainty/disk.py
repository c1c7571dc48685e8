"""The radius of a point uniformly distributed over a disk: ``P(R ≤ r) = (r / r_max)²``.

A residual unbalance known only to lie inside its tolerance circle ``|U| ≤ U_per`` (ISO
21940-11: the balancing is accepted once the residual is within the permissible value) is,
with nothing else known, uniform over that disk: the maximum-entropy distribution on it. Its
magnitude is then this radius and its phase uniform on ``[0, 2π)``, independent of it.

>>> d = UniformDiskRadius(2.0)
>>> float(d.mean[0]), round(float(d.std[0]) ** 2, 12)          # 2/3 r_max, r_max²/18
(1.3333333333333333, 0.222222222222)
>>> d.from_standard(np.array([[0.0]])).round(6).tolist()       # median r_max/√2
[[1.414214]]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import special

from surrogate_rbrdo.core.validate import check_positive
from surrogate_rbrdo.uncertainty.marginals import _Marginal


@dataclass(frozen=True)
class UniformDiskRadius(_Marginal):
    """Radius ``R = r_max √V``, ``V ~ U(0, 1)``: density ``2 r / r_max²`` on ``[0, r_max]``."""

    r_max: float = 1.0

    def __post_init__(self) -> None:
        check_positive("r_max", self.r_max)

    def _mean(self) -> float:
        return 2.0 * self.r_max / 3.0

    def _std(self) -> float:
        return self.r_max / math.sqrt(18.0)

    def ppf_normal(self, z: np.ndarray) -> np.ndarray:
        return self.r_max * np.sqrt(special.ndtr(np.asarray(z, dtype=float)))

    def cdf_normal_inv(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        if np.any((x < 0) | (x > self.r_max)):
            raise ValueError(f"theta has a value outside [0, {self.r_max}]: outside the "
                             "UniformDiskRadius support")
        with np.errstate(divide="ignore"):
            return special.ndtri((x / self.r_max) ** 2)
