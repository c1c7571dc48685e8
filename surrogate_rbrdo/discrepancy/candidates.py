"""The candidate library: which registered effects the workflow may name, and how each is fitted.

A candidate is derived from its effect class in :data:`~surrogate_rbrdo.spindle.effects.EFFECTS`
alone — its ``bounds`` (the physical range) and ``off_params`` (the off state):

* **strength** parameters are those of ``off_params`` (the ones that switch the effect on); a
  parameter whose off value is infinite (a housing stiffness ``k_h = ∞``) is fitted as its
  reciprocal (a compliance, off at 0). A strength whose off value sits on a bound of its range is
  one-sided (softening ``a ≥ 0``), else two-sided (cross-coupling ``κ``);
* **shape** parameters are the other bounded fields (an exponent, a housing mass); they are
  fitted too, from the start values of :data:`SHAPE_STARTS` (or the middle of their range);
* **scopes**: an effect that acts per bearing (its class overrides a hook of
  :class:`~surrogate_rbrdo.spindle.effects.Effect` called per bearing,
  :data:`PER_BEARING_HOOKS`) is tried on all bearings and on each alone. Every effect has a
  ``bearings`` field, but one acting on the rotor or the load alone (gyroscopics, a tool
  interface, an unbalance error) ignores it: its scoped variants are the same model, so they
  are not tried again.

So adding a candidate is registering one effect class; :data:`SHAPE_STARTS` only helps the
fit start well. Which effects are candidates is an explicit list
(:data:`DEFAULT_LIBRARY`, or the options' ``library``); effects that exist to build truths only
(:mod:`surrogate_rbrdo.discrepancy.truth_effects`) are never in it.

>>> c = candidate("speed_softening", ("front", "rear"))
>>> c.strength, c.one_sided, c.shape, c.scopes
(('a',), (True,), ('exponent',), ((), ('front',), ('rear',)))
>>> h = candidate("housing", ("front", "rear"))
>>> h.strength, h.reciprocal, h.lower, h.upper
(('k_N_per_m',), (True,), (0.0,), (1e-06,))
>>> e = h.effect((), {"k_N_per_m": 2e-9, "m_kg": 10.0, "c_Ns_per_m": 0.0})
>>> round(e.k_N_per_m / 1e6, 3), e.m_kg
(500.0, 10.0)
"""

from __future__ import annotations

import dataclasses
import inspect
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.spindle.effects import EFFECTS, Effect

#: the candidates tried by default (registry names; explicit, so truth-only effects stay out);
#: the tool-holder interface is registered by the rig's spindle effects (issue 14)
DEFAULT_LIBRARY: tuple[str, ...] = (
    "speed_softening", "thermal_preload", "cross_coupling", "anisotropy", "housing",
    "gyroscopics", "unbalance_error",
) + (("tool_interface",) if "tool_interface" in tuple(EFFECTS) else ())

#: start values of shape parameters (a fit starts from each; the largest effect shapes first)
SHAPE_STARTS: dict[str, dict[str, tuple[float, ...]]] = {
    "speed_softening": {"exponent": (2.0, 1.0, 3.0)},
    "thermal_preload": {"q": (2.0, 1.0, 3.0)},
    "housing": {"m_kg": (0.0, 10.0, 40.0), "c_Ns_per_m": (0.0,)},
}

#: experiments that separate two confounded candidates (unordered pairs of registry names)
SEPARATING_TESTS: dict[frozenset[str], str] = {
    frozenset({"speed_softening", "thermal_preload"}):
        "a run-up and a run-down (thermal preload lags the speed, softening does not) or a "
        "thermal soak at constant speed (preload drifts with temperature, softening does not)",
    frozenset({"housing", "unbalance_error"}):
        "a second unbalance run with a known trial mass (fixes the unbalance, leaves the "
        "housing)",
    frozenset({"anisotropy", "cross_coupling"}):
        "an impact test at standstill in x and y (anisotropy splits the modes at Ω = 0, "
        "cross-coupling does not)",
    frozenset({"housing", "speed_softening"}):
        "an impact test on the housing up to 2 kHz (a housing mode; softening has none)",
    frozenset({"housing", "thermal_preload"}):
        "an impact test on the housing up to 2 kHz (a housing mode; preload growth has none)",
}


