"""Options of a design formulation (frozen, validated on construction).

>>> round(FormulationOptions(p_target=0.05).beta_target, 4)
1.6449
>>> FormulationOptions(p_target=1.5)
Traceback (most recent call last):
...
ValueError: p_target = 1.5 is not allowed: must lie in (0.0, 1.0)
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from scipy.stats import norm

from surrogate_rbrdo.core.validate import check_choice, check_int, check_range
from surrogate_rbrdo.formulations.deterministic import DeterministicOptions
from surrogate_rbrdo.formulations.reliability import PF_BOUNDS, RELIABILITY_MEASURES

#: estimators whose P_f carries no sampling error (an upper confidence bound is undefined)
NO_SAMPLING_ERROR = ("form", "sorm", "fosm")


def check_reliability(reliability_measure: str, pf_bound: str, estimator: str) -> None:
    """Check that the reliability measure, the P_f bound and the estimator go together
    (``ValueError`` naming the field otherwise)."""
    check_choice("reliability_measure", reliability_measure, RELIABILITY_MEASURES)
    check_choice("pf_bound", pf_bound, PF_BOUNDS)
    if reliability_measure == "quantile" and estimator != "mc":
        raise ValueError(f"reliability_measure = 'quantile' is not allowed with estimator = "
                         f"{estimator!r}: the quantile of the common sample needs 'mc'")
    if pf_bound == "upper" and estimator in NO_SAMPLING_ERROR:
        raise ValueError(f"pf_bound = 'upper' is not allowed with estimator = {estimator!r}: it "
                         "has no sampling error to bound (use a sampling estimator: mc, is, ais, "
                         "subset)")


@dataclass(frozen=True)
class FormulationOptions:
    """Shared options of every formulation.

    Parameters
    ----------
    p_target : float
        Target probability of failure, in (0, 1). Used by ``rbdo`` and ``rbrdo``.
    n_theta : int
        Size of the common-random-number θ sample (paper: N_mc = 1000), >= 1.
    estimator : str
        Registry name of the estimator. ``"mc"`` takes the fast path (response values on the
        fixed sample → ``mc_from_values``); any other name calls ``estimator.estimate(...)``
        with the same fixed standard-normal sample ``u``.
    estimator_options : mapping
        Keyword options for ``get_estimator(estimator, **estimator_options)``.
    ci_level : float
        Confidence level of the P_f interval, in (0, 1).
    deterministic : DeterministicOptions
        The g_det constraints (stress ratio and resonance guard).
    reliability_measure : {"probability", "beta", "quantile"}
        How each reliability column is written (:mod:`~.reliability`): ``P_f/P_target − 1``,
        ``β_t − β`` (RIA; smooth with FORM) or the ``P_target``-quantile of the limit state on
        the common sample (PMA; same feasible set as the sample ``P̂_f``, continuous in ``x``;
        ``estimator = "mc"`` only).
    pf_bound : {"estimate", "upper"}
        Constrain the estimate, or (conservative) the upper end of its ``ci_level`` interval
        (sampling estimators only).
    """

    p_target: float = 0.05
    n_theta: int = 1000
    estimator: str = "mc"
    estimator_options: Mapping[str, Any] = field(default_factory=dict)
    ci_level: float = 0.95
    deterministic: DeterministicOptions = field(default_factory=DeterministicOptions)
    reliability_measure: str = "probability"
    pf_bound: str = "estimate"

    def __post_init__(self) -> None:
        check_range("p_target", self.p_target, 0.0, 1.0, inclusive=False)
        check_int("n_theta", self.n_theta, minimum=1)
        if not isinstance(self.estimator, str):
            raise ValueError(f"estimator = {self.estimator!r} is not allowed: must be a name")
        check_range("ci_level", self.ci_level, 0.0, 1.0, inclusive=False)
        if not isinstance(self.deterministic, DeterministicOptions):
            raise ValueError(f"deterministic = {self.deterministic!r} is not allowed: must be "
                             "a DeterministicOptions")
        object.__setattr__(self, "estimator_options",
                           MappingProxyType(dict(self.estimator_options)))
        check_reliability(self.reliability_measure, self.pf_bound, self.estimator)

    @property
    def beta_target(self) -> float:
        """Target reliability index β_t = Φ⁻¹(1 − P_target)."""
        return float(norm.isf(self.p_target))
