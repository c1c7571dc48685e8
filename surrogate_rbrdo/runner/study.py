"""Experiment kind ``study``: the paper's RBRDO study end to end.

DOE → Kriging of the tool-tip amplitude ``y`` over (x, θ) (``runner.pipeline``; ``y`` is the
peak over the speed range or, with ``[response]``, the amplitude at one speed; or no
surrogate: ``structure = "fe"``) → g_det design
model (``runner.design_model``) → RBRDO at every P_target → RDO, RBDO, deterministic → ASF
compromises, MBR → verification of every chosen design with the full FE model → tables,
figures, ``meta.json``. All formulations share one θ sample (common random numbers).

Config tables (every key optional unless stated; unknown keys raise):

``[spindle]``       see :func:`~surrogate_rbrdo.runner.config.spindle_from_config`
``[uncertainty]``   ``mean``, ``std`` (θ = bearing stiffness factors), optional ``corr``
``[limit]``         ``delta_lim_um`` (19.5)
``[response]``      ``kind`` ("peak": the peak over the speed range, default; "at_speed": the
                    amplitude at ``speed_rpm``): ``spindle.evaluate.ResponseSpec``
``[surrogate]``     the pipeline's ``SurrogateConfig`` schema (``n_doe``, ``surrogate``, …);
                    ``structure = "fe"``: the full FE model in the loop (ground truth)
``[design_model]``  ``n_train``, ``n_validate``, ``n_jobs`` (:class:`DesignModelOptions`)
``[deterministic]`` ``stress``, ``yield_strength_pa``, ``resonance`` ("paper"|"separation"|
                    "none"), ``factor``, ``omega_max_rpm``, ``operating_speeds_rpm``, ``margin``
``[optimization]``  ``p_targets``, ``strategies``, ``strategy_p_target``, ``weights``,
                    ``n_theta``, ``estimator``, ``pop_size``, ``n_gen``, ``n_jobs``
``[verification]``  ``n_theta``, ``pf_method`` ("mc"|"is"), ``is_samples``, ``n_jobs``,
                    ``chunk``
``[report]``        ``baseline`` ([F N, L mm, D mm]), ``n_speeds``, ``campbell_speeds``,
                    ``n_modes``
``[refine]``        ``rounds`` (0: off), ``designs``, ``theta``, ``tol``, ``hyper``: FE
                    infill at the optimiser's designs, refit, optimise again
                    (:class:`~surrogate_rbrdo.runner.refine.RefineOptions`)
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, fields
from functools import partial
from typing import Any

import numpy as np

from surrogate_rbrdo.core import LimitState
from surrogate_rbrdo.core.validate import (
    check_choice,
    check_int,
    check_keys,
    check_positive,
    check_range,
)
from surrogate_rbrdo.runner.config import (
    limit_from_config,
    response_from_config,
    spindle_from_config,
    uncertainty_from_config,
)
from surrogate_rbrdo.runner.design_model import DesignModelOptions, fit_design_model
from surrogate_rbrdo.runner.experiments import EXPERIMENTS
from surrogate_rbrdo.runner.refine import RefineOptions, refine_surrogate, select_designs
from surrogate_rbrdo.runner.runfolder import RunFolder
from surrogate_rbrdo.spindle.evaluate import ResponseSpec

RPM = 2.0 * np.pi / 60.0
DESIGN_NAMES = ("preload_N", "span_mm", "diameter_mm")
TABLES = {"spindle", "uncertainty", "limit", "surrogate", "design_model", "deterministic",
          "optimization", "verification", "report", "refine", "response"}
DET_KEYS = {"stress", "yield_strength_pa", "resonance", "factor", "omega_max_rpm",
            "operating_speeds_rpm", "margin"}


@dataclass(frozen=True)
class OptimizationConfig:
    """``[optimization]``: the RBRDO levels, the comparison strategies and NSGA-II budget."""

    p_targets: tuple[float, ...] = (0.10, 0.05, 0.01)
    strategies: tuple[str, ...] = ("rdo", "rbdo", "deterministic")
    strategy_p_target: float = 0.05
    weights: tuple[float, ...] = (0.5, 0.5)
    n_theta: int = 1000
    estimator: str = "mc"
    pop_size: int = 100
    n_gen: int = 200
    n_jobs: int = 2
    eliminate_duplicates: bool = True

    def __post_init__(self) -> None:
        from surrogate_rbrdo.estimators import ESTIMATORS
        from surrogate_rbrdo.formulations import FORMULATIONS

        object.__setattr__(self, "p_targets", tuple(self.p_targets))
        object.__setattr__(self, "strategies", tuple(self.strategies))
        object.__setattr__(self, "weights", tuple(self.weights))
        if not self.p_targets:
            raise ValueError("optimization.p_targets = [] is not allowed: give at least one")
        for i, p in enumerate(self.p_targets):
            check_range(f"optimization.p_targets[{i}]", p, 0.0, 1.0, inclusive=False)
        if len(set(self.p_targets)) != len(self.p_targets):
            raise ValueError(f"optimization.p_targets = {list(self.p_targets)} is not allowed: "
                             "contains duplicates")
        check_range("optimization.strategy_p_target", self.strategy_p_target, 0.0, 1.0,
                    inclusive=False)
        for i, s in enumerate(self.strategies):
            check_choice(f"optimization.strategies[{i}]", s, sorted(FORMULATIONS))
        if len(self.weights) != 2:
            raise ValueError(f"optimization.weights = {list(self.weights)} is not allowed: "
                             "need two weights (μ, σ)")
        for i, w in enumerate(self.weights):
            check_positive(f"optimization.weights[{i}]", w)
        check_choice("optimization.estimator", self.estimator, sorted(ESTIMATORS))
        check_int("optimization.n_theta", self.n_theta, minimum=2)
        check_int("optimization.pop_size", self.pop_size, minimum=2)
        check_int("optimization.n_gen", self.n_gen, minimum=1)
        check_int("optimization.n_jobs", self.n_jobs, minimum=1)


@dataclass(frozen=True)
class VerificationConfig:
    """``[verification]``: full-FE check of every chosen design."""

    n_theta: int = 10_000
    pf_method: str = "mc"
    is_samples: int = 2000
    n_jobs: int = 2
    chunk: int = 250

    def __post_init__(self) -> None:
        check_int("verification.n_theta", self.n_theta, minimum=2)
        check_choice("verification.pf_method", self.pf_method, ("mc", "is"))
        check_int("verification.is_samples", self.is_samples, minimum=10)
        check_int("verification.n_jobs", self.n_jobs, minimum=1)
        check_int("verification.chunk", self.chunk, minimum=1)


@dataclass(frozen=True)
class ReportConfig:
    """``[report]``: baseline design and the spindle figures."""

    baseline: tuple[float, ...] | None = None
    n_speeds: int = 300
    campbell_speeds: int = 25
    n_modes: int = 6

    def __post_init__(self) -> None:
        check_int("report.n_speeds", self.n_speeds, minimum=2)
        check_int("report.campbell_speeds", self.campbell_speeds, minimum=2)
        check_int("report.n_modes", self.n_modes, minimum=1)


def _dataclass_from(cls, where: str, table: Mapping[str, Any]):
    allowed = {f.name for f in fields(cls)}
    check_keys(where, table, allowed)
    kw = {k: (tuple(v) if isinstance(v, list) else v) for k, v in table.items()}
    return cls(**kw)


# ----------------------------------------------------------------------------- config
@dataclass(frozen=True, eq=False)
class StudyConfig:
    """Every part of a study config, validated before any work starts."""

    spindle: Any
    inputs: Any
    limit: LimitState
    surrogate: Any
    design_model: DesignModelOptions
    deterministic: Any
    optimization: OptimizationConfig
    verification: VerificationConfig
    report: ReportConfig
    baseline: np.ndarray
    seed: int
    refine: RefineOptions = RefineOptions()
    response: ResponseSpec = ResponseSpec()


def parse_study_config(config: Mapping[str, Any]) -> StudyConfig:
    """Validate a ``study`` config (a dict from :func:`load_config`); raises ``ValueError``
    naming the field and value before any expensive work."""
    from surrogate_rbrdo.formulations import DeterministicOptions
    from surrogate_rbrdo.runner.pipeline import SurrogateConfig, check_structure_response

    top = {k for k in config if not k.startswith("_") and k != "experiment"}
    check_keys("study config (tables)", {k: None for k in top}, TABLES)
    seed = int(config.get("experiment", {}).get("seed", 0))
    spindle = spindle_from_config(config.get("spindle", {}), config.get("_base_dir", "."))

    inputs = uncertainty_from_config(config.get("uncertainty", {}), spindle.theta_bearings)

    limit = limit_from_config(config.get("limit", {}))

    surrogate = SurrogateConfig.from_dict(dict(config.get("surrogate", {})))
    response = response_from_config(config.get("response", {}))
    g = spindle.geometry
    if response.kind == "at_speed" and not g.speed_min_rpm <= response.speed_rpm \
            <= g.speed_max_rpm:
        raise ValueError(f"response.speed_rpm = {response.speed_rpm} is not allowed: must lie "
                         f"in the spindle's speed range [{g.speed_min_rpm}, "
                         f"{g.speed_max_rpm}] rpm (the bearing laws are fitted there)")
    check_structure_response(surrogate, response)
    dmo = _dataclass_from(DesignModelOptions, "[design_model]", config.get("design_model", {}))

    det = dict(config.get("deterministic", {}))
    check_keys("[deterministic]", det, DET_KEYS)
    kw: dict[str, Any] = {}
    for k in ("stress", "yield_strength_pa", "resonance", "factor", "margin"):
        if k in det:
            kw[k] = det[k]
    if "omega_max_rpm" in det:
        kw["omega_max"] = check_positive("deterministic.omega_max_rpm",
                                         det["omega_max_rpm"]) * RPM
    else:
        kw["omega_max"] = spindle.geometry.speed_max_rpm * RPM
    if "operating_speeds_rpm" in det:
        kw["operating_speeds"] = tuple(float(s) * RPM for s in det["operating_speeds_rpm"])
    try:
        det_opts = DeterministicOptions(**kw)
    except ValueError as exc:
        raise ValueError(f"deterministic.{exc}") from None
    if det_opts.resonance == "separation":
        raise ValueError("deterministic.resonance = 'separation' is not allowed in a study: the "
                         "g_det design model has no critical-speed surrogate; use 'paper' or "
                         "'none'")

    opt = _dataclass_from(OptimizationConfig, "[optimization]", config.get("optimization", {}))
    ver = _dataclass_from(VerificationConfig, "[verification]", config.get("verification", {}))
    rep = _dataclass_from(ReportConfig, "[report]", config.get("report", {}))
    ref = _dataclass_from(RefineOptions, "[refine]", config.get("refine", {}))
    if ref.rounds and surrogate.structure in ("fe", "substructure"):
        why = ("there is no surrogate to refine" if surrogate.structure == "fe" else
               "the refinement loop adds (x, θ) points, and this surrogate is trained on "
               "designs only")
        raise ValueError(f"refine.rounds = {ref.rounds} is not allowed with surrogate.structure "
                         f"= {surrogate.structure!r}: {why} (use rounds = 0)")
    try:
        base = spindle.design_map.check(np.asarray(
            rep.baseline if rep.baseline is not None else spindle.baseline, dtype=float))
    except ValueError as exc:
        raise ValueError(f"report.baseline: {exc}") from None
    return StudyConfig(spindle=spindle, inputs=inputs, limit=limit, surrogate=surrogate,
                       design_model=dmo, deterministic=det_opts, optimization=opt,
                       verification=ver, report=rep, baseline=base, seed=seed, refine=ref,
                       response=response)


# ----------------------------------------------------------------------------- verification
def _fe_chunk(spindle, x: np.ndarray, theta: np.ndarray, response=None) -> np.ndarray:
    from surrogate_rbrdo.spindle.evaluate import ResponseSpec

    response = ResponseSpec() if response is None else response
    return response.fe_response(spindle)(x[None, :], theta)[0]


def fe_values(spindle, X: np.ndarray, theta: np.ndarray, *, n_jobs: int, chunk: int,
              progress: bool, response=None) -> np.ndarray:
    """Full-FE ``y`` (default the peak amplitude; else the ``ResponseSpec`` ``response``) of
    designs ``X`` (P, 3) on ``theta`` (N, m): (P, N) metres."""
    jobs = [(i, s) for i in range(X.shape[0]) for s in range(0, theta.shape[0], chunk)]
    out = np.empty((X.shape[0], theta.shape[0]))
    if n_jobs == 1:
        it = jobs
        if progress:
            from tqdm.auto import tqdm

            it = tqdm(jobs, desc="FE verification", unit="chunk", leave=False)
        for i, s in it:
            out[i, s:s + chunk] = _fe_chunk(spindle, X[i], theta[s:s + chunk], response)
        return out
    from joblib import Parallel, delayed

    par = Parallel(n_jobs=n_jobs, backend="loky", return_as="generator")
    gen = par(delayed(_fe_chunk)(spindle, X[i], theta[s:s + chunk], response)
              for i, s in jobs)
    if progress:
        from tqdm.auto import tqdm

        gen = tqdm(gen, total=len(jobs), desc="FE verification", unit="chunk", leave=False)
    for (i, s), vals in zip(jobs, gen, strict=True):
        out[i, s:s + chunk] = vals
    return out


# ----------------------------------------------------------------------------- figures
def plot_front_designs(fronts: Mapping[str, np.ndarray], path, *, baseline=None):
    """Front designs in the (L, D) and (L, F) planes, one colour per label."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
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
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _save_fig(fig, path) -> None:
    import matplotlib.pyplot as plt

    fig.savefig(path, dpi=120)
    plt.close(fig)


