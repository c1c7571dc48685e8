"""The held-out split and the gap between model and data on held-out points.

Speeds are split *before* anything is fitted: the top ``extrapolate_fraction`` of the 1x
speeds are held out for extrapolation, and every ``every``-th of the rest (starting in the
middle of the first stride) for interpolation; everything else trains. Of an impact test (an
FRF at one speed) every ``every``-th line is held out the same way, for interpolation in
frequency: an effect the FRFs show more clearly than the 1x response (a small anisotropy, a
polar-inertia error) must then predict FRF lines it was not fitted to, as a 1x effect must
predict held-out speeds. The gap is measured on held-out 1x speeds with the unbalance and
parameters fitted on training speeds only: RMSE and largest modulus of the complex residual
(µm), and the whitened χ² per real observable.

The held-out *check* of a candidate (:mod:`.naming`) compares predictive χ²
(:func:`predictive_chi2`): a held-out residual is whitened with the covariance of the
prediction error, the noise plus what the training fit's parameter uncertainty propagates to
the held-out points (``I + J Σ Jᵀ`` in whitened units, the textbook prediction variance
``σ²(1 + x₀ᵀ(XᵀX)⁻¹x₀)`` of a regression; Seber & Wild 2003, *Nonlinear Regression*, §5.1).
Without it, held-out points that the training fit predicts poorly even with the true model —
speeds beyond the training range on the flank of a resonance, where a small error in a mode's
frequency or damping is many noise SDs — penalise whichever model moves the mode, right or
wrong.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from surrogate_rbrdo.core.validate import check_int, check_range
from surrogate_rbrdo.discrepancy.fit import Fit, _fd_rows
from surrogate_rbrdo.discrepancy.nuisance import Parametrisation
from surrogate_rbrdo.discrepancy.observables import MeasuredData
from surrogate_rbrdo.discrepancy.problem import Problem, _whitened, _whitened_design


@dataclass(frozen=True)
class Split:
    """Masks over one 1x block's speeds: training, interleaved and extrapolated held-out."""

    train: np.ndarray
    interleaved: np.ndarray
    extrapolated: np.ndarray
    every: int = 5

    def to_dict(self, speeds_rpm: np.ndarray) -> dict:
        return {k: np.asarray(speeds_rpm)[getattr(self, k)].round(1).tolist()
                for k in ("train", "interleaved", "extrapolated")}


