"""Experiment kind ``surrogate_validation``: the peak-amplitude surrogate against the full FE model.

For each surrogate *variant* (the ``[surrogate]`` table, plus overrides in
``[validation.variants]``, e.g. ``raw = {transform = "none"}``, ``al = {active_learning =
true}``) the run trains a surrogate with :func:`~surrogate_rbrdo.runner.pipeline.
train_peak_surrogate` and writes

* ``metrics.csv``: R², RMSE, NRMSE, max error on ``n_test`` fresh LHS points of the joint box
  (all points and the subcritical ones, ``y < δ_lim``; also R² of ``log y``);
* ``loo.csv``: closed-form (Dubrule) leave-one-out metrics in the fitted (transformed) space and
  back-transformed to ``y``;
* ``mc_comparison.csv``: μ_y, σ_y and P_f from surrogate-MC vs full-FE MC at the validation
  designs with the same θ sample (``n_theta``), with pass/fail against the targets (μ, σ within
  ``rel_tol``; P_f within max(1 point, 3 SE));
* ``cost.csv``: FE calls of training, fit time and the P_f accuracy per variant (the
  active-learning comparison);
* ``parity_<variant>.png`` (µm) and ``parity_log_<variant>.png`` (log10 y);
* variants with ``structure = "substructure"`` (Kriging of the condensed rotor over the
  designs, exact bearing coupling) train on ``n_doe`` *designs*; their LOO row
  (``closed_form_condensed``) is the closed-form LOO of that Kriging at the training designs,
  coupled at nominal θ, against the exact coupling of their FE condensation;
* for variants with ``structure = "resonance"`` (the physics-structured surrogate):
  ``resonance_submodels.csv`` (each ingredient — ``n_c``, ``A_res``, background ``y`` — against
  the FE resonance quantities at the test points, relative errors; ``n_c`` also within
  ``|n_max/n_c - 1| <= 0.05``) and ``nc_at_designs.csv`` (the ``n_c`` model at the validation
  designs × the first ``n_theta_nc`` θ of the MC sample: error in rpm against the θ-spread of
  ``n_c``, which is what places the failure boundary). Their LOO rows are the combined model
  (``closed_form_combined``: each sub-model's closed-form LOO, combined) plus one row per
  sub-model in its own log space.

Every variant trains from a fresh copy of the same training seed, so variants with the same DOE
settings get the same DOE (before run ``struct2`` a shared ``SeedSequence`` was advanced by
each variant's ``spawn``: variants after the first drew other DOEs). Variants share the FE
cache (``<results root>/.cache``), so e.g. the log and raw variants cost the FE calls once.
Config tables: ``[spindle]``, ``[uncertainty]``
(``mean``, ``std``, optional ``corr``; default Table 4 pooled CoVs), ``[limit]``
(``delta_lim_um``), ``[surrogate]`` (:class:`~surrogate_rbrdo.runner.pipeline.SurrogateConfig`)
and ``[validation]`` (``n_test``, ``n_theta``, ``designs`` label → ``[F N, L mm, D mm]``,
``variants``, ``rel_tol``, ``n_theta_nc``).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.counting import CallCounter
from surrogate_rbrdo.core.protocols import Prediction
from surrogate_rbrdo.core.validate import check_int, check_keys, check_positive
from surrogate_rbrdo.doe import lhs
from surrogate_rbrdo.reporting.plots_surrogate import parity_plot
from surrogate_rbrdo.runner.config import (
    limit_from_config,
    spindle_from_config,
    uncertainty_from_config,
)
from surrogate_rbrdo.runner.experiments import EXPERIMENTS
from surrogate_rbrdo.runner.pipeline import (
    PeakSurrogate,
    SurrogateConfig,
    fe_cache,
    inverse,
    joint_bounds,
    sample_fe,
    sample_resonance,
    train_peak_surrogate,
)
from surrogate_rbrdo.runner.resonance_surrogate import ResonanceSurrogate
from surrogate_rbrdo.runner.runfolder import RunFolder
from surrogate_rbrdo.runner.substructure_surrogate import SubstructureSurrogate
from surrogate_rbrdo.spindle.evaluate import PeakAmplitudeResponse
from surrogate_rbrdo.surrogates.validation import compare_mc, loo_cv, validation_metrics

VALIDATION_KEYS = {"n_test", "n_theta", "designs", "variants", "rel_tol", "n_theta_nc"}

DEFAULT_DESIGNS = {
    "resonant": [2000.0, 650.0, 60.0],
    "subcritical_far": [2000.0, 330.0, 75.0],
    "boundary_a": [1000.0, 425.0, 60.0],
    "boundary_b": [3000.0, 480.0, 70.0],
    "boundary_c": [2000.0, 460.0, 65.0],
}


def _fe_mc_one(spindle: Any, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
    return PeakAmplitudeResponse(spindle)(x[None, :], theta)[0]


def fe_mc(spindle: Any, x: np.ndarray, theta: np.ndarray, *, n_jobs: int, cache_dir: Any,
          counter: CallCounter, progress: bool = False) -> np.ndarray:
    """Full-FE values ``(P, N)`` at designs × θ (vectorised over θ, designs in parallel, cached).

    Only computed designs (cache misses) are counted, ``N`` calls each.
    """
    import joblib

    func = _fe_mc_one
    mem = None
    if cache_dir is not None:
        mem = joblib.Memory(location=str(Path(cache_dir) / "fe_mc"), verbose=0)
        func = mem.cache(_fe_mc_one)
    todo = [i for i in range(x.shape[0])
            if mem is None or not func.check_call_in_cache(spindle, x[i], theta)]
    it = (joblib.delayed(func)(spindle, x[i], theta) for i in range(x.shape[0]))
    if progress:
        from tqdm import tqdm

        it = tqdm(it, total=x.shape[0], desc="full-FE MC", unit="design")
    out = joblib.Parallel(n_jobs=n_jobs, backend="loky")(it)
    counter.add(len(todo) * theta.shape[0])
    return np.vstack(out)


class _GridAdapter:
    """Gives ``compare_mc`` the surrogate's response (median for the log transform)."""

    def __init__(self, sur: PeakSurrogate) -> None:
        self.sur = sur

    def predict_grid(self, x: np.ndarray, theta: np.ndarray) -> Prediction:
        y = self.sur.response(x, theta)
        return Prediction(mean=y, std=np.full_like(y, np.nan))


