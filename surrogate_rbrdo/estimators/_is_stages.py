"""The two stages of :class:`~surrogate_rbrdo.estimators.importance.ImportanceSampling` for one
design (and one phase stratum, :mod:`._periodic`): see that module's docstring."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
from scipy import special

from surrogate_rbrdo.estimators._common import LimitStateU, nan_p
from surrogate_rbrdo.estimators._design_points import design_point_from
from surrogate_rbrdo.estimators._is_density import (
    MixtureDraws,
    ScaledGaussians,
    cv_estimate,
    shell_share,
)
from surrogate_rbrdo.estimators._tail import pareto_khat

#: share of the second stage drawn from the first stage's mixture (defensive, Hesterberg 1995)
STAGE2_DEFENSIVE = 0.2
#: searches for further design points started from first-stage samples
DISCOVERY_TRIES = 2
#: a tail sample failing deeper than every tangent plane by this distance is unexplained
LIN_TOL = 0.05
#: a design point found after sampling is reported when Φ(−β) ≥ LATE_RELEVANCE · P̂
LATE_RELEVANCE = 0.01


class Stages:
    """The two IS stages for one design (see the module docstring)."""

    def __init__(self, est: Any, G: LimitStateU, pts: list, u: np.ndarray
                 ) -> None:
        self.est, self.G, self.u, self.pts, self.dp = est, G, u, list(pts), pts[0]
        m, n = u.shape[1], u.shape[0]
        beta, centres, shares = geometry(self.pts)
        a = (0.0 if self.dp.status == "not_reached"      # one region by construction
             else shell_share(est.defensive, est.shell, self.dp.beta, m, n))
        n_shell = int(round(a * n))
        self.two = est.pilot < 1.0 and self.dp.status == "converged"
        self.n1 = n_shell + max(2, int(round(est.pilot * (n - n_shell)))) if self.two else n
        self.two = self.two and n - self.n1 >= 2
        self.q1 = MixtureDraws(centres, shares, est.shell * abs(self.dp.beta),
                               n_shell / self.n1 if self.two else a)
        # the tail beyond the design points: failures when the mean is safe, survivals when it
        # fails; for a limit state not reached, the superset {G <= G(u_b)} ({G >= G(u_b)})
        self.level = self.dp.g_star if self.dp.status == "not_reached" else 0.0

    def _tail(self, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        g = self.G(v)
        if self.dp.status == "not_reached":
            fail = g <= self.level if self.dp.beta >= 0 else g < self.level
        else:
            fail = g < 0
        return (fail if self.dp.beta >= 0 else ~fail), fail, g

    def _stage(self, v: np.ndarray, logq: Any, pts: list) -> dict:
        beta, c, _ = geometry(pts)
        tail, fail, g = self._tail(v)
        logw = -0.5 * np.einsum("ij,ij->i", v, v) - logq(v)
        w_floor = float(np.exp(np.max(-0.5 * np.sum(c * c, axis=1) - logq(c))))
        half = v @ c.T >= np.sum(c * c, axis=1)
        r = cv_estimate(tail, half, logw, beta, w_floor)
        wt = np.where(tail, np.exp(np.where(tail, logw, 0.0)), 0.0)
        outside = ~half.any(axis=1)
        return {"r": r, "v": v, "wt": wt, "fail": fail, "outside": tail & outside, "g": g,
                "n_other": int(np.sum(tail & outside)),
                "other": wt[outside].sum() / wt.sum() if wt.sum() > 0 else 0.0}

    def _discover(self, s1: dict) -> list:
        """Further design points from the first stage's samples that no known design point
        accounts for: tail samples outside every known half-space (found there by the shell),
        the heaviest first; then samples, failing or not, whose ``G`` lies deeper than every
        design point's tangent plane predicts (:func:`unexplained`: a branch of a series system
        that overlaps a known one and that no sample reached), the most deeply failing (lowest
        ``G``) first. A search on the deflected function from such a sample, then from the mirror
        image of what it found, while any remain (at most ``DISCOVERY_TRIES`` searches from
        samples: on a failure domain that bends back every search ends in a bulge)."""
        pts = list(self.pts)
        if self.dp.status != "converged" or self.dp.beta < 0:
            return pts
        v, wt, g = s1["v"], s1["wt"], s1["g"]
        tried = np.zeros(v.shape[0], dtype=bool)
        for _ in range(DISCOVERY_TRIES):
            if len(pts) >= self.est.n_design_points:
                break
            c = geometry(pts)[1]
            outside = ~(v @ c.T >= np.sum(c * c, axis=1)).any(axis=1)
            left = (wt > 0) & outside & ~tried
            deep = unexplained(v, g, pts) & ~tried
            if left.any():
                j = np.flatnonzero(left)[np.argmax(wt[left])]
            elif deep.any():        # the most deeply failing (lowest G) first
                j = np.flatnonzero(deep)[np.argmin(g[deep])]
            else:
                break
            tried[j] = True
            dp = design_point_from(self.G, v.shape[1], pts, self.est.form, v[j])
            if dp is None:
                continue
            pts.append(dp)
            mirror = design_point_from(self.G, v.shape[1], pts, self.est.form, -dp.u_star)
            if mirror is not None and len(pts) < self.est.n_design_points:
                pts.append(mirror)
        return pts

    def _late(self, s2: dict, pts: list) -> float:
        """``β`` of a relevant design point found *after* sampling, NaN if none: one search on
        the deflected function from the most deeply failing (lowest ``G``) second-stage sample
        among those below every tangent plane (:func:`unexplained`), run only where there is one.
        The density did not include it, so ``P_f`` may be low by up to ``Φ(−β)``: the caller
        warns (a branch hidden behind a known one that no first-stage sample revealed)."""
        if self.dp.status != "converged" or self.dp.beta < 0:
            return np.nan
        v, g = s2["v"], s2["g"]
        deep = unexplained(v, g, pts)
        if not deep.any():
            return np.nan
        j = np.flatnonzero(deep)[np.argmin(g[deep])]
        dp = design_point_from(self.G, v.shape[1], pts, self.est.form, v[j])
        if dp is None:
            return np.nan
        beta = float(np.linalg.norm(dp.u_star))
        p = max(float(s2["r"].p), 1e-300)          # of the sampled tail, as Φ(−β)
        relevant = special.log_ndtr(-beta) >= np.log(LATE_RELEVANCE * p)
        return beta if relevant else np.nan

    def run(self, out: Collect, i: int) -> None:
        """Fill row ``i`` of ``out``."""
        n_out0 = self.G.n_outside
        v1, comp = self.q1.points(self.u[: self.n1])
        s1 = self._stage(v1, self.q1.logpdf, self.pts)
        stages, pts = [s1], self.pts
        khat = pareto_khat(s1["wt"][comp >= 0])
        if self.two:
            pts = self._discover(s1)
            _, centres, shares = geometry(pts)
            comp_all = comp if len(pts) == len(self.pts) else np.where(comp >= 0, comp, -1)
            sg = ScaledGaussians.fit(v1, s1["wt"], comp_all, centres, shares)
            u2 = self.u[self.n1:]
            nd = int(round(STAGE2_DEFENSIVE * u2.shape[0]))
            v2 = np.vstack([self.q1.points(u2[:nd])[0], sg.points(u2[nd:])])

            def logq2(v: np.ndarray) -> np.ndarray:
                return np.logaddexp(np.log(STAGE2_DEFENSIVE) + self.q1.logpdf(v),
                                    np.log1p(-STAGE2_DEFENSIVE) + sg.logpdf(v))

            stages.append(self._stage(v2, logq2, pts))
            khat = pareto_khat(stages[1]["wt"])
            out.diag["late_beta"][i] = self._late(stages[1], pts)
        # the estimate is the last stage's: given the first stage, the second is a plain IS
        # run from a fixed density (an inverse-variance combination would favour the runs
        # that land low, whose reported errors are small too)
        last = stages[-1]
        # a probability: the control-variate estimate (or its complement) projected on [0, 1]
        out.pf[i] = np.clip(last["r"].p if self.dp.beta >= 0 else 1.0 - last["r"].p, 0.0, 1.0)
        out.se[i] = last["r"].se
        out.stages[i, : len(stages)] = [st["r"].p for st in stages]
        out.nfail[i] = sum(int(st["fail"].sum()) for st in stages)
        out.ndis[i] = sum(st["r"].n_disagree for st in stages)
        out.n_other[i] = last["n_other"]
        out.nout[i] = self.G.n_outside - n_out0
        beta = geometry(pts)[0]
        out.beta[i], out.ustar[i], out.n_dp[i] = self.dp.beta, self.dp.u_star, beta.size
        out.betas[i, : beta.size] = beta
        out.diag["ess"][i] = last["r"].ess
        out.diag["shell_share"][i] = self.q1.a
        out.diag["pareto_k"][i] = khat
        out.diag["other_share"][i] = last["other"]


def unexplained(v: np.ndarray, g: np.ndarray, pts: list) -> np.ndarray:
    """Samples ``v`` (values ``g`` of the sampled tail's function) that fail deeper than every
    design point's tangent plane predicts, by more than ``LIN_TOL`` in distance:
    ``min_k (G_k(v) − g) / ‖∇G(u_k)‖ > LIN_TOL`` with ``G_k(v) = G(u_k) + ∇G(u_k)·(v − u_k)``.

    On a series system every branch's samples lie on their own branch's plane; a sample of a
    branch no design point has found fails deeper than all of them, even where it lies in a
    known point's half-space (3-branch system in 6-D, branches 1 and 2 at ρ = 0.45: half of
    branch 2 lies beyond branch 1's hyperplane, and IS reported the two-branch value 7–23 SE
    low in 5 of 8 runs). A failure domain curved away from the origin (convex) fails *less*
    deeply than its tangent plane and is never flagged.

    >>> from types import SimpleNamespace as NS
    >>> pts = [NS(u_star=np.array([3.0, 0.0]), grad=np.array([-1.0, 0.0]), g_star=0.0)]
    >>> v = np.array([[3.2, 0.1], [3.2, 3.5]])
    >>> g = np.minimum(3.0 - v[:, 0], 3.0 - v[:, 1])    # second sample on the u₂ branch
    >>> unexplained(v, g, pts).tolist()
    [False, True]
    """
    depth = np.full(v.shape[0], np.inf)
    for q in pts:
        grad = np.asarray(q.grad, dtype=float)
        ng = float(np.linalg.norm(grad))
        if not (np.isfinite(ng) and ng > 0):
            return np.zeros(v.shape[0], dtype=bool)
        g_lin = float(q.g_star) + (v - q.u_star) @ grad
        depth = np.minimum(depth, (g_lin - g) / ng)
    return np.isfinite(g) & (depth > LIN_TOL)


def geometry(pts: list) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``β_k = ±‖u_k‖``, centres ``u_k`` and shares ``π_k ∝ Φ(−|β_k|)`` of a list of design
    points (the distance itself, not FORM's β clipped at ``beta_max`` when not reached: the
    half-space at ``u_k`` has probability ``Φ(−‖u_k‖)``)."""
    beta = np.array([np.copysign(np.linalg.norm(q.u_star), q.beta) for q in pts])
    shares = special.ndtr(-np.abs(beta))
    shares = shares / shares.sum() if shares.sum() > 0 else np.full(len(pts), 1 / len(pts))
    return beta, np.array([q.u_star for q in pts]), shares


