"""Figures of surrogate validation (matplotlib ``Figure`` objects; the caller saves them).

>>> fig = parity_plot([1.0, 10.0, 100.0], [1.2, 9.0, 110.0], label="peak amplitude [µm]",
...                   title="main: peak amplitude at 3 fresh LHS points", log=True)
>>> fig.axes[0].get_xscale(), fig.axes[0].get_title()
('log', 'main: peak amplitude at 3 fresh LHS points')
"""

from __future__ import annotations

import textwrap

import numpy as np
from matplotlib.figure import Figure


def parity_plot(y_true: np.ndarray, y_pred: np.ndarray, *, y_std: np.ndarray | None = None,
                title: str = "surrogate vs true model", label: str = "y", log: bool = False):
    """Predicted vs true values with the identity line; optional ±2σ error bars; ``log``:
    both axes logarithmic (values must be > 0). ``label`` names the quantity with its unit
    (``"peak amplitude [µm]"``); a long ``title`` is wrapped so it fits the figure.

    Returns the ``Figure`` (the caller saves it).
    """
    yt, yp = np.ravel(y_true), np.ravel(y_pred)
    if yt.shape != yp.shape:
        raise ValueError(f"y_pred has shape {yp.shape} is not allowed: must match {yt.shape}")
    if log and not (np.all(yt > 0) and np.all(yp > 0)):
        raise ValueError("log = True is not allowed: every value must be > 0")
    fig = Figure(figsize=(5.0, 5.0), layout="constrained")
    ax = fig.subplots()
    if y_std is not None:
        ax.errorbar(yt, yp, yerr=2 * np.ravel(y_std), fmt="o", ms=3, alpha=0.6, lw=0.8,
                    label="prediction ± 2σ")
    else:
        ax.plot(yt, yp, "o", ms=3, alpha=0.7, label="prediction")
    lo, hi = float(min(yt.min(), yp.min())), float(max(yt.max(), yp.max()))
    ax.plot([lo, hi], [lo, hi], "k--", lw=1, label="identity")
    if log:
        ax.set_xscale("log")
        ax.set_yscale("log")
    ax.set_xlabel(f"true {label}")
    ax.set_ylabel(f"surrogate {label}")
    ax.set_title("\n".join(textwrap.wrap(title, 48)), fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    return fig


def parity_figures(name: str, y_true: np.ndarray, y_pred: np.ndarray) -> dict[str, Figure]:
    """The two parity figures of a variant (file name → figure): peak amplitude in µm on
    linear and on log axes (``y`` in m)."""
    n = np.size(y_true)
    args = (np.asarray(y_true) * 1e6, np.asarray(y_pred) * 1e6)
    title = f"{name}: peak amplitude at {n} fresh LHS points"
    return {f"parity_{name}.png": parity_plot(*args, title=title, label="peak amplitude [µm]"),
            f"parity_log_{name}.png": parity_plot(*args, title=f"{title}, log scale",
                                                  label="peak amplitude [µm]", log=True)}


__all__ = ["parity_figures", "parity_plot"]
