"""Evaluate ``func(point) -> float`` (or a fixed-length vector) on every row of a point set.

* **Parallel**: joblib, processes (``"loky"``) by default; ``"threading"`` and ``"sequential"``
  are accepted too; ``"dask"`` runs joblib's Dask backend against a ``distributed.Client``
  passed by the caller (or a temporary ``LocalCluster`` when ``client="local"``).
* **Cached / resumable**: pass a ``joblib.Memory`` (the caller chooses its location). A point
  whose result is already stored is loaded, not recomputed, so a rerun or an interrupted run
  picks up where it stopped: every finished point is written as soon as it is computed.
* **Counted**: points that are actually computed (cache misses) are added to a
  :class:`~surrogate_rbrdo.core.CallCounter` (one ``add`` per call), loaded ones as
  ``cached``; the count is taken where ``func`` runs (in the worker) and returned with the
  value, so it is counted, never inferred from the cache.

Cache key: joblib hashes the pickled ``func`` and the point. A module-level function is pickled
by reference (module and name), so after changing its *code* point the cache at a new location;
a model object (e.g. an FE model instance) is pickled with its parameters, so changing a
parameter changes the key. With Dask workers on other machines the cache location must be on a
shared file system.
* **Vector outputs**: ``n_outputs=k`` accepts ``func(point) -> array (k,)`` (one call per point,
  counted once); ``y`` is then ``(n, k)`` and a point is ok only if all ``k`` values are finite.
  Vector results are cached under a different function (``_call_vector``) than scalar ones, so
  the two never share cache entries.
* **Non-finite output**: ``on_nonfinite="raise"`` raises
  :class:`~surrogate_rbrdo.core.ModelError` naming the first offending point;
  ``"exclude"`` keeps going and flags the points in ``ok_mask``.

>>> import numpy as np
>>> from surrogate_rbrdo.core import CallCounter
>>> c = CallCounter()
>>> f = lambda p: np.nan if p[0] < 0 else float(p[0] ** 2)
>>> res = evaluate_points(f, [[-1.0], [2.0]], counter=c, on_nonfinite="exclude")
>>> res.ok_mask.tolist(), res.points_ok.tolist(), res.y_ok.tolist(), c.calls
([False, True], [[2.0]], [4.0], 2)
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import joblib
import numpy as np
from tqdm.auto import tqdm

from surrogate_rbrdo.core.counting import CallCounter
from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.validate import check_choice, check_finite_array

BACKENDS = ("loky", "threading", "sequential", "dask")


@dataclass(frozen=True)
class SampleResult:
    """Outcome of :func:`evaluate_points`.

    Attributes
    ----------
    points : ndarray, shape (n, D)
        All requested points, in order.
    y : ndarray, shape (n,) or (n, k)
        Function values (NaN/inf kept as returned where ``ok_mask`` is False); ``(n, k)`` with
        ``n_outputs=k``.
    ok_mask : ndarray of bool, shape (n,)
        True where ``y`` is finite (every component, for vector outputs).
    from_cache : ndarray of bool, shape (n,)
        True where the value was loaded from the cache instead of computed.
    n_evaluated : int
        Number of points actually computed in this call (= what was added to the counter).
    backend : str
    wall_time_s : float
    """

    points: np.ndarray
    y: np.ndarray
    ok_mask: np.ndarray
    from_cache: np.ndarray
    n_evaluated: int
    backend: str
    wall_time_s: float

    @property
    def points_ok(self) -> np.ndarray:
        """Points with a finite value."""
        return self.points[self.ok_mask]

    @property
    def y_ok(self) -> np.ndarray:
        """Finite values."""
        return self.y[self.ok_mask]

    @property
    def bad_points(self) -> np.ndarray:
        """Points whose value was NaN or infinite."""
        return self.points[~self.ok_mask]

    def to_dict(self) -> dict[str, Any]:
        """Plain-python view."""
        return {
            "points": self.points.tolist(), "y": self.y.tolist(),
            "ok_mask": self.ok_mask.tolist(), "from_cache": self.from_cache.tolist(),
            "n_evaluated": self.n_evaluated, "backend": self.backend,
            "wall_time_s": self.wall_time_s,
        }


def _call(func: Callable[[np.ndarray], float], point: np.ndarray,
          counter: CallCounter | None = None) -> float:
    """``func(point)``; ``counter`` (not part of the cache key) counts it."""
    value = float(func(point))
    if counter is not None:
        counter.add(1)
    return value


def _call_vector(func: Callable[[np.ndarray], np.ndarray], point: np.ndarray,
                 counter: CallCounter | None = None) -> np.ndarray:
    value = np.asarray(func(point), dtype=float).reshape(-1)
    if counter is not None:
        counter.add(1)
    return value


def _point_task(target: Callable[..., Any], func: Any, point: np.ndarray) -> tuple[Any, int]:
    """A worker's task: the value and 1 if ``func`` ran here (0: the cache answered)."""
    counter = CallCounter()
    return target(func, point, counter=counter), counter.calls