# ----------------------------------------------------------------------------- the study
def _label(name: str, pt: float) -> str:
    return f"{name} {pt * 100:g}%"


@EXPERIMENTS.register("study")
def run_study(config: Mapping[str, Any], run: RunFolder, *, progress: bool = False
              ) -> dict[str, Any]:
    """Run the study described by ``config`` into ``run``; returns a summary dict."""
    import matplotlib

    matplotlib.use("Agg")
    from surrogate_rbrdo.estimators import mc_from_values
    from surrogate_rbrdo.formulations import FormulationOptions, make_formulation
    from surrogate_rbrdo.optimization import (
        NSGA2Options,
        archive_front,
        front_table,
        mbr_table,
        run_many,
        run_nsga2,
        select_compromise,
        strategy_table,
        write_csv,
    )
    from surrogate_rbrdo.reporting.plots_optimization import (
        plot_convergence,
        plot_pareto_fronts,
    )
    from surrogate_rbrdo.runner.pipeline import train_peak_surrogate

    cfg = parse_study_config(config)          # every ValueError before any work
    opt, ver, sp = cfg.optimization, cfg.verification, cfg.spindle
    rng = np.random.default_rng(cfg.seed)
    r_sur, r_dm, r_crn, r_opt, r_ver = rng.spawn(5)
    r_ref = rng.spawn(1)[0]   # after the others: their streams are unchanged
    lo, hi = sp.design_map.bounds[:, 0], sp.design_map.bounds[:, 1]
    t_start = time.perf_counter()
    # FE points are cached per experiment (joblib.Memory keyed by the point), shared by runs
    cache_dir = run.path.parent / "_fe_cache"

    # 1. surrogate of the peak amplitude over (x, θ)
    with run.timed("surrogate"):
        surrogate, sinfo = train_peak_surrogate(sp, cfg.inputs, cfg.limit, cfg.surrogate,
                                                rng=r_sur, cache_dir=cache_dir,
                                                progress=progress, response=cfg.response)
    fe_loop = cfg.surrogate.structure == "fe"   # the FE model itself in the loop
    run.write_json("surrogate_info.json", sinfo)
    fe_calls = {"doe": int(sinfo.get("fe_calls", 0))}

    # 2. g_det design model
    with run.timed("design_model"):
        dmodel = fit_design_model(sp, cfg.design_model, rng=r_dm, progress=progress)
    run.write_json("design_model_validation.json", dmodel.validation)
    fe_calls["design_model"] = int(dmodel.validation["n_fe_calls"])

    # 3. formulations (same θ sample for all) and NSGA-II runs
    seed_seq = r_crn.bit_generator.seed_seq

    def formulation(name: str, pt: float):
        return make_formulation(
            name, response=surrogate.response, inputs=cfg.inputs, limit=cfg.limit,
            deterministic=dmodel, rng=np.random.default_rng(seed_seq),
            options=FormulationOptions(p_target=pt, n_theta=opt.n_theta,
                                       estimator=opt.estimator,
                                       deterministic=cfg.deterministic))

    runs = [("rbrdo", pt) for pt in opt.p_targets]
    runs += [(s, opt.strategy_p_target) for s in opt.strategies]
    nsga = NSGA2Options(pop_size=opt.pop_size, n_gen=opt.n_gen,
                        eliminate_duplicates=opt.eliminate_duplicates)
    labels = [_label(n, pt) for n, pt in runs]

    def optimise(r: np.random.Generator) -> tuple[list[Any], list[Any], dict[str, Any]]:
        """Every run on the current surrogate: formulations, results, results by label."""
        fs = [formulation(n, pt) for n, pt in runs]
        tasks = [partial(run_nsga2, f, lo, hi, rng=ri, options=nsga, progress=progress)
                 for f, ri in zip(fs, r.spawn(len(runs)), strict=True)]
        out = run_many(tasks, n_jobs=opt.n_jobs)
        every_run.extend(out)   # call counts cover the refinement rounds too
        return fs, out, dict(zip(labels, out, strict=True))

    every_run: list[Any] = []

    with run.timed("optimization"):
        forms, results, res = optimise(r_opt)

    def compromises(res: Mapping[str, Any]) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for lab, r in res.items():
            try:
                out[lab] = select_compromise(r, opt.weights if r.archive.F.shape[1] == 2
                                             else None)
            except ValueError:
                out[lab] = None
        return out

    # 3b. refinement: FE at the chosen designs, refit, optimise again (``[refine]``)
    refine_rows: list[dict[str, Any]] = []
    refine_meta: list[dict[str, Any]] = []
    if cfg.refine.rounds:
        from surrogate_rbrdo.core import CallCounter
        from surrogate_rbrdo.runner.pipeline import fe_cache

        ref, ref_counter, ref_cache = cfg.refine, CallCounter(), fe_cache(cache_dir)
        bounds = sp.design_map.bounds
        for rnd, r_round in enumerate(r_ref.spawn(ref.rounds), start=1):
            r_th, r_fit, r_nsga = r_round.spawn(3)
            comp = compromises(res)
            fr = {lab: res[lab].archive.X[archive_front(res[lab])]   # sorted by objective 1
                  for (name, _), lab in zip(runs, labels, strict=True)
                  if name in ("rbrdo", "rdo")}
            X_sel = select_designs([c.x for c in comp.values() if c is not None], fr, bounds,
                                   ref.designs)
            with run.timed(f"refine_{rnd}"):
                surrogate, st = refine_surrogate(
                    surrogate, sp, X_sel, cfg.inputs.sample(ref.theta, rng=r_th),
                    cfg.surrogate, cfg.limit, rng=r_fit,
                    cache=ref_cache, counter=ref_counter,
                    progress=progress, tol=ref.tol, hyper=ref.hyper,
                    response=cfg.response)
                refine_rows.append({"round": rnd, **{k: v for k, v in st.items()
                                                     if not isinstance(v, list)}})
                refine_meta.append({"round": rnd, "designs": X_sel.tolist(), **st})
                if not st["refit"]:
                    break
                forms, results, res = optimise(r_nsga)
        fe_calls["refine"] = int(ref_counter.calls)
        write_csv(run.file("refine.csv"), refine_rows)
        run.write_json("surrogate_info.json", surrogate.info)

    # 4. fronts, compromises, MBR
    comp = compromises(res)
    fronts, clouds, front_designs = {}, {}, {}
    front_rows = []
    for (name, pt), lab in zip(runs, labels, strict=True):
        r = res[lab]
        if name in ("rbrdo", "rdo"):
            idx = archive_front(r)
            fronts[lab] = r.archive.F[idx]
            front_designs[lab] = r.archive.X[idx]
            clouds[lab] = r.archive.F[r.archive.feasible]
            for row in front_table(r, design_names=DESIGN_NAMES):
                front_rows.append({"run": lab, "p_target_pct": pt * 100, **row})
    if front_rows:
        write_csv(run.file("pareto_fronts.csv"), front_rows)
    rb = [lab for (n, _), lab in zip(runs, labels, strict=True) if n == "rbrdo"]
    rb_fronts = {lab: fronts[lab] for lab in rb}
    fig = plot_pareto_fronts(rb_fronts, quantity=cfg.response.label,
                             compromises={lab: (comp[lab].mean, comp[lab].std)
                                          for lab in rb if comp[lab] is not None},
                             clouds={lab: clouds[lab] for lab in rb})
    fig.axes[0].set_title("RBRDO feasible Pareto fronts per P_target "
                          f"({'full FE' if fe_loop else 'surrogate'}, CRN sample)")
    _save_fig(fig, run.file("pareto_fronts.png"))
    all_fronts = {k: v for k, v in fronts.items()}
    fig = plot_pareto_fronts(all_fronts, quantity=cfg.response.label,
                             compromises={k: (comp[k].mean, comp[k].std)
                                          for k in all_fronts if comp[k]})
    _save_fig(fig, run.file("pareto_fronts_with_rdo.png"))
    plot_front_designs({lab: front_designs[lab] for lab in rb}, run.file("front_designs.png"),
                       baseline=cfg.baseline)
    fig = plot_convergence({lab: list(r.history) for lab, r in res.items()})
    _save_fig(fig, run.file("convergence.png"))

    # 5. chosen designs, on the CRN sample (surrogate) and with the full FE model
    chosen: dict[str, np.ndarray] = {"baseline": cfg.baseline}
    for lab in labels:
        if comp[lab] is not None:
            chosen[lab] = comp[lab].x
    names = list(chosen)
    Xc = np.array([chosen[k] for k in names])
    ref_form = forms[0]
    crn = ref_form.assess(Xc)
    # g_det of the chosen designs from the design model alone: a second ``evaluate`` would
    # repeat the response calls that ``assess`` just made (FE solves with structure = "fe")
    det_c = ref_form.constraints_det
    det_names = det_c.names if det_c is not None else ()
    G_det = det_c(Xc) if det_names else np.empty((Xc.shape[0], 0))
    theta_v = cfg.inputs.sample(ver.n_theta, rng=r_ver)
    with run.timed("verification_fe"):
        y_fe = fe_values(sp, Xc, theta_v, n_jobs=ver.n_jobs, chunk=ver.chunk,
                         progress=progress, response=cfg.response)
    fe_calls["verification"] = int(y_fe.size)
    # FE in the loop: no surrogate columns (NaN), not a copy of the FE ones
    y_sv = np.full_like(y_fe, np.nan) if fe_loop else surrogate.response(Xc, theta_v)
    est_fe = mc_from_values(y_fe, cfg.limit)
    if fe_loop:
        from types import SimpleNamespace

        nan = np.full(Xc.shape[0], np.nan)
        est_sv = SimpleNamespace(mean=nan, std=nan, pf=nan)
    else:
        est_sv = mc_from_values(y_sv, cfg.limit)
    pf_is = None
    if ver.pf_method == "is":
        from surrogate_rbrdo.estimators import get_estimator

        with run.timed("verification_is"):
            e = get_estimator("is", n_samples=ver.is_samples).estimate(
                cfg.response.fe_response(sp), cfg.inputs, cfg.limit, Xc, rng=r_ver.spawn(1)[0])
        pf_is = np.asarray(e.pf)
        fe_calls["verification_is"] = int(e.n_calls)
    ver_rows = []
    for i, k in enumerate(names):
        row = {"design": k, **{n: float(v) for n, v in zip(DESIGN_NAMES, Xc[i], strict=True)},
               "mean_um_surrogate_crn": crn.mean[i] * 1e6,
               "std_um_surrogate_crn": crn.std[i] * 1e6,
               "pf_pct_surrogate_crn": crn.pf[i] * 100,
               "mean_um_surrogate": est_sv.mean[i] * 1e6, "std_um_surrogate": est_sv.std[i] * 1e6,
               "pf_pct_surrogate": est_sv.pf[i] * 100,
               "mean_um_fe": est_fe.mean[i] * 1e6, "std_um_fe": est_fe.std[i] * 1e6,
               "pf_pct_fe": est_fe.pf[i] * 100,
               "pf_ci_low_pct_fe": float(np.asarray(est_fe.pf_ci)[i, 0] * 100),
               "pf_ci_high_pct_fe": float(np.asarray(est_fe.pf_ci)[i, 1] * 100),
               "max_abs_err_um": float(np.abs(y_sv[i] - y_fe[i]).max() * 1e6),
               "n_theta_fe": ver.n_theta}
        if pf_is is not None:
            row["pf_pct_fe_is"] = float(pf_is[i] * 100)
        row.update({f"g_{n}": float(v) for n, v in zip(det_names, G_det[i], strict=True)})
        ver_rows.append(row)
    write_csv(run.file("verification.csv"), ver_rows)

    # strategy table (Fig. 6): μ, σ, P_f per formulation on the CRN sample + FE columns
    entries = {}
    for i, k in enumerate(names):
        pt = None
        for (n, p), lab in zip(runs, labels, strict=True):
            if lab == k and n in ("rbrdo", "rbdo"):
                pt = p
        entries[k] = {"x": Xc[i], "mean": crn.mean[i], "std": crn.std[i], "pf": crn.pf[i],
                      "p_target": pt}
    srows = strategy_table(entries, design_names=DESIGN_NAMES)
    for i, r in enumerate(srows):
        r.update({"mean_um_fe": est_fe.mean[i] * 1e6, "std_um_fe": est_fe.std[i] * 1e6,
                  "pf_pct_fe": est_fe.pf[i] * 100})
    write_csv(run.file("strategy_comparison.csv"), srows)

    levels_s = [(pt, comp[lab].mean, comp[lab].std)
                for (n, pt), lab in zip(runs, labels, strict=True)
                if n == "rbrdo" and comp[lab] is not None]
    mbr_rows = []
    if len(levels_s) >= 2:
        for r in mbr_table(levels_s):
            mbr_rows.append({"source": "surrogate_crn", **r})
        idx = {k: i for i, k in enumerate(names)}
        levels_f = [(pt, est_fe.mean[idx[lab]], est_fe.std[idx[lab]])
                    for (n, pt), lab in zip(runs, labels, strict=True)
                    if n == "rbrdo" and lab in idx]
        for r in mbr_table(levels_f):
            mbr_rows.append({"source": "fe_verification", **r})
    # the ends of each feasible front (least μ, least σ: from different designs) do not jump
    # between branches as a compromise can, and under CRN they can only worsen as P_target
    # tightens (the feasible set shrinks; an optimiser's fronts only approximately so)
    levels_e = [(pt, fronts[lab][:, 0].min(), fronts[lab][:, 1].min())
                for (n, pt), lab in zip(runs, labels, strict=True)
                if n == "rbrdo" and len(fronts[lab])]
    if len(levels_e) >= 2:
        for r in mbr_table(levels_e):
            mbr_rows.append({"source": "front_ends_crn", **r})
    if mbr_rows:
        write_csv(run.file("mbr.csv"), mbr_rows)

    comp_rows = []
    for (n, pt), lab in zip(runs, labels, strict=True):
        c, r = comp[lab], res[lab]
        if c is None:
            comp_rows.append({"run": lab, "feasible": False})
            continue
        comp_rows.append({"run": lab, "formulation": n, "p_target_pct": pt * 100,
                          **{k: float(v) for k, v in zip(DESIGN_NAMES, c.x, strict=True)},
                          "mean_um": c.mean * 1e6, "std_um": c.std * 1e6, "pf_pct": c.pf * 100,
                          "reliability_g": float(c.G[0]) if n in ("rbrdo", "rbdo") else "",
                          "front_size": int(archive_front(r).size),
                          "front_active_1pct": int(np.sum(
                              r.archive.pf[archive_front(r)] > 0.9 * pt)) if n == "rbrdo"
                          else "",
                          "wall_time_s": r.wall_time_s,
                          "surrogate_calls": r.n_surrogate_calls,
                          "design_model_calls": r.n_model_calls})
    write_csv(run.file("compromises.csv"), comp_rows)

    # 6. Campbell and unbalance response, baseline vs the chosen design
    pick = _label("rbrdo", 0.05) if _label("rbrdo", 0.05) in chosen else (rb[0] if rb else None)
    with run.timed("spindle_figures"):
        _spindle_figures(run, sp, cfg, {"baseline": cfg.baseline,
                                        **({f"{pick} compromise": chosen[pick]} if pick else {})})
    opt_sur = int(sum(r.n_surrogate_calls for r in every_run))
    if fe_loop:   # the "surrogate" calls were FE calls; there is no surrogate
        fe_calls["optimization"] = opt_sur
        fe_calls["crn_assessment"] = int(crn.n_calls)
        opt_sur = total_sur = 0
    else:
        total_sur = opt_sur + int(y_sv.size) + int(crn.n_calls)
    extra = {"model_in_loop": "fe" if fe_loop else "surrogate",
             "response": cfg.response.label,
             "fe_calls": {**fe_calls, "total": int(sum(fe_calls.values()))},
             "surrogate_calls": {"optimization": opt_sur, "total": int(total_sur)},
             "design_model_calls": int(sum(r.n_model_calls for r in every_run)),
             "optimizer_seeds": {lab: r.optimizer.get("seed") for lab, r in res.items()},
             "study_wall_time_s": time.perf_counter() - t_start,
             "refine": refine_meta,
             "surrogate": sinfo.get("config", {})}
    run.write_json("study_meta.json", extra)
    summary_rows = [{k: (round(v, 4) if isinstance(v, float) else v) for k, v in r.items()
                     if k in ("design", "preload_N", "span_mm", "diameter_mm", "mean_um_fe",
                              "std_um_fe", "pf_pct_fe", "mean_um_surrogate", "std_um_surrogate",
                              "pf_pct_surrogate")} for r in ver_rows]
    return {"summary": summary_rows, "mbr": mbr_rows, "compromises": comp_rows,
            "timings_s": dict(run.timings), "meta": extra}


