"""Tables of a surrogate validation (the ``surrogate_validation`` experiment kind).

Rows are lists in the column order of the ``*_HEADER`` constants; no row holds a timing (the
run times go to ``meta.json``), so reruns with one seed give byte-identical tables.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from surrogate_rbrdo.surrogates.structured.resonance import ResonanceSurrogate
from surrogate_rbrdo.surrogates.validation import LOOSummary, MCComparison, validation_metrics


def rel_row(variant: str, quantity: str, subset: str, true: np.ndarray, pred: np.ndarray,
             unit_scale: float, unit: str) -> list[Any]:
    if true.size < 2:
        return [variant, quantity, subset, int(true.size), "", "", "", "", unit]
    e = pred / true - 1.0
    ml = validation_metrics(np.log(true), np.log(pred))
    return [variant, quantity, subset, int(true.size), round(ml.r2, 6),
            float(f"{np.sqrt(np.mean(e**2)):.3e}"), float(f"{np.max(np.abs(e)):.3e}"),
            round(float(np.max(np.abs(pred - true))) * unit_scale, 4), unit]


SUB_HEADER = ["variant", "quantity", "subset", "n", "r2_log", "rms_rel_err", "max_rel_err",
              "max_abs_err", "unit"]
NC_HEADER = ["variant", "design", "n_theta", "nc_fe_mean_rpm", "nc_fe_std_rpm",
             "r_min", "r_max", "nc_max_abs_err_rpm", "nc_mean_err_rpm", "err_over_std"]


def resonance_rows(name: str, sur: ResonanceSurrogate, Z_t: np.ndarray, Q_t: np.ndarray,
                      Z_d: np.ndarray, Q_d: np.ndarray, labels: list[str],
                      n_th: int) -> tuple[list[list[Any]], list[list[Any]]]:
    n_max = sur.n_max_rpm
    p = sur.sub_predictions(Z_t)
    p["nc"] = sur.nc_of(p)  # the n_c the combination uses (local model in its band)
    r = n_max / Q_t[:, 0]
    near = np.abs(r - 1) <= 0.05
    rows = [rel_row(name, "critical_rpm", "all", Q_t[:, 0], p["nc"], 1.0, "rpm"),
            rel_row(name, "critical_rpm", "|r-1|<=0.05", Q_t[near, 0], p["nc"][near], 1.0,
                     "rpm"),
            rel_row(name, "amp_res", "r>=1", Q_t[r >= 1, 1], p["ares"][r >= 1], 1e6, "um")]
    if "bg" in p:
        m = r <= 0.95
        rows.append(rel_row(name, "background_y", "r<=0.95", Q_t[m, 3], p["bg"][m], 1e6,
                             "um"))
    nc_rows = []
    pd = sur.nc_points(Z_d)
    for i, lab in enumerate(labels):
        sl = slice(i * n_th, (i + 1) * n_th)
        t, q = Q_d[sl, 0], pd[sl]
        sd = float(np.std(t, ddof=1))
        err = q - t
        nc_rows.append([name, lab, n_th, round(float(t.mean()), 1), round(sd, 2),
                        round(float(n_max / t.max()), 5), round(float(n_max / t.min()), 5),
                        round(float(np.max(np.abs(err))), 2), round(float(err.mean()), 2),
                        round(float(np.max(np.abs(err)) / sd), 4) if sd > 0 else ""])
    return rows, nc_rows


def metrics_row(variant: str, y: np.ndarray, yp: np.ndarray, lim: float) -> list[Any]:
    m = validation_metrics(y * 1e6, yp * 1e6)
    sub = y < lim
    ms = validation_metrics(y[sub] * 1e6, yp[sub] * 1e6) if sub.sum() >= 2 else None
    mlog = validation_metrics(np.log(y), np.log(np.maximum(yp, 1e-300)))
    return [variant, m.n, round(m.r2, 5), round(m.rmse, 4), round(m.nrmse, 5),
            round(m.max_abs_error, 3), round(mlog.r2, 5), int(sub.sum()),
            round(ms.r2, 5) if ms else "", round(ms.rmse, 4) if ms else "",
            round(ms.max_abs_error, 4) if ms else ""]


METRICS_HEADER = ["variant", "n_test", "r2", "rmse_um", "nrmse", "max_abs_error_um", "r2_log",
                  "n_subcritical", "r2_subcritical", "rmse_subcritical_um",
                  "max_abs_error_subcritical_um"]
LOO_HEADER = ["variant", "method", "n_train", "r2_fitted_space", "rmse_fitted_space",
              "r2_y", "rmse_y_um", "nrmse_y", "max_abs_error_y_um"]
MC_HEADER = ["variant", "design", "preload_N", "span_mm", "diameter_mm", "mean_fe_um",
             "mean_sur_um", "mean_rel_err", "ok_mean", "std_fe_um", "std_sur_um",
             "std_rel_err", "ok_std", "pf_fe", "pf_sur", "pf_abs_err", "pf_tol", "ok_pf"]
COST_HEADER = ["variant", "active_learning", "structure", "transform", "fe_calls_train",
               "n_train", "max_pf_abs_err", "mean_pf_abs_err", "n_pf_pass", "n_mean_pass",
               "n_std_pass", "n_designs"]


def loo_rows(name: str, loo: LOOSummary) -> list[list[Any]]:
    """``loo.csv`` rows of one variant: the model's LOO, then one per sub-model."""
    ml = validation_metrics(loo.y_true * 1e6, loo.y_loo * 1e6)
    rows = [[name, loo.method, loo.n_train, round(loo.r2_fitted, 5), round(loo.rmse_fitted, 5),
             round(ml.r2, 5), round(ml.rmse, 4), round(ml.nrmse, 5), round(ml.max_abs_error, 3)]]
    for k, lo in loo.sub.items():
        rows.append([name, f"closed_form:{k}", int(lo.y_true.size), round(lo.metrics.r2, 6),
                     float(f"{lo.metrics.rmse:.4e}"), "", "", "", ""])
    return rows


