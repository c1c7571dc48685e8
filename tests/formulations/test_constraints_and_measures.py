"""Generic design constraints (callables, safe expressions) and the reliability measures
(probability, β, common-sample quantile; the conservative upper bound)."""

import numpy as np
import pytest
from scipy import special, stats

from surrogate_rbrdo.core import LimitState
from surrogate_rbrdo.core.errors import OutsideDomainError
from surrogate_rbrdo.core.protocols import Estimate
from surrogate_rbrdo.estimators import EstimatorWarning
from surrogate_rbrdo.formulations import (
    DesignConstraint,
    DeterministicOptions,
    FormulationOptions,
    make_formulation,
)
from surrogate_rbrdo.formulations.reliability import (
    harrell_davis,
    quantile_rank,
    reliability_column,
)
from surrogate_rbrdo.uncertainty import MultivariateNormal

NO_DET = DeterministicOptions(stress=False, resonance="none")
NAMES = ("F", "L", "D")


def test_expression_arithmetic_comparisons_and_functions():
    x = np.array([[2.0, 3.0, 4.0], [1.0, -1.0, 0.5]])
    cases = {
        "F * L - D <= 1": x[:, 0] * x[:, 1] - x[:, 2] - 1,
        "F**2 >= L + 2": x[:, 1] + 2 - x[:, 0] ** 2,
        "sqrt(D) + abs(L) - exp(0) * pi": np.sqrt(x[:, 2]) + np.abs(x[:, 1]) - np.pi,
        "max(F, L, 2.5) < min(D, 10)": np.maximum(np.maximum(x[:, 0], x[:, 1]), 2.5)
        - np.minimum(x[:, 2], 10),
        "-F / 2 > log10(100) - e": np.log10(100) - np.e + x[:, 0] / 2,
    }
    for text, expected in cases.items():
        c = DesignConstraint.from_expression("c", text, NAMES)
        np.testing.assert_allclose(c(x), expected, rtol=1e-14, err_msg=text)
        assert c.expression == text


@pytest.mark.parametrize("text, match", [
    ("__import__('os').system('true')", "is not allowed: call of"),
    ("F.real", "Attribute"),
    ("(lambda: 1)()", "call of"),
    ("F if L else D", "IfExp"),
    ("'abc'", "constant 'abc'"),
    ("True + F", "constant True"),
    ("F <= L <= D", "at most one comparison"),
    ("F == L", "comparison Eq"),
    ("G + 1", "unknown name 'G'"),
    ("sqrt(x=F)", "call of 'sqrt'"),
    ("F +", "syntax error"),
    ("[F][0]", "Subscript"),
])
def test_expression_whitelist_rejects_everything_else(text, match):
    with pytest.raises(ValueError, match=match):
        DesignConstraint.from_expression("c", text, NAMES)


def test_callable_constraint_and_bad_input():
    c = DesignConstraint("ratio", lambda x: x[:, 1] / x[:, 2] - 12.0, scale=12.0)
    np.testing.assert_allclose(c(np.array([[0.0, 600.0, 60.0]])), [-1.0 / 6.0])
    with pytest.raises(ValueError, match="scale = 0.0 is not allowed"):
        DesignConstraint("c", np.sum, scale=0.0)
    with pytest.raises(ValueError, match="must be callable"):
        DesignConstraint("c", 3.0)
    with pytest.raises(ValueError, match=r"returned shape \(3,\), expected \(1,\)"):
        DesignConstraint("c", lambda x: np.ones(3))(np.ones((1, 3)))


def linear(x, t):
    return x[:, :1] + t[:, :1].T


def build(name="rbdo", constraints=(), **opts):
    return make_formulation(
        name, response=linear, inputs=MultivariateNormal([0.0], std=[1.0]),
        limit=LimitState(3.0), constraints=constraints, rng=np.random.default_rng(0),
        options=FormulationOptions(deterministic=NO_DET, **{"n_theta": 20_000, **opts}))


def test_design_constraints_are_appended_after_the_reliability_column():
    c1 = DesignConstraint.from_expression("upper", "x <= 0.5", ("x",))
    c2 = DesignConstraint("lower", lambda x: -x[:, 0] - 1.0)
    form = build(constraints=(c1, c2))
    assert form.constraint_names == ("pf", "upper", "lower")
    ev = form.evaluate(np.array([[0.0], [1.0]]))
    np.testing.assert_allclose(ev.G[:, 1:], [[-0.5, -1.0], [0.5, -2.0]])
    assert form.describe()["design_constraints"] == {"upper": "x <= 0.5",
                                                    "lower": "python callable"}
    with pytest.raises(ValueError, match="each name once"):
        build(constraints=(c1, c1))
    with pytest.raises(ValueError, match="is not a DesignConstraint"):
        build(constraints=("x <= 1",))


def test_measures_share_the_feasible_set():
    """probability, β and quantile columns have the same sign (the quantile up to the
    Harrell-Davis smoothing of a few ranks, away from the boundary)."""
    x = np.linspace(-1.5, 2.0, 36)[:, None]
    cols = {m: build(reliability_measure=m, p_target=0.02).evaluate(x).G[:, 0]
            for m in ("probability", "beta", "quantile")}
    pf = special.ndtr(x[:, 0] - 3.0)
    clear = np.abs(pf / 0.02 - 1) > 0.1
    for m, col in cols.items():
        assert np.array_equal(col[clear] <= 0, pf[clear] <= 0.02), m
    # β column: β_t − β exactly for the sample P_f
    p_hat = build().evaluate(x).estimate.pf
    beta = np.clip(-special.ndtri(p_hat), -38.0, 38.0)     # P_f = 0 stands for β = 38
    np.testing.assert_allclose(cols["beta"], special.ndtri(0.98) - beta)


