"""The discrepancy workflow: where the model and the data part, which effect is missing, and how
much the gap shrinks once it is added.

1. **Where.** The model's own uncertain parameters (bearing stiffness factors, a damping factor,
   the unbalance of every 1x test) are recalibrated on the training speeds; whitened residuals
   show where the data leave the model.
2. **Which effect.** Every candidate of the library is fitted on top of the recalibrated model
   (nuisance refitted with it) and tested (:mod:`.naming`); the best passing one is added and the
   search repeats for a second effect (forward selection, at most ``max_effects``). A name
   must also beat every plausible generic local change (:mod:`.rivals`); a first-stage
   detection that none beats is an unnamed residual.
3. **Nothing missing / unnamed residual.** Whatever is named, the final model's residual must
   pass three lack-of-fit tests (each at ``alpha_residual / 3``): the χ² goodness of fit, a GP
   structure test along speed and frequency, and the projection on generic local
   sensitivities (:mod:`.generic`).
   If no candidate passes and the residual is noise: *nothing missing*. If the residual keeps
   structure: *unnamed residual* (no library name is given, even for an effect that explained a
   part), with a GP correction for prediction only.
4. **The gap.** Held-out RMSE, largest error and χ² per observable, before (recalibrated
   baseline) and after (the named model, or the baseline plus the GP correction).
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_int, check_positive, check_range
from surrogate_rbrdo.discrepancy.candidates import (
    DEFAULT_LIBRARY,
    check_library,
    library,
    separating_test,
)
from surrogate_rbrdo.discrepancy.fit import Fit, fit
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.generic import beside_names
from surrogate_rbrdo.discrepancy.gp import gp_correction
from surrogate_rbrdo.discrepancy.holdout import Gap, Split, held_out_gap, masks_for, split_speeds
from surrogate_rbrdo.discrepancy.naming import Assessment, HoldoutProblems, Stage
from surrogate_rbrdo.discrepancy.noise import run_offsets, run_states, theta_jacobian
from surrogate_rbrdo.discrepancy.nuisance import NuisanceOptions
from surrogate_rbrdo.discrepancy.observables import THIN_IMPACTS, MeasuredData
from surrogate_rbrdo.discrepancy.problem import Problem
from surrogate_rbrdo.discrepancy.rivals import (
    RIVAL_SEPARATION,
    RIVAL_SEPARATION_AT_SPEED,
    RIVAL_SEPARATION_SPRING,
)
from surrogate_rbrdo.discrepancy.search import SlotEstimate, fit_nuisance, slot_estimate
from surrogate_rbrdo.discrepancy.selection import refined, select
from surrogate_rbrdo.discrepancy.soak import SoakTest
from surrogate_rbrdo.discrepancy.summary import BlockCurves, block_curves
from surrogate_rbrdo.spindle.effects import Effect
from surrogate_rbrdo.spindle.geometry import SpindleGeometry

VERDICTS = ("named", "confounded", "nothing_missing", "unnamed_residual")
#: what a library effect the data cannot tell from a generic change becomes
GENERIC_CONFOUND = ("confounded", "unnamed_residual")


@dataclass(frozen=True)
class DiscrepancyOptions:
    """Options of the workflow; every threshold is fixed before data are seen.

    Attributes
    ----------
    library : tuple of str
        Candidate effects (registry names), explicit.
    nuisance : NuisanceOptions
    alpha : float
        Family-wise error rate of naming, per stage (bootstrap min-p over the candidates).
    alpha_residual : float
        Error rate of declaring a residual unexplained (three lack-of-fit tests, a third each).
    n_draws : int
        Bootstrap draws of the null distributions.
    holdout_every, extrapolate_fraction : int, float
        The held-out split (:func:`~surrogate_rbrdo.discrepancy.holdout.split_speeds`).
    max_effects : int
        Most effects named (forward selection stages).
    confound_delta : float
        Passing candidates within this ``Δχ²`` of the best are confounded (χ²₁ 99 %: 6.63).
    holdout_tolerance : float
        Largest worsening of a held-out subset's χ² a named effect may cause (χ²₁ 99.9 %:
        10.83; the total held-out χ² must fall in any case).
    use_identified : bool
        Add identified bearing stiffness to the observables (off by default: it is identified
        from the same records as the 1x phasors, so it would count them twice).
    use_impacts : bool
        Whether a measured-data folder's (or a rig campaign's) impact records become FRF
        blocks, one per spin speed and hit direction (``experiment.data_from_folder``; the
        impact test plan of ``rig.impacts.ImpactPlan``). On by default: the candidate search
        carries each candidate from the 1x data to the FRFs (:mod:`.search`), and blocks with
        too few hits are dropped (``min_impact_dof``). Blocks passed to
        :func:`find_discrepancy` directly are used as given (subject to ``min_impact_dof``).
    min_impact_dof : int
        Fewest degrees of freedom of an impact block's noise covariance for the block to be
        used (``R − 1`` for ``R`` hits; 9: 10 hits). Each line's 2×2 covariance is estimated
        with ``ν`` degrees of freedom, so the line's whitened residual is a Hotelling T²,
        ``∝ F(2, ν − 1)``: its variance is finite only for ``ν ≥ 6``, and the expected
        precision of the estimate is ``ν/(ν − 3)`` times the true one (Wishart; 4 with 5
        hits, 1.5 with 10), a bias the whitening corrects at the price of a noisier scale.
        With fewer the few lines near a resonance dominate χ² with heavy tails; pooling the
        covariance over lines is no remedy, since an FRF's noise grows with the response at
        a resonance. The default campaign's 5 hits at standstill (ν = 4) are not used.
    max_nfev : int
        Residual evaluations per candidate fit.
    n_jobs : int
        Worker processes for the candidate fits of a stage (:func:`~.naming.fit_all`; the
        same answers for any value). 1 in the blind harness, which runs whole scenarios in
        parallel instead.
    generic_confound : {"confounded", "unnamed_residual"}
        The answer when the first stage's best library member and its closest generic local
        change explain the data alike — neither adds significantly to the other
        (:attr:`~.rivals.RivalTest.mutual`; e.g. a preload growth and a passive spring
        beside its bearing): ``"unnamed_residual"`` (the default: the model left unchanged,
        the library fit reported as partial, the test marked ``mutual``) or ``"confounded"``
        (the set, with the generic change in ``confounded_generic``, its best member carried
        for prediction, the residual tests still judging it). The data are the same whichever
        is hidden, so no rule is right for both: the second answers a hidden preload growth
        with a confounded set that holds it, and a hidden spring (outside the library) with
        one that holds library names. The default keeps the rule that an effect outside the
        library never gets a library name (docs/discrepancy.md, "Mutual confounds with a
        generic change", both measured).
    """

    library: tuple[str, ...] = DEFAULT_LIBRARY
    nuisance: NuisanceOptions = field(default_factory=NuisanceOptions)
    alpha: float = 0.01
    alpha_residual: float = 0.01
    n_draws: int = 300
    holdout_every: int = 5
    extrapolate_fraction: float = 0.1
    max_effects: int = 2
    confound_delta: float = 6.63
    holdout_tolerance: float = 10.83
    use_identified: bool = False
    use_impacts: bool = True
    min_impact_dof: int = 9
    max_nfev: int = 150
    n_jobs: int = 1
    generic_confound: str = "unnamed_residual"

    def __post_init__(self) -> None:
        object.__setattr__(self, "library", check_library(self.library))
        if not isinstance(self.nuisance, NuisanceOptions):
            raise ValueError(f"nuisance = {self.nuisance!r} is not allowed: must be a "
                             "NuisanceOptions")
        check_range("alpha", self.alpha, 1e-6, 0.2)
        check_range("alpha_residual", self.alpha_residual, 1e-6, 0.2)
        check_int("n_draws", self.n_draws, minimum=100)
        check_int("holdout_every", self.holdout_every, minimum=2)
        check_range("extrapolate_fraction", self.extrapolate_fraction, 0.0, 0.5)
        check_int("max_effects", self.max_effects, minimum=1)
        check_int("max_nfev", self.max_nfev, minimum=5)
        check_int("n_jobs", self.n_jobs, minimum=1)
        check_int("min_impact_dof", self.min_impact_dof, minimum=4)
        if self.generic_confound not in GENERIC_CONFOUND:
            raise ValueError(f"generic_confound = {self.generic_confound!r} is not allowed: "
                             f"must be one of {', '.join(map(repr, GENERIC_CONFOUND))}")
        check_positive("confound_delta", self.confound_delta)
        check_positive("holdout_tolerance", self.holdout_tolerance, allow_zero=True)


@dataclass(frozen=True)
class DiscrepancyResult:
    """What the workflow found (``findings()`` is the machine-readable form)."""

    verdict: str
    effects: tuple[Assessment, ...]
    confounded_with: tuple[str, ...]
    test: dict
    residual_test: dict
    gap_before: Gap
    gap_after: Gap
    stages: tuple[Stage, ...]
    base: Fit
    final: Fit
    split: Split
    speeds_rpm: np.ndarray
    partial: tuple[str, ...]
    separating: str
    seconds: float
    options: DiscrepancyOptions
    #: run-to-run SD of each log stiffness factor estimated from the repeats (0: no runs)
    run_scatter: tuple[float, ...] = ()
    #: every block's data and predictions at every point (:mod:`.summary`)
    curves: tuple[BlockCurves, ...] = ()
    #: impact blocks left out for too few hits: ``(name, dof)`` (``min_impact_dof``)
    dropped_blocks: tuple[tuple[str, int], ...] = ()
    #: for *confounded*: the generic local changes (:mod:`.rivals`) the data cannot tell from
    #: the set's library members, e.g. a grounded spring beside a bearing
    confounded_generic: tuple[str, ...] = ()
    #: the thermal soak's verdicts on the drifting candidates it was put to (:mod:`.soak`)
    soak: tuple[SoakTest, ...] = ()

    @property
    def named_effects(self) -> tuple[Effect, ...]:
        """The effects the updated model adds (for *confounded*: the best-fitting member)."""
        if self.verdict not in ("named", "confounded"):
            return ()
        return tuple(s.candidate.effect(s.scope, v) for s, v in
                     zip(self.final.par.slots, self.final.par.slot_values(self.final.x),
                         strict=True))

    @property
    def fitted_effects(self) -> tuple[tuple[str, SlotEstimate], ...]:
        """``(name, estimate)`` of every effect the updated model adds, from the final joint
        fit — the parameters :attr:`named_effects` carries (a stage's own fit of an effect
        named earlier is refitted with the effects named after it)."""
        if self.verdict not in ("named", "confounded"):
            return ()
        return tuple((s.candidate.name, slot_estimate(self.final, i))
                     for i, s in enumerate(self.final.par.slots))

    def recalibration(self, fit: Fit | None = None) -> dict:
        f = self.final if fit is None else fit
        rows = f.par.rows(f.x[None])
        return {"theta": dict(zip(f.par.theta_bearings, rows.theta[0].tolist(), strict=True)),
                "damping_scale": dict(zip(f.par.bearings, rows.damping[0].tolist(),
                                          strict=True)),
                "mass_factor": dict(zip(f.par.nuisance.mass_disks, rows.mass[0].tolist(),
                                        strict=True)),
                "channel_gain": rows.gain[0].tolist(), "channel_tau_s": rows.tau[0].tolist(),
                "unbalance_kgm": [[float(abs(u)), float(np.degrees(np.angle(u)))]
                                  for u in f.evaluation.unbalance[0][0]]
                if f.evaluation.unbalance else []}


def _problem(fm: ForwardModel, data: MeasuredData, masks: dict | None,
             nuisance: NuisanceOptions, runs: tuple | None) -> Problem:
    """A problem on the points ``masks`` select; with ``runs`` ``(par, x, s)`` it carries the
    run-averaging correction at ``x`` (:mod:`.noise`)."""
    p = Problem(fm, data, masks, nuisance)
    return p if runs is None else Problem(fm, data, masks, nuisance, run_offsets(p, *runs))


def _problems(fm: ForwardModel, data: MeasuredData, split: Split, nuisance: NuisanceOptions,
              runs: tuple | None = None):
    """Training, held-out (interleaved, extrapolated) and all-held-out problems."""
    def prob(which: str) -> Problem:
        return _problem(fm, data, masks_for(data, split, which), nuisance, runs)
    return (prob("train"), HoldoutProblems(prob("interleaved"), prob("extrapolated")),
            prob("held_out"))


def _recalibrate(fm, data, split, options) -> tuple:
    """The problems and the recalibrated baseline, with the runs' thermal scatter (estimated
    from the repeats) averaged into the model when the data have runs; the average depends on
    the state it is taken at, so fit and average alternate until the fit settles."""
    train, ho, held = _problems(fm, data, split, options.nuisance)
    par = train.parametrisation()
    base = fit_nuisance(train, max_nfev=options.max_nfev)
    W = np.concatenate([w.reshape(-1, 2, 2) for w in train.whiten])
    runs = None
    for _ in range(RUN_ITERATIONS):
        u = tuple(v[0] for v in base.evaluation.unbalance)
        states = run_states(train if runs is None else _problem(
            fm, data, masks_for(data, split, "train"), options.nuisance, None),
            theta_jacobian(train, par, base.x, u), W)
        if not states:
            break
        runs = (par, base.x, states)
        train, ho, held = _problems(fm, data, split, options.nuisance, runs)
        previous, base = base.chi2, fit(train, par, base.x, max_nfev=options.max_nfev)
        if abs(previous - base.chi2) < 0.1:
            break
    return train, ho, held, base, runs


#: most alternations of fit and run average
RUN_ITERATIONS = 4


def find_discrepancy(data: MeasuredData, geometry: SpindleGeometry, effects: tuple[Effect, ...],
                     *, options: DiscrepancyOptions = DiscrepancyOptions(),
                     rng: np.random.Generator,
                     theta_bearings: tuple[str, ...] | None = None) -> DiscrepancyResult:
    """Run the workflow on measured ``data`` against the model (``geometry`` + ``effects``).

    Parameters
    ----------
    data : MeasuredData
    geometry : SpindleGeometry
        The model's geometry (the design already applied).
    effects : tuple of Effect
        The model's own effects.
    options : DiscrepancyOptions
    rng : numpy.random.Generator
        For the bootstrap null distributions.
    theta_bearings : tuple of str, optional
        Bearings with a stiffness factor (default all).
    """
    rng = require_rng(rng)
    t0 = time.perf_counter()
    if not options.use_identified and data.identified is not None:
        data = replace(data, identified=None)
    data, dropped = _drop_thin_impacts(data, options.min_impact_dof)
    one_x = [b for b in data.blocks if b.sweep.kind == "unbalance_1x"]
    if not one_x:
        raise ValueError("data: no 'unbalance_1x' block; the workflow needs 1x responses vs "
                         "speed")
    split = split_speeds(one_x[0].mean.shape[0], options.holdout_every,
                         options.extrapolate_fraction)
    planes = tuple(u.position_mm for u in geometry.unbalances)
    fm = ForwardModel(geometry, effects, data.channels, planes, theta_bearings,
                      options.nuisance.mass_disks)
    train, ho, held, base, runs = _recalibrate(fm, data, split, options)
    sel = select(train, base, library(options.library, fm.bearing_names), ho, options, rng,
                  data.soaks)
    stages, named, current, withheld = list(sel.stages), sel.named, sel.current, sel.withheld
    if not withheld:     # a withheld name decides the verdict; more draws could not change it
        stages[-1] = refined(train, stages[-1], options.alpha_residual / 3, rng)
    res = _conclude(data, train, (held, ho), split, base, current, tuple(stages), named,
                    sel.confounded, sel.generic, withheld, options, one_x[0].coord,
                    time.perf_counter() - t0, sel.soak)
    everything = _problem(fm, data, None, options.nuisance, runs)
    held_pts = split.interleaved | split.extrapolated
    gp = ((train, current.evaluation.residuals[0]) if res.verdict == "unnamed_residual"
          else None)
    return replace(res, run_scatter=tuple(
        float(v) for v in np.concatenate(list(runs[2].values())).std(axis=0, ddof=1))
        if runs else (),
                   curves=tuple(block_curves(everything, held_pts, base, current, gp)),
                   dropped_blocks=dropped, seconds=time.perf_counter() - t0)


def _conclude(data, train, holdout, split, base, final, stages, named, confounded, generic,
              withheld, options, speeds, seconds, soak=()) -> DiscrepancyResult:
    held, ho = holdout
    parts = {"interleaved": ho.interleaved, "extrapolated": ho.extrapolated}
    last = stages[-1]
    level = options.alpha_residual / 3
    residual = {"gof_chi2": final.chi2, "gof_dof": final.dof, "gof_p": last.gof_p,
                "structure": last.structure, "structure_p": last.structure_p,
                "generic": last.generic, "generic_p": last.generic_p, "threshold": level}
    ps = {"gof": (final.chi2, last.gof_p), "structure": (last.structure, last.structure_p),
          "generic": (last.generic, last.generic_p)}
    worst = min(ps, key=lambda k: ps[k][1])
    unexplained = ps[worst][1] <= level or bool(withheld)
    before = held_out_gap(train, held, parts, base)
    first = stages[0]
    partial: tuple[str, ...] = ()
    if unexplained:
        verdict = "unnamed_residual"
        partial = tuple(a.name for a in named + confounded + withheld)
        r_train = final.evaluation.residuals[0]
        after = held_out_gap(train, held, parts, final,
                             correction=lambda p: gp_correction(train, r_train, p))
        test = {"statistic": ps[worst][0], "p_value": ps[worst][1], "threshold": level,
                "kind": f"residual lack of fit ({worst})"}
        if withheld:
            test = _withheld_test(withheld, soak)
        effects, conf, generic = (), (), ()
    else:
        after = held_out_gap(train, held, parts, final)
        if confounded:
            verdict, effects, conf = "confounded", confounded, tuple(a.name for a in confounded)
        elif named:
            verdict, effects, conf = "named", named, ()
        else:
            verdict, effects, conf = "nothing_missing", (), ()
        lead = effects[0] if effects else max(first.assessments, key=lambda a: a.delta_chi2,
                                              default=None)
        test = {"statistic": lead.delta_chi2 if lead else 0.0,
                "p_value": lead.p_adjusted if lead else 1.0, "threshold": options.alpha,
                "kind": "likelihood ratio, bootstrap min-p over candidates",
                "candidate": lead.name if lead else None}
        if generic and lead is not None and lead.rival is not None:
            test["generic_rival"] = lead.rival.to_dict()    # the encompassing test, both ways
        by_soak = [t for t in soak if lead is not None and t.candidate == lead.name
                   and t.outcome == "drift"]
        if by_soak and effects:
            # the sweep alone could not tell it from its rivals; the soak did
            test["soak"] = by_soak[-1].to_dict()
    separating = "; ".join(t for t in (
        separating_test(list(conf)) if len(conf) > 1 else "",
        # a confounded set with a generic change: the experiment for the member carried (whose
        # rival the set holds); a withheld group: for its best-separated member
        _rival_separation(data, withheld or confounded[:1]) if withheld or generic else "")
        if t)
    return DiscrepancyResult(
        verdict, tuple(effects), conf, test, residual, before, after, stages, base, final, split,
        np.asarray(speeds), partial, separating, seconds, options,
        confounded_generic=generic, soak=tuple(soak))       # only a confounded set holds one


def _withheld_test(withheld: tuple[Assessment, ...], soak: tuple[SoakTest, ...]) -> dict:
    """The ``test`` of a group withheld at the first stage: the soak's test when it confirmed
    a member's drift (that member then fails a naming check: the soak separated it, the checks
    did not pass it) or rejected it; else the encompassing test against the closest generic
    change."""
    names = {a.name for a in withheld}
    for outcome, p_value, kind in (
            ("drift", "p_drift", "the thermal soak confirms the drift of {}, which fails a "
                                 "naming check"),
            ("no_drift", "p_below", "the thermal soak rejects the drift {} predicts "
                                    "(statistic: the drift in units of the prediction)")):
        t = next((t for t in soak if t.outcome == outcome and t.candidate in names), None)
        if t is not None:
            return {"statistic": t.beta, "p_value": getattr(t, p_value), "threshold": t.level,
                    "kind": "detected; " + kind.format(t.candidate), "soak": t.to_dict()}
    rivals = [a for a in withheld if a.rival is not None]
    rt = max((a.rival for a in rivals), key=lambda t: t.statistic)
    carried = (withheld[0] if withheld[0].rival is not None else rivals[0]).rival
    return {"statistic": rt.statistic, "p_value": rt.p_value, "threshold": rt.level,
            "kind": "detected, not separable from a generic local change "
                    f"(encompassing test; closest: {rt.rival})",
            # both ways, for the member the model would carry (the policy's): does its rival
            # add to its fit (no: explained alike)
            "rival_adds": carried.rival_adds, "mutual": carried.mutual}


def _drop_thin_impacts(data: MeasuredData, min_dof: int
                       ) -> tuple[MeasuredData, tuple[tuple[str, int], ...]]:
    """The data without impact blocks whose noise covariance has fewer than ``min_dof``
    degrees of freedom, and ``(name, dof)`` of those dropped (with a warning: the user's hits
    are not silently ignored) after those the reader left out already (the provenance's
    :data:`~.observables.THIN_IMPACTS`)."""
    thin = tuple((b.name, int(b.dof)) for b in data.blocks
                 if b.sweep.kind == "impact" and b.dof < min_dof)
    before = tuple((str(n), int(d)) for n, d in data.provenance.get(THIN_IMPACTS, ()))
    if not thin:
        return data, before
    warnings.warn(f"{len(thin)} impact block(s) left out: their noise covariance has "
                  f"{min(d for _, d in thin)}-{max(d for _, d in thin)} degrees of freedom, "
                  f"fewer than min_impact_dof = {min_dof} (hits per direction - 1); the "
                  "analysis uses the other blocks", stacklevel=3)
    keep = tuple(b for b in data.blocks if b.sweep.kind != "impact" or b.dof >= min_dof)
    return replace(data, blocks=keep), before + thin


def _rival_separation(data: MeasuredData, withheld: tuple[Assessment, ...]) -> str:
    """The experiment that would separate a withheld name: off-synchronous data if the data
    have none (impact tests at speed); else a thermal soak when the best-separated member
    drifts with temperature at a fixed speed (:data:`TEMPERATURE_DRIFT`) and its closest
    rival is a grounded spring beside a bearing it acts on — within one shaft diameter of it
    (:func:`~.generic.beside_bearings`; a constant stiffness there, with θ recalibrated, spans
    that bearing's speed law; a member on all bearings acts on every one); else a larger
    effect or more speeds (a soak does not separate a spring from an effect that does not
    drift, nor from one at the other bearing)."""
    at_speed = any(b.sweep.kind == "impact" and b.sweep.speed_rpm > 0 for b in data.blocks)
    if not at_speed:
        return RIVAL_SEPARATION
    if data.soaks:                     # a soak was run: its verdicts are in ``soak``
        return RIVAL_SEPARATION_AT_SPEED
    a = max((a for a in withheld if a.rival is not None), key=lambda a: a.rival.statistic,
            default=None)
    if a is None or a.name not in TEMPERATURE_DRIFT or not a.rival.rival.startswith(
            "grounded spring"):
        return RIVAL_SEPARATION_AT_SPEED
    beside = beside_names(a.rival.rival)
    scope = a.fit.slot.scope if a.fit is not None else ()
    if beside and (not scope or set(scope) & set(beside)):
        return RIVAL_SEPARATION_SPRING
    return RIVAL_SEPARATION_AT_SPEED


#: effects whose signature drifts as the spindle warms at a fixed speed (a preload growth
#: follows the rings' temperature difference), which a thermal soak separates from a constant
#: stiffness (``rivals.RIVAL_SEPARATION_SPRING``)
TEMPERATURE_DRIFT = ("thermal_preload",)
