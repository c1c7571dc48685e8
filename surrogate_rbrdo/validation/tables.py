"""Tables of a validation campaign, as rows and as files (CSV + a JSON summary).

:func:`write_tables` writes into a folder (the runner only chooses the folder):

=========================  =================================================================
``table7.csv``             Table 7's analogue, one row per comparison, quantity and metric
``measured.csv``           μ, σ, P_f with intervals of every design and quantity
``model_vs_measured.csv``  the verdicts (Holm-adjusted), if a model was given
``replications.csv``       every replication's y (peak over the range, rated speed)
``critical_speeds.csv``    critical speeds from run-ups/run-downs, with the model's nearest
``curves.csv``             Fig. 8's data: measured mean and SD per speed (and the model's)
``phasors_<design>.csv``   all probes' 1x phasors, the rig campaign's ``phasors.csv`` format
                           (what the discrepancy workflow reads)
``validation.json``        options, designs, seeds, installation, timings, disagreements,
                           and the truth's draws per replication (provenance)
=========================  =================================================================
"""

from __future__ import annotations

import csv
import json
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.rig.campaign import PHASOR_COLUMNS
from surrogate_rbrdo.validation.campaign import DesignResult, ValidationResult
from surrogate_rbrdo.validation.replicas import LEVELS
from surrogate_rbrdo.validation.table7 import table7_rows

UM = 1e6


def _jsonable(v: Any) -> Any:
    if isinstance(v, Mapping):
        return {str(k): _jsonable(w) for k, w in v.items()}
    if isinstance(v, (list, tuple)):
        return [_jsonable(w) for w in v]
    if isinstance(v, np.ndarray):
        return _jsonable(v.tolist())
    if isinstance(v, (np.floating, float)):
        return None if not np.isfinite(v) else float(v)
    if isinstance(v, (np.integer, np.bool_)):
        return v.item()
    return v


def write_csv(path: Path, rows: Iterable[Mapping[str, Any]]) -> Path:
    """Rows of dicts (same keys) into a CSV file; nothing written for no rows."""
    rows = list(rows)
    with open(path, "w", newline="") as fh:
        if rows:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    return path


def table7_table(result: ValidationResult) -> list[dict[str, Any]]:
    return [r.to_dict() for c in result.comparisons for r in table7_rows(c)]


def measured_table(result: ValidationResult) -> list[dict[str, Any]]:
    rows = []
    for d in result.designs:
        for q, m in d.moments.items():
            rows.append({"design": d.name, "quantity": q, "n": m.n, "mean_um": m.mean * UM,
                         "mean_ci_low_um": m.mean_ci[0] * UM, "mean_ci_high_um": m.mean_ci[1] * UM,
                         "std_um": m.std * UM, "std_ci_low_um": m.std_ci[0] * UM,
                         "std_ci_high_um": m.std_ci[1] * UM, "pf": m.pf, "pf_ci_low": m.pf_ci[0],
                         "pf_ci_high": m.pf_ci[1], "n_fail": m.n_fail})
    return rows


def verdict_table(result: ValidationResult) -> list[dict[str, Any]]:
    rows = []
    for v in result.verdicts:
        s, unit = (1.0, "fraction") if v.metric == "pf" else (UM, "um")
        rows.append({"design": v.design, "quantity": v.quantity, "metric": v.metric,
                     "unit": unit, "measured": v.measured * s,
                     "measured_ci_low": v.measured_ci[0] * s,
                     "measured_ci_high": v.measured_ci[1] * s, "model": v.model * s,
                     "model_ci_low": v.model_ci[0] * s, "model_ci_high": v.model_ci[1] * s,
                     "difference": v.difference * s, "u_combined": v.u_combined * s,
                     "dof": v.dof, "test": v.test, "p_value": v.p_value, "p_holm": v.p_holm,
                     "verdict": "agree" if v.agree else "disagree"})
    return rows


def replication_table(result: ValidationResult) -> list[dict[str, Any]]:
    lim = result.options.delta_lim_m
    return [{"design": d.name, "replica": r, "peak_um": d.peak[r] * UM,
             "peak_speed_rpm": d.peak_speed_rpm[r], "rated_um": d.rated[r] * UM,
             "failed_peak": bool(d.peak[r] > lim), "failed_rated": bool(d.rated[r] > lim)}
            for d in result.designs for r in range(d.peak.size)]


