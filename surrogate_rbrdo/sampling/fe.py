"""FE sampling loops: joint points for training, designs × a θ sample for verification.

Every FE evaluation of the toolkit goes through one of two functions, both counted (a
:class:`~surrogate_rbrdo.core.CallCounter` receives the (x, θ) points actually computed and,
as ``cached``, those loaded from the cache; the count is taken where the model is called, in
the worker process, and returned with the values), cached (a ``joblib.Memory`` the caller
places, :func:`fe_cache`: keyed to the package's source, so a changed model never reuses
stale values; a rerun or ``--resume`` loads finished points) and parallel (joblib/loky
processes):

* :func:`sample_positive`: a point-wise function ``f(z)`` on rows ``z = [x, θ]`` (the DOE of
  a surrogate; vector outputs with ``n_outputs``), keeping the points whose outputs are
  finite and positive (via :func:`~surrogate_rbrdo.sampling.evaluate.evaluate_points`);
* :func:`sample_designs`: a ``Response`` ``(P, d) × (N, m) → (P, N)`` on designs × a θ
  sample, one task per (design, θ chunk) (full-FE Monte Carlo of chosen designs).

>>> import numpy as np
>>> from surrogate_rbrdo.core import CallCounter
>>> c = CallCounter()
>>> y = sample_designs(lambda x, t: x[:, :1] * t[:, 0][None, :], np.array([[1.0], [2.0]]),
...                    np.arange(5.0)[:, None], chunk=2, counter=c)
>>> y.tolist(), c.calls
([[0.0, 1.0, 2.0, 3.0, 4.0], [0.0, 2.0, 4.0, 6.0, 8.0]], 10)
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import joblib
import numpy as np
from tqdm.auto import tqdm

from surrogate_rbrdo.core.counting import CallCounter
from surrogate_rbrdo.core.files import source_digest
from surrogate_rbrdo.core.validate import check_finite_array, check_int
from surrogate_rbrdo.sampling.evaluate import evaluate_points


def fe_cache(cache_dir: str | Path | None, name: str = "fe_points") -> joblib.Memory | None:
    """A ``joblib.Memory`` under ``cache_dir/name/code-<source hash>`` (``None``: no cache).

    joblib keys an entry by the cached function's code and the pickled arguments (the model
    object with its parameters), not by the code of the model's classes; the folder per
    source hash (``core.files.source_digest``) makes any change of the package's code start
    a fresh cache, so a fixed FE model is never answered with values of the old one."""
    if cache_dir is None:
        return None
    location = Path(cache_dir) / name / f"code-{source_digest()}"
    return joblib.Memory(location=str(location), verbose=0)


def sample_positive(func: Callable[[np.ndarray], Any], Z: np.ndarray, *,
                    n_outputs: int | None = None, n_jobs: int = 1, backend: str = "loky",
                    cache: Any = None, counter: CallCounter | None = None,
                    progress: bool = False, desc: str = "FE points"
                    ) -> tuple[np.ndarray, np.ndarray]:
    """``func`` at joint points ``Z`` (counted, cached, parallel); returns the points whose
    outputs (all ``n_outputs`` of them) are finite and > 0, and those outputs."""
    Z = check_finite_array("Z", Z, ndim=2)
    res = evaluate_points(
        func, Z, n_jobs=n_jobs, backend=backend, cache=cache, counter=counter,
        on_nonfinite="exclude", progress=progress, n_outputs=n_outputs, desc=desc,
        client="local" if backend == "dask" else None)
    if n_outputs is None:
        ok = (res.y > 0) & res.ok_mask
    else:
        ok = res.ok_mask & np.all(np.where(np.isfinite(res.y), res.y, 0.0) > 0, axis=1)
    return Z[ok], res.y[ok]


def _design_chunk(response: Any, x: np.ndarray, theta: np.ndarray,
                  counter: CallCounter | None = None) -> np.ndarray:
    """One design on a θ chunk; ``counter`` (not part of the cache key) counts the points
    computed here (a cache hit never runs this)."""
    y = response(x[None, :], theta)[0]
    if counter is not None:
        counter.add(y.size)
    return y


def _chunk_task(func: Any, response: Any, x: np.ndarray, theta: np.ndarray
                ) -> tuple[np.ndarray, int]:
    """A worker's task: the chunk's values and the FE points computed for them (0 when the
    cache answered), counted in the worker."""
    counter = CallCounter()
    return func(response, x, theta, counter=counter), counter.calls


def sample_designs(response: Any, X: np.ndarray, theta: np.ndarray, *, n_jobs: int = 1,
                   chunk: int | None = None, cache: Any = None,
                   counter: CallCounter | None = None, progress: bool = False,
                   desc: str = "FE designs") -> np.ndarray:
    """``response`` of designs ``X`` (P, d) on ``theta`` (N, m) → (P, N).

    One task per design and chunk of ``chunk`` θ rows (default: the whole sample), run in
    ``n_jobs`` loky processes; with ``cache`` (a ``joblib.Memory``) a finished task is loaded,
    not recomputed, and only computed tasks are counted (``N_chunk`` calls each).
    """
    X = check_finite_array("X", np.atleast_2d(np.asarray(X, dtype=float)), ndim=2)
    theta = check_finite_array("theta", np.atleast_2d(np.asarray(theta, dtype=float)), ndim=2)
    n_jobs = check_int("n_jobs", n_jobs, minimum=1)
    chunk = theta.shape[0] if chunk is None else check_int("chunk", chunk, minimum=1)
    jobs = [(i, s) for i in range(X.shape[0]) for s in range(0, theta.shape[0], chunk)]
    func = _design_chunk if cache is None else cache.cache(_design_chunk, ignore=["counter"])
    out = np.empty((X.shape[0], theta.shape[0]))
    if n_jobs == 1:
        it: Any = (_chunk_task(func, response, X[i], theta[s:s + chunk]) for i, s in jobs)
    else:
        it = joblib.Parallel(n_jobs=n_jobs, backend="loky", return_as="generator")(
            joblib.delayed(_chunk_task)(func, response, X[i], theta[s:s + chunk])
            for i, s in jobs)
    if progress:
        it = tqdm(it, total=len(jobs), desc=desc, unit="chunk", leave=False)
    for (i, s), (vals, computed) in zip(jobs, it, strict=True):
        out[i, s:s + chunk] = vals
        if counter is not None:      # per finished task: an interruption keeps the count
            if computed:
                counter.add(computed)
            if len(vals) > computed:
                counter.add_cached(len(vals) - computed)
    return out


__all__ = ["fe_cache", "sample_designs", "sample_positive"]
