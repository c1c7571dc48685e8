"""A Gaussian-process discrepancy for prediction (Kennedy & O'Hagan 2001): it corrects what no
library effect explains, without naming it.

The GP lives on the whitened residuals of each 1x block along speed: per series (channel ×
real/imaginary part) ``r = δ + e`` with ``δ ~ GP(0, τ k_ℓ)``, squared-exponential ``k_ℓ`` over
the speed scaled to [0, 1], and ``e`` the unit whitened noise. ``(ℓ, τ)`` are the ones that
maximise the structure test's likelihood ratio
(:func:`~surrogate_rbrdo.discrepancy.calibration.gp_statistic`). At a held-out speed the
posterior mean ``τ k*ᵀ (τ K + I)⁻¹ r`` is turned back into metres with that speed's noise
covariance (the correction is in units of the local noise), so it interpolates between measured
speeds and fades to zero away from them — a correction, not a law.
"""

from __future__ import annotations

import numpy as np

from surrogate_rbrdo.discrepancy.calibration import GP_LENGTHS, GP_TAUS
from surrogate_rbrdo.discrepancy.problem import Problem


def _hyper(R: np.ndarray, t: np.ndarray) -> tuple[float, float, float]:
    """``(ℓ, τ, LR)`` maximising the GP likelihood ratio of the residual series ``R``."""
    best = (GP_LENGTHS[0], 0.0, 0.0)
    for ell in GP_LENGTHS:
        K = np.exp(-0.5 * ((t[:, None] - t[None, :]) / ell) ** 2)
        lam, U = np.linalg.eigh(K)
        lam = np.clip(lam, 0.0, None)
        q = np.sum((U.T @ R) ** 2, axis=1)
        for tau in GP_TAUS:
            tl = tau * lam
            lr = float(np.sum(q * tl / (1 + tl)) - R.shape[1] * np.sum(np.log1p(tl)))
            if lr > best[2]:
                best = (ell, tau, lr)
    return best


def gp_correction(train: Problem, r_train: np.ndarray, target: Problem) -> list[np.ndarray]:
    """Complex corrections (m) per block of ``target`` from the whitened training residuals
    ``r_train`` (residual order of ``train``); zero for blocks without a 1x test."""
    out = []
    series = train.series()
    k = 0
    for bt, Wt in zip(target.blocks, target.whiten, strict=True):
        corr = np.zeros(bt.mean.shape, dtype=complex)
        if bt.sweep.kind == "unbalance_1x" and bt.mean.size:
            bi = next(i for i, b in enumerate(train.blocks) if b.name == bt.name)
            off, X, C, t = series[bi]
            R = r_train[off:off + 2 * X * C].reshape(X, 2 * C)
            c0 = train.blocks[bi].coord
            span = c0.max() - c0.min()
            ts = (bt.coord - c0.min()) / (span if span > 0 else 1.0)
            ell, tau, _ = _hyper(R, t)
            if tau > 0:
                K = tau * np.exp(-0.5 * ((t[:, None] - t[None, :]) / ell) ** 2)
                Ks = tau * np.exp(-0.5 * ((ts[:, None] - t[None, :]) / ell) ** 2)
                mean_w = Ks @ np.linalg.solve(K + np.eye(X), R)       # (X*, 2C) whitened
                w = mean_w.reshape(-1, C, 2)
                v = np.linalg.solve(Wt, w[..., None])[..., 0]          # back to metres
                corr = v[..., 0] + 1j * v[..., 1]
            k += 1
        out.append(corr)
    return out
