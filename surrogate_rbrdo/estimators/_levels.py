"""What the multi-level estimators (``ais``, ``subset``) share: the stall test of their
intermediate thresholds and the loop over designs.

Kept apart from ``_common`` because it needs :func:`~.mc.mc_with_outside` (``mc`` imports
``_common``).

>>> guard = StallGuard()
>>> [guard(g, k, np.array([0.0, 8.0])) for k, g in enumerate([4.0, 2.0, 2.0, 2.0, 2.0], start=1)]
[False, False, False, False, True]
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.protocols import LimitState
from surrogate_rbrdo.estimators._common import LimitStateU, check_args, nan_p, normal_ci
from surrogate_rbrdo.estimators.mc import mc_with_outside


class StallGuard:
    """True once the thresholds γ_k stopped decreasing (by ``rel`` × the spread of ``G`` in
    the first level) ``n`` times in a row: no failure in reach.

    The spread (standard deviation of the level-1 values), not ``|γ_1|``: a response far from
    its threshold (``G`` ≈ 300 ± 0.2 µm) decreases by a fraction of a spread per level, a
    vanishing fraction of ``|γ_1|``; a bounded one stops decreasing at all.
    """

    def __init__(self, n: int = 3, rel: float = 1e-3) -> None:
        self.n, self.rel = n, rel
        self.prev, self.stalled, self.scale = np.inf, 0, 1.0

    def __call__(self, gamma: float, level: int, g: np.ndarray | None = None) -> bool:
        if level == 1:
            finite = g[np.isfinite(g)] if g is not None else np.empty(0)
            spread = float(finite.std()) if finite.size > 1 else 0.0
            self.scale = spread if spread > 0 else abs(gamma)
        self.stalled = self.stalled + 1 if self.prev - gamma < self.rel * self.scale else 0
        self.prev = min(self.prev, gamma)
        return self.stalled >= self.n


class PerDesign(NamedTuple):
    """Per-design results of :func:`run_per_design` (arrays of length P)."""

    pf: np.ndarray
    se: np.ndarray
    extra: np.ndarray       # (P, k): the estimator's own per-design diagnostics
    levels: np.ndarray
    status: np.ndarray      # "converged", "not_reached" (pf is an upper bound) or "failed"
    calls: int
    n_outside: np.ndarray
    moments: Any   # mc_with_outside of the level-1 responses (μ_y, σ_y and their SEs)


class LevelResult(NamedTuple):
    """What a multi-level estimator's ``_one`` returns for one design.

    ``reached``: the failure domain was reached. If not, ``pf`` and ``se`` estimate
    ``P(G ≤ γ_last)`` for the last intermediate threshold ``γ_last > 0``, an upper bound of
    ``P_f`` (the failure domain ``{G < 0}`` lies inside ``{G ≤ γ_last}``).
    """

    pf: float
    se: float
    extra: Any              # a float or a 1-D array: the estimator's own diagnostics
    level: int
    reached: bool
    y0: np.ndarray


ON_FAILURE = ("bound", "raise", "nan")


def run_per_design(est: Any, response: Any, inputs: Any, limit: LimitState, x: np.ndarray,
                   rng: np.random.Generator, u: np.ndarray | None, *, what: str, why: str,
                   advice: str) -> PerDesign:
    """Check the arguments, run ``est._one(G, m, u, rng_i) -> LevelResult`` for every design.

    Common random numbers: one seed is drawn from ``rng`` once per call and every design runs
    with its own generator ``default_rng(seed)`` started from that same seed, so every design
    sees the same chain randomness and a design's ``P_f`` does not depend on its position in
    ``x`` or on the other rows (with a shared generator, design i's levels would continue the
    stream left by designs 0…i−1).

    A design whose failure domain is not reached within ``max_levels`` (or whose thresholds
    stopped decreasing) follows ``est.on_failure``: ``"bound"`` reports the upper bound
    ``P(G ≤ γ_last)`` with ``status = "not_reached"``; ``"nan"`` gives NaN (``"failed"``);
    ``"raise"`` raises :class:`ModelError`:
    ``"{what} did not reach the failure domain for design i after k levels
    (max_levels=…; {why}); {advice}"``.
    """
    x, u = check_args(inputs, limit, x, rng, u)
    p, m = x.shape[0], inputs.dim
    pf, se, levels = nan_p(p), nan_p(p), np.zeros(p, int)
    extra = []
    status = np.full(p, "converged", dtype=object)
    nout = np.zeros(p, int)
    y0s, calls = [], 0
    seed = np.random.SeedSequence(rng.integers(0, 2**63, size=4))
    for i in range(p):
        G = LimitStateU(response, inputs, limit, x[i])
        r = est._one(G, m, u, np.random.default_rng(seed))
        calls += G.calls
        nout[i] = G.n_outside
        y0s.append(r.y0)
        pf[i], se[i], levels[i] = r.pf, r.se, r.level
        extra.append(np.atleast_1d(np.asarray(r.extra, dtype=float)))
        if r.reached:
            continue
        if est.on_failure == "raise":
            raise ModelError(
                f"{what} did not reach the failure domain for design {i} after {r.level} "
                f"levels (max_levels={est.max_levels}; {why}); {advice}")
        status[i] = "not_reached" if est.on_failure == "bound" else "failed"
        if est.on_failure == "nan":
            pf[i] = se[i] = np.nan
            extra[-1] = np.full_like(extra[-1], np.nan)
    return PerDesign(pf, se, np.vstack(extra), levels, status.astype(str), calls, nout,
                     mc_with_outside(np.vstack(y0s), limit))


def interval(pf: np.ndarray, se: np.ndarray, status: np.ndarray, level: float) -> np.ndarray:
    """``pf_ci``: ``pf ± z·se`` clipped to ``[0, 1]``; ``[0, pf + z·se]`` where ``pf`` is an upper
    bound (``status == "not_reached"``)."""
    ci = normal_ci(pf, se, level)
    nr = status == "not_reached"
    ci[nr, 0] = 0.0
    return ci


__all__ = ["LevelResult", "ON_FAILURE", "PerDesign", "StallGuard", "interval", "run_per_design"]
