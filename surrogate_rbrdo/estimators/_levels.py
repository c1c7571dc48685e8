"""What the multi-level estimators (``ais``, ``subset``) share: the stall test of their
intermediate thresholds and the loop over designs.

Kept apart from ``_common`` because it needs :func:`~.mc.mc_from_values` (``mc`` imports
``_common``).

>>> guard = StallGuard()
>>> [guard(g, k) for k, g in enumerate([4.0, 2.0, 2.0, 2.0, 2.0], start=1)]
[False, False, False, False, True]
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.protocols import LimitState
from surrogate_rbrdo.estimators._common import LimitStateU, check_args, nan_p
from surrogate_rbrdo.estimators.mc import mc_from_values


class StallGuard:
    """True once the thresholds γ_k stopped decreasing (by ``rel`` × |γ_1|) ``n`` times in a
    row: no failure in reach."""

    def __init__(self, n: int = 3, rel: float = 1e-3) -> None:
        self.n, self.rel = n, rel
        self.prev, self.stalled, self.scale = np.inf, 0, 1.0

    def __call__(self, gamma: float, level: int) -> bool:
        if level == 1:
            self.scale = abs(gamma)
        self.stalled = self.stalled + 1 if self.prev - gamma < self.rel * self.scale else 0
        self.prev = min(self.prev, gamma)
        return self.stalled >= self.n


class PerDesign(NamedTuple):
    """Per-design results of :func:`run_per_design` (arrays of length P)."""

    pf: np.ndarray
    se: np.ndarray
    extra: np.ndarray
    levels: np.ndarray
    converged: np.ndarray
    calls: int
    moments: Any   # mc_from_values of the level-1 responses (μ_y, σ_y and their SEs)


def run_per_design(est: Any, response: Any, inputs: Any, limit: LimitState, x: np.ndarray,
                   rng: np.random.Generator, u: np.ndarray | None, *, what: str, why: str,
                   advice: str) -> PerDesign:
    """Check the arguments, run ``est._one(G, m, u, rng)`` for every design and collect.

    ``_one`` returns ``(pf, se, extra, level, converged, y_level1)``. A design that does not
    converge raises :class:`ModelError` when ``est.on_failure == "raise"``:
    ``"{what} did not reach the failure domain for design i after k levels
    (max_levels=…; {why}); {advice}"``.
    """
    x, u = check_args(inputs, limit, x, rng, u)
    p, m = x.shape[0], inputs.dim
    pf, se, extra, levels = nan_p(p), nan_p(p), nan_p(p), np.zeros(p, int)
    conv = np.zeros(p, bool)
    y0s, calls = [], 0
    for i in range(p):
        G = LimitStateU(response, inputs, limit, x[i])
        pf[i], se[i], extra[i], levels[i], conv[i], y0 = est._one(G, m, u, rng)
        calls += G.calls
        y0s.append(y0)
        if not conv[i] and est.on_failure == "raise":
            raise ModelError(
                f"{what} did not reach the failure domain for design {i} after {levels[i]} "
                f"levels (max_levels={est.max_levels}; {why}); {advice}")
    return PerDesign(pf, se, extra, levels, conv, calls, mc_from_values(np.vstack(y0s), limit))


__all__ = ["PerDesign", "StallGuard", "run_per_design"]
