"""``[deterministic] design_basis``: what the deterministic strategy designs against."""

import numpy as np
import pytest

from surrogate_rbrdo.spindle.evaluate import ResponseSpec
from surrogate_rbrdo.study import credible_problem
from surrogate_rbrdo.study.config import DeterministicTable

CRED = credible_problem()


def test_default_follows_the_response():
    t = DeterministicTable()
    np.testing.assert_array_equal(t.design_theta(CRED.inputs, CRED.response),
                                  CRED.design_theta)
    assert t.design_theta(CRED.inputs, ResponseSpec("at_speed", 24000.0)) is None
    assert DeterministicTable(design_basis="median").design_theta(CRED.inputs,
                                                                  CRED.response) is None


def test_bad_design_basis_names_the_field():
    with pytest.raises(ValueError, match="design_basis = 'worst' is not allowed"):
        DeterministicTable(design_basis="worst")
    with pytest.raises(ValueError, match="deterministic.design_basis = 'unbalance_cases' is "
                                         "not allowed with response.kind = 'at_speed'"):
        DeterministicTable(design_basis="unbalance_cases").design_theta(
            CRED.inputs, ResponseSpec("at_speed", 24000.0))
