"""Null distributions of the workflow's test statistics, by a linearised parametric bootstrap.

Under "nothing is missing" the data are the fitted model plus noise. Each draw simulates what
the workflow computes: noise on every cell from its estimated covariance, a *new covariance
estimate* from the same number of repeats (with the run-to-run structure of a repeated speed
sweep, :mod:`.noise`), the unbiased precision from it, whitening, the recalibration of the
nuisance (projection on the whitened Jacobian of the outer parameters and the unbalance), and
then the statistics:

* ``gof``: the χ² of the recalibrated model;
* ``candidates``: per candidate, the likelihood-ratio statistic ``Δχ²`` of adding it, maximised
  over its variants (the sup-LR over a parameter that vanishes under the null: Davies 1987,
  *Biometrika* 74:33); one-sided where its strength is (``Δ = max(z, 0)²``). The variants cover
  what the nonlinear search reaches, since a maximum over more shapes is larger under the null
  too: every bearing scope; the shape starts and the first shape parameter over the range the
  search's valley steps through (:func:`~.search.valley_grid`); and for a candidate with a
  shape, secants to the screened strengths (a housing's first-order column does not depend on
  its mass: the mass acts only once the spring is soft enough, where the fit may put it);
* ``structure``: a Gaussian-process likelihood ratio on the residuals along speed (or frequency),
  maximised over a grid of length scales and variances — the Kennedy–O'Hagan discrepancy
  (2001, *J. R. Stat. Soc. B* 63:425) used as a test: it detects structure, it cannot name it;
* ``generic``: the largest one-parameter likelihood ratio among the generic local sensitivities
  (:mod:`.generic`: the stiffness and mass of each element, each disk, a spring at each node)
  on the residual — a lack-of-fit test aimed at a local structural change, which a library
  effect can mimic in part but leaves a residual along.

So the thresholds account for the finite number of repeats, the fitted nuisance, the maximisation
over scopes and shapes and, through the minimum p-value over candidates, for the number of
candidates tried (Westfall & Young, *Resampling-Based Multiple Testing*, 1993, single-step
min-p). The linearisation is at the recalibrated fit; at the noise levels of the campaigns its
curvature error is far below the noise (checked by the null rates of the blind grid).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.stats import chi2

from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.discrepancy.candidates import Candidate
from surrogate_rbrdo.discrepancy.fit import FD_STEP, Fit
from surrogate_rbrdo.discrepancy.generic import generic_columns, generic_labels
from surrogate_rbrdo.discrepancy.impedance import acts_on_rotor
from surrogate_rbrdo.discrepancy.noise import NoiseModel
from surrogate_rbrdo.discrepancy.problem import Problem
from surrogate_rbrdo.discrepancy.search import screen_values, valley_grid

#: shape values per decade of a candidate's first shape parameter among its variants, over the
#: range the search's valley covers (:func:`~.search.valley_grid`; module doc)
SHAPE_PER_DECADE = 6
#: a secant variant stands for the fits near its point ``g`` (its amplitude is free); it is kept
#: only for an effect of at most this whitened, nuisance-orthogonal norm: under the null the fit
#: at a larger one has a positive likelihood ratio ``2 z |g| − |g|²`` only when the noise
#: projection ``z`` exceeds ``|g| / 2 = 6`` (probability 1e-9)
SECANT_MAX_NORM = 12.0
#: GP length scales (fraction of the speed or frequency span) and variances of the structure test
GP_LENGTHS = (0.03, 0.08, 0.2, 0.5)
GP_TAUS = tuple(np.geomspace(1e-2, 1e3, 16).tolist())
#: model rows evaluated at once by :func:`linearise` (bounds its memory, not its answers)
ROW_BLOCK = 256


@dataclass(frozen=True)
class Variant:
    """One (scope, shape) of a candidate and its unwhitened columns: the Jacobian of its
    strengths at the off state or, when ``secant`` is not 0, the secant ``(f(s) − f(off)) / s``
    to the first strength's value ``off + secant`` (one column)."""

    scope: tuple[str, ...]
    shape: tuple[tuple[str, float], ...]
    columns: np.ndarray  # (n_obs, n_strength)
    secant: float = 0.0


