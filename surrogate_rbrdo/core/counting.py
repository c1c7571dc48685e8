"""Cost accounting: every call of an expensive model goes through one counting wrapper.

>>> import numpy as np
>>> resp = CountingResponse(lambda x, t: x[:, :1] + t[:, 0][None, :])
>>> y = resp(np.zeros((3, 1)), np.ones((5, 1)))
>>> y.shape, resp.counter.calls
((3, 5), 15)
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from surrogate_rbrdo.core.errors import ModelError


@dataclass
class CallCounter:
    """Thread-safe counter of model evaluations (one call = one (x, θ) point).

    ``calls`` counts evaluations actually computed; ``cached`` counts results a cached
    sampler loaded instead of computing them (``add_cached``), so a resumed run can say both.
    """

    calls: int = 0
    batches: int = 0
    cached: int = 0
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False, compare=False)

    def add(self, n: int) -> None:
        with self._lock:
            self.calls += int(n)
            self.batches += 1

    def add_cached(self, n: int) -> None:
        with self._lock:
            self.cached += int(n)

    def reset(self) -> None:
        with self._lock:
            self.calls = 0
            self.batches = 0
            self.cached = 0


class CountingResponse:
    """Wrap a response ``f(x, theta) -> (P, N)`` and count evaluated points.

    Non-finite outputs raise :class:`~surrogate_rbrdo.core.errors.ModelError` naming the
    offending design and θ.
    """

    def __init__(self, func: Callable[[np.ndarray, np.ndarray], np.ndarray],
                 counter: CallCounter | None = None) -> None:
        self.func = func
        self.counter = counter if counter is not None else CallCounter()

    def __call__(self, x: np.ndarray, theta: np.ndarray) -> np.ndarray:
        x = np.atleast_2d(np.asarray(x, dtype=float))
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        y = np.asarray(self.func(x, theta), dtype=float)
        expected = (x.shape[0], theta.shape[0])
        if y.shape != expected:
            raise ModelError(f"response returned shape {y.shape}, expected {expected}")
        self.counter.add(y.size)
        if not np.all(np.isfinite(y)):
            i, j = np.argwhere(~np.isfinite(y))[0]
            raise ModelError(
                f"response returned {y[i, j]} at design x={x[i].tolist()}, "
                f"theta={theta[j].tolist()}"
            )
        return y


class CountingDesigns:
    """Wrap a per-design function ``f(x (P, d)) -> anything`` and count designs (rows).

    For deterministic models called once per population (e.g. the g_det design model).

    >>> f = CountingDesigns(lambda x: x.sum(axis=1))
    >>> f(np.ones((4, 3))).tolist(), f.counter.calls
    ([3.0, 3.0, 3.0, 3.0], 4)
    """

    def __init__(self, func: Callable[[np.ndarray], object],
                 counter: CallCounter | None = None) -> None:
        self.func = func
        self.counter = counter if counter is not None else CallCounter()

    def __call__(self, x: np.ndarray) -> object:
        x = np.atleast_2d(np.asarray(x, dtype=float))
        out = self.func(x)
        self.counter.add(x.shape[0])
        return out
