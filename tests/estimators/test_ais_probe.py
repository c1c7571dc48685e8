"""ais: the failure branches a cross-entropy density lacks are found and sampled (issue 13).

Known answers: the design points of the four-branch series system (Waarts 2000), whose straight
branches ``|u₁ − u₂|/√2 > k/2`` have the design points ``±(k/2)(1, −1)/√2`` (β = k/2), and of a
linear limit state (one design point, nothing to add).
"""

import numpy as np
import pytest

from surrogate_rbrdo.estimators._ce_probe import MAX_PROBES, augment, probe_missed
from surrogate_rbrdo.estimators._common import LimitStateU
from surrogate_rbrdo.estimators._vmfn import VMFNMixture
from surrogate_rbrdo.estimators.adaptive import CrossEntropyIS
from surrogate_rbrdo.estimators.coverage import coverage
from surrogate_rbrdo.estimators.form import FORM
from surrogate_rbrdo.estimators.problems import linear_standard, series_four_branch

pytestmark = pytest.mark.known_answer


def _directional(dirs: np.ndarray, radius: float, defensive: float = 0.1) -> VMFNMixture:
    """A vMFN density concentrated on the unit directions ``dirs`` at ``radius`` (what the
    cross-entropy fit gives on those branches), with a defensive standard normal."""
    k, m = dirs.shape
    mix = VMFNMixture(np.full(k, 1.0 / k), dirs, np.full(k, 30.0), np.full(k, 50.0),
                      np.full(k, radius**2))
    return mix.with_defensive(defensive)


class _Counted:
    """The limit state with an independent count of the points it is called on."""

    rows = 0

    def __init__(self, G):
        self._G = G
        type(self).rows = 0

    def __call__(self, u):
        type(self).rows += np.atleast_2d(u).shape[0]
        return self._G(u)

    def __getattr__(self, name):
        return getattr(self._G, name)


def _limit_state(prob):
    return LimitStateU(prob.response, prob.inputs, prob.limit, prob.x[0])


def test_probe_finds_the_branches_the_density_lacks():
    """A density on the two curved branches only (directions ±(1, 1)/√2): the probe returns the
    two straight branches' design points ±(3.5, −3.5)/√2 (β = 3.5), not the covered ones."""
    prob = series_four_branch(7.0)
    rng = np.random.default_rng(3)
    q = _directional(np.array([[1.0, 1.0], [-1.0, -1.0]]) / np.sqrt(2.0), 3.3)
    v1 = rng.standard_normal((1000, 2))
    G = _limit_state(prob)
    g1 = G(v1)
    res = probe_missed(_Counted(G), q, v1, g1, 1.8e-3, 2000, FORM(), rng)
    assert res.calls == _Counted.rows                  # every model call is counted
    assert res.beta.size == 2
    np.testing.assert_allclose(res.beta, 3.5, atol=1e-4)
    expect = 3.5 / np.sqrt(2.0) * np.array([1.0, -1.0])
    got = res.centres[np.argsort(res.centres[:, 0])]
    np.testing.assert_allclose(got, np.array([-expect, expect]), atol=1e-3)
    assert 2 <= res.n_searches <= MAX_PROBES


def test_probe_adds_nothing_on_a_covered_branch():
    """Linear limit state β = 3 in 2-D with a density on its one branch: nothing is missed, and
    the final density is the density itself."""
    prob = linear_standard(beta=3.0, dim=2)
    rng = np.random.default_rng(0)
    G = _limit_state(prob)
    alpha = -np.asarray(G(np.eye(2)) - G(np.zeros((1, 2))))        # gradient direction of -G
    alpha = alpha / np.linalg.norm(alpha)
    q = _directional(alpha[None, :], 3.3)
    v1 = rng.standard_normal((1000, 2))
    res = probe_missed(G, q, v1, G(v1), 1.35e-3, 2000, FORM(), rng)
    assert res.beta.size == 0
    assert augment(q, res, 1.35e-3) is q


def test_ais_series_system_reports_its_branches():
    """The four-branch system with a small level size, where the fit loses branches most often:
    no silent miss in 12 runs (without the probe: 2 of these 12 runs 6 and 10 SE low, 3 of 40),
    exact P_f by quadrature."""
    row = coverage(series_four_branch(7.0), "ais", {"n_per_level": 500, "n_final": 1000},
                   n_seeds=12)
    assert row.silent_misses == 0, row


def test_probe_option_checked():
    with pytest.raises(ValueError, match="probe"):
        CrossEntropyIS(probe="yes")
