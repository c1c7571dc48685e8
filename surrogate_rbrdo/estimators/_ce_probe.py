"""Failure branches the cross-entropy density missed: found by design-point searches, added to
the final IS density.

A cross-entropy density is refitted at every level from samples of the previous one; a failure
branch that one fit leaves out is not sampled again and is lost for good. On the four-branch
series system (k = 7) one or both straight branches (each 10.5 % of P_f) were lost in 5 of 100
runs, each reported with a tight interval around a value 3–8 standard errors low: the final
sample never visits a branch its density lacks, so no weight diagnostic can see it.

The probe looks with the first level, a plain standard-normal sample that sees every direction:

1. *Candidates*: the first-level points with ``G`` at or below its 10 % quantile (near or in
   the failure domain), lowest first.
2. *Coverage*, without model calls: the final density ``q`` (the adapted one with its
   defensive part) is asked how often ``n_final`` of its points would fall in the half-space
   beyond each candidate, ``{w: â·w ≥ ‖v‖}`` (``â = v/‖v‖``) — estimated from ``N_COVER`` draws
   of ``q``. A candidate expected to be visited fewer than ``MIN_HITS`` times is uncovered.
3. *Search*: from the lowest uncovered candidate, an iHL-RF design-point search (the FORM of the
   ``is`` estimator). A converged ``u*`` whose half-space ``{a*·w ≥ β*}`` the final sample is
   expected to visit fewer than ``MIN_HITS`` times — or where ``q`` has less than ``STARVED``
   (1/4) of the density ``π* N(u*, I)`` would give at its FORM share
   ``π* = Φ(−β*)/(P̂ + Φ(−β*))`` (:func:`coverage_ratio`, the median over the branch; a
   *starved* branch: in 20-D the fit covered a branch of 45 % of P_f with 2–5 % of its points,
   and where a branch overlaps a covered one, ``q``'s draws in its half-space all lay near the
   other branch) — and which is relevant (``Φ(−β*) ≥ RELEVANCE · P̂``, ``P̂`` the last level's
   estimate), is a missed branch. The
   candidates the branch at ``u*`` accounts for (:func:`explained`: ``N(u*, I)`` reaches their
   half-space, or the tangent plane at ``u*`` predicts their ``G``) are then closed, and the
   next open one is searched (at most ``MAX_PROBES`` searches, together at most ``n_final``
   model calls: a search that would exceed them is stopped — the probe never costs more than
   the final sample).

Each missed branch enters the final density as ``N(u*, I)`` (the density of post-FORM
importance sampling; shares ``∝ Φ(−β*)``, their total ``b = ΣΦ(−β*)/(P̂ + ΣΦ(−β*))`` clipped to
``[B_MIN, B_MAX]``). The final estimate stays a plain IS run from a fixed density, unbiased for
any failure domain; the branch now contributes through well-placed points instead of not at all.
On a one-branch limit state every candidate is covered or its search returns the covered design
point: nothing is added, and the searches are the only cost.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import special

from surrogate_rbrdo.estimators._gmm import GaussianMixture
from surrogate_rbrdo.estimators.form import FORM

#: a half-space the final sample is expected to visit fewer times than this is not covered
MIN_HITS = 5.0
#: design-point searches at most per design
MAX_PROBES = 8
#: a branch visited less than this share of its fair number of points is starved: added too
STARVED = 0.25
#: a candidate lies on a found branch when its tangent plane predicts its G to this distance
LIN_TOL = 0.5
#: a missed branch counts when Φ(−β*) ≥ RELEVANCE · P̂
RELEVANCE = 1e-2
#: draws of the final density used to measure coverage (no model calls)
N_COVER = 4000
#: share of the first level searched for candidates (lowest G)
CANDIDATE_QUANTILE = 0.1
#: bounds of the total share of the final density given to the added branches
B_MIN, B_MAX = 0.05, 0.5
#: iterations of one probe search
PROBE_ITER = 30
#: draws from a found branch used to measure how well the final density covers it
N_RATIO = 400


@dataclass(frozen=True)
class DensityMix:
    """``Σ_i w_i q_i`` of densities with ``logpdf(v)`` and ``sample(n, rng)``.

    >>> n01 = GaussianMixture(np.ones(1), np.zeros((1, 1)), np.eye(1)[None])
    >>> mix = DensityMix(np.array([0.5, 0.5]), (n01, n01))
    >>> bool(np.isclose(mix.logpdf(np.zeros((1, 1)))[0], -0.5 * np.log(2 * np.pi)))
    True
    """

    weights: np.ndarray
    parts: tuple[Any, ...]

    def logpdf(self, v: np.ndarray) -> np.ndarray:
        """Log-density at the rows of ``v``."""
        with np.errstate(divide="ignore"):
            lw = np.log(self.weights)
        return special.logsumexp(
            np.column_stack([lw[i] + p.logpdf(v) for i, p in enumerate(self.parts)]), axis=1)

    def sample(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """Draw ``n`` points (in blocks per part; the order carries no information)."""
        counts = rng.multinomial(n, self.weights / self.weights.sum())
        return np.vstack([p.sample(int(c), rng)
                          for p, c in zip(self.parts, counts, strict=True) if c > 0])


def unit_gaussians(centres: np.ndarray, shares: np.ndarray) -> GaussianMixture:
    """``Σ π_k N(u_k, I)`` as a :class:`GaussianMixture`."""
    k, m = centres.shape
    return GaussianMixture(shares / shares.sum(), centres.copy(), np.repeat(np.eye(m)[None], k, 0))


def half_space_share(draws: np.ndarray, normals: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Share of ``draws`` in each half-space ``{w: n_j·w ≥ d_j}`` (unit normals ``(J, m)``).

    >>> w = np.array([[1.0, 0.0], [3.0, 0.0], [0.0, 3.0]])
    >>> half_space_share(w, np.array([[1.0, 0.0]]), np.array([2.0])).tolist()
    [0.3333333333333333]
    """
    return np.mean(draws @ normals.T >= offsets[None, :], axis=0)


