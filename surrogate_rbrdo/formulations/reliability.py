"""The reliability constraint column ``P_f ≤ P_target`` in three equivalent scales.

``reliability_measure`` (of :class:`~.options.FormulationOptions`) says how the column is
written, all feasible where ``<= 0``:

* ``"probability"``: ``P_f / P_target − 1`` (the default; on the scale of the stress ratio);
* ``"beta"``: ``β_t − β`` with ``β = −Φ⁻¹(P_f)`` (clipped to ±38): the reliability-index
  approach (RIA). Smooth in ``x`` for FORM/SORM, well scaled for gradient-based solvers;
* ``"quantile"``: the performance-measure approach (PMA) on the common-random-number sample:
  ``−q / s`` with ``q`` the Harrell–Davis estimate (Harrell & Davis 1982, *Biometrika* 69) of
  the ``P_target``-quantile of the limit state ``g = limit.g(y)`` over the ``N`` samples and
  ``s = |threshold|`` (1 if the threshold is 0). ``q ≥ 0`` says "at most a share ``P_target``
  of the sample fails", the sample-average constraint up to the smoothing of a few order
  statistics around rank ``P_target N``; unlike the staircase ``P̂_f`` it is smooth in ``x``,
  which a gradient-based solver needs (crude MC only).

``pf_bound = "upper"`` (the conservative option, against the optimiser's curse of a
sample-average constraint) constrains the upper end of the estimator's two-sided ``ci_level``
interval instead of the estimate: Clopper–Pearson for MC (in the quantile scale: the quantile
at level ``k/N`` with ``k`` the largest failure count whose exact upper bound is still
``≤ P_target``), ``pf ± z·se`` or the log-normal interval for IS/ais/subset.

A design whose estimate is only a *lower* bound of P_f (``diagnostics["pf_bound"] ==
"lower"``: FORM/SORM/IS where the design-point search did not settle from a safe mean, or the
limit state was not reached from a failing one) cannot be certified feasible: a lower bound at
or below ``P_target`` says nothing about ``P_f``. Such designs get ``P_f = 1`` in the column
(infeasible); a lower bound above ``P_target`` proves infeasibility and is kept. An
``"upper"`` label (``P_f`` at most the value) is conservative and used as it is.

>>> quantile_rank(1000, 0.05, "estimate", 0.95), quantile_rank(1000, 0.05, "upper", 0.95)
(50, 36)
>>> g = np.arange(1.0, 1001.0)[None, :]          # the 5 % quantile of 1..1000 is about 50
>>> round(float(harrell_davis(g, 0.05)[0]), 1)
50.5
"""

from __future__ import annotations

import numpy as np
from scipy import special

from surrogate_rbrdo.core.protocols import Estimate, LimitState
from surrogate_rbrdo.estimators import clopper_pearson

RELIABILITY_MEASURES = ("probability", "beta", "quantile")
PF_BOUNDS = ("estimate", "upper")
BETA_CLIP = 38.0   # Φ(−38) ≈ 3e-316: a finite stand-in for P_f = 0 or 1


def quantile_rank(n: int, p_target: float, pf_bound: str, ci_level: float) -> int:
    """Largest number ``k`` of failures among ``n`` samples that still satisfies the constraint:
    ``⌊p_target n⌋``, or the largest ``k`` whose Clopper–Pearson upper bound is ``≤ p_target``
    (``-1`` when even ``k = 0`` is not enough: ``n`` too small for the conservative bound)."""
    k = int(np.floor(p_target * n + 1e-9))
    if pf_bound == "estimate":
        return k
    ks = np.arange(0, k + 1)
    ok = clopper_pearson(ks, n, ci_level)[:, 1] <= p_target
    return int(ks[ok].max()) if ok.any() else -1


def harrell_davis(g: np.ndarray, p: float) -> np.ndarray:
    """Harrell–Davis estimate of the ``p``-quantile of each row of ``g`` ``(P, N)``: the average
    of the order statistics weighted by ``Beta(p(N+1), (1−p)(N+1))`` over ``[(i−1)/N, i/N]``.
    Only the lowest ranks carry weight for small ``p``: they are found by partial sorting."""
    n = g.shape[1]
    a, b = p * (n + 1), (1 - p) * (n + 1)
    sd = np.sqrt(a * b / ((a + b) ** 2 * (a + b + 1)))
    m = int(min(n, np.ceil(n * (p + 12 * sd)) + 2))
    low = np.sort(np.partition(g, m - 1, axis=1)[:, :m] if m < n else g, axis=1)
    edges = special.betainc(a, b, np.arange(m + 1) / n)
    return low @ np.diff(edges)


def probability_of(est: Estimate, pf_bound: str, p_target: float | None = None
                   ) -> np.ndarray:
    """The estimate ``pf`` or the upper end of its interval; with ``p_target``, a design whose
    value is only a lower bound of P_f (``diagnostics["pf_bound"] == "lower"``) at or below
    ``p_target`` counts as ``1`` (its feasibility is not shown).

    >>> from surrogate_rbrdo.core.protocols import Estimate
    >>> z = np.zeros(2)
    >>> est = Estimate(z, z, np.array([1e-4, 1e-4]), z, z, z, np.full((2, 2), 1e-4), 0, "form",
    ...                {"pf_bound": np.array(["", "lower"])})
    >>> probability_of(est, "estimate", 1e-3).tolist()
    [0.0001, 1.0]
    """
    p = np.array(est.pf if pf_bound == "estimate" else est.pf_ci[:, 1], dtype=float)
    labels = est.diagnostics.get("pf_bound") if p_target is not None else None
    if labels is not None:
        lower = np.asarray(labels).astype(str) == "lower"
        if lower.shape == p.shape:
            p[lower & ~(p > p_target)] = 1.0
    return p


def reliability_column(measure: str, pf_bound: str, est: Estimate, values: np.ndarray | None,
                       limit: LimitState, p_target: float, ci_level: float) -> np.ndarray:
    """One reliability constraint column (see the module docstring).

    ``values`` are the responses ``(P, N)`` on the common sample (needed by ``"quantile"``).
    """
    if measure == "quantile":
        if values is None:
            raise ValueError("reliability_measure = 'quantile' needs the response values on the "
                             "common sample: use estimator = 'mc'")
        n = values.shape[1]
        k = quantile_rank(n, p_target, pf_bound, ci_level)
        if k < 1:
            raise ValueError(f"n_theta = {n} is too small for P_target = {p_target} with "
                             f"pf_bound = {pf_bound!r}: fewer than one failure allowed")
        # a point outside the model's physical domain (NaN) is not a failure: g = +inf
        g = np.where(np.isnan(values), np.inf, limit.g(np.nan_to_num(values)))
        scale = abs(limit.threshold) if limit.threshold != 0 else 1.0
        return -harrell_davis(np.clip(g, -1e300, 1e300), k / n) / scale
    p = probability_of(est, pf_bound, p_target)
    if measure == "probability":
        return p / p_target - 1.0
    with np.errstate(divide="ignore"):
        beta = np.clip(-special.ndtri(p), -BETA_CLIP, BETA_CLIP)
    return float(-special.ndtri(p_target)) - beta


__all__ = ["BETA_CLIP", "PF_BOUNDS", "RELIABILITY_MEASURES", "harrell_davis", "probability_of",
           "quantile_rank", "reliability_column"]
