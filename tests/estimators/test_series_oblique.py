"""A series system whose branches are neither axis-aligned nor opposite (review s5 of issue 13):
``max_i (a_i·u − β_i) > 0``, β = (3.0, 3.4, 3.8), branches 1 and 2 at ρ = 0.45, so half of
branch 2 lies in branch 1's half-space.

Known answer: inclusion–exclusion over MVN orthant probabilities, checked here against the
complement of one trivariate normal CDF (an independent formula) and a Monte Carlo sample.
Before the fix, ``is`` reported the two-branch value 4–30 SE low without a warning in 23 of 40
runs (6-D), and the ais probe judged the found branch 2 covered in 15-D (3 silent misses of 40).
"""

import numpy as np
import pytest
from scipy import integrate, stats

from surrogate_rbrdo.estimators._ce_probe import coverage_ratio, half_space_share
from surrogate_rbrdo.estimators._gmm import GaussianMixture
from surrogate_rbrdo.estimators.coverage import coverage
from surrogate_rbrdo.estimators.problems import (
    OBLIQUE_NORMALS,
    series_oblique,
    union_of_half_spaces,
)

pytestmark = pytest.mark.known_answer
BETA = np.array([3.0, 3.4, 3.8])


def test_exact_value_by_an_independent_formula():
    """``P_f = 1 − Φ₃(β; A Aᵀ)`` and 4·10⁵ Monte Carlo draws (4.5 SE band)."""
    prob = series_oblique(dim=6)
    cov = OBLIQUE_NORMALS @ OBLIQUE_NORMALS.T
    cdf = stats.multivariate_normal.cdf(BETA, np.zeros(3), cov, abseps=1e-12, releps=1e-10,
                                        rng=np.random.default_rng(1))
    np.testing.assert_allclose(prob.pf_exact[0], 1.0 - cdf, rtol=1e-4)
    u = np.random.default_rng(2).standard_normal((400_000, 6))
    mc = np.mean(prob.response(prob.x, u)[0] > 0.0)
    assert abs(mc - prob.pf_exact[0]) < 4.5 * np.sqrt(prob.pf_exact[0] / 4e5)


@pytest.mark.parametrize("dim", [6, 15])
def test_exact_value_by_one_dimensional_quadrature(dim):
    """Given ``u₁`` the three branches are independent: branch 1 is ``u₁ > 3``, branch 2
    ``u₂ > 3.4·√1.25 − 0.5 u₁``, branch 3 ``u₃ + u₄ + u₅ > 7.6 + u₁`` with ``u₃ + u₄ + u₅ ~
    N(0, 3)``, so ``1 − P_f = ∫_{−∞}^{3} φ(u₁) Φ(3.4√1.25 − 0.5 u₁) Φ((7.6 + u₁)/√3) du₁`` —
    a formula that shares nothing with the package's inclusion–exclusion."""
    def safe(u1):
        return (stats.norm.pdf(u1) * stats.norm.cdf(3.4 * np.sqrt(1.25) - 0.5 * u1)
                * stats.norm.cdf((7.6 + u1) / np.sqrt(3.0)))
    ps, _ = integrate.quad(safe, -12.0, 3.0, epsabs=1e-14, epsrel=1e-12)
    np.testing.assert_allclose(series_oblique(dim=dim).pf_exact[0], 1.0 - ps, rtol=1e-7)


def test_union_of_half_spaces_refuses_bad_normals():
    with pytest.raises(ValueError, match="unit normals"):
        union_of_half_spaces(2.0 * np.eye(2), np.array([3.0, 3.0]))
    with pytest.raises(ValueError, match="parallel or opposite"):
        union_of_half_spaces(np.array([[1.0, 0.0], [-1.0, 0.0]]), np.array([3.0, 3.0]))
    with pytest.raises(ValueError, match="one unit normal per offset"):
        union_of_half_spaces(np.eye(2), np.array([3.0, 3.0, 3.0]))


@pytest.mark.parametrize("dim", [6, 15])
def test_is_finds_the_overlapping_branch(dim):
    """IS on 20 seeds: every run covered at 3 SE, none warned (all three branches are found,
    and the control variates are exact for a union of half-spaces)."""
    row = coverage(series_oblique(dim=dim), "is", {}, n_seeds=20)
    assert row.covered == 20 and row.warned == 0, row
    assert abs(row.mean_pf / row.exact - 1.0) < 0.02, row


def test_is_on_the_complement_finds_it_too():
    """The failing-mean path (IS on −G: the safe set is the union of the three half-spaces)."""
    base = series_oblique(dim=6)
    prob = type(base)(**{**base.__dict__, "response": lambda x, t: -base.response(x, t),
                         "pf_exact": 1.0 - base.pf_exact, "name": "series_oblique_safe"})
    row = coverage(prob, "is", {}, n_seeds=10)
    assert row.covered == 10 and row.warned == 0, row


def test_coverage_ratio_sees_what_the_half_space_share_misses():
    """A density on branch 1 only, a little wide (what a cross-entropy fit gives), in 15-D:
    4 % of its draws lie in branch 2's half-space (the old test called that covered), but near
    branch 2's design point ``u₂ = 3.4 a₂`` it has < 1 % of the density of ``N(u₂, I)``."""
    m = 15
    a2 = np.zeros(m)
    a2[:6] = OBLIQUE_NORMALS[1]
    u2, c1 = 3.4 * a2, np.eye(m)[0] * 3.0
    q = GaussianMixture(np.ones(1), c1[None], 1.44 * np.eye(m)[None])
    rng = np.random.default_rng(0)
    share = half_space_share(q.sample(20_000, rng), a2[None], np.array([3.4]))[0]
    assert share > 0.03
    assert coverage_ratio(q, u2, rng) < 0.01
    at_u2 = GaussianMixture(np.ones(1), u2[None], np.eye(m)[None])
    assert coverage_ratio(at_u2, u2, rng) == pytest.approx(1.0)


@pytest.mark.slow
@pytest.mark.parametrize("dim", [6, 15])
def test_ais_does_not_lose_the_overlapping_branch(dim):
    """ais, 40 seeds: no silent miss (before: 3 of 40 in 15-D)."""
    row = coverage(series_oblique(dim=dim), "ais", {}, n_seeds=40)
    assert row.silent_misses == 0, row


def test_is_says_so_when_a_weak_hidden_branch_is_missed():
    """Branch 2 at β = 3.9 (3 % of P_f): few first-stage samples reveal it, and IS missed it
    silently in 3 of 40 runs (z ≈ −3) before the check after sampling. Now a run that misses it
    finds its design point from the second stage and warns: no silent miss in 40."""
    prob = series_oblique(dim=6, beta=(3.0, 3.9, 3.8))
    row = coverage(prob, "is", {}, n_seeds=40)
    assert row.silent_misses == 0 and row.warned >= 1, row
    assert any("found after sampling" in m for m in row.messages), row.messages
