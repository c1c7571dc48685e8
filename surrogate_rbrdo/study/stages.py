"""The RBRDO study as stage functions, each returning a frozen result.

surrogate (:func:`~surrogate_rbrdo.surrogates.structured.train_surrogate`) → design model
(:func:`~surrogate_rbrdo.surrogates.design_model.fit_design_model`) → :func:`optimise` (RBRDO
at every P_target, then the comparison strategies, on one common-random-number θ sample) →
:func:`refine` (optional FE infill where the optimiser went) → :func:`verify` (every chosen
design with the full FE model). Tables and figures of the results:
:mod:`~surrogate_rbrdo.reporting.study`.

Every model call goes through a counting wrapper (:class:`~surrogate_rbrdo.core.
CountingResponse`, :class:`~surrogate_rbrdo.core.counting.CountingDesigns`) and each result
carries its ``calls`` (``{"fe": …, "surrogate": …, "design_model": …}``): counted, also inside
worker processes (a run returns its counts with its result). When the model in the loop is
the FE model itself (``structure = "fe"``) its calls are counted as FE calls.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from functools import partial
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from surrogate_rbrdo.core.counting import CallCounter, CountingDesigns, CountingResponse
from surrogate_rbrdo.core.protocols import Estimate
from surrogate_rbrdo.estimators import get_estimator, mc_from_values
from surrogate_rbrdo.formulations import FormulationOptions, make_formulation
from surrogate_rbrdo.formulations.constraints import constraint_matrix
from surrogate_rbrdo.optimization import (
    Compromise,
    OptimizationResult,
    archive_front,
    run_many,
    select_compromise,
)
from surrogate_rbrdo.sampling.fe import sample_designs
from surrogate_rbrdo.study.checks import campbell_critical_speeds
from surrogate_rbrdo.study.fronts import FrontCheck, verify_fronts
from surrogate_rbrdo.study.options import OptimizationOptions, VerificationOptions
from surrogate_rbrdo.study.problem import Problem
from surrogate_rbrdo.surrogates.refine import RefineOptions, refine_surrogate, select_designs
from surrogate_rbrdo.surrogates.structured.base import TrainedSurrogate


def run_label(name: str, p_target: float) -> str:
    """``"rbrdo 5%"``: the label of a run in tables and figures."""
    return f"{name} {p_target * 100:g}%"


def _stored(est: Estimate) -> Estimate:
    """``est`` with plain-dict diagnostics (a stage result is pickled into the run folder)."""
    return replace(est, diagnostics=dict(est.diagnostics))


def merge_calls(*parts: Mapping[str, int]) -> dict[str, int]:
    """Sum call counts by model (``"fe"``, ``"surrogate"``, ``"design_model"``)."""
    out: dict[str, int] = {}
    for p in parts:
        for k, v in p.items():
            out[k] = out.get(k, 0) + int(v)
    return out


@dataclass(frozen=True, eq=False)
class Optimisation:
    """Every optimiser run of one surrogate: ``runs[i]`` = ``(formulation, p_target)``,
    ``labels[i]`` its label, ``results[i]`` its :class:`OptimizationResult`; ``calls``
    counted (``"surrogate"`` or ``"fe"`` for the model in the loop, ``"design_model"``)."""

    runs: tuple[tuple[str, float], ...]
    labels: tuple[str, ...]
    results: tuple[OptimizationResult, ...]
    calls: Mapping[str, int] = field(default_factory=dict)

    def by_label(self) -> dict[str, OptimizationResult]:
        return dict(zip(self.labels, self.results, strict=True))

    def compromises(self, weights: tuple[float, ...]) -> dict[str, Compromise | None]:
        """ASF compromise of each run (``None``: no feasible design)."""
        out: dict[str, Compromise | None] = {}
        for lab, r in self.by_label().items():
            try:
                out[lab] = select_compromise(r, weights if r.archive.F.shape[1] == 2 else None)
            except ValueError:
                out[lab] = None
        return out

    def fronts(self) -> dict[str, np.ndarray]:
        """Designs of the feasible archive front of every RBRDO/RDO run (sorted by μ)."""
        return {lab: r.archive.X[archive_front(r)]
                for (name, _), lab, r in zip(self.runs, self.labels, self.results, strict=True)
                if name in ("rbrdo", "rdo")}


class _TrackedFormulation:
    """A formulation whose ``evaluate`` advances a progress bar (one tick per batch)."""

    def __init__(self, formulation: Any, bar: Any) -> None:
        self._f, self._bar = formulation, bar

    def __getattr__(self, name: str) -> Any:
        return getattr(self._f, name)

    def evaluate(self, x: np.ndarray) -> Any:
        ev = self._f.evaluate(x)
        self._bar.update(1)
        return ev


def formulation(problem: Problem, model: Any, design_model: Any, name: str, p_target: float,
                options: OptimizationOptions, crn: np.random.SeedSequence) -> Any:
    """The formulation ``name`` at ``p_target`` on ``model``, with the CRN sample of ``crn``
    (formulations built from one ``crn`` see the same θ)."""
    return make_formulation(
        name, response=model, inputs=problem.inputs, limit=problem.limit,
        deterministic=design_model, rng=np.random.default_rng(crn),
        constraints=problem.constraints, design_theta=problem.design_theta,
        options=FormulationOptions(p_target=p_target, n_theta=options.n_theta,
                                   estimator=options.estimator,
                                   estimator_options=options.estimator_options,
                                   reliability_measure=options.reliability_measure,
                                   pf_bound=options.pf_bound,
                                   deterministic=problem.deterministic))


def _run_one(problem: Problem, trained: TrainedSurrogate, design_model: Any, run: tuple[str, float],
             options: OptimizationOptions, crn: np.random.SeedSequence, rng: np.random.Generator,
             bar: tuple[str, int] | None) -> tuple[OptimizationResult, dict[str, int]]:
    """One optimiser run (possibly in a worker process); returns the result and its counts."""
    model = CountingResponse(trained.model.response)
    dm = CountingDesigns(design_model)
    form = formulation(problem, model, dm, *run, options, crn)
    pbar = None
    if bar is not None:
        # a thread lock: tqdm's default process lock is a semaphore that a killed worker
        # would leak (the resource tracker then warns at exit)
        tqdm.set_lock(threading.RLock())
        pbar = tqdm(total=options.n_gen, desc=bar[0], unit="gen", position=bar[1], leave=False)
        form = _TrackedFormulation(form, pbar)
    try:
        lo, hi = problem.design_bounds[:, 0], problem.design_bounds[:, 1]
        res = options.optimizer_function(run[0])(form, lo, hi, rng=rng,
                                                 options=options.optimizer_config(run[0]),
                                                 progress=False)
    finally:
        if pbar is not None:
            pbar.close()
    return res, {trained.in_loop: model.counter.calls, "design_model": dm.counter.calls}


def _bar_label(label: str, name: str, p_target: float) -> str:
    """``"quick/r1 rbrdo P_target=5%"`` (P_target only where the formulation has one)."""
    pt = f" P_target={p_target * 100:g}%" if name in ("rbrdo", "rbdo") else ""
    return f"{label} {name}{pt}".strip()


def optimise(problem: Problem, trained: TrainedSurrogate, design_model: Any,
             options: OptimizationOptions, *, crn: np.random.SeedSequence,
             rng: np.random.Generator, progress: bool = False, label: str = "") -> Optimisation:
    """Every run of ``options.runs`` on ``trained`` (side by side in ``options.n_jobs``
    processes; the results do not depend on ``n_jobs``)."""
    runs = options.runs
    labels = tuple(run_label(n, p) for n, p in runs)
    tasks = [partial(_run_one, problem, trained, design_model, run, options, crn, r,
                     (_bar_label(label, *run), i if options.n_jobs > 1 else 0)
                     if progress else None)
             for i, (run, lab, r) in enumerate(zip(runs, labels, rng.spawn(len(runs)),
                                                   strict=True))]
    out = run_many(tasks, n_jobs=options.n_jobs)
    return Optimisation(runs, labels, tuple(r for r, _ in out),
                        merge_calls(*(c for _, c in out)))


@dataclass(frozen=True, eq=False)
class Refinement:
    """Rounds of FE infill at the optimiser's designs: ``rounds`` (one stats mapping per round,
    with the designs), the refitted ``surrogate`` and the ``optimisation`` on it (``None``
    when no round refitted), ``calls`` (FE calls of the infill, the re-optimisations')."""

    rounds: tuple[Mapping[str, Any], ...] = ()
    surrogate: TrainedSurrogate | None = None
    optimisation: Optimisation | None = None
    calls: Mapping[str, int] = field(default_factory=dict)


def refine(problem: Problem, trained: TrainedSurrogate, design_model: Any,
           optimisation: Optimisation, options: OptimizationOptions,
           refine_options: RefineOptions, *, crn: np.random.SeedSequence,
           rng: np.random.Generator, cache: Any = None, progress: bool = False,
           label: str = "") -> Refinement:
    """FE at the chosen designs, refit, optimise again, for up to ``refine_options.rounds``
    rounds (stop once the error at the chosen designs is below ``tol``)."""
    ref = refine_options
    if not ref.rounds:
        return Refinement()
    counter = CallCounter()
    rounds: list[Mapping[str, Any]] = []
    sur, opt, refitted = trained, optimisation, False
    calls: Mapping[str, int] = {}
    for rnd, r_round in enumerate(rng.spawn(ref.rounds), start=1):
        r_th, r_fit, r_opt = r_round.spawn(3)
        comp = opt.compromises(options.weights)
        X_sel = select_designs([c.x for c in comp.values() if c is not None], opt.fronts(),
                               problem.design_bounds, ref.designs)
        sur, st = refine_surrogate(sur, problem.spindle, X_sel,
                                   problem.inputs.sample(ref.theta, rng=r_th), problem.limit,
                                   rng=r_fit, cache=cache, counter=counter, progress=progress,
                                   tol=ref.tol, hyper=ref.hyper)
        rounds.append({"round": rnd, "designs": X_sel.tolist(), **st})
        if not st["refit"]:
            break
        refitted = True
        opt = optimise(problem, sur, design_model, options, crn=crn, rng=r_opt,
                       progress=progress, label=label)
        calls = merge_calls(calls, opt.calls)
    return Refinement(tuple(rounds), sur if refitted else None, opt if refitted else None,
                      merge_calls(calls, {"fe": counter.calls, "fe_cached": counter.cached}))


@dataclass(frozen=True, eq=False)
class Verification:
    """The chosen designs on the CRN sample and with the full FE model on a fresh sample.

    Attributes
    ----------
    names : tuple of str
        ``"baseline"`` and the label of every run with a compromise.
    X : ndarray (k, d)
    crn : Estimate
        The model in the loop on the CRN sample (the first RBRDO formulation's).
    det_names : tuple of str
    G_det : ndarray (k, n_det)
        Deterministic constraints: g_det from the design model, then the problem's design
        constraints (practice checks, the exact separation guard, expressions).
    fe : Estimate
        Full-FE Monte Carlo on ``n_theta`` fresh θ.
    surrogate : Estimate or None
        The surrogate on the same fresh sample (``None``: the FE model was in the loop).
    max_abs_err : ndarray (k,)
        ``max |y_surrogate − y_FE|`` over the fresh sample (NaN with the FE model in the loop).
    pf_is : ndarray or None
        Importance-sampling P_f with the FE model (``pf_method = "is"``).
    n_theta : int
    critical_rpm : tuple of ndarray
        Damped forward critical speeds (rpm) of each design from its FE Campbell diagram,
        up to 1.5 × the top speed (empty tuple: not checked, ``campbell_speeds = 0``).
    fronts : FrontCheck or None
        Front designs of every RBRDO/RDO run checked with the FE model
        (``front_designs > 0``).
    calls : mapping
    """

    names: tuple[str, ...]
    X: np.ndarray
    crn: Estimate
    det_names: tuple[str, ...]
    G_det: np.ndarray
    fe: Estimate
    surrogate: Estimate | None
    max_abs_err: np.ndarray
    pf_is: np.ndarray | None
    n_theta: int
    calls: Mapping[str, int] = field(default_factory=dict)
    critical_rpm: tuple[np.ndarray, ...] = ()
    fronts: FrontCheck | None = None


def chosen_designs(problem: Problem, optimisation: Optimisation,
                   weights: tuple[float, ...]) -> dict[str, np.ndarray]:
    """The baseline and every run's compromise design, by label."""
    chosen = {"baseline": problem.baseline}
    for lab, c in optimisation.compromises(weights).items():
        if c is not None:
            chosen[lab] = c.x
    return chosen


def verify(problem: Problem, trained: TrainedSurrogate, design_model: Any,
           optimisation: Optimisation, options: OptimizationOptions,
           ver: VerificationOptions, *, crn: np.random.SeedSequence, rng: np.random.Generator,
           cache: Any = None, progress: bool = False, label: str = "") -> Verification:
    """The chosen designs (:func:`chosen_designs`) assessed on the CRN sample and checked with
    the full FE model (``ver.n_theta`` fresh θ; the same sample for the surrogate)."""
    chosen = chosen_designs(problem, optimisation, options.weights)
    names, Xc = tuple(chosen), np.array(list(chosen.values()))
    model = CountingResponse(trained.model.response)
    dm = CountingDesigns(design_model)
    ref_form = formulation(problem, model, dm, *optimisation.runs[0], options, crn)
    crn_est = ref_form.assess(Xc)
    det_c = ref_form.constraints_det
    det_names = (det_c.names if det_c is not None else ()) + tuple(
        c.name for c in problem.constraints)
    G_det = np.column_stack([det_c(Xc) if det_c is not None and det_c.names
                             else np.empty((Xc.shape[0], 0)),
                             constraint_matrix(problem.constraints, Xc)])
    crit = tuple(campbell_critical_speeds(problem.spindle, Xc, n_speeds=ver.campbell_speeds)) \
        if ver.campbell_speeds else ()
    theta_v = problem.inputs.sample(ver.n_theta, rng=rng)
    fe_counter = CallCounter()
    y_fe = sample_designs(problem.fe_response(), Xc, theta_v, n_jobs=ver.n_jobs, chunk=ver.chunk,
                          cache=cache, counter=fe_counter, progress=progress,
                          desc=f"{label} FE verification".strip())
    est_fe = mc_from_values(y_fe, problem.limit)
    fe_loop = trained.in_loop == "fe"
    if fe_loop:   # no surrogate columns (NaN), not a copy of the FE ones
        est_sv, err = None, np.full(Xc.shape[0], np.nan)
    else:
        y_sv = model(Xc, theta_v)
        est_sv = mc_from_values(y_sv, problem.limit)
        err = np.abs(y_sv - y_fe).max(axis=1)
    pf_is, is_counter = None, CallCounter()
    if ver.pf_method == "is":
        e = get_estimator("is", n_samples=ver.is_samples).estimate(
            CountingResponse(problem.fe_response(), is_counter), problem.inputs,
            problem.limit, Xc, rng=rng.spawn(1)[0])
        pf_is = np.asarray(e.pf)
    fronts = None
    if ver.front_designs:
        fronts = verify_fronts(problem, optimisation, ver.front_designs,
                               problem.inputs.sample(ver.front_n_theta, rng=rng.spawn(1)[0]),
                               n_jobs=ver.n_jobs, chunk=ver.chunk, cache=cache,
                               progress=progress, label=label)
    calls = merge_calls({"fe": fe_counter.calls + is_counter.calls,
                         "fe_cached": fe_counter.cached + is_counter.cached,
                         "design_model": dm.counter.calls},
                        {trained.in_loop: model.counter.calls},
                        fronts.calls if fronts is not None else {})
    return Verification(names, Xc, _stored(crn_est), tuple(det_names), G_det, _stored(est_fe),
                        None if est_sv is None else _stored(est_sv), err,
                        pf_is, ver.n_theta, calls, crit, fronts)


__all__ = ["Optimisation", "Refinement", "Verification", "chosen_designs", "formulation",
           "merge_calls", "optimise", "refine", "run_label", "verify"]
