"""Blind tests: a grid of hidden-effect scenarios, strengths defined by signal-to-noise, and
rates of correct and wrong answers for the workflow and both baselines.

**Strength** is not a parameter value: it is the whitened distance between the truth's
observables and the best recalibrated baseline model, ``z = √χ²_min`` on the noise-free
campaign's training points with the noise covariance of its means (:func:`~.synthetic.expected`)
— the part of the effect the recalibration cannot absorb, in units of noise, where the tests
look. ``sub-noise`` is ``z = 1``,
``marginal`` ``z = 4`` (about where a single 1-parameter test at the workflow's family-wise
level detects half the time), ``strong`` ``z = 12``. The effect's parameter that gives a target
``z`` is found by bisection on a reference assembly (θ = 1, nominal damping, permissible
unbalance in both planes); every scenario then draws its own assembly, and its realised ``z`` is
recorded. So the grid carries over to other effects, noise levels and campaigns.

**Outcomes** (:func:`score`): ``correct_name``, ``correct_confounded`` (the confounded set
holds the hidden effect), ``partial`` (some, not all, of two hidden effects named, no wrong
one), ``wrong_name``, ``false_alarm`` (something reported when nothing is hidden, or for an
absorbed effect), ``detected_unnamed`` (an ``unnamed_residual`` for a library effect),
``nothing`` (``nothing_missing``). For an effect outside the library, ``unnamed_residual`` and
``nothing_missing`` are right and any library name is wrong.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from surrogate_rbrdo.discrepancy.baselines import gp_baseline, sparse_baseline
from surrogate_rbrdo.discrepancy.calibration import _apply, _data_whitening, linearise
from surrogate_rbrdo.discrepancy.candidates import library
from surrogate_rbrdo.discrepancy.fit import fit
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.holdout import masks_for, split_speeds
from surrogate_rbrdo.discrepancy.problem import Problem
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
from surrogate_rbrdo.spindle.effects import EFFECTS, Effect
from surrogate_rbrdo.spindle.geometry import SpindleGeometry

#: target strengths z (whitened norm of what the recalibration cannot absorb)
STRENGTHS = {"sub-noise": 1.0, "marginal": 4.0, "strong": 12.0}


@dataclass(frozen=True)
class Hidden:
    """A hidden effect whose strength is set by one parameter, ``knob``.

    ``knob_limit`` is the knob's physical extreme (largest strength); ``reciprocal`` means the
    effect grows as the knob falls (a stiffness). ``truth_only`` effects are geometry changes
    from :data:`~.truth_effects.TRUTH_MODIFIERS`, not registry effects.
    """

    name: str
    knob: str
    knob_limit: float
    fixed: dict = field(default_factory=dict)
    reciprocal: bool = False
    truth_only: bool = False

    def apply(self, geometry: SpindleGeometry, effects: tuple[Effect, ...], value: float
              ) -> tuple[SpindleGeometry, tuple[Effect, ...]]:
        kw = {**self.fixed, self.knob: value}
        if self.truth_only:
            return TRUTH_MODIFIERS[self.name](geometry, **kw), effects
        return geometry, effects + (EFFECTS[self.name](**kw),)

    def value(self, s: float) -> float:
        """Knob value at strength coordinate ``s`` ∈ (0, 1] (1 = the physical extreme),
        geometric from 1e-6 of the extreme."""
        t = 1e-6 ** (1.0 - s)
        return self.knob_limit / t if self.reciprocal else self.knob_limit * t


#: the hidden effects of the default grid: the library's effects in a typical configuration
#: (both bearings; softening and preload growth quadratic in speed; a 20 kg housing stage) and
#: two effects outside the library
HIDDEN: dict[str, Hidden] = {
    "speed_softening": Hidden("speed_softening", "a", 0.9, {"exponent": 2.0}),
    "thermal_preload": Hidden("thermal_preload", "b", 3.0, {"q": 2.0}),
    "cross_coupling": Hidden("cross_coupling", "kappa", 0.5),
    "anisotropy": Hidden("anisotropy", "s", 0.5),
    "housing": Hidden("housing", "k_N_per_m", 1e6, {"m_kg": 20.0}, reciprocal=True),
    "gyroscopics": Hidden("gyroscopics", "g", 1.0),
    "unbalance_error": Hidden("unbalance_error", "epsilon", 5.0, {"delta_deg": 30.0}),
    "magnetic_pull": Hidden("magnetic_pull", "k_N_per_m", 1.5e8, truth_only=True),
    "shaft_stiffness_loss": Hidden("shaft_stiffness_loss", "depth", 0.9,
                                   {"position_mm": 250.0}, truth_only=True),
}


@dataclass(frozen=True)
class Context:
    """The model and the virtual campaign of a grid."""

    geometry: SpindleGeometry
    effects: tuple[Effect, ...]
    campaign: Campaign
    permissible_kgm: float
    options: DiscrepancyOptions = field(default_factory=DiscrepancyOptions)

    @property
    def planes(self) -> tuple[float, ...]:
        return tuple(u.position_mm for u in self.geometry.unbalances)

    def reference_assembly(self) -> Assembly:
        n = len(self.planes)
        return Assembly(np.ones(2), np.ones(len(self.geometry.bearings)),
                        np.full(n, self.permissible_kgm + 0j))

    def truth(self, hidden: tuple[tuple[Hidden, float], ...]) -> Truth:
        g, e = self.geometry, self.effects
        for h, v in hidden:
            g, e = h.apply(g, e, v)
        return Truth(g, e, planes_mm=self.planes,
                     provenance={"hidden": [{"name": h.name, h.knob: v, **h.fixed}
                                            for h, v in hidden]})


def strength(ctx: Context, hidden: tuple[tuple[Hidden, float], ...], noise: NoiseLevel,
             assembly: Assembly | None = None) -> float:
    """``z = √χ²_min``: the recalibrated baseline against the noise-free truth, on the
    training points of the workflow's split (what its tests see)."""
    asm = ctx.reference_assembly() if assembly is None else assembly
    data = expected(ctx.truth(hidden), asm, ctx.campaign, noise,
                    default_channels(ctx.geometry))
    fm = ForwardModel(ctx.geometry, ctx.effects, data.channels, ctx.planes,
                      mass_disks=ctx.options.nuisance.mass_disks)
    o = ctx.options
    split = split_speeds(len(ctx.campaign.speeds_rpm), o.holdout_every, o.extrapolate_fraction)
    prob = Problem(fm, data, masks_for(data, split, "train"), ctx.options.nuisance)
    par = prob.parametrisation()
    return math.sqrt(max(fit(prob, par, par.x0(), max_nfev=80).chi2, 0.0))


