"""A candidate that needs one of the model's own parameters on its bound is not physical."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from surrogate_rbrdo.discrepancy.search import _pinned


def _fit(x, lo, hi):
    return SimpleNamespace(x=np.asarray(x, float), par=SimpleNamespace(
        bounds=lambda: (np.asarray(lo, float), np.asarray(hi, float))))


def test_a_parameter_just_short_of_its_bound_is_pinned():
    lo, hi = np.log([0.5, 0.25, 1e-9]), np.log([1.5, 4.0, 1.0])
    # damping factor 0.2500094 (a bounded trust-region fit stops just short of 0.25)
    f = _fit(np.log([1.0, 0.2500094, 1e-3]), lo, hi)
    assert _pinned(f, 2).tolist() == [False, True]
    assert _pinned(_fit(np.log([1.49, 1.1, 1e-3]), lo, hi), 2).tolist() == [False, False]
    assert _pinned(_fit(np.log([1.5, 4.0, 1e-3]), lo, hi), 2).tolist() == [True, True]
