"""Shape parameters on a bound tried inside their range (:func:`interior`).

A candidate's fit with a shape parameter on a bound other than a natural zero is unphysical
(:class:`~.search.CandidateFit` ``at_bound``) — unless the data do not prefer the bound. The
bound shapes are held inside, alone and together, and a held fit within the likelihood-ratio
margin for the number held replaces the bound one (``docs/discrepancy.md``, "A shape on a
bound is tried inside").
"""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
from scipy.optimize import brentq
from scipy.special import gammaln
from scipy.stats import chi2

from surrogate_rbrdo.discrepancy.candidates import Candidate
from surrogate_rbrdo.discrepancy.fit import Fit, fit
from surrogate_rbrdo.discrepancy.nuisance import Slot
from surrogate_rbrdo.discrepancy.problem import Problem
from surrogate_rbrdo.discrepancy.search import CandidateFit, describe, on_bound, transfer


def interior(problem: Problem, base: Fit, cf: CandidateFit, delta: float, *,
             max_nfev: int = 60) -> CandidateFit:
    """``cf``, or a fit with its bound shape parameters held inside their range when that fits
    within the confounding margin of it.

    A shape parameter on a bound other than a natural zero makes a fit unphysical
    (:class:`CandidateFit` ``at_bound``: the law is stretched) — but only if the bound binds.
    A shape the data hardly see drifts to a bound as well as anywhere: a housing stage stiff
    enough that its mode lies far above the measured band acts as a series spring whatever its
    mass, and its fit can end at the largest mass with a χ² no better than at 20 kg. So every
    non-empty set of such parameters is held — each alone and together, at every combination
    of their start values inside the range (:func:`held_options`) — and the rest refitted. A
    held fit that is physical (not ``at_bound``: holding one shape must not leave another on
    its bound) and whose χ² exceeds ``cf``'s by no more than :func:`hold_threshold` (``delta``,
    the χ²₁ confounding margin, at its level for the number held) says the data do not prefer
    the bound; the best such fit is the candidate's (its ``Δχ²`` is the smaller one, the held
    shapes are reported as fixed, without an interval, and counted in
    :attr:`CandidateFit.n_fitted`: they were chosen from the data)."""
    c, slot, f = cf.slot.candidate, cf.slot, cf.fit
    best: CandidateFit | None = None
    for held in held_options(c, slot, f.par.slot_values(f.x)[-1]):
        s2 = Slot(c, slot.scope, slot.fixed + held)
        par = base.par.with_slots(base.par.slots + (s2,))
        f2 = fit(problem, par, transfer(f.par, f.x, par, par.x0()), max_nfev=max_nfev)
        if f2.chi2 - f.chi2 > hold_threshold(delta, len(held)):
            continue
        d2 = describe(c, s2, f2, base.chi2)
        if not d2.at_bound and (best is None or f2.chi2 < best.fit.chi2):
            best = replace(d2, held=tuple(p for p, _ in held))
    return cf if best is None else best


def held_options(c: Candidate, slot: Slot, values: dict[str, float]
                 ) -> list[tuple[tuple[str, float], ...]]:
    """Every hold :func:`interior` tries: for each non-empty set of the free shape parameters
    on a bound (not a natural zero), every combination of their start values inside the range
    (a natural zero counts as inside), as ``((name, value), …)``.

    >>> from surrogate_rbrdo.discrepancy.candidates import candidate
    >>> h = candidate("housing", ("front", "rear"))
    >>> [dict(o) for o in held_options(h, Slot(h, ()), {"m_kg": 250.0, "c_Ns_per_m": 1e6})]
    ... # doctest: +NORMALIZE_WHITESPACE
    [{'m_kg': 0.0}, {'m_kg': 10.0}, {'m_kg': 40.0}, {'c_Ns_per_m': 0.0},
     {'m_kg': 0.0, 'c_Ns_per_m': 0.0}, {'m_kg': 10.0, 'c_Ns_per_m': 0.0},
     {'m_kg': 40.0, 'c_Ns_per_m': 0.0}]
    """
    bound = []
    for p, (a, b), starts in zip(c.shape, c.shape_bounds, c.shape_starts, strict=True):
        v = values.get(p)
        if p in dict(slot.fixed) or v is None or not on_bound(v, (a, b)):
            continue
        inside = [float(s) for s in starts if a < s < b or s == 0 == min(abs(a), abs(b))]
        bound.append([(p, s) for s in inside])
    return [combo for k in range(1, len(bound) + 1)
            for subset in itertools.combinations(bound, k)
            for combo in itertools.product(*subset)]


def hold_threshold(delta: float, n_held: int) -> float:
    """How much worse (χ²) a fit with ``n_held`` shapes held may be than the free one and
    still count as the data not preferring the bounds: the χ² quantile with ``n_held``
    degrees of freedom at the level of the χ²₁ margin ``delta`` (the likelihood ratio of
    ``n_held`` restrictions).

    Solved on the log tail (:func:`_log_chi2_sf`), so a large margin does not underflow to a
    level of 0 and an infinite threshold.

    >>> round(hold_threshold(6.635, 1), 3), round(hold_threshold(6.635, 2), 2)
    (6.635, 9.21)
    """
    if n_held == 1:
        return float(delta)
    target = _log_chi2_sf(delta, 1)
    hi = delta + 10.0 * n_held
    while _log_chi2_sf(hi, n_held) > target:      # more degrees of freedom: a larger quantile
        hi = 2.0 * hi
    return float(brentq(lambda t: _log_chi2_sf(t, n_held) - target, delta, hi, xtol=1e-10,
                        rtol=1e-14))


def _log_chi2_sf(t: float, k: int) -> float:
    """``log P(χ²ₖ > t)``; where the tail underflows, from the asymptotic series of the upper
    incomplete gamma function, ``Γ(a, z) ≈ z^(a−1) e^(−z) (1 + (a−1)/z)`` (Abramowitz &
    Stegun 6.5.32; ``a = k/2``, ``z = t/2 > 300`` there, the next term's relative size
    ``a²/z²`` below 1e-4)."""
    p = chi2.sf(t, k)
    if p > 1e-280:
        return float(np.log(p))
    a, z = k / 2, t / 2
    return float(-z + (a - 1) * np.log(z) - gammaln(a) + np.log1p((a - 1) / z))
