"""Sequential Monte Carlo p-values of the residual lack-of-fit tests.

The three lack-of-fit statistics of a stage (``gof``, ``structure``, ``generic``) are referred
to the bootstrap's draws (:mod:`.calibration`). A p-value with fewer than 20 draws beyond the
statistic is extrapolated by a scaled χ² matched on the moments of all the draws
(:class:`~.calibration.TailModel`). For a sum of many terms (``gof``) that shape fits the far
tail. For a *maximum* of many one-parameter statistics (``generic``: the best of 64 local
changes on the rig) it does not: the maximum is narrow for its mean, so the matched scale is
below 1 and the fitted tail falls faster than the true one, which is that of its largest
χ²₁-like terms. Measured on the rig with a strong thermal preload known to the model (b 0.5,
default noise; a 20 000-draw bootstrap, 40 subsamples of 400): where the 400-draw model puts
0.0033 the bootstrap's own tail is 0.0059 (mean; 10–90 % 0.0031–0.0081), at 0.001 it is 0.0021.
The p of one statistic also moves a lot between bootstrap seeds (16.08: 0.0015 and 0.0037).

So a p-value in the extrapolated range that is not far below the test's level is refined by
more draws, in chunks of the residual statistics alone (the candidates' columns are not
needed), until the statistic has :data:`MIN_EXCEED` draws beyond it — Besag & Clifford's
sequential stopping rule (1991, *Biometrika* 78:301) — or :data:`MAX_DRAWS` draws are taken;
the p-value is then the Monte Carlo one, ``(1 + h) / (1 + n)`` (Davison & Hinkley 1997,
*Bootstrap Methods and their Application*, §4.2: under the null ``P(p ≤ α) ≤ α``). A p-value
extrapolated to at most :data:`FAR` (a hundredth) of the level is taken as it stands once at
least :data:`FAR_DRAWS` draws lie none of them beyond the statistic — the statistic of a real
misfit (p 1e-10) would otherwise cost :data:`MAX_DRAWS` draws every time. The moment fit's
error at that point is large (review s10, M3: for a maximum of 64 independent χ²₁ from 400
draws the exact tail there is 4.8e-4 in the median, 1.5e-3 at worst; of 256, 6.8e-4 and
3.0e-3), so the fit alone is not trusted: no draw beyond the statistic in 800 is itself
evidence against a p near the level (probability ``(1 − 0.0033)^800 ≈ 0.07``), and the fit is
then made on twice the draws. Nothing changes — no draw is taken — when every p-value is
settled by the first draws in the empirical range. The workflow
refines the last stage's p-values only (``selection.refined``): theirs give the verdict; an
earlier stage's serve its screen (``naming.QUIET_P``, far from the level) and are left as
they are.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from surrogate_rbrdo.discrepancy.calibration import (
    Linearisation,
    NullDistribution,
    TailModel,
    simulate_null,
)
from surrogate_rbrdo.discrepancy.problem import Problem

#: draws beyond the statistic at which its Monte Carlo p-value is taken as it stands (the
#: empirical range of :meth:`~.calibration.NullDistribution.p_value`)
MIN_EXCEED = 20
#: most draws of the residual statistics (a p of 0.0033 has about 13 draws beyond it)
MAX_DRAWS = 4000
#: draws added at a time
CHUNK = 400
#: a p-value extrapolated to at most this fraction of the level is not refined further ...
FAR = 0.01
#: ... once at least this many draws are taken, none of them beyond the statistic
FAR_DRAWS = 2 * CHUNK


def settled_p(draws: np.ndarray, value: float, level: float) -> float | None:
    """The p-value of ``value`` against ``draws`` if more draws would not change the decision
    at ``level`` (see module doc), else ``None``.

    >>> d = np.arange(1.0, 401.0)
    >>> settled_p(d, 380.5, 0.0033)      # 20 draws beyond: empirical
    0.05236907730673317
    >>> settled_p(d, 395.5, 0.0033) is None
    True
    >>> settled_p(d, 1e4, 0.0033) is None      # far beyond, but only 400 draws: one chunk more
    True
    """
    h = int(np.sum(draws >= value))
    if h >= MIN_EXCEED:
        return float((1 + h) / (1 + draws.size))
    if h > 0 or draws.size < FAR_DRAWS:
        return None
    p = float(TailModel.from_draws(draws).sf(value))
    return p if p <= FAR * level else None


def sequential_p_values(draws: dict[str, np.ndarray], observed: dict[str, float],
                        level: float, more, *, max_draws: int = MAX_DRAWS
                        ) -> dict[str, float]:
    """Besag–Clifford p-values of the statistics ``observed`` against their ``draws``
    (arrays of one length, drawn together): while one is not settled (:func:`settled_p`) and
    fewer than ``max_draws`` are taken, ``more(n)`` adds ``n`` joint draws (a dict of arrays);
    an unsettled p-value is then the Monte Carlo one, ``(1 + h) / (1 + n)``."""
    pool = {k: np.asarray(draws[k], dtype=float) for k in observed}
    n = min(v.size for v in pool.values())
    open_ = [k for k, v in observed.items() if settled_p(pool[k], v, level) is None]
    while open_ and n < max_draws:
        extra = more(min(CHUNK, max_draws - n))
        pool = {k: np.concatenate([v, np.asarray(extra[k], dtype=float)])
                for k, v in pool.items()}
        n = min(v.size for v in pool.values())
        open_ = [k for k in open_ if settled_p(pool[k], observed[k], level) is None]
    out = {}
    for k, v in observed.items():
        p = settled_p(pool[k], v, level)
        out[k] = p if p is not None else float((1 + np.sum(pool[k] >= v)) / (1 + pool[k].size))
    return out


def residual_p_values(problem: Problem, lin: Linearisation, null: NullDistribution,
                      observed: dict[str, float], *, level: float,
                      rng: np.random.Generator, max_draws: int = MAX_DRAWS
                      ) -> dict[str, float]:
    """p-values of the residual statistics ``observed`` (``{"gof": …, "structure": …,
    "generic": …}``): :meth:`~.calibration.NullDistribution.p_value` where the bootstrap's
    draws settle them all, else :func:`sequential_p_values` with further draws of the residual
    statistics alone at the same linearisation and noise model (module doc)."""
    out = {k: null.p_value(k, v) for k, v in observed.items()}
    if all(settled_p(getattr(null, k), v, level) is not None for k, v in observed.items()):
        return out
    resid = replace(lin, candidates=())

    def more(n: int) -> dict[str, np.ndarray]:
        d = simulate_null(problem, resid, n_draws=n, rng=rng)
        return {k: getattr(d, k) for k in observed}

    return sequential_p_values({k: getattr(null, k) for k in observed}, observed, level, more,
                               max_draws=max_draws)
