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
import os
import shutil
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

from joblib import Parallel, delayed

from surrogate_rbrdo.core.validate import check_int


def preload(modules: tuple[str, ...], n_jobs: int) -> Iterator[tuple[str, ...]]:
    """Start importing ``modules`` on each of ``n_jobs`` joblib workers; returns the tasks'
    results to drain, in order (empty for ``n_jobs = 1``: nothing to prepare).

    One task per worker: each task, once its imports are done, waits until ``n_jobs``
    distinct processes have checked in (a file per process in a scratch folder, at most
    :data:`RENDEZVOUS_S`), so a worker that starts first cannot take a second task while
    another is still starting — loky gives a task to any idle worker.

    >>> list(preload(("json",), 1))
    []
    """
    check_int("n_jobs", n_jobs, minimum=1)
    if n_jobs == 1 or not modules:
        return iter(())
    return _drained(tuple(modules), n_jobs)


#: longest a preloading task waits for the other workers to check in (s)
RENDEZVOUS_S = 10.0
#: the scratch folders' name prefix (in the system's temporary folder)
FOLDER_PREFIX = "rbrdo-preload-"


def _drained(modules: tuple[str, ...], n_jobs: int) -> Iterator[tuple[str, ...]]:
    """The preload tasks, dispatched now (``joblib.Parallel`` dispatches when called; a
    generator function would not call it before the first result is asked for), and their
    results to drain, the scratch folder removed once they are drained."""
    folder = tempfile.mkdtemp(prefix=FOLDER_PREFIX)
    try:
        results = Parallel(n_jobs=n_jobs, return_as="generator")(
            delayed(_import)(modules, folder, n_jobs) for _ in range(n_jobs))
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    return _removing(results, folder)


def _removing(results: Iterator, folder: str) -> Iterator:
    try:
        yield from results
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _import(modules: tuple[str, ...], folder: str, n_jobs: int) -> tuple[str, ...]:
    for m in modules:
        importlib.import_module(m)
    Path(folder, str(os.getpid())).touch()
    end = time.monotonic() + RENDEZVOUS_S
    while len(os.listdir(folder)) < n_jobs and time.monotonic() < end:
        time.sleep(0.01)
    return modules
