"""Worker processes made ready ahead of their work: imports on joblib's (loky) workers.

A loky worker imports the modules of the first task it is given, while the process that gave
it waits: about a second for the discrepancy package on the shipped run, per worker. Started
with :func:`preload` just before some work of the calling process (reading the data), the
imports happen meanwhile; drain the returned iterator before the next ``joblib.Parallel``
call, which then finds the same workers ready (joblib reuses its workers between calls with
the same number of jobs). Nothing computed depends on it.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator

from joblib import Parallel, delayed

from surrogate_rbrdo.core.validate import check_int


def preload(modules: tuple[str, ...], n_jobs: int) -> Iterator[tuple[str, ...]]:
    """Start importing ``modules`` on each of ``n_jobs`` joblib workers (one task per worker:
    with idle workers each takes one); returns the tasks' results to drain, in order (empty
    for ``n_jobs = 1``: nothing to prepare).

    >>> list(preload(("json",), 1))
    []
    """
    check_int("n_jobs", n_jobs, minimum=1)
    if n_jobs == 1 or not modules:
        return iter(())
    return Parallel(n_jobs=n_jobs, return_as="generator")(
        delayed(_import)(tuple(modules)) for _ in range(n_jobs))


def _import(modules: tuple[str, ...]) -> tuple[str, ...]:
    for m in modules:
        importlib.import_module(m)
    return modules
