"""Blind tests: a grid of hidden-effect scenarios, strengths defined by signal-to-noise, and
rates of correct and wrong answers for the workflow and both baselines.

**Strength** is not a parameter value: it is the whitened distance between the truth's
observables and the best recalibrated baseline model, ``z = √χ²_min``, on the noise-free
campaign's training points with the noise covariance of its means (a data source's
``expected``) — the part of the effect the recalibration cannot absorb, in units of noise, where
the tests look. ``sub-noise`` is ``z = 1``, ``marginal`` ``z = 4`` (about where a single
1-parameter test at the workflow's family-wise level detects half the time), ``strong``
``z = 12``. The effect's parameter that gives a target ``z`` is found by bisection on the
source's reference assembly; every scenario then draws its own assembly and noise, and its
realised ``z`` is recorded. So the grid carries over to other effects, noise levels and
campaigns.

**Outcomes** (:func:`score`): ``correct_name``, ``correct_confounded`` (the confounded set
holds the hidden effect), ``partial`` (some, not all, of two hidden effects named, no wrong
one), ``wrong_name``, ``false_alarm`` (something reported when nothing is hidden, or for an
absorbed effect), ``detected_unnamed`` (an ``unnamed_residual`` for a library effect),
``nothing`` (``nothing_missing``). For an effect outside the library, ``unnamed_residual`` and
``nothing_missing`` are right and any library name is wrong.

A **data source** has ``measure(geometry, effects, noise, seed) -> MeasuredData`` and
``expected(geometry, effects, noise) -> MeasuredData`` (noise-free means, the noise covariance
of the means); :class:`SyntheticSource` is the phasor-level stand-in of :mod:`.synthetic`,
the virtual rig's fast path plugs in the same way (``benchmarks/discrepancy_blind.py``).
"""

from __future__ import annotations

import math
import resource
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any, Protocol

import numpy as np

from surrogate_rbrdo.discrepancy.baselines import gp_baseline, sparse_baseline
from surrogate_rbrdo.discrepancy.calibration import linearise
from surrogate_rbrdo.discrepancy.fit import Fit, fit
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.holdout import masks_for, split_speeds
from surrogate_rbrdo.discrepancy.nuisance import NuisanceOptions
from surrogate_rbrdo.discrepancy.observables import MeasuredData
from surrogate_rbrdo.discrepancy.problem import Problem
from surrogate_rbrdo.discrepancy.rig_source import FACTORS, RigSource
from surrogate_rbrdo.discrepancy.rivals import damping_law_columns, rival_refit
from surrogate_rbrdo.discrepancy.synthetic import (
    Assembly,
    Campaign,
    NoiseLevel,
    Truth,
    default_channels,
    expected,
    measure,
)
from surrogate_rbrdo.discrepancy.truth_effects import TRUTH_MODIFIERS
from surrogate_rbrdo.discrepancy.workflow import DiscrepancyOptions, find_discrepancy
from surrogate_rbrdo.rig.impacts import ImpactPlan
from surrogate_rbrdo.rig.thermal import SoakPlan
from surrogate_rbrdo.spindle.effects import EFFECTS, Effect, with_effects
from surrogate_rbrdo.spindle.geometry import SpindleGeometry
from surrogate_rbrdo.spindle.reference import reference_spindle

#: target strengths z (whitened norm of what the recalibration cannot absorb)
STRENGTHS = {"sub-noise": 1.0, "marginal": 4.0, "strong": 12.0}


@dataclass(frozen=True)
class Hidden:
    """A hidden effect whose strength is set by one parameter, ``knob``.

    ``knob_limit`` is the knob's physical extreme (largest strength); ``reciprocal`` means the
    effect grows as the knob falls (a stiffness); ``knob_off`` is its off value when the effect
    grows away from a value other than 0 (a factor, off at 1); ``linked`` parameters are set to
    the knob times a factor (a second stiffness in a fixed ratio). ``truth_only`` effects are
    geometry changes from :data:`~.truth_effects.TRUTH_MODIFIERS`, not registry effects.
    """

    name: str
    knob: str
    knob_limit: float
    fixed: dict = field(default_factory=dict)
    reciprocal: bool = False
    truth_only: bool = False
    knob_off: float = 0.0
    linked: dict = field(default_factory=dict)

    def apply(self, geometry: SpindleGeometry, effects: tuple[Effect, ...], value: float
              ) -> tuple[SpindleGeometry, tuple[Effect, ...]]:
        kw = {**self.fixed, self.knob: value, **{p: value * f for p, f in self.linked.items()}}
        if self.truth_only:
            return TRUTH_MODIFIERS[self.name](geometry, **kw), effects
        return geometry, with_effects(effects, (EFFECTS[self.name](**kw),))

    def value(self, s: float) -> float:
        """Knob value at strength coordinate ``s`` ∈ (0, 1] (1 = the physical extreme),
        geometric from 1e-6 of the extreme's distance to the off value."""
        t = 1e-6 ** (1.0 - s)
        if self.reciprocal:
            return self.knob_limit / t
        return self.knob_off + (self.knob_limit - self.knob_off) * t


