"""Whitened residuals of a model against measured data, with the unbalance solved exactly.

The outer parameters are the model's own uncertain parameters (the *nuisance*,
:mod:`.nuisance`) and, when a candidate effect is tried, its parameters. The unbalance phasors
of every 1x test are *inner* parameters: the 1x response is linear in them, so for given outer
parameters they are the exact weighted least-squares solution, and the residual that the outer
fit sees is the variable-projection residual (Golub & Pereyra 1973, *SIAM J. Numer. Anal.*
10:413). Everything is batched over rows of outer
parameters: a finite-difference Jacobian is one call.
"""

from __future__ import annotations

import copy
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.nuisance import NuisanceOptions, Parametrisation, Rows
from surrogate_rbrdo.discrepancy.observables import ComplexBlock, MeasuredData, RealBlock


@dataclass(frozen=True)
class Evaluation:
    """Residuals and predictions of a batch of outer rows."""

    residuals: np.ndarray              # (B, n) whitened
    predictions: tuple[np.ndarray, ...]  # per block: (B, X, C) complex, or (B, X, nb, 2)
    unbalance: tuple[np.ndarray, ...]    # per 1x block: (B, planes) complex

    @property
    def chi2(self) -> np.ndarray:
        return np.sum(self.residuals**2, axis=-1)


