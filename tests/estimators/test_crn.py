"""Common random numbers over a population: a design's estimate is a function of the design
only, not of its position in ``x`` or of the other rows (review s4, F13-3)."""

import numpy as np
import pytest

from surrogate_rbrdo.estimators import ESTIMATORS, get_estimator
from surrogate_rbrdo.estimators.problems import linear_standard

NAMES = sorted(ESTIMATORS)
PROB = linear_standard(beta=2.3, dim=2, shifts=(0.0, 0.5, 0.0, -0.3))


def pf_of(name, x, with_u):
    inputs = PROB.inputs
    u = inputs.standard_sample(2000, rng=np.random.default_rng(7)) if with_u else None
    est = get_estimator(name)
    return est.estimate(PROB.response, inputs, PROB.limit, x, rng=np.random.default_rng(3),
                        u=u).pf


@pytest.mark.parametrize("with_u", [True, False], ids=["u_given", "u_none"])
@pytest.mark.parametrize("name", NAMES)
def test_pf_of_a_design_does_not_depend_on_the_other_rows(name, with_u):
    # rows 0 and 2 are the same design: same P_f in one call, and the same P_f as the
    # design alone (same rng seed, same u) and as the design placed after other rows
    pf = pf_of(name, PROB.x, with_u)
    assert pf[0] == pf[2]
    alone = pf_of(name, PROB.x[:1], with_u)
    assert alone[0] == pf[0]
    last = pf_of(name, PROB.x[[1, 3, 0]], with_u)
    assert last[2] == pf[0]
    assert last[0] == pf[1] and last[1] == pf[3]