@pytest.mark.known_answer
def test_quantile_column_is_the_limit_state_quantile():
    """y = x + θ, θ ~ N(0, 1), failure y > 3: g = 3 − y has the p-quantile 3 − x − Φ⁻¹(1 − p)."""
    x = np.array([[0.0], [1.0]])
    col = build(reliability_measure="quantile", p_target=0.05,
                n_theta=200_000).evaluate(x).G[:, 0]
    exact = -(3.0 - x[:, 0] - special.ndtri(0.95)) / 3.0
    np.testing.assert_allclose(col, exact, atol=0.01)


@pytest.mark.known_answer
def test_conservative_rank_is_the_clopper_pearson_bound():
    """k_cp is the largest failure count whose exact (beta-quantile) upper bound <= p_target."""
    n, p, level = 5000, 0.01, 0.95
    k = quantile_rank(n, p, "upper", level)
    upper = stats.beta.ppf(0.5 + level / 2, k + 1, n - k)
    upper_next = stats.beta.ppf(0.5 + level / 2, k + 2, n - k - 1)
    assert upper <= p < upper_next
    assert quantile_rank(n, p, "estimate", level) == 50


def test_conservative_option_is_stricter_than_the_estimate():
    x = np.linspace(0.0, 1.5, 16)[:, None]
    for m in ("probability", "quantile"):
        est = build(reliability_measure=m, p_target=0.05).evaluate(x).G[:, 0]
        upper = build(reliability_measure=m, p_target=0.05, pf_bound="upper").evaluate(x).G[:, 0]
        assert np.all(upper >= est), m
    up = build(p_target=0.05, pf_bound="upper").evaluate(x)
    np.testing.assert_allclose(up.G[:, 0], up.estimate.pf_ci[:, 1] / 0.05 - 1.0)


def test_harrell_davis_matches_the_quantile_of_a_large_sample():
    rng = np.random.default_rng(0)
    g = rng.standard_normal((3, 100_000))
    np.testing.assert_allclose(harrell_davis(g, 0.01), special.ndtri(0.01), atol=0.02)


@pytest.mark.parametrize("opts, match", [
    ({"reliability_measure": "quantile", "estimator": "is"}, "needs 'mc'"),
    ({"pf_bound": "upper", "estimator": "form"}, "no sampling error"),
    ({"reliability_measure": "pmf"}, "reliability_measure = 'pmf' is not allowed"),
    ({"pf_bound": "lower"}, "pf_bound = 'lower' is not allowed"),
])
def test_bad_measure_options(opts, match):
    with pytest.raises(ValueError, match=match):
        FormulationOptions(**opts)


def test_too_small_sample_for_the_quantile_fails_clearly():
    form = build(reliability_measure="quantile", p_target=0.001, n_theta=500)
    with pytest.raises(ValueError, match="n_theta = 500 is too small"):
        form.evaluate(np.zeros((1, 1)))


@pytest.mark.parametrize("measure", ["probability", "quantile"])
def test_points_outside_the_physical_domain_are_not_failures(measure):
    """A response that raises OutsideDomainError for θ < −1 (about 16 % of the sample): those
    points are not failures (the meaning every estimator uses), μ_y is that of the points
    inside, and a warning says so."""
    def resp(x, t):
        bad = np.flatnonzero(t[:, 0] < -1.0)
        if bad.size:
            raise OutsideDomainError("theta < -1", rows=bad)
        return x[:, :1] + t[:, :1].T

    form = make_formulation("rbdo", response=resp, inputs=MultivariateNormal([0.0], std=[1.0]),
                            limit=LimitState(1.0), rng=np.random.default_rng(0),
                            options=FormulationOptions(n_theta=20_000, p_target=0.2,
                                                       reliability_measure=measure,
                                                       deterministic=NO_DET))
    with pytest.warns(EstimatorWarning, match="outside the model's physical domain"):
        ev = form.evaluate(np.zeros((1, 1)))
    theta = form.theta[:, 0]
    out = ev.estimate.diagnostics["n_outside_domain"][0]
    assert out == np.sum(theta < -1.0)
    assert ev.estimate.pf[0] == pytest.approx(np.sum(theta > 1.0) / 20_000)
    assert ev.estimate.mean[0] == pytest.approx(theta[theta >= -1.0].mean())
    if measure == "quantile":   # the 20 % quantile of g = 1 − θ over the sample, outside = +inf
        g = np.where(theta < -1.0, np.inf, 1.0 - theta)
        assert -ev.G[0, 0] == pytest.approx(np.sort(g)[4000], abs=0.01)
    assert np.isfinite(ev.F).all()


@pytest.mark.parametrize("measure", ["probability", "beta"])
def test_a_lower_bound_below_the_target_is_not_feasible(measure):
    """A P_f that is only a lower bound (FORM unconverged from a safe mean) cannot certify
    P_f ≤ P_target: at or below the target it counts as infeasible; above it, it proves
    infeasibility and is kept; labels "" and "upper" pass unchanged."""
    pf = np.array([1e-3, 1e-3, 1e-3, 5e-2])
    z = np.zeros(4)
    est = Estimate(z, z, pf, z, z, z, np.c_[pf, pf], 0, "form",
                   {"pf_bound": np.array(["", "upper", "lower", "lower"])})
    limit = LimitState(threshold=1.0)
    col = reliability_column(measure, "estimate", est, None, limit, 1e-2, 0.95)
    assert np.all(col[:2] < 0)                   # certified feasible
    assert col[2] > 0 and col[3] > 0             # unproven, proven infeasible
    if measure == "probability":
        assert col[3] == pytest.approx(5e-2 / 1e-2 - 1.0)   # the bound itself is kept
