"""Figures of the discrepancy workflow: where the model and the data part, the candidates'
ranking, and the gap before and after, one figure per observable."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from joblib import Parallel, delayed

from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.discrepancy.plan import DiscrepancyPlan
from surrogate_rbrdo.discrepancy.report import write_run


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_residual_map(result, path: str | Path) -> Path:
    """Whitened residual modulus of the recalibrated baseline per channel and point (colour,
    log scale; held-out points hatched below the axis) and χ²/dof per speed band, per block."""
    plt = _plt()
    curves = result.curves
    fig, axes = plt.subplots(2, len(curves), figsize=(5.5 * len(curves), 6), squeeze=False)
    for k, c in enumerate(curves):
        ax = axes[0, k]
        z = np.sqrt(np.sum(c.white_before**2, axis=-1)).T                   # (C, X)
        im = ax.pcolormesh(c.coord, np.arange(len(c.channels)), np.log10(np.maximum(z, 1e-2)),
                           cmap="magma", shading="nearest", vmin=-1, vmax=3)
        ax.set_yticks(range(len(c.channels)), c.channels)
        ax.set_title(f"{c.name}: |whitened residual| before (log10)")
        ho = c.coord[c.held_out]
        ax.plot(ho, np.full(ho.size, -0.45), "v", color="c", ms=4, label="held out")
        if ho.size:
            ax.legend(loc="upper left", fontsize=7)
        fig.colorbar(im, ax=ax)
        ax2 = axes[1, k]
        tb, ta = c.chi2_table("before"), c.chi2_table("after")
        edges = np.asarray(next(iter(tb.values()))["band_edges"])
        mid = 0.5 * (edges[:-1] + edges[1:])
        for ch in c.channels:
            ax2.semilogy(mid, [v or np.nan for v in tb[ch]["bands"]], "o-", lw=1, label=ch)
        ax2.semilogy(mid, np.nanmean([[v or np.nan for v in ta[ch]["bands"]]
                                      for ch in c.channels], axis=0), "k--", lw=2,
                     label="after (mean)")
        ax2.axhline(1.0, color="grey", lw=0.8)
        ax2.set_xlabel(c.coord_label)
        ax2.set_ylabel("χ²/dof per band")
        ax2.legend(fontsize=7, ncol=2)
    fig.suptitle(f"where model and data part — verdict: {result.verdict}")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)


def plot_candidates(result, path: str | Path) -> Path:
    """Δχ² of every candidate in each stage, with the family-wise threshold's p-value."""
    plt = _plt()
    fig, axes = plt.subplots(1, len(result.stages), figsize=(5 * len(result.stages), 3.5),
                             squeeze=False)
    for i, st in enumerate(result.stages):
        ax = axes[0, i]
        names = [a.name for a in st.assessments]
        d = [max(a.delta_chi2, 1e-3) for a in st.assessments]
        colors = ["tab:green" if a.passed else "tab:grey" for a in st.assessments]
        ax.barh(names, d, color=colors)
        ax.set_xscale("log")
        ax.set_xlabel("Δχ² (green: passes every check)")
        ax.set_title(f"stage {i + 1}")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)


#: the gap figure's layout, in inches: fixed margins instead of ``tight_layout`` (which draws
#: every figure twice to measure its labels; a third of the figures' CPU)
_AX_W, _AX_H, _LEFT, _RIGHT, _TOP, _BOTTOM, _WGAP, _HGAP = 3.4, 2.0, 0.8, 0.15, 0.7, 0.5, 0.7, 0.2


