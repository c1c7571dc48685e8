"""The measurement noise as the bootstrap simulates it, and the mean of runs — including their
run-to-run structure.

A speed sweep repeated ``R`` times is ``R`` *runs*, each with its own thermal state, and a run's
state moves the whole sweep at once: the bearings' stiffness changes, so every speed and channel
of the run shifts along the model's derivatives ``J_θ = ∂y/∂ log θ``. The per-cell covariance
estimated from the repeats then contains a component that is perfectly correlated across cells
(and whose effect on the mean is absorbed by the recalibrated θ), and null distributions that
assume independent cells are wrong — measured on the virtual rig's default campaign: the
generic lack-of-fit test rejected 10 % of null data sets at the 1 % level.

So for a block that keeps its runs, the noise is decomposed run by run,
``d_r = y_r − ȳ = J_θ a_r + δ_r(x) i ȳ(x) + e_r`` (``a_r`` by least squares in the data's
whitening; ``δ_r(x)`` a phase error common to every channel of the record at point ``x`` — the
keyphasor's shaft-angle reference, whose error at a speed with a near-integer number of samples
per revolution does not average out), with ``Σ_a`` the covariance of the ``a_r``, ``σ_δ(x)`` the
SD of the ``δ_r(x)`` and ``Σ_e`` the per-cell covariance of the ``e_r``; every bootstrap draw
simulates ``R`` runs from the three and re-estimates the per-cell covariance from them exactly
as the data's was estimated (:meth:`~.observables.ComplexBlock.from_repeats`). Blocks without
runs (and averaged FRFs) get a Wishart draw with the cell's degrees of freedom (Bartlett's
decomposition).

The mean of the runs is not the response at the mean state: the response is nonlinear in θ
(near a resonance strongly: a resonance a few half-power bandwidths wide is far from quadratic
over the runs' scatter), so the model's mean is the average of its responses over the runs'
own states, ``(1/R) Σ_r y(θ e^{a_r})`` with each run's ``a_r`` estimated from the run
(:func:`run_states`), computed at a fit as a correction of the unit responses
(:func:`run_offsets`) that the problem adds to every row. On the virtual rig's default campaign
(thermal preload CoV 8 %) the generic lack-of-fit test rejected 58 % of null data sets at the
1 % level without it; with a Gaussian second-order (Jensen) correction still some; with the
runs' own states none of 30.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from surrogate_rbrdo.discrepancy.nuisance import Parametrisation
from surrogate_rbrdo.discrepancy.problem import Problem


@dataclass(frozen=True)
class RunStructure:
    """One run-structured block: its cells, ``J_θ`` rows, ``Σ_a`` and ``Σ_e`` factors."""

    cells: slice            # the block's cells among all complex cells
    J: np.ndarray           # (2 n_cells, k) unwhitened
    La: np.ndarray          # (k, k) Cholesky factor of Σ_a
    Le: np.ndarray          # (n_cells, 2, 2) Cholesky factors of Σ_e (per run)
    R: int
    V: np.ndarray           # (X, C, 2) common-phase direction i·ȳ at each point
    sd_phase: np.ndarray    # (X,) SD of a run's common phase error at each point
    a: np.ndarray           # (R, k) each run's estimated deviation along J_θ


@dataclass(frozen=True)
class NoiseModel:
    """What a bootstrap draw of the noise needs (see module doc)."""

    L: np.ndarray           # (nc, 2, 2) Cholesky factors of the cells' covariance of the mean
    dof: np.ndarray         # (nc,)
    sd: np.ndarray          # (nr,) real observables' SDs
    dof_r: np.ndarray       # (nr,)
    runs: tuple[RunStructure, ...]

    @classmethod
    def of(cls, problem: Problem, J_theta: np.ndarray, whiten: np.ndarray) -> NoiseModel:
        """From the problem's data; ``J_theta`` (n_obs, k) are the unwhitened derivatives along
        which a run's state moves it, ``whiten`` (nc, 2, 2) the data's cell whitening."""
        cov, dof, sd, dof_r = problem.noise_cells()
        runs, c0 = [], 0
        for b in problem.blocks:
            n = b.mean.size
            if b.runs is not None and J_theta.shape[1]:
                runs.append(_run_structure(b, slice(c0, c0 + n),
                                           J_theta[2 * c0:2 * (c0 + n)], whiten[c0:c0 + n]))
            c0 += n
        return cls(np.linalg.cholesky(cov), dof, sd, dof_r, tuple(runs))

    def draw(self, B: int, rng: np.random.Generator
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``B`` draws: the noise of the observables ``(B, n_obs)``, the cells' whitening
        ``(B, nc, 2, 2)`` and the real observables' whitening ``(B, nr)``, each from its own
        re-estimated covariance."""
        nc = self.L.shape[0]
        e_c = _lower_times(self.L, rng.normal(size=(B, nc, 2)))
        W = _wishart_whitening(self.L, self.dof, rng, B)
        for rs in self.runs:
            e_c[:, rs.cells], W[:, rs.cells] = _draw_runs(rs, B, rng)
        s_hat = self.sd * np.sqrt(rng.chisquare(self.dof_r, size=(B, self.sd.size))
                                  / np.maximum(self.dof_r, 1))
        e_r = self.sd * rng.normal(size=(B, self.sd.size))
        return np.concatenate([e_c.reshape(B, -1), e_r], axis=1), W, 1.0 / s_hat


