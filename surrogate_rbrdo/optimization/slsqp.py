"""Gradient-based single-objective RBDO: SLSQP on a formulation, with batched finite differences.

``run_slsqp(formulation, lower, upper, *, rng, options=SLSQPOptions())`` minimises the single
objective of a formulation (``rbdo``, ``deterministic``) subject to all its constraint columns
with :func:`scipy.optimize.minimize` (``method="SLSQP"``, Kraft 1988) in the box, in variables
scaled to ``[0, 1]``. Objective and constraint gradients come from one batched
``formulation.evaluate`` call of the ``d + 1`` (forward) or ``2d + 1`` (central) points around
the iterate, so a vectorised surrogate or the common-random-number sample is evaluated once per
gradient, and every evaluated design is recorded in the archive like NSGA-II's.

SLSQP needs constraints that are smooth in ``x``. The sample-average ``P̂_f`` of crude MC is a
staircase; write the reliability constraint as the common-sample quantile
(``reliability_measure = "quantile"``: the same feasible set, continuous in ``x``) or use FORM
with ``reliability_measure = "beta"`` (the reliability-index approach, whose optimum is the
FORM optimum published for most RBDO benchmarks). Say which probability is constrained when
comparing with a published optimum (``docs/optimization.md``).

Starts: the box centre (or ``options.x0``), then ``n_starts − 1`` points of a Latin hypercube
drawn from ``rng``; the best feasible end point wins (least violation if none is feasible).

>>> import numpy as np
>>> from surrogate_rbrdo.formulations import (DeterministicOptions, DesignConstraint,
...                                          FormulationOptions, make_formulation)
>>> from surrogate_rbrdo.uncertainty import MultivariateNormal
>>> hyperbola = DesignConstraint.from_expression("area", "x0 * x1 >= 1", ("x0", "x1"))
>>> form = make_formulation(
...     "deterministic", response=lambda x, t: x.sum(axis=1, keepdims=True) + 0 * t.T,
...     inputs=MultivariateNormal([0.0], std=[1.0]), limit=None, constraints=(hyperbola,),
...     options=FormulationOptions(n_theta=1, deterministic=DeterministicOptions(
...         stress=False, resonance="none")), rng=np.random.default_rng(0))
>>> res = run_slsqp(form, [0.1, 0.1], [4.0, 4.0], rng=np.random.default_rng(1))
>>> np.round(res.X[0], 5).tolist(), round(float(res.F[0, 0]), 6)    # min x0 + x1, x0 x1 >= 1
([1.0, 1.0], 2.0)
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass

import numpy as np
from scipy.optimize import minimize
from scipy.stats import qmc

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive
from surrogate_rbrdo.optimization.evaluator import RecordingEvaluator
from surrogate_rbrdo.optimization.nsga2 import OPTIMIZERS, check_bounds
from surrogate_rbrdo.optimization.pareto import total_violation
from surrogate_rbrdo.optimization.result import OptimizationResult


@dataclass(frozen=True)
class SLSQPOptions:
    """Settings of :func:`run_slsqp`.

    >>> SLSQPOptions(fd_scheme="backward")
    Traceback (most recent call last):
    ...
    ValueError: fd_scheme = 'backward' is not allowed: must be one of ['forward', 'central']
    """

    n_starts: int = 1
    maxiter: int = 100
    ftol: float = 1e-8
    fd_step: float = 1e-5
    fd_scheme: str = "central"
    feasibility_tol: float = 1e-6
    x0: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        check_int("n_starts", self.n_starts, minimum=1)
        check_int("maxiter", self.maxiter, minimum=1)
        check_positive("ftol", self.ftol)
        check_positive("fd_step", self.fd_step)
        check_choice("fd_scheme", self.fd_scheme, ("forward", "central"))
        check_positive("feasibility_tol", self.feasibility_tol)
        if self.x0 is not None:
            object.__setattr__(self, "x0", tuple(float(v) for v in self.x0))


class _Cached:
    """Objective, constraints and their finite-difference gradients at the last iterate, from
    one batched evaluation (SLSQP asks for them separately at the same point)."""

    def __init__(self, evaluator: RecordingEvaluator, lo: np.ndarray, span: np.ndarray,
                 options: SLSQPOptions) -> None:
        self.ev, self.lo, self.span, self.o = evaluator, lo, span, options
        self.key: bytes | None = None

    def at(self, z: np.ndarray) -> _Cached:
        z = np.clip(np.asarray(z, dtype=float), 0.0, 1.0)
        if z.tobytes() == self.key:
            return self
        d, h = z.size, self.o.fd_step
        eye = np.eye(d)
        # forward steps inside the unit box (backward where the upper bound is closer than h);
        # central differences where both sides fit, one-sided at a bound
        up = np.where(z + h <= 1.0, h, -h)
        both = (self.o.fd_scheme == "central") & (z + h <= 1.0) & (z - h >= 0.0)
        idx = np.flatnonzero(both)
        pts = np.array([z] + [z + up[i] * eye[i] for i in range(d)]
                       + [z - h * eye[i] for i in idx])
        F, G = self._evaluate(pts)
        f, g = F[:, 0], -G          # scipy: inequality constraints are c(z) >= 0
        plus_f, plus_g = f[1:d + 1], g[1:d + 1]
        minus_f, minus_g = np.full(d, np.nan), np.full((d, g.shape[1]), np.nan)
        minus_f[idx], minus_g[idx] = f[d + 1:], g[d + 1:]
        df, dg = _differences(f[0], g[0], plus_f, plus_g, minus_f, minus_g, up, h, z)
        self.df, self.dg = df, dg.T
        self.f, self.g, self.key = float(f[0]), g[0], z.tobytes()
        return self

    def _evaluate(self, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One batched evaluation; when the model fails somewhere in the batch, each point
        alone (a failed difference point is NaN, the iterate itself must succeed)."""
        x = self.lo + self.span * pts
        try:
            return self.ev(x)
        except ModelError:
            pass
        F0, G0 = self.ev(x[:1])           # the iterate: its failure is the caller's error
        F = np.full((len(x), F0.shape[1]), np.nan)
        G = np.full((len(x), G0.shape[1]), np.nan)
        F[0], G[0] = F0[0], G0[0]
        for k in range(1, len(x)):
            try:
                F[k], G[k] = (a[0] for a in self.ev(x[k:k + 1]))
            except ModelError:
                continue
        return F, G


