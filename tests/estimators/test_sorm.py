"""SORM against Breitung's closed form on the paraboloid and the exact P_f."""

import numpy as np
import pytest
from scipy import special

from surrogate_rbrdo.core import ModelError
from surrogate_rbrdo.estimators import SORM
from surrogate_rbrdo.estimators.problems import linear_standard, paraboloid
from surrogate_rbrdo.estimators.sorm import sorm_pf, tangent_basis

pytestmark = pytest.mark.known_answer


def run(prob, **kw):
    return SORM(**kw).estimate(prob.response, prob.inputs, prob.limit, prob.x,
                               rng=np.random.default_rng(0))


@pytest.mark.parametrize("beta, kappa, dim", [(3.0, 0.3, 5), (3.0, -0.1, 5), (2.0, 0.5, 3)])
def test_breitung_formula_and_curvatures(beta, kappa, dim):
    prob = paraboloid(beta=beta, kappa=kappa, dim=dim)
    est = run(prob, formula="breitung")
    np.testing.assert_allclose(est.diagnostics["curvatures"][0], kappa, atol=1e-4)
    breitung = special.ndtr(-beta) * (1 + beta * kappa) ** (-(dim - 1) / 2)
    assert est.pf[0] == pytest.approx(breitung, rel=1e-4)


@pytest.mark.parametrize("beta, kappa, dim", [(3.0, 0.3, 5), (3.0, -0.1, 5), (-1.0, 0.2, 3)])
def test_hohenbichler_closer_than_form(beta, kappa, dim):
    prob = paraboloid(beta=beta, kappa=kappa, dim=dim)
    est = run(prob)
    exact = prob.pf_exact[0]
    err_sorm = abs(est.pf[0] - exact) / exact
    err_form = abs(est.diagnostics["pf_form"][0] - exact) / exact
    assert err_sorm < 0.1 and err_sorm < 0.5 * err_form


def test_linear_sorm_equals_form():
    prob = linear_standard(beta=3.0, dim=4, shifts=(0.0, 0.5))
    est = run(prob)
    np.testing.assert_allclose(est.pf, prob.pf_exact, rtol=1e-5)
    np.testing.assert_allclose(est.diagnostics["curvatures"][0], 0.0, atol=1e-4)


def test_not_applicable_is_an_error():
    # 1 + beta*kappa = 0.04 > 0 (u* is a design point) but 1 + psi*kappa < 0 for psi = 3.28
    prob = paraboloid(beta=3.0, kappa=-0.32, dim=2)
    with pytest.raises(ModelError, match="SORM is not applicable for design 0"):
        run(prob)
    est = run(prob, formula="breitung")
    assert est.pf[0] == pytest.approx(special.ndtr(-3.0) / np.sqrt(1 - 0.96), rel=1e-3)


def test_helpers():
    a = np.array([0.6, 0.8, 0.0])
    R = tangent_basis(a)
    np.testing.assert_allclose(R.T @ R, np.eye(2), atol=1e-12)
    np.testing.assert_allclose(R.T @ a, 0.0, atol=1e-12)
    assert sorm_pf(2.0, np.zeros(3), "breitung") == pytest.approx(special.ndtr(-2.0))
    assert np.isnan(sorm_pf(2.0, np.array([-0.6]), "breitung"))
