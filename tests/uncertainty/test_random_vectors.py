"""Unit and property tests of the random vectors and their transforms."""

import numpy as np
import pytest
from scipy import stats

from surrogate_rbrdo.uncertainty import (
    Independent,
    LogNormal,
    MultivariateNormal,
    Nataf,
    Normal,
    RandomVector,
    Uniform,
)

CORR = np.array([[1.0, 0.6, -0.2], [0.6, 1.0, 0.3], [-0.2, 0.3, 1.0]])


def all_vectors():
    return [
        MultivariateNormal([1.0, -2.0, 0.5], std=[0.5, 2.0, 1.0], corr=CORR),
        MultivariateNormal([0.0, 1.0], cov=[[2.0, 0.3], [0.3, 1.0]]),
        Normal(3.0, 0.5),
        LogNormal.from_moments(2.0, 0.4),
        Uniform(-1.0, 3.0),
        Independent([Normal(0.0, 1.0), LogNormal(0.0, 0.3), Uniform(0.0, 2.0)]),
        Nataf([Normal(0.0, 1.0), LogNormal(0.0, 0.3), Uniform(0.0, 2.0)], CORR),
    ]


@pytest.mark.parametrize("rv", all_vectors(), ids=lambda r: type(r).__name__)
class TestContract:
    def test_protocol_and_shapes(self, rv):
        assert isinstance(rv, RandomVector)
        rng = np.random.default_rng(0)
        assert rv.sample(7, rng=rng).shape == (7, rv.dim)
        assert rv.standard_sample(7, rng=rng).shape == (7, rv.dim)
        assert rv.mean.shape == (rv.dim,)
        assert rv.cov.shape == (rv.dim, rv.dim)

    def test_round_trip(self, rv):
        u = rv.standard_sample(200, rng=np.random.default_rng(1))
        np.testing.assert_allclose(rv.to_standard(rv.from_standard(u)), u, atol=1e-8)

    def test_sample_moments(self, rv):
        n = 200_000
        th = rv.sample(n, rng=np.random.default_rng(2))
        sd = np.sqrt(np.diag(rv.cov))
        # 5 standard errors on the mean; 3 % on the covariance (loose but can fail)
        np.testing.assert_array_less(np.abs(th.mean(0) - rv.mean), 5 * sd / np.sqrt(n))
        np.testing.assert_allclose(np.cov(th.T).reshape(rv.cov.shape), rv.cov,
                                   atol=0.03 * np.outer(sd, sd).max())

    def test_rng_required_and_deterministic(self, rv):
        with pytest.raises(ValueError, match="Generator"):
            rv.sample(3, rng=None)
        a = rv.sample(4, rng=np.random.default_rng(9))
        b = rv.sample(4, rng=np.random.default_rng(9))
        np.testing.assert_array_equal(a, b)

    def test_zero_sample_size_rejected(self, rv):
        with pytest.raises(ValueError, match="n = 0"):
            rv.sample(0, rng=np.random.default_rng(0))

    def test_wrong_shape_rejected(self, rv):
        with pytest.raises(ValueError, match="shape"):
            rv.from_standard(np.zeros((2, rv.dim + 1)))


def test_mvn_std_corr_equals_cov():
    std = np.array([0.5, 2.0, 1.0])
    a = MultivariateNormal(np.zeros(3), std=std, corr=CORR)
    b = MultivariateNormal(np.zeros(3), cov=CORR * np.outer(std, std))
    np.testing.assert_allclose(a.cov, b.cov)
    np.testing.assert_allclose(a.chol @ a.chol.T, a.cov)


@pytest.mark.parametrize("kwargs, match", [
    ({"cov": [[1.0, 2.0], [2.0, 1.0]]}, "not positive definite"),
    ({"cov": [[1.0, 0.1], [0.2, 1.0]]}, "not symmetric"),
    ({}, "exactly one"),
    ({"cov": np.eye(2), "std": [1.0, 1.0]}, "exactly one"),
    ({"std": [1.0, -1.0]}, "std"),
    ({"std": [1.0, 1.0], "corr": [[1.0, 1.2], [1.2, 1.0]]}, r"\|value\| > 1"),
    ({"std": [1.0, 1.0], "corr": [[2.0, 0.0], [0.0, 1.0]]}, "diagonal"),
    ({"cov": [[1.0, np.nan], [np.nan, 1.0]]}, "finite"),
])
def test_mvn_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        MultivariateNormal(np.zeros(2), **kwargs)


