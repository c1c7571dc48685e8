"""Is a converged FORM point a local *minimum* of the distance to the limit state?

iHL-RF (and SLSQP) stop at any first-order KKT point of ``min ‖u‖ s.t. G(u) = 0``: ``G = 0``
and ``u ∥ −∇G``. That is a stationary point of the distance on the limit state, which may be a
saddle or a maximum where the failure domain is concave towards the origin. Example (review s4,
F13-1): ``y = u₁ + κ Σ_{i≥2} u_i²``, failure ``y > 3``; for ``2κβ > 1`` the axis point
``(3, 0, …)`` is a saddle and the nearest points lie on a ring at ``β* = √5`` (κ = 0.5), so
``Φ(−3)`` under-estimates ``P_f`` 60-fold in 3-D.

The check (a poll, as in a pattern search, Kolda, Lewis & Torczon 2003): the ``2(m − 1)``
points at radius ``β(1 − ε)`` tilted by an angle ``h`` from ``u*`` towards ``±`` each
direction orthogonal to ``u*``. Inside the sphere of radius ``β`` every point near a local
minimum lies on the origin's side of the limit state; a poll point on the other side proves a
point of the limit state nearer than ``β`` (the segment from the origin to it crosses ``G = 0``)
— the search continues from there. Along a tilt ``h`` the limit state lies at
``ρ(h) ≈ β + ½ β (1 − β k) h²`` (``k`` the surface's curvature towards the origin in that
direction), so the poll sees a saddle whose ``β k − 1 > 2ε/h²`` (0.2 with the defaults): a
milder one has its minimum within a few per cent of ``β``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from surrogate_rbrdo.estimators._constrained import orthonormal_complement

#: tilt of the poll (radians) and relative shrink of its radius
POLL_ANGLE, POLL_SHRINK = 0.1, 1e-3


def nearer_point(G: Any, u: np.ndarray, sign0: float, h: float = POLL_ANGLE,
                 eps: float = POLL_SHRINK) -> np.ndarray | None:
    """The poll point (module docstring) deepest on the far side of the limit state from the
    origin (``sign0 · G < 0``, ``sign0`` the sign of ``G(0)``), or None when there is none: a
    local minimum as far as the poll can see. One batched call of ``2(m − 1)`` points.

    >>> class Concave:                     # failure u₁ + 0.5 u₂² > 3: a saddle at (3, 0)
    ...     def __call__(self, u): return 3.0 - u[:, 0] - 0.5 * u[:, 1] ** 2
    >>> p = nearer_point(Concave(), np.array([3.0, 0.0]), 1.0)
    >>> bool(np.linalg.norm(p) < 3.0), bool(Concave()(p[None, :])[0] < 0)
    (True, True)
    >>> class Linear:
    ...     def __call__(self, u): return 3.0 - u[:, 0]
    >>> nearer_point(Linear(), np.array([3.0, 0.0]), 1.0) is None
    True
    """
    far = far_side_points(G, u, sign0, h, eps)
    return far[0] if far.shape[0] else None


def far_side_points(G: Any, u: np.ndarray, sign0: float, h: float = POLL_ANGLE,
                    eps: float = POLL_SHRINK) -> np.ndarray:
    """Every poll point of :func:`nearer_point` on the far side of the limit state, deepest
    first (``(k, m)``, ``k = 0`` at a local minimum as far as the poll can see).

    >>> class Corner:                      # series system min(3 − u₁, 3 − u₂): corner (3, 3)
    ...     def __call__(self, u): return np.minimum(3.0 - u[:, 0], 3.0 - u[:, 1])
    >>> far_side_points(Corner(), np.array([3.0, 3.0]), 1.0).shape[0]   # both tilts fail
    2
    """
    beta = float(np.linalg.norm(u))
    m = u.size
    if m < 2 or not (np.isfinite(beta) and beta > 0):
        return np.empty((0, m))
    e = u / beta
    tilts = orthonormal_complement(e)
    tilts = np.vstack([tilts, -tilts])
    P = beta * (1.0 - eps) * (np.cos(h) * e[None, :] + np.sin(h) * tilts)
    g = sign0 * np.asarray(G(P), dtype=float)
    g = np.where(np.isfinite(g), g, np.inf)   # outside the physical domain: not a failure
    order = np.argsort(g, kind="stable")
    return P[order[g[order] < 0]]


__all__ = ["POLL_ANGLE", "POLL_SHRINK", "far_side_points", "nearer_point"]
