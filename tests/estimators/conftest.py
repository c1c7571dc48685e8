"""Single-threaded BLAS for these tests: small arrays, and no oversubscription on shared CPUs."""

import pytest
from threadpoolctl import threadpool_limits


@pytest.fixture(autouse=True, scope="session")
def _one_blas_thread():
    with threadpool_limits(1):
        yield