def _parallel_config(backend: str, n_jobs: int, client: Any) -> tuple[Any, Any]:
    """Return (context manager, cluster-to-close)."""
    if backend != "dask":
        return joblib.parallel_config(backend=backend, n_jobs=n_jobs), None
    try:  # optional dependency (the [dask] extra), imported only for this backend
        from distributed import Client, LocalCluster
    except ImportError as exc:  # pragma: no cover - optional dependency
        raise ValueError(
            "backend = 'dask' is not allowed: the 'distributed' package is not installed "
            "(pip install surrogate_rbrdo[dask])"
        ) from exc
    cluster = None
    if isinstance(client, str) and client == "local":
        cluster = LocalCluster(n_workers=max(1, n_jobs), threads_per_worker=1,
                               processes=False, dashboard_address=":0")
        client = Client(cluster, set_as_default=False)
    elif not isinstance(client, Client):
        raise ValueError(
            f"client = {client!r} is not allowed: backend 'dask' needs a distributed.Client "
            "or 'local' (temporary LocalCluster)"
        )
    # n_jobs=-1: as many tasks in flight as the cluster has worker threads
    return joblib.parallel_config(backend="dask", client=client, n_jobs=-1), (cluster, client)


def evaluate_points(
    func: Callable[[np.ndarray], float],
    points: np.ndarray,
    *,
    n_jobs: int = 1,
    backend: str = "loky",
    cache: Any = None,
    counter: CallCounter | None = None,
    on_nonfinite: str = "raise",
    progress: bool = False,
    client: Any = None,
    n_outputs: int | None = None,
    desc: str = "evaluating",
) -> SampleResult:
    """Evaluate ``func`` on every row of ``points``.

    Parameters
    ----------
    func : callable
        ``func(point: ndarray (D,)) -> float``. For processes or Dask it must be picklable
        (a module-level function or a picklable object); for caching its code is hashed.
    points : array_like, shape (n, D)
    n_jobs : int
        Parallel workers (``-1``: all cores; ``1``: serial in this process). Ignored by
        ``"dask"`` (the cluster's workers decide) and ``"sequential"``.
    backend : {"loky", "threading", "sequential", "dask"}
    cache : joblib.Memory, optional
        On-disk store; the caller chooses its location. ``None``: no caching.
    counter : CallCounter, optional
        Receives the number of points actually computed.
    on_nonfinite : {"raise", "exclude"}
    progress : bool
        Show a tqdm progress bar over computed points.
    client : distributed.Client or "local", optional
        Required by ``backend="dask"``; ``"local"`` starts (and closes) a temporary in-process
        ``LocalCluster`` with ``n_jobs`` workers.
    n_outputs : int, optional
        ``None`` (default): ``func`` returns a float and ``y`` is ``(n,)``. An integer ``k``:
        ``func`` returns ``k`` values (any array-like) and ``y`` is ``(n, k)``; a return of
        another length raises ``ValueError``.
    desc : str
        Label of the progress bar.

    Returns
    -------
    SampleResult

    Raises
    ------
    ModelError
        With ``on_nonfinite="raise"``, if ``func`` returns NaN or inf (message names the point).
    """
    t0 = time.perf_counter()
    X = check_finite_array("points", np.atleast_2d(np.asarray(points, dtype=float)), ndim=2)
    _check_args(func, backend, on_nonfinite, n_jobs, cache, n_outputs)
    n = X.shape[0]
    y = np.full(n if n_outputs is None else (n, int(n_outputs)), np.nan)
    from_cache = np.zeros(n, dtype=bool)
    base: Callable[..., Any] = _call if n_outputs is None else _call_vector
    target: Callable[..., Any] = base
    if cache is not None:
        target = cache.cache(base, ignore=["counter"])
        for i in range(n):
            if target.check_call_in_cache(func, X[i]):
                y[i] = target(func, X[i])
                from_cache[i] = True
    todo = np.flatnonzero(~from_cache)
    if counter is not None and from_cache.any():
        counter.add_cached(int(from_cache.sum()))

    n_evaluated = 0
    if todo.size:
        done, computed = _compute(target, func, X[todo], backend, n_jobs, client, counter,
                                  progress, desc)
        from_cache[todo[computed == 0]] = True
        n_evaluated = int(computed.sum())
        if n_outputs is not None:
            bad = [len(v) for v in done if len(v) != n_outputs]
            if bad:
                raise ValueError(f"func returned {bad[0]} values is not allowed: must return "
                                 f"n_outputs = {n_outputs}")
        y[todo] = done

    ok = np.isfinite(y) if n_outputs is None else np.isfinite(y).all(axis=1)
    if on_nonfinite == "raise" and not ok.all():
        i = int(np.flatnonzero(~ok)[0])
        raise ModelError(
            f"func returned {y[i]} at point index {i}: {X[i].tolist()} "
            f"({int((~ok).sum())} non-finite of {n}; pass on_nonfinite='exclude' to drop them)"
        )
    return SampleResult(points=X, y=y, ok_mask=ok, from_cache=from_cache,
                        n_evaluated=n_evaluated, backend=backend,
                        wall_time_s=time.perf_counter() - t0)


