"""Infill helpers: the joint (x, θ) DOE box and greedy maximin selection of candidates.

>>> import numpy as np
>>> joint_bounds([[0.0, 1.0]], [1.0], [0.1], theta_sigmas=2.0).round(3).tolist()
[[0.0, 1.0], [0.8, 1.2]]
>>> cand = np.array([[0.1, 0.1], [0.5, 0.5], [0.9, 0.9], [0.12, 0.1]])
>>> maximin_select(cand, np.array([[0.0, 0.0]]), np.array([[0.0, 1.0], [0.0, 1.0]]),
...                2).tolist()
[[0.9, 0.9], [0.5, 0.5]]
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_positive

THETA_BOXES = ("sigma", "bounds")


def joint_bounds(design_bounds: object, mean: Sequence[float], std: Sequence[float], *,
                 theta_box: str = "sigma", theta_sigmas: float = 4.0,
                 theta_bounds: tuple[float, float] = (0.5, 1.5)) -> np.ndarray:
    """The ``(d + m, 2)`` joint DOE box: the design box, then the θ box.

    ``theta_box = "sigma"``: ``mean ± theta_sigmas · std`` per θ component (±4σ holds the
    Monte Carlo samples, P(outside) ≈ 6e-5 per component); ``"bounds"``: ``theta_bounds``
    for every component.
    """
    check_choice("theta_box", theta_box, THETA_BOXES)
    xb = np.asarray(design_bounds, dtype=float)
    mean = np.asarray(mean, dtype=float)
    if theta_box == "sigma":
        check_positive("theta_sigmas", theta_sigmas)
        std = np.asarray(std, dtype=float)
        tb = np.column_stack([mean - theta_sigmas * std, mean + theta_sigmas * std])
    else:
        tb = np.tile(np.asarray(theta_bounds, dtype=float), (mean.size, 1))
    return np.vstack([xb, tb])


def maximin_select(cand: np.ndarray, Z: np.ndarray, bounds: np.ndarray, n: int, *,
                   min_dist: float = 0.0) -> np.ndarray:
    """Greedy maximin: ``n`` rows of ``cand``, each the farthest (unit-scaled box) from all
    points so far (``Z`` included); stops early when the farthest is nearer than
    ``min_dist``."""
    lo, span = bounds[:, 0], bounds[:, 1] - bounds[:, 0]
    cu, zu = (cand - lo) / span, (Z - lo) / span
    dmin = np.full(cand.shape[0], np.inf)
    for a in range(0, zu.shape[0], 256):
        d = np.sqrt(((cu[:, None, :] - zu[None, a:a + 256, :]) ** 2).sum(-1))
        dmin = np.minimum(dmin, d.min(axis=1))
    chosen: list[int] = []
    for _ in range(min(n, cand.shape[0])):
        i = int(np.argmax(dmin))
        if dmin[i] < min_dist:
            break
        chosen.append(i)
        dmin = np.minimum(dmin, np.sqrt(((cu - cu[i]) ** 2).sum(-1)))
        dmin[i] = -np.inf
    return cand[chosen]


__all__ = ["THETA_BOXES", "joint_bounds", "maximin_select"]
