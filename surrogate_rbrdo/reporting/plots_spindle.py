"""Figures of the spindle model: Campbell diagram and tool-tip unbalance response."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_campbell(campbells: dict[str, object], path: str | Path, *,
                  speed_max_rpm: float | None = None) -> Path:
    """Campbell diagram(s): damped frequencies vs speed, forward solid / backward dashed,
    the 1x line and the critical speeds (circles). ``campbells`` maps a label to a
    :class:`~surrogate_rbrdo.spindle.modal.Campbell`."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    top = 0.0
    for c_i, (label, c) in enumerate(campbells.items()):
        col = colors[c_i % len(colors)]
        sp = c.speeds_rpm
        for k in range(c.frequency_hz.shape[1]):
            for whirl, ls in (("forward", "-"), ("backward", "--")):
                f = np.where(c.whirl[:, k] == whirl, c.frequency_hz[:, k], np.nan)
                ax.plot(sp, f, ls, color=col, lw=1.2,
                        label=f"{label}" if (k == 0 and whirl == "forward") else None)
        cs = c.critical_speeds_rpm
        ax.plot(cs, cs / 60.0, "o", color=col, mfc="none", ms=8)
        for s in cs:
            ax.annotate(f"{s:.0f}", (s, s / 60.0), textcoords="offset points", xytext=(4, -12),
                        fontsize=8, color=col)
        top = max(top, sp[-1])
    ax.plot([0, top], [0, top / 60.0], "k:", lw=1, label="1x")
    if speed_max_rpm:
        ax.axvline(speed_max_rpm, color="grey", lw=0.8)
    ax.set_xlabel("speed (rpm)")
    ax.set_ylabel("damped natural frequency (Hz)")
    ax.set_ylim(0, max(1.5 * top / 60.0, 1.0))
    ax.set_title("Campbell diagram (solid: forward, dashed: backward; o: 1x critical speeds)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return _save(fig, path)


def plot_unbalance_response(curves: dict[str, tuple[np.ndarray, np.ndarray]], path: str | Path,
                            *, limit_um: float | None = None,
                            bands: dict[str, tuple[np.ndarray, np.ndarray]] | None = None
                            ) -> Path:
    """Tool-tip amplitude (µm) vs speed (rpm), log scale; optional ±2σ bands and δ_lim."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for label, (sp, amp_um) in curves.items():
        line, = ax.semilogy(sp, amp_um, lw=1.3, label=label)
        if bands and label in bands:
            lo, hi = bands[label]
            ax.fill_between(sp, lo, hi, color=line.get_color(), alpha=0.2, lw=0)
    if limit_um:
        ax.axhline(limit_um, color="r", ls="--", lw=1, label=f"δ_lim = {limit_um:g} µm")
    ax.set_xlabel("speed (rpm)")
    ax.set_ylabel("tool-tip amplitude (µm)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return _save(fig, path)


def _save(fig, path: str | Path) -> Path:
    import os

    path = Path(path)
    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    fig.savefig(tmp, dpi=120)
    os.replace(tmp, path)
    _plt().close(fig)
    return path