def _spindle_figures(run: RunFolder, sp, cfg: StudyConfig, designs: Mapping[str, np.ndarray]
                     ) -> None:
    from surrogate_rbrdo.reporting.plots_spindle import plot_campbell, plot_unbalance_response
    from surrogate_rbrdo.spindle.harmonic import tool_amplitude
    from surrogate_rbrdo.spindle.modal import campbell

    g = sp.geometry
    rep = cfg.report
    speeds = np.linspace(g.speed_min_rpm, g.speed_max_rpm, rep.n_speeds)
    camp_speeds = np.linspace(0.0, g.speed_max_rpm, rep.campbell_speeds)
    curves, camps, rows = {}, {}, []
    for label, x in designs.items():
        model = sp.model(np.asarray(x, float))
        amp = tool_amplitude(model, speeds)[0] * 1e6
        curves[label] = (speeds, amp)
        camps[label] = campbell(model, camp_speeds, n_modes=rep.n_modes)
        rows.append([label, *np.round(x, 3),
                     " ".join(f"{c:.0f}" for c in camps[label].critical_speeds_rpm)])
    run.write_csv("critical_speeds.csv", ["design", *DESIGN_NAMES, "critical_speeds_rpm"], rows)
    run.write_csv("unbalance_response.csv", ["speed_rpm", *[f"{k}_um" for k in curves]],
                  np.column_stack([speeds, *[c[1] for c in curves.values()]]).tolist())
    plot_campbell(camps, run.file("campbell.png"), speed_max_rpm=g.speed_max_rpm)
    plot_unbalance_response(curves, run.file("unbalance_response.png"),
                            limit_um=cfg.limit.threshold * 1e6)
