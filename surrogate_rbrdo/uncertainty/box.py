"""A box holding a random vector's samples: each component's marginal quantiles.

For a design of experiments over θ (a Kriging of ``y(x, θ)``), the box must hold the Monte
Carlo samples and stay inside the support of every marginal: ``mean ± k σ`` does the first for
a Gaussian component but leaves the support of a bounded one (a phase on ``[0°, 360°)``, an
unbalance fraction on ``[0, 1]``). :func:`marginal_box` takes, per component, the quantiles
of its marginal at ``Φ(∓k)`` instead: ``mean ± k σ`` for a normal component (the same box as
before), the support's ends (to within ``Φ(−k)``) for a bounded one, the right tails for a
lognormal one.

>>> from surrogate_rbrdo.uncertainty.blocks import BlockIndependent
>>> from surrogate_rbrdo.uncertainty.marginals import Uniform
>>> from surrogate_rbrdo.uncertainty.mvn import MultivariateNormal
>>> from surrogate_rbrdo.uncertainty.nataf import Independent
>>> v = BlockIndependent((MultivariateNormal([1.0, 1.0], std=[0.015, 0.033]),
...                       Independent([Uniform(0.0, 360.0)])))
>>> marginal_box(v, 4.0).round(3).tolist()
[[0.94, 1.06], [0.868, 1.132], [0.011, 359.989]]
"""

from __future__ import annotations

from typing import Any

import numpy as np

from surrogate_rbrdo.core.validate import check_positive
from surrogate_rbrdo.uncertainty.blocks import BlockIndependent
from surrogate_rbrdo.uncertainty.marginals import _Marginal
from surrogate_rbrdo.uncertainty.nataf import _MarginalVector


def marginal_box(inputs: Any, sigmas: float = 4.0) -> np.ndarray:
    """``(m, 2)``: per component of ``inputs``, its marginal quantiles at ``Φ(−sigmas)`` and
    ``Φ(sigmas)`` (any other random vector: ``mean ± sigmas · std``, exact for Gaussian
    marginals)."""
    check_positive("sigmas", sigmas)
    if isinstance(inputs, BlockIndependent):
        return np.vstack([marginal_box(b, sigmas) for b in inputs.blocks])
    z = np.array([-sigmas, sigmas])
    if isinstance(inputs, _Marginal):
        return inputs.ppf_normal(z)[None, :]
    if isinstance(inputs, _MarginalVector):
        return np.array([m.ppf_normal(z) for m in inputs.marginals])
    mean = np.asarray(inputs.mean, dtype=float).reshape(-1)
    std = np.sqrt(np.diag(np.asarray(inputs.cov, dtype=float)))
    return np.column_stack([mean - sigmas * std, mean + sigmas * std])


__all__ = ["marginal_box"]