def calibrate(ctx: Context, h: Hidden, target: float, noise: NoiseLevel,
              *, tol: float = 0.05) -> tuple[float, float]:
    """Knob value whose strength is ``target`` (bisection on the strength coordinate) and the
    strength reached; the physical extreme if even that is weaker."""
    lo, hi = 0.0, 1.0
    z_hi = strength(ctx, ((h, h.value(hi)),), noise)
    if z_hi <= target:
        return h.value(hi), z_hi
    z = z_hi
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        z = strength(ctx, ((h, h.value(mid)),), noise)
        if abs(z - target) <= tol * target:
            return h.value(mid), z
        lo, hi = (mid, hi) if z < target else (lo, mid)
    return h.value(0.5 * (lo + hi)), z


@dataclass(frozen=True)
class Scenario:
    """One blind scenario: its class, hidden effects with knob values, noise and seed."""

    label: str
    strength: str
    hidden: tuple[tuple[Hidden, float], ...]
    noise_label: str
    noise: NoiseLevel
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


def run_scenario(ctx: Context, sc: Scenario) -> dict:
    """Simulate one scenario, run the workflow and both baselines; one result row."""
    rng = np.random.default_rng(sc.seed)
    r_asm, r_meas, r_wf = rng.spawn(3)
    asm = Assembly.draw(ctx.permissible_kgm, len(ctx.planes), len(ctx.geometry.bearings),
                        rng=r_asm)
    truth = ctx.truth(sc.hidden)
    data = measure(truth, asm, ctx.campaign, sc.noise, rng=r_meas,
                   channels=default_channels(ctx.geometry))
    res = find_discrepancy(data, ctx.geometry, ctx.effects, options=ctx.options, rng=r_wf)
    absorbed = frozenset(res.stages[0].absorbed) & sc.truth_names
    names = tuple(a.name for a in res.effects)
    fm = ForwardModel(ctx.geometry, ctx.effects, data.channels, ctx.planes,
                      mass_disks=ctx.options.nuisance.mass_disks)
    sv, snames = sparse_baseline(data, fm)
    gv = gp_baseline(res, ctx.options.alpha_residual)
    z = strength(ctx, sc.hidden, sc.noise, asm) if sc.hidden else 0.0
    return {
        "class": sc.label, "strength": sc.strength, "noise": sc.noise_label, "seed": sc.seed,
        "hidden": "+".join(f"{h.name}:{v:.4g}" for h, v in sc.hidden) or "none",
        "z_realised": z, "verdict": res.verdict, "names": "+".join(names),
        "outcome": score(sc.truth_names, sc.outside, absorbed, res.verdict, names),
        "gp_verdict": gv,
        "gp_outcome": score(sc.truth_names, sc.outside, absorbed, gv, ()),
        "sparse_verdict": sv, "sparse_names": "+".join(snames),
        "sparse_outcome": score(sc.truth_names, sc.outside, absorbed, sv, snames),
        "gap_before_chi2": res.gap_before.chi2_dof, "gap_after_chi2": res.gap_after.chi2_dof,
        "seconds": res.seconds,
    }


def noise_levels(base: NoiseLevel, factors: dict[str, float]) -> dict[str, NoiseLevel]:
    """Noise levels scaling every component of ``base``."""
    return {k: replace(base, **{f: getattr(base, f) * s for f in
                                ("additive_m", "gain", "phase_rad", "frf_additive",
                                 "k_relative")}) for k, s in factors.items()}


def signature_cosines(ctx: Context, noise: NoiseLevel) -> tuple[tuple[str, ...], np.ndarray]:
    """|cos| between candidates' signatures on the campaign's observables: their first-order
    change of the observables (all bearings, first shape start), whitened and with what the
    recalibration absorbs projected out — the confounds the data cannot separate."""
    data = expected(ctx.truth(()), ctx.reference_assembly(), ctx.campaign, noise,
                    default_channels(ctx.geometry))
    fm = ForwardModel(ctx.geometry, ctx.effects, data.channels, ctx.planes,
                      mass_disks=ctx.options.nuisance.mass_disks)
    prob = Problem(fm, data, nuisance=ctx.options.nuisance)
    par = prob.parametrisation()
    base = fit(prob, par, par.x0(), max_nfev=80)
    lin = linearise(prob, base, library(ctx.options.library, fm.bearing_names))
    W = _data_whitening(prob)
    N = _apply(W, lin.nuisance)
    Q, _ = np.linalg.qr(N)
    names, dirs = [], []
    for c, vs in lin.candidates:
        v = next((v for v in vs if v.scope == ()), vs[0])
        u = _apply(W, v.columns[:, :1])[:, 0]
        u = u - Q @ (Q.T @ u)
        names.append(c.name)
        dirs.append(u / np.linalg.norm(u))
    D = np.array(dirs)
    return tuple(names), np.abs(D @ D.T)
