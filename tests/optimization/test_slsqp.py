"""SLSQP on a formulation: behaviour at the edge of a model's domain (review of issue 13)."""

import numpy as np
import pytest

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.formulations import (
    DesignConstraint,
    DeterministicOptions,
    FormulationOptions,
    make_formulation,
)
from surrogate_rbrdo.optimization import SLSQPOptions, run_slsqp
from surrogate_rbrdo.optimization.evaluator import RecordingEvaluator
from surrogate_rbrdo.optimization.slsqp import _Cached, _differences
from surrogate_rbrdo.uncertainty import MultivariateNormal

HYPERBOLA = DesignConstraint.from_expression("area", "x0 * x1 >= 1", ("x0", "x1"))


def hyperbola_problem(response):
    return make_formulation(
        "deterministic", response=response, inputs=MultivariateNormal([0.0], std=[1.0]),
        limit=None, constraints=(HYPERBOLA,), rng=np.random.default_rng(0),
        options=FormulationOptions(n_theta=1, deterministic=DeterministicOptions(
            stress=False, resonance="none")))


def test_a_model_error_at_a_difference_point_falls_back_to_one_side():
    """A model that fails for x0 > 1: at an iterate on that edge the central difference crosses
    into the failing region, so the gradient falls back to the backward difference instead of
    aborting the run (review of issue 13: it used to)."""
    def response(x, t):
        if np.any(x[:, 0] > 1.0 + 1e-12):
            raise ModelError("outside the model's validity")
        return (x[:, :1] ** 2 + 3 * x[:, 1:2]) + 0 * t.T

    form = hyperbola_problem(response)
    evaluator = RecordingEvaluator(form)
    lo, span = np.array([0.0, 0.0]), np.array([2.0, 2.0])
    cache = _Cached(evaluator, lo, span, SLSQPOptions(fd_step=1e-5))
    at = cache.at(np.array([0.5, 0.25]))          # x = (1, 0.5), on the edge
    np.testing.assert_allclose(at.df, [2.0 * 2.0, 3.0 * 2.0], rtol=1e-4)   # d/dz = span d/dx
    with pytest.raises(ModelError, match="failed on both sides of variable 0"):
        _differences(0.0, np.zeros(1), np.array([np.nan]), np.zeros((1, 1)),
                     np.array([np.nan]), np.zeros((1, 1)), np.ones(1), 1.0, np.zeros(1))


def test_a_model_error_at_the_iterate_propagates():
    def response(x, t):
        raise ModelError("always fails")

    with pytest.raises(ModelError, match="always fails"):
        run_slsqp(hyperbola_problem(response), [0.1, 0.1], [4.0, 4.0],
                  rng=np.random.default_rng(1))
