"""A four-branch series system of linear limit states in 10-D (``problems.series_linear``:
failure ``u₁ > 3``, ``u₂ > 3``, ``−u₁ > 3.5`` or ``−u₂ > 3.5``; exact
``P_f = 1 − (1 − Φ(−3) − Φ(−3.5))²``), found silently wrong by est6: IS reported half of P_f
with a 1–5 % error in 34 of 40 runs (its search stopped at the corner ``(3, 3, 0, …)`` where two
branches meet and never started from the second branch's mirror), ais missed the β = 3.5
branches without a warning in 27 of 40 runs.
"""

import numpy as np
import pytest

from surrogate_rbrdo.estimators.coverage import coverage
from surrogate_rbrdo.estimators.importance import ImportanceSampling
from surrogate_rbrdo.estimators.problems import series_linear

pytestmark = pytest.mark.known_answer


def test_is_finds_the_four_design_points():
    prob = series_linear(dim=10)
    r = ImportanceSampling().estimate(prob.response, prob.inputs, prob.limit, prob.x,
                                      rng=np.random.default_rng(0))
    betas = r.diagnostics["betas"][0]
    np.testing.assert_allclose(np.sort(betas[np.isfinite(betas)]), [3.0, 3.0, 3.5, 3.5],
                               atol=1e-3)
    assert abs(r.pf[0] - prob.pf_exact[0]) <= 3 * r.pf_se[0]
    assert abs(r.pf[0] / prob.pf_exact[0] - 1.0) < 0.05


def test_ais_misses_no_branch_silently():
    row = coverage(series_linear(dim=10), "ais", {}, n_seeds=6)
    assert row.silent_misses == 0, row
