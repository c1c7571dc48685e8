"""Shared helpers of the surrogate wrappers: BLAS pinning, input checks, seeds."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
from threadpoolctl import ThreadpoolController

from surrogate_rbrdo.core.rng import require_rng
from surrogate_rbrdo.core.validate import check_finite_array

_CONTROLLER: list[ThreadpoolController] = []


def _controller() -> ThreadpoolController:
    # ``threadpool_limits`` rescans the loaded shared libraries on every call (~0.5-3 ms,
    # more than a whole 10^5-point grid prediction); a controller built once is ~20 µs.
    if not _CONTROLLER:
        import scipy.linalg  # noqa: F401  (make sure scipy's BLAS is loaded and seen)

        _CONTROLLER.append(ThreadpoolController())
    return _CONTROLLER[0]


@contextmanager
def blas_threads(n: int | None) -> Iterator[None]:
    """Limit BLAS to ``n`` threads inside the block (``None``: leave as is).

    One thread is the default of every surrogate here: on the development machine two BLAS
    threads made smt training about 4x slower than one (small matrices, thread overhead).

    >>> with blas_threads(1):
    ...     pass
    """
    if n is None:
        yield
        return
    with _controller().limit(limits=n, user_api="blas"):
        yield


def check_training_data(X: object, y: object) -> tuple[np.ndarray, np.ndarray]:
    """Validate training data: ``X`` (n, D) finite, ``y`` (n,) finite, ``n >= D + 1``."""
    X = check_finite_array("X", X, ndim=2)
    y = check_finite_array("y", np.asarray(y, dtype=float).reshape(-1), ndim=1)
    if y.shape[0] != X.shape[0]:
        raise ValueError(
            f"y has {y.shape[0]} values is not allowed: must match the {X.shape[0]} rows of X"
        )
    if X.shape[0] < X.shape[1] + 1:
        raise ValueError(
            f"X has n = {X.shape[0]} rows is not allowed: need n >= dimension + 1 = "
            f"{X.shape[1] + 1}"
        )
    return X, y


def check_predict_input(X: object, n_features: int) -> np.ndarray:
    """Validate prediction points: 2-D with ``n_features`` columns, finite."""
    X = check_finite_array("X", np.atleast_2d(np.asarray(X, dtype=float)), ndim=2)
    if X.shape[1] != n_features:
        raise ValueError(
            f"X has {X.shape[1]} columns is not allowed: the model was fitted on {n_features}"
        )
    return X


def seed_from(rng: np.random.Generator) -> int:
    """Draw an integer seed for a library that wants an ``int`` (smt, scikit-learn)."""
    return int(rng.integers(0, 2**31 - 1))


class SurrogateWrapper:
    """What the registry's wrappers share: options (``options_cls``), the rng, BLAS threads,
    the checks at the start of ``fit`` and the fitted attributes at its end."""

    options_cls: type = type(None)

    def __init__(self, options: Any = None, *, rng: np.random.Generator) -> None:
        self.options = options if options is not None else self.options_cls()
        self.rng = rng

    def _threads(self) -> int | None:
        return self.options.blas_threads or None

    def _start_fit(self, X: object, y: object
                   ) -> tuple[np.random.Generator, np.ndarray, np.ndarray]:
        """Check the options' type, the rng and the data; returns ``(rng, X, y)``."""
        if not isinstance(self.options, self.options_cls):
            raise ValueError(f"options = {self.options!r} is not allowed: must be "
                             f"{self.options_cls.__name__}")
        rng = require_rng(self.rng)
        return (rng, *check_training_data(X, y))

    def _store_fit(self, model: Any, X: np.ndarray, y: np.ndarray) -> None:
        self.model_ = model
        self.n_features_in_ = X.shape[1]
        self.X_train_ = X
        self.y_train_ = y