def separating_test(names: list[str]) -> str:
    """The experiments that would separate the candidates ``names`` (pairs looked up in
    :data:`SEPARATING_TESTS`; otherwise a generic advice)."""
    out = []
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            t = SEPARATING_TESTS.get(frozenset({a, b}))
            if t and t not in out:
                out.append(f"{a} vs {b}: {t}")
    if not out:
        out.append("a test at operating points where the fitted alternatives' predictions "
                   "differ most (see candidates.csv: their predicted responses)")
    return "; ".join(out)


#: most effects a candidate keeps built (:meth:`Candidate.effect`)
EFFECT_CACHE_SIZE = 4096


@dataclass(frozen=True)
class Candidate:
    """How one registered effect is fitted (built by :func:`candidate`).

    ``lower``/``upper`` bound the strength parameters in fitting units (reciprocal for
    ``reciprocal`` ones); ``off`` is the off state in those units.
    """

    name: str
    effect_cls: type
    strength: tuple[str, ...]
    one_sided: tuple[bool, ...]
    reciprocal: tuple[bool, ...]
    off: tuple[float, ...]
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    shape: tuple[str, ...]
    shape_bounds: tuple[tuple[float, float], ...]
    shape_starts: tuple[tuple[float, ...], ...]
    scopes: tuple[tuple[str, ...], ...]
    #: effects already built, keyed by scope and the parameters' bits (a fit's finite-difference
    #: rows rebuild the same effect many times; equal inputs give an equal effect)
    _built: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def n_strength(self) -> int:
        return len(self.strength)

    def effect(self, scope: tuple[str, ...], values: dict[str, float]) -> Effect:
        """The effect with ``values`` in fitting units (strength and shape parameters).

        Reciprocal strengths at 0 are off (∞); when some reciprocal strength is on, the others
        are kept just on (compliance ≥ 1e-18: effectively rigid), since an effect may require
        its stiffnesses to be all finite or all infinite (a tool interface)."""
        key = (tuple(scope), np.array([values[p] for p in self.strength + self.shape],
                                      dtype=float).tobytes())
        hit = self._built.get(key)
        if hit is None:
            if len(self._built) >= EFFECT_CACHE_SIZE:
                self._built.clear()
            hit = self._built[key] = self._effect(scope, values)
        return hit

    def _effect(self, scope: tuple[str, ...], values: dict[str, float]) -> Effect:
        kw: dict[str, Any] = {}
        on = any(float(values[p]) > 0 for p, rec in zip(self.strength, self.reciprocal,
                                                        strict=True) if rec)
        for p, rec in zip(self.strength, self.reciprocal, strict=True):
            v = float(values[p])
            kw[p] = (1.0 / max(v, 1e-18) if on else math.inf) if rec else v
        for p in self.shape:
            kw[p] = float(values[p])
        if scope:
            kw["bearings"] = tuple(scope)
        return self.effect_cls(**kw)

    def physical(self, values: dict[str, float]) -> dict[str, float]:
        """Fitting units → the effect's own parameters (reciprocals undone)."""
        out = dict(values)
        for p, rec in zip(self.strength, self.reciprocal, strict=True):
            if rec:
                out[p] = math.inf if values[p] <= 0 else 1.0 / values[p]
        return out