class Problem:
    """Whitened residuals of ``forward`` against ``data`` on the points ``masks`` select.

    Parameters
    ----------
    forward : ForwardModel
        Its channels must include every channel of the data.
    data : MeasuredData
    masks : dict, optional
        Block name (or ``"identified"``) → boolean mask of the points used; default all.
    nuisance : NuisanceOptions, optional
        What is recalibrated (default :class:`~.nuisance.NuisanceOptions`).
    run_offset : list, optional
        Per block (after masking), a correction added to the unit responses or None.

    Residual order: every complex block's cells ``[Re, Im]`` (points × channels), then the
    identified stiffness, then the priors' pseudo-observations.
    """

    def __init__(self, forward: ForwardModel, data: MeasuredData,
                 masks: dict[str, np.ndarray] | None = None,
                 nuisance: NuisanceOptions | None = None,
                 run_offset: list[np.ndarray | None] | None = None) -> None:
        masks = masks or {}
        self.forward = forward
        self.nuisance = NuisanceOptions() if nuisance is None else nuisance
        self.data = data
        key = {(c.position_mm, c.direction): i for i, c in enumerate(forward.channels)}
        self.blocks: list[ComplexBlock] = []
        self.channel_index: list[np.ndarray] = []
        self.whiten: list[np.ndarray] = []
        for b in data.blocks:
            m = masks.get(b.name, np.ones(b.mean.shape[0], dtype=bool))
            if not np.any(m):
                continue  # a block without points here (an impact test on held-out speeds)
            sub = b.subset(m)
            try:
                idx = np.array([key[(c.position_mm, c.direction)] for c in b.channels])
            except KeyError as exc:
                raise ValueError(f"block {b.name!r}: channel {exc.args[0]} is not a channel "
                                 "of the forward model") from None
            self.blocks.append(sub)
            self.channel_index.append(idx)
            self.whiten.append(sub.whitening())
        self.identified: RealBlock | None = None
        if data.identified is not None:
            ib = data.identified
            m = masks.get("identified", np.ones(ib.speeds_rpm.size, dtype=bool))
            self.identified = RealBlock(ib.name, ib.speeds_rpm[m], ib.bearings, ib.values[m],
                                        ib.sd[m], ib.dof)
        self.n_prior = self.parametrisation().n_prior
        #: per block, a correction added to the model's unit responses (the average over the
        #: runs' thermal states, :func:`~.noise.run_offsets`); None: none
        self.run_offset = list(run_offset) if run_offset else [None] * len(self.blocks)
        if len(self.run_offset) != len(self.blocks):
            raise ValueError(f"run_offset has {len(self.run_offset)} entries for "
                             f"{len(self.blocks)} blocks")

    def only(self, kind: str) -> Problem:
        """The same problem on its blocks of sweep ``kind`` alone (and the identified
        stiffness); its parametrisation drops what only the other blocks see (the force
        channel of impact tests)."""
        sub = copy.copy(self)                  # without the recent rows (__getstate__)
        keep = [i for i, b in enumerate(self.blocks) if b.sweep.kind == kind]
        sub.blocks = [self.blocks[i] for i in keep]
        sub.channel_index = [self.channel_index[i] for i in keep]
        sub.whiten = [self.whiten[i] for i in keep]
        sub.run_offset = [self.run_offset[i] for i in keep]
        sub.n_prior = sub.parametrisation().n_prior
        return sub

    def parametrisation(self) -> Parametrisation:
        """The nuisance-only parametrisation of this problem."""
        return Parametrisation(self.forward.theta_bearings, self.forward.bearing_names,
                               self.nuisance, len(self.forward.channels),
                               impacts=any(b.sweep.kind == "impact" for b in self.blocks))

    @property
    def n_data(self) -> int:
        n = sum(2 * b.mean.size for b in self.blocks)
        return n + (self.identified.values.size if self.identified is not None else 0)

    @property
    def n_obs(self) -> int:
        return self.n_data + self.n_prior

    @property
    def n_inner(self) -> int:
        """Number of real inner parameters (unbalance phasors of the 1x tests)."""
        return sum(2 * len(self.forward.planes_mm) for b in self.blocks
                   if b.sweep.kind == "unbalance_1x")

    def responses(self, rows: Rows) -> list[np.ndarray]:
        """Model responses per block through the measurement chain: complex unit-load
        responses ``(B, X, C, L)`` per complex block, then identified stiffness
        ``(B, X, nb, 2)``. Rows equal in their physical parameters are solved once."""
        _, ds, extras, mass = rows.physical()
        out: list[np.ndarray] = []
        G_all: list[np.ndarray] = []
        if self.blocks:
            # one pass over every block; rows equal in what the blocks see are solved once
            thetas = {k: rows.theta_for(k) for k in {b.sweep.kind for b in self.blocks}}
            keys = [(*(t[i].tobytes() for t in thetas.values()), ds[i].tobytes(),
                     mass[i].tobytes(), extras[i]) for i in range(ds.shape[0])]
            at: dict = {}
            inv = np.array([at.setdefault(k, len(at)) for k in keys])
            u = np.unique(inv, return_index=True)[1]
            G_all = self._unit_responses([keys[i] for i in u], u, thetas, ds, extras, mass)
            # the measurement chain at every block's points at once (elementwise: the same
            # numbers as block by block), then each block's points and channels
            freq = np.concatenate([b.sweep.freq_rad_s for b in self.blocks])
            ends = np.cumsum([b.sweep.freq_rad_s.size for b in self.blocks])
            chain_all = rows.gain[:, None] / (1 + 1j * freq[None, :, None] * rows.tau[:, None])
            force_all = rows.force_chain(freq)
        for b, idx, off, G, e in zip(self.blocks, self.channel_index, self.run_offset,
                                     G_all, ends if self.blocks else (), strict=True):
            G = G[inv][:, :, idx]
            if off is not None:
                G = G + off[None]
            pts = slice(e - b.sweep.freq_rad_s.size, e)
            chain = chain_all[:, pts][:, :, idx]
            if b.sweep.kind == "impact":      # an FRF: response over the measured force
                chain = chain * force_all[:, pts, None]
            out.append(G * chain[..., None])
        if self.identified is not None:
            ib = self.identified
            Z = self.forward.bearing_impedance(ib.sweep, rows.theta, ds, extras)
            names = self.forward.bearing_names
            j = [names.index(n) for n in ib.bearings]
            out.append(np.stack([Z[:, :, j, 0, 0].real, Z[:, :, j, 1, 1].real], axis=-1))
        return out

    def __getstate__(self) -> dict:
        """The state without the recent rows' memo (:meth:`_unit_responses`): keyed by the
        sweeps' ids, it can never hit in an unpickled problem (a worker's) or in a copy on
        other blocks (:meth:`only`), and it is up to ~2 MB."""
        return {k: v for k, v in self.__dict__.items() if k != "_recent"}

    def _unit_responses(self, keys: list, u: np.ndarray, thetas: dict, ds: np.ndarray,
                        extras: list, mass: np.ndarray) -> list[np.ndarray]:
        """The forward model's unit responses per block for the distinct physical rows ``u``
        (``keys`` theirs), those solved in recent calls taken from :attr:`_recent` (a
        Jacobian's rows that move a channel gain are the point's own physics, solved for the
        residual just before). Each row is solved on its own (the forward model's arithmetic
        per row does not depend on the rows beside it), so the numbers are the same."""
        recent = self.__dict__.setdefault("_recent", OrderedDict())
        sweeps = tuple(id(b.sweep) for b in self.blocks)
        tags = [(sweeps, k) for k in keys]
        hits = {j: recent[t] for j, t in enumerate(tags) if t in recent}
        new = [j for j in range(len(tags)) if j not in hits]
        G: list[np.ndarray] = []
        if new:
            v = u[new]
            # one array per kind, shared by its blocks: the forward model evaluates the bearing
            # impedance once per distinct array over all its sweeps' points
            sel = {k: t[v] for k, t in thetas.items()}
            G = self.forward.responses([b.sweep for b in self.blocks],
                                       [sel[b.sweep.kind] for b in self.blocks],
                                       ds[v], [extras[i] for i in v], mass[v])
        for j in hits:
            recent.move_to_end(tags[j])
        for n, j in enumerate(new):
            recent[tags[j]] = [g[n].copy() for g in G]
            if len(recent) > RECENT_ROWS:
                recent.popitem(last=False)
        if not hits:
            return G
        fresh = {j: n for n, j in enumerate(new)}
        return [np.stack([G[k][fresh[j]] if j in fresh else hits[j][k]
                          for j in range(len(tags))]) for k in range(len(self.blocks))]

    def evaluate(self, par: Parametrisation, X: np.ndarray) -> Evaluation:
        """Residuals (unbalance solved per row and 1x block) for outer rows ``X`` (B, n)."""
        X = np.atleast_2d(X)
        raw = self.responses(par.rows(X))
        res, preds, unb = [], [], []
        for b, W, G in zip(self.blocks, self.whiten, raw, strict=False):
            if b.sweep.kind == "unbalance_1x":
                r, u = _project_unbalance(G, b.mean, W)
                pred = np.einsum("bxcl,bl->bxc", G, u)
                unb.append(u)
            else:
                pred = G.sum(axis=-1)
                r = _whitened(b.mean[None] - pred, W)
            res.append(r)
            preds.append(pred)
        if self.identified is not None:
            ib, k = self.identified, raw[-1]
            res.append(((ib.values[None] - k) / ib.sd[None]).reshape(k.shape[0], -1))
            preds.append(k)
        res.append(par.prior_residuals(X))
        return Evaluation(np.concatenate(res, axis=1), tuple(preds), tuple(unb))

    def model_vector(self, par: Parametrisation, X: np.ndarray,
                     unbalance: tuple[np.ndarray, ...]) -> np.ndarray:
        """Unwhitened model observables ``(B, n_obs)`` (residual order; a prior's row is
        ``(p − μ)/σ`` against an observation 0 of unit SD) with a fixed unbalance per 1x
        block (each ``(planes,)`` complex)."""
        X = np.atleast_2d(X)
        return np.concatenate([self.data_vector(par.rows(X), unbalance),
                               -par.prior_residuals(X)], axis=1)

    def data_vector(self, rows: Rows, unbalance: tuple[np.ndarray, ...]) -> np.ndarray:
        """The data part of :meth:`model_vector` for explicit model rows."""
        raw = self.responses(rows)
        out, k = [], 0
        for b, G in zip(self.blocks, raw, strict=False):
            if b.sweep.kind == "unbalance_1x":
                pred = G @ unbalance[k]
                k += 1
            else:
                pred = G.sum(axis=-1)
            out.append(np.stack([pred.real, pred.imag], axis=-1).reshape(G.shape[0], -1))
        if self.identified is not None:
            out.append(raw[-1].reshape(raw[-1].shape[0], -1))
        return np.concatenate(out, axis=1)

    def unbalance_design(self, par: Parametrisation, x: np.ndarray) -> np.ndarray:
        """Unwhitened real design ``(n_obs, n_inner)`` of the unbalance at ``x``."""
        raw = self.responses(par.rows(x[None]))
        A = np.zeros((self.n_obs, self.n_inner))
        r0, c0 = 0, 0
        for b, G in zip(self.blocks, raw, strict=False):
            n = 2 * G.shape[1] * G.shape[2]
            if b.sweep.kind == "unbalance_1x":
                D = _real_design(G[0]).reshape(n, -1)
                A[r0:r0 + n, c0:c0 + D.shape[1]] = D
                c0 += D.shape[1]
            r0 += n
        return A

    def noise_cells(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Noise description in residual order: complex cells' covariances ``(nc, 2, 2)`` and
        dofs ``(nc,)``, real observables' SDs ``(nr,)`` and dofs ``(nr,)`` (identified
        stiffness, then the priors with unit SD known exactly)."""
        cov = np.concatenate([b.cov.reshape(-1, 2, 2) for b in self.blocks])
        dof = np.concatenate([np.full(b.mean.size, b.dof) for b in self.blocks])
        sd, dr = [np.ones(self.n_prior)], [np.full(self.n_prior, KNOWN_DOF)]
        if self.identified is not None:
            ib = self.identified
            sd.insert(0, ib.sd.ravel())
            dr.insert(0, np.full(ib.sd.size, ib.dof))
        return cov, dof, np.concatenate(sd), np.concatenate(dr)

    def series(self) -> list[tuple[int, int, int, np.ndarray]]:
        """Per complex block: residual offset, points X, channels C and the points' coordinate
        scaled to [0, 1] (for tests of structure along speed or frequency)."""
        out, off = [], 0
        for b in self.blocks:
            X, C = b.mean.shape
            c = b.coord
            span = c.max() - c.min()
            out.append((off, X, C, (c - c.min()) / (span if span > 0 else 1.0)))
            off += 2 * X * C
        return out


#: distinct physical rows whose unit responses a problem keeps (:meth:`Problem._unit_responses`;
#: a few tens of kB each)
RECENT_ROWS = 64

#: degrees of freedom standing for a variance known exactly (a prior's unit SD)
KNOWN_DOF = 10**9


def _whitened(r: np.ndarray, W: np.ndarray) -> np.ndarray:
    """Whiten complex residuals ``r`` (B, X, C) with per-cell ``W`` (X, C, 2, 2) → (B, 2XC)."""
    re, im = r.real, r.imag                 # the sums of :func:`_times_2x2`, written out
    out = np.empty(r.shape + (2,))
    out[..., 0] = W[..., 0, 0] * re + W[..., 0, 1] * im
    out[..., 1] = W[..., 1, 0] * re + W[..., 1, 1] * im
    return out.reshape(r.shape[0], -1)


def _times_2x2(W: np.ndarray, V: np.ndarray) -> np.ndarray:
    """``W @ V`` for 2x2 ``W`` (..., 2, 2) and ``V`` (..., 2, k), written out: the same sums
    of two products as ``einsum``'s, a few times faster for many small cells."""
    out = np.empty(np.broadcast_shapes(W.shape[:-2], V.shape[:-2]) + (2, V.shape[-1]))
    for i in (0, 1):
        out[..., i, :] = W[..., i, 0, None] * V[..., 0, :] + W[..., i, 1, None] * V[..., 1, :]
    return out