def critical_table(result: ValidationResult) -> list[dict[str, Any]]:
    rows = []
    for d in result.designs:
        camp = result.model_campbell.get(d.name)
        model_cs = np.asarray([] if camp is None else camp.critical_speeds_rpm)
        for c in d.criticals:
            near = float(model_cs[np.argmin(np.abs(model_cs - c.speed_rpm))]) \
                if model_cs.size else float("nan")
            rows.append({"design": d.name, "replica": c.replica, "speed_rpm": c.speed_rpm,
                         "runup_rpm": c.runup_rpm, "rundown_rpm": c.rundown_rpm,
                         "both_ramps": c.both_ramps,
                         "amplification_factor": c.amplification_factor,
                         "model_rpm": near, "relative_difference": near / c.speed_rpm - 1.0})
    return rows


def curve_table(result: ValidationResult) -> list[dict[str, Any]]:
    rows = []
    m = result.model
    for d in result.designs:
        mu, sd = d.curve.mean(axis=0), d.curve.std(axis=0, ddof=1)
        bm = None if m is None else m.band_mean.get(d.name)
        bs = None if m is None else m.band_std.get(d.name)
        for i, s in enumerate(result.options.speeds_rpm):
            rows.append({"design": d.name, "speed_rpm": s, "measured_mean_um": mu[i] * UM,
                         "measured_std_um": sd[i] * UM,
                         "model_mean_um": np.nan if bm is None else bm[i] * UM,
                         "model_std_um": np.nan if bs is None else bs[i] * UM})
    return rows


def phasor_rows(result: ValidationResult, d: DesignResult) -> list[tuple[Any, ...]]:
    """``d``'s phasors in the rig campaign's ``phasors.csv`` columns (``build, tool, run`` =
    the replication index where that level is drawn anew, else 0; the measured speed is the
    nominal one; 7 significant digits, far below the 1x noise, 0.73 nm per part in 1 s)."""
    rep = result.options.replicate
    rows = []
    for r in range(d.phasors.shape[0]):
        b, t, u = (r if lvl in rep else 0 for lvl in LEVELS)
        for i, s in enumerate(result.options.speeds_rpm):
            for j, ch in enumerate(result.channels):
                X = d.phasors[r, i, j]
                rows.append((f"{d.name}_r{r:02d}_s{i:03d}", b, t, u, s, s, ch,
                             *(f"{v:.7g}" for v in (abs(X), np.degrees(np.angle(X)), X.real,
                                                    X.imag))))
    return rows


def summary(result: ValidationResult) -> dict[str, Any]:
    """JSON-able summary with the provenance of every number."""
    return _jsonable({
        "options": result.options.to_dict(), "baseline": result.baseline,
        "designs": {d.name: {"x": d.x, "n_records": d.n_records,
                             "probe_positions_mm": d.positions_mm,
                             "truth_draws": d.draws} for d in result.designs},
        "seed": result.seed, "installation": result.installation, "timings": result.timings,
        "model_calls": None if result.model is None else result.model.n_calls,
        "disagreements": [v.to_dict() for v in result.disagreements]})


def write_tables(result: ValidationResult, out_dir: str | Path) -> dict[str, Path]:
    """Write every table of ``result`` into ``out_dir`` (created); returns name → path."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {
        "table7": write_csv(out / "table7.csv", table7_table(result)),
        "measured": write_csv(out / "measured.csv", measured_table(result)),
        "replications": write_csv(out / "replications.csv", replication_table(result)),
        "critical_speeds": write_csv(out / "critical_speeds.csv", critical_table(result)),
        "curves": write_csv(out / "curves.csv", curve_table(result)),
    }
    if result.verdicts:
        paths["model_vs_measured"] = write_csv(out / "model_vs_measured.csv",
                                               verdict_table(result))
    for d in result.designs:
        p = out / f"phasors_{d.name}.csv"
        with open(p, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(PHASOR_COLUMNS)
            w.writerows(phasor_rows(result, d))
        paths[f"phasors_{d.name}"] = p
    paths["summary"] = out / "validation.json"
    paths["summary"].write_text(json.dumps(summary(result), indent=1))
    return paths
