"""Tables and figures of an RBRDO study (:mod:`surrogate_rbrdo.study.stages` results).

The functions return rows (lists of dicts, μm and percent in the column names) or write into
``out``, any object with ``write_rows(name, rows)``, ``write_csv(name, header, rows)``,
``save_figure(name, fig)`` and ``write_json(name, data)`` (a run folder; no result table has
a timing column, so reruns with one seed give byte-identical tables).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from surrogate_rbrdo.optimization import (
    archive_front,
    front_table,
    mbr_table,
    strategy_table,
)
from surrogate_rbrdo.reporting.plots_optimization import (
    plot_convergence,
    plot_front_designs,
    plot_pareto_fronts,
)
from surrogate_rbrdo.reporting.spindle import spindle_overview, write_overview
from surrogate_rbrdo.study.plan import StudyPlan, final_models
from surrogate_rbrdo.study.problem import DESIGN_NAMES
from surrogate_rbrdo.study.stages import (
    Optimisation,
    Refinement,
    Verification,
    merge_calls,
    run_label,
)


def front_rows(opt: Optimisation) -> list[dict[str, Any]]:
    """``pareto_fronts.csv``: the feasible archive front of every RBRDO and RDO run."""
    rows = []
    for (name, pt), lab, r in zip(opt.runs, opt.labels, opt.results, strict=True):
        if name in ("rbrdo", "rdo"):
            for row in front_table(r, design_names=DESIGN_NAMES):
                rows.append({"run": lab, "p_target_pct": pt * 100, **row})
    return rows


def critical_columns(crit_rpm: np.ndarray, speed_range_rpm: tuple[float, float]
                     ) -> dict[str, Any]:
    """The FE Campbell check of one design: its first damped critical speed (rpm, NaN if none
    up to 1.5 × the top speed), how many lie inside the operating range, and the first one's
    margin above the top speed (``n_1/n_max − 1``).

    >>> critical_columns(np.array([21780.0]), (1000.0, 24000.0))["criticals_in_range_fe"]
    1
    """
    lo, hi = speed_range_rpm
    first = float(crit_rpm[0]) if crit_rpm.size else float("nan")
    return {"first_critical_rpm_fe": first,
            "criticals_in_range_fe": int(np.sum((crit_rpm >= lo) & (crit_rpm <= hi))),
            "first_critical_margin_fe": first / hi - 1.0}


def verification_rows(ver: Verification, speed_range_rpm: tuple[float, float] = (0.0, np.inf)
                      ) -> list[dict[str, Any]]:
    """``verification.csv``: every chosen design on the CRN sample, the surrogate and the FE
    model on the fresh sample, the FE P_f interval, the deterministic constraints and the FE
    Campbell check (critical speeds against ``speed_range_rpm``)."""
    crn, fe = ver.crn, ver.fe
    nan = np.full(len(ver.names), np.nan)
    sv = ver.surrogate
    s_mean, s_std, s_pf = (nan, nan, nan) if sv is None else (sv.mean, sv.std, sv.pf)
    rows = []
    for i, k in enumerate(ver.names):
        row = {"design": k,
               **{n: float(v) for n, v in zip(DESIGN_NAMES, ver.X[i], strict=True)},
               "mean_um_surrogate_crn": crn.mean[i] * 1e6,
               "std_um_surrogate_crn": crn.std[i] * 1e6,
               "pf_pct_surrogate_crn": crn.pf[i] * 100,
               "mean_um_surrogate": s_mean[i] * 1e6, "std_um_surrogate": s_std[i] * 1e6,
               "pf_pct_surrogate": s_pf[i] * 100,
               "mean_um_fe": fe.mean[i] * 1e6, "std_um_fe": fe.std[i] * 1e6,
               "pf_pct_fe": fe.pf[i] * 100,
               "pf_ci_low_pct_fe": float(np.asarray(fe.pf_ci)[i, 0] * 100),
               "pf_ci_high_pct_fe": float(np.asarray(fe.pf_ci)[i, 1] * 100),
               "max_abs_err_um": float(ver.max_abs_err[i] * 1e6),
               "n_theta_fe": ver.n_theta}
        if ver.pf_is is not None:
            row["pf_pct_fe_is"] = float(ver.pf_is[i] * 100)
        if ver.critical_rpm:
            row.update(critical_columns(ver.critical_rpm[i], speed_range_rpm))
        row.update({f"g_{n}": float(v) for n, v in zip(ver.det_names, ver.G_det[i],
                                                          strict=True)})
        rows.append(row)
    return rows


def strategy_rows(opt: Optimisation, ver: Verification) -> list[dict[str, Any]]:
    """``strategy_comparison.csv`` (the paper's Fig. 6): μ, σ, P_f of every chosen design on
    the CRN sample, with the FE columns."""
    entries = {}
    for i, k in enumerate(ver.names):
        pt = None
        for (n, p), lab in zip(opt.runs, opt.labels, strict=True):
            if lab == k and n in ("rbrdo", "rbdo"):
                pt = p
        entries[k] = {"x": ver.X[i], "mean": ver.crn.mean[i], "std": ver.crn.std[i],
                      "pf": ver.crn.pf[i], "p_target": pt}
    rows = strategy_table(entries, design_names=DESIGN_NAMES)
    for i, r in enumerate(rows):
        r.update({"mean_um_fe": ver.fe.mean[i] * 1e6, "std_um_fe": ver.fe.std[i] * 1e6,
                  "pf_pct_fe": ver.fe.pf[i] * 100})
    return rows


def mbr_rows(opt: Optimisation, ver: Verification, weights: tuple[float, ...],
             in_loop: str = "surrogate") -> list[dict[str, Any]]:
    """``mbr.csv``: marginal benefit ratios between the P_target levels, from the compromises
    of the model in the loop on the CRN sample (``<in_loop>_crn``: ``surrogate_crn`` or
    ``fe_crn``), their FE verification and the ends of each feasible front.

    An MBR measures what relaxing P_target buys only where the reliability constraint acts.
    Every row says whether it does: ``active_from`` / ``active_to`` count the designs of each
    level's feasible archive front whose CRN P_f exceeds 0.9 P_target, and ``constraint``
    is ``"active"`` when either count is positive, else ``"inactive at both levels"`` — the
    Δμ and Δσ of such a row are the optimiser's and the sample's noise, not a benefit (a
    seed sweep gives their spread: ``benchmarks/study_seed_stability.py``)."""
    comp = opt.compromises(weights)
    rb = [(pt, lab) for (n, pt), lab in zip(opt.runs, opt.labels, strict=True) if n == "rbrdo"]
    res = opt.by_label()
    active = {round(pt * 100, 9): int(np.sum(res[lab].archive.pf[archive_front(res[lab])]
                                             > 0.9 * pt)) for pt, lab in rb}
    levels_s = [(pt, comp[lab].mean, comp[lab].std) for pt, lab in rb if comp[lab] is not None]
    rows: list[dict[str, Any]] = []
    if len(levels_s) >= 2:
        rows += [{"source": f"{in_loop}_crn", **r} for r in mbr_table(levels_s)]
        idx = {k: i for i, k in enumerate(ver.names)}
        levels_f = [(pt, ver.fe.mean[idx[lab]], ver.fe.std[idx[lab]]) for pt, lab in rb
                    if lab in idx]
        rows += [{"source": "fe_verification", **r} for r in mbr_table(levels_f)]
    # the ends of each feasible front (least μ, least σ: from different designs) do not jump
    # between branches as a compromise can, and under CRN they can only worsen as P_target
    # tightens (the feasible set shrinks; an optimiser's fronts only approximately so)
    levels_e = []
    for pt, lab in rb:
        F = res[lab].archive.F[archive_front(res[lab])]
        if len(F):
            levels_e.append((pt, F[:, 0].min(), F[:, 1].min()))
    if len(levels_e) >= 2:
        rows += [{"source": "front_ends_crn", **r} for r in mbr_table(levels_e)]
    for r in rows:
        a0, a1 = active[round(r["from_pct"], 9)], active[round(r["to_pct"], 9)]
        r.update(active_from=a0, active_to=a1,
                 constraint="active" if a0 or a1 else "inactive at both levels")
    return rows


def compromise_rows(opt: Optimisation, weights: tuple[float, ...]) -> list[dict[str, Any]]:
    """``compromises.csv``: the ASF compromise of every run, its front size and call counts
    (no timings: they go to ``meta.json``)."""
    comp = opt.compromises(weights)
    rows: list[dict[str, Any]] = []
    for (n, pt), lab, r in zip(opt.runs, opt.labels, opt.results, strict=True):
        c = comp[lab]
        if c is None:
            rows.append({"run": lab, "feasible": False})
            continue
        front = archive_front(r)
        rows.append({"run": lab, "formulation": n, "p_target_pct": pt * 100,
                     **{k: float(v) for k, v in zip(DESIGN_NAMES, c.x, strict=True)},
                     "mean_um": c.mean * 1e6, "std_um": c.std * 1e6, "pf_pct": c.pf * 100,
                     "reliability_g": float(c.G[0]) if n in ("rbrdo", "rbdo") else "",
                     "front_size": int(front.size),
                     "front_active_1pct": int(np.sum(r.archive.pf[front] > 0.9 * pt))
                     if n == "rbrdo" else "",
                     "surrogate_calls": r.n_surrogate_calls,
                     "design_model_calls": r.n_model_calls})
    return rows


def refine_rows(rounds: tuple[Mapping[str, Any], ...]) -> list[dict[str, Any]]:
    """``refine.csv``: the scalar statistics of every refinement round."""
    return [{k: v for k, v in r.items() if not isinstance(v, list)} for r in rounds]


def front_figures(out: Any, opt: Optimisation, weights: tuple[float, ...], *,
                  quantity: str, model_in_loop: str, baseline: np.ndarray) -> None:
    """``pareto_fronts.png`` (RBRDO), ``pareto_fronts_with_rdo.png``, ``front_designs.png``
    and ``convergence.png``."""
    comp = opt.compromises(weights)
    res = opt.by_label()
    fronts = {lab: res[lab].archive.F[archive_front(res[lab])]
              for (n, _), lab in zip(opt.runs, opt.labels, strict=True) if n in ("rbrdo", "rdo")}
    rb = [lab for (n, _), lab in zip(opt.runs, opt.labels, strict=True) if n == "rbrdo"]
    fig = plot_pareto_fronts(
        {lab: fronts[lab] for lab in rb}, quantity=quantity,
        compromises={lab: (comp[lab].mean, comp[lab].std) for lab in rb if comp[lab]},
        clouds={lab: res[lab].archive.F[res[lab].archive.feasible] for lab in rb})
    fig.axes[0].set_title(f"RBRDO: feasible Pareto fronts per P_target\n({quantity}; "
                          f"{'full FE model' if model_in_loop == 'fe' else 'surrogate'}, one "
                          "CRN θ sample)", fontsize=10)
    out.save_figure("pareto_fronts.png", fig)
    fig = plot_pareto_fronts(fronts, quantity=quantity,
                             compromises={k: (comp[k].mean, comp[k].std)
                                          for k in fronts if comp[k]})
    fig.axes[0].set_title(f"RBRDO and RDO: feasible Pareto fronts\n({quantity}, one CRN θ "
                          "sample)", fontsize=10)
    out.save_figure("pareto_fronts_with_rdo.png", fig)
    fig = plot_front_designs({lab: res[lab].archive.X[archive_front(res[lab])] for lab in rb},
                             baseline=baseline)
    out.save_figure("front_designs.png", fig)
    fig = plot_convergence({lab: list(r.history) for lab, r in res.items()},
                           name="μ_y", note="deterministic run: nominal y")
    out.save_figure("convergence.png", fig)


def spindle_figures(out: Any, spindle: Any, designs: Mapping[str, np.ndarray], *,
                    n_speeds: int, campbell_speeds: int, n_modes: int,
                    limit_um: float | None = None) -> None:
    """``critical_speeds.csv``, ``unbalance_response.csv``, ``campbell.png`` and
    ``unbalance_response.png`` of ``designs`` (nominal θ)."""
    ov = spindle_overview(spindle, designs, n_speeds=n_speeds, campbell_speeds=campbell_speeds,
                          n_modes=n_modes)
    write_overview(out, ov, n_modes=n_modes, speed_max_rpm=spindle.geometry.speed_max_rpm,
                   limit_um=limit_um, critical_csv=True)


def spotlight(opt: Optimisation, ver: Verification) -> dict[str, np.ndarray]:
    """The baseline and the RBRDO 5 % compromise (else the first RBRDO one) for the spindle
    figures."""
    chosen = dict(zip(ver.names, ver.X, strict=True))
    rb = [lab for (n, _), lab in zip(opt.runs, opt.labels, strict=True)
          if n == "rbrdo" and lab in chosen]
    pick = run_label("rbrdo", 0.05) if run_label("rbrdo", 0.05) in chosen else \
        (rb[0] if rb else None)
    out = {"baseline": chosen["baseline"]}
    if pick is not None:
        out[f"{pick} compromise"] = chosen[pick]
    return out


def study_meta(problem: Any, options: Any, trained: Any, design_model: Any, opt: Optimisation,
               ref: Refinement, ver: Verification) -> dict[str, Any]:
    """For ``meta.json``: the model calls per stage and model (all counted where the model
    was called), the FE values each stage loaded from the FE cache (``fe_cache_hits``), the
    optimiser's seeds and run times, the refinement rounds."""
    final_sur, final_opt = ref.surrogate or trained, ref.optimisation or opt
    stages = {"optimization": merge_calls(opt.calls, {k: v for k, v in ref.calls.items()
                                                      if k not in ("fe", "fe_cached")}),
              "refine": {"fe": ref.calls.get("fe", 0)}, "verification": ver.calls}
    fe = {"doe": trained.fe_calls,
          "design_model": 0 if design_model is None else design_model.validation["n_fe_calls"],
          **{k: int(c.get("fe", 0)) for k, c in stages.items()}}
    # FE values loaded from the FE cache instead of computed, per stage (counted by the
    # samplers; the design model's FE designs are not cached)
    hits = {"doe": trained.fe_cache_hits, "refine": int(ref.calls.get("fe_cached", 0)),
            "verification": int(ver.calls.get("fe_cached", 0))}
    sc = {k: int(c.get("surrogate", 0)) for k, c in stages.items() if k != "refine"}
    dm = {k: int(c.get("design_model", 0)) for k, c in stages.items() if k != "refine"}
    runs = final_opt.by_label()
    return {"model_in_loop": trained.in_loop, "response": problem.response.label,
            "design_box": problem.design_bounds.tolist(),
            "theta_names": list(problem.theta_names),
            "design_constraints": [c.name for c in problem.constraints],
            "fe_calls": {**fe, "total": sum(fe.values())},
            "fe_cache_hits": {**hits, "total": sum(hits.values())},
            "surrogate_calls": {**sc, "total": sum(sc.values())},
            "design_model_calls": {**dm, "total": sum(dm.values())},
            "optimizer": options.optimizer,
            "optimizer_seeds": {lab: r.optimizer.get("seed") for lab, r in runs.items()},
            "optimizer_wall_time_s": {lab: r.wall_time_s for lab, r in runs.items()},
            "refine": [dict(r) for r in ref.rounds],
            "surrogate": final_sur.options.to_dict() if hasattr(final_sur.options, "to_dict")
            else {}}


#: the verification columns printed in the terminal summary
SUMMARY_COLUMNS = ("design", "preload_N", "span_mm", "diameter_mm", "mean_um_fe", "std_um_fe",
                   "pf_pct_fe", "mean_um_surrogate", "std_um_surrogate", "pf_pct_surrogate")


def write_study_report(out: Any, p: StudyPlan, results: Mapping[str, Any]) -> dict[str, Any]:
    """Every table, figure and JSON file of a study into ``out`` (the module docstring), from
    the stage results by name (``surrogate``, ``design_model``, ``optimise``, ``refine``,
    ``verify``); returns the summary (``summary`` rows, ``mbr``, ``compromises``, ``meta``)."""
    sur, opt = final_models(results)
    ver, w = results["verify"], p.optimization.weights
    out.write_json("surrogate_info.json", {**sur.to_dict(), **dict(sur.model.info)})
    if results["design_model"] is not None:
        out.write_json("design_model_validation.json", results["design_model"].validation)
    if results["refine"].rounds:
        out.write_rows("refine.csv", refine_rows(results["refine"].rounds))
    fronts = front_rows(opt)
    if fronts:
        out.write_rows("pareto_fronts.csv", fronts)
    front_figures(out, opt, w, quantity=p.problem.response.label, model_in_loop=sur.in_loop,
                  baseline=p.problem.baseline)
    g = p.problem.spindle.geometry
    ver_rows = verification_rows(ver, (g.speed_min_rpm, g.speed_max_rpm))
    out.write_rows("verification.csv", ver_rows)
    if ver.fronts is not None:
        out.write_rows("front_verification.csv", ver.fronts.rows(DESIGN_NAMES))
    out.write_rows("strategy_comparison.csv", strategy_rows(opt, ver))
    mbr = mbr_rows(opt, ver, w, sur.in_loop)
    if mbr:
        out.write_rows("mbr.csv", mbr)
    comp = compromise_rows(opt, w)
    out.write_rows("compromises.csv", comp)
    rep = p.report
    spindle_figures(out, p.problem.spindle, spotlight(opt, ver), n_speeds=rep.n_speeds,
                    campbell_speeds=rep.campbell_speeds, n_modes=rep.n_modes,
                    limit_um=p.problem.limit.threshold * 1e6)
    meta = study_meta(p.problem, p.optimization, *(results[k] for k in (
        "surrogate", "design_model", "optimise", "refine", "verify")))
    if p.theta_source is not None:       # [uncertainty] from: the identified model's origin
        meta["uncertainty_from"] = p.theta_source
    out.write_json("study_meta.json", meta)
    summary = [{k: (round(v, 4) if isinstance(v, float) else v) for k, v in r.items()
                if k in SUMMARY_COLUMNS} for r in ver_rows]
    return {"summary": summary, "mbr": mbr, "compromises": comp, "meta": meta}


__all__ = ["compromise_rows", "critical_columns", "front_figures", "front_rows", "mbr_rows",
           "refine_rows", "spindle_figures", "spotlight", "strategy_rows", "study_meta",
           "write_study_report",
           "verification_rows"]
