"""Feasible Pareto sets and the ASF compromise (own vectorised numpy, no pymoo needed).

>>> import numpy as np
>>> F = np.array([[1.0, 4.0], [2.0, 2.0], [3.0, 3.0], [4.0, 1.0], [0.5, 0.5]])
>>> G = np.array([[0.0], [-1.0], [-1.0], [-1.0], [1.0]])   # last point infeasible
>>> feasible_pareto(F, G).tolist()
[True, True, False, True, False]
>>> int(asf_compromise(F[[0, 1, 3]]))
1
"""

from __future__ import annotations

import numpy as np

from surrogate_rbrdo.core.validate import check_positive


def feasible_mask(G: np.ndarray) -> np.ndarray:
    """``True`` where every constraint is ``<= 0`` (no constraints: all feasible)."""
    G = np.asarray(G, dtype=float)
    if G.ndim == 1:
        G = G[:, None]
    return np.all(G <= 0.0, axis=1)


def total_violation(G: np.ndarray) -> np.ndarray:
    """Sum of the positive parts of the constraints per row (0 where feasible or none).

    >>> total_violation(np.array([[-1.0, 2.0], [0.5, 0.25]])).tolist()
    [2.0, 0.75]
    >>> total_violation(np.empty((2, 0))).tolist()
    [0.0, 0.0]
    """
    return np.maximum(np.asarray(G, dtype=float), 0.0).sum(axis=1)


def nondominated(F: np.ndarray) -> np.ndarray:
    """Mask of non-dominated rows of ``F`` (minimisation); exact duplicates keep one copy.

    Two objectives use an O(n log n) sweep; one objective keeps the minimisers; more objectives
    use a chunked pairwise test.
    """
    F = np.asarray(F, dtype=float)
    n = F.shape[0]
    mask = np.zeros(n, dtype=bool)
    if n == 0:
        return mask
    if F.shape[1] == 1:
        best = F[:, 0].min()
        mask[np.flatnonzero(F[:, 0] == best)[0]] = True
        return mask
    if F.shape[1] == 2:
        order = np.lexsort((F[:, 1], F[:, 0]))  # by f1, ties by f2
        f2 = F[order, 1]
        prev_min = np.minimum.accumulate(np.concatenate([[np.inf], f2[:-1]]))
        mask[order[f2 < prev_min]] = True
        return mask
    _, first = np.unique(F, axis=0, return_index=True)
    keep = np.zeros(n, dtype=bool)
    keep[first] = True
    for start in range(0, n, 256):
        blk = F[start:start + 256]
        le = np.all(F[None, :, :] <= blk[:, None, :], axis=2)
        lt = np.any(F[None, :, :] < blk[:, None, :], axis=2)
        mask[start:start + 256] = ~np.any(le & lt, axis=1)
    return mask & keep


def feasible_pareto(F: np.ndarray, G: np.ndarray) -> np.ndarray:
    """Mask of points that are feasible and non-dominated among the feasible points."""
    F = np.asarray(F, dtype=float)
    feas = feasible_mask(G)
    out = np.zeros(F.shape[0], dtype=bool)
    idx = np.flatnonzero(feas)
    out[idx[nondominated(F[idx])]] = True
    return out


def asf_compromise(F: np.ndarray, weights=(0.5, 0.5), *, rho: float = 1e-6) -> int:
    """Index of the achievement-scalarising-function compromise of a front.

    Objectives are normalised by the front's ideal and nadir points,
    ``f̃ = (f − z_ideal) / (z_nadir − z_ideal)`` (a zero range maps to 0), and the point
    minimising ``max_i f̃_i / w_i + rho · Σ_i f̃_i / w_i`` is returned (the augmentation ``rho``
    only breaks ties towards non-weakly-dominated points). With the paper's weights 0.5/0.5 this
    is the front point closest, in the Chebyshev sense, to the normalised ideal point along the
    diagonal. Same definition as pymoo's ``ASF`` decomposition with ``utopian_point = ideal``
    on normalised objectives.

    Parameters
    ----------
    F : ndarray, shape (n, n_obj)
        A (feasible, non-dominated) front.
    weights : sequence of float
        Positive weights, one per objective.
    """
    F = np.asarray(F, dtype=float)
    if F.ndim != 2 or F.shape[0] == 0:
        raise ValueError(f"F has shape {F.shape}: need a non-empty (n, n_obj) front")
    w = np.asarray(weights, dtype=float)
    if w.shape != (F.shape[1],):
        raise ValueError(f"weights = {tuple(weights)} is not allowed: need {F.shape[1]} values")
    for i, wi in enumerate(w):
        check_positive(f"weights[{i}]", float(wi))
    ideal, nadir = F.min(axis=0), F.max(axis=0)
    span = nadir - ideal
    Fn = np.divide(F - ideal, span, out=np.zeros_like(F), where=span > 0)
    s = Fn / w
    return int(np.argmin(s.max(axis=1) + rho * s.sum(axis=1)))
