"""Shared helpers of the surrogate wrappers: BLAS pinning, input checks, seeds."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
from threadpoolctl import ThreadpoolController

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