def candidate(name: str, bearings: tuple[str, ...]) -> Candidate:
    """The fitting description of the registered effect ``name`` for a spindle with
    ``bearings`` (names)."""
    cls = EFFECTS.get(name)
    bounds: dict[str, tuple[float, float]] = dict(cls.bounds)
    off: dict[str, float] = dict(cls.off_params)
    if not off:
        raise ValueError(f"effect {name!r} has no off_params: it cannot be a candidate")
    strength, one_sided, recip, offv, lo, hi = [], [], [], [], [], []
    for p, v in off.items():
        b_lo, b_hi = bounds.get(p, (-math.inf, math.inf))
        if math.isinf(v):
            strength.append(p)
            recip.append(True)
            offv.append(0.0)
            lo.append(0.0)
            hi.append(1.0 / b_lo if b_lo > 0 else math.inf)
            one_sided.append(True)
        else:
            strength.append(p)
            recip.append(False)
            offv.append(float(v))
            lo.append(float(b_lo))
            hi.append(float(b_hi))
            one_sided.append(v <= b_lo or v >= b_hi)
    starts = SHAPE_STARTS.get(name, {})
    shape = tuple(p for p in bounds if p not in off)
    shape_bounds = tuple(tuple(map(float, bounds[p])) for p in shape)
    shape_starts = tuple(
        tuple(starts.get(p, (_default_start(cls, p, bounds[p]),))) for p in shape)
    scopes: tuple[tuple[str, ...], ...] = ((),)
    if acts_per_bearing(cls) and len(bearings) > 1:
        scopes = ((),) + tuple((b,) for b in bearings)
    return Candidate(name, cls, tuple(strength), tuple(one_sided), tuple(recip), tuple(offv),
                     tuple(lo), tuple(hi), shape, shape_bounds, shape_starts, scopes)


#: the hooks of :class:`~surrogate_rbrdo.spindle.effects.Effect` called once per bearing (those
#: with a ``bearing`` argument, but ``applies_to``, the scope test itself): only through them
#: does an effect's ``bearings`` field act
PER_BEARING_HOOKS: tuple[str, ...] = tuple(
    n for n, f in vars(Effect).items() if n != "applies_to"
    and inspect.isfunction(f) and "bearing" in inspect.signature(f).parameters)


def acts_per_bearing(cls: type) -> bool:
    """Whether effect class ``cls`` overrides a hook called per bearing
    (:data:`PER_BEARING_HOOKS`), so that its ``bearings`` field changes the model.

    >>> PER_BEARING_HOOKS
    ('preload', 'bearing', 'support')
    >>> acts_per_bearing(EFFECTS.get("speed_softening")), acts_per_bearing(
    ...     EFFECTS.get("gyroscopics"))
    (True, False)
    """
    return any(getattr(cls, n) is not getattr(Effect, n) for n in PER_BEARING_HOOKS)


def _default_start(cls: type, p: str, bound: tuple[float, float]) -> float:
    """The field's default if it lies in range, else the middle of the range."""
    f = {f.name: f for f in dataclasses.fields(cls)}[p]
    d = f.default
    lo, hi = bound
    if isinstance(d, (int, float)) and lo <= d <= hi and math.isfinite(d):
        return float(d)
    return 0.5 * (lo + hi) if math.isfinite(hi) else lo


def check_library(names: tuple[str, ...]) -> tuple[str, ...]:
    """``names`` if it is a non-empty list of distinct registered effects that can be
    candidates (each has ``off_params``: the value at which it is absent).

    >>> check_library(("housing", "anisotropy"))
    ('housing', 'anisotropy')
    >>> check_library(("housing", "housing"))
    Traceback (most recent call last):
    ...
    ValueError: library = ['housing', 'housing'] is not allowed: a name appears twice
    """
    names = tuple(names)
    if not names:
        raise ValueError("library = [] is not allowed: give at least one registered effect, "
                         f"e.g. {list(DEFAULT_LIBRARY)}")
    if len(set(names)) != len(names):
        raise ValueError(f"library = {list(names)} is not allowed: a name appears twice")
    fit = sorted(n for n in EFFECTS if dict(EFFECTS.get(n).off_params))
    for i, n in enumerate(names):
        if n not in fit:
            raise ValueError(f"library[{i}] = {n!r} is not allowed: must be one of {fit} "
                             "(registered effects with off_params)")
    return names


def library(names: tuple[str, ...], bearings: tuple[str, ...]) -> tuple[Candidate, ...]:
    """Candidates for the registry names ``names`` (unknown names raise, listing the known)."""
    if len(set(names)) != len(names):
        raise ValueError(f"library = {list(names)}: a name appears twice")
    return tuple(candidate(n, bearings) for n in names)