def _run_structure(b, cells: slice, J: np.ndarray, W: np.ndarray) -> RunStructure:
    """Split a block's run deviations into the ``J_θ`` part, a common phase error per run and
    point (all channels of a record share the keyphasor's shaft-angle reference), and the
    rest."""
    R, X, C = b.runs.shape
    d = b.runs - b.mean[None]
    d = np.stack([d.real, d.imag], axis=-1).reshape(R, -1, 2)            # (R, n, 2)
    dw = np.einsum("nij,rnj->rni", W, d).reshape(R, -1)
    Jw = np.einsum("nij,njk->nik", W, J.reshape(-1, 2, J.shape[1])).reshape(-1, J.shape[1])
    a, *_ = np.linalg.lstsq(Jw, dw.T, rcond=None)                       # (k, R)
    e = (d - (J @ a).T.reshape(R, -1, 2)).reshape(R, X, C, 2)
    V = np.stack([-b.mean.imag, b.mean.real], axis=-1)                  # i·ȳ as (Re, Im)
    Wv = np.einsum("xcij,xcj->xci", W.reshape(X, C, 2, 2), V)
    We = np.einsum("xcij,rxcj->rxci", W.reshape(X, C, 2, 2), e)
    delta = np.einsum("rxci,xci->rx", We, Wv) / np.maximum(np.einsum("xci,xci->x", Wv, Wv),
                                                           1e-300)
    e = (e - delta[..., None, None] * V[None]).reshape(R, -1, 2)
    # the phase fit takes one of the 2C real values of each run and point
    Se = np.einsum("rni,rnj->nij", e, e) / (R - 1) * (2 * C) / (2 * C - 1)
    Sa = np.atleast_2d(np.cov(a)) + 1e-30 * np.eye(a.shape[0])
    Le = np.linalg.cholesky(Se + 1e-30 * np.eye(2))
    return RunStructure(cells, J, np.linalg.cholesky(Sa), Le, R, V,
                        delta.std(axis=0, ddof=1), a.T)


def _draw_runs(rs: RunStructure, B: int, rng: np.random.Generator
               ) -> tuple[np.ndarray, np.ndarray]:
    """Mean noise ``(B, n, 2)`` and whitening ``(B, n, 2, 2)`` of ``R`` simulated runs."""
    n, k = rs.Le.shape[0], rs.J.shape[1]
    a = rng.normal(size=(B, rs.R, k)) @ rs.La.T
    e = _lower_times(rs.Le, rng.normal(size=(B, rs.R, n, 2)))
    X = rs.V.shape[0]
    delta = rng.normal(size=(B, rs.R, X)) * rs.sd_phase
    y = e + (a @ rs.J.T).reshape(B, rs.R, n, 2) + (
        delta[..., None, None] * rs.V).reshape(B, rs.R, n, 2)
    m = y.mean(axis=1)
    d = y - m[:, None]
    S = np.einsum("brni,brnj->bnij", d, d) / (rs.R - 1) / rs.R       # covariance of the mean
    nu = rs.R - 1
    return m, _whitening_2x2(S, (nu - 3) / nu)


