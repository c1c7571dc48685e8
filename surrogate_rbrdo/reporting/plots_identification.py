"""Figures of the identification: convergence (paper Fig. 1), speed trend ±2σ (Fig. 3) and
normal Q–Q plots with R² (Fig. 4)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
from scipy import stats

from surrogate_rbrdo.reporting.figures import pyplot as _plt
from surrogate_rbrdo.reporting.figures import save_figure as _save


def plot_convergence(results: Mapping[str, object], truth: np.ndarray, path: str | Path, *,
                     tol: float = 0.05) -> Path:
    """Median (line) and interquartile band (shade) over records of the relative error of
    ``k`` and ``c`` vs samples, one curve per method (the paper's Fig. 1, with both parameters).

    ``results`` maps a label to an :class:`~surrogate_rbrdo.identification.IdentificationResult`
    computed with a ``stride`` (its trajectory is plotted); ``truth`` is ``(n,)`` or ``(B, n)``.
    """
    plt = _plt()
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
        ax.set_ylabel(f"|{first.names[j]} / truth − 1|")
        ax.set_title(f"{first.names[j]}: median and IQR over {first.estimate.shape[0]} records")
    axes[0, 0].legend(fontsize=8)
    fig.tight_layout()
    return _save(fig, path)


def plot_trend(model, speeds_rpm: np.ndarray, values: np.ndarray, path: str | Path, *,
               truth=None, coefficients=None) -> Path:
    """Identified values vs speed with the fitted trend, the ±2σ scatter band (trend × (1 ± 2
    σ_e)) and the trend's 95 % interval; ``truth`` (callable speed → ``(d,)``) is drawn dashed.

    ``model`` is an :class:`~surrogate_rbrdo.identification.model.IdentifiedUncertainty`;
    ``values (N, d)`` are its input columns (SI).
    """
    plt = _plt()
    names = list(model.coefficients if coefficients is None else coefficients)
    cols = [model.coefficients.index(c) for c in names]
    ncol = min(len(cols), 2)
    nrow = int(np.ceil(len(cols) / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(6 * ncol, 3.6 * nrow), squeeze=False)
    grid = np.linspace(np.min(speeds_rpm), np.max(speeds_rpm), 200)
    sd = np.sqrt(np.diag(model.factor_cov))
    for ax, j in zip(axes.ravel(), cols, strict=False):
        tr = model.trends[j]
        t, ts = tr.predict(grid), tr.predict_std(grid)
        scale = 1e6 if "_k_" in model.coefficients[j] else 1.0
        unit = "MN/m" if scale == 1e6 else "N s/m"
        ax.plot(speeds_rpm, values[:, j] / scale, ".", ms=2.5, color="0.55", label="identified")
        ax.plot(grid, t / scale, "C0", lw=1.5, label=f"trend ({tr.law})")
        ax.fill_between(grid, t * (1 - 2 * sd[j]) / scale, t * (1 + 2 * sd[j]) / scale,
                        color="C0", alpha=0.15, lw=0, label="±2σ scatter")
        ax.fill_between(grid, (t - 1.96 * ts) / scale, (t + 1.96 * ts) / scale, color="C1",
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
    plt = _plt()
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


__all__ = ["plot_convergence", "plot_qq", "plot_trend"]
