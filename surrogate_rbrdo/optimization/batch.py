"""Run independent optimisations (e.g. one per P_target) side by side in processes.

Each task is a zero-argument callable returning an :class:`~.result.OptimizationResult`
(``functools.partial(run_nsga2, form, lower, upper, rng=child, options=opts)``). Tasks carry
their own Generators, so the results do not depend on ``n_jobs``. A run consumes its Generator
(in this process; a worker consumes a pickled copy), so build fresh tasks to repeat a study.
Workers pin BLAS to ``blas_threads`` threads (threadpoolctl) so that processes do not
oversubscribe the cores.

>>> from functools import partial
>>> run_many([partial(pow, 2, 3), partial(pow, 3, 2)], n_jobs=1)
[8, 9]
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from joblib import Parallel, delayed
from threadpoolctl import threadpool_limits

from surrogate_rbrdo.core.validate import check_int


def _call_pinned(task: Callable[[], Any], blas_threads: int) -> Any:
    with threadpool_limits(limits=blas_threads, user_api="blas"):
        return task()


def run_many(tasks: Sequence[Callable[[], Any]], *, n_jobs: int = 1,
             blas_threads: int = 1) -> list[Any]:
    """Run ``tasks`` and return their results in order.

    Parameters
    ----------
    tasks : sequence of callables
        Zero-argument callables (picklable with cloudpickle when ``n_jobs > 1``).
    n_jobs : int
        Worker processes (joblib/loky); 1 runs in this process.
    blas_threads : int
        BLAS threads per task.
    """
    n_jobs = check_int("n_jobs", n_jobs, minimum=1)
    blas_threads = check_int("blas_threads", blas_threads, minimum=1)
    tasks = list(tasks)
    if n_jobs == 1 or len(tasks) <= 1:
        return [_call_pinned(t, blas_threads) for t in tasks]
    return list(Parallel(n_jobs=min(n_jobs, len(tasks)), backend="loky")(
        delayed(_call_pinned)(t, blas_threads) for t in tasks))