#: the hidden effects of the default grid: the library's effects in a typical configuration
#: (both bearings; softening and preload growth quadratic in speed; a 20 kg housing stage; a
#: tool interface with k_r/k_t as in docs/rig.md) and effects outside the library
HIDDEN: dict[str, Hidden] = {
    "speed_softening": Hidden("speed_softening", "a", 0.9, {"exponent": 2.0}),
    "thermal_preload": Hidden("thermal_preload", "b", 3.0, {"q": 2.0}),
    "cross_coupling": Hidden("cross_coupling", "kappa", 0.5),
    "anisotropy": Hidden("anisotropy", "s", 0.5),
    "housing": Hidden("housing", "k_N_per_m", 1e6, {"m_kg": 20.0}, reciprocal=True),
    "gyroscopics": Hidden("gyroscopics", "g", 1.0),
    "unbalance_error": Hidden("unbalance_error", "epsilon", 5.0, {"delta_deg": 30.0}),
    "magnetic_pull": Hidden("magnetic_pull", "k_N_per_m", 1.5e8, truth_only=True),
    "bearing_seal": Hidden("bearing_seal", "k_N_per_m", 1.5e8, truth_only=True),
    "shaft_stiffness_loss": Hidden("shaft_stiffness_loss", "depth", 0.9,
                                   {"position_mm": 250.0}, truth_only=True),
    "disk_mass_error": Hidden("disk_mass_error", "factor", 3.0, truth_only=True, knob_off=1.0),
}
if "tool_interface" in tuple(EFFECTS):  # registered by the rig's spindle effects
    # k_r / k_t as in docs/rig.md's example (5e6 N m/rad at 3e8 N/m)
    HIDDEN["tool_interface"] = Hidden("tool_interface", "k_t_N_per_m", 1e6, reciprocal=True,
                                      linked={"k_r_Nm_per_rad": 5e6 / 3e8})


class DataSource(Protocol):
    """Where scenario data come from (see module doc)."""

    def measure(self, geometry: SpindleGeometry, effects: tuple[Effect, ...], noise: str,
                seed: int) -> MeasuredData: ...

    def expected(self, geometry: SpindleGeometry, effects: tuple[Effect, ...],
                 noise: str) -> MeasuredData: ...


@dataclass(frozen=True)
class SyntheticSource:
    """The phasor-level stand-in (:mod:`.synthetic`): a drawn assembly per seed, 1x records,
    impact FRFs and identified stiffness with the noise of ``noise_levels[noise]``."""

    campaign: Campaign
    noise_levels: dict[str, NoiseLevel]
    permissible_kgm: float
    planes_mm: tuple[float, ...]

    def _truth(self, geometry, effects) -> Truth:
        return Truth(geometry, effects, planes_mm=self.planes_mm)

    def measure(self, geometry, effects, noise, seed) -> MeasuredData:
        r_asm, r_meas = np.random.default_rng(seed).spawn(2)
        asm = Assembly.draw(self.permissible_kgm, len(self.planes_mm), 2, rng=r_asm)
        return measure(self._truth(geometry, effects), asm, self.campaign,
                       self.noise_levels[noise], rng=r_meas, channels=default_channels(geometry))

    def expected(self, geometry, effects, noise) -> MeasuredData:
        n = len(self.planes_mm)
        asm = Assembly(np.ones(2), np.ones(2), np.full(n, self.permissible_kgm / n + 0j))
        return expected(self._truth(geometry, effects), asm, self.campaign,
                        self.noise_levels[noise], default_channels(geometry))


@dataclass(frozen=True)
class Context:
    """The model, the data source and the workflow's options of a grid."""

    geometry: SpindleGeometry
    effects: tuple[Effect, ...]
    source: Any
    options: DiscrepancyOptions = field(default_factory=DiscrepancyOptions)

    @property
    def planes(self) -> tuple[float, ...]:
        return tuple(u.position_mm for u in self.geometry.unbalances)

    def truth(self, hidden: tuple[tuple[Hidden, float], ...]
              ) -> tuple[SpindleGeometry, tuple[Effect, ...]]:
        g, e = self.geometry, self.effects
        for h, v in hidden:
            g, e = h.apply(g, e, v)
        return g, e

    def forward(self, data: MeasuredData) -> ForwardModel:
        return ForwardModel(self.geometry, self.effects, data.channels, self.planes,
                            mass_disks=self.options.nuisance.mass_disks)


