"""The random vector of a spindle θ specification (``spindle.peak_response.ThetaSpec``).

Blocks, independent of each other (:class:`~surrogate_rbrdo.uncertainty.blocks.
BlockIndependent`), in the spec's column order:

* bearing stiffness factors: multivariate normal, mean 1, ``stiffness_std``,
  ``stiffness_corr`` (identity if None), unless a ``stiffness`` random vector is given (e.g.
  lognormal factors, :func:`~surrogate_rbrdo.uncertainty.factors.stiffness_factors`, or the
  model of an identification);
* thermal preload state ``τ ~ U(0, thermal_max)`` (only if ``thermal_max > 0``): anywhere
  between a cold start and the hot steady state, with nothing known to favour one;
* unbalance magnitude fractions ``r_j``: radius of a point uniform over the tolerance disk
  (:class:`~surrogate_rbrdo.uncertainty.disk.UniformDiskRadius`, only with
  ``magnitude = "disk"``);
* phases ``U(0°, 360°)``, one per plane or per plane after the first, marked ``periodic``
  (an angle: 0° ≡ 360°).

>>> from types import SimpleNamespace
>>> spec = SimpleNamespace(stiffness_std=(0.015, 0.033), stiffness_corr=None,
...                        thermal_max=0.0, magnitude="disk", n_planes=2,
...                        relative_phase=True)
>>> v = theta_random_vector(spec)
>>> v.dim, v.from_standard(np.zeros((1, 5))).round(4).tolist()
(5, [[1.0, 1.0, 0.7071, 0.7071, 180.0]])
"""

from __future__ import annotations

from typing import Any

import numpy as np

from surrogate_rbrdo.uncertainty.blocks import BlockIndependent
from surrogate_rbrdo.uncertainty.disk import UniformDiskRadius
from surrogate_rbrdo.uncertainty.marginals import Uniform
from surrogate_rbrdo.uncertainty.mvn import MultivariateNormal
from surrogate_rbrdo.uncertainty.nataf import Independent


def theta_random_vector(spec: Any, stiffness: Any = None) -> BlockIndependent:
    """:class:`BlockIndependent` of ``spec`` (attributes as ``ThetaSpec``'s); ``stiffness``
    replaces the default normal block of the stiffness factors (a random vector of the same
    dimension, one factor per bearing of the spec)."""
    std = np.asarray(spec.stiffness_std, dtype=float)
    if stiffness is None:
        corr = None if spec.stiffness_corr is None else np.asarray(spec.stiffness_corr, float)
        stiffness = MultivariateNormal(np.ones(std.size), std=std, corr=corr)
    elif int(stiffness.dim) != std.size:
        raise ValueError(f"stiffness.dim = {stiffness.dim} is not allowed: need {std.size}, "
                         "one factor per bearing of the spec")
    blocks: list[Any] = [stiffness]
    rest = []
    if spec.thermal_max > 0:
        rest.append(Uniform(0.0, float(spec.thermal_max)))
    if spec.magnitude == "disk":
        rest += [UniformDiskRadius(1.0) for _ in range(spec.n_planes)]
    n_phase = spec.n_planes - (1 if spec.relative_phase else 0)
    rest += [Uniform(0.0, 360.0, periodic=True) for _ in range(n_phase)]
    if rest:
        blocks.append(Independent(rest))
    return BlockIndependent(blocks)


__all__ = ["theta_random_vector"]