def _differences(f0: float, g0: np.ndarray, plus_f: np.ndarray, plus_g: np.ndarray,
                 minus_f: np.ndarray, minus_g: np.ndarray, up: np.ndarray, h: float,
                 z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Finite differences per variable: central where both sides were evaluated, one-sided
    where the model failed on one side (NaN), ``ModelError`` where it failed on both.

    >>> df, dg = _differences(1.0, np.zeros(1), np.array([1.1, np.nan]), np.zeros((2, 1)),
    ...                       np.array([0.9, 0.8]), np.zeros((2, 1)), np.full(2, 0.1), 0.1,
    ...                       np.zeros(2))
    >>> np.round(df, 6).tolist()
    [1.0, 2.0]
    """
    fwd_f, fwd_g = (plus_f - f0) / up, (plus_g - g0) / up[:, None]
    bwd_f, bwd_g = (f0 - minus_f) / h, (g0 - minus_g) / h
    ctr_f = (plus_f - minus_f) / (up + h)
    ctr_g = (plus_g - minus_g) / (up + h)[:, None]
    has_p, has_m = np.isfinite(plus_f), np.isfinite(minus_f)
    if np.any(~has_p & ~has_m):
        i = int(np.flatnonzero(~has_p & ~has_m)[0])
        raise ModelError(f"SLSQP: the model failed on both sides of variable {i} at the "
                         f"scaled point z = {z.tolist()}: no finite-difference gradient")
    df = np.where(has_p & has_m, ctr_f, np.where(has_p, fwd_f, bwd_f))
    dg = np.where((has_p & has_m)[:, None], ctr_g, np.where(has_p[:, None], fwd_g, bwd_g))
    return df, dg


def _starts(lo, hi, options: SLSQPOptions, rng: np.random.Generator) -> np.ndarray:
    first = (0.5 * np.ones(lo.size) if options.x0 is None
             else (np.asarray(options.x0) - lo) / (hi - lo))
    if options.x0 is not None and (first.size != lo.size or np.any((first < 0) | (first > 1))):
        raise ValueError(f"x0 = {list(options.x0)} is not allowed: must lie in the box "
                         f"[{lo.tolist()}, {hi.tolist()}]")
    if options.n_starts == 1:
        return first[None, :]
    more = qmc.LatinHypercube(d=lo.size, seed=rng).random(options.n_starts - 1)
    return np.vstack([first, more])


def _one_start(cache: _Cached, z0: np.ndarray, scale: float, n_con: int, lo: np.ndarray,
               span: np.ndarray, options: SLSQPOptions) -> dict:
    """One SLSQP run from ``z0`` (unit box); its end point and SciPy's verdict."""
    cons = [{"type": "ineq", "fun": lambda z: cache.at(z).g,
             "jac": lambda z: cache.at(z).dg}] if n_con else []
    res = minimize(lambda z: cache.at(z).f / scale, z0, jac=lambda z: cache.at(z).df / scale,
                   method="SLSQP", bounds=[(0.0, 1.0)] * z0.size, constraints=cons,
                   options={"maxiter": options.maxiter, "ftol": options.ftol})
    end = cache.at(res.x)
    return {"x": (lo + span * np.clip(res.x, 0, 1)).tolist(), "f": end.f,
            "violation": float(total_violation(-end.g[None, :])[0]),
            "success": bool(res.success), "message": str(res.message), "nit": int(res.nit)}


@OPTIMIZERS.register("slsqp")
def run_slsqp(formulation, lower, upper, *, rng: np.random.Generator,
              options: SLSQPOptions | None = None, progress: bool = False
              ) -> OptimizationResult:
    """Minimise a single-objective formulation with SLSQP from one or more starts.

    Parameters
    ----------
    formulation : Formulation
        ``evaluate(x) -> Evaluation`` with ``n_obj == 1``; its constraint columns should be
        smooth in ``x`` (see the module docstring).
    lower, upper : array_like, shape (d,)
        Design bounds.
    rng : numpy.random.Generator
        Draws the Latin-hypercube starts after the first (``n_starts > 1``).
    options : SLSQPOptions
    progress : bool
        Show a tqdm bar (one tick per evaluated batch).

    Returns
    -------
    OptimizationResult
        ``X, F, G``: the best end point (one row); ``archive``: every evaluated design (the
        finite-difference points included); ``optimizer``: options, and per start its end
        point, objective, violation, SciPy's ``success``/``message`` and iteration count.
    """
    options = SLSQPOptions() if options is None else options
    if not isinstance(options, SLSQPOptions):
        raise ValueError(f"options = {options!r} is not allowed: must be SLSQPOptions")
    if formulation.n_obj != 1:
        raise ValueError(f"formulation {formulation.name!r} has {formulation.n_obj} objectives:"
                         " SLSQP minimises one (use rbdo or deterministic, or NSGA-II)")
    lo, hi = check_bounds(lower, upper)
    rng = require_rng(rng)
    span = hi - lo
    evaluator = RecordingEvaluator(formulation, progress=progress, total=None,
                                   desc=f"SLSQP {formulation.name}")
    cache = _Cached(evaluator, lo, span, options)
    t0 = time.perf_counter()
    runs = []
    try:
        starts = _starts(lo, hi, options, rng)
        scale = max(abs(cache.at(starts[0]).f), 1e-12)   # objective scaled to O(1)
        for z0 in starts:
            runs.append(_one_start(cache, z0, scale, formulation.n_con, lo, span, options))
    finally:
        evaluator.close_progress()
    archive = evaluator.freeze()
    wall = time.perf_counter() - t0
    feas = [r for r in runs if r["violation"] <= options.feasibility_tol]
    best = min(feas, key=lambda r: r["f"]) if feas else min(runs, key=lambda r: r["violation"])
    X = np.array([best["x"]])
    ev = formulation.evaluate(X)
    return evaluator.result(archive, X, ev.F, ev.G, wall,
                            {"name": "slsqp", **asdict(options), "starts": runs})


#: read by the study's options: SLSQP minimises a single objective only
run_slsqp.single_objective = True
