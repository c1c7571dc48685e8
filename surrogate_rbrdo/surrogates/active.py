"""Active learning of a limit state (AK-MCS, Echard et al. 2011) over a candidate pool.

The one AK-MCS of the toolkit (the global surrogate structure's ``active_learning`` calls it
with a grid pool). Starting from a space-filling LHS over ``bounds`` (or given initial
points; a handful of random points makes the first models so poor that the U criterion can
stop falsely), repeat:

1. fit the surrogate on the design so far;
2. predict the candidate pool: a flat array of joint points, or a :class:`GridPool` (every
   design × every θ row, predicted at once by the separable predictor);
3. ``U = |μ - threshold| / σ`` (how many standard deviations the prediction is from the limit
   state; large U means the sign of ``g`` is unlikely to be wrong);
   ``P_f = mean(failed(μ))`` over the pool;
4. stop (``stop="u"``) when the fraction of the pool with ``U < u_stop`` is at most
   ``uncertain_frac`` (0, the default: ``min U ≥ u_stop``; classically ``u_stop = 2``, each
   candidate misclassified with probability ≤ Φ(-2) ≈ 2.3 %), or (``stop="pf"``) when the
   relative change of ``P_f`` stayed below ``pf_rel_change`` for ``patience`` iterations, or
   ``"either"``/``"both"``; else add the ``batch_size`` candidates with the smallest U (from
   a grid pool at most one per design, for diversity), evaluate them with the true model
   (counted) and go on (at most ``max_added`` points).

The surrogate may be fitted to a transform ``t(y)`` (e.g. ``log y``): pass the limit state in
that space (``LimitState(log δ)``); U and ``P_f`` are computed where the model lives.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from surrogate_rbrdo.core.counting import CallCounter
from surrogate_rbrdo.core.protocols import LimitState, Prediction, Surrogate
from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import (
    check_choice,
    check_finite_array,
    check_int,
    check_positive,
    check_range,
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
    uncertain_frac: float = 0.0
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
        check_range("uncertain_frac", self.uncertain_frac, 0.0, 1.0)
        check_positive("pf_rel_change", self.pf_rel_change)
        check_int("patience", self.patience, minimum=1)
        check_choice("stop", self.stop, ("u", "pf", "either", "both"))
        check_int("n_jobs", self.n_jobs, minimum=1)
        check_int("predict_chunk", self.predict_chunk, minimum=1)


@dataclass(frozen=True)
class GridPool:
    """Candidates on a grid: every row of ``designs`` (P, d) with every row of ``theta``
    (N, m). The fitted model must have ``predict_grid(designs, theta) -> Prediction``
    ``(P, N)`` (e.g. :meth:`TransformedKriging.predict_transformed`)."""

    designs: np.ndarray
    theta: np.ndarray

    @property
    def shape(self) -> tuple[int, int]:
        return (self.designs.shape[0], self.theta.shape[0])

    def points(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Joint points ``[x, θ]`` of grid cells ``(rows, cols)``."""
        return np.column_stack([self.designs[rows], self.theta[cols]])