def split_speeds(n: int, every: int = 5, extrapolate_fraction: float = 0.1) -> Split:
    """Split ``n`` ascending speeds.

    >>> s = split_speeds(20, every=5, extrapolate_fraction=0.1)
    >>> np.flatnonzero(s.extrapolated).tolist(), np.flatnonzero(s.interleaved).tolist()
    ([18, 19], [2, 7, 12, 17])
    """
    check_int("holdout_every", every, minimum=2)
    check_range("extrapolate_fraction", extrapolate_fraction, 0.0, 0.5)
    if n < 8:
        raise ValueError(f"the 1x test has {n} speeds: need at least 8 to hold some out")
    n_ex = max(1, math.ceil(extrapolate_fraction * n)) if extrapolate_fraction > 0 else 0
    ex = np.zeros(n, dtype=bool)
    ex[n - n_ex:] = True
    inter = np.zeros(n, dtype=bool)
    inter[every // 2:n - n_ex:every] = True
    return Split(~(ex | inter), inter, ex, every)


def masks_for(data: MeasuredData, split: Split, which: str) -> dict[str, np.ndarray]:
    """Per-block masks selecting ``which`` (``train``, ``interleaved``, ``extrapolated``,
    ``held_out``) of every 1x block; of an impact block every ``split.every``-th line is
    interleaved (held out), the rest trains."""
    out = {}
    for b in data.blocks:
        n = b.mean.shape[0]
        if b.sweep.kind != "unbalance_1x":
            inter = np.zeros(n, dtype=bool)
            inter[split.every // 2::split.every] = True
            out[b.name] = {"train": ~inter, "interleaved": inter, "held_out": inter,
                           "extrapolated": np.zeros(n, dtype=bool)}[which]
            continue
        if n != split.train.size:
            raise ValueError(f"block {b.name!r} has {n} speeds, the split {split.train.size}: "
                             "every 1x test must use the same speeds")
        out[b.name] = (split.interleaved | split.extrapolated if which == "held_out"
                       else getattr(split, which))
    if data.identified is not None:
        ib = data.identified
        m = out[next(b.name for b in data.blocks if b.sweep.kind == "unbalance_1x")]
        out["identified"] = m if ib.speeds_rpm.size == m.size else np.full(
            ib.speeds_rpm.size, which == "train")
    return out


@dataclass(frozen=True)
class Gap:
    """Held-out agreement: RMSE and largest |residual| (µm), χ² per real observable, and per
    channel the same (the 1x blocks only); from :func:`held_out_gap` also the predictive χ²
    per real observable (against the noise *and* the training fit's prediction uncertainty,
    :func:`predictive_chi2`; NaN where not computed) and the same figures per part of the
    held-out speeds (``parts``: interleaved, extrapolated)."""

    rmse: float
    max_abs: float
    chi2_dof: float
    chi2: float
    n: int
    per_channel: dict
    predictive_chi2_dof: float = math.nan
    parts: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        out = {"rmse": self.rmse, "max_abs": self.max_abs, "chi2_dof": self.chi2_dof,
               "predictive_chi2_dof": self.predictive_chi2_dof}
        out.update({k: g.to_dict() for k, g in self.parts.items()})
        return out


def residuals(problem: Problem, par: Parametrisation, x: np.ndarray,
              unbalance: tuple[np.ndarray, ...],
              correction: list[np.ndarray] | None = None) -> list[np.ndarray]:
    """Complex residuals ``data − model`` per block of ``problem`` (its points) with the
    parameters ``x`` and the unbalance fitted elsewhere; ``correction`` is added to the model
    (a GP prediction)."""
    raw = problem.responses(par.rows(x[None]))
    out, k = [], 0
    for i, (b, G) in enumerate(zip(problem.blocks, raw, strict=False)):
        if b.sweep.kind == "unbalance_1x":
            pred = G[0] @ unbalance[k]
            k += 1
        else:
            pred = G[0].sum(axis=-1)
        if correction is not None:
            pred = pred + correction[i]
        out.append(b.mean - pred)
    return out


def gap(problem: Problem, res: list[np.ndarray]) -> Gap:
    """The gap of complex residuals ``res`` (from :func:`residuals`) on the 1x blocks."""
    mods, chis, per = [], [], {}
    for b, W, r in zip(problem.blocks, problem.whiten, res, strict=False):
        if b.sweep.kind != "unbalance_1x" or r.size == 0:
            continue
        w = _whitened(r[None], W)[0].reshape(r.shape + (2,))
        mods.append(np.abs(r).ravel())
        chis.append(np.sum(w**2, axis=-1).ravel())
        for j, c in enumerate(b.channels):
            per[f"{b.name}:{c.name}"] = {
                "rmse": float(np.sqrt(np.mean(np.abs(r[:, j]) ** 2)) * 1e6),
                "max_abs": float(np.max(np.abs(r[:, j])) * 1e6),
                "chi2_dof": float(np.sum(w[:, j] ** 2) / (2 * r.shape[0]))}
    if not mods:
        return Gap(math.nan, math.nan, math.nan, math.nan, 0, {})
    m, c = np.concatenate(mods), np.concatenate(chis)
    return Gap(float(np.sqrt(np.mean(m**2)) * 1e6), float(m.max() * 1e6),
               float(c.sum() / (2 * c.size)), float(c.sum()), 2 * c.size, per)


def held_out_gap(train: Problem, held: Problem, parts: dict[str, Problem], f: Fit, *,
                 correction: Callable[[Problem], list[np.ndarray]] | None = None) -> Gap:
    """The gap of ``f`` (fitted on ``train``) on the held-out 1x speeds of ``held`` and of
    each of ``parts`` (named subsets of them: the interleaved and the extrapolated speeds),
    with the unbalance its training points fix.

    Beside the noise-only χ² per real observable it gives the predictive χ² per real
    observable (:func:`predictive_chi2`): a speed beyond the training range on a resonance's
    flank is predicted poorly even by the true model, and there the noise-only χ² is large
    while the predictive one is about 1. ``correction(problem)`` (a GP's correction, for
    prediction only) is added to the model; the predictive χ² then is NaN (it has no
    covariance for the GP's own prediction error).
    """
    u = tuple(x[0] for x in f.evaluation.unbalance)
    one_x = {k: p.only("unbalance_1x") for k, p in {"held": held, **parts}.items()}

    def part(p: Problem, pred: float) -> Gap:
        g = gap(p, residuals(p, f.par, f.x, u, None if correction is None
                             else correction(p)))
        return replace(g, predictive_chi2_dof=pred / g.n if correction is None and g.n
                       else math.nan)

    names = tuple(one_x)
    preds = ((math.nan,) * len(names) if correction is not None
             else predictive_chi2(train, tuple(one_x.values()), f))
    gaps = {k: part(one_x[k], pr) for k, pr in zip(names, preds, strict=True)}
    return replace(gaps.pop("held"), parts=gaps)


def predictive_chi2(train: Problem, held: Problem | tuple[Problem, ...], f: Fit, *,
                    deviance: bool = False) -> float | tuple[float, ...]:
    """χ² of the held-out residuals of ``f`` (fitted on ``train``) against the covariance of
    the prediction error: ``rᵀ (I + J Σ Jᵀ + D (AᵀA)⁻¹ Dᵀ)⁻¹ r`` in whitened units, with ``J``
    the held-out residuals' derivative in the outer parameters (the unbalance re-solved on
    the training points at every step), ``Σ`` the fit's Gauss–Newton covariance with no
    direction less known than the parameters' physical ranges allow (``Fit.covariance(
    bounded=True)``: a parameter training does not see, or barely sees, gets the largest
    variance an estimate confined to its range can have — the same for both, not ``∞``
    turned into ``0`` nor ``1/|J_j|²``), ``D`` and
    ``A`` the whitened unbalance designs of the held-out and training points of each 1x test
    (the unbalance's own uncertainty given the parameters). ``0`` when ``held`` has no points;
    a tuple of held-out problems gives a tuple (the training side computed once).

    With ``deviance`` the predictive deviance ``rᵀ C⁻¹ r + log det C`` (−2 log of the Gaussian
    predictive density, up to a constant; the noise-only whitening has ``C = I``, log det 0):
    the log-determinant charges a model for the spread of its predictions, without which a
    larger model — whose prediction covariance is never smaller — would score better on the
    same residuals (the held-out check compares deviances, :mod:`.naming`).
    """
    par, x = f.par, f.x
    lo, hi = par.bounds()
    rows, h = _fd_rows(x, par, lo, hi)
    X = np.vstack([x[None], rows])
    unb = train.evaluate(par, X).unbalance
    S = f.covariance(bounded=True)   # an unseen parameter: known to its physical range only
    A = [_whitened_design(W, G[0]) for b, W, G in zip(
        train.blocks, train.whiten, train.responses(par.rows(x[None])), strict=False)
        if b.sweep.kind == "unbalance_1x"]
    names = [b.name for b in train.blocks if b.sweep.kind == "unbalance_1x"]
    # each held-out 1x test takes the unbalance its own training points fix (by name)
    one_x = {n: (u, np.linalg.pinv(a.T @ a)) for n, u, a in zip(names, unb, A, strict=True)}
    out = tuple(_predictive(p, par, X, h, one_x, S, deviance)
                for p in (held if isinstance(held, tuple) else (held,)))
    return out if isinstance(held, tuple) else out[0]


def _predictive(held: Problem, par: Parametrisation, X: np.ndarray, h: np.ndarray,
                one_x: dict[str, tuple[np.ndarray, np.ndarray]], S: np.ndarray,
                deviance: bool = False) -> float:
    """:func:`predictive_chi2` on one held-out problem, from the training side's rows ``X``
    (the fit and its finite-difference steps ``h``), ``Σ``, and per 1x test (by block name)
    the rows' unbalances and ``(AᵀA)⁻¹``."""
    R, D = [], []
    off = 0
    for b, W, G in zip(held.blocks, held.whiten, held.responses(par.rows(X)), strict=False):
        if b.sweep.kind == "unbalance_1x":
            if b.name not in one_x:
                raise ValueError(f"held-out 1x test {b.name!r} has no training points: its "
                                 "unbalance is not fixed by the training fit")
            unb, AtA = one_x[b.name]
            pred = np.einsum("bxcl,bl->bxc", G, unb)
            D.append((off, _whitened_design(W, G[0]), AtA))
        else:
            pred = G.sum(axis=-1)
        R.append(_whitened(b.mean[None] - pred, W))
        off += R[-1].shape[1]
    R = np.concatenate(R, axis=1)
    if R.shape[1] == 0:
        return 0.0
    r0 = R[0]
    J = ((R[1:] - r0[None]) / h[:, None]).T
    C = np.eye(r0.size) + J @ S @ J.T
    for o, Dk, Pk in D:
        n = Dk.shape[0]
        C[o:o + n, o:o + n] += Dk @ Pk @ Dk.T
    chi2 = float(r0 @ np.linalg.solve(C, r0))
    return chi2 + float(np.linalg.slogdet(C)[1]) if deviance else chi2