def mc_rows(name: str, labels: list[str], X: np.ndarray, cmp: MCComparison) -> list[list[Any]]:
    """``mc_comparison.csv`` rows of one variant: μ, σ, P_f of surrogate-MC vs FE-MC."""
    pf_err = np.abs(cmp.pf_sur - cmp.pf_true)
    rows = []
    for i, label in enumerate(labels):
        rows.append([
            name, label, *np.round(X[i], 2),
            round(cmp.mean_true[i] * 1e6, 4), round(cmp.mean_sur[i] * 1e6, 4),
            round(cmp.mean_rel_err[i], 4), bool(cmp.ok_mean[i]),
            round(cmp.std_true[i] * 1e6, 4), round(cmp.std_sur[i] * 1e6, 4),
            round(cmp.std_rel_err[i], 4), bool(cmp.ok_std[i]),
            round(cmp.pf_true[i], 4), round(cmp.pf_sur[i], 4), round(pf_err[i], 4),
            round(cmp.pf_tol[i], 4), bool(cmp.ok_pf[i])])
    return rows


def cost_row(name: str, active_learning: bool, structure: str, transform: str, fe_train: int,
             n_train: int, cmp: MCComparison) -> list[Any]:
    """``cost.csv`` row: training FE calls and the P_f accuracy of one variant."""
    pf_err = np.abs(cmp.pf_sur - cmp.pf_true)
    return [name, active_learning, structure, transform, fe_train, n_train,
            round(float(pf_err.max()), 4), round(float(pf_err.mean()), 4),
            int(cmp.ok_pf.sum()), int(cmp.ok_mean.sum()), int(cmp.ok_std.sum()), cmp.x.shape[0]]


def validation_tables(labels: list[str], truth: Any, assessments: Any, limit: float,
                      n_theta_nc: int) -> dict[str, tuple[list[str], list[list[Any]]]]:
    """The tables of a surrogate validation, file name → (header, rows): ``metrics.csv``,
    ``loo.csv``, ``mc_comparison.csv``, ``cost.csv`` (the training's FE evaluations, computed
    or loaded from the cache: the same on a rerun) and, with a resonance variant,
    ``resonance_submodels.csv`` and ``nc_at_designs.csv``."""
    out: dict[str, tuple[list[str], list[list[Any]]]] = {
        "metrics.csv": (METRICS_HEADER, []), "loo.csv": (LOO_HEADER, []),
        "mc_comparison.csv": (MC_HEADER, []), "cost.csv": (COST_HEADER, [])}
    for a in assessments:
        tr = a.trained
        fe = a.fe_calls + a.fe_cache_hits if a.fe_calls is not None else tr.fe_calls
        out["metrics.csv"][1].append(metrics_row(a.name, truth.y, a.y_pred, limit))
        out["loo.csv"][1].extend(loo_rows(a.name, a.loo))
        out["mc_comparison.csv"][1].extend(mc_rows(a.name, labels, truth.X, a.mc))
        out["cost.csv"][1].append(cost_row(
            a.name, getattr(tr.options, "active_learning", False), tr.structure,
            tr.model.info.get("transform", ""), fe, tr.model.n_train, a.mc))
        if tr.structure == "resonance":
            sub, nc = resonance_rows(a.name, tr.model, *truth.resonance, labels,
                                     min(n_theta_nc, truth.theta.shape[0]))
            out.setdefault("resonance_submodels.csv", (SUB_HEADER, []))[1].extend(sub)
            out.setdefault("nc_at_designs.csv", (NC_HEADER, []))[1].extend(nc)
    return out


def validation_calls(truth: Any, assessments: Any) -> dict[str, Any]:
    """Counted model calls of a surrogate validation (``calls.json``): FE calls computed and
    FE cache hits per stage and variant, surrogate calls per variant."""
    fe = {**truth.calls, **{f"train_{a.name}": a.fe_calls or 0 for a in assessments}}
    hits = {**truth.cache_hits, **{f"train_{a.name}": a.fe_cache_hits or 0
                                   for a in assessments}}
    sur = {a.name: a.surrogate_calls for a in assessments}
    return {"fe_calls": {**fe, "total": sum(fe.values())},
            "fe_cache_hits": {**hits, "total": sum(hits.values())},
            "surrogate_calls": {**sur, "total": sum(sur.values())},
            "note": "fe_calls: FE points computed in this run; fe_cache_hits: loaded from the "
                    "FE cache (both counted at the sampler); cost.csv's fe_calls_train is their "
                    "sum per variant"}


__all__ = ["COST_HEADER", "LOO_HEADER", "MC_HEADER", "METRICS_HEADER", "NC_HEADER",
           "SUB_HEADER", "cost_row", "loo_rows", "mc_rows", "metrics_row", "rel_row",
           "resonance_rows", "validation_calls", "validation_tables"]
