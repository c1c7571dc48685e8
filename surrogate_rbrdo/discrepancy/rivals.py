"""Can a library name be told from a generic local change? An encompassing test.

A library effect that passes the likelihood-ratio test explains *something*; it does not follow
that the something is that effect. The generic local parameters of sensitivity-based updating
(:mod:`.generic`: the stiffness and mass of each shaft element, each disk's mass and inertia,
a grounded spring at each node — Friswell & Mottershead 1995, ch. 7) are the rival
explanations: a heavier motor rotor, a magnetic pull, a local loss of shaft stiffness are each
one of them to first order, and a library effect can mimic part of any — but only changes of
a plausible size and sign count as rivals (:data:`~.generic.PLAUSIBLE`: at 1× a bearing
stiffness that falls as ``Ω²`` *is* a mass at the bearing, ``−Ω² Δm``, yet the mass that
mimics a few percent of softening is more than the shaft element weighs; the rival's
coefficient is confined to its range, where its χ² is a clipped quadratic). The candidate is
*separable* only if it explains the data significantly better than every one-parameter generic
change, in the sense of the encompassing (J-) test of non-nested models (Davidson & MacKinnon
1981, *Econometrica* 49:781; Mizon & Richard 1986, *Econometrica* 54:657): adding the library
effect to the generic rival must reduce χ² by more than the χ² quantile of the level that
defines a confounded set (``confound_delta``, χ²₁ 99 %; χ²ₖ at the same level for a candidate
with ``k`` free parameters). The test is the intersection of one test per rival (every rival
must be rejected), so it needs no correction for the number of rivals.

Beside the structural rivals, the nuisance's own *form* is a rival: the model's bearing damping
has a fixed speed law, and at 1× a skew-symmetric cross-coupled stiffness ``k_xy`` acts on a
forward circular orbit exactly as a damping ``−k_xy/Ω`` — so a bearing damping that varies with
speed in a way the model does not know (``c(Ω) = s c₀(Ω) (Ω/Ω_ref)^p``, one exponent per
bearing: Jorgensen & Shin 1998 and most spindle-bearing damping measurements find damping
falling with speed) is a rival of ``cross_coupling`` that names nothing. Its column is the
damping factor's column scaled row by row by ``ln(Ω/Ω_ref)`` (each observation sees the
damping at its own speed).

A grounded spring is a rival with a *sign* (:func:`~.generic.node_spring_ranges`): passive
connections from shaft to ground (seals, elastomer rings, a bearing row the model lacks) are
positive; only the motor's air gap (unbalanced magnetic pull) gives a negative one. This
decides the bearing speed laws: with the stiffness factor θ recalibrated, a constant spring
``Δk`` at a bearing's node spans ``{1, k(Ω)}`` — any change ``a + b k(Ω)`` of that bearing,
and with the modelled ``k(Ω)`` already falling with speed (19 % at 24 000 rpm) that is nearly
any extra speed law: a further softening is ``θ`` up and ``Δk < 0``, a preload growth ``θ``
down and ``Δk > 0`` (measured: with the impact plan a strong softening's signature lies 99.6 %
inside span(nuisance, spring at its bearing's node)). A passive spring can stand in for the
preload growth (the name is withheld: a thermal soak separates them), not for the softening.

The generic rivals are linear at the stage's base fit (nuisance refitted with them, to first
order): the rival alone has ``χ²_base − Δ(rival)`` with the base's nuisance projected out; the
library candidate is its nonlinear fit. With both in one model the χ² is
``χ²_lib − Δ(rival | lib)``, the rival's first-order gain on the candidate's residual with what
the candidate's model refits — its fit's Jacobian and the unbalance at its fit — projected out
(the same gain is the converse direction, ``rival_adds``). Before the ninth session the joint
model also projected the *base's* nuisance columns out, about 22 further directions where the
base and the fit differ, which understated the rival's gain on top of the candidate and could
make the statistic negative (review s11 H2: −14 to −19); on a linear problem the two agree. A
strong effect far from its linearisation favours the library (its rival is only linear): that
direction of error names an effect the final lack-of-fit tests then still check.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import qr
from scipy.stats import chi2

from surrogate_rbrdo.discrepancy.calibration import Linearisation, _apply, _data_whitening
from surrogate_rbrdo.discrepancy.problem import Problem


@dataclass(frozen=True)
class RivalTest:
    """A candidate against its closest generic rival.

    Attributes
    ----------
    statistic : float
        ``min_j [χ²(rival_j) − χ²(rival_j + candidate)]``: what the candidate adds to the
        rival that mimics it best.
    threshold : float
        χ²ₖ quantile at the confound level (``k`` the candidate's free parameters).
    rival : str
        The generic local change attaining the minimum.
    rival_delta_chi2 : float
        That rival's own first-order gain over the stage's base.
    level : float
        The confound level (``P(χ²₁ > confound_delta)``).
    n_free : int
    rival_adds : float
        The reverse direction, ``χ²(candidate) − χ²(rival + candidate)`` for the same rival:
        what that rival adds to the fitted candidate (``inf``: not computed).
    rival_one_sided : bool
        The rival's range ends at 0 (a sign: a passive spring): under the null its bounded
        gain is ``½χ²₀ + ½χ²₁`` (Self & Liang 1987), so its quantile at the level is χ²₁'s
        at twice the level.
    """

    statistic: float
    threshold: float
    rival: str
    rival_delta_chi2: float
    level: float = 0.01
    n_free: int = 1
    rival_adds: float = math.inf
    rival_one_sided: bool = False

    @property
    def p_value(self) -> float:
        """``P(χ²ₖ > statistic)``: small when the candidate adds to every rival."""
        return float(chi2.sf(self.statistic, self.n_free)) if self.statistic > 0 else 1.0

    @property
    def passed(self) -> bool:
        return self.statistic > self.threshold

    @property
    def mutual(self) -> bool:
        """Neither explains the data better: the candidate adds nothing significant to its
        closest rival (not :attr:`passed`) and that rival, a one-parameter change, adds
        nothing significant to the candidate (``rival_adds`` within the χ²₁ quantile of the
        level, at twice the level for a one-sided rival) — the non-nested pair the data cannot
        discriminate (Davidson & MacKinnon 1981: neither model is rejected against the
        other)."""
        tail = 2 * self.level if self.rival_one_sided else self.level
        return not self.passed and self.rival_adds <= float(chi2.isf(tail, 1))

    def to_dict(self) -> dict:
        return {"statistic": self.statistic, "threshold": self.threshold,
                "p_value": self.p_value, "level": self.level, "rival": self.rival,
                "rival_delta_chi2": self.rival_delta_chi2, "rival_adds": self.rival_adds,
                "rival_one_sided": self.rival_one_sided, "passed": self.passed,
                "mutual": self.mutual}


#: relative size of a pivoted QR's diagonal, on unit-norm columns, below which a column of ``B``
#: adds no direction (it repeats the others)
RANK_TOL = 1e-10


def _orth(B: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """``Y`` with its projection on the column space of ``B`` removed: Householder QR with
    column pivoting on ``B``'s columns scaled to unit norm (the span does not depend on the
    parameters' units, which differ by many decades), rank-revealing, so a column that repeats
    others adds no direction made of round-off.

    >>> B = np.array([[1.0, 2.0], [0.0, 0.0], [0.0, 0.0]])          # rank 1
    >>> _orth(B, np.array([[1.0], [1.0], [0.0]])).ravel().tolist()
    [0.0, 1.0, 0.0]
    """
    norms = np.linalg.norm(B, axis=0)
    live = norms > 0
    if not np.any(live):
        return Y
    Q, R, _ = qr(B[:, live] / norms[live], mode="economic", pivoting=True)
    d = np.abs(np.diag(R))
    Q = Q[:, :int(np.count_nonzero(d > RANK_TOL * d[0]))]
    return Y - Q @ (Q.T @ Y)


#: the experiment that separates a library effect from its generic rivals (1x data: ω = Ω)
RIVAL_SEPARATION = (
    "excitation off the synchronous line (impact tests or a shaker at speed, ω ≠ Ω): under 1× "
    "unbalance alone a bearing stiffness varying as Ω² equals a mass at the bearing, a polar "
    "inertia equals minus a diametral inertia, a cross-coupled stiffness equals a damping ∝ "
    "1/Ω; off the synchronous line they part")

#: what is left when the data already hold impact tests at speed
RIVAL_SEPARATION_AT_SPEED = (
    "a larger effect or impact tests at more speeds over a wider range: the data hold FRFs "
    "off the synchronous line already, and the closest generic change differs from the "
    "candidate only in its speed law")

#: ... when the closest rival is a (passive, positive) grounded spring: with the bearing's
#: stiffness factor recalibrated it spans any change ``a + b k(Ω)`` of a bearing's stiffness
RIVAL_SEPARATION_SPRING = (
    "a thermal soak (hold a speed and repeat the impact tests as the spindle warms: a preload "
    "growth drifts with temperature, a constant stiffness beside the bearing — a seal, a "
    "bearing row that does not soften — does not); no excitation separates them, since with "
    "the bearing's stiffness factor recalibrated a constant spring at its node spans any "
    "change a + b k(Ω) of that bearing's stiffness")


#: plausible range of a bearing damping's speed exponent ``p`` in ``c ∝ Ω^p``
DAMPING_EXPONENT = (-1.0, 1.0)


def damping_law_columns(problem: Problem, lin: Linearisation, names: tuple[str, ...]
                        ) -> tuple[np.ndarray, tuple[str, ...], np.ndarray]:
    """Unwhitened columns of a speed exponent of each bearing's damping (module doc), from the
    damping factors' columns of ``lin.nuisance`` (outer parameter ``names`` in its order),
    their labels and plausible ranges (:data:`DAMPING_EXPONENT`)."""
    idx = [i for i, n in enumerate(names) if n.startswith("log_damping")]
    scale = np.zeros(problem.n_obs)
    # one reference speed for every test (the 1x speeds' geometric mean): an impact test at
    # speed sees the damping at its own speed; at standstill the law does not apply (0)
    spins = np.concatenate([b.sweep.spin_rad_s for b in problem.blocks
                            if b.sweep.kind == "unbalance_1x"] or [np.ones(1)])
    ref = np.exp(np.mean(np.log(spins[spins > 0]))) if np.any(spins > 0) else 1.0
    off = 0
    for b in problem.blocks:
        X, C = b.mean.shape
        spin = np.asarray(b.sweep.spin_rad_s, dtype=float)
        ln = np.log(np.where(spin > 0, spin, ref) / ref)
        scale[off:off + 2 * X * C] = np.repeat(ln, 2 * C)
        off += 2 * X * C
    cols = lin.nuisance[:, idx] * scale[:, None]
    labels = tuple(f"speed law of damping ({names[i].removeprefix('log_damping_')})"
                   for i in idx)
    return cols, labels, np.tile(DAMPING_EXPONENT, (len(idx), 1))


def _bounded_fit(U: np.ndarray, r: np.ndarray, bounds: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Per column ``u`` the χ² reduction of the best multiple ``c u`` of it with ``c`` inside
    its ``bounds``, ``2 c uᵀr − c² uᵀu`` (a quadratic in ``c``: its bounded minimiser is the
    clipped free one), and that ``c``. A column the projection left empty gains nothing."""
    uu = np.einsum("nk,nk->k", U, U)
    ur = U.T @ r
    live = uu > 0
    c = np.clip(np.where(live, ur / np.where(live, uu, 1.0), 0.0), bounds[:, 0], bounds[:, 1])
    return np.where(live, 2 * c * ur - c * c * uu, 0.0), c


def _rivals(problem: Problem, lin: Linearisation,
            extra: tuple[np.ndarray, tuple[str, ...], np.ndarray] | None):
    """Whitened nuisance ``N``, rival columns ``G`` and ``U`` (``G`` with ``N`` projected
    out), the rivals' labels and ranges, and which rivals the nuisance does not absorb; None
    when there is no rival."""
    cols, labels = lin.generic, lin.generic_labels
    bounds = (lin.generic_bounds if lin.generic_bounds is not None
              else np.tile([-np.inf, np.inf], (cols.shape[1], 1)))
    if extra is not None and extra[0].shape[1]:
        cols, labels = np.hstack([cols, extra[0]]), labels + extra[1]
        bounds = np.vstack([bounds, extra[2]])
    if cols.shape[1] == 0:
        return None
    W = _data_whitening(problem)
    N = _apply(W, lin.nuisance)
    G = _apply(W, cols)
    gg = np.einsum("nk,nk->k", G, G)
    U = _orth(N, G)
    live = np.einsum("nk,nk->k", U, U) > 1e-12 * gg          # not absorbed by the nuisance
    return N, G, U, labels, bounds, live


def rival_refit(problem: Problem, lin: Linearisation, r: np.ndarray,
                extra: tuple[np.ndarray, tuple[str, ...], np.ndarray] | None = None
                ) -> tuple[float, str, np.ndarray]:
    """The generic rival (inside its plausible range, nuisance refitted with it) that reduces
    the χ² of whitened residuals ``r`` of a fit at ``lin``'s base most, to first order: that
    reduction, the rival's label (``(0.0, "")`` without rivals) and the residuals after its
    refit, ``P⊥r − c u`` (``u`` the rival's column with the nuisance projected out, ``c`` its
    bounded coefficient; ``r`` itself without rivals). Rows keep ``r``'s order, so the data
    rows and the priors' rows can be told apart: what is left is the part of a discrepancy no
    generic local change explains."""
    rv = _rivals(problem, lin, extra)
    if rv is None:
        return 0.0, "", r.copy()
    N, _, U, labels, bounds, live = rv
    rp = _orth(N, r[:, None])[:, 0]
    gain, c = _bounded_fit(U, rp, bounds)
    gain = np.where(live, gain, 0.0)
    j = int(np.argmax(gain))
    return float(gain[j]), labels[j], rp - c[j] * U[:, j]


def rival_test(problem: Problem, lin: Linearisation, base_chi2: float, base_r: np.ndarray,
               fit_chi2: float, fit_r: np.ndarray, fit_jac: np.ndarray, n_free: int,
               confound_delta: float,
               extra: tuple[np.ndarray, tuple[str, ...], np.ndarray] | None = None,
               fit_design: np.ndarray | None = None) -> RivalTest:
    """The encompassing test of a fitted candidate against every generic rival (module doc).

    Parameters
    ----------
    problem : Problem
        The stage's training problem.
    lin : Linearisation
        The stage's linearisation (nuisance and generic columns at its base, with the generic
        changes' plausible ranges).
    base_chi2, base_r : float, ndarray
        χ² and whitened residuals of the stage's base fit.
    fit_chi2, fit_r, fit_jac : float, ndarray, ndarray
        The candidate's fit: χ², whitened residuals and Jacobian (outer parameters).
    n_free : int
        The candidate's free parameters.
    confound_delta : float
        χ²₁ quantile of the confound level.
    extra : (ndarray, tuple of str, ndarray), optional
        Further rival columns (unwhitened), labels and ranges (:func:`damping_law_columns`).
    fit_design : ndarray, optional
        The unbalance design at the candidate's fit (unwhitened, ``Problem.unbalance_design``):
        with ``fit_jac`` it spans what the candidate's model refits, against which the closest
        rival's gain on top of it (``rival_adds``) is taken — the first-order gain of adding
        the rival to the fitted candidate (score / Gauss–Newton step at that fit). Without it,
        ``fit_jac`` alone (a problem without unbalance).
    """
    level = float(chi2.sf(confound_delta, 1))
    k = max(n_free, 1)
    threshold = float(chi2.isf(level, k))
    rv = _rivals(problem, lin, extra)
    if rv is None:
        return RivalTest(np.inf, threshold, "", 0.0, level, k)
    N, G, U, labels, bounds, live = rv
    gain = _bounded_fit(U, _orth(N, base_r[:, None])[:, 0], bounds)[0]    # rival alone
    gg = np.einsum("nk,nk->k", G, G)
    # every rival's gain on the candidate's residual with what the candidate's own model
    # refits (its Jacobian, the unbalance at its fit) projected out: the joint model, to first
    # order at the candidate's fit (its χ² is ``fit_chi2 − adds``)
    own = fit_jac if fit_design is None else np.hstack(
        [fit_jac, _apply(_data_whitening(problem), fit_design)])
    V = _orth(own, G)
    V = np.where(np.einsum("nk,nk->k", V, V) > 1e-12 * gg, V, 0.0)
    adds = _bounded_fit(V, fit_r, bounds)[0]
    stat = np.where(live, (base_chi2 - gain) - (fit_chi2 - adds), np.inf)
    j = int(np.argmin(stat))
    return RivalTest(float(stat[j]), threshold, labels[j] if labels else str(j),
                     float(gain[j]), level, k, float(adds[j]), bool(0.0 in bounds[j]))