@dataclass(frozen=True)
class ProbeResult:
    """Missed branches ``centres (K, m)`` with ``beta (K,)``, the searches run and their calls."""

    centres: np.ndarray
    beta: np.ndarray
    n_searches: int
    calls: int


def probe_missed(G: Any, q: Any, v1: np.ndarray, g1: np.ndarray, pf_hint: float, n_final: int,
                 form: FORM, rng: np.random.Generator) -> ProbeResult:
    """The failure branches the final density ``q`` misses (module docstring).

    ``v1``, ``g1``: the first-level standard-normal points and their ``G``; ``pf_hint``: the
    adapted estimate of P_f (relevance of a branch); ``G`` counts its calls.
    """
    m = v1.shape[1]
    calls0 = G.calls
    ok = np.isfinite(g1)
    if ok.sum() < 2:
        return ProbeResult(np.empty((0, m)), np.empty(0), 0, 0)
    cand = np.flatnonzero(ok & (g1 <= np.quantile(g1[ok], CANDIDATE_QUANTILE)))
    cand = cand[np.argsort(g1[cand])]
    radii = np.linalg.norm(v1[cand], axis=1)
    cand, radii = cand[radii > 0], radii[radii > 0]
    dirs = v1[cand] / radii[:, None]
    draws = q.sample(N_COVER, rng)
    open_ = n_final * half_space_share(draws, dirs, radii) < MIN_HITS
    centres, betas, searches, g0 = [], [], 0, None

    def spent(_iterate: np.ndarray | None = None) -> bool:
        """The probe's budget is used up (also the searches' ``stop``, called per iterate)."""
        return G.calls - calls0 >= n_final

    while open_.any() and searches < MAX_PROBES and not spent():
        j = int(np.flatnonzero(open_)[0])
        open_[j] = False
        if g0 is None:
            g0 = float(G(np.zeros((1, m)))[0])
        dp = form.run(G, m, start=(v1[cand[j]], g0), max_iter=PROBE_ITER, stop=spent)
        searches += 1
        if dp.status != "converged" or not dp.beta > 0:
            continue
        u_star = np.asarray(dp.u_star, dtype=float)
        beta = float(np.linalg.norm(u_star))
        open_ &= ~explained(v1[cand], g1[cand], dirs, radii, u_star, np.asarray(dp.grad))
        hits = n_final * half_space_share(draws, (u_star / beta)[None], np.array([beta]))[0]
        p_k = float(special.ndtr(-beta))
        relevant = special.log_ndtr(-beta) >= np.log(RELEVANCE * max(pf_hint, 1e-300))
        new = all(np.linalg.norm(u_star - c) > 0.5 * beta for c in centres)
        share = p_k / (max(pf_hint, 0.0) + p_k) if p_k > 0 else 0.0
        starved = coverage_ratio(q, u_star, rng) < STARVED * share
        if (hits < MIN_HITS or starved) and relevant and new:
            centres.append(u_star)
            betas.append(beta)
    return ProbeResult(np.array(centres).reshape(-1, m), np.array(betas, dtype=float),
                       searches, G.calls - calls0)


