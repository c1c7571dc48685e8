"""Active learning of a limit state (AK-MCS, Echard et al. 2011) over a candidate pool.

Starting from a space-filling LHS over ``bounds`` (a handful of random points makes the first
models so poor that the U criterion can stop falsely), repeat:

1. fit the surrogate on the design so far;
2. predict the candidate pool (e.g. Monte Carlo points in the joint (x, θ) space);
3. ``U = |μ - threshold| / σ`` (how many standard deviations the prediction is from the limit
   state; large U means the sign of ``g`` is unlikely to be wrong);
   ``P_f = mean(failed(μ))`` over the pool;
4. stop (``stop="u"``) when ``min U ≥ u_stop`` (classically 2: each candidate misclassified with
   probability ≤ Φ(-2) ≈ 2.3 %), or (``stop="pf"``) when the relative change of ``P_f`` stayed
   below ``pf_rel_change`` for ``patience`` iterations, or ``"either"``/``"both"``; else add the
   ``batch_size`` candidates with the smallest U, evaluate them with the true model (counted),
   and go on (at most ``max_added`` points).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.core.counting import CallCounter
from surrogate_rbrdo.core.protocols import LimitState, Surrogate
from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import (
    check_choice,
    check_finite_array,
    check_int,
    check_positive,
)
from surrogate_rbrdo.doe import check_bounds, lhs
from surrogate_rbrdo.sampling import evaluate_points


@dataclass(frozen=True)
class AKMCSOptions:
    """Options of :func:`ak_mcs` (see the module docstring for the algorithm)."""

    n_initial: int = 20
    max_added: int = 100
    batch_size: int = 1
    u_stop: float = 2.0
    pf_rel_change: float = 0.01
    patience: int = 3
    stop: str = "u"
    n_jobs: int = 1
    predict_chunk: int = 20000

    def __post_init__(self) -> None:
        check_int("n_initial", self.n_initial, minimum=2)
        check_int("max_added", self.max_added, minimum=0)
        check_int("batch_size", self.batch_size, minimum=1)
        check_positive("u_stop", self.u_stop)
        check_positive("pf_rel_change", self.pf_rel_change)
        check_int("patience", self.patience, minimum=1)
        check_choice("stop", self.stop, ("u", "pf", "either", "both"))
        check_int("predict_chunk", self.predict_chunk, minimum=1)


@dataclass(frozen=True)
class AKMCSResult:
    """Outcome of :func:`ak_mcs`.

    Attributes
    ----------
    model : Surrogate
        The last fitted surrogate (on ``X``, ``y``).
    X, y : ndarray
        Final design (initial LHS + added points) and true values (non-finite points dropped).
    added : ndarray, shape (k, D)
        Points added by the learning, in order.
    n_calls : int
        True-model evaluations made by this call (initial design included).
    pf : float
        Final ``P_f`` estimate on the pool.
    converged : bool
        Whether the stopping rule fired (False: ``max_added`` reached).
    stop_reason : str
    history : list of dict
        Per iteration: ``n_points``, ``pf``, ``min_u``, ``n_uncertain`` (U < u_stop).
    """

    model: Surrogate
    X: np.ndarray
    y: np.ndarray
    added: np.ndarray
    n_calls: int
    pf: float
    converged: bool
    stop_reason: str
    history: list[dict[str, Any]] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return {"n_points": int(self.y.size), "added": self.added.tolist(),
                "n_calls": self.n_calls, "pf": self.pf, "converged": self.converged,
                "stop_reason": self.stop_reason, "history": self.history}


def _predict(model: Surrogate, pool: np.ndarray, chunk: int) -> tuple[np.ndarray, np.ndarray]:
    mu, sd = np.empty(pool.shape[0]), np.empty(pool.shape[0])
    for a in range(0, pool.shape[0], chunk):
        p = model.predict(pool[a:a + chunk])
        mu[a:a + chunk], sd[a:a + chunk] = p.mean, p.std
    return mu, sd


def ak_mcs(
    func: Callable[[np.ndarray], float],
    candidates: np.ndarray,
    bounds: object,
    limit: LimitState,
    surrogate_factory: Callable[[np.random.Generator], Surrogate],
    *,
    rng: np.random.Generator,
    options: AKMCSOptions | None = None,
    counter: CallCounter | None = None,
    cache: Any = None,
) -> AKMCSResult:
    """Enrich a space-filling design where the limit state ``y = threshold`` is uncertain.

    Parameters
    ----------
    func : callable
        True model, point-wise ``func(z) -> float`` on the joint input ``z`` (D,).
    candidates : ndarray, shape (n_pool, D)
        Candidate pool (typically Monte Carlo points of the joint (x, θ) input).
    bounds : array_like, shape (D, 2)
        Box of the initial LHS (should cover the pool).
    limit : LimitState
        Threshold and failure side.
    surrogate_factory : callable
        ``factory(rng) -> unfitted Surrogate`` (e.g. ``lambda r: KrgSE(opts, rng=r)``); called
        with a fresh child generator at every refit.
    rng : numpy.random.Generator
    options : AKMCSOptions, optional
    counter : CallCounter, optional
        Receives every true-model evaluation.
    cache : joblib.Memory, optional
        Passed to :func:`~surrogate_rbrdo.sampling.evaluate_points`.

    Examples
    --------
    >>> import numpy as np
    >>> from surrogate_rbrdo.surrogates import GPR, GPROptions
    >>> rng = np.random.default_rng(0)
    >>> pool = rng.normal(size=(2000, 2))
    >>> f = lambda z: float(z[0] + z[1])                  # fails above 2.5: Pf = Φ(-2.5/√2)
    >>> res = ak_mcs(f, pool, [[-4, 4], [-4, 4]], LimitState(2.5),
    ...              lambda r: GPR(GPROptions(n_restarts=0), rng=r), rng=rng,
    ...              options=AKMCSOptions(n_initial=8, max_added=20))
    >>> res.converged, res.pf == float(np.mean(pool.sum(1) > 2.5)), res.n_calls < 28
    (True, True, True)
    """
    rng = require_rng(rng)
    o = options if options is not None else AKMCSOptions()
    pool = check_finite_array("candidates", candidates, ndim=2)
    b = check_bounds(bounds)
    if b.shape[0] != pool.shape[1]:
        raise ValueError(
            f"bounds has {b.shape[0]} rows is not allowed: must match the {pool.shape[1]} "
            "columns of candidates"
        )
    counter = counter if counter is not None else CallCounter()
    start = counter.calls

    def run(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        r = evaluate_points(func, points, n_jobs=o.n_jobs, cache=cache, counter=counter,
                            on_nonfinite="exclude")
        return r.points_ok, r.y_ok

    X, y = run(lhs(o.n_initial, b, rng=rng))
    added: list[np.ndarray] = []
    history: list[dict[str, Any]] = []
    pf_hist: list[float] = []
    thr = limit.threshold
    used = np.zeros(pool.shape[0], dtype=bool)  # pool points already in the design
    reason = "max_added reached"
    converged = False
    while True:
        model = surrogate_factory(rng.spawn(1)[0]).fit(X, y)
        mu, sd = _predict(model, pool, o.predict_chunk)
        with np.errstate(divide="ignore"):
            U = np.where(sd > 0, np.abs(mu - thr) / sd, np.inf)
        U[used] = np.inf  # known exactly: never re-added (round-off can leave σ > 0 there)
        pf = float(np.mean(limit.failed(mu)))
        pf_hist.append(pf)
        history.append({"n_points": int(y.size), "pf": pf, "min_u": float(U.min()),
                        "n_uncertain": int(np.sum(U < o.u_stop))})
        u_ok = bool(U.min() >= o.u_stop)
        pf_ok = len(pf_hist) > o.patience and all(
            abs(pf_hist[-1 - k] - pf_hist[-2 - k]) <= o.pf_rel_change * max(pf_hist[-1], 1e-300)
            for k in range(o.patience))
        fired = {"u": u_ok, "pf": pf_ok, "either": u_ok or pf_ok, "both": u_ok and pf_ok}[o.stop]
        if fired:
            converged = True
            reason = f"min U = {U.min():.3g} >= {o.u_stop}" if u_ok else "P_f stable"
            if u_ok and pf_ok:
                reason += " and P_f stable"
            break
        n_added = sum(a.shape[0] for a in added)
        if n_added >= o.max_added:
            break
        k = min(o.batch_size, o.max_added - n_added)
        pick = np.argsort(U, kind="stable")[:k]
        used[pick] = True
        Xn, yn = run(pool[pick])
        added.append(pool[pick])
        X, y = np.vstack([X, Xn]), np.concatenate([y, yn])
    return AKMCSResult(
        model=model, X=X, y=y,
        added=np.vstack(added) if added else np.empty((0, pool.shape[1])),
        n_calls=counter.calls - start, pf=pf_hist[-1], converged=converged,
        stop_reason=reason, history=history,
    )
