"""Whitened residuals of a model against measured data, with the unbalance solved exactly.

The outer parameters are the model's own uncertain parameters (the *nuisance*: a stiffness factor
θ per bearing, a factor on the bearing damping) and, when a candidate effect is tried, its
parameters. The unbalance phasors of every 1x test are *inner* parameters: the 1x response is
linear in them, so for given outer parameters they are the exact weighted least-squares
solution, and the residual that the outer fit sees is the variable-projection residual
(Golub & Pereyra 1973, *SIAM J. Numer. Anal.* 10:413). Everything is batched over rows of outer
parameters: a finite-difference Jacobian is one call.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_range
from surrogate_rbrdo.discrepancy.candidates import Candidate
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.observables import ComplexBlock, MeasuredData, RealBlock
from surrogate_rbrdo.spindle.effects import Effect


@dataclass(frozen=True)
class NuisanceOptions:
    """Which of the model's own parameters are recalibrated, and within which range.

    Attributes
    ----------
    theta_bounds : (float, float)
        Range of each bearing's stiffness factor θ (the paper's identification bounds
        ``[0.5, 1.5] k_catalog``).
    damping : {"common", "per_bearing", "fixed"}
        One factor on every bearing's damping, one per bearing, or none.
    damping_bounds : (float, float)
        Range of a damping factor (the paper's ``[0.5, 2.0] c_init``, widened to 0.25–4 since
        damping is the worst-known parameter).
    """

    theta_bounds: tuple[float, float] = (0.5, 1.5)
    damping: str = "common"
    damping_bounds: tuple[float, float] = (0.25, 4.0)

    def __post_init__(self) -> None:
        check_choice("nuisance.damping", self.damping, ("common", "per_bearing", "fixed"))
        for name in ("theta_bounds", "damping_bounds"):
            lo, hi = getattr(self, name)
            check_range(f"nuisance.{name}[0]", lo, 1e-3, 1.0)
            check_range(f"nuisance.{name}[1]", hi, 1.0, 1e3)


@dataclass(frozen=True)
class Slot:
    """A candidate effect in the model at one bearing scope; ``fixed`` shape values are not
    fitted."""

    candidate: Candidate
    scope: tuple[str, ...] = ()
    fixed: tuple[tuple[str, float], ...] = ()

    @property
    def free(self) -> tuple[str, ...]:
        fx = dict(self.fixed)
        return self.candidate.strength + tuple(p for p in self.candidate.shape if p not in fx)

    @property
    def label(self) -> str:
        s = f"{self.candidate.name}"
        return s + (f"[{','.join(self.scope)}]" if self.scope else "")


#: typical size of a reciprocal strength parameter (a compliance, m/N): 1/(1 GN/m)
RECIPROCAL_SCALE = 1e-9


@dataclass(frozen=True)
class Parametrisation:
    """Outer parameter vector ``x`` ↔ model rows: ``[log θ…, log s…, slot parameters…]``."""

    theta_bearings: tuple[str, ...]
    bearings: tuple[str, ...]
    nuisance: NuisanceOptions
    slots: tuple[Slot, ...] = ()

    @property
    def n_theta(self) -> int:
        return len(self.theta_bearings)

    @property
    def n_damping(self) -> int:
        return {"common": 1, "per_bearing": len(self.bearings), "fixed": 0}[
            self.nuisance.damping]

    @property
    def n_nuisance(self) -> int:
        return self.n_theta + self.n_damping

    @property
    def names(self) -> tuple[str, ...]:
        out = [f"log_theta_{b}" for b in self.theta_bearings]
        if self.nuisance.damping == "common":
            out.append("log_damping")
        elif self.nuisance.damping == "per_bearing":
            out += [f"log_damping_{b}" for b in self.bearings]
        for s in self.slots:
            out += [f"{s.label}.{p}" for p in s.free]
        return tuple(out)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        lo = [np.log(self.nuisance.theta_bounds[0])] * self.n_theta
        hi = [np.log(self.nuisance.theta_bounds[1])] * self.n_theta
        lo += [np.log(self.nuisance.damping_bounds[0])] * self.n_damping
        hi += [np.log(self.nuisance.damping_bounds[1])] * self.n_damping
        for s in self.slots:
            c = s.candidate
            lo += list(c.lower)
            hi += list(c.upper)
            fx = dict(s.fixed)
            for p, (a, b) in zip(c.shape, c.shape_bounds, strict=True):
                if p not in fx:
                    lo.append(a)
                    hi.append(b)
        return np.array(lo, dtype=float), np.array(hi, dtype=float)

    def scales(self) -> np.ndarray:
        """A typical magnitude per parameter (finite-difference steps are relative to it)."""
        out = [0.05] * self.n_theta + [0.3] * self.n_damping
        for s in self.slots:
            c = s.candidate
            for rec, a, b in zip(c.reciprocal, c.lower, c.upper, strict=True):
                out.append(RECIPROCAL_SCALE if rec else (b - a) / 50 if np.isfinite(b - a)
                           else 0.01)
            fx = dict(s.fixed)
            for p, (a, b) in zip(c.shape, c.shape_bounds, strict=True):
                if p not in fx:
                    out.append(max((b - a) / 100, 1e-3) if np.isfinite(b - a) else 1.0)
        return np.array(out, dtype=float)

    def x0(self, starts: dict[str, float] | None = None) -> np.ndarray:
        """Nominal nuisance, every slot off, shapes at their first start (or ``starts``)."""
        starts = starts or {}
        x = [0.0] * self.n_nuisance
        for s in self.slots:
            c = s.candidate
            x += [starts.get(f"{s.label}.{p}", o) for p, o in zip(c.strength, c.off,
                                                                   strict=True)]
            fx = dict(s.fixed)
            for p, st in zip(c.shape, c.shape_starts, strict=True):
                if p not in fx:
                    x.append(starts.get(f"{s.label}.{p}", st[0]))
        return np.array(x, dtype=float)

    def slot_values(self, x: np.ndarray) -> list[dict[str, float]]:
        """Per slot: its parameters (fitting units) including fixed shapes."""
        k = self.n_nuisance
        out = []
        for s in self.slots:
            vals = dict(s.fixed)
            for p in s.free:
                vals[p] = float(x[k])
                k += 1
            out.append(vals)
        return out

    def rows(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[tuple[Effect, ...]]]:
        """θ (B, m), damping factors (B, nb) and per-row extra effects for outer rows ``X``."""
        X = np.atleast_2d(X)
        B = X.shape[0]
        theta = np.exp(X[:, :self.n_theta])
        nd = self.n_damping
        d = np.exp(X[:, self.n_theta:self.n_nuisance]) if nd else np.ones((B, 0))
        ds = np.ones((B, len(self.bearings))) * (d if nd else 1.0)
        extras = [tuple(s.candidate.effect(s.scope, v)
                        for s, v in zip(self.slots, self.slot_values(x), strict=True))
                  for x in X]
        return theta, ds, extras


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
    """

    def __init__(self, forward: ForwardModel, data: MeasuredData,
                 masks: dict[str, np.ndarray] | None = None) -> None:
        masks = masks or {}
        self.forward = forward
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

    @property
    def n_obs(self) -> int:
        n = sum(2 * b.mean.size for b in self.blocks)
        return n + (self.identified.values.size if self.identified is not None else 0)

    @property
    def n_inner(self) -> int:
        """Number of real inner parameters (unbalance phasors of the 1x tests)."""
        return sum(2 * len(self.forward.planes_mm) for b in self.blocks
                   if b.sweep.kind == "unbalance_1x")

    def responses(self, theta: np.ndarray, ds: np.ndarray,
                  extras: list[tuple[Effect, ...]]) -> list[np.ndarray]:
        """Raw model responses per block for explicit rows: complex unit-load responses
        ``(B, X, C, L)`` per complex block, then identified stiffness ``(B, X, nb, 2)``."""
        out = []
        for b, idx in zip(self.blocks, self.channel_index, strict=True):
            out.append(self.forward.response(b.sweep, theta, ds, extras)[:, :, idx])
        if self.identified is not None:
            ib = self.identified
            Z = self.forward.bearing_impedance(ib.sweep, theta, ds, extras)
            names = self.forward.bearing_names
            j = [names.index(n) for n in ib.bearings]
            out.append(np.stack([Z[:, :, j, 0, 0].real, Z[:, :, j, 1, 1].real], axis=-1))
        return out

    def evaluate(self, par: Parametrisation, X: np.ndarray) -> Evaluation:
        """Residuals (unbalance solved per row and 1x block) for outer rows ``X`` (B, n)."""
        raw = self.responses(*par.rows(X))
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
        return Evaluation(np.concatenate(res, axis=1), tuple(preds), tuple(unb))

    def model_vector(self, raw: list[np.ndarray], unbalance: tuple[np.ndarray, ...]
                     ) -> np.ndarray:
        """Unwhitened model observables ``(B, n_obs)`` (residual order) from raw responses and
        a fixed unbalance per 1x block (each ``(planes,)`` complex)."""
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

    def unbalance_design(self, raw: list[np.ndarray]) -> np.ndarray:
        """Unwhitened real design ``(n_obs, n_inner)`` of the unbalance (row 0 of ``raw``)."""
        cols, rows = [], []
        for b, G in zip(self.blocks, raw, strict=False):
            n = 2 * G.shape[1] * G.shape[2]
            if b.sweep.kind == "unbalance_1x":
                cols.append(_real_design(G[0]).reshape(n, -1))
            rows.append(n)
        if self.identified is not None:
            rows.append(self.identified.values.size)
        A = np.zeros((sum(rows), sum(c.shape[1] for c in cols)))
        r0, c0, k = 0, 0, 0
        for b, n in zip(self.blocks, rows, strict=False):
            if b.sweep.kind == "unbalance_1x":
                A[r0:r0 + n, c0:c0 + cols[k].shape[1]] = cols[k]
                c0 += cols[k].shape[1]
                k += 1
            r0 += n
        return A

    def noise_cells(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Noise description in residual order: complex cells' covariances ``(nc, 2, 2)`` and
        dofs ``(nc,)``, real observables' SDs ``(nr,)`` and dofs ``(nr,)``."""
        cov = np.concatenate([b.cov.reshape(-1, 2, 2) for b in self.blocks])
        dof = np.concatenate([np.full(b.mean.size, b.dof) for b in self.blocks])
        if self.identified is None:
            return cov, dof, np.zeros(0), np.zeros(0, dtype=int)
        ib = self.identified
        return cov, dof, ib.sd.ravel(), np.full(ib.sd.size, ib.dof)

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


def _whitened(r: np.ndarray, W: np.ndarray) -> np.ndarray:
    """Whiten complex residuals ``r`` (B, X, C) with per-cell ``W`` (X, C, 2, 2) → (B, 2XC)."""
    v = np.stack([r.real, r.imag], axis=-1)
    return np.einsum("xcij,bxcj->bxci", W, v).reshape(r.shape[0], -1)


def _real_design(G: np.ndarray) -> np.ndarray:
    """Complex ``G`` (..., L) acting on ``u = a + ib`` → real (..., 2, 2L) on ``[a, b]``."""
    top = np.concatenate([G.real, -G.imag], axis=-1)
    bot = np.concatenate([G.imag, G.real], axis=-1)
    return np.stack([top, bot], axis=-2)


def _project_unbalance(G: np.ndarray, y: np.ndarray, W: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Weighted LS unbalance ``u`` per row and the whitened residual ``W (y − G u)``."""
    B, X, C, L = G.shape
    A = np.einsum("xcij,bxcjk->bxcik", W, _real_design(G)).reshape(B, 2 * X * C, 2 * L)
    yw = np.einsum("xcij,xcj->xci", W, np.stack([y.real, y.imag], axis=-1)).reshape(-1)
    Q, R = np.linalg.qr(A)
    coef = np.linalg.solve(R, np.einsum("bnk,n->bk", Q, yw)[..., None])[..., 0]
    r = yw[None] - np.einsum("bnk,bk->bn", A, coef)
    return r, coef[:, :L] + 1j * coef[:, L:]
