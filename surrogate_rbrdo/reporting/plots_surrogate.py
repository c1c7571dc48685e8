"""Figures of surrogate validation (matplotlib ``Figure`` objects; the caller saves them).

>>> fig = parity_plot([1.0, 10.0, 100.0], [1.2, 9.0, 110.0], label="peak amplitude [µm]",
...                   title="main: peak amplitude at 3 fresh LHS points", log=True)
>>> fig.axes[0].get_xscale(), fig.axes[0].get_title()
('log', 'main: peak amplitude at 3 fresh LHS points')
"""

from __future__ import annotations

import textwrap
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from surrogate_rbrdo.reporting import tables_surrogate as tab
from surrogate_rbrdo.study.assessment import AssessmentPlan


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




#: the ``mc_comparison.csv`` columns printed in the terminal summary
SUMMARY_COLUMNS = ("variant", "design", "mean_rel_err", "std_rel_err", "pf_fe", "pf_sur",
                   "ok_mean", "ok_std", "ok_pf")


def write_assessment_run(out: Any, p: AssessmentPlan, truth: Any, variants: Any
                         ) -> dict[str, Any]:
    """A surrogate validation's tables (``tables_surrogate.validation_tables``), parity
    figures per variant, ``surrogate_info.json`` and ``calls.json`` into ``out`` (a run
    folder); returns the summary (variants, ``meta``: counted calls, MC comparison rows)."""
    tables = tab.validation_tables(list(p.designs), truth, variants, p.limit.threshold,
                                   p.validation.n_theta_nc)
    for name, (header, rows) in tables.items():
        out.write_csv(name, header, rows)
    for a in variants:
        for name, fig in parity_figures(a.name, truth.y, a.y_pred).items():
            out.save_figure(name, fig)
    out.write_json("surrogate_info.json", {a.name: {k: v for k, v in a.trained.to_dict().items()
                                                    if k != "options"} for a in variants})
    meta = {**tab.validation_calls(truth, variants), "n_theta": p.validation.n_theta,
            "n_test": int(truth.y.size)}
    out.write_json("calls.json", meta)
    return {"variants": [a.name for a in variants], "meta": meta,
            "summary": [{k: x for k, x in zip(tab.MC_HEADER, r, strict=True)
                         if k in SUMMARY_COLUMNS} for r in tables["mc_comparison.csv"][1]]}


__all__ = ["SUMMARY_COLUMNS", "parity_figures", "parity_plot", "write_assessment_run"]