def _check_args(func: Any, backend: str, on_nonfinite: str, n_jobs: Any, cache: Any,
                n_outputs: Any) -> None:
    check_choice("backend", backend, BACKENDS)
    check_choice("on_nonfinite", on_nonfinite, ("raise", "exclude"))
    if isinstance(n_jobs, bool) or not isinstance(n_jobs, (int, np.integer)) or n_jobs == 0 \
            or n_jobs < -1:
        raise ValueError(f"n_jobs = {n_jobs!r} is not allowed: must be -1 or an integer >= 1")
    if cache is not None and not isinstance(cache, joblib.Memory):
        raise ValueError(f"cache = {cache!r} is not allowed: must be a joblib.Memory or None")
    if not callable(func):
        raise ValueError(f"func = {func!r} is not allowed: must be callable")
    if n_outputs is not None and (isinstance(n_outputs, bool) or not isinstance(
            n_outputs, (int, np.integer)) or n_outputs < 1):
        raise ValueError(f"n_outputs = {n_outputs!r} is not allowed: must be None or an "
                         "integer >= 1")


def _compute(target: Callable[..., Any], func: Any, points: np.ndarray, backend: str,
             n_jobs: int, client: Any, counter: CallCounter | None, progress: bool,
             desc: str) -> tuple[list[Any], np.ndarray]:
    """``target(func, point)`` for every row, in this process or in parallel: the values and
    per point 1 if it was computed (0: the cache answered); counted (also when a later point
    raises: the finished ones are cached already)."""
    done: list[Any] = []
    try:
        if backend == "sequential" or (backend != "dask" and n_jobs == 1):
            _collect((_point_task(target, func, p) for p in points), len(points), progress,
                     done, desc)
        else:
            ctx, closer = _parallel_config(backend, int(n_jobs), client)
            try:
                with ctx:
                    par = joblib.Parallel(return_as="generator")
                    it = par(joblib.delayed(_point_task)(target, func, p) for p in points)
                    _collect(it, len(points), progress, done, desc)
            finally:
                if closer is not None and closer[0] is not None:
                    closer[1].close()
                    closer[0].close()
    finally:
        n = sum(c for _, c in done)
        if counter is not None and n:
            counter.add(n)
        if counter is not None and len(done) > n:
            counter.add_cached(len(done) - n)
    return [v for v, _ in done], np.array([c for _, c in done], dtype=int)


def _collect(it: Any, total: int, progress: bool, out: list[float], desc: str) -> None:
    if progress:
        it = tqdm(it, total=total, desc=desc, unit="pt", leave=False)
    for v in it:
        out.append(v)
