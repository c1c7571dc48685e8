"""The sparse-regression baseline's STLSQ on a collinear polynomial library (known answers)."""

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy.baselines import stlsq

X = np.linspace(1000.0, 24000.0, 50) / 24000.0
THETA = np.vander(X, 5, increasing=True)


@pytest.mark.known_answer
def test_exact_law_recovered_from_the_full_collinear_library():
    """Noise-free ``0.03 − 0.05 x²``: backward elimination returns exactly its two terms."""
    xi, _ = stlsq(THETA, 0.03 - 0.05 * X**2, np.full(X.size, 1e6))
    np.testing.assert_allclose(xi, [0.03, 0.0, -0.05, 0.0, 0.0], atol=1e-10)


@pytest.mark.known_answer
def test_strong_trend_survives_noise_and_constant_alone_gives_no_trend():
    """A 5 % fall over the range with 0.1 % noise (t ≈ 100) keeps a falling trend — the
    all-at-once threshold dropped it, since every term's standard error is inflated by the
    collinear library in the full fit; a constant alone keeps no trend term."""
    sd = 1e-3
    rng = np.random.default_rng(3)
    w = np.full(X.size, 1.0 / sd)
    xi, _ = stlsq(THETA, 0.03 - 0.05 * X**2 + sd * rng.standard_normal(X.size), w)
    trend = THETA[-1, 1:] @ xi[1:] - THETA[0, 1:] @ xi[1:]
    assert trend == pytest.approx(-0.05 * (X[-1] ** 2 - X[0] ** 2), rel=0.1)
    xi0, _ = stlsq(THETA, 0.03 + sd * rng.standard_normal(X.size), w)
    assert np.count_nonzero(xi0[1:]) == 0 and xi0[0] == pytest.approx(0.03, abs=5 * sd)