@dataclass(frozen=True)
class Linearisation:
    """Unwhitened Jacobians at a fit: nuisance (outer and unbalance) and candidate columns."""

    nuisance: np.ndarray                        # (n_obs, p)
    candidates: tuple[tuple[Candidate, tuple[Variant, ...]], ...]
    absorbed: tuple[str, ...]                   # candidates the nuisance absorbs entirely
    generic: np.ndarray                         # (n_obs, r) leading generic directions
    n_theta: int = 0                            # nuisance columns of the stiffness factors
    generic_labels: tuple[str, ...] = ()        # what each generic column changes
    generic_bounds: np.ndarray | None = None    # (r, 2) plausible range, in column units


def _shape_grid(c: Candidate) -> list[tuple[tuple[str, float], ...]]:
    """The shapes of a candidate's variants: its shape starts and, for the first shape
    parameter, the range the search's valley covers (:func:`~.search.valley_grid` at
    :data:`SHAPE_PER_DECADE`); the starts first, in their order."""
    grids = [[]]
    for i, (p, starts) in enumerate(zip(c.shape, c.shape_starts, strict=True)):
        values = list(starts)
        if i == 0:
            values += [float(v) for v in valley_grid(c, SHAPE_PER_DECADE) if v not in starts]
        grids = [g + [(p, v)] for g in grids for v in values]
    return [tuple(g) for g in grids]


def _variant_rows(c: Candidate, scope, shape, base_extras, secants: bool):
    """The model rows of one (scope, shape) of ``c``: a small step of each strength off the
    off state (derivative columns) or, with ``secants``, the first strength at each screened
    value (:func:`~.search.screen_values`); each row with its step."""
    vals0 = {p: o for p, o in zip(c.strength, c.off, strict=True)} | dict(shape)
    out = []
    if secants:
        for v in screen_values(c):
            out.append((base_extras + (c.effect(scope, vals0 | {c.strength[0]: float(v)}),),
                        float(v) - c.off[0]))
        return out
    for i, (o, lo_i, hi_i, rec) in enumerate(zip(c.off, c.lower, c.upper, c.reciprocal,
                                                 strict=True)):
        step = 1e-3 * (1e-9 if rec else max(hi_i - lo_i, 1e-6) / 50.0)
        step = step if o + step <= hi_i else -step
        out.append((base_extras + (c.effect(scope, vals0 | {c.strength[i]: o + step}),), step))
    return out