def test_marginal_transforms_match_scipy():
    u = np.linspace(-3, 3, 13)[:, None]
    p = stats.norm.cdf(u)
    np.testing.assert_allclose(Normal(1.0, 2.0).from_standard(u), stats.norm(1, 2).ppf(p),
                               atol=1e-12)
    np.testing.assert_allclose(LogNormal(0.2, 0.4).from_standard(u),
                               stats.lognorm(0.4, scale=np.exp(0.2)).ppf(p))
    np.testing.assert_allclose(Uniform(-1, 3).from_standard(u), stats.uniform(-1, 4).ppf(p))


@pytest.mark.parametrize("make, match", [
    (lambda: Normal(0.0, 0.0), "sigma"),
    (lambda: LogNormal(0.0, -1.0), "sigma"),
    (lambda: LogNormal.from_moments(-1.0, 1.0), "mean"),
    (lambda: Uniform(1.0, 1.0), "hi"),
    (lambda: Independent([]), "empty"),
    (lambda: Independent([Normal(0, 1), "x"]), r"marginals\[1\]"),
])
def test_marginal_bad_input(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_support_violations_are_clear():
    with pytest.raises(ValueError, match="support"):
        LogNormal(0.0, 1.0).to_standard(np.array([[-1.0]]))
    with pytest.raises(ValueError, match="support"):
        Uniform(0.0, 1.0).to_standard(np.array([[2.0]]))


def test_nataf_lognormal_fictitious_correlation_closed_form():
    # Liu & Der Kiureghian (1986): exact rho0 for two lognormals
    s1, s2, rho = 0.3, 0.8, 0.7
    nat = Nataf([LogNormal(0.0, s1), LogNormal(1.0, s2)], [[1.0, rho], [rho, 1.0]])
    exact = np.log1p(rho * np.sqrt(np.expm1(s1**2) * np.expm1(s2**2))) / (s1 * s2)
    assert abs(nat.corr0[0, 1] - exact) < 1e-8


def test_nataf_reproduces_target_correlation():
    nat = Nataf([Uniform(0.0, 1.0), LogNormal(0.0, 0.5), Normal(0.0, 1.0)], CORR)
    th = nat.sample(400_000, rng=np.random.default_rng(3))
    np.testing.assert_allclose(np.corrcoef(th.T), CORR, atol=0.01)
    # uniform-uniform: rho = (6/pi) asin(rho0/2), so rho0 = 2 sin(pi rho/6)
    nu = Nataf([Uniform(0, 1), Uniform(0, 1)], [[1.0, 0.5], [0.5, 1.0]])
    assert abs(nu.corr0[0, 1] - 2 * np.sin(np.pi * 0.5 / 6)) < 1e-8


def test_nataf_unattainable_correlation():
    with pytest.raises(ValueError, match="not attainable"):
        Nataf([LogNormal(0.0, 2.0), LogNormal(0.0, 0.2)], [[1.0, -0.9], [-0.9, 1.0]])


def test_nataf_normal_marginals_equal_mvn():
    nat = Nataf([Normal(1.0, 0.5), Normal(-1.0, 2.0)], [[1.0, 0.4], [0.4, 1.0]])
    mvn = MultivariateNormal([1.0, -1.0], std=[0.5, 2.0], corr=[[1.0, 0.4], [0.4, 1.0]])
    u = np.random.default_rng(0).standard_normal((5, 2))
    np.testing.assert_allclose(nat.from_standard(u), mvn.from_standard(u))


def test_hashable_and_identity_equality():
    a = MultivariateNormal([0.0], cov=[[1.0]])
    assert a == a and hash(a) == hash(a)
    assert len({a, MultivariateNormal([0.0], cov=[[1.0]])}) == 2


def test_frozen():
    mvn = MultivariateNormal([0.0], cov=[[1.0]])
    with pytest.raises(AttributeError):
        mvn.mean = np.ones(1)
    with pytest.raises(ValueError):
        mvn.mean[0] = 3.0
