"""Workers made ready ahead of their work (``core.workers.preload``)."""

from __future__ import annotations

import glob
import os
import sys
import tempfile
import time

import pytest
from joblib import Parallel, delayed

from surrogate_rbrdo.core.workers import FOLDER_PREFIX, preload


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


def test_preload_starts_the_imports_before_it_is_drained():
    """The point of preloading: the workers import while the caller does other work, so the
    tasks are on the workers before the first result is asked for — each checks in (a file
    in the scratch folder) without the caller draining anything."""
    before = set(glob.glob(os.path.join(tempfile.gettempdir(), FOLDER_PREFIX + "*")))
    ready = preload(("tabnanny",), 2)
    folders = set(glob.glob(os.path.join(tempfile.gettempdir(), FOLDER_PREFIX + "*"))) - before
    assert len(folders) == 1
    folder = folders.pop()
    end = time.monotonic() + 30.0
    while len(os.listdir(folder)) < 2 and time.monotonic() < end:
        time.sleep(0.05)
    assert len(os.listdir(folder)) == 2            # both workers checked in, nothing drained
    assert list(ready) == [("tabnanny",), ("tabnanny",)]
    assert not os.path.exists(folder)              # removed once drained


def test_preload_checks_n_jobs():
    with pytest.raises(ValueError, match="n_jobs = 0 is not allowed"):
        preload(("json",), 0)
