"""Figures of surrogate validation (matplotlib, Agg backend; the caller passes the path)."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure


def parity_plot(y_true: np.ndarray, y_pred: np.ndarray, *, y_std: np.ndarray | None = None,
                title: str = "surrogate vs true model", label: str = "y"):
    """Predicted vs true values with the identity line; optional ±2σ error bars.

    Returns the ``Figure`` (the caller saves and closes it).
    """
    yt, yp = np.ravel(y_true), np.ravel(y_pred)
    if yt.shape != yp.shape:
        raise ValueError(f"y_pred has shape {yp.shape} is not allowed: must match {yt.shape}")
    fig = Figure(figsize=(4.5, 4.5))
    ax = fig.subplots()
    if y_std is not None:
        ax.errorbar(yt, yp, yerr=2 * np.ravel(y_std), fmt="o", ms=3, alpha=0.6, lw=0.8,
                    label="prediction ± 2σ")
    else:
        ax.plot(yt, yp, "o", ms=3, alpha=0.7, label="prediction")
    lo, hi = float(min(yt.min(), yp.min())), float(max(yt.max(), yp.max()))
    ax.plot([lo, hi], [lo, hi], "k--", lw=1, label="identity")
    ax.set_xlabel(f"true {label}")
    ax.set_ylabel(f"surrogate {label}")
    ax.set_title(title)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    return fig