def linearise(problem: Problem, base: Fit, candidates: tuple[Candidate, ...]) -> Linearisation:
    """Jacobians of the unwhitened observables at ``base`` (unbalance held at its fit)."""
    par, x = base.par, base.x
    u = tuple(v[0] for v in base.evaluation.unbalance)
    # nuisance outer columns
    h = FD_STEP * np.maximum(np.abs(x), par.scales())
    lo, hi = par.bounds()
    h = np.where(x + h > hi, -h, h)
    f = problem.model_vector(par, np.vstack([x[None], x[None] + np.diag(h)]), u)
    J = ((f[1:] - f[0]) / h[:, None]).T
    nuis = np.hstack([J, problem.unbalance_design(par, x)])
    # candidate columns: one batch of rows, each its own extra effect; the derivative columns
    # first, then (for a candidate with a shape) the secants along its first strength
    specs, ex_rows = [], []
    extras = par.rows(x[None]).extras[0]
    for secants in (False, True):
        for c in candidates:
            if secants and not c.shape:
                continue
            for scope in c.scopes:
                for shape in _shape_grid(c):
                    rows = _variant_rows(c, scope, shape, extras, secants)
                    ex_rows += [r for r, _ in rows]
                    if secants:
                        specs += [(c, scope, shape, np.array([h]), h) for _, h in rows]
                    else:
                        specs.append((c, scope, shape, np.array([h for _, h in rows]), 0.0))
    # in blocks of rows: the model's work arrays for thousands of rows at once are large
    fc = np.empty((len(ex_rows), f.shape[1]))
    rb = par.rows(x[None])
    for i in range(0, len(ex_rows), ROW_BLOCK):
        ex = ex_rows[i:i + ROW_BLOCK]
        # a candidate leaves the nuisance's prior pseudo-observations as they are at ``x``
        fc[i:i + len(ex)] = np.hstack([
            problem.data_vector(replace(rb.repeat(len(ex)), extras=ex), u),
            np.broadcast_to(f[0, f.shape[1] - problem.n_prior:], (len(ex), problem.n_prior))])
    out: dict[str, list[Variant]] = {}
    k = 0
    for c, scope, shape, steps, secant in specs:
        cols = ((fc[k:k + steps.size] - f[0]) / steps[:, None]).T
        k += steps.size
        out.setdefault(c.name, []).append(Variant(scope, shape, cols, secant))
    W = _data_whitening(problem)
    Q, _ = np.linalg.qr(_apply(W, nuis))
    kept, absorbed = [], []
    for c in candidates:
        vs = _distinct(out[c.name], W, Q)
        (kept.append((c, tuple(vs))) if vs else absorbed.append(c.name))
    G, labels, bounds = _generic_basis(problem, base, W, Q)
    return Linearisation(nuis, tuple(kept), tuple(absorbed), G, par.sizes[0], labels, bounds)


def _generic_basis(problem: Problem, base: Fit, W, Q
                   ) -> tuple[np.ndarray, tuple[str, ...], np.ndarray]:
    """The generic sensitivities that the nuisance does not absorb (relative residual norm
    above 1e-6 once it is projected out), as unwhitened columns scaled to unit whitened,
    nuisance-orthogonal norm; their labels and plausible ranges in those units."""
    G = generic_columns(problem, base)
    labels = generic_labels(problem.forward.model(
        tuple(e for e in base.par.rows(base.x[None]).extras[0] if acts_on_rotor(e))))
    Gw = _apply(W, G)
    n0 = np.linalg.norm(Gw, axis=0)
    n1 = np.linalg.norm(Gw - Q @ (Q.T @ Gw), axis=0)
    keep = n1 > 1e-6 * np.maximum(n0, 1e-300)
    bounds = np.array([[lo, hi] for _, lo, hi in labels]).reshape(-1, 2)[keep] * n1[keep, None]
    return (G[:, keep] / n1[keep], tuple(lb for (lb, _, _), k in zip(labels, keep, strict=True)
                                         if k), bounds)


def _distinct(variants: list[Variant], W, Q) -> list[Variant]:
    """Drop strength columns the nuisance absorbs (relative residual < 1e-6), variants left
    without a column, secants to effects larger than :data:`SECANT_MAX_NORM` (whitened,
    nuisance-orthogonal norm), and duplicates (|cos| > 0.9999 in that metric)."""
    keep, dirs = [], []
    for v in variants:
        U = _apply(W, v.columns)
        n0 = np.linalg.norm(U, axis=0)
        U = U - Q @ (Q.T @ U)
        n1 = np.linalg.norm(U, axis=0)
        live = n1 > 1e-6 * np.maximum(n0, 1e-300)
        if not live.any() or abs(v.secant) * n1[0] > SECANT_MAX_NORM:
            continue
        v = Variant(v.scope, v.shape, v.columns[:, live], v.secant)
        d = U[:, live][:, 0] / np.linalg.norm(U[:, live][:, 0])
        if live.sum() == 1 and any(abs(d @ e) > 0.9999 for e in dirs):
            continue
        dirs.append(d)
        keep.append(v)
    return keep