def _gap_axes(plt, n_cols: int):
    """A figure of 3 rows (amplitude, phase, whitened residual) × ``n_cols`` channels, laid
    out with fixed margins (:data:`_AX_W` …), the rows of a column sharing their x axis."""
    w = _LEFT + _RIGHT + n_cols * _AX_W + (n_cols - 1) * _WGAP
    h = _TOP + _BOTTOM + 3 * _AX_H + 2 * _HGAP
    fig, axes = plt.subplots(3, n_cols, figsize=(w, h), sharex="col", squeeze=False)
    fig.subplots_adjust(left=_LEFT / w, right=1 - _RIGHT / w, bottom=_BOTTOM / h,
                        top=1 - _TOP / h, wspace=_WGAP / _AX_W, hspace=_HGAP / _AX_H)
    return fig, axes


def plot_gap(block, path: str | Path) -> Path:
    """One observable block (the 1x response vs speed, or the FRF of one hit direction at one
    speed), one column per channel: amplitude and phase of the data (±2 standard errors) and
    of the model before and after, and the whitened residual of both; held-out points marked
    (cyan lines)."""
    plt = _plt()
    c = block
    fig, axes = _gap_axes(plt, len(c.channels))
    x = c.coord
    for j, ch in enumerate(c.channels):
        a1, a2, a3 = axes[:, j]
        amp = np.abs(c.data[:, j]) * 1e6
        a1.errorbar(x, amp, yerr=2 * c.se[:, j] * 1e6, fmt="o", ms=3, color="k",
                    label="data ±2σ")
        for lab, y, st in (("before", c.before, "--"), ("after", c.after, "-")):
            a1.plot(x, np.abs(y[:, j]) * 1e6, st, label=lab)
            a2.plot(x, np.degrees(np.angle(y[:, j])), st, label=lab)
        a2.plot(x, np.degrees(np.angle(c.data[:, j])), "o", ms=3, color="k")
        for lab, w, st in (("before", c.white_before, "o--"), ("after", c.white_after, "o-")):
            a3.semilogy(x, np.maximum(np.sqrt(np.sum(w[:, j] ** 2, axis=-1)), 1e-3), st,
                        ms=3, label=lab)
        a3.axhline(2.0, color="grey", lw=0.8)
        for ax in (a1, a2, a3):      # one collection per axes, spanning it (x data, y axes)
            ax.vlines(x[c.held_out], 0, 1, transform=ax.get_xaxis_transform(), color="c",
                      lw=0.6, alpha=0.5)
        a1.set_yscale("log")
        a1.set_title(ch, y=1.0, pad=4)   # fixed: no search above the axes' tick labels
        a3.set_xlabel(c.coord_label)
    a1, a2, a3 = axes[:, 0]
    a1.set_ylabel("amplitude (µm/unit load)" if c.coord_label.startswith("freq")
                  else "1x amplitude (µm)")
    a2.set_ylabel("phase (deg)")
    a3.set_ylabel("|residual| / noise")
    a1.legend(fontsize=8)
    a3.legend(fontsize=8)
    fig.suptitle(f"{c.name}: data, model before and after (held-out points: cyan lines)")
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)


@dataclass(frozen=True)
class _Curves:
    """What :func:`plot_residual_map` reads of a result (sent to a worker instead of the
    whole result with its fits)."""

    verdict: str
    curves: tuple


@dataclass(frozen=True)
class _Bar:
    """What :func:`plot_candidates` reads of an assessment."""

    name: str
    delta_chi2: float
    passed: bool


@dataclass(frozen=True)
class _StageBars:
    """What :func:`plot_candidates` reads of a stage."""

    assessments: tuple[_Bar, ...]


@dataclass(frozen=True)
class _Ranking:
    """What :func:`plot_candidates` reads of a result (sent to a worker instead of it)."""

    stages: tuple[_StageBars, ...]

    @classmethod
    def of(cls, result) -> _Ranking:
        return cls(tuple(_StageBars(tuple(_Bar(a.name, float(a.delta_chi2), bool(a.passed))
                                          for a in st.assessments))
                         for st in result.stages))