def _real_design(G: np.ndarray) -> np.ndarray:
    """Complex ``G`` (..., L) acting on ``u = a + ib`` → real (..., 2, 2L) on ``[a, b]``."""
    top = np.concatenate([G.real, -G.imag], axis=-1)
    bot = np.concatenate([G.imag, G.real], axis=-1)
    return np.stack([top, bot], axis=-2)


def _whitened_design(W: np.ndarray, G: np.ndarray) -> np.ndarray:
    """Whitened real design ``(…, 2XC, 2L)`` of a 1x block's unbalance: complex ``G``
    ``(…, X, C, L)``, per-cell whitening ``W`` ``(X, C, 2, 2)``."""
    return _times_2x2(W, _real_design(G)).reshape(G.shape[:-3] + (-1, 2 * G.shape[-1]))


def _project_unbalance(G: np.ndarray, y: np.ndarray, W: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Weighted LS unbalance ``u`` per row and the whitened residual ``W (y − G u)``."""
    L = G.shape[-1]
    A = _whitened_design(W, G)
    yw = np.einsum("xcij,xcj->xci", W, np.stack([y.real, y.imag], axis=-1)).reshape(-1)
    Q, R = np.linalg.qr(A)
    coef = np.linalg.solve(R, np.einsum("bnk,n->bk", Q, yw)[..., None])[..., 0]
    r = yw[None] - np.einsum("bnk,bk->bn", A, coef)
    return r, coef[:, :L] + 1j * coef[:, L:]
