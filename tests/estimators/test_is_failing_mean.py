"""IS where the mean point fails (P_f > 1/2): the safe set is the tail, and its several
regions are searched like those of a failure domain (issue 13, review: IS reported
1 − P_f = 1.0e-6 ± 5e-7 on a credible-problem design where MC gave 2.0e-5 ± 4.5e-6).

Known answer: failure ``|a·u| < β``, ``1 − P_f = 2Φ(−β)`` (closed form).
"""

import numpy as np
import pytest
from scipy import special

from surrogate_rbrdo.estimators.coverage import coverage
from surrogate_rbrdo.estimators.importance import ImportanceSampling
from surrogate_rbrdo.estimators.problems import linear_standard, two_sided_safe

pytestmark = pytest.mark.known_answer


@pytest.mark.parametrize("dim", [2, 10])
def test_is_finds_both_safe_slivers(dim):
    """Before: one sliver's design point only, ``1 − P̂_f = Φ(−4.5)`` (half the truth) with a
    0.7 % error. Now both slivers' design points (β = −4.5 each) and the exact complement."""
    prob = two_sided_safe(dim=dim, beta=4.5)
    r = ImportanceSampling().estimate(prob.response, prob.inputs, prob.limit, prob.x,
                                      rng=np.random.default_rng(0))
    safe = 2.0 * special.ndtr(-4.5)
    assert abs((1.0 - r.pf[0]) - safe) <= 3 * r.pf_se[0] + 1e-12
    assert abs((1.0 - r.pf[0]) / safe - 1.0) < 0.05
    assert r.diagnostics["n_design_points"][0] == 2
    betas = r.diagnostics["betas"][0]
    np.testing.assert_allclose(np.sort(betas[np.isfinite(betas)]), [-4.5, -4.5], atol=1e-3)
    assert r.diagnostics["beta_form"][0] < 0


def test_is_complement_coverage():
    row = coverage(two_sided_safe(dim=5, beta=4.0), "is", {}, n_seeds=5)
    assert row.covered == 5 and row.warned == 0, row


def test_is_failing_mean_linear_unchanged():
    """One safe half-space (β = −1): P_f = Φ(1) exactly (the control variate is exact)."""
    prob = linear_standard(beta=-1.0, dim=2)
    r = ImportanceSampling().estimate(prob.response, prob.inputs, prob.limit, prob.x,
                                      rng=np.random.default_rng(1))
    assert r.pf[0] == pytest.approx(special.ndtr(1.0), rel=1e-9)
