"""Figures of the identification: convergence (paper Fig. 1), speed trend ±2σ (Fig. 3) and
normal Q–Q plots with R² (Fig. 4); :func:`write_identification_figures` draws all three for an
identification run (what the ``identification`` experiment kind writes)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from surrogate_rbrdo.identification.condensation import (
    condense_reactions,
    node_at,
    phasor_time_regression,
)
from surrogate_rbrdo.identification.experiment import table_rows
from surrogate_rbrdo.identification.identify import identify
from surrogate_rbrdo.identification.plan import IdentificationPlan
from surrogate_rbrdo.identification.recursions import MISG, RLS, SG
from surrogate_rbrdo.identification.scatter import run_factors
from surrogate_rbrdo.reporting.figures import pyplot as _pyplot
from surrogate_rbrdo.reporting.figures import save_figure as _save
from surrogate_rbrdo.spindle.assembly import SpindleModel


def plot_convergence(results: Mapping[str, object], truth: np.ndarray, path: str | Path, *,
                     tol: float = 0.05, reference_label: str = "truth") -> Path:
    """Median (line) and interquartile band (shade) over records of the relative error of
    ``k`` and ``c`` vs samples, one curve per method (the paper's Fig. 1, with both parameters).

    ``results`` maps a label to an :class:`~surrogate_rbrdo.identification.IdentificationResult`
    computed with a ``stride`` (its trajectory is plotted); ``truth`` is ``(n,)`` or ``(B, n)``.
    """
    plt = _pyplot()
    first = next(iter(results.values()))
    n = first.estimate.shape[1]
    fig, axes = plt.subplots(1, n, figsize=(5.5 * n, 4.2), squeeze=False)
    for label, res in results.items():
        if res.trajectory is None:
            raise ValueError(f"results[{label!r}] has no trajectory: identify(..., stride=k)")
        tr = np.broadcast_to(np.atleast_2d(np.asarray(truth, dtype=float)),
                             res.estimate.shape)
        err = np.abs(res.trajectory / tr[:, None, :] - 1.0)
        x = res.trajectory_samples + 1
        for j, ax in enumerate(axes[0]):
            q25, q50, q75 = np.percentile(err[..., j], [25, 50, 75], axis=0)
            line, = ax.loglog(x, q50, lw=1.4, label=label)
            ax.fill_between(x, q25, q75, color=line.get_color(), alpha=0.15, lw=0)
    for j, ax in enumerate(axes[0]):
        ax.axhline(tol, color="k", lw=0.8, ls=":")
        ax.set_xlabel("samples (iterations)")
        ax.set_ylabel(f"|{first.names[j]} / {reference_label} − 1|")
        ax.set_title(f"{first.names[j]}: median and IQR over {first.estimate.shape[0]} records")
    axes[0, 0].legend(fontsize=8)
    fig.tight_layout()
    return _save(fig, path)


def plot_trend(model, speeds_rpm: np.ndarray, values: np.ndarray, path: str | Path, *,
               truth=None, coefficients=None) -> Path:
    """Identified values vs speed with the fitted trend, the ±2σ band of the scatter the study
    gets at each speed (trend × (1 ± 2 σ_e(Ω))) and the trend's 95 % interval (statistical and
    systematic); ``truth`` (callable speed → ``(d,)``) is drawn dashed.

    ``model`` is an :class:`~surrogate_rbrdo.identification.model.IdentifiedUncertainty`;
    ``values (N, d)`` are its input columns (SI).
    """
    plt = _pyplot()
    names = list(model.coefficients if coefficients is None else coefficients)
    cols = [model.coefficients.index(c) for c in names]
    ncol = min(len(cols), 2)
    nrow = int(np.ceil(len(cols) / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(6 * ncol, 3.6 * nrow), squeeze=False)
    lo_s, hi_s = model.speed_range_rpm
    grid = np.linspace(lo_s, hi_s, 120)
    sd = np.sqrt(np.array([np.diag(model.factor_cov_at(s)) for s in grid]))      # (G, d)
    ci = np.array([model.trend_interval(s) for s in grid])                       # (G, 2, d)
    for ax, j in zip(axes.ravel(), cols, strict=False):
        tr = model.trends[j]
        t = tr.predict(grid)
        scale = 1e6 if "_k_" in model.coefficients[j] else 1.0
        unit = "MN/m" if scale == 1e6 else "N s/m"
        ax.plot(speeds_rpm, values[:, j] / scale, ".", ms=2.5, color="0.55", label="identified")
        ax.plot(grid, t / scale, "C0", lw=1.5, label=f"trend ({tr.law})")
        ax.fill_between(grid, t * (1 - 2 * sd[:, j]) / scale, t * (1 + 2 * sd[:, j]) / scale,
                        color="C0", alpha=0.15, lw=0, label=f"±2σ {model.scatter} scatter")
        ax.fill_between(grid, ci[:, 0, j] / scale, ci[:, 1, j] / scale, color="C1",
                        alpha=0.5, lw=0, label="trend 95 % CI")
        if truth is not None:
            ax.plot(grid, np.array([truth(s)[j] for s in grid]) / scale, "k--", lw=1,
                    label="truth")
        ax.set_title(model.coefficients[j])
        ax.set_xlabel("speed (rpm)")
        ax.set_ylabel(unit)
    for ax in axes.ravel()[len(cols):]:
        ax.set_visible(False)
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    return _save(fig, path)


def plot_qq(factors: np.ndarray, names, path: str | Path) -> Path:
    """Normal Q–Q plot of each column of ``factors`` with its fitted line and R² (Fig. 4)."""
    plt = _pyplot()
    X = np.asarray(factors, dtype=float)
    names = list(names)
    ncol = min(len(names), 4)
    nrow = int(np.ceil(len(names) / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(3.4 * ncol, 3.2 * nrow), squeeze=False)
    for ax, j in zip(axes.ravel(), range(X.shape[1]), strict=False):
        (osm, osr), (slope, icpt, r) = stats.probplot(X[:, j], dist="norm")
        ax.plot(osm, osr, ".", ms=2.5)
        ax.plot(osm, slope * osm + icpt, "r--", lw=1)
        ax.set_title(f"{names[j]}  R² = {r * r:.4f}", fontsize=9)
        ax.set_xlabel("normal quantile")
    for ax in axes.ravel()[X.shape[1]:]:
        ax.set_visible(False)
    fig.tight_layout()
    return _save(fig, path)


def campaign_convergence(model: SpindleModel, run, speed_rpm: float, *,
                         n_samples: int = 2000, dt_s: float = 1e-4) -> tuple[dict, np.ndarray]:
    """SG, MISG(p = 3) and RLS on the 1× time samples of the used records at the campaign speed
    nearest ``speed_rpm`` (:func:`phasor_time_regression`, ``Δt`` = 0.1 ms as the paper): the
    results with trajectories, and each record's closed-form estimate (their reference — least
    squares on these samples equals it exactly, so the curves show the recursions' convergence,
    not the identification error)."""
    resp, camp = run.responses, run.campaign
    ok = camp.used
    speeds = np.unique(resp.speed_rpm[ok])
    s = float(speeds[np.argmin(np.abs(speeds - speed_rpm))])
    rows = np.flatnonzero(ok & (resp.speed_rpm == s))
    probe = [node_at(model, float(p)) for p in resp.positions_mm[::2]]
    unb = [(node_at(model, pos), U * np.exp(1j * np.radians(ph)))
           for pos, U, ph in resp.unbalance]
    cr = condense_reactions(model, [s], probe_nodes=probe, unbalance=unb)
    x, r = cr.reactions(resp.phasors[rows], np.full(rows.size, s))
    reg = phasor_time_regression(x, r, np.full(rows.size, s), n_samples=n_samples, dt_s=dt_s)
    est = camp.identification.estimate[rows]                        # (n, 8): k, c per b, dir
    ref = est.reshape(rows.size, -1, 2, 2).transpose(0, 1, 3, 2).reshape(-1, 2)
    th0 = ref * [0.8, 0.7]
    res = {m.name: identify(reg, m, theta0=th0, stride=10) for m in (SG(), MISG(p=3), RLS())}
    return res, ref


def write_identification_figures(model: SpindleModel, run, out_dir: str | Path, *,
                                 convergence_speed_rpm: float = 10_000.0) -> dict[str, Path]:
    """Fig. 1 (convergence at one speed), Fig. 3 (trends ±2σ) and Fig. 4 (Q–Q of each run's
    detrended factors — the independent sample — and of all records') of an
    :class:`~surrogate_rbrdo.identification.experiment.IdentificationRun` into ``out_dir``."""
    out = Path(out_dir)
    u, camp = run.uncertainty, run.campaign
    cols = [camp.identification.names.index(c) for c in u.coefficients]
    sp = run.responses.speed_rpm[camp.used]
    X = camp.identification.estimate[camp.used][:, cols]
    res, ref = campaign_convergence(model, run, convergence_speed_rpm)
    e = X / u.trend(sp)
    runs = run_factors(e, run.responses.groups[camp.used], _rel_cov(camp, cols, u, sp))
    return {"fig1_convergence": plot_convergence(res, ref, out / "identification_convergence.png",
                                                 reference_label="closed form"),
            "fig3_trend": plot_trend(u, sp, X, out / "identification_trend.png"),
            "fig4_qq": plot_qq(runs, [f"{c} (per run)" for c in u.coefficients],
                               out / "identification_qq.png"),
            "fig4_qq_records": plot_qq(e, u.coefficients,
                                       out / "identification_qq_records.png")}


def _rel_cov(camp, cols, u, sp):
    """The used records' identification covariance of the factors (for run weighting)."""
    C = camp.identification.covariance
    if C is None:
        return None
    t = u.trend(sp)
    return C[camp.used][:, cols][:, :, cols] / (t[:, :, None] * t[:, None, :])



def write_identification_run(out: Any, p: IdentificationPlan, res: Any) -> dict[str, Any]:
    """``identified.csv``, ``uncertainty.json`` (what ``[uncertainty] from`` of a study
    reads), ``identification_summary.json`` and the figures (``p.options.figures``) of an
    ``IdentificationRun`` into ``out`` (a run folder); returns the summary (``meta``, rows of
    θ's mean and std, records used, trend laws)."""
    camp, u = res.campaign, res.uncertainty
    out.write_csv("identified.csv", *table_rows(camp.table))
    out.write_json("uncertainty.json", u.to_dict())
    figures = (write_identification_figures(p.model, res, out.path,
                                            convergence_speed_rpm=p.options.convergence_speed_rpm)
               if p.options.figures else {})
    info = {"flag_counts": camp.flag_counts, "timings_s": res.timings,
            "provenance": res.provenance, "rig_run": p.rig_run,
            "figures": {k: Path(v).name for k, v in figures.items()}}
    out.write_json("identification_summary.json", info)
    d = u.to_dict()
    sd = np.sqrt(np.diag(np.asarray(d["cov"])))
    rows = [{"theta": n, "speed_rpm": d["speed_rpm"], "mean": round(float(m), 5),
             "std": round(float(s), 5)} for n, m, s in zip(d["names"], d["mean"], sd,
                                                            strict=True)]
    used = int(np.sum(camp.used))
    return {"meta": {"n_records": int(res.responses.n), "n_used": used,
                     "source": str(p.source), "rig_run": p.rig_run,
                     "identification_s": res.timings, "flag_counts": camp.flag_counts},
            "summary": rows + [{"records": int(res.responses.n), "used": used,
                                "trend_laws": {c: t.law for c, t in zip(
                                    u.coefficients, u.trends, strict=True)}}]
            + impact_rows(d.get("provenance", {}).get("damping"))}


def impact_rows(damping: Mapping[str, Any] | None) -> list[dict[str, Any]]:
    """One summary line per installation's impact fit: η̂, the tool mass factor, the fit's
    χ²/ν and the lack-of-fit test against the hits' own scatter (docs/identification.md §5b).

    >>> impact_rows({"source": "response"})
    []
    """
    if not damping or damping.get("source") != "impact":
        return []
    return [{"impacts": key, "eta_s": [float(f"{e:.4g}") for e in inst["eta_s"]],
             "tool_mass": round(float(inst["parameters"].get("tool_mass", 1.0)), 4),
             "chi2_dof": round(float(inst["chi2_dof"]), 2)} | _lack_of_fit(inst)
            for key, inst in damping["installations"].items()]


def _lack_of_fit(inst: Mapping[str, Any]) -> dict[str, Any]:
    if "lack_of_fit" not in inst:                  # written before the test existed
        return {}
    lof = inst["lack_of_fit"]
    if not lof:
        return {"lack_of_fit": "not tested (fewer than 3 hits per direction)"}
    return {"lack_of_fit": ("MODEL ERROR " if lof["flagged"] else "ok ")
            + f"(chi2/dof {lof['chi2_dof']:.3g}, threshold {lof['threshold']:g})"}


__all__ = ["campaign_convergence", "impact_rows", "plot_convergence", "plot_qq", "plot_trend",
           "write_identification_figures", "write_identification_run"]