@dataclass(frozen=True)
class AKMCSResult:
    """Outcome of :func:`ak_mcs`.

    Attributes
    ----------
    model : Surrogate
        The last fitted surrogate (on ``X``, ``y``).
    X, y : ndarray
        Final design (initial points + added points) and true values (points the true model
        did not give a valid value at are dropped).
    added : ndarray, shape (k, D)
        Points added by the learning, in order.
    n_calls : int
        True-model evaluations counted during this call (initial design included unless
        given).
    pf : float
        Final ``P_f`` estimate on the pool.
    converged : bool
        Whether the stopping rule fired (False: ``max_added`` reached or pool exhausted).
    stop_reason : str
    history : list of dict
        Per iteration: ``n_points``, ``pf``, ``min_u``, ``n_uncertain`` (U < u_stop) and
        ``uncertain_frac``.
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


def _predict(model: Any, pool: np.ndarray | GridPool, chunk: int) -> Prediction:
    if isinstance(pool, GridPool):
        return model.predict_grid(pool.designs, pool.theta)
    mu, sd = np.empty(pool.shape[0]), np.empty(pool.shape[0])
    for a in range(0, pool.shape[0], chunk):
        p = model.predict(pool[a:a + chunk])
        mu[a:a + chunk], sd[a:a + chunk] = p.mean, p.std
    return Prediction(mean=mu, std=sd)


def _pick(U: np.ndarray, k: int, pool: np.ndarray | GridPool) -> tuple[Any, np.ndarray]:
    """Indices into the pool (a flat index array or ``(rows, cols)``) and their points."""
    if not isinstance(pool, GridPool):
        pick = np.argsort(U, kind="stable")[:k]
        return pick, pool[pick]
    best_t = np.argmin(U, axis=1)                  # best θ per pool design
    best_u = U[np.arange(U.shape[0]), best_t]
    rows = np.argsort(best_u, kind="stable")[:k]
    rows = rows[np.isfinite(best_u[rows])]
    return (rows, best_t[rows]), pool.points(rows, best_t[rows])


def _stop(U: np.ndarray, pf_hist: list[float], o: AKMCSOptions) -> str | None:
    """The reason the stopping rule fired, or None."""
    frac = float(np.mean(U < o.u_stop))
    u_ok = frac <= o.uncertain_frac
    pf_ok = len(pf_hist) > o.patience and all(
        abs(pf_hist[-1 - k] - pf_hist[-2 - k]) <= o.pf_rel_change * max(pf_hist[-1], 1e-300)
        for k in range(o.patience))
    if not {"u": u_ok, "pf": pf_ok, "either": u_ok or pf_ok, "both": u_ok and pf_ok}[o.stop]:
        return None
    if not u_ok:
        return "P_f stable"
    reason = (f"min U = {U.min():.3g} >= {o.u_stop}" if o.uncertain_frac == 0 else
              f"uncertain fraction {frac:.4f} <= {o.uncertain_frac}")
    return reason + (" and P_f stable" if pf_ok else "")


def ak_mcs(
    func: Callable[[np.ndarray], float],
    candidates: np.ndarray | GridPool,
    bounds: object,
    limit: LimitState,
    surrogate_factory: Callable[[np.random.Generator], Any],
    *,
    rng: np.random.Generator,
    options: AKMCSOptions | None = None,
    counter: CallCounter | None = None,
    cache: Any = None,
    initial: tuple[np.ndarray, np.ndarray] | None = None,
    evaluate: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]] | None = None,
    progress: bool = False,
) -> AKMCSResult:
    """Enrich a space-filling design where the limit state ``y = threshold`` is uncertain.

    Parameters
    ----------
    func : callable
        True model, point-wise ``func(z) -> float`` on the joint input ``z`` (D,).
    candidates : ndarray, shape (n_pool, D), or GridPool
        Candidate pool (typically Monte Carlo points of the joint (x, θ) input).
    bounds : array_like, shape (D, 2)
        Box of the initial LHS (should cover the pool).
    limit : LimitState
        Threshold and failure side, in the space the surrogate predicts.
    surrogate_factory : callable
        ``factory(rng) -> unfitted Surrogate`` (e.g. ``lambda r: KrgSE(opts, rng=r)``); called
        with a fresh child generator at every refit; ``.fit(X, y)`` returns the fitted model.
    rng : numpy.random.Generator
        Draws the initial LHS (unless ``initial`` is given); every refit gets ``rng.spawn``.
    options : AKMCSOptions, optional
    counter : CallCounter, optional
        Receives every true-model evaluation.
    cache : joblib.Memory, optional
        Passed to :func:`~surrogate_rbrdo.sampling.evaluate_points`.
    initial : (X, y), optional
        Already evaluated initial points (then ``n_initial`` is not used).
    evaluate : callable, optional
        ``points -> (points_kept, y_kept)``; default ``func`` through ``evaluate_points``
        (non-finite values dropped).
    progress : bool
        A progress bar over the added points.

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
    grid = isinstance(candidates, GridPool)
    width = (candidates.designs.shape[1] + candidates.theta.shape[1] if grid
             else check_finite_array("candidates", candidates, ndim=2).shape[1])
    b = check_bounds(bounds)
    if b.shape[0] != width:
        raise ValueError(f"bounds has {b.shape[0]} rows is not allowed: must match the {width} "
                         "columns of candidates")
    counter = counter if counter is not None else CallCounter()
    start = counter.calls

    def run(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if evaluate is not None:
            return evaluate(points)
        r = evaluate_points(func, points, n_jobs=o.n_jobs, cache=cache, counter=counter,
                            on_nonfinite="exclude")
        return r.points_ok, r.y_ok

    X, y = initial if initial is not None else run(lhs(o.n_initial, b, rng=rng))
    pool = candidates if grid else np.asarray(candidates, dtype=float)
    bar = tqdm(total=o.max_added, desc="active learning", unit="pt") if progress else None
    try:
        return _learn(X, y, pool, limit, surrogate_factory, run, o, rng=rng, bar=bar,
                      n_calls=lambda: counter.calls - start, width=width)
    finally:
        if bar is not None:
            bar.close()


def _learn(X: np.ndarray, y: np.ndarray, pool: np.ndarray | GridPool, limit: LimitState,
           surrogate_factory: Callable[[np.random.Generator], Any],
           run: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]], o: AKMCSOptions, *,
           rng: np.random.Generator, bar: Any, n_calls: Callable[[], int], width: int
           ) -> AKMCSResult:
    """The AK-MCS loop (module docstring) from the evaluated points ``X``, ``y``."""
    used = np.zeros(pool.shape if isinstance(pool, GridPool) else pool.shape[0], dtype=bool)
    added: list[np.ndarray] = []
    history: list[dict[str, Any]] = []
    pf_hist: list[float] = []
    reason, converged = "max_added reached", False
    while True:
        model = surrogate_factory(rng.spawn(1)[0]).fit(X, y)
        p = _predict(model, pool, o.predict_chunk)
        with np.errstate(divide="ignore", invalid="ignore"):
            U = np.where(p.std > 0, np.abs(p.mean - limit.threshold) / p.std, np.inf)
        U[used] = np.inf  # known exactly: never re-added (round-off can leave σ > 0)
        pf_hist.append(float(np.mean(limit.failed(p.mean))))
        history.append({"n_points": int(y.size), "pf": pf_hist[-1], "min_u": float(U.min()),
                        "n_uncertain": int(np.sum(U < o.u_stop)),
                        "uncertain_frac": float(np.mean(U < o.u_stop))})
        fired = _stop(U, pf_hist, o)
        if fired is not None:
            reason, converged = fired, True
            break
        n_added = sum(a.shape[0] for a in added)
        if n_added >= o.max_added:
            break
        idx, new = _pick(U, min(o.batch_size, o.max_added - n_added), pool)
        if new.shape[0] == 0:
            reason = "pool exhausted"
            break
        used[idx] = True
        Xn, yn = run(new)
        added.append(new)
        X, y = np.vstack([X, Xn]), np.concatenate([y, yn])
        if bar is not None:
            bar.update(new.shape[0])
    return AKMCSResult(model=model, X=X, y=y,
                       added=np.vstack(added) if added else np.empty((0, width)),
                       n_calls=n_calls(), pf=pf_hist[-1], converged=converged,
                       stop_reason=reason, history=history)


__all__ = ["AKMCSOptions", "AKMCSResult", "GridPool", "ak_mcs"]
