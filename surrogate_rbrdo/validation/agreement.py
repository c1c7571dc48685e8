"""Model vs measurement: does the model's μ, σ, P_f of each design agree with the rig's,
within the uncertainty of both?

Per design, quantity and metric, the hypothesis "the model's value is the measured quantity's
true value" is tested, and the verdicts are taken together with Holm's step-down correction
(Holm 1979) so that "disagree" means *beyond uncertainty at family-wise level α*:

* **μ and σ** — the difference ``d`` against the combined standard uncertainty
  (GUM, JCGM 100:2008, §5 and Annex G): the measurement's standard error (``s/√n`` for μ,
  the distribution-free delta-method error of the SD for σ), the calibration of the probes
  as a type B relative uncertainty ``u_cal`` (one installation for the whole campaign: a
  systematic error, it does not average out), and the model's Monte Carlo error;
  ``t = d/u_c`` with Welch–Satterthwaite degrees of freedom (GUM G.4). It is the
  normalised-error (E_n) comparison of ISO 13528:2022 with the coverage factor replaced by the
  t quantile, which matters at n = 20;
* **P_f** — the exact binomial test of the measured failure count at the model's P_f; the
  model's own Monte Carlo interval is given the benefit of the doubt (the test is made at the
  value inside the model's interval closest to the measured fraction).

>>> m = Moments(20, 10e-6, 1e-6, (8e-6, 12e-6), 4e-6, 0.7e-6, (3e-6, 5e-6), 0.1, (0.01, 0.3), 2)
>>> p = Moments(4000, 14e-6, 0.1e-6, (13.8e-6, 14.2e-6), 4e-6, 0.05e-6, (3.9e-6, 4.1e-6),
...             0.5, (0.48, 0.52), 2000)
>>> v = holm(compare_moments("a", "peak", m, p, u_cal=0.02), alpha=0.05)
>>> [(x.metric, x.agree) for x in v]
[('mean', False), ('std', True), ('pf', False)]
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np
from scipy import stats

from surrogate_rbrdo.validation.model import Moments

METRICS = ("mean", "std", "pf")


@dataclass(frozen=True)
class Verdict:
    """One model-vs-measurement comparison; ``agree`` uses the Holm-adjusted p-value."""

    design: str
    quantity: str
    metric: str
    measured: float
    measured_ci: tuple[float, float]
    model: float
    model_ci: tuple[float, float]
    difference: float
    u_combined: float
    dof: float
    test: str
    p_value: float
    p_holm: float
    agree: bool

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def _t_test(d: float, u_meas: float, df_meas: int, u_cal: float, u_model: float,
            df_model: int) -> tuple[float, float, float]:
    """Combined standard uncertainty, Welch–Satterthwaite dof and two-sided p of ``d``."""
    uc = float(np.sqrt(u_meas**2 + u_cal**2 + u_model**2))
    if uc == 0.0:
        return 0.0, np.inf, 1.0 if d == 0.0 else 0.0
    den = u_meas**4 / max(df_meas, 1) + u_model**4 / max(df_model, 1)
    dof = uc**4 / den if den > 0 else np.inf
    return uc, float(dof), float(2.0 * stats.t.sf(abs(d) / uc, dof))


def compare_moments(design: str, quantity: str, measured: Moments, model: Moments, *,
                    u_cal: float) -> list[Verdict]:
    """The three comparisons of one design and quantity, unadjusted (``p_holm = p``): pass
    all of a campaign's comparisons to :func:`holm` together."""
    out = []
    for metric in ("mean", "std"):
        mv, pv = getattr(measured, metric), getattr(model, metric)
        mse, pse = getattr(measured, f"{metric}_se"), getattr(model, f"{metric}_se")
        uc, dof, p = _t_test(mv - pv, mse, measured.n - 1, u_cal * abs(mv), pse, model.n - 1)
        out.append(Verdict(design, quantity, metric, mv, getattr(measured, f"{metric}_ci"), pv,
                           getattr(model, f"{metric}_ci"), mv - pv, uc, dof,
                           "t (GUM combined uncertainty)", p, p, True))
    lo, hi = model.pf_ci
    p0 = float(np.clip(measured.n_fail / measured.n, lo, hi))
    if p0 in (0.0, 1.0):
        p = 1.0 if measured.n_fail == round(p0 * measured.n) else 0.0
    else:
        p = float(stats.binomtest(measured.n_fail, measured.n, p0).pvalue)
    out.append(Verdict(design, quantity, "pf", measured.pf, measured.pf_ci, model.pf,
                       model.pf_ci, measured.pf - model.pf, float("nan"), float(measured.n),
                       "exact binomial", p, p, True))
    return out


def holm(verdicts: Sequence[Verdict], alpha: float) -> list[Verdict]:
    """Holm's step-down adjusted p-values (monotone, capped at 1) and the verdicts at ``alpha``.

    >>> v = [Verdict("a", "peak", "mean", 0, (0, 0), 0, (0, 0), 0, 0, 0, "", p, p, True)
    ...      for p in (0.01, 0.04, 0.03)]
    >>> [(round(x.p_holm, 2), x.agree) for x in holm(v, 0.05)]
    [(0.03, False), (0.06, True), (0.06, True)]
    """
    p = np.array([v.p_value for v in verdicts], float)
    m = p.size
    order = np.argsort(p, kind="stable")
    adj = np.empty(m)
    adj[order] = np.minimum(1.0, np.maximum.accumulate((m - np.arange(m)) * p[order]))
    return [replace(v, p_holm=float(a), agree=bool(a >= alpha))
            for v, a in zip(verdicts, adj, strict=True)]
