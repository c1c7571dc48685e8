"""Immutable optimisation results and the archive of every evaluated design.

>>> import numpy as np
>>> rec = ArchiveRecorder()
>>> rec.add(np.zeros((2, 1)), np.ones((2, 2)), np.zeros((2, 0)), np.ones(2), np.ones(2),
...         np.zeros(2))
>>> rec.freeze().generation.tolist()
[0, 0]
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.optimization.pareto import feasible_mask, total_violation


@dataclass(frozen=True, eq=False)
class Archive:
    """Every design evaluated during one run, in evaluation order.

    Attributes
    ----------
    X : (n, d) designs; F : (n, n_obj) objectives; G : (n, n_con) constraints (<= 0 feasible);
    generation : (n,) int, 0 = initial population; mean, std, pf : (n,) estimates of the
    primary response on the fixed θ sample (μ_y, σ_y, P_f; NaN where not computed).
    """

    X: np.ndarray
    F: np.ndarray
    G: np.ndarray
    generation: np.ndarray
    mean: np.ndarray
    std: np.ndarray
    pf: np.ndarray

    def __len__(self) -> int:
        return int(self.X.shape[0])

    @property
    def feasible(self) -> np.ndarray:
        """Boolean mask of designs with every constraint ``<= 0``."""
        return feasible_mask(self.G)

    def to_dict(self) -> dict[str, Any]:
        return {k: getattr(self, k).tolist()
                for k in ("X", "F", "G", "generation", "mean", "std", "pf")}


class ArchiveRecorder:
    """Append-only buffer filled during one run; :meth:`freeze` concatenates once."""

    def __init__(self) -> None:
        self._chunks: list[tuple[np.ndarray, ...]] = []

    @property
    def n_batches(self) -> int:
        return len(self._chunks)

    def add(self, X, F, G, mean, std, pf) -> None:
        gen = np.full(X.shape[0], len(self._chunks), dtype=np.int64)
        self._chunks.append((X, F, G, gen, mean, std, pf))

    def freeze(self) -> Archive:
        if not self._chunks:
            raise ValueError("archive is empty: no design was evaluated")
        cols = [np.concatenate(c, axis=0) for c in zip(*self._chunks, strict=True)]
        for c in cols:
            c.flags.writeable = False
        return Archive(*cols)


@dataclass(frozen=True, eq=False)
class OptimizationResult:
    """Outcome of one optimiser run.

    Attributes
    ----------
    X, F, G : ndarray
        Final population (designs, objectives, constraints).
    pareto_mask : ndarray of bool
        Feasible non-dominated members of the final population.
    archive : Archive
        Every evaluated design (use :func:`~.postprocess.feasible_pareto` on it for the front
        over the whole run).
    n_surrogate_calls : int
        θ points evaluated by the response(s) (the paper's "surrogate calls").
    n_model_calls : int
        Designs passed to the deterministic FE model.
    history : tuple of dict
        Per generation: ``generation``, ``n_evals``, ``n_feasible``, ``f_min`` (per objective,
        over feasible designs of that batch), ``cv_min`` (least total violation).
    wall_time_s : float
    formulation : dict
        ``Formulation.describe()``.
    optimizer : dict
        Optimiser name, options and seed.
    """

    X: np.ndarray
    F: np.ndarray
    G: np.ndarray
    pareto_mask: np.ndarray
    archive: Archive
    n_surrogate_calls: int
    n_model_calls: int
    history: tuple[Mapping[str, Any], ...]
    wall_time_s: float
    formulation: Mapping[str, Any] = field(default_factory=dict)
    optimizer: Mapping[str, Any] = field(default_factory=dict)

    def to_dict(self, *, include_archive: bool = False) -> dict[str, Any]:
        """Plain-python view (lists instead of arrays), for JSON output."""
        out = {
            "X": self.X.tolist(), "F": self.F.tolist(), "G": self.G.tolist(),
            "pareto_mask": self.pareto_mask.tolist(),
            "n_surrogate_calls": int(self.n_surrogate_calls),
            "n_model_calls": int(self.n_model_calls),
            "n_evaluated": len(self.archive),
            "history": [dict(h) for h in self.history],
            "wall_time_s": float(self.wall_time_s),
            "formulation": dict(self.formulation), "optimizer": dict(self.optimizer),
        }
        if include_archive:
            out["archive"] = self.archive.to_dict()
        return out


def batch_history(gen: int, F: np.ndarray, G: np.ndarray) -> dict[str, Any]:
    """Summary of one evaluated batch for :attr:`OptimizationResult.history`."""
    feas = feasible_mask(G)
    cv = total_violation(G)
    f_min = F[feas].min(axis=0).tolist() if feas.any() else [float("nan")] * F.shape[1]
    return {"generation": gen, "n_evals": int(F.shape[0]), "n_feasible": int(feas.sum()),
            "f_min": f_min, "cv_min": float(cv.min()) if cv.size else 0.0}
