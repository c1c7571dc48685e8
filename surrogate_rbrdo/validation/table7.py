"""Table 7's analogue: P_f, μ_y, σ_y of the baseline and another design on the same paired
replications, their improvements with intervals, tests, effect sizes and power statements.

One :class:`Comparison` per (design vs baseline, quantity); :func:`table7_rows` flattens it into
the rows of ``table7.csv`` (one per metric):

=========  ========================  ==============================  =====================
metric     test                      effect size                     distribution-free
=========  ========================  ==============================  =====================
P_f        exact McNemar             Cohen's g                       (exact already)
μ_y        paired t                  d_z = d̄/s_d, exact CI           Wilcoxon signed-rank
σ_y        Pitman–Morgan             SD ratio, exact CI (normal)     BCa bootstrap of ratio
=========  ========================  ==============================  =====================

P_f per replication is the failure indicator ``y_i > δ_lim`` of that replication's
measured ``y`` (``docs/validation.md`` says why); μ_y and σ_y are the mean and SD of the
replications' ``y``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from surrogate_rbrdo.validation.paired_binary import PairedProportions, paired_proportions
from surrogate_rbrdo.validation.paired_spread import PairedSpread, paired_spread
from surrogate_rbrdo.validation.statistics import PairedComparison, paired_comparison


@dataclass(frozen=True)
class Comparison:
    """The paired statistics of ``after`` against ``before`` for one quantity."""

    quantity: str
    before: str
    after: str
    pf: PairedProportions
    mean: PairedComparison
    std: PairedSpread

    def to_dict(self) -> dict[str, Any]:
        return {"quantity": self.quantity, "before": self.before, "after": self.after,
                "pf": self.pf.to_dict(), "mean": self.mean.to_dict(),
                "std": self.std.to_dict()}


def compare_designs(before: np.ndarray, after: np.ndarray, *, quantity: str, names: tuple[str, str],
                    delta_lim_m: float, rng: np.random.Generator, confidence: float = 0.95,
                    alpha: float = 0.05, power: float = 0.8, n_boot: int = 9999) -> Comparison:
    """Paired statistics of the values ``after`` (n,) against ``before`` (n,) (metres)."""
    a, b = np.asarray(before, float), np.asarray(after, float)
    kw = dict(confidence=confidence, alpha=alpha)
    pf = paired_proportions(a > delta_lim_m, b > delta_lim_m, name=f"{quantity} P_f",
                            power=power, **kw)
    mean = paired_comparison(a, b, rng=rng, name=f"{quantity} mean", n_boot=n_boot, **kw)
    std = paired_spread(a, b, rng=rng, name=f"{quantity} std", power=power, n_boot=n_boot, **kw)
    return Comparison(quantity, names[0], names[1], pf, mean, std)


@dataclass(frozen=True)
class Table7Row:
    """One row of Table 7's analogue (amplitudes in µm, P_f as a fraction)."""

    quantity: str
    baseline: str
    design: str
    metric: str
    before: float
    after: float
    change: float
    change_ci_low: float
    change_ci_high: float
    relative_change: float
    relative_ci_low: float
    relative_ci_high: float
    test: str
    statistic: float
    df: float
    p_value: float
    effect_name: str
    effect: float
    effect_ci_low: float
    effect_ci_high: float
    check: str
    check_value: str
    power: str

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def _pf_row(c: Comparison) -> Table7Row:
    p = c.pf
    return Table7Row(
        c.quantity, c.before, c.after, "P_f", p.p_before, p.p_after, p.diff, *p.diff_ci,
        p.relative_change, np.nan, np.nan, "exact McNemar", float(p.before_only),
        float(p.before_only + p.after_only), p.mcnemar_p, "Cohen's g", p.cohens_g, np.nan,
        np.nan, "2x2 pairs (both, before only, after only, neither)",
        f"{p.both}/{p.before_only}/{p.after_only}/{p.neither}",
        f"P_f,before >= {p.min_detectable_p_before:.2f} detected with power {p.power:g} "
        "when the design never fails")


def _mean_row(c: Comparison) -> Table7Row:
    m = c.mean
    return Table7Row(
        c.quantity, c.before, c.after, "mu_y", m.mean_before * 1e6, m.mean_after * 1e6,
        m.mean_diff * 1e6, *(v * 1e6 for v in m.bootstrap_diff_ci), m.relative_change,
        *m.bootstrap_relative_ci, "paired t", m.t, float(m.df), m.p_value, "d_z", m.d_z,
        *m.d_z_ci, "Wilcoxon signed-rank p", f"{m.wilcoxon_p:.3g}",
        f"|d_z| >= {m.min_detectable_d_z:.2f} detected with power 0.8")


def _std_row(c: Comparison) -> Table7Row:
    s = c.std
    return Table7Row(
        c.quantity, c.before, c.after, "sigma_y", s.sd_before * 1e6, s.sd_after * 1e6,
        (s.sd_after - s.sd_before) * 1e6, np.nan, np.nan, s.relative_change,
        s.ratio_ci[0] - 1.0, s.ratio_ci[1] - 1.0, "Pitman-Morgan", s.t, float(s.df),
        s.p_value, "SD ratio", s.ratio, *s.ratio_ci, "BCa bootstrap CI of the relative change",
        f"[{s.bootstrap_relative_ci[0]:.3g}, {s.bootstrap_relative_ci[1]:.3g}]",
        f"SD ratio <= {s.min_detectable_ratio:.2f} detected with power {s.power:g} "
        f"(pair correlation {s.correlation:.2f})")


def table7_rows(c: Comparison) -> list[Table7Row]:
    """The P_f, μ_y and σ_y rows of one comparison (the paper's Table 7 order)."""
    return [_pf_row(c), _mean_row(c), _std_row(c)]
