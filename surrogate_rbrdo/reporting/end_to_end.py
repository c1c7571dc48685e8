"""``report.md`` of the end-to-end loop: a results section in the paper's order (rig campaign →
identification → the study's θ → RBRDO → validation on the rig → discrepancy) with this run's
numbers, each with the file (and stage) it comes from, and the figures embedded by relative
path.

The inputs are the stages' frozen results; the parts' own files (``rig/``, ``identification/``,
``study/``, ``validation/``, ``discrepancy/``) are written here too, from the same results,
so every number in ``report.md`` can be found again in a table of the run folder.

>>> _fmt(0.000123456), _fmt(12345.678), _fmt(float("nan"))
('0.000123', '1.23e+04', '—')
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.files import atomic_write_text
from surrogate_rbrdo.reporting.plots_identification import write_identification_figures
from surrogate_rbrdo.reporting.plots_rig import write_rig_report
from surrogate_rbrdo.reporting.plots_validation import write_validation_report
from surrogate_rbrdo.rig.store import open_dataset
from surrogate_rbrdo.validation.campaign import file_label
from surrogate_rbrdo.validation.table7 import table7_rows


def _fmt(v: float, digits: int = 3) -> str:
    """A number to ``digits`` significant figures (``—`` for NaN/None)."""
    if v is None or not np.isfinite(v):
        return "—"
    return f"{float(v):.{digits}g}"


def _table(header: Sequence[str], rows: Sequence[Sequence[Any]]) -> list[str]:
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return out + ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]


def _figures(folder: Path, root: Path, names: Sequence[str] | None = None) -> list[str]:
    """Markdown image lines for the PNGs of ``folder`` (relative to ``root``)."""
    pngs = sorted(folder.rglob("*.png")) if names is None else [folder / n for n in names]
    return [f"![{p.stem}]({p.relative_to(root).as_posix()})" for p in pngs if p.is_file()]


def _pick(res: Any) -> Any:
    """The comparison the headline quotes: RBRDO 5 % (the paper's choice) if validated,
    else the first design against the baseline."""
    peak = [c for c in res.comparisons if c.quantity == "peak"]
    five = [c for c in peak if c.after.endswith("5pct") and c.after.startswith("rbrdo")]
    return (five or peak or [None])[0]


def _headline_lines(theta: Any, bearings: Sequence[str], ver: Any, res: Any, disc: Any,
                    limit_um: float, res2: Any = None, reoptimise: Any = None) -> list[str]:
    mvn = theta.stiffness
    sd = np.sqrt(np.diag(np.asarray(mvn.cov, float)))
    th = ", ".join(f"{b} {m:.3f} ± {s:.1%}" for b, m, s in zip(bearings, mvn.mean, sd,
                                                                 strict=True))
    out = ["## Headline", "", f"* **θ identified on the rig** (§2): {th} (mean factor ± SD)."]
    c = _pick(res)
    if c is not None:
        m, sp, pf = c.mean, c.std, c.pf
        i = {file_label(n): j for j, n in enumerate(ver.names)}.get(c.after)
        model_pf = f"{ver.fe.pf[i]:.3g}" if i is not None else "—"
        lo, hi = m.bootstrap_relative_ci
        n = res.options.n_replications
        out += [f"* **{c.after} against {c.before} on the rig** (§4, n = {n} paired "
                f"replications): mean peak {m.mean_before * 1e6:.3g} → "
                f"{m.mean_after * 1e6:.3g} µm ({m.relative_change:+.1%} [{lo:+.1%}, "
                f"{hi:+.1%}], paired t = {m.t:.3g}, p = {m.p_value:.2g}, d_z = {m.d_z:.2f}); "
                f"σ {sp.sd_before * 1e6:.3g} → {sp.sd_after * 1e6:.3g} µm "
                f"({sp.relative_change:+.1%}); P_f(y > {limit_um:g} µm) {pf.p_before:.2f} → "
                f"{pf.p_after:.2f} (exact McNemar p = {pf.mcnemar_p:.2g}); the model's P_f "
                f"(FE verification, §3): {model_pf}.",
                "* The paper's Table 7 (RBRDO 5 %, 24 000 rpm): μ −16.84 %, σ −29.78 %, P_f "
                "55.44 % → 0.35 %."]
    bad = res.disagreements
    out.append(f"* **Model against rig** (§4): {len(bad)} of {len(res.verdicts)} "
               "comparisons disagree beyond uncertainty (Holm, α = 0.05).")
    if disc.ran:
        named = [getattr(e, "name", str(e)) for e in disc.result.named_effects]
        out.append(f"* **Discrepancy** (§5): verdict *{disc.result.verdict}*"
                   + (f", named {', '.join(named)}; updated spindle in "
                      "`discrepancy/spindle_updated.toml`" if named else "")
                   + (". Optimised again and validated again (§6): "
                      f"{len(res2.disagreements)} of {len(res2.verdicts)} comparisons "
                      "disagree with the updated model." if res2 is not None else
                      f". **Not re-optimised**: {reoptimise.reason}."))
    else:
        out.append(f"* **Discrepancy** (§5): not run ({disc.reason}).")
    return out + [""]


def _rig_section(campaign: Any, options: Any, rig_summary: Mapping[str, Any], variability: Any,
                 root: Path) -> list[str]:
    o = options
    trial = o.trial_unbalance
    lines = ["## 1. Rig campaign (stage `campaign`)", "",
             f"{campaign.n_records} records on the virtual rig's truth (the model's spindle "
             f"at its baseline with the hidden effects of `[rig]`): {len(o.speeds_rpm)} speeds "
             f"{_fmt(min(o.speeds_rpm), 5)}–{_fmt(max(o.speeds_rpm), 5)} rpm × {o.repeats} "
             f"repeats of {o.duration_s:g} s"
             + (f", each speed also with a trial mass of {trial[1] * 1e6:g} g mm at "
                f"{trial[0]:g} mm (phase {trial[2]:g}°)" if trial is not None else "")
             + ". Source: `campaign/phasors.csv`, `campaign/dataset/`.", "",
             f"The hidden variability the identification has to find (`[rig.variability]`): "
             f"bearing stiffness CoV {variability.bearing_k_cov:.1%} per build, thermal "
             f"preload CoV {variability.thermal_preload_cov:.1%} per run (stiffness ∝ F^1/3)."]
    crit = {k: v for k, v in rig_summary.items() if k.startswith(("critical_speeds",
                                                                  "model_critical"))}
    if crit:
        lines += ["", "Critical speeds (`rig/rig_summary.json`): " + "; ".join(
            f"{k} = {[round(float(x)) for x in v]}" for k, v in crit.items())]
    return lines + [""] + _figures(root / "rig", root) + [""]


def truth_theta(dataset: Path) -> np.ndarray:
    """θ the rig's truth had in each steady record without the trial mass (virtual rig only:
    each record's provenance), ``(n, m)``; empty when the records do not carry it."""
    ds = open_dataset(dataset)
    rows = [r for r in ds.select(kind="steady") if not r["labels"].get("trial", 0)]
    th = [ds.load(r).provenance.get("theta") for r in rows]
    return np.array([t for t in th if t is not None], float)


def _theta_section(ident: Any, theta: Any, bearings: Sequence[str], root: Path,
                   truth: np.ndarray) -> list[str]:
    mvn = theta.stiffness
    mean, sd = np.asarray(mvn.mean, float), np.sqrt(np.diag(np.asarray(mvn.cov, float)))
    used = np.asarray(ident.campaign.used, bool)
    prov = theta.provenance
    tm, ts = ((truth.mean(axis=0), truth.std(axis=0, ddof=1)) if truth.size else
              (np.full(len(bearings), np.nan), np.full(len(bearings), np.nan)))
    rows = [(b, _fmt(m, 4), f"{s:.2%}", _fmt(a, 4), f"{c:.2%}") for b, m, s, a, c in
            zip(bearings, mean, sd, tm, ts, strict=True)]
    speeds = np.asarray(prov.get("speeds_rpm", []), float)
    return ["## 2. Identification and the study's θ (stages `demodulate`, `identify`, "
            "`uncertainty`)",
            "",
            f"{int(used.sum())} of {used.size} identified coefficient vectors used "
            "(`identification/identified.csv`, column `used`; flags in "
            "`identification/identification_summary.json`); trend, physical scatter and "
            "systematic uncertainty in `identification/uncertainty.json`.",
            "",
            "θ of the study — stiffness factors relative to the model's nominal bearing "
            "stiffness, the moment-matched mixture over the identified speeds "
            + (f"{_fmt(speeds.min(), 5)}–{_fmt(speeds.max(), 5)} rpm ({speeds.size} speeds)"
               if speeds.size else "") + " (stage `uncertainty`; `theta.json`):", "",
            *_table(["bearing", "identified mean factor", "SD", "truth's mean", "truth's SD"],
                    rows), "",
            f"The truth's columns are the θ the rig's hidden truth had in the {truth.shape[0]} "
            "steady records without the trial mass (each record's provenance in "
            "`campaign/dataset/`; a real rig has no such column): one build measured over its "
            "runs, so its mean is *this* spindle's deviation from the catalogue and its SD the "
            "run-to-run (thermal) scatter — not the assembly-to-assembly scatter that the "
            "validation's replications draw (`[rig.variability] bearing_k_cov`).", "",
            *_figures(root / "identification", root), ""]


def _study_section(ver: Any, limit_um: float, root: Path, folder: str = "study") -> list[str]:
    rows = []
    for i, n in enumerate(ver.names):
        fe = ver.fe
        lo, hi = (float(v) for v in np.asarray(fe.pf_ci)[i])
        rows.append((n, ", ".join(_fmt(v, 5) for v in ver.X[i]), _fmt(fe.mean[i] * 1e6),
                     _fmt(fe.std[i] * 1e6), f"{fe.pf[i]:.3g} [{lo:.3g}, {hi:.3g}]"))
    return ["## 3. RBRDO on the identified θ (stages `surrogate` … `verify`)", "",
            f"The chosen designs, checked with the FE model on {ver.n_theta} fresh θ samples "
            f"(`{folder}/verification.csv`, columns `*_fe`); y = peak tool-tip amplitude over the "
            f"range, failure y > {limit_um:g} µm.", "",
            *_table(["design", "x = [F N, L mm, D mm]", "μ_y µm", "σ_y µm",
                     "P_f [95 % CI]"], rows), "",
            f"Fronts, strategy comparison and compromises: `{folder}/pareto_fronts.csv`, "
            f"`{folder}/strategy_comparison.csv`, `{folder}/compromises.csv`.", "",
            *_figures(root / folder, root), ""]


def _validation_section(res: Any, root: Path, folder: str = "validation") -> list[str]:
    n = res.options.n_replications
    rows = []
    for c in res.comparisons:
        if c.quantity != "peak":
            continue
        for r in table7_rows(c):
            ci = (f" [{_fmt(r.relative_ci_low)}, {_fmt(r.relative_ci_high)}]"
                  if np.isfinite(r.relative_ci_low) else "")
            rows.append((r.design, r.metric, _fmt(r.before), _fmt(r.after),
                         _fmt(r.relative_change) + ci, f"{r.test} {_fmt(r.statistic)}",
                         _fmt(r.p_value), f"{r.effect_name} {_fmt(r.effect)}"))
    verdicts = [(v.design, v.quantity, v.metric, _fmt(v.measured * (1e6 if v.metric != "pf"
                                                                     else 1)),
                 _fmt(v.model * (1e6 if v.metric != "pf" else 1)), _fmt(v.p_holm),
                 "agree" if v.agree else "**disagree**") for v in res.verdicts]
    out = ["## 4. Validation on the rig (stages `measure`, `model`)", "",
           f"Each design built on the rig's truth and measured over {n} paired replications "
           f"(fresh assembly and run each; baseline `{res.baseline}`). Table 7's analogue for "
           f"y, the peak over the range (`{folder}/table7.csv`; amplitudes in µm, P_f as a "
           "fraction, relative change as a fraction with its interval):", "",
           *_table(["design", "metric", "baseline", "design value", "relative change [CI]",
                    "test", "p", "effect size"], rows), ""]
    if verdicts:
        out += ["Model (the study's FE verification) against measurement, Holm-corrected "
                f"(`{folder}/model_vs_measured.csv`; µm, P_f as a fraction):", "",
                *_table(["design", "quantity", "metric", "measured", "model", "p (Holm)",
                         "verdict"], verdicts), ""]
    out += [f"The full section: [{folder}/validation.md]({folder}/validation.md).", "",
            *_figures(root / folder, root), ""]
    return out


def _discrepancy_section(stage: Any, root: Path, reoptimised: Any) -> list[str]:
    out = ["## 5. Discrepancy (stage `discrepancy`)", ""]
    if not stage.ran:
        return out + [f"Not run: {stage.reason}. The model is unchanged; nothing is "
                      "re-optimised.", ""]
    r = stage.result
    named = [getattr(e, "name", str(e)) for e in r.named_effects]
    out += [f"Run because {stage.reason}. On the campaign's phasors "
            f"(`campaign/phasors.csv`) the workflow's verdict is **{r.verdict}**"
            + (f": {', '.join(named)}" if named else "") + " (`discrepancy/findings.json`, "
            "`discrepancy/candidates.csv`)."]
    if named and reoptimised.done:
        out += ["", "The updated spindle (the model's effects plus the named ones, fitted) is "
                "written to `discrepancy/spindle_updated.toml`; §6 optimises it again "
                "(stage `reoptimise`: " + reoptimised.reason + ") and validates its designs "
                "on the rig."]
    elif named:
        out += ["", "The updated spindle (the model's effects plus the named ones, fitted) is "
                "written to `discrepancy/spindle_updated.toml`. **It is not re-optimised** "
                f"(stage `reoptimise`): {reoptimised.reason}."]
    else:
        out += ["", "No effect is named, so the model is not updated and nothing is "
                "re-optimised."]
    return out + [""] + _figures(root / "discrepancy", root) + [""]


def _updated_section(ver: Any, res: Any, before: Any, limit_um: float, root: Path
                     ) -> list[str]:
    """§6: the study on the updated spindle and its designs on the rig."""
    out = ["## 6. The updated model: optimised again, validated again (stages `*_updated`)", ""]
    out += _study_section(ver, limit_um, root, "study_updated")[2:]
    out += _validation_section(res, root, "validation_updated")[2:]
    n0, n1 = len(before.disagreements), len(res.disagreements)
    out += [f"Model against rig: {n0} of {len(before.verdicts)} comparisons disagreed with the "
            f"identified model (§4), {n1} of {len(res.verdicts)} with the updated one "
            "(`validation_updated/model_vs_measured.csv`).", ""]
    return out


def _timings_section(timings: Mapping[str, float]) -> list[str]:
    rows = [(k, f"{v:.1f}") for k, v in timings.items()]
    total = sum(timings.values())
    return ["## Stage timings (`meta.json`, `stages`)", "",
            *_table(["stage", "seconds"], rows + [("**total of the stages**",
                                                   f"{total:.1f}")]), ""]


def write_loop_report(out_dir: str | Path, *, truth: Any, campaign: Any, campaign_options: Any,
                      model: Any, identification: Any, identification_figures: bool,
                      convergence_speed_rpm: float, theta: Any, theta_bearings: Sequence[str],
                      verification: Any, limit_um: float, validation: Any, discrepancy: Any,
                      timings: Mapping[str, float], rig_figures: bool = True,
                      updated: tuple[Any, Any] = (None, None), reoptimise: Any = None
                      ) -> dict[str, Any]:
    """Write the parts' files and ``report.md`` into ``out_dir``; return the headline
    numbers (the runner's summary)."""
    root = Path(out_dir)
    rig_summary = write_rig_report(campaign, truth, root / "rig") if rig_figures else {}
    if identification_figures:
        write_identification_figures(model, identification, root / "identification",
                                     convergence_speed_rpm=convergence_speed_rpm)
    mvn = theta.stiffness
    atomic_write_text(root / "theta.json", json.dumps(
        {"names": list(theta_bearings), "mean": np.asarray(mvn.mean).tolist(),
         "cov": np.asarray(mvn.cov).tolist(), "provenance": theta.provenance},
        indent=1, default=str))
    write_validation_report(validation, root / "validation")
    ver2, res2 = updated
    if res2 is not None:
        write_validation_report(res2, root / "validation_updated")
    lines = ["# Results: the data-driven loop on the virtual rig", "",
             "One run of `rbrdo run` (experiment kind `end_to_end`): every number below is "
             "this run's, and names the file of the run folder it comes from.", ""]
    lines += _headline_lines(theta, theta_bearings, verification, validation, discrepancy,
                             limit_um, res2, reoptimise)
    lines += _rig_section(campaign, campaign_options, rig_summary, truth.variability, root)
    lines += _theta_section(identification, theta, theta_bearings, root,
                            truth_theta(campaign.dataset))
    lines += _study_section(verification, limit_um, root)
    lines += _validation_section(validation, root)
    lines += _discrepancy_section(discrepancy, root, reoptimise)
    if res2 is not None:
        lines += _updated_section(ver2, res2, validation, limit_um, root)
    lines += _timings_section(timings)
    atomic_write_text(root / "report.md", "\n".join(lines) + "\n")
    return _headline(verification, validation, discrepancy, theta)


def _headline(ver: Any, res: Any, disc: Any, theta: Any) -> dict[str, Any]:
    rows = [{"design": d.name, "mu_peak_um": round(d.moments["peak"].mean * 1e6, 4),
             "sigma_peak_um": round(d.moments["peak"].std * 1e6, 4),
             "pf_peak": d.moments["peak"].pf} for d in res.designs]
    bad = [f"{v.design} {v.quantity} {v.metric}" for v in res.disagreements]
    meta = {"theta_mean": np.asarray(theta.stiffness.mean).round(5).tolist(),
            "disagreements": bad, "discrepancy_ran": disc.ran,
            "discrepancy_verdict": disc.result.verdict if disc.ran else None}
    return {"summary": rows, "meta": meta}


__all__ = ["write_loop_report"]
