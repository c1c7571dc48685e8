"""Stiffness factors with normal or positive (lognormal) support and the same moments."""

import numpy as np
import pytest

from surrogate_rbrdo.uncertainty import MultivariateNormal, stiffness_factors

CORR = np.array([[1.0, 0.4], [0.4, 1.0]])


def test_normal_is_the_multivariate_normal():
    a = stiffness_factors([1.0, 1.0], [0.06, 0.07], CORR)
    b = MultivariateNormal([1.0, 1.0], std=[0.06, 0.07], corr=CORR)
    u = np.random.default_rng(0).standard_normal((5, 2))
    np.testing.assert_allclose(a.from_standard(u), b.from_standard(u))


def test_lognormal_has_the_moments_the_correlation_and_positive_support():
    th = stiffness_factors([1.0, 1.2], [0.2, 0.3], CORR, distribution="lognormal")
    s = th.sample(400_000, rng=np.random.default_rng(1))
    np.testing.assert_allclose(s.mean(axis=0), [1.0, 1.2], rtol=2e-3)
    np.testing.assert_allclose(s.std(axis=0), [0.2, 0.3], rtol=1e-2)
    assert np.corrcoef(s.T)[0, 1] == pytest.approx(0.4, abs=0.01)     # Nataf hits the target
    assert np.all(th.from_standard(np.array([[-40.0, -40.0]])) > 0)


@pytest.mark.parametrize("kw, match", [
    ({"distribution": "gamma"}, "distribution = 'gamma' is not allowed"),
    ({"mean": [1.0, -1.0], "distribution": "lognormal"}, r"mean\[1\] = -1.0 is not allowed"),
    ({"std": [0.1]}, "must match"),
])
def test_bad_input(kw, match):
    args = {"mean": [1.0, 1.0], "std": [0.1, 0.1], **kw}
    with pytest.raises(ValueError, match=match):
        stiffness_factors(**args)
