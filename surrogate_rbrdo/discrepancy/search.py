"""Fit each candidate effect on what the recalibration cannot absorb.

For a candidate, every bearing scope and shape start is screened first: the strength is stepped
along a geometric grid from the off state to its physical bound with the nuisance held at its
recalibrated value and what the recalibration absorbs to first order projected out (one
batched evaluation). The best start of every scope is then refined by a short bounded fit of
the nuisance and the candidate's parameters together (the recalibration moves far when an
effect is strong, so a screen at the base nuisance cannot choose the scope), and the best of
these is fitted to convergence.

**A stretched recalibration** (:func:`stretched`). When the recalibration holds a nuisance
parameter on a bound of its range — a stiffness or damping factor at the end of its physical
range, a probe gain 6 prior SDs off — the model's own parameters have absorbed a discrepancy
they cannot represent, and a strong effect's fit started there stays in the recalibration's
basin. On the rig's 1x data with a hidden softening of 20 % at 24 000 rpm on both bearings
(``a = 0.2``, exponent 2; default noise, seed 12) the recalibration ends with both stiffness
factors at 1.5 and both damping factors at 0.25 (χ² 488 539 on 445 observations); every fit of
the softening from there — even from the truth's own ``a`` and exponent — returns ``a = 0``,
and the best scope ended at χ² 1 079 (rear bearing alone), while from the nuisance's prior mean
the softening on both bearings reaches χ² 358 at ``a = 0.201``, exponent 2.00. So when the
base is stretched every scope's best start is also screened with the nuisance at its prior
mean (nothing projected out) and short-fitted from there, as the recalibration itself is
started (:func:`fit_nuisance`); an unstretched base costs nothing more. With a stretched 1x
recalibration the continuation in the data carries every scope's 1x fit, each with its valley
(:func:`warm_fits`): the 1x data of a strong effect often fit one bearing as well as both.

**Continuation in the data** (:class:`Warm`). When the data hold sharper observables than the
1x responses — impact FRFs, whose lightly damped peaks sit between lines 40 Hz apart — the χ²
of a gross effect that moves the modes is rugged in its parameters: a housing stage's χ²
changes by a factor of ten between k = 5.5e8 and 6e8 N/m, so neither a grid of starts nor a
first-order screen lands in the right well. The 1x responses vary smoothly with the
parameters (a response vs speed, not lines past a peak), so the candidate is first searched
on the 1x blocks alone (the same screening and fits) and that fit starts one more fit on all
the data, with the nuisance only the other blocks see (the force channel, the impact run's
bearing state) at its prior mean: its recalibrated value has absorbed part of the missing
effect. This is the usual order of model updating, smooth data first and the sharp data from
there (a homotopy in the data, cf. Friswell & Mottershead 1995, *Finite Element Model
Updating in Structural Dynamics*); it needs nothing of the effect but its class.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.stats import chi2

from surrogate_rbrdo.discrepancy.candidates import Candidate
from surrogate_rbrdo.discrepancy.fit import Fit, fit, fit_batch
from surrogate_rbrdo.discrepancy.nuisance import Slot
from surrogate_rbrdo.discrepancy.problem import Problem

#: screened strengths per start (geometric from 1e-4 of the range, or 1e-11 m/N, to the bound)
N_SCREEN = 12
#: residual evaluations of the short fit from each scope's start (the best is then finished)
SHORT_NFEV = 25
#: the 1x valley (:func:`valley`): profile points per decade of the first shape parameter,
#: decades below its bound, points improved on all the data, and starts kept from them
VALLEY_PER_DECADE = 24
VALLEY_DECADES = 3
VALLEY_LM = 16
VALLEY_KEEP = 2
#: residual evaluations of each 1x fit along the valley (each starts at its neighbour's)
VALLEY_NFEV = 15


@dataclass(frozen=True)
class CandidateFit:
    """A candidate's best fit on top of a base model.

    Attributes
    ----------
    name : str
    slot : Slot
        Scope and fixed shapes of the best start.
    fit : Fit
    delta_chi2 : float
        Base χ² minus this fit's χ² (≥ 0).
    parameters : dict
        The effect's parameters (its own units; reciprocals undone; ``bearings``).
    ci : dict
        95 % Wald intervals of the fitted parameters (own units).
    at_bound : bool
        A strength parameter sits on its physical bound (not the off state) and the data
        want it beyond (:func:`bound_score` above :data:`BOUND_SCORE`), or a shape
        parameter on a bound other than a natural zero (a massless, undamped housing is
        physical; a softening exponent at the end of its range means the law is stretched).
    significant : bool
        Some strength's interval, conditional on the fitted shapes, excludes the off state
        (the effect is on).
    held : tuple of str
        Shape parameters :func:`~.holds.interior` held inside their range (in ``slot.fixed``): their
        values were chosen from the data.
    """

    name: str
    slot: Slot
    fit: Fit
    delta_chi2: float
    parameters: dict
    ci: dict
    at_bound: bool
    significant: bool
    held: tuple[str, ...] = ()

    @property
    def n_fitted(self) -> int:
        """Parameters chosen from the data: the free ones and the shapes held by
        :func:`~.holds.interior` (a likelihood-ratio threshold's degrees of freedom)."""
        return len(self.slot.free) + len(self.held)

    @property
    def effect(self):
        vals = self.fit.par.slot_values(self.fit.x)[-1]
        return self.slot.candidate.effect(self.slot.scope, vals)


def screen_values(c: Candidate) -> np.ndarray:
    """Strength values (first strength parameter) tried from the off state outwards."""
    lo, hi, off, rec = c.lower[0], c.upper[0], c.off[0], c.reciprocal[0]
    if rec:
        top = hi if math.isfinite(hi) else 1e-6
        return np.geomspace(1e-11, top, N_SCREEN)
    span = hi - lo
    pos = off + np.geomspace(1e-4 * span, hi - off, N_SCREEN) if hi > off else np.zeros(0)
    neg = off - np.geomspace(1e-4 * span, off - lo, N_SCREEN) if off > lo else np.zeros(0)
    return np.concatenate([pos, neg])


def screen(problem: Problem, base: Fit, c: Candidate, at: np.ndarray | None = None,
           scope: tuple[str, ...] | None = None) -> list[tuple[float, Slot, dict[str, float]]]:
    """χ² of every (scope, shape start, strength) with the nuisance at ``base`` and what its
    recalibration absorbs to first order projected out (the residual orthogonal to the base
    fit's Jacobian): returns ``(χ², slot, start values)`` sorted, best first. With ``at``
    (values of ``base``'s parameters, :func:`cold_start`) the nuisance is held there instead
    and nothing is projected out (the recalibration's absorption is what ``at`` undoes); with
    ``scope`` only that bearing scope is screened."""
    par0 = base.par
    xb = base.x if at is None else at
    rows, meta = [], []
    shapes = [[]]
    for p, starts in zip(c.shape, c.shape_starts, strict=True):
        shapes = [s + [(p, v)] for s in shapes for v in starts]
    for sc in (c.scopes if scope is None else (scope,)):
        for shape in shapes:
            slot = Slot(c, sc)
            par = par0.with_slots(par0.slots + (slot,))
            for v in screen_values(c):
                start = {f"{slot.label}.{p}": val for p, val in shape}
                start[f"{slot.label}.{c.strength[0]}"] = float(v)
                x = par.x0(start)
                x[:xb.size] = xb
                rows.append(x)
                meta.append((slot, start, par))
    out = []
    # what the recalibration absorbs, to first order: the span of the base fit's Jacobian
    Q, _ = (np.linalg.qr(base.jac) if base.jac.size and at is None
            else (np.zeros((base.jac.shape[0], 0)), 0))
    by_par: dict[int, list[int]] = {}
    for i, (_, _, par) in enumerate(meta):
        by_par.setdefault(id(par), []).append(i)
    for idx in by_par.values():
        par = meta[idx[0]][2]
        r = problem.evaluate(par, np.array([rows[i] for i in idx])).residuals
        r = r - (r @ Q) @ Q.T
        chi = np.sum(r**2, axis=1)
        out += [(float(chi[k]), meta[i][0], meta[i][1]) for k, i in enumerate(idx)]
    return sorted(out, key=lambda t: t[0])


@dataclass(frozen=True)
class Warm:
    """The base model on the 1x blocks alone (:func:`warm_base`), where a candidate is first
    searched when the data also hold impact FRFs (module doc)."""

    problem: Problem
    base: Fit


def warm_base(problem: Problem, base: Fit, *, max_nfev: int = 60) -> Warm | None:
    """The recalibration of ``base`` refitted on ``problem``'s 1x blocks alone, or None when
    the problem has no other blocks (nothing to continue to) or no 1x block."""
    sub = _one_x_part(problem)
    if sub is None:
        return None
    par = sub.parametrisation().with_slots(base.par.slots)
    return Warm(sub, fit(sub, par, transfer(base.par, base.x, par, par.x0()),
                         max_nfev=max_nfev))


def fit_nuisance(problem: Problem, *, max_nfev: int = 60) -> Fit:
    """The recalibration of the model's own parameters on ``problem`` (no effect): fitted
    from the prior means and, when the data also hold impact FRFs, from the recalibration on
    the 1x blocks alone (the continuation in the data of the module doc, the nuisance only
    the FRFs see at its prior mean); the lower χ² is kept.

    The FRFs' χ² is rugged in the nuisance too: on the rig's high-noise null draw 1399883758
    the fit from the prior means ended at χ² 89 143 with both damping factors, three probe
    gains, the tool mass and the hammer gain on their bounds, the fit from the 1x
    recalibration at 2 398 (2 585 observations) near the truth's draws (``docs/discrepancy.md``,
    Method, step 2).
    """
    par = problem.parametrisation()
    best = fit(problem, par, par.x0(), max_nfev=max_nfev)
    sub = _one_x_part(problem)
    if sub is None:
        return best
    ps = sub.parametrisation()
    warm = fit(sub, ps, ps.x0(), max_nfev=max_nfev)
    other = fit(problem, par, transfer(ps, warm.x, par, par.x0()), max_nfev=max_nfev)
    return other if other.chi2 < best.chi2 else best


def _one_x_part(problem: Problem) -> Problem | None:
    """``problem`` on its 1x blocks alone, or None when it has no 1x block or nothing else
    (no sharper data to continue to)."""
    kinds = {b.sweep.kind for b in problem.blocks}
    if "unbalance_1x" not in kinds or kinds == {"unbalance_1x"}:
        return None
    return problem.only("unbalance_1x")


def transfer(src, x: np.ndarray, dst, fill: np.ndarray) -> np.ndarray:
    """The values of ``x`` (parametrisation ``src``) in parametrisation ``dst``, by name; a
    parameter ``src`` lacks takes its value from ``fill``."""
    d = dict(zip(src.names, x, strict=True))
    return np.array([d.get(n, f) for n, f in zip(dst.names, fill, strict=True)], dtype=float)


def on_bound(v: float, bounds: tuple[float, float]) -> bool:
    """Whether a shape value sits on a bound of its range that is not a natural zero."""
    return any(e != 0 and abs(v - e) <= 1e-6 * abs(e) for e in bounds)


def fit_candidate(problem: Problem, base: Fit, c: Candidate,
                  extra_starts: list[tuple[Slot, dict[str, float]]] = (),
                  *, max_nfev: int = 60, warm: Warm | None = None,
                  scope: tuple[str, ...] | None = None) -> CandidateFit:
    """Best fit of candidate ``c`` on top of ``base`` (see module doc); with ``warm`` one more
    start comes from the candidate's fit on the 1x blocks alone (from every scope's when the
    1x recalibration is :func:`stretched`); with ``scope`` only that bearing scope is tried.
    A fit whose shape ends on a bound is tried inside by :func:`~.holds.interior`."""
    par0 = base.par

    def at_base(slot: Slot, st: dict[str, float], xb: np.ndarray = base.x
                ) -> tuple[Slot, np.ndarray]:
        x0 = par0.with_slots(par0.slots + (slot,)).x0(st)
        x0[:xb.size] = xb
        return slot, x0

    def best_per_scope(at: np.ndarray | None) -> list[tuple[Slot, np.ndarray]]:
        out, seen = [], set()
        for _, s, st in screen(problem, base, c, at=at, scope=scope):
            if s.scope not in seen:
                seen.add(s.scope)
                out.append(at_base(s, st, base.x if at is None else at))
        return out

    starts = best_per_scope(None)                    # best start of every scope
    if stretched(base):                              # and from the nuisance's prior mean
        starts += best_per_scope(cold_start(base))
    starts += [at_base(s, st) for s, st in extra_starts if scope in (None, s.scope)]
    if warm is not None:
        for cw in warm_fits(warm, c, max_nfev):
            par = par0.with_slots(par0.slots + (cw.slot,))
            starts.append((cw.slot, transfer(cw.fit.par, cw.fit.x, par, par.x0())))
            starts += [(cw.slot, x) for x in valley(problem, warm, cw, par)]
    best: Fit | None = None
    best_slot = None
    for slot, x0 in starts:
        par = par0.with_slots(par0.slots + (slot,))
        f = fit(problem, par, x0, max_nfev=SHORT_NFEV if len(starts) > 1 else max_nfev)
        if best is None or f.chi2 < best.chi2:
            best, best_slot = f, slot
    if len(starts) > 1:                              # finish the best start
        best = fit(problem, best.par, best.x, max_nfev=max_nfev, start=best)
    return describe(c, best_slot, best, base.chi2)


def warm_fits(warm: Warm, c: Candidate, max_nfev: int) -> list[CandidateFit]:
    """The candidate's fits on the 1x blocks alone that start the continuation in the data:
    the best one, or — when the 1x recalibration is :func:`stretched` (a strong effect) — the
    best of every bearing scope. The 1x responses of a strong effect often fit as well on one
    bearing as on both (a 20 kg housing stage of 6e8 N/m on both bearings of the rig: χ² 398.5
    on both, 397.8 on the front one alone, 445 observations), while the FRFs tell them apart
    (2 494 on both, 16 023 on the front alone, 2 585 observations): the scope the 1x data
    prefer by noise must not decide which valley is searched."""
    if not stretched(warm.base):
        return [fit_candidate(warm.problem, warm.base, c, max_nfev=max_nfev)]
    return [fit_candidate(warm.problem, warm.base, c, max_nfev=max_nfev, scope=s)
            for s in c.scopes]


def stretched(base: Fit) -> bool:
    """Whether the recalibration ``base`` holds a nuisance parameter on a bound of its range
    (a stiffness or damping factor at the end of its physical range, a priored parameter
    6 prior SDs from its mean): the model's own parameters have absorbed a discrepancy they
    cannot represent, and their values are a poor start for the effect that causes it
    (:func:`fit_candidate`, module doc)."""
    n = base.par.n_nuisance
    lo, hi = base.par.bounds()
    x = base.x[:n]
    tol = 1e-6 * np.maximum(np.abs(hi[:n] - lo[:n]), 1e-30)
    return bool(np.any((x - lo[:n] <= tol) | (hi[:n] - x <= tol)))


def cold_start(base: Fit) -> np.ndarray:
    """``base``'s parameters with the nuisance at its prior mean (effects already in the
    model keep their fitted values)."""
    x = base.x.copy()
    n = base.par.n_nuisance
    x[:n] = base.par.x0()[:n]
    return x


def valley(problem: Problem, warm: Warm, cw: CandidateFit, par) -> list[np.ndarray]:
    """Starts on all the data from the valley the 1x data leave open (module doc).

    The 1x responses often fix a combination of a candidate's parameters only (a housing
    stage's k/m); along that valley the sharper data decide. The candidate's first shape
    parameter is stepped over its range (:data:`VALLEY_PER_DECADE` points per decade,
    :data:`VALLEY_DECADES` decades below its bound, and its lower bound), each point refitted
    on the 1x blocks from its neighbour's fit (a continuation, up and down from ``cw``); every
    point is carried to all the data (``par``) with the nuisance the 1x data do not see at its
    prior mean, the best :data:`VALLEY_LM` are improved by a few batched Levenberg–Marquardt
    steps (:func:`~.fit.fit_batch`: the nuisance and shapes the 1x data cannot fix re-solved
    per point) and the best :data:`VALLEY_KEEP` returned. None for a candidate without shape
    parameters."""
    c = cw.slot.candidate
    grid = valley_grid(c)
    if grid.size == 0:
        return []
    p = c.shape[0]
    i0 = int(np.searchsorted(grid, cw.parameters[p]))
    label = cw.slot.label
    rows = []
    for seq in (grid[i0:], grid[:i0][::-1]):
        prev = cw.fit
        for v in seq:
            slot = Slot(c, cw.slot.scope, ((p, float(v)),))
            p1 = warm.base.par.with_slots(warm.base.par.slots + (slot,))
            prev = fit(warm.problem, p1, transfer(prev.par, prev.x, p1, p1.x0()),
                       max_nfev=VALLEY_NFEV)
            rows.append(transfer(prev.par, prev.x, par, par.x0({f"{label}.{p}": float(v)})))
    X = np.array(rows)
    chi = problem.evaluate(par, X).chi2
    X, chi = fit_batch(problem, par, X[np.argsort(chi)[:VALLEY_LM]])
    return list(X[np.argsort(chi)[:VALLEY_KEEP]])


def valley_grid(c: Candidate, per_decade: int = VALLEY_PER_DECADE) -> np.ndarray:
    """The values of ``c``'s first shape parameter the valley steps through: ``per_decade``
    points per decade from :data:`VALLEY_DECADES` decades below its upper bound (or its lower
    bound) to the bound, and the lower bound; empty for a candidate without shape parameters
    or with an unbounded one.

    >>> from surrogate_rbrdo.discrepancy.candidates import candidate
    >>> g = valley_grid(candidate("housing", ("front", "rear")), per_decade=2)
    >>> g.round(3).tolist()
    [0.0, 0.25, 0.791, 2.5, 7.906, 25.0, 79.057, 250.0]
    """
    if not c.shape:
        return np.zeros(0)
    a, b = c.shape_bounds[0]
    if not math.isfinite(b) or b <= 0:
        return np.zeros(0)
    lo = max(a, b * 10.0**-VALLEY_DECADES)
    grid = np.geomspace(lo, b, max(int(per_decade * math.log10(b / lo)), 2) + 1)
    return np.unique(np.concatenate([[a], grid])) if a < lo else grid


@dataclass(frozen=True)
class SlotEstimate:
    """One effect's parameters in a fit, with their intervals.

    Attributes
    ----------
    parameters : dict
        Own units (reciprocals undone; ``bearings`` when scoped).
    ci : dict
        95 % Wald intervals (own units); ``None`` for a strength parameter that is not
        identified.
    identified : dict
        Per fitted parameter: ``False`` for a strength whose interval contains its off state
        (zero, or a rigid interface for a compliance). Such an estimate sits on or near the
        boundary of its range, where the Wald interval is not valid (Self & Liang 1987, JASA
        82:605): the data cannot tell the parameter from off, so no interval is reported.
    at_bound, significant : bool
        As :class:`CandidateFit`.
    """

    parameters: dict
    ci: dict
    identified: dict
    at_bound: bool
    significant: bool


def slot_estimate(f: Fit, index: int) -> SlotEstimate:
    """Parameters and intervals of slot ``index`` of fit ``f`` (see :class:`SlotEstimate`)."""
    slots = f.par.slots
    slot, c = slots[index], slots[index].candidate
    k0 = f.par.n_nuisance + sum(len(s.free) for s in slots[:index])
    lo_ci, hi_ci = f.wald_ci()
    # significance is judged conditional on the fitted shapes: a shape parameter is not
    # identified when the strength is small, and its correlation with the strength would
    # otherwise blow the strength's interval up (the reported intervals are unconditional)
    shape = np.zeros(f.x.size, dtype=bool)
    shape[k0:k0 + len(slot.free)] = [p not in c.strength for p in slot.free]
    lo_s, hi_s = f.wald_ci(fixed=shape)
    params = c.physical(f.par.slot_values(f.x)[index])
    ci, identified, at_bound, significant = {}, {}, False, False
    for i, p in enumerate(slot.free):
        a, b = float(lo_ci[k0 + i]), float(hi_ci[k0 + i])
        x = f.x[k0 + i]
        identified[p] = True
        if p in c.strength:
            j = c.strength.index(p)
            off, lo, hi = c.off[j], c.lower[j], c.upper[j]
            edge = hi if x > off else lo
            if edge != off and abs(x - edge) <= 1e-6 * max(abs(edge), 1e-30):
                at_bound |= bound_score(f, k0 + i, 1.0 if edge > off else -1.0) > BOUND_SCORE
            significant |= not (lo_s[k0 + i] <= off <= hi_s[k0 + i])
            identified[p] = not (a <= off <= b)
            if c.reciprocal[j]:
                a, b = (math.inf if b <= 0 else 1 / b), (math.inf if a <= 0 else 1 / a)
        else:                          # a shape pinned at a bound that is not a natural zero
            at_bound |= on_bound(x, c.shape_bounds[c.shape.index(p)])
        ci[p] = [a, b] if identified[p] else None
    if slot.scope:
        params["bearings"] = list(slot.scope)
    return SlotEstimate(params, ci, identified, at_bound, significant)


#: χ²₁ 99 %: a strength on its physical bound makes a fit unphysical only if relaxing the
#: bound would lower χ² by more than this (:func:`bound_score`)
BOUND_SCORE = float(chi2.isf(0.01, 1))


def bound_score(f: Fit, k: int, outward: float) -> float:
    """The score (Lagrange-multiplier) statistic of parameter ``k`` of ``f``, held on a bound
    whose outside lies in direction ``outward`` (±1): ``g_k² V_kk`` when the χ² slope
    ``g = Jᵀr`` points outside, else 0 — to first order the χ² reduction if the bound were
    relaxed, the other parameters refitted (Silvey 1959, *Ann. Math. Stat.* 30:389; for an
    inequality constraint Gouriéroux, Holly & Monfort 1982, *Econometrica* 50:63).

    A truth on (or within noise of) the end of a physical range — full gyroscopic coupling
    where the model has none, a preload grown to its largest — puts half of all fits on the
    bound; only data that want to go beyond it make the fit unphysical. A parameter the data
    do not see scores 0.

    >>> from types import SimpleNamespace
    >>> J = np.array([[1.0], [1.0]]); r = np.array([-1.0, -1.0])   # data want x larger
    >>> f = SimpleNamespace(jac=J, evaluation=SimpleNamespace(residuals=r[None]),
    ...                     covariance=lambda: np.linalg.inv(J.T @ J))
    >>> bound_score(f, 0, +1.0), bound_score(f, 0, -1.0)
    (2.0, 0.0)
    """
    g = f.jac[:, k] @ f.evaluation.residuals[0]
    if g * outward >= 0:
        return 0.0
    v = f.covariance()[k, k]
    return float(g * g * v) if np.isfinite(v) else 0.0


def describe(c: Candidate, slot: Slot, f: Fit, base_chi2: float) -> CandidateFit:
    """Parameters, intervals and plausibility flags of a candidate's fit (its last slot)."""
    e = slot_estimate(f, len(f.par.slots) - 1)
    return CandidateFit(c.name, slot, f, max(base_chi2 - f.chi2, 0.0), e.parameters, e.ci,
                        e.at_bound, e.significant)
