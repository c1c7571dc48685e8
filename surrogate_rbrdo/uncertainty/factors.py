"""Random multiplicative factors (e.g. bearing stiffness factors θ) from their mean, standard
deviation and correlation, with a choice of support.

A stiffness factor is physically positive. A normal model (the paper's Table 4 CoVs ≈ 6 %)
puts a mass ``Φ(−1/CoV)`` ≈ 1e-61 below zero: negligible for sampling, but a FORM search or a
subset chain can step there, where the FE model raises ``OutsideDomainError`` (the estimators
then treat the point as not a failure — P_f is that of failure inside the domain — and say how
many points fell outside, ``docs/estimators.md``). The lognormal
option has the same mean, standard deviation and (Nataf) Pearson correlation and positive
support, so θ ≤ 0 never arises; its upper tail is heavier (skewness ``3 CoV + CoV³``, 0.18 at
CoV 6 %), its lower tail lighter: for a response that fails when a bearing *softens* it gives a
smaller P_f than the normal model — a modelling choice to state, not a numerical fix.

>>> th = stiffness_factors([1.0, 1.0], [0.0605, 0.0641], distribution="lognormal")
>>> np.round(th.mean, 12).tolist(), np.round(th.std, 12).tolist()
([1.0, 1.0], [0.0605, 0.0641])
>>> bool(np.all(th.from_standard(np.full((1, 2), -40.0)) > 0))
True
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_positive
from surrogate_rbrdo.uncertainty.marginals import LogNormal
from surrogate_rbrdo.uncertainty.mvn import MultivariateNormal
from surrogate_rbrdo.uncertainty.nataf import Independent, Nataf

FACTOR_DISTRIBUTIONS = ("normal", "lognormal")


def stiffness_factors(mean: Sequence[float], std: Sequence[float],
                      corr: np.ndarray | None = None, *, distribution: str = "normal"):
    """A random vector of positive factors with the given moments: ``MultivariateNormal``
    (mean > 8 std, so P(θ ≤ 0) < 1e-15) or lognormal marginals (``LogNormal.from_moments``)
    coupled by Nataf to the Pearson correlation ``corr`` (independent when ``corr`` is
    ``None``)."""
    check_choice("distribution", distribution, FACTOR_DISTRIBUTIONS)
    mean = np.asarray(mean, dtype=float).reshape(-1)
    std = np.asarray(std, dtype=float).reshape(-1)
    if mean.shape != std.shape:
        raise ValueError(f"mean and std have shapes {mean.shape} and {std.shape}: must match")
    for i, (m, s) in enumerate(zip(mean, std, strict=True)):
        check_positive(f"std[{i}]", float(s))
        if distribution == "normal" and not m > 8.0 * s:
            raise ValueError(f"mean[{i}] = {m} is not allowed: a stiffness factor must stay "
                             f"positive: need mean > 8 std = {8.0 * s:g} (or "
                             "distribution = 'lognormal', mean > 0)")
        check_positive(f"mean[{i}]", float(m))
    if distribution == "normal":
        try:
            return MultivariateNormal(mean, std=std, corr=corr)
        except ValueError as exc:
            raise ValueError(f"corr: {exc}") from None
    marginals = [LogNormal.from_moments(float(m), float(s)) for m, s in zip(mean, std,
                                                                            strict=True)]
    try:
        return Independent(marginals) if corr is None else Nataf(marginals, corr)
    except ValueError as exc:
        raise ValueError(f"corr: {exc}") from None


__all__ = ["FACTOR_DISTRIBUTIONS", "stiffness_factors"]
