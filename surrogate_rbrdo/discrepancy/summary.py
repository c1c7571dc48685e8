"""Where the model and the data part: residuals of every observable at every point, before and
after, and their χ²/dof per observable and per speed band.

For each block of the data, at every point (training and held-out): the measured mean and its
standard error, the recalibrated baseline's prediction (*before*) and the final model's
(*after*: the named effects added, or the baseline plus the GP correction for an unnamed
residual), and the whitened residuals of both. Everything is computed with the parameters and
unbalance fitted on training points only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.discrepancy.fit import Fit
from surrogate_rbrdo.discrepancy.gp import gp_correction
from surrogate_rbrdo.discrepancy.holdout import residuals
from surrogate_rbrdo.discrepancy.problem import Problem, _whitened

#: speed (or frequency) bands of the χ²/dof table
N_BANDS = 5


@dataclass(frozen=True)
class BlockCurves:
    """One block's points: coordinates, data, predictions and whitened residuals."""

    name: str
    coord: np.ndarray                 # (X,) rpm or Hz
    coord_label: str
    channels: tuple[str, ...]
    data: np.ndarray                  # (X, C) complex
    se: np.ndarray                    # (X, C) standard error of |data| (m)
    before: np.ndarray                # (X, C) complex
    after: np.ndarray                 # (X, C) complex
    white_before: np.ndarray          # (X, C, 2)
    white_after: np.ndarray           # (X, C, 2)
    held_out: np.ndarray              # (X,) bool

    def chi2_table(self, which: str = "before", bands: int = N_BANDS) -> dict:
        """χ²/dof per channel, overall and per band of the coordinate."""
        w = self.white_before if which == "before" else self.white_after
        edges = np.linspace(self.coord.min(), self.coord.max(), bands + 1)
        k = np.clip(np.searchsorted(edges, self.coord, side="right") - 1, 0, bands - 1)
        out = {}
        for j, c in enumerate(self.channels):
            q = np.sum(w[:, j] ** 2, axis=-1)
            out[c] = {"all": float(q.mean() / 2),
                      "bands": [float(q[k == i].mean() / 2) if np.any(k == i) else None
                                for i in range(bands)],
                      "band_edges": edges.tolist()}
        return out


def block_curves(problem: Problem, held: np.ndarray, base: Fit, final: Fit,
                 gp_train: tuple[Problem, np.ndarray] | None = None) -> list[BlockCurves]:
    """Curves of every block of ``problem`` (all points; ``held`` marks held-out points of the
    1x blocks); ``gp_train`` = (training problem, its whitened residuals at ``final``) adds
    the GP correction to *after*."""
    ub = tuple(u[0] for u in base.evaluation.unbalance)
    uf = tuple(u[0] for u in final.evaluation.unbalance)
    rb = residuals(problem, base.par, base.x, ub)
    corr = gp_correction(gp_train[0], gp_train[1], problem) if gp_train else None
    ra = residuals(problem, final.par, final.x, uf, corr)
    out = []
    for b, W, r0, r1 in zip(problem.blocks, problem.whiten, rb, ra, strict=True):
        se = np.sqrt(np.trace(b.cov, axis1=-2, axis2=-1) / 2)
        ho = held if b.sweep.kind == "unbalance_1x" else np.zeros(b.mean.shape[0], bool)
        out.append(BlockCurves(
            b.name, b.coord, b.coord_label, tuple(c.name for c in b.channels), b.mean, se,
            b.mean - r0, b.mean - r1,
            _whitened(r0[None], W)[0].reshape(r0.shape + (2,)),
            _whitened(r1[None], W)[0].reshape(r1.shape + (2,)), ho))
    return out
