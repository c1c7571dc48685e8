"""optuna NSGA-II backend: same contract as pymoo's, reproducible, finds the toy front."""

import numpy as np
import pytest

from surrogate_rbrdo.formulations import DeterministicOptions, FormulationOptions, make_formulation
from surrogate_rbrdo.optimization import OPTIMIZERS, OptunaOptions, archive_front, run_optuna
from surrogate_rbrdo.optimization.toys import LinearMixToy

TOY = LinearMixToy()
NO_DET = DeterministicOptions(stress=False, resonance="none")


def form(name="rbrdo"):
    return make_formulation(
        name, response=TOY.response, inputs=TOY.inputs(), limit=TOY.limit,
        options=FormulationOptions(p_target=0.12, n_theta=2000, deterministic=NO_DET),
        rng=np.random.default_rng(0))


def test_registry_and_reproducible():
    assert OPTIMIZERS["optuna"] is run_optuna
    opts = OptunaOptions(pop_size=12, n_gen=4)
    a = run_optuna(form(), [0.0], [1.0], rng=np.random.default_rng(5), options=opts)
    b = run_optuna(form(), [0.0], [1.0], rng=np.random.default_rng(5), options=opts)
    np.testing.assert_array_equal(a.archive.X, b.archive.X)
    np.testing.assert_array_equal(a.archive.G, b.archive.G)
    assert len(a.archive) == 48 and a.n_surrogate_calls == 48 * 2000
    assert a.archive.generation.max() == 3 and a.X.shape == (12, 1)


def test_finds_the_reliable_front():
    res = run_optuna(form(), [0.0], [1.0], rng=np.random.default_rng(1),
                     options=OptunaOptions(pop_size=30, n_gen=15))
    X = res.archive.X[archive_front(res), 0]
    xa, _ = TOY.reliable_interval(0.12)
    assert X.min() == pytest.approx(xa, abs=0.05)
    assert X.max() == pytest.approx(1.0, abs=0.05)


def test_single_objective_and_bad_options():
    res = run_optuna(form("rbdo"), [0.0], [1.0], rng=np.random.default_rng(2),
                     options=OptunaOptions(pop_size=10, n_gen=3))
    assert res.F.shape == (10, 1)
    with pytest.raises(ValueError, match="mutation_prob"):
        OptunaOptions(mutation_prob=2.0)
