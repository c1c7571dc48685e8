"""The blind-test grid: which scenarios, at which strengths (calibrated by signal-to-noise), and
the signature cosines that decide which pairs of candidates are confounded on a campaign.

Classes (:func:`build_grid`): *nothing hidden*; every library effect alone at ``sub-noise``,
``marginal`` and ``strong`` strength (an effect the recalibration absorbs entirely, such as an
unbalance error with the unbalance unknown, once, as ``absorbed``); *confounded pairs* — a
candidate hidden at the strength where it is separated from its twin by only ``z_sep = 1.5``
noise units, for every pair whose signatures' cosine (same sign for one-sided strengths) is at
least ``min_cos``; *two effects at once* (both strong); and effects *outside the library*
(``marginal`` and ``strong``) — each at every noise level and seed. On request, every library
effect alone at ``separable`` strength too: where the part of its strength no generic local
change explains reaches a target (:func:`calibrate_grid`), so that "strong" means nameable
rather than merely visible.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from surrogate_rbrdo.discrepancy.blind import (
    HIDDEN,
    STRENGTHS,
    Context,
    Scenario,
    calibrate,
    separable_strength,
)
from surrogate_rbrdo.discrepancy.calibration import _apply, _data_whitening, linearise
from surrogate_rbrdo.discrepancy.candidates import library
from surrogate_rbrdo.discrepancy.fit import fit
from surrogate_rbrdo.discrepancy.problem import Problem

#: the outside-library effects of the grid
OUTSIDE = ("magnetic_pull", "shaft_stiffness_loss", "disk_mass_error", "bearing_seal")
#: pairs hidden together (both strong)
PAIRS = (("housing", "speed_softening"), ("cross_coupling", "anisotropy"))


def signature_cosines(ctx: Context, noise: str) -> tuple[tuple[str, ...], np.ndarray]:
    """Signed cosines between candidates' signatures on the campaign's observables: their
    first-order change of the observables (all bearings, first shape start, towards a larger
    strength), whitened, with what the recalibration absorbs projected out."""
    data = ctx.source.expected(ctx.geometry, ctx.effects, noise)
    prob = Problem(ctx.forward(data), data, nuisance=ctx.options.nuisance)
    par = prob.parametrisation()
    base = fit(prob, par, par.x0(), max_nfev=80)
    lin = linearise(prob, base, library(ctx.options.library, prob.forward.bearing_names))
    W = _data_whitening(prob)
    Q, _ = np.linalg.qr(_apply(W, lin.nuisance))
    names, dirs = [], []
    for c, vs in lin.candidates:
        v = next((v for v in vs if v.scope == ()), vs[0])
        u = _apply(W, v.columns[:, :1])[:, 0]
        u = u - Q @ (Q.T @ u)
        names.append(c.name)
        dirs.append(u / np.linalg.norm(u))
    D = np.array(dirs)
    return tuple(names), D @ D.T


@dataclass(frozen=True)
class Calibration:
    """Knob values per (effect, strength, noise) and the strengths they reach."""

    knob: dict[tuple[str, str, str], float]
    z: dict[tuple[str, str, str], float]
    #: for the ``strong`` cells: the part of ``z`` no generic rival explains and that rival
    #: (:func:`~.blind.separable_strength`)
    separable: dict[tuple[str, str, str], tuple[float, str]] = field(default_factory=dict)


def calibrate_grid(ctx: Context, names: tuple[str, ...], noises: tuple[str, ...],
                   strengths: dict[str, float] = STRENGTHS, *,
                   separable_target: float | None = None) -> Calibration:
    """Bisect every (effect, strength, noise) to its target strength; the separable part of
    every strong cell's strength.

    With ``separable_target``, every library effect (not the outside ones) also gets a
    ``separable`` cell: the knob at which the part of its strength no generic rival explains,
    ``z_sep`` (:func:`~.blind.separable_strength`), reaches the target — the strength at which
    the workflow's encompassing test can name it — or its physical extreme if even that falls
    short (the cell's recorded ``z_sep`` says so). Its ``z`` is the total strength there.
    """
    knob, z, sep = {}, {}, {}
    measured: dict = {}

    def sep_of(c, hidden, nz):          # separable_strength, once per knob and noise
        key = (tuple((h.name, v) for h, v in hidden), nz)
        if key not in measured:
            measured[key] = separable_strength(c, hidden, nz)
        return measured[key]

    for n in names:
        for s, target in strengths.items():
            for nz in noises:
                knob[(n, s, nz)], z[(n, s, nz)] = calibrate(ctx, HIDDEN[n], target, nz)
                if s == "strong":
                    sep[(n, s, nz)] = separable_strength(
                        ctx, ((HIDDEN[n], knob[(n, s, nz)]),), nz)[1:]
        if separable_target is None or HIDDEN[n].truth_only:
            continue
        for nz in noises:
            k = (n, "separable", nz)
            knob[k], _ = calibrate(ctx, HIDDEN[n], separable_target, nz,
                                   measure=lambda c, hd, v: sep_of(c, hd, v)[1])
            z[k], zs, rival = sep_of(ctx, ((HIDDEN[n], knob[k]),), nz)
            sep[k] = (zs, rival)
    return Calibration(knob, z, sep)


def confounded_pairs(names: tuple[str, ...], cos: np.ndarray, one_sided: dict[str, bool],
                     min_cos: float = 0.95) -> list[tuple[str, str, float]]:
    """Ordered pairs (hidden, twin, |cos|) the data cannot tell apart to first order: a
    one-sided candidate only mimics in its own direction (positive cosine).

    >>> confounded_pairs(("a", "b"), np.array([[1, -0.99], [-0.99, 1]]), {"a": True, "b": True})
    []
    """
    out = []
    for i, a in enumerate(names):
        for j, b in enumerate(names):
            c = cos[i, j]
            if i != j and (c >= min_cos or (abs(c) >= min_cos and not (one_sided[a]
                                                                        and one_sided[b]))):
                out.append((a, b, float(abs(c))))
    return out


def build_grid(ctx: Context, cal: Calibration, noises: tuple[str, ...], seeds: int,
               pairs: list[tuple[str, str, float]], *, z_sep: float = 1.5,
               base_seed: int = 0) -> list[Scenario]:
    """Every scenario of the grid (module doc); seeds differ between every cell."""
    out: list[Scenario] = []
    ss = np.random.SeedSequence(base_seed)

    def add(label, strength, hidden, nz):
        for _ in range(seeds):
            out.append(Scenario(label, strength, hidden, nz,
                                int(ss.spawn(1)[0].generate_state(1)[0])))

    calibrated = {key[0] for key in cal.z}          # the grid covers what was calibrated
    library_names = [n for n, h in HIDDEN.items()
                     if not h.truth_only and n in ctx.options.library and n in calibrated]
    for nz in noises:
        add("nothing hidden", "-", (), nz)
        for n in library_names:
            if cal.z[(n, "strong", nz)] < 0.5:          # absorbed entirely
                add(f"single: {n}", "absorbed", ((HIDDEN[n], cal.knob[(n, "strong", nz)]),), nz)
                continue
            for s in (*STRENGTHS, "separable"):
                if (n, s, nz) in cal.knob:
                    add(f"single: {n}", s, ((HIDDEN[n], cal.knob[(n, s, nz)]),), nz)
        for a, b, c in pairs:
            target = z_sep / math.sqrt(max(1 - c * c, 1e-12))
            if target <= STRENGTHS["strong"] * 3:
                knob, _ = calibrate(ctx, HIDDEN[a], target, nz)
                add(f"confounded: {a} ~ {b}", f"z={target:.1f}", ((HIDDEN[a], knob),), nz)
        for a, b in PAIRS:
            if a in library_names and b in library_names:
                add(f"two: {a} + {b}", "strong", ((HIDDEN[a], cal.knob[(a, "strong", nz)]),
                                                  (HIDDEN[b], cal.knob[(b, "strong", nz)])), nz)
        for n in (n for n in OUTSIDE if n in calibrated):
            for s in ("marginal", "strong"):
                add(f"outside: {n}", s, ((HIDDEN[n], cal.knob[(n, s, nz)]),), nz)
    return out