def _rel_row(variant: str, quantity: str, subset: str, true: np.ndarray, pred: np.ndarray,
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


def _resonance_tables(name: str, sur: ResonanceSurrogate, Z_t: np.ndarray, Q_t: np.ndarray,
                      Z_d: np.ndarray, Q_d: np.ndarray, labels: list[str],
                      n_th: int) -> tuple[list[list[Any]], list[list[Any]]]:
    n_max = sur.n_max_rpm
    p = sur.sub_predictions(Z_t)
    p["nc"] = sur.nc_of(p)  # the n_c the combination uses (local model in its band)
    r = n_max / Q_t[:, 0]
    near = np.abs(r - 1) <= 0.05
    rows = [_rel_row(name, "critical_rpm", "all", Q_t[:, 0], p["nc"], 1.0, "rpm"),
            _rel_row(name, "critical_rpm", "|r-1|<=0.05", Q_t[near, 0], p["nc"][near], 1.0,
                     "rpm"),
            _rel_row(name, "amp_res", "r>=1", Q_t[r >= 1, 1], p["ares"][r >= 1], 1e6, "um")]
    if "bg" in p:
        m = r <= 0.95
        rows.append(_rel_row(name, "background_y", "r<=0.95", Q_t[m, 3], p["bg"][m], 1e6,
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


def _metrics_row(variant: str, y: np.ndarray, yp: np.ndarray, lim: float) -> list[Any]:
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
               "n_train", "fit_time_s", "train_time_s", "max_pf_abs_err", "mean_pf_abs_err",
               "n_pf_pass", "n_mean_pass", "n_std_pass", "n_designs"]


@EXPERIMENTS.register("surrogate_validation")
def run_surrogate_validation(config: Mapping[str, Any], run: RunFolder, *,
                             progress: bool = False) -> dict[str, Any]:
    top = {k for k in config if not k.startswith("_") and k != "experiment"}
    check_keys("surrogate_validation config (tables)", {k: None for k in top},
               {"spindle", "uncertainty", "limit", "surrogate", "validation"})
    val = dict(config.get("validation", {}))
    check_keys("[validation]", val, VALIDATION_KEYS)
    n_test = check_int("validation.n_test", val.get("n_test", 120), minimum=2)
    n_theta = check_int("validation.n_theta", val.get("n_theta", 1000), minimum=2)
    rel_tol = check_positive("validation.rel_tol", val.get("rel_tol", 0.05))
    n_theta_nc = check_int("validation.n_theta_nc", val.get("n_theta_nc", 40), minimum=2)
    spindle = spindle_from_config(config.get("spindle", {}), config.get("_base_dir", "."))
    inputs = uncertainty_from_config(config.get("uncertainty", {}), spindle.theta_bearings)
    limit = limit_from_config(config.get("limit", {}))
    base = SurrogateConfig.from_dict(dict(config.get("surrogate", {})))
    variants = {"main": base}
    raw_var = val.get("variants", {})
    if not isinstance(raw_var, Mapping):
        raise ValueError("validation.variants is not allowed: must be a table name = {overrides}")
    for name, over in raw_var.items():
        if name == "main" or not isinstance(over, Mapping):
            raise ValueError(f"validation.variants.{name} is not allowed: must be a table of "
                             "[surrogate] overrides named other than 'main'")
        try:
            variants[name] = SurrogateConfig.from_dict({**base.to_dict(), **over})
        except ValueError as exc:
            raise ValueError(f"validation.variants.{name}: {exc}") from None
    for name, v in variants.items():
        if v.structure == "fe":
            where = "surrogate" if name == "main" else f"validation.variants.{name}"
            raise ValueError(f"{where}.structure = 'fe' is not allowed here: a surrogate "
                             "validation needs a surrogate (use 'global', 'resonance' or "
                             "'substructure')")
    designs = {}
    for label, xv in dict(val.get("designs", DEFAULT_DESIGNS)).items():
        try:
            designs[label] = spindle.design_map.check(np.asarray(xv, dtype=float))
        except ValueError as exc:
            raise ValueError(f"validation.designs.{label}: {exc}") from None
    if len(designs) < 1:
        raise ValueError("validation.designs is not allowed: give at least one design")
    X_des = np.vstack(list(designs.values()))

    seed = int(config["experiment"].get("seed", 0))
    ss_train, ss_test, ss_theta = np.random.SeedSequence(seed).spawn(3)
    cache_dir = run.path.parent.parent / ".cache"
    points_cache = fe_cache(cache_dir)
    fe_test_counter, fe_mc_counter = CallCounter(), CallCounter()

    # ---- truth: fresh LHS test points and full-FE MC at the designs (same θ sample for all)
    with run.timed("fe_test_points"):
        Z_test = lhs(n_test, joint_bounds(spindle, inputs, base),
                     rng=np.random.default_rng(ss_test))
        Z_test, y_test = sample_fe(spindle, Z_test, base, cache=points_cache,
                                   counter=fe_test_counter, progress=progress)
    theta = inputs.sample(n_theta, rng=np.random.default_rng(ss_theta))
    with run.timed("fe_mc"):
        y_fe = fe_mc(spindle, X_des, theta, n_jobs=base.n_jobs, cache_dir=cache_dir,
                     counter=fe_mc_counter, progress=progress)

    metrics_rows, loo_rows, mc_rows, cost_rows, sur_calls = [], [], [], [], 0
    sub_rows: list[list[Any]] = []
    nc_rows: list[list[Any]] = []
    Q_test = None
    n_th = min(n_theta_nc, n_theta)
    info_all: dict[str, Any] = {}
    for name, cfg in variants.items():
        counter = CallCounter()
        with run.timed(f"train_{name}"):
            sur, info = train_peak_surrogate(spindle, inputs, limit, cfg,
                                             rng=np.random.default_rng(_copy(ss_train)),
                                             cache_dir=cache_dir, progress=progress,
                                             counter=counter)
        train_s = run.timings[f"train_{name}"]
        # FE calls of training counted as if uncached (the cache is shared between variants)
        fe_train = int(sur.n_train)
        info_all[name] = {k: v for k, v in info.items() if k != "config"}
        yp = sur.response_points(Z_test)
        sur_calls += yp.size
        metrics_rows.append(_metrics_row(name, y_test, yp, limit.threshold))
        with run.timed(f"loo_{name}"):
            if isinstance(sur, ResonanceSurrogate):
                sub_loo = sur.sub_loo()
                y_tr, y_lo = sur.loo_points(sub_loo)
                lm = validation_metrics(np.log(y_tr), np.log(y_lo))
                loo_method, loo_r2, loo_rmse = "closed_form_combined", lm.r2, lm.rmse
            elif isinstance(sur, SubstructureSurrogate):
                # LOO of the Kriging of S at the training designs, y at nominal θ
                y_tr, y_lo = sur.loo_points()
                lm = validation_metrics(np.log(y_tr), np.log(y_lo))
                loo_method, loo_r2, loo_rmse = "closed_form_condensed", lm.r2, lm.rmse
                sub_loo = {}
            else:
                loo = loo_cv(sur.model, method="closed_form")
                y_tr = inverse(loo.y_true, sur.transform)
                y_lo = inverse(loo.y_loo, sur.transform)
                loo_method, loo_r2, loo_rmse = loo.method, loo.metrics.r2, loo.metrics.rmse
                sub_loo = {}
        ml = validation_metrics(y_tr * 1e6, y_lo * 1e6)
        loo_rows.append([name, loo_method, sur.n_train, round(loo_r2, 5),
                         round(loo_rmse, 5), round(ml.r2, 5), round(ml.rmse, 4),
                         round(ml.nrmse, 5), round(ml.max_abs_error, 3)])
        for k, lo in sub_loo.items():
            loo_rows.append([name, f"closed_form:{k}", int(lo.y_true.size),
                             round(lo.metrics.r2, 6), float(f"{lo.metrics.rmse:.4e}"),
                             "", "", "", ""])
        if isinstance(sur, ResonanceSurrogate):
            if Q_test is None:
                with run.timed("fe_resonance_test_points"):
                    Z_t, Q_test = sample_resonance(spindle, Z_test, base,
                                                   cache=points_cache,
                                                   counter=fe_test_counter, progress=progress)
                    Z_d = np.column_stack([np.repeat(X_des, n_th, axis=0),
                                           np.tile(theta[:n_th], (X_des.shape[0], 1))])
                    Z_d, Q_d = sample_resonance(spindle, Z_d, base, cache=points_cache,
                                                counter=fe_test_counter, progress=progress)
                if Z_d.shape[0] != X_des.shape[0] * n_th:
                    raise ValueError("FE resonance quantities failed at a validation design")
            rs, ncs = _resonance_tables(name, sur, Z_t, Q_test, Z_d, Q_d, list(designs),
                                        n_th)
            sub_rows += rs
            nc_rows += ncs
        with run.timed(f"surrogate_mc_{name}"):
            cmp = compare_mc(_GridAdapter(sur), X_des, theta, limit, y_true=y_fe,
                             rel_tol=rel_tol)
        sur_calls += X_des.shape[0] * n_theta
        pf_err = np.abs(cmp.pf_sur - cmp.pf_true)
        for i, label in enumerate(designs):
            mc_rows.append([
                name, label, *np.round(X_des[i], 2),
                round(cmp.mean_true[i] * 1e6, 4), round(cmp.mean_sur[i] * 1e6, 4),
                round(cmp.mean_rel_err[i], 4), bool(cmp.ok_mean[i]),
                round(cmp.std_true[i] * 1e6, 4), round(cmp.std_sur[i] * 1e6, 4),
                round(cmp.std_rel_err[i], 4), bool(cmp.ok_std[i]),
                round(cmp.pf_true[i], 4), round(cmp.pf_sur[i], 4), round(pf_err[i], 4),
                round(cmp.pf_tol[i], 4), bool(cmp.ok_pf[i])])
        cost_rows.append([name, cfg.active_learning, cfg.structure,
                          info.get("transform", cfg.transform), fe_train, sur.n_train,
                          round(info["fit_time_s"], 2), round(train_s, 2),
                          round(float(pf_err.max()), 4), round(float(pf_err.mean()), 4),
                          int(cmp.ok_pf.sum()), int(cmp.ok_mean.sum()), int(cmp.ok_std.sum()),
                          len(designs)])
        with run.timed("plots"):
            parity_plot(y_test * 1e6, yp * 1e6, run.file(f"parity_{name}.png"),
                        title=f"{name}: {n_test} fresh LHS points", label="peak amplitude µm")
            parity_plot(np.log10(y_test), np.log10(yp), run.file(f"parity_log_{name}.png"),
                        title=f"{name}: {n_test} fresh LHS points", label="log10 y [m]")

    run.write_csv("metrics.csv", METRICS_HEADER, metrics_rows)
    run.write_csv("loo.csv", LOO_HEADER, loo_rows)
    run.write_csv("mc_comparison.csv", MC_HEADER, mc_rows)
    run.write_csv("cost.csv", COST_HEADER, cost_rows)
    if sub_rows:
        run.write_csv("resonance_submodels.csv", SUB_HEADER, sub_rows)
        run.write_csv("nc_at_designs.csv", NC_HEADER, nc_rows)
    run.write_json("surrogate_info.json", info_all)
    run.write_json("calls.json", {
        "fe_calls_test_points": fe_test_counter.calls, "fe_calls_mc": fe_mc_counter.calls,
        "fe_calls_train_computed": {n: i["fe_calls"] for n, i in info_all.items()},
        "surrogate_calls": sur_calls, "n_theta": n_theta, "n_test": int(y_test.size),
        "note": "computed = cache misses in this run; cost.csv gives the training size"})
    return {
        "variants": list(variants),
        "fe_calls": {"test": fe_test_counter.calls, "mc": fe_mc_counter.calls,
                     **{f"train_{n}": i["fe_calls"] for n, i in info_all.items()}},
        "surrogate_calls": sur_calls,
        "metrics": [dict(zip(METRICS_HEADER, r, strict=True)) for r in metrics_rows],
        "cost": [dict(zip(COST_HEADER, r, strict=True)) for r in cost_rows],
        "resonance_submodels": [dict(zip(SUB_HEADER, r, strict=True)) for r in sub_rows],
        "nc_at_designs": [dict(zip(NC_HEADER, r, strict=True)) for r in nc_rows],
        "summary": [{k: v for k, v in zip(MC_HEADER, r, strict=True)
                     if k in ("variant", "design", "mean_rel_err", "std_rel_err", "pf_fe",
                              "pf_sur", "ok_mean", "ok_std", "ok_pf")} for r in mc_rows],
    }


def _copy(ss: np.random.SeedSequence) -> np.random.SeedSequence:
    """A fresh copy of ``ss``: ``Generator.spawn`` advances the *shared* SeedSequence's child
    counter, so reusing one object would give every variant after the first another DOE."""
    return np.random.SeedSequence(ss.entropy, spawn_key=ss.spawn_key, pool_size=ss.pool_size)


__all__ = ["fe_mc", "run_surrogate_validation"]
