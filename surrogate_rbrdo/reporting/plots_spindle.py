"""Figures of the spindle model: Campbell diagram and tool-tip unbalance response.

Each function returns a ``matplotlib.figure.Figure`` (no pyplot state; the caller saves it).
Every figure is titled, its axes carry units, its legend names every curve drawn (and says
"first N of M" when only some were computed), and its axis limits show every curve.

>>> import numpy as np
>>> fig = plot_unbalance_response({"a": (np.array([1e3, 2e4]), np.array([0.5, 3.0]))},
...                               limit_um=1.5)
>>> fig.axes[0].get_title()
'tool-tip unbalance response (nominal θ), 1 design'
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure


def _designs(n: int, of_total: int | None) -> str:
    if of_total is not None and of_total > n:
        return f"first {n} of {of_total} designs"
    return f"{n} design" + ("s" if n != 1 else "")


def plot_campbell(campbells: dict[str, object], *, speed_max_rpm: float | None = None,
                  of_total: int | None = None):
    """Campbell diagram(s): damped frequencies vs speed, forward solid / backward dashed,
    the 1x line and the critical speeds (circles). ``campbells`` maps a label to a
    :class:`~surrogate_rbrdo.spindle.modal.Campbell`; ``of_total``: how many designs there
    were if only these were computed (the title says "first N of M")."""
    fig = Figure(figsize=(9.0, 5.0), layout="constrained")
    ax = fig.subplots()
    top, f_max = 0.0, 0.0
    for c_i, (label, c) in enumerate(campbells.items()):
        col = f"C{c_i % 10}"
        sp = c.speeds_rpm
        for k in range(c.frequency_hz.shape[1]):
            for whirl, ls in (("forward", "-"), ("backward", "--")):
                f = np.where(c.whirl[:, k] == whirl, c.frequency_hz[:, k], np.nan)
                ax.plot(sp, f, ls, color=col, lw=1.2,
                        label=f"{label}" if (k == 0 and whirl == "forward") else None)
        if np.isfinite(c.frequency_hz).any():
            f_max = max(f_max, float(np.nanmax(c.frequency_hz)))
        cs = c.critical_speeds_rpm
        ax.plot(cs, cs / 60.0, "o", color=col, mfc="none", ms=8)
        for s in cs:
            ax.annotate(f"{s:.0f}", (s, s / 60.0), textcoords="offset points", xytext=(4, -12),
                        fontsize=8, color=col)
        top = max(top, sp[-1])
    ax.plot([0, top], [0, top / 60.0], "k:", lw=1, label="1x (synchronous)")
    if speed_max_rpm:
        ax.axvline(speed_max_rpm, color="grey", lw=0.8, label="top speed")
    ax.set_xlabel("speed [rpm]")
    ax.set_ylabel("damped natural frequency [Hz]")
    ax.set_ylim(0, 1.05 * max(f_max, top / 60.0, 1.0))
    ax.set_title(f"Campbell diagram, {_designs(len(campbells), of_total)}\n"
                 "solid: forward whirl, dashed: backward; o: 1x critical speeds [rpm]",
                 fontsize=10)
    _outside_legend(ax)
    return fig


def _outside_legend(ax) -> None:
    """The legend right of the axes (constrained layout makes room), so it never hides a
    curve."""
    n = len(ax.get_legend_handles_labels()[1])
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
              ncols=2 if n > 18 else 1)


def plot_unbalance_response(curves: dict[str, tuple[np.ndarray, np.ndarray]], *,
                            limit_um: float | None = None,
                            bands: dict[str, tuple[np.ndarray, np.ndarray]] | None = None):
    """Tool-tip amplitude (µm) vs speed (rpm), log scale; optional ±2σ bands and δ_lim."""
    fig = Figure(figsize=(9.0, 5.0), layout="constrained")
    ax = fig.subplots()
    for label, (sp, amp_um) in curves.items():
        line, = ax.semilogy(sp, amp_um, lw=1.3, label=label)
        if bands and label in bands:
            lo, hi = bands[label]
            ax.fill_between(sp, lo, hi, color=line.get_color(), alpha=0.2, lw=0)
    if limit_um:
        ax.axhline(limit_um, color="r", ls="--", lw=1, label=f"δ_lim = {limit_um:g} µm")
    ax.set_xlabel("speed [rpm]")
    ax.set_ylabel("tool-tip amplitude [µm]")
    ax.set_title(f"tool-tip unbalance response (nominal θ), {_designs(len(curves), None)}",
                 fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    _outside_legend(ax)
    return fig


__all__ = ["plot_campbell", "plot_unbalance_response"]
