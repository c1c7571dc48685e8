"""Figures of optimisation results: Pareto fronts per P_target, archive clouds, compromises.

Inputs are plain arrays (no optimiser objects), in SI units; axes are labelled in μm.

>>> import matplotlib
>>> matplotlib.use("Agg")
>>> import numpy as np
>>> fronts = {"P_t = 10 %": np.array([[15e-6, 12e-6], [16e-6, 10e-6]]),
...           "P_t = 5 %": np.array([[16e-6, 10e-6], [17e-6, 9e-6]])}
>>> fig = plot_pareto_fronts(fronts, compromises={"P_t = 10 %": (15e-6, 12e-6)})
>>> len(fig.axes[0].lines)
3
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np


def plot_pareto_fronts(fronts: Mapping[str, np.ndarray], *,
                       compromises: Mapping[str, tuple[float, float]] | None = None,
                       clouds: Mapping[str, np.ndarray] | None = None,
                       scale: float = 1e6, unit: str = "μm", quantity: str = "peak amplitude",
                       ax=None):
    """Plot μ_y–σ_y Pareto fronts, one per label (e.g. per P_target or per strategy).

    Parameters
    ----------
    fronts : mapping label -> ndarray (n, 2)
        Feasible non-dominated ``[μ_y, σ_y]`` points (SI).
    compromises : mapping label -> (μ, σ), optional
        ASF compromise designs, drawn as stars in the front's colour.
    clouds : mapping label -> ndarray (n, 2), optional
        All feasible evaluated points, drawn faintly behind the fronts.
    scale, unit : float, str
        Axis scaling and unit name.
    quantity : str
        What y is, for the axis labels (``ResponseSpec.label``).
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=(6.0, 4.5), constrained_layout=True)
    else:
        fig = ax.figure
    for i, (label, F) in enumerate(fronts.items()):
        color = f"C{i}"
        if clouds is not None and label in clouds and len(clouds[label]):
            C = np.asarray(clouds[label], dtype=float) * scale
            ax.scatter(C[:, 0], C[:, 1], s=3, color=color, alpha=0.12, linewidths=0)
        F = np.asarray(F, dtype=float)
        F = F[np.argsort(F[:, 0])] * scale
        ax.plot(F[:, 0], F[:, 1], "o-", ms=3, lw=1.2, color=color, label=label)
        if compromises is not None and label in compromises:
            m, s = compromises[label]
            ax.plot([m * scale], [s * scale], "*", ms=14, color=color, mec="k",
                    label=f"{label}: ASF compromise")
    ax.set_xlabel(f"mean μ_y of the {quantity} [{unit}]")
    ax.set_ylabel(f"standard deviation σ_y [{unit}]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def plot_convergence(histories: Mapping[str, list], *, objective: int = 0, scale: float = 1e6,
                     unit: str = "μm", ax=None):
    """Best feasible value of one objective per generation, one line per run.

    ``histories`` maps a label to ``OptimizationResult.history`` (dicts with ``f_min``).
    """
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=(6.0, 3.5), constrained_layout=True)
    else:
        fig = ax.figure
    for label, hist in histories.items():
        best = np.fmin.accumulate(np.array([h["f_min"][objective] for h in hist], dtype=float))
        ax.plot(np.arange(len(best)), best * scale, label=label)
    ax.set_xlabel("generation")
    ax.set_ylabel(f"best feasible objective {objective} [{unit}]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return fig