def rig_context(*, impacts: bool = True, soak: bool = True, n_draws: int = 400) -> Context:
    """The benchmarks' rig context: the reference spindle at its baseline design as the model,
    the virtual rig's data (:class:`~.rig_source.RigSource`: 50 speeds 1 000–24 000 rpm, 20
    runs, the noise levels of :data:`~.rig_source.FACTORS`; the impact plan unless
    ``impacts=False``; the thermal soak of ``rig.thermal.SoakPlan`` unless ``soak=False``)
    and the probe-chain nuisance."""
    sp = reference_spindle()
    speeds = tuple(np.linspace(1000.0, 24000.0, 50).tolist())
    source = RigSource(speeds, 20, FACTORS, impacts=ImpactPlan() if impacts else None,
                       soak=SoakPlan() if soak else None)
    return Context(sp.geometry_for(sp.baseline), sp.effects, source, DiscrepancyOptions(
        nuisance=NuisanceOptions.probe_chain(), n_draws=n_draws))


def _recalibrated(ctx: Context, hidden: tuple[tuple[Hidden, float], ...], noise: str
                  ) -> tuple[Problem, Fit, float]:
    """The training problem on the noise-free truth, the recalibrated baseline's fit, and
    ``z``."""
    data = ctx.source.expected(*ctx.truth(hidden), noise)
    o = ctx.options
    one_x = next(b for b in data.blocks if b.sweep.kind == "unbalance_1x")
    split = split_speeds(one_x.mean.shape[0], o.holdout_every, o.extrapolate_fraction)
    prob = Problem(ctx.forward(data), data, masks_for(data, split, "train"), o.nuisance)
    par = prob.parametrisation()
    f = fit(prob, par, par.x0(), max_nfev=80)
    return prob, f, math.sqrt(max(f.chi2 - float(np.sum(par.prior_residuals(f.x) ** 2)), 0.0))


def strength(ctx: Context, hidden: tuple[tuple[Hidden, float], ...], noise: str) -> float:
    """``z = √χ²_min``: the recalibrated baseline against the noise-free truth, on the
    training points of the workflow's split (what its tests see)."""
    return _recalibrated(ctx, hidden, noise)[2]


def separable_strength(ctx: Context, hidden: tuple[tuple[Hidden, float], ...], noise: str
                       ) -> tuple[float, float, str]:
    """``(z, z_sep, rival)``: the strength and the part of it no single generic local change
    explains — ``z_sep`` is the norm of the data's whitened residual left after the first-order
    refit of the generic rival of :mod:`.rivals` that reduces the χ² most (inside its plausible
    range and sign, the nuisance refitted with it, a damping speed law included), on the
    noise-free truth. Like ``z``, it counts the data rows only (the priors' pseudo-observations
    move with the refit but are not signal).

    A hidden effect with small ``z_sep`` is one the workflow's encompassing test cannot
    tell from that rival whatever its ``z`` (a preload growth beside a passive spring at its
    bearing's node, ``rivals`` module doc): the name is withheld by design, so ``z`` alone
    overstates how nameable a "strong" effect is. This is first order, so for a strong
    nonlinear effect a diagnostic, not a bound.
    """
    prob, f, z = _recalibrated(ctx, hidden, noise)
    lin = linearise(prob, f, ())
    _, rival, left = rival_refit(prob, lin, f.evaluation.residuals[0],
                                 damping_law_columns(prob, lin, f.par.names))
    return z, float(np.linalg.norm(left[:prob.n_data])), rival


def separable(ctx: Context, hidden: tuple[tuple[Hidden, float], ...], noise: str) -> float:
    """``z_sep`` of :func:`separable_strength` alone (a ``measure`` for :func:`calibrate`)."""
    return separable_strength(ctx, hidden, noise)[1]


def calibrate(ctx: Context, h: Hidden, target: float, noise: str,
              *, tol: float = 0.05,
              measure: Callable[[Context, tuple[tuple[Hidden, float], ...], str], float]
              = strength) -> tuple[float, float]:
    """Knob value whose strength is ``target`` (bisection on the strength coordinate) and the
    strength reached; the physical extreme if even that is weaker. ``measure`` is what
    "strength" means: :func:`strength` (``z``, the default) or :func:`separable` (``z_sep``,
    the part of ``z`` no generic rival explains)."""
    lo, hi = 0.0, 1.0
    z = measure(ctx, ((h, h.value(hi)),), noise)
    if z <= target:
        return h.value(hi), z
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        z = measure(ctx, ((h, h.value(mid)),), noise)
        if abs(z - target) <= tol * target:
            return h.value(mid), z
        lo, hi = (mid, hi) if z < target else (lo, mid)
    return h.value(0.5 * (lo + hi)), z


