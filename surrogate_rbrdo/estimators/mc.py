"""Crude Monte Carlo: the paper's Eqs. 12-14 with standard errors and an exact binomial CI."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace
from types import MappingProxyType
from typing import Any

import numpy as np

from surrogate_rbrdo.core.protocols import Estimate, LimitState
from surrogate_rbrdo.core.validate import check_int, check_range
from surrogate_rbrdo.estimators._common import (
    check_args,
    check_finite_y,
    clopper_pearson,
    evaluate_in_domain,
    make_estimate,
)
from surrogate_rbrdo.estimators._tail import EstimatorWarning
from surrogate_rbrdo.estimators.registry import ESTIMATORS


def mc_from_values(
    y: np.ndarray, limit: LimitState, *, ci_level: float = 0.95, method: str = "mc"
) -> Estimate:
    """Monte Carlo estimates from a ``(P, N)`` array of responses (one row per design).

    ``mean = ȳ`` (Eq. 12), ``std`` = sample standard deviation with ``N − 1`` (Eq. 13),
    ``pf`` = fraction of samples with ``limit.failed(y)`` (Eq. 14). Standard errors:
    ``std/√N`` for the mean, the distribution-free delta-method value
    ``√((m₄ − (N−3)/(N−1) s⁴)/N) / (2s)`` for the standard deviation, ``√(pf(1−pf)/N)`` for
    ``pf``. The interval for ``pf`` is Clopper-Pearson (exact binomial), so it stays valid at
    zero failures. ``N = 1`` gives NaN for ``std`` and its error.

    Parameters
    ----------
    y : array_like, shape (P, N)
        Responses, finite.
    limit : LimitState
    ci_level : float
        Confidence level of ``pf_ci`` in (0, 1).
    method : str
        Name stored in :attr:`Estimate.method`.

    Examples
    --------
    >>> from surrogate_rbrdo.core import LimitState
    >>> est = mc_from_values(np.array([[1.0, 2.0, 3.0, 4.0]]), LimitState(3.5))
    >>> est.mean.tolist(), est.pf.tolist(), est.n_calls
    ([2.5], [0.25], 4)
    >>> round(float(est.std[0]), 6)
    1.290994
    """
    y = np.asarray(y, dtype=float)
    if y.ndim != 2:
        raise ValueError(f"y has shape {y.shape}: must be (P, N) (designs x samples)")
    p, n = y.shape
    if p < 1 or n < 1:
        raise ValueError(f"y has shape {y.shape}: need at least one design and one sample (N >= 1)")
    ci_level = check_range("ci_level", ci_level, 0.0, 1.0, inclusive=False)
    check_finite_y(y, "y")
    mean = y.mean(axis=1)
    nfail = np.count_nonzero(limit.failed(y), axis=1)
    pf = nfail / n
    if n > 1:
        d2 = y - mean[:, None]
        np.square(d2, out=d2)
        m2 = d2.sum(axis=1) / n
        var = m2 * (n / (n - 1))
        std = np.sqrt(var)
        m4 = np.einsum("ij,ij->i", d2, d2) / n
        var_s2 = np.maximum(m4 - (n - 3) / (n - 1) * var**2, 0.0) / n
        with np.errstate(divide="ignore", invalid="ignore"):
            std_se = np.where(std > 0, np.sqrt(var_s2) / (2.0 * np.where(std > 0, std, 1.0)), 0.0)
        mean_se = std / np.sqrt(n)
    else:
        std = std_se = mean_se = np.full(p, np.nan)
    pf_se = np.sqrt(pf * (1.0 - pf) / n)
    return make_estimate(
        method, y.size, p, mean=mean, std=std, pf=pf, mean_se=mean_se, std_se=std_se,
        pf_se=pf_se, pf_ci=clopper_pearson(nfail, n, ci_level),
        diagnostics={"ci_level": ci_level, "ci_method": "clopper-pearson", "n_samples": n,
                     "n_failures": nfail},
    )


def mc_with_outside(y: np.ndarray, limit: LimitState, *, ci_level: float = 0.95,
                    method: str = "mc") -> Estimate:
    """:func:`mc_from_values` where NaN marks a point outside the model's physical domain.

    Such points are **not failures** (:mod:`._common`): ``pf`` is the share of the ``N`` points
    that fail inside the domain, ``P(failure and inside)``, with its Clopper–Pearson interval.
    μ_y, σ_y and their errors use the points inside only, row by row: the moments of ``y``
    conditional on the domain (``y`` is not defined outside). ``diagnostics`` adds
    ``n_outside_domain`` and ``p_outside`` (their share) per design. Without NaN this is
    :func:`mc_from_values`.

    >>> from surrogate_rbrdo.core import LimitState
    >>> est = mc_with_outside(np.array([[1.0, 2.0, np.nan, 4.0]]), LimitState(3.5))
    >>> est.pf.tolist(), est.mean.round(6).tolist(), est.diagnostics["p_outside"].tolist()
    ([0.25], [2.333333], [0.25])
    """
    y = np.asarray(y, dtype=float)
    out = np.isnan(y)
    if not out.any():
        est = mc_from_values(y, limit, ci_level=ci_level, method=method)
        zero = np.zeros(y.shape[0], dtype=int)
        return replace(est, diagnostics=MappingProxyType(
            {**est.diagnostics, "n_outside_domain": zero, "p_outside": zero.astype(float)}))
    p, n = y.shape
    rows = [mc_from_values(r[np.isfinite(r)][None, :], limit, ci_level=ci_level, method=method)
            if np.isfinite(r).any() else None for r in y]
    nout = out.sum(axis=1)
    nfail = np.array([0 if e is None else e.diagnostics["n_failures"][0] for e in rows])
    pf = nfail / n

    def col(name: str) -> np.ndarray:
        return np.array([np.nan if e is None else float(getattr(e, name)[0]) for e in rows])

    return make_estimate(
        method, int(np.count_nonzero(~out)), p, mean=col("mean"), std=col("std"),
        mean_se=col("mean_se"), std_se=col("std_se"), pf=pf, pf_se=np.sqrt(pf * (1 - pf) / n),
        pf_ci=clopper_pearson(nfail, n, ci_level),
        diagnostics={"ci_level": ci_level, "ci_method": "clopper-pearson", "n_samples": n,
                     "n_failures": nfail, "n_outside_domain": nout, "p_outside": nout / n})


#: below this many failures the normal interval pf ± 3·SE of crude MC is unreliable (Poisson
#: skew); the Clopper-Pearson ``pf_ci`` stays exact
MC_MIN_FAILURES = 10


@ESTIMATORS.register("mc")
@dataclass(frozen=True)
class MonteCarlo:
    """Crude Monte Carlo over ``n_samples`` θ samples, vectorised over designs.

    With ``u`` given, its rows are the (common) standard-normal sample and ``n_samples`` is
    ignored. Points outside the model's physical domain are not failures and the moments are
    those of the points inside (:func:`mc_with_outside`); when there are any, an
    :class:`~._tail.EstimatorWarning` says how many. Fewer than ``MC_MIN_FAILURES`` failures
    for a design raise an :class:`~._tail.EstimatorWarning` (the normal interval is then
    unreliable; ``pf_ci`` is exact).

    >>> from surrogate_rbrdo.core import LimitState
    >>> from surrogate_rbrdo.uncertainty import MultivariateNormal
    >>> inputs = MultivariateNormal([0.0], cov=[[1.0]])
    >>> est = MonteCarlo(20_000).estimate(lambda x, t: x[:, :1] + t[:, 0][None, :], inputs,
    ...                                   LimitState(2.0), np.zeros((2, 1)),
    ...                                   rng=np.random.default_rng(0))
    >>> est.pf.shape, bool(abs(est.pf[0] - 0.02275) < 4 * est.pf_se[0])
    ((2,), True)
    """

    n_samples: int = 10_000
    ci_level: float = 0.95

    def __post_init__(self) -> None:
        check_int("n_samples", self.n_samples, minimum=1)
        check_range("ci_level", self.ci_level, 0.0, 1.0, inclusive=False)

    def estimate(self, response: Any, inputs: Any, limit: LimitState, x: np.ndarray, *,
                 rng: np.random.Generator, u: np.ndarray | None = None) -> Estimate:
        """Estimate μ_y, σ_y and P_f for every design of ``x``."""
        x, u = check_args(inputs, limit, x, rng, u)
        if u is None:
            u = inputs.standard_sample(self.n_samples, rng=rng)
        y, _, _ = evaluate_in_domain(response, x, inputs.from_standard(u))
        est = mc_with_outside(y, limit, ci_level=self.ci_level, method="mc")
        few = np.flatnonzero(np.asarray(est.diagnostics["n_failures"]) < MC_MIN_FAILURES)
        if few.size:
            warnings.warn(
                f"crude Monte Carlo: fewer than {MC_MIN_FAILURES} failures in {y.shape[1]} "
                f"samples for design(s) {few[:10].tolist()}: pf ± z·pf_se is unreliable (0 "
                "failures give pf_se = 0); use pf_ci (Clopper-Pearson) or more samples",
                EstimatorWarning, stacklevel=2)
        warn_outside(est.diagnostics["n_outside_domain"], y.shape[1], "crude Monte Carlo")
        return est


def warn_outside(n_outside: np.ndarray, n: int, what: str) -> None:
    """Raise an :class:`~._tail.EstimatorWarning` when sample points fell outside the model's
    physical domain (the moments are then conditional on the domain, P_f excludes them)."""
    n_outside = np.asarray(n_outside)
    bad = np.flatnonzero(n_outside > 0)
    if bad.size:
        warnings.warn(
            f"{what}: {int(n_outside[bad].max())} of {n} sample points lie outside the model's "
            f"physical domain for design(s) {bad[:10].tolist()}: they are not counted as "
            "failures and the moments of y are those inside the domain (biased where that "
            "mass matters); consider inputs with positive support (stiffness_factors(..., "
            "distribution='lognormal'))", EstimatorWarning, stacklevel=3)
