"""Workers made ready ahead of their work (``core.workers.preload``)."""

from __future__ import annotations

import os
import sys

import pytest
from joblib import Parallel, delayed

from surrogate_rbrdo.core.workers import preload


def test_preload_imports_on_the_workers_that_the_next_call_reuses():
    """Each worker gets one import task; the next ``Parallel`` call with the same number of
    jobs runs on those same processes, where the module is already imported."""
    done = list(preload(("tabnanny",), 2))
    assert done == [("tabnanny",), ("tabnanny",)]
    # a lambda travels by value (cloudpickle): the workers cannot import this test module
    seen = Parallel(n_jobs=2)(delayed(lambda n: (n in sys.modules, os.getpid()))("tabnanny")
                              for _ in range(4))
    assert all(flag for flag, _ in seen)
    assert all(pid != os.getpid() for _, pid in seen)


def test_preload_checks_n_jobs():
    with pytest.raises(ValueError, match="n_jobs = 0 is not allowed"):
        preload(("json",), 0)