class Negated:
    """``−G`` with ``G``'s call counters: the limit-state function whose failure domain is the
    safe set of ``G`` (points outside the physical domain, ``G = +inf``, become ``−inf``: they
    count with the safe set, so ``1 − P(−G < 0)`` is ``P(failure and inside)``)."""

    def __init__(self, G: Any) -> None:
        self.G = G

    def __getattr__(self, name: str) -> Any:       # calls, n_outside, scale, last_y
        return getattr(self.G, name)

    def __call__(self, u: np.ndarray) -> np.ndarray:
        return -self.G(u)


def negated(dp: Any) -> Any:
    """The design point ``dp`` of ``G`` as one of ``−G`` (same ``u*``, signs flipped)."""
    return replace(dp, beta=-dp.beta, alpha=-np.asarray(dp.alpha), grad=-np.asarray(dp.grad),
                   g_star=-dp.g_star, g_origin=-dp.g_origin)


def complement(out: Collect, i: int, n: int) -> None:
    """Row ``i`` of ``out`` filled for ``−G`` (``P(safe)``, ``n`` points) turned into ``G``'s:
    ``P_f = 1 − P(safe)`` (same SE), the β's negative, failures counted in ``G``'s domain."""
    out.pf[i] = 1.0 - out.pf[i]
    out.stages[i] = 1.0 - out.stages[i]
    out.beta[i], out.betas[i] = -out.beta[i], -out.betas[i]
    out.nfail[i] = n - out.nfail[i]


class Collect:
    """Per-design results of :class:`ImportanceSampling` (arrays of length P)."""

    def __init__(self, p: int, m: int, k: int) -> None:
        self.pf, self.se, self.beta = nan_p(p), nan_p(p), nan_p(p)
        self.diag = {key: nan_p(p) for key in ("ess", "pareto_k", "other_share", "late_beta",
                                               "shell_share", "n_mc_strata")}
        self.nfail, self.ndis, self.nout = (np.zeros(p, int) for _ in range(3))
        self.n_other, self.n_dp = np.zeros(p, int), np.zeros(p, int)
        self.ustar, self.betas = np.full((p, m), np.nan), np.full((p, k), np.nan)
        self.stages = np.full((p, 2), np.nan)
        self.status = np.full(p, "failed", dtype=object)
        self.calls = self.form_calls = 0