def coverage_ratio(q: Any, u_star: np.ndarray, rng: np.random.Generator,
                   n: int = N_RATIO) -> float:
    """Median of ``q(w) / φ(w − u*)`` over the branch at ``u*``: ``w`` drawn from ``N(u*, I)``
    folded into the half-space ``{a*·w ≥ β*}`` (no model calls).

    A density that samples the branch as well as ``π N(u*, I)`` would gives about ``π``. The
    share of ``q``'s draws in the half-space cannot tell: where the branch overlaps a covered
    one (two branches of a series system at ρ = 0.45 in 15-D) ``q`` put 4 % of its draws in
    the half-space, all of them near the covered branch and none near ``u*``, and the branch
    (18 % of P_f) was lost in 2 of 19 unwarned runs, 4–5 SE low.

    >>> n01 = GaussianMixture(np.ones(1), np.zeros((1, 2)), np.eye(2)[None])
    >>> at = GaussianMixture(np.ones(1), np.array([[3.0, 0.0]]), np.eye(2)[None])
    >>> rng = np.random.default_rng(0)
    >>> float(coverage_ratio(at, np.array([3.0, 0.0]), rng))
    1.0
    >>> bool(coverage_ratio(n01, np.array([3.0, 0.0]), rng) < 0.02)
    True
    """
    beta = float(np.linalg.norm(u_star))
    a = u_star / beta
    z = rng.standard_normal((n, u_star.size))
    along = z @ a
    w = u_star + z + (np.abs(along) - along)[:, None] * a[None, :]
    log_phi = -0.5 * np.sum((w - u_star) ** 2, axis=1) - 0.5 * u_star.size * np.log(2 * np.pi)
    return float(np.exp(np.median(q.logpdf(w) - log_phi)))


def explained(v: np.ndarray, g: np.ndarray, dirs: np.ndarray, radii: np.ndarray,
              u_star: np.ndarray, grad: np.ndarray) -> np.ndarray:
    """Candidates ``v`` (values ``g``) the branch at design point ``u*`` accounts for: its
    density ``N(u*, I)`` reaches their half-space with probability ≥ 1 %, or the tangent plane
    at ``u*`` predicts their ``G`` to within ``LIN_TOL`` in distance (``|∇G·(v − u*) − g| ≤
    LIN_TOL ‖∇G‖``; in many dimensions a candidate's radius is mostly noise across the branch,
    and only the second test recognises it).

    Series system ``G = min(3 − u₁, 3 − u₂)``; the branch of ``u₁`` (``u* = 3 e₁``) accounts
    for the first candidate, not for the second (on the branch of ``u₂``):

    >>> v = np.array([[2.5, 2.0, -1.5], [0.1, 2.6, 1.0]])
    >>> g = np.minimum(3.0 - v[:, 0], 3.0 - v[:, 1])
    >>> r = np.linalg.norm(v, axis=1)
    >>> u_star, grad = np.array([3.0, 0, 0]), np.array([-1.0, 0, 0])
    >>> explained(v, g, v / r[:, None], r, u_star, grad).tolist()
    [True, False]
    """
    near = special.ndtr(dirs @ u_star - radii) >= 1e-2
    ng = float(np.linalg.norm(grad))
    if not (np.isfinite(ng) and ng > 0):
        return near
    return near | (np.abs((v - u_star) @ grad - g) <= LIN_TOL * ng)


def augment(q: Any, probe: ProbeResult, pf_hint: float) -> Any:
    """``(1 − b) q + b Σ π_k N(u_k, I)`` for the missed branches (``q`` itself if none)."""
    if probe.beta.size == 0:
        return q
    p = special.ndtr(-probe.beta)
    b = float(np.clip(p.sum() / (max(pf_hint, 0.0) + p.sum()), B_MIN, B_MAX))
    return DensityMix(np.array([1.0 - b, b]), (q, unit_gaussians(probe.centres, p)))


__all__ = ["DensityMix", "ProbeResult", "augment", "coverage_ratio", "explained",
           "half_space_share", "probe_missed", "unit_gaussians"]
