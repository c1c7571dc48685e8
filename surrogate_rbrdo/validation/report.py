"""A validation campaign as a markdown results section (the paper's Sect. 4.3, our numbers).

:func:`markdown_section` is text only; figures are embedded by the relative paths given.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from surrogate_rbrdo.validation.campaign import ValidationResult
from surrogate_rbrdo.validation.table7 import Table7Row, table7_rows
from surrogate_rbrdo.validation.tables import critical_table

UM = 1e6


def _g(v: float, d: int = 3) -> str:
    return "–" if v is None or not np.isfinite(v) else f"{v:.{d}g}"


def _ci(lo: float, hi: float, d: int = 3) -> str:
    return "" if not (np.isfinite(lo) and np.isfinite(hi)) else f" [{lo:.{d}g}, {hi:.{d}g}]"


def _row(r: Table7Row) -> str:
    unit = "" if r.metric == "P_f" else " µm"
    return (f"| {r.metric} | {r.design} | {_g(r.before)}{unit} | {_g(r.after)}{unit} | "
            f"{_g(r.change)}{_ci(r.change_ci_low, r.change_ci_high)} | "
            f"{_g(100 * r.relative_change)} %"
            f"{_ci(100 * r.relative_ci_low, 100 * r.relative_ci_high)}"
            f" | {r.test}: {_g(r.statistic, 4)} (df {_g(r.df)}), p = {_g(r.p_value)} | "
            f"{r.effect_name} = {_g(r.effect)}{_ci(r.effect_ci_low, r.effect_ci_high)} | "
            f"{r.check}: {r.check_value} | {r.power} |")


def _table7(result: ValidationResult, quantity: str) -> list[str]:
    head = ["| metric | design | baseline | design value | change [CI] | relative [CI] | test | "
            "effect size [CI] | check | power |", "|" + "---|" * 10]
    rows = [_row(r) for c in result.comparisons if c.quantity == quantity
            for r in table7_rows(c)]
    return head + rows


def _verdicts(result: ValidationResult) -> list[str]:
    out = ["| design | quantity | metric | measured [CI] | model [CI] | p (Holm) | verdict |",
           "|---|---|---|---|---|---|---|"]
    for v in result.verdicts:
        s, u = (1.0, "") if v.metric == "pf" else (UM, " µm")
        out.append(f"| {v.design} | {v.quantity} | {v.metric} | {_g(v.measured * s)}{u}"
                   f"{_ci(v.measured_ci[0] * s, v.measured_ci[1] * s)} | {_g(v.model * s)}{u}"
                   f"{_ci(v.model_ci[0] * s, v.model_ci[1] * s)} | {_g(v.p_holm)} | "
                   f"{'agree' if v.agree else '**disagree**'} |")
    return out


def _criticals(result: ValidationResult) -> list[str]:
    rows = critical_table(result)
    out = ["| design | replication | rig (run-down / run-up) rpm | model rpm | model − rig |",
           "|---|---|---|---|---|"]
    for r in rows:
        one = "" if r["both_ramps"] else ", one ramp only"
        diff = r["relative_difference"]
        out.append(f"| {r['design']} | {r['replica']} | {r['speed_rpm']:.0f} "
                   f"({_g(r['rundown_rpm'], 5)} / {_g(r['runup_rpm'], 5)}{one}) | "
                   f"{_g(r['model_rpm'], 5)} | "
                   f"{_g(100 * diff) + ' %' if np.isfinite(diff) else '–'} |")
    for d in result.designs:
        if not d.criticals and result.options.ramps:
            cs = result.model_campbell.get(d.name)
            model = "–" if cs is None else ", ".join(f"{v:.0f}" for v in cs.critical_speeds_rpm)
            out.append(f"| {d.name} | – | none in the ramps | {model or 'none'} | |")
    return out


def markdown_section(result: ValidationResult, figures: Mapping[str, str] | None = None) -> str:
    """The campaign as markdown: designs, Table 7 analogues (peak over the range and rated
    speed), model vs measurement, critical speeds, figures, provenance."""
    o = result.options
    lo, hi = o.speed_range_rpm
    lines = [
        "## Validation on the virtual rig", "",
        f"{o.n_replications} paired replications per design (each a fresh assembly and run "
        f"drawn from the rig's variability model; pairs share {', '.join(o.shared) or 'nothing'};"
        f" steady-state measurements by the `{o.method}` path). y = peak tool-tip 1x amplitude "
        f"over {lo:.0f}–{hi:.0f} rpm (dwell search); P_f per replication = 1 if that "
        f"replication's measured y exceeds δ_lim = {o.delta_lim_um:g} µm, else 0.", "",
        "| design | x | measured μ_y (µm) | σ_y (µm) | P_f [CI] |", "|---|---|---|---|---|"]
    for d in result.designs:
        m = d.moments["peak"]
        tag = " (baseline)" if d.name == result.baseline and d.name != "baseline" else ""
        lines.append(f"| {d.name}{tag} | {[round(v, 2) for v in d.x]} | "
                     f"{_g(m.mean * UM)}{_ci(m.mean_ci[0] * UM, m.mean_ci[1] * UM)} | "
                     f"{_g(m.std * UM)}{_ci(m.std_ci[0] * UM, m.std_ci[1] * UM)} | "
                     f"{_g(m.pf)}{_ci(*m.pf_ci)} |")
    lines += ["", f"### Table 7 analogue: y = peak over {lo:.0f}–{hi:.0f} rpm", ""]
    lines += _table7(result, "peak")
    lines += ["", f"### Table 7 analogue: amplitude at the rated speed {o.rated_speed_rpm:.0f} rpm",
              ""]
    lines += _table7(result, "rated")
    if result.verdicts:
        lines += ["", "### Model vs measurement (Holm-adjusted, family-wise α = "
                  f"{o.alpha:g})", ""] + _verdicts(result)
        bad = result.disagreements
        lines += ["", f"{len(bad)} of {len(result.verdicts)} comparisons disagree beyond "
                  "uncertainty" + (": " + "; ".join(f"{v.design} {v.quantity} {v.metric}"
                                                     for v in bad) if bad else ".")]
    if o.ramps:
        lines += ["", "### Critical speeds (run-up and run-down on the rig)", ""]
        lines += _criticals(result)
    for key, title in (("fig8_response", "Fig. 8 analogue: full-range response ±2σ"),
                       ("fig7_campbell", "Fig. 7 analogue: Campbell diagram"),
                       ("paired_peak", "Paired replications"),
                       ("model_vs_measured_fig", "Model vs measurement")):
        if figures and key in figures:
            lines += ["", f"![{title}]({figures[key]})"]
    t = result.timings
    lines += ["", f"Provenance: seed entropy {result.seed['entropy']}, spawn key "
              f"{result.seed['spawn_key']}; {sum(d.n_records for d in result.designs)} "
              f"steady-state records; measured in {t['measure_s']:.1f} s, statistics "
              f"{t['statistics_s']:.1f} s, model {t['model_s']:.1f} s "
              "(truth draws per replication and the probe installation: `validation.json`).", ""]
    return "\n".join(lines)