def plot_all(result, out_dir: str | Path, *, n_jobs: int = 1) -> dict[str, Path]:
    """Every figure into ``out_dir``: ``residual_map.png``, ``candidates.png`` and
    ``gap_<block>.png`` per observable block (one column per channel). With ``n_jobs > 1``
    every figure is drawn on that many joblib (loky) worker
    processes — the ones the analysis used, when they are still up — largest first (a
    figure's cost grows with its channels and points); every figure is drawn by the same
    code from the same data either way, so the files are the same."""
    check_int("n_jobs", n_jobs, minimum=1)
    out = Path(out_dir)
    jobs = [("residual_map", plot_residual_map, _Curves(result.verdict, tuple(result.curves)),
             out / "residual_map.png", sum(c.data.size for c in result.curves)),
            ("candidates", plot_candidates, _Ranking.of(result), out / "candidates.png", 0)]
    jobs += [(f"gap_{c.name}", plot_gap, c, out / f"gap_{c.name}.png", c.data.size)
             for c in result.curves]
    jobs.sort(key=lambda j: -j[4])                  # longest first (LPT)
    if n_jobs == 1 or len(jobs) < 2:
        made = [func(arg, path) for _, func, arg, path, _ in jobs]
    else:
        made = Parallel(n_jobs=min(n_jobs, len(jobs)))(
            delayed(func)(arg, path) for _, func, arg, path, _ in jobs)
    paths = {j[0]: m for j, m in zip(jobs, made, strict=True)}
    order = ["residual_map", "candidates"] + [f"gap_{c.name}" for c in result.curves]
    return {k: paths[k] for k in order}


def verdict_line(res: Any) -> str:
    """One line: the verdict, what is named, the test (and the thermal soak's verdicts, when
    one was consulted) and the held-out gap."""
    t, b, a = res.test, res.gap_before, res.gap_after
    what = {"named": ", ".join(e.name for e in res.effects),
            "confounded": " | ".join(res.confounded_with + tuple(
                f"({g})" for g in res.confounded_generic))}.get(res.verdict, "")
    soak = "; ".join(f"soak: {s.candidate} {s.outcome.replace('_', ' ')} (p {s.p_drift:.2g})"
                     for s in res.soak)
    return (f"{res.verdict}{': ' + what if what else ''}{' [' + soak + ']' if soak else ''} "
            f"(statistic {t['statistic']:.4g}, "
            f"p {t['p_value']:.3g}, threshold {t['threshold']:g}); held-out RMSE "
            f"{b.rmse:.4g} -> {a.rmse:.4g} um, chi2/dof {b.chi2_dof:.3g} -> {a.chi2_dof:.3g} "
            f"(predictive {b.predictive_chi2_dof:.3g} -> {a.predictive_chi2_dof:.3g})")


def write_discrepancy_run(out_dir: str | Path, p: DiscrepancyPlan, res: Any, data: Any
                          ) -> dict[str, Any]:
    """A discrepancy run's files (``discrepancy.report.write_run``: findings, updated
    ``[spindle]``, candidates, curves) and figures (:func:`plot_all`) into ``out_dir``;
    returns the summary (``meta``: verdict, named effects, data folder, figures; ``summary``:
    :func:`verdict_line` and the named effects' parameters). ``data``: the campaign result or
    the data folder."""
    out = Path(out_dir)
    write_run(res, out, spindle_section=p.spindle_section, model_effects=p.spindle.effects)
    (out / "figures").mkdir(exist_ok=True)
    figs = plot_all(res, out / "figures", n_jobs=p.options.n_jobs)
    src = data
    named = [{"effect": e.name, **{k: float(f"{v:.6g}") for k, v in e.fit.parameters.items()
                                   if isinstance(v, float) and np.isfinite(v)}}
             for e in res.effects]
    return {"meta": {"verdict": res.verdict, "named": [e.name for e in res.effects],
                     "confounded_with": list(res.confounded_with),
                     "data": str(src if isinstance(src, Path) else src.root),
                     "analyse_s": res.seconds, "figures": sorted(f.name for f in figs.values())},
            "summary": [{"verdict": verdict_line(res)}, *named]}