@dataclass(frozen=True)
class Scenario:
    """One blind scenario: its class, hidden effects with knob values, noise label and seed."""

    label: str
    strength: str
    hidden: tuple[tuple[Hidden, float], ...]
    noise: str
    seed: int

    @property
    def truth_names(self) -> frozenset[str]:
        return frozenset(h.name for h, _ in self.hidden if not h.truth_only)

    @property
    def outside(self) -> bool:
        return any(h.truth_only for h, _ in self.hidden)


def score(truth: frozenset[str], outside: bool, absorbed: frozenset[str], verdict: str,
          names: tuple[str, ...]) -> str:
    """Outcome label of one answer (module doc). ``absorbed``: hidden effects the
    recalibration absorbs entirely (nothing is the right answer for them).

    >>> score(frozenset({"housing"}), False, frozenset(), "named", ("housing",))
    'correct_name'
    >>> score(frozenset(), True, frozenset(), "named", ("housing",))
    'wrong_name'
    """
    visible = truth - absorbed
    got = set(names)
    if verdict == "named":
        if got - visible:
            return "wrong_name"
        return "correct_name" if got == visible else "partial"
    if verdict == "confounded":
        return "correct_confounded" if got & visible else "wrong_name"
    if verdict == "unnamed_residual":
        return "detected_unnamed" if (visible or outside) else "false_alarm"
    return "nothing"


def run_scenario(ctx: Context, sc: Scenario) -> dict[str, Any]:
    """Simulate one scenario, run the workflow and both baselines; one result row
    (``seconds``: the workflow's wall time; ``cpu_seconds``: the process's CPU time for the
    whole row, which a machine shared with other jobs does not inflate; ``peak_rss_mb``: the
    peak resident memory of the process that ran it so far, a worker's with joblib)."""
    cpu0 = time.process_time()
    data = ctx.source.measure(*ctx.truth(sc.hidden), sc.noise, sc.seed)
    res = find_discrepancy(data, ctx.geometry, ctx.effects, options=ctx.options,
                           rng=np.random.default_rng([sc.seed, 7]))
    absorbed = frozenset(res.stages[0].absorbed) & sc.truth_names
    names = tuple(a.name for a in res.effects)
    if data.identified is not None:
        sv, snames = sparse_baseline(data, ctx.forward(data))
    else:
        sv, snames = "not_run", ()
    gv = gp_baseline(res, ctx.options.alpha_residual)
    return {
        "class": sc.label, "strength": sc.strength, "noise": sc.noise, "seed": sc.seed,
        "hidden": "+".join(f"{h.name}:{v:.4g}" for h, v in sc.hidden) or "none",
        "verdict": res.verdict, "names": "+".join(names),
        "outcome": score(sc.truth_names, sc.outside, absorbed, res.verdict, names),
        "gp_verdict": gv, "gp_outcome": score(sc.truth_names, sc.outside, absorbed, gv, ()),
        "sparse_verdict": sv, "sparse_names": "+".join(snames),
        "sparse_outcome": (score(sc.truth_names, sc.outside, absorbed, sv, snames)
                           if sv != "not_run" else "not_run"),
        "statistic": res.test["statistic"], "p_value": res.test["p_value"],
        "gap_before_chi2": res.gap_before.chi2_dof, "gap_after_chi2": res.gap_after.chi2_dof,
        "gof_p": res.residual_test["gof_p"],
        # a library effect and a generic change explain the data alike (rivals.RivalTest)
        "mutual_generic": bool(res.test.get("mutual", False) or res.confounded_generic),
        # the thermal soak's verdicts (discrepancy.soak): candidate:outcome
        "soak": "+".join(f"{t.candidate}:{t.outcome}" for t in res.soak),
        "parameters": "; ".join(f"{a.name} {a.fit.parameters}" for a in res.effects if a.fit),
        "seconds": res.seconds, "cpu_seconds": time.process_time() - cpu0,
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }


def rates(rows: list[dict[str, Any]], column: str = "outcome") -> dict[tuple[str, str], dict]:
    """Per (class, strength): the number of scenarios and the fraction of each outcome."""
    groups: dict[tuple[str, str], list[str]] = {}
    for r in rows:
        groups.setdefault((r["class"], r["strength"]), []).append(r[column])
    return {k: {"n": len(v), **{o: c / len(v) for o, c in Counter(v).items()}}
            for k, v in groups.items()}


def noise_levels(base: NoiseLevel, factors: dict[str, float]) -> dict[str, NoiseLevel]:
    """Synthetic noise levels scaling every component of ``base``."""
    return {k: replace(base, **{f: getattr(base, f) * s for f in
                                ("additive_m", "gain", "phase_rad", "frf_additive",
                                 "k_relative")}) for k, s in factors.items()}
