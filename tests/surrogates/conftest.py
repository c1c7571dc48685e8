import numpy as np
import pytest

from surrogate_rbrdo.doe import lhs
from surrogate_rbrdo.surrogates import SURROGATES, GPROptions, KrigingOptions


def f5(Z):
    """5-D analytic test function in (x, theta) form: 3 design columns, 2 theta columns."""
    x, t = Z[:, :3], Z[:, 3:]
    return np.sin(3 * x[:, 0]) + x[:, 1] * x[:, 2] ** 2 + t[:, 0] * np.exp(0.5 * x[:, 0] * t[:, 1])


BOUNDS5 = [[0.0, 1.0], [-1.0, 1.0], [0.0, 2.0], [0.5, 1.5], [0.5, 1.5]]


def make(name, rng):
    cls = SURROGATES[name]
    opts = KrigingOptions(n_start=2) if name.startswith("krg") else GPROptions(n_restarts=0)
    return cls(opts, rng=rng)


@pytest.fixture(scope="session")
def data5():
    Z = lhs(40, BOUNDS5, rng=np.random.default_rng(11))
    return Z, f5(Z)


@pytest.fixture(scope="session")
def fitted5(data5):
    Z, y = data5
    return {name: make(name, np.random.default_rng(5)).fit(Z, y) for name in SURROGATES}