def _lower_times(L: np.ndarray, z: np.ndarray) -> np.ndarray:
    """``L z`` for lower-triangular 2x2 ``L`` (..., 2, 2) and vectors ``z`` (..., 2)."""
    out = np.empty(np.broadcast_shapes(L.shape[:-1], z.shape))
    out[..., 0] = L[..., 0, 0] * z[..., 0]
    out[..., 1] = L[..., 1, 0] * z[..., 0] + L[..., 1, 1] * z[..., 1]
    return out


def _whitening_2x2(S: np.ndarray, factor) -> np.ndarray:
    """``W`` (upper triangular) with ``WᵀW = factor · S⁻¹`` for symmetric positive 2x2 ``S``,
    in closed form (the batched LAPACK calls cost more than the arithmetic)."""
    a, b, c = S[..., 0, 0], S[..., 0, 1], S[..., 1, 1]
    det = a * c - b * b
    p00, p01, p11 = factor * c / det, -factor * b / det, factor * a / det
    l00 = np.sqrt(p00)
    l10 = p01 / l00
    l11 = np.sqrt(np.maximum(p11 - l10 * l10, 0.0))
    W = np.zeros(S.shape)
    W[..., 0, 0], W[..., 0, 1], W[..., 1, 1] = l00, l10, l11
    return W


def _wishart_whitening(L: np.ndarray, dof: np.ndarray, rng: np.random.Generator,
                       B: int) -> np.ndarray:
    """Per draw and cell ``W`` with ``WᵀW = (ν − 3) S⁻¹``, ``S ~ Wishart(Σ, ν)`` (Bartlett)."""
    n = L.shape[0]
    A = np.zeros((B, n, 2, 2))
    A[..., 0, 0] = np.sqrt(rng.chisquare(dof, size=(B, n)))
    A[..., 1, 1] = np.sqrt(rng.chisquare(dof - 1, size=(B, n)))
    A[..., 1, 0] = rng.normal(size=(B, n))
    LA = L @ A
    S = LA @ np.swapaxes(LA, -1, -2)
    return _whitening_2x2(S, (dof - 3).astype(float))


def run_states(problem: Problem, J_theta: np.ndarray, whiten: np.ndarray
               ) -> dict[str, np.ndarray]:
    """Per run-structured block (by name): each run's log stiffness deviation from the mean
    state ``(R, k)``, estimated by least squares along ``J_θ``."""
    nm = NoiseModel.of(problem, J_theta, whiten)
    names = [b.name for b in problem.blocks if b.runs is not None]
    return {n: rs.a for n, rs in zip(names, nm.runs, strict=True)} if nm.runs else {}


def run_offsets(problem: Problem, par: Parametrisation, x: np.ndarray,
                states: dict[str, np.ndarray]) -> list[np.ndarray | None]:
    """Per block of ``problem``: the average of the unit responses over its runs' states minus
    the response at the fitted state (``None`` for blocks without estimated states)."""
    rows = par.rows(x[None])
    if any(o is not None for o in problem.run_offset):
        raise ValueError("run_offsets: the problem carries offsets already; give the plain one")
    center = problem.responses(rows)
    out: list[np.ndarray | None] = []
    for i, b in enumerate(problem.blocks):
        a = states.get(b.name)
        if a is None or b.runs is None:
            out.append(None)
            continue
        n = a.shape[0]
        r = rows.repeat(n)
        rep = replace(r, theta=rows.theta * np.exp(a))
        out.append(problem.responses(rep)[i].mean(axis=0) - center[i][0])
    return out


def theta_jacobian(problem: Problem, par: Parametrisation, x: np.ndarray,
                   unbalance: tuple[np.ndarray, ...]) -> np.ndarray:
    """Unwhitened derivatives ``(n_obs, k)`` of the observables with respect to the log
    stiffness factors (the first ``k`` outer parameters), unbalance held."""
    k = par.sizes[0]
    h = 1e-5
    X = np.vstack([x[None], x[None] + h * np.eye(x.size)[:k]])
    f = problem.model_vector(par, X, unbalance)
    return ((f[1:] - f[0]) / h).T
