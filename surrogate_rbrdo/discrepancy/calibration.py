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
    nrow = len(ex_rows)
    fc = np.zeros((0, f.shape[1]))
    if nrow:
        rb = par.rows(x[None])
        rows = replace(rb.repeat(nrow), extras=ex_rows)
        # a candidate leaves the nuisance's prior pseudo-observations as they are at ``x``
        fc = np.hstack([problem.data_vector(rows, u),
                        np.broadcast_to(f[0, f.shape[1] - problem.n_prior:],
                                        (nrow, problem.n_prior))])
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


def _apply(W: tuple[np.ndarray, np.ndarray], M: np.ndarray) -> np.ndarray:
    """Whiten unwhitened columns ``M`` (n_obs, k) (or a batch (B, n_obs, k) with batched W)."""
    Wc, wr = W
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
    """Draw the statistics ``n_draws`` times under the recalibrated model (see module doc)."""
    rng = require_rng(rng)
    noise = NoiseModel.of(problem, lin.nuisance[:, :lin.n_theta], _data_whitening(problem)[0])
    cols = [lin.nuisance]
    index, off = [], 0
    for c, vs in lin.candidates:
        for v in vs:
            index.append((c, v.columns.shape[1], off))
            cols.append(v.columns)
            off += v.columns.shape[1]
    cols.append(lin.generic)
    M = np.hstack(cols)
    p = lin.nuisance.shape[1]
    ng = lin.generic.shape[1]
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
        Mw = _apply(Wb, np.broadcast_to(M, (B,) + M.shape))
        Q, _ = np.linalg.qr(Mw[..., :p])            # one factorisation for both projections
        r = ew - _project_on(Q, ew)
        U = Mw[..., p:] - _project_on(Q, Mw[..., p:])
        gof.append(np.sum(r**2, axis=1))
        struct.append(gp_statistic(r, series, eig))
        Ug = U[..., U.shape[-1] - ng:]
        gen.append(_max_single(Ug, r) if ng else np.zeros(B))
        U = U[..., :U.shape[-1] - ng]
        cand.append(_candidate_stats(r, U, index, lin))
    K = len(names)
    return NullDistribution(np.concatenate(gof), np.concatenate(struct), np.concatenate(gen),
                            np.concatenate(cand) if K else np.zeros((n_draws, 0)), names)


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


def _candidate_stats(r, U, index, lin) -> np.ndarray:
    """Per draw and candidate the LR statistic, maximised over the candidate's variants."""
    out = np.zeros((r.shape[0], len(lin.candidates)))
    order = {c.name: k for k, (c, _) in enumerate(lin.candidates)}
    for c, ncol, off in index:
        Uv = U[..., off:off + ncol]
        if ncol == 1:
            u = Uv[..., 0]
            num = np.einsum("bn,bn->b", u, r)
            d = num**2 / np.einsum("bn,bn->b", u, u)
            if c.one_sided[0]:
                d = np.where(num > 0, d, 0.0)
        else:
            d = np.einsum("bn,bn->b", r, _project(Uv, r))
        k = order[c.name]
        out[:, k] = np.maximum(out[:, k], d)
    return out


def chi2_sf(value: float, dof: int) -> float:
    """χ² upper tail (for reporting an uncalibrated reference beside the bootstrap)."""
    return float(chi2.sf(value, dof))