def _data_whitening(problem: Problem) -> tuple[np.ndarray, np.ndarray]:
    Wc = np.concatenate([w.reshape(-1, 2, 2) for w in problem.whiten])
    _, _, sd, _ = problem.noise_cells()
    return Wc, 1.0 / sd


def _apply(W: tuple[np.ndarray, np.ndarray], M: np.ndarray, transpose: bool = False
           ) -> np.ndarray:
    """Whiten unwhitened columns ``M`` (n_obs, k) (or a batch (B, n_obs, k) with batched W);
    with ``transpose`` apply ``Wᵀ``."""
    Wc, wr = W
    if transpose:
        Wc = np.swapaxes(Wc, -1, -2)
    nc = 2 * Wc.shape[-3]
    Mc = M[..., :nc, :].reshape(M.shape[:-2] + (nc // 2, 2, M.shape[-1]))
    Yc = (Wc @ Mc).reshape(M.shape[:-2] + (nc, M.shape[-1]))
    return np.concatenate([Yc, M[..., nc:, :] * wr[..., :, None]], axis=-2)


@dataclass(frozen=True)
class TailModel:
    """``P(T > t) ≈ π₊ · P(a χ²_d > t)``, moments matched on the positive draws."""

    pi_pos: float
    scale: float
    df: float

    @classmethod
    def from_draws(cls, t: np.ndarray) -> TailModel:
        pos = t[t > 1e-12]
        if pos.size < 10:
            return cls(max(pos.size / max(t.size, 1), 1e-12), 1.0, 1.0)
        m, v = pos.mean(), pos.var(ddof=1)
        return cls(pos.size / t.size, v / (2 * m), 2 * m * m / v)

    def sf(self, t: np.ndarray | float) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        return np.where(t > 1e-12, self.pi_pos * chi2.sf(t / self.scale, self.df), 1.0)

    def isf(self, p: float) -> float:
        """The statistic whose tail probability is ``p`` (0 if ``p >= π₊``)."""
        if p >= self.pi_pos:
            return 0.0
        return float(self.scale * chi2.isf(p / self.pi_pos, self.df))


def kernel_eigs(series: list[tuple[int, int, int, np.ndarray]]) -> list[list[tuple]]:
    """Per block and length scale the eigenpairs of the squared-exponential kernel."""
    out = []
    for _, _, _, t in series:
        row = []
        for ell in GP_LENGTHS:
            K = np.exp(-0.5 * ((t[:, None] - t[None, :]) / ell) ** 2)
            lam, U = np.linalg.eigh(K)
            row.append((np.clip(lam, 0.0, None), U))
        out.append(row)
    return out


def gp_statistic(r: np.ndarray, series: list[tuple[int, int, int, np.ndarray]],
                 eig: list[list[tuple]] | None = None) -> np.ndarray:
    """Structure statistic of whitened residuals ``r`` (..., n): per block the GP
    likelihood ratio ``max_{ℓ, τ} Σ_j [q_j τλ_j/(1 + τλ_j) − m log(1 + τλ_j)]``, summed over
    blocks (``λ_j`` eigenvalues of the squared-exponential kernel over the block's points,
    ``q_j`` the squared projections of its ``m = 2C`` residual series)."""
    eig = kernel_eigs(series) if eig is None else eig
    total = np.zeros(r.shape[:-1])
    taus = np.asarray(GP_TAUS)
    for (off, X, C, _), pairs in zip(series, eig, strict=True):
        R = r[..., off:off + 2 * X * C].reshape(r.shape[:-1] + (X, 2 * C))
        best = np.zeros(r.shape[:-1])
        for lam, U in pairs:
            q = np.sum((U.T @ R) ** 2, axis=-1)                              # (..., X)
            tl = taus[:, None] * lam[None, :]                                # (T, X)
            lr = (q[..., None, :] * (tl / (1 + tl))).sum(-1) - 2 * C * np.log1p(tl).sum(-1)
            best = np.maximum(best, lr.max(axis=-1))
        total = total + best
    return total


@dataclass(frozen=True)
class NullDistribution:
    """Bootstrap draws of the statistics under "nothing is missing"."""

    gof: np.ndarray                  # (n,)
    structure: np.ndarray            # (n,)
    generic: np.ndarray              # (n,)
    candidates: np.ndarray           # (n, K) Δχ² per candidate
    names: tuple[str, ...]

    def tails(self) -> list[TailModel]:
        return [TailModel.from_draws(self.candidates[:, k]) for k in range(len(self.names))]

    def min_p(self) -> np.ndarray:
        """Per draw the smallest candidate p-value (marginal tails from the draws)."""
        if not self.names:
            return np.ones(self.gof.size)
        tails = self.tails()
        p = np.stack([tl.sf(self.candidates[:, k]) for k, tl in enumerate(tails)], axis=1)
        return p.min(axis=1)

    def critical_p(self, alpha: float) -> float:
        """The marginal p-value a candidate must reach for family-wise level ``alpha``."""
        return float(np.quantile(self.min_p(), alpha))

    def adjusted(self, p_raw: float) -> float:
        """Family-wise adjusted p-value of a candidate with marginal p ``p_raw`` (single-step
        min-p): the probability that some candidate reaches a p this small by chance."""
        mp = self.min_p()
        return float((1 + np.sum(mp <= p_raw)) / (1 + mp.size))

    def p_value(self, stat: str, value: float) -> float:
        """Upper-tail p-value of the ``gof``, ``structure`` or ``generic`` statistic (empirical,
        moment-matched in the far tail)."""
        draws = getattr(self, stat)
        tl = TailModel.from_draws(draws)
        emp = (1 + np.sum(draws >= value)) / (1 + draws.size)
        return float(max(tl.sf(value), 0.0)) if emp * draws.size < 20 else float(emp)


def simulate_null(problem: Problem, lin: Linearisation, *, n_draws: int,
                  rng: np.random.Generator, chunk: int = 25) -> NullDistribution:
    """Draw the statistics ``n_draws`` times under the recalibrated model (see module doc).

    Per draw only the nuisance columns are whitened and factorised; a one-column variant's
    statistic ``(uᵀr)² / uᵀu`` (``u`` its whitened column less its projection on them) comes
    from products with the unwhitened columns (:class:`_Singles`), so memory does not grow
    with the number of variants. Variants with several columns are projected explicitly.
    """
    rng = require_rng(rng)
    noise = NoiseModel.of(problem, lin.nuisance[:, :lin.n_theta], _data_whitening(problem)[0])
    N = lin.nuisance
    singles = _Singles.of(problem, lin)
    multi = [(order, v.columns) for order, (c, vs) in enumerate(lin.candidates) for v in vs
             if v.columns.shape[1] > 1]
    series = problem.series()
    eig = kernel_eigs(series)
    gof, struct, cand, gen = [], [], [], []
    names = tuple(c.name for c, _ in lin.candidates)
    left = n_draws
    while left > 0:
        B = min(chunk, left)
        left -= B
        e, W, wr = noise.draw(B, rng)
        Wb = (W, wr)
        ew = _apply(Wb, e[..., None])[..., 0]
        Q, _ = np.linalg.qr(_apply(Wb, np.broadcast_to(N, (B,) + N.shape)))
        r = ew - _project_on(Q, ew)
        gof.append(np.sum(r**2, axis=1))
        struct.append(gp_statistic(r, series, eig))
        d = singles.statistics(Wb, Q, r)                     # (B, columns)
        out = np.zeros((B, len(names)))
        for k, sl in enumerate(singles.candidate_slices):
            if sl.stop > sl.start:
                out[:, k] = d[:, sl].max(axis=1)
        for k, M in multi:
            U = _apply(Wb, np.broadcast_to(M, (B,) + M.shape))
            U = U - _project_on(Q, U)
            out[:, k] = np.maximum(out[:, k], np.einsum("bn,bn->b", r, _project(U, r)))
        cand.append(out)
        g = singles.generic_slice
        gen.append(d[:, g].max(axis=1) if g.stop > g.start else np.zeros(B))
    K = len(names)
    return NullDistribution(np.concatenate(gof), np.concatenate(struct), np.concatenate(gen),
                            np.concatenate(cand) if K else np.zeros((n_draws, 0)), names)


@dataclass(frozen=True)
class _Singles:
    """The one-column variants (grouped by candidate) and the generic columns, less their
    projection on the nuisance in the data's whitening, with what the bootstrap needs of them.

    Subtracting a combination of the nuisance columns changes no statistic (each draw projects
    the nuisance out again); it keeps ``uᵀu = |W m|² − |Qᵀ W m|²`` free of cancellation, since
    in a draw's whitening ``W m`` is then nearly orthogonal to the nuisance already.
    ``|W m|²`` is the product of the columns' squares per cell (``m₀², 2 m₀ m₁, m₁²``; ``m²``
    for a real observable) with the draw's precisions (``WᵀW``); ``Qᵀ W m = (WᵀQ)ᵀ m``.
    """

    columns: np.ndarray              # (n_obs, k) unwhitened
    squares: np.ndarray              # (3 nc + nr, k)
    whole: np.ndarray                # (k,) |W m|² of the columns before the reduction
    one_sided: np.ndarray            # (k,) bool: only a positive projection counts
    candidate_slices: tuple[slice, ...]
    generic_slice: slice

    @classmethod
    def of(cls, problem: Problem, lin: Linearisation) -> _Singles:
        cols, sides, slices = [], [], []
        for c, vs in lin.candidates:
            one = [v.columns for v in vs if v.columns.shape[1] == 1]
            start = sum(m.shape[1] for m in cols)
            cols += one
            sides += [c.one_sided[0]] * len(one)
            slices.append(slice(start, start + len(one)))
        start = sum(m.shape[1] for m in cols)
        cols.append(lin.generic)
        sides += [False] * lin.generic.shape[1]
        M = np.hstack(cols)
        W = _data_whitening(problem)
        Nw = _apply(W, lin.nuisance)
        scale = np.linalg.norm(Nw, axis=0)
        scale = np.where(scale > 0, scale, 1.0)
        Q, R = np.linalg.qr(Nw / scale)
        Mw = _apply(W, M)
        beta = np.linalg.lstsq(R, Q.T @ Mw, rcond=None)[0] / scale[:, None]
        whole = np.einsum("nk,nk->k", Mw, Mw)
        M = M - lin.nuisance @ beta
        nc = 2 * W[0].shape[0]
        Mc = M[:nc].reshape(nc // 2, 2, -1)
        sq = np.concatenate([Mc[:, 0]**2, 2 * Mc[:, 0] * Mc[:, 1], Mc[:, 1]**2, M[nc:]**2])
        return cls(M, sq, whole, np.array(sides, dtype=bool), tuple(slices),
                   slice(start, start + lin.generic.shape[1]))

    def statistics(self, W: tuple[np.ndarray, np.ndarray], Q: np.ndarray, r: np.ndarray
                   ) -> np.ndarray:
        """Per draw and column ``(uᵀr)² / uᵀu`` (0 for a one-sided column whose projection is
        negative, and for a column the nuisance absorbs): whitening ``W`` (batched), nuisance
        basis ``Q`` (B, n, p), residuals ``r`` (B, n) orthogonal to it."""
        Wc, wr = W
        B = r.shape[0]
        num = _apply(W, r[..., None], transpose=True)[..., 0] @ self.columns
        P = np.concatenate([Wc[..., 0, 0]**2 + Wc[..., 1, 0]**2,
                            Wc[..., 0, 0] * Wc[..., 0, 1] + Wc[..., 1, 0] * Wc[..., 1, 1],
                            Wc[..., 0, 1]**2 + Wc[..., 1, 1]**2, wr**2], axis=1)
        Z = np.swapaxes(_apply(W, Q, transpose=True), -1, -2)
        QtM = (np.ascontiguousarray(Z).reshape(-1, Z.shape[-1]) @ self.columns).reshape(
            B, Z.shape[1], -1)
        den = P @ self.squares - np.einsum("bpk,bpk->bk", QtM, QtM)
        # a column the nuisance absorbs (what is left below 1e-12 of it, the rule of
        # rivals._rivals) explains nothing; its 0/0 would be rounding
        live = den > 1e-12 * self.whole[None]
        d = np.where(live, num**2 / np.where(live, den, 1.0), 0.0)
        return np.where(self.one_sided[None] & (num <= 0), 0.0, d)


def linear_statistics(problem: Problem, lin: Linearisation, r: np.ndarray) -> np.ndarray:
    """First-order LR statistic of every candidate on whitened residuals ``r`` of the fit that
    was linearised (data whitening): the same formula as the bootstrap's, so it screens which
    candidates are worth a nonlinear fit."""
    W = _data_whitening(problem)
    Q, _ = np.linalg.qr(_apply(W, lin.nuisance)[None])
    rr = r[None] - _project_on(Q, r[None])
    out = np.zeros(len(lin.candidates))
    for k, (c, vs) in enumerate(lin.candidates):
        for v in vs:
            U = _apply(W, v.columns)[None]
            U = U - _project_on(Q, U)
            if U.shape[-1] == 1:
                u = U[0, :, 0]
                num = float(u @ rr[0])
                d = num**2 / float(u @ u) if (num > 0 or not c.one_sided[0]) else 0.0
            else:
                d = float(rr[0] @ _project(U, rr)[0])
            out[k] = max(out[k], d)
    return out


def generic_statistic(problem: Problem, lin: Linearisation, r: np.ndarray) -> float:
    """The largest one-parameter likelihood ratio of a generic local change on the residual
    (data whitening), after the nuisance columns are projected out of both."""
    if lin.generic.shape[1] == 0:
        return 0.0
    W = _data_whitening(problem)
    Q, _ = np.linalg.qr(_apply(W, lin.nuisance)[None])
    rr = r[None] - _project_on(Q, r[None])
    U = _apply(W, lin.generic)[None]
    return float(_max_single(U - _project_on(Q, U), rr)[0])


def _max_single(U: np.ndarray, r: np.ndarray) -> np.ndarray:
    """``max_j (u_jᵀ r)² / u_jᵀ u_j`` per draw: the best single direction's LR statistic."""
    num = np.einsum("bnk,bn->bk", U, r)
    return np.max(num**2 / np.einsum("bnk,bnk->bk", U, U), axis=1)


def _project(N: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """Batched orthogonal projection of ``Y`` (B, n[, k]) on the columns of ``N`` (B, n, p),
    by Householder QR (the nuisance columns are far from orthogonal — channel gains against
    the unbalance — so normal equations would lose the digits the test needs)."""
    return _project_on(np.linalg.qr(N)[0], Y)


def _project_on(Q: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """:func:`_project` with the orthonormal basis ``Q`` (B, n, p) of the columns given."""
    vec = Y.ndim == 2
    Y = Y[..., None] if vec else Y
    out = Q @ (np.swapaxes(Q, -1, -2) @ Y)
    return out[..., 0] if vec else out


def chi2_sf(value: float, dof: int) -> float:
    """χ² upper tail (for reporting an uncalibrated reference beside the bootstrap)."""
    return float(chi2.sf(value, dof))
