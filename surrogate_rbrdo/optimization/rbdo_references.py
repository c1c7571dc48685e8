"""Independent references for the RBDO benchmarks of :mod:`~.rbdo_benchmarks`.

Nothing here uses the toolkit's estimators, formulations or optimisers (only the benchmarks'
limit-state callables), so the tests and ``benchmarks/bench_rbdo.py`` can judge those against
them:

* :func:`form_optimum_nested` — the FORM (RIA) optimum by two nested SciPy SLSQP problems: the
  design point of each chance constraint is ``min ‖u‖²`` subject to ``g(x, μ + L u) = 0``
  (normal inputs: the transformation is linear, no Nataf), from several starts; the outer
  problem minimises the cost subject to ``β_j(x) ≥ β_t``.
* :func:`exact_optimum` — the exact-probability optimum where the probabilities have an
  independent evaluation: Youn & Choi by 1-D quadratures (``youn_choi_pf``), the cantilever by
  its closed form.
* :func:`mc_recheck` — crude Monte Carlo of every chance constraint at one design with fresh
  samples, ``P_f / P_target``.

>>> from surrogate_rbrdo.optimization.rbdo_benchmarks import youn_choi
>>> x = form_optimum_nested(youn_choi(0.3, 3.0))
>>> np.round(x, 4).tolist()
[3.4391, 3.2866]
"""

from __future__ import annotations

import numpy as np
from scipy import optimize, special

from surrogate_rbrdo.optimization.rbdo_benchmarks import (
    RBDOBenchmark,
    cantilever_pf,
    youn_choi_pf,
)
from surrogate_rbrdo.uncertainty import MultivariateNormal

#: starting points (in units of the search distance) of the design-point searches
_STARTS = ((0.0, 0.0), (-1.0, 0.0), (1.0, 0.0), (0.0, -1.0), (0.0, 1.0))


def _normal(bench: RBDOBenchmark) -> tuple[np.ndarray, np.ndarray]:
    if not isinstance(bench.inputs, MultivariateNormal):
        raise ValueError(f"benchmark {bench.name!r}: the nested FORM reference needs normal "
                         "inputs (MultivariateNormal)")
    return np.asarray(bench.inputs.mean, dtype=float), np.linalg.cholesky(bench.inputs.cov)


def reliability_index(bench: RBDOBenchmark, x: np.ndarray, j: int,
                      warm: dict | None = None) -> float:
    """FORM ``β`` of chance constraint ``j`` at design ``x`` (sign: negative when the mean
    point fails), by SLSQP on ``min ‖u‖²`` s.t. ``g = 0`` from several starts (and from the
    last design point in ``warm``, which is updated)."""
    mean, chol = _normal(bench)
    c = bench.constraints[j]
    xr = np.asarray(x, dtype=float)[None, :]

    def g(u: np.ndarray) -> float:
        return float(c.limit.g(c.response(xr, (mean + chol @ u)[None, :]))[0, 0])

    m = mean.size
    every = []
    for s in _STARTS:
        u0 = np.zeros(m)
        u0[: min(2, m)] = 2.0 * np.asarray(s)[: min(2, m)]
        every.append(u0)
    best, u_best = np.inf, None
    # the last design point and the origin first; every start when neither converges
    for starts in ([warm[j], every[0]] if warm and j in warm else every, every[1:]):
        for u0 in starts:
            r = optimize.minimize(lambda u: u @ u, u0, jac=lambda u: 2 * u, method="SLSQP",
                                  constraints=[{"type": "eq", "fun": g}],
                                  options={"ftol": 1e-14, "maxiter": 500})
            if r.success and abs(g(r.x)) < 1e-8 and r.fun < best:
                best, u_best = float(r.fun), r.x
        if u_best is not None:
            break
    if warm is not None and u_best is not None:
        warm[j] = u_best
    return float(np.sign(g(np.zeros(m))) * np.sqrt(best))


def form_optimum_nested(bench: RBDOBenchmark, x0: np.ndarray | None = None) -> np.ndarray:
    """The FORM (RIA) optimum of ``bench``: min cost s.t. every ``β_j ≥ β_t`` (nested SLSQP;
    each design-point search starts from the last one found, after five starts at the first
    design)."""
    mean, _ = _normal(bench)
    x0 = 0.5 * (bench.lower + bench.upper) if x0 is None else np.asarray(x0, dtype=float)
    warm: dict = {}

    def cost(x: np.ndarray) -> float:
        return float(np.mean(bench.cost(x[None, :], mean[None, :])))

    cons = [{"type": "ineq", "fun": (lambda x, j=j: reliability_index(bench, x, j, warm)
                                     - bench.beta_target)}
            for j in range(len(bench.constraints))]
    res = optimize.minimize(cost, x0, method="SLSQP", constraints=cons,
                            bounds=list(zip(bench.lower, bench.upper, strict=True)),
                            options={"ftol": 1e-12, "maxiter": 200})
    return res.x


def exact_optimum(bench: RBDOBenchmark) -> np.ndarray | None:
    """The exact-probability optimum (Youn & Choi: quadrature; cantilever: closed form), or
    None where no independent evaluation of the probabilities exists here."""
    if bench.name.startswith("youn_choi"):
        sigma = float(np.sqrt(bench.inputs.cov[0, 0]))

        def pfs(d: np.ndarray) -> np.ndarray:
            return youn_choi_pf(d, sigma)[:2]     # G₃ is never active (β₃ > 4)
        cost, x0 = np.sum, np.array([3.5, 3.3])
    elif bench.name == "cantilever":
        def pfs(d: np.ndarray) -> np.ndarray:
            return cantilever_pf(d)
        cost, x0 = np.prod, np.array([3.0, 3.0])
    else:
        return None
    res = optimize.minimize(cost, x0, method="SLSQP", options={"ftol": 1e-12},
                            bounds=list(zip(bench.lower, bench.upper, strict=True)),
                            constraints=[{"type": "ineq", "fun": lambda d: -special.ndtri(
                                np.maximum(pfs(d), 1e-300)) - bench.beta_target}])
    return res.x


def mc_recheck(bench: RBDOBenchmark, x: np.ndarray, n: int = 1_000_000,
               seed: int = 99) -> np.ndarray:
    """Crude Monte Carlo of every chance constraint at design ``x`` with ``n`` fresh samples:
    ``P_f / P_target`` per constraint."""
    theta = bench.inputs.sample(n, rng=np.random.default_rng(seed))
    xr = np.asarray(x, dtype=float)[None, :]
    return np.array([np.mean(c.limit.failed(c.response(xr, theta)[0]))
                     for c in bench.constraints]) / bench.p_target


__all__ = ["exact_optimum", "form_optimum_nested", "mc_recheck", "reliability_index"]
