"""Figures of optimisation results: Pareto fronts per P_target, archive clouds, compromises,
front designs and convergence.

Inputs are plain arrays (no optimiser objects), in SI units; axes are labelled in μm. Every
function returns a ``matplotlib.figure.Figure`` (no pyplot state: nothing to close; the caller
saves it).

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
from matplotlib.figure import Figure


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
    if ax is None:
        fig = Figure(figsize=(6.0, 4.5), layout="constrained")
        ax = fig.subplots()
    else:
        fig = ax.figure
    cloud_label = "feasible designs evaluated (faint, in each front's colour)"
    for i, (label, F) in enumerate(fronts.items()):
        color = f"C{i}"
        if clouds is not None and label in clouds and len(clouds[label]):
            C = np.asarray(clouds[label], dtype=float) * scale
            ax.scatter(C[:, 0], C[:, 1], s=3, color=color, alpha=0.12, linewidths=0,
                       label=cloud_label)
            cloud_label = "_" + cloud_label          # one legend entry for all the clouds
        F = np.asarray(F, dtype=float)
        F = F[np.argsort(F[:, 0])] * scale
        ax.plot(F[:, 0], F[:, 1], "o-", ms=3, lw=1.2, color=color, label=label)
        if compromises is not None and label in compromises:
            m, s = compromises[label]
            ax.plot([m * scale], [s * scale], "*", ms=14, color=color, mec="k",
                    label=f"{label}: ASF compromise")
    ax.set_xlabel(f"mean μ_y of the {quantity} [{unit}]")
    ax.set_ylabel(f"standard deviation σ_y [{unit}]")
    ax.set_title(f"feasible Pareto fronts (μ_y, σ_y)\n{quantity}", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def plot_convergence(histories: Mapping[str, list], *, objective: int = 0, scale: float = 1e6,
                     unit: str = "μm", name: str = "μ_y", note: str = "", ax=None):
    """Best feasible value of one objective per generation, one line per run.

    ``histories`` maps a label to ``OptimizationResult.history`` (dicts with ``f_min``);
    ``name`` is what objective ``objective`` is (axis and title), ``note`` a remark for the
    title (e.g. what a single-objective run minimises instead).
    """
    if ax is None:
        fig = Figure(figsize=(6.5, 4.0), layout="constrained")
        ax = fig.subplots()
    else:
        fig = ax.figure
    for label, hist in histories.items():
        best = np.fmin.accumulate(np.array([h["f_min"][objective] for h in hist], dtype=float))
        ax.plot(np.arange(len(best)), best * scale, label=label)
    ax.set_xlabel("generation")
    ax.set_ylabel(f"best feasible {name} [{unit}]")
    extra = f" ({note})" if note else ""
    ax.set_title(f"convergence of objective {objective + 1}, {name}{extra}:\n"
                 "best feasible value so far, per run", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def plot_front_designs(fronts: Mapping[str, np.ndarray], *, baseline=None):
    """Front designs ``[F N, L mm, D mm]`` in the (L, D) and (L, F) planes, one colour per
    label."""
    fig = Figure(figsize=(10, 4), layout="constrained")
    axes = fig.subplots(1, 2)
    for i, (label, X) in enumerate(fronts.items()):
        X = np.asarray(X, float)
        axes[0].scatter(X[:, 1], X[:, 2], s=12, color=f"C{i}", label=label, alpha=0.8)
        axes[1].scatter(X[:, 1], X[:, 0], s=12, color=f"C{i}", label=label, alpha=0.8)
    if baseline is not None:
        axes[0].plot(baseline[1], baseline[2], "kx", ms=10, label="baseline")
        axes[1].plot(baseline[1], baseline[0], "kx", ms=10, label="baseline")
    axes[0].set_xlabel("span L [mm]")
    axes[0].set_ylabel("diameter D [mm]")
    axes[1].set_xlabel("span L [mm]")
    axes[1].set_ylabel("preload F_f [N]")
    for a in axes:
        a.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle("designs on the feasible RBRDO Pareto fronts", fontsize=10)
    return fig


__all__ = ["plot_convergence", "plot_front_designs", "plot_pareto_fronts"]
