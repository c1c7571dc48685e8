"""Figures of a validation campaign (Fig. 7 and Fig. 8 analogues, paired replications, model
vs measurement) and :func:`write_validation_report`, which writes tables, figures and a
markdown section into a folder.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.reporting.figures import pyplot as _plt
from surrogate_rbrdo.reporting.figures import save_figure as _save
from surrogate_rbrdo.validation.campaign import ValidationResult
from surrogate_rbrdo.validation.report import markdown_section
from surrogate_rbrdo.validation.tables import write_tables

UM = 1e6


def plot_response_bands(result: ValidationResult, path: str | Path) -> Path:
    """Fig. 8's analogue: per design, the measured tool-tip amplitude over the speed list,
    mean ± 2σ over the replications, each replication's measured peak (dots), the model's
    mean ± 2σ band beside it (dashed), and δ_lim."""
    plt = _plt()
    n = len(result.designs)
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n, 4.0), squeeze=False)
    sp = np.asarray(result.options.speeds_rpm)
    lim = result.options.delta_lim_um
    for ax, d in zip(axes[0], result.designs, strict=True):
        mu, sd = d.curve.mean(axis=0) * UM, d.curve.std(axis=0, ddof=1) * UM
        ax.fill_between(sp, np.maximum(mu - 2 * sd, 0.0), mu + 2 * sd, color="C0", alpha=0.3,
                        lw=0, label="measured ±2σ")
        ax.plot(sp, mu, color="C0", lw=1.2, label="measured mean")
        ax.plot(d.peak_speed_rpm, d.peak * UM, ".", color="C3", ms=4,
                label="replication peaks")
        m = result.model
        if m is not None and d.name in m.band_mean:
            bm, bs = m.band_mean[d.name] * UM, m.band_std[d.name] * UM
            ax.plot(sp, bm, "k--", lw=1.0, label="model mean")
            ax.plot(sp, bm + 2 * bs, "k:", lw=0.8, label="model ±2σ")
            ax.plot(sp, np.maximum(bm - 2 * bs, 0.0), "k:", lw=0.8)
        ax.axhline(lim, color="r", ls="--", lw=1, label=f"δ_lim = {lim:g} µm")
        ax.set_ylim(bottom=0.0)
        ax.set_title(f"{d.name}: x = [{', '.join(f'{v:g}' for v in d.x)}]", fontsize=9)
        ax.set_xlabel("speed (rpm)")
        ax.grid(True, alpha=0.3)
    axes[0, 0].set_ylabel("tool-tip 1x amplitude (µm)")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle(f"Full-range response on the rig, n = {result.options.n_replications} "
                 "replications per design", fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


def plot_campbell_validation(result: ValidationResult, path: str | Path) -> Path:
    """Fig. 7's analogue: the model's Campbell diagram of each design (nominal θ; forward
    solid, backward dashed; o = its critical speeds) and the critical speeds measured on the
    rig (squares, the bar spanning run-down to run-up peak; hollow: seen in one ramp only)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4.8))
    top = result.options.speed_range_rpm[1]
    f_top = 1.6 * top / 60.0
    for i, d in enumerate(result.designs):
        col = f"C{i}"
        c = result.model_campbell.get(d.name)
        if c is not None:
            for k in range(c.frequency_hz.shape[1]):
                for whirl, ls in (("forward", "-"), ("backward", "--")):
                    f = np.where(c.whirl[:, k] == whirl, c.frequency_hz[:, k], np.nan)
                    ax.plot(c.speeds_rpm, f, ls, color=col, lw=1.0, alpha=0.8,
                            label=f"{d.name} (model)" if k == 0 and whirl == "forward" else None)
            cs = c.critical_speeds_rpm
            ax.plot(cs, cs / 60.0, "o", color=col, mfc="none", ms=9)
            f_top = max(f_top, 1.15 * float(np.nanmin(c.frequency_hz[:, 0])))
        for cm in d.criticals:
            lo = np.nanmin([cm.rundown_rpm, cm.runup_rpm])
            hi = np.nanmax([cm.rundown_rpm, cm.runup_rpm])
            ax.errorbar(cm.speed_rpm, cm.speed_rpm / 60.0,
                        xerr=[[cm.speed_rpm - lo], [hi - cm.speed_rpm]], fmt="s", color=col,
                        mfc=col if cm.both_ramps else "none", ms=6, capsize=3,
                        label=f"{d.name} (rig run-up/down)" if cm.both_ramps
                        else f"{d.name} (rig, one ramp only)")
    right = max([top * 1.05] + [c.speeds_rpm[-1] for c in result.model_campbell.values()])
    ax.plot([0, right], [0, right / 60.0], "k:", lw=1, label="1x")
    ax.axvline(top, color="grey", lw=0.8)
    ax.set_xlim(0, right)
    ax.set_ylim(0, f_top)
    ax.set_xlabel("speed (rpm)")
    ax.set_ylabel("damped natural frequency (Hz)")
    ax.set_title("Campbell diagram: model (lines, o) and critical speeds measured on the rig",
                 fontsize=9)
    handles, labels = ax.get_legend_handles_labels()
    uniq = dict(zip(labels, handles, strict=True))
    ax.legend(uniq.values(), uniq.keys(), fontsize=7)
    fig.tight_layout()
    return _save(fig, path)


