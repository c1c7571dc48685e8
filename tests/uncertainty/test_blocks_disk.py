"""Block-independent random vectors and the uniform-disk radius.

Known answers: a point uniform over a disk of radius ``a`` has ``P(R ≤ r) = (r/a)²``,
``E[x²] = a²/4`` for its Cartesian coordinates and ``E[x y] = 0``.
"""

import numpy as np
import pytest

from surrogate_rbrdo.uncertainty import MultivariateNormal, RandomVector, Uniform
from surrogate_rbrdo.uncertainty.blocks import BlockIndependent
from surrogate_rbrdo.uncertainty.disk import UniformDiskRadius
from surrogate_rbrdo.uncertainty.nataf import Independent


@pytest.mark.known_answer
def test_radius_and_uniform_phase_give_a_uniform_disk():
    a = 3.0
    v = Independent([UniformDiskRadius(a), Uniform(0.0, 2 * np.pi)])
    th = v.sample(200_000, rng=np.random.default_rng(1))
    x, y = th[:, 0] * np.cos(th[:, 1]), th[:, 0] * np.sin(th[:, 1])
    for r in (0.5, 1.5, 2.9):
        assert abs(np.mean(th[:, 0] <= r) - (r / a) ** 2) < 4e-3
    assert abs(np.mean(x**2) / (a**2 / 4) - 1) < 1e-2
    assert abs(np.mean(x * y)) < 1e-2
    assert abs(th[:, 0].mean() - v.mean[0]) < 5e-3 and abs(th[:, 0].std() - v.std[0]) < 5e-3


def test_radius_round_trip_and_support():
    d = UniformDiskRadius(1e-5)
    u = np.linspace(-4, 4, 9)[:, None]
    np.testing.assert_allclose(d.to_standard(d.from_standard(u)), u, atol=1e-9)
    with pytest.raises(ValueError, match="outside"):
        d.to_standard(np.array([[2e-5]]))
    with pytest.raises(ValueError, match="r_max"):
        UniformDiskRadius(0.0)


def test_blocks_moments_transform_and_independence():
    mvn = MultivariateNormal([1.0, 2.0], std=[0.1, 0.2], corr=[[1.0, 0.5], [0.5, 1.0]])
    ind = Independent([UniformDiskRadius(1.0), Uniform(0.0, 360.0)])
    v = BlockIndependent([mvn, ind])
    assert isinstance(v, RandomVector) and v.dim == 4
    np.testing.assert_allclose(v.mean, np.concatenate([mvn.mean, ind.mean]))
    np.testing.assert_allclose(v.cov[:2, :2], mvn.cov)
    np.testing.assert_allclose(v.cov[2:, :2], 0.0)
    u = v.standard_sample(50_000, rng=np.random.default_rng(2))
    th = v.from_standard(u)
    np.testing.assert_allclose(th[:, :2], mvn.from_standard(u[:, :2]))
    np.testing.assert_allclose(np.cov(th.T), v.cov, atol=0.02 * np.abs(v.cov).max())
    np.testing.assert_allclose(v.to_standard(th), u, atol=1e-8)


def test_bad_blocks_are_refused():
    with pytest.raises(ValueError, match="blocks is empty"):
        BlockIndependent([])
    with pytest.raises(ValueError, match="blocks\\[0\\]"):
        BlockIndependent([np.ones(2)])
