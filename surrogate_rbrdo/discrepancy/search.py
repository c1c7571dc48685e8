"""Fit each candidate effect on what the recalibration cannot absorb.

For a candidate, every bearing scope and shape start is screened first: the strength is stepped
along a geometric grid from the off state to its physical bound with the nuisance held at its
recalibrated value and what the recalibration absorbs to first order projected out (one
batched evaluation). The best start of every scope is then refined by a short bounded fit of
the nuisance and the candidate's parameters together (the recalibration moves far when an
effect is strong, so a screen at the base nuisance cannot choose the scope), and the best of
these is fitted to convergence.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.discrepancy.candidates import Candidate
from surrogate_rbrdo.discrepancy.fit import Fit, fit
from surrogate_rbrdo.discrepancy.nuisance import Slot
from surrogate_rbrdo.discrepancy.problem import Problem

#: screened strengths per start (geometric from 1e-4 of the range, or 1e-11 m/N, to the bound)
N_SCREEN = 12
#: residual evaluations of the short fit from each scope's start (the best is then finished)
SHORT_NFEV = 25


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
        A strength parameter sits on its physical bound (not the off state), or a shape
        parameter on a bound other than a natural zero (a massless, undamped housing is
        physical; a softening exponent at the end of its range means the law is stretched).
    significant : bool
        Some strength's interval, conditional on the fitted shapes, excludes the off state
        (the effect is on).
    """

    name: str
    slot: Slot
    fit: Fit
    delta_chi2: float
    parameters: dict
    ci: dict
    at_bound: bool
    significant: bool

    @property
    def effect(self):
        vals = self.fit.par.slot_values(self.fit.x)[-1]
        return self.slot.candidate.effect(self.slot.scope, vals)


def _screen_values(c: Candidate) -> np.ndarray:
    """Strength values (first strength parameter) tried from the off state outwards."""
    lo, hi, off, rec = c.lower[0], c.upper[0], c.off[0], c.reciprocal[0]
    if rec:
        top = hi if math.isfinite(hi) else 1e-6
        return np.geomspace(1e-11, top, N_SCREEN)
    span = hi - lo
    pos = off + np.geomspace(1e-4 * span, hi - off, N_SCREEN) if hi > off else np.zeros(0)
    neg = off - np.geomspace(1e-4 * span, off - lo, N_SCREEN) if off > lo else np.zeros(0)
    return np.concatenate([pos, neg])


def screen(problem: Problem, base: Fit, c: Candidate
           ) -> list[tuple[float, Slot, dict[str, float]]]:
    """χ² of every (scope, shape start, strength) with the nuisance at ``base`` and what its
    recalibration absorbs to first order projected out (the residual orthogonal to the base
    fit's Jacobian): returns ``(χ², slot, start values)`` sorted, best first."""
    par0 = base.par
    rows, meta = [], []
    shapes = [[]]
    for p, starts in zip(c.shape, c.shape_starts, strict=True):
        shapes = [s + [(p, v)] for s in shapes for v in starts]
    for scope in c.scopes:
        for shape in shapes:
            slot = Slot(c, scope)
            par = par0.with_slots(par0.slots + (slot,))
            for v in _screen_values(c):
                start = {f"{slot.label}.{p}": val for p, val in shape}
                start[f"{slot.label}.{c.strength[0]}"] = float(v)
                x = par.x0(start)
                x[:base.x.size] = base.x
                rows.append(x)
                meta.append((slot, start, par))
    out = []
    # what the recalibration absorbs, to first order: the span of the base fit's Jacobian
    Q, _ = np.linalg.qr(base.jac) if base.jac.size else (np.zeros((base.jac.shape[0], 0)), 0)
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


def fit_candidate(problem: Problem, base: Fit, c: Candidate,
                  extra_starts: list[tuple[Slot, dict[str, float]]] = (),
                  *, max_nfev: int = 60) -> CandidateFit:
    """Best fit of candidate ``c`` on top of ``base`` (see module doc)."""
    starts, seen = [], set()
    for _, s, st in screen(problem, base, c):       # best start of every scope
        if s.scope not in seen:
            seen.add(s.scope)
            starts.append((s, st))
    starts += list(extra_starts)
    best: Fit | None = None
    best_slot = None
    par0 = base.par
    for slot, st in starts:
        par = par0.with_slots(par0.slots + (slot,))
        x0 = par.x0(st)
        x0[:base.x.size] = base.x
        f = fit(problem, par, x0, max_nfev=SHORT_NFEV if len(starts) > 1 else max_nfev)
        if best is None or f.chi2 < best.chi2:
            best, best_slot = f, slot
    if len(starts) > 1:                              # finish the best start
        best = fit(problem, best.par, best.x, max_nfev=max_nfev)
    return describe(c, best_slot, best, base.chi2)


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
            at_bound |= bool(edge != off and abs(x - edge) <= 1e-6 * max(abs(edge), 1e-30))
            significant |= not (lo_s[k0 + i] <= off <= hi_s[k0 + i])
            identified[p] = not (a <= off <= b)
            if c.reciprocal[j]:
                a, b = (math.inf if b <= 0 else 1 / b), (math.inf if a <= 0 else 1 / a)
        else:                          # a shape pinned at a bound that is not a natural zero
            a_s, b_s = c.shape_bounds[c.shape.index(p)]
            at_bound |= any(e != 0 and abs(x - e) <= 1e-6 * abs(e) for e in (a_s, b_s))
        ci[p] = [a, b] if identified[p] else None
    if slot.scope:
        params["bearings"] = list(slot.scope)
    return SlotEstimate(params, ci, identified, at_bound, significant)


def describe(c: Candidate, slot: Slot, f: Fit, base_chi2: float) -> CandidateFit:
    """Parameters, intervals and plausibility flags of a candidate's fit (its last slot)."""
    e = slot_estimate(f, len(f.par.slots) - 1)
    return CandidateFit(c.name, slot, f, max(base_chi2 - f.chi2, 0.0), e.parameters, e.ci,
                        e.at_bound, e.significant)