def plot_paired(result: ValidationResult, path: str | Path, quantity: str = "peak") -> Path:
    """Each replication's ``y`` for the baseline and every other design, joined pair by pair
    (log scale), with δ_lim."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(1.8 + 1.6 * len(result.designs), 4.0))
    vals = [d.values(quantity) * UM for d in result.designs]
    for r in range(vals[0].size):
        ax.plot(range(len(vals)), [v[r] for v in vals], "-", color="grey", lw=0.6, alpha=0.7)
    for i, v in enumerate(vals):
        ax.plot(np.full(v.size, i), v, "o", color=f"C{i}", ms=4)
    ax.axhline(result.options.delta_lim_um, color="r", ls="--", lw=1, label="δ_lim")
    ax.set_xticks(range(len(vals)), [d.name for d in result.designs])
    ax.set_yscale("log")
    ax.set_ylabel(f"{quantity} tool-tip amplitude (µm)")
    ax.set_title("paired replications", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return _save(fig, path)


def plot_model_vs_measured(result: ValidationResult, path: str | Path) -> Path:
    """μ, σ (µm) and P_f of every design and quantity: measured interval vs model interval;
    red marks a disagreement."""
    plt = _plt()
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.6))
    for ax, metric, scale in zip(axes, ("mean", "std", "pf"), (UM, UM, 1.0), strict=True):
        vs = [v for v in result.verdicts if v.metric == metric]
        for k, v in enumerate(vs):
            col = "C3" if not v.agree else "C0"
            ax.errorbar(v.measured * scale, k + 0.1, xerr=[[(v.measured - v.measured_ci[0])
                                                            * scale],
                                                           [(v.measured_ci[1] - v.measured)
                                                            * scale]],
                        fmt="s", color=col, capsize=3)
            ax.errorbar(v.model * scale, k - 0.1, xerr=[[(v.model - v.model_ci[0]) * scale],
                                                        [(v.model_ci[1] - v.model) * scale]],
                        fmt="o", mfc="none", color="k", capsize=3)
        ax.set_yticks(range(len(vs)), [f"{v.design}/{v.quantity}" for v in vs], fontsize=7)
        ax.set_title({"mean": "μ_y (µm)", "std": "σ_y (µm)", "pf": "P_f"}[metric], fontsize=9)
        if metric != "pf":
            ax.set_xscale("log")
    axes[0].set_xlabel("squares: measured; circles: model")
    fig.tight_layout()
    return _save(fig, path)


def write_validation_report(result: ValidationResult, out_dir: str | Path, *,
                            figures: bool = True) -> Mapping[str, Path]:
    """Tables (``validation.tables.write_tables``), figures and ``validation.md`` (a results
    section with the figures embedded by relative path) into ``out_dir``."""
    out = Path(out_dir)
    paths = dict(write_tables(result, out))
    if figures:
        paths["fig8_response"] = plot_response_bands(result, out / "fig8_response.png")
        paths["fig7_campbell"] = plot_campbell_validation(result, out / "fig7_campbell.png")
        paths["paired_peak"] = plot_paired(result, out / "paired_peak.png", "peak")
        if result.verdicts:
            paths["model_vs_measured_fig"] = plot_model_vs_measured(
                result, out / "model_vs_measured.png")
    rel = {k: p.name for k, p in paths.items() if p.suffix == ".png"}
    paths["markdown"] = out / "validation.md"
    paths["markdown"].write_text(markdown_section(result, rel))
    return paths


def validation_summary(result: ValidationResult) -> dict[str, Any]:
    """The run's summary: per design μ, σ (µm) and P_f of the measured peak, the
    model-vs-measurement count; ``meta``: timings, disagreements, records."""
    rows = [{"design": d.name, "x": list(d.x),
             "mu_peak_um": round(d.moments["peak"].mean * 1e6, 4),
             "sigma_peak_um": round(d.moments["peak"].std * 1e6, 4),
             "pf_peak": d.moments["peak"].pf} for d in result.designs]
    bad = [f"{v.design} {v.quantity} {v.metric}" for v in result.disagreements]
    verdicts = ([{"model_vs_measured": f"{len(bad)} of {len(result.verdicts)} disagree beyond "
                  "uncertainty"}] if result.verdicts else [])
    return {"meta": {"timings": dict(result.timings), "disagreements": bad,
                     "n_records": sum(d.n_records for d in result.designs)},
            "summary": rows + verdicts}
