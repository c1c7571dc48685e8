"""NSGA-II backend: reproducibility, archive bookkeeping, bad configuration."""

import numpy as np
import pytest

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.formulations import DeterministicOptions, FormulationOptions, make_formulation
from surrogate_rbrdo.optimization import NSGA2Options, feasible_pareto, run_nsga2
from surrogate_rbrdo.optimization.toys import LinearMixToy

NO_DET = DeterministicOptions(stress=False, resonance="none")
TOY = LinearMixToy()


def toy_formulation(name="rbrdo", n_theta=500, seed=0):
    return make_formulation(
        name, response=TOY.response, inputs=TOY.inputs(), limit=TOY.limit,
        options=FormulationOptions(p_target=0.1, n_theta=n_theta, deterministic=NO_DET),
        rng=np.random.default_rng(seed))


SMALL = NSGA2Options(pop_size=20, n_gen=8)


def test_reproducible_to_the_bit():
    runs = [run_nsga2(toy_formulation(), [0.0], [1.0], rng=np.random.default_rng(7),
                      options=SMALL) for _ in range(2)]
    a, b = runs
    for k in ("X", "F", "G", "generation"):
        np.testing.assert_array_equal(getattr(a.archive, k), getattr(b.archive, k))
    np.testing.assert_array_equal(a.X, b.X)
    np.testing.assert_array_equal(a.pareto_mask, b.pareto_mask)
    c = run_nsga2(toy_formulation(), [0.0], [1.0], rng=np.random.default_rng(8), options=SMALL)
    assert not np.array_equal(a.archive.X, c.archive.X)


def test_archive_and_counts():
    form = toy_formulation(n_theta=300)
    res = run_nsga2(form, [0.0], [1.0], rng=np.random.default_rng(1), options=SMALL)
    arch = res.archive
    assert arch.generation.min() == 0 and arch.generation.max() == SMALL.n_gen - 1
    assert np.sum(arch.generation == 0) == SMALL.pop_size
    assert res.n_surrogate_calls == len(arch) * 300
    assert res.n_model_calls == 0
    assert len(res.history) == SMALL.n_gen
    assert sum(h["n_evals"] for h in res.history) == len(arch)
    # every final member was evaluated, with the same F as recorded in the archive
    for x, f in zip(res.X, res.F, strict=True):
        i = np.flatnonzero(np.all(arch.X == x, axis=1))
        assert i.size and np.array_equal(arch.F[i[0]], f)
    # archive records match a fresh evaluation (the formulation is a function of x)
    ev = form.evaluate(arch.X[:5])
    np.testing.assert_array_equal(ev.F, arch.F[:5])
    np.testing.assert_array_equal(ev.estimate.pf, arch.pf[:5])
    assert res.pareto_mask.any()
    np.testing.assert_array_equal(res.pareto_mask, feasible_pareto(res.F, res.G))
    d = res.to_dict()
    assert d["n_evaluated"] == len(arch) and d["optimizer"]["pymoo_mutation_prob_var"] == 0.25


def test_single_objective_runs_through_nsga2():
    form = toy_formulation("rbdo", n_theta=2000)
    res = run_nsga2(form, [0.0], [1.0], rng=np.random.default_rng(2),
                    options=NSGA2Options(pop_size=20, n_gen=25))
    assert res.F.shape == (20, 1)
    best = res.X[res.pareto_mask][0, 0]
    # min μ = max x s.t. P_f <= 10 % on the fixed sample: brute force on a fine grid
    grid = np.linspace(0.0, 1.0, 4001)[:, None]
    feasible = np.all(form.evaluate(grid).G <= 0, axis=1)
    assert best == pytest.approx(grid[feasible, 0].max(), abs=2e-3)


@pytest.mark.parametrize("kwargs, match", [
    ({"pop_size": 1}, "pop_size"), ({"n_gen": 0}, "n_gen"),
    ({"crossover_prob": 1.2}, "crossover_prob"), ({"mutation_prob": -0.1}, "mutation_prob"),
    ({"mutation_mode": "per_gene"}, "mutation_mode"),
])
def test_bad_options(kwargs, match):
    with pytest.raises(ValueError, match=match):
        NSGA2Options(**kwargs)


def test_bad_bounds_and_rng():
    form = toy_formulation()
    with pytest.raises(ValueError, match="lower < upper"):
        run_nsga2(form, [1.0], [0.0], rng=np.random.default_rng(0), options=SMALL)
    with pytest.raises(ValueError, match="rng"):
        run_nsga2(form, [0.0], [1.0], rng=0, options=SMALL)


def test_run_many_in_processes_matches_sequential():
    from functools import partial

    from surrogate_rbrdo.optimization import run_many

    def tasks():  # fresh tasks: a run consumes its Generator
        return [partial(run_nsga2, toy_formulation(seed=s), [0.0], [1.0],
                        rng=np.random.default_rng(s),
                        options=NSGA2Options(pop_size=10, n_gen=3)) for s in (0, 1)]

    seq = run_many(tasks(), n_jobs=1)
    par = run_many(tasks(), n_jobs=2)
    assert not np.array_equal(seq[0].archive.X, seq[1].archive.X)
    for a, b in zip(seq, par, strict=True):
        np.testing.assert_array_equal(a.archive.X, b.archive.X)
        np.testing.assert_array_equal(a.archive.F, b.archive.F)


def test_progress_bar_optional(capsys):
    res = run_nsga2(toy_formulation(n_theta=50), [0.0], [1.0], rng=np.random.default_rng(0),
                    options=NSGA2Options(pop_size=6, n_gen=3), progress=True)
    assert len(res.history) == 3
    assert "NSGA-II rbrdo" in capsys.readouterr().err


@pytest.mark.parametrize("engine", ["lean", "pymoo"])
def test_error_in_generation_zero_is_not_replaced_by_empty_archive(engine):
    """Issue 13 reproduction: a response returning NaN for x > 0.5 under ``rdo``; the run must
    raise the formulation's ModelError naming the design, not "archive is empty"."""
    def nan_above_half(x, theta):
        y = TOY.response(x, theta)
        return np.where(x[:, :1] > 0.5, np.nan, y)

    form = make_formulation(
        "rdo", response=nan_above_half, inputs=TOY.inputs(), limit=TOY.limit,
        options=FormulationOptions(n_theta=50, deterministic=NO_DET),
        rng=np.random.default_rng(0))
    with pytest.raises(ModelError, match="must be finite"):
        run_nsga2(form, [0.0], [1.0], rng=np.random.default_rng(1),
                  options=NSGA2Options(pop_size=10, n_gen=2, engine=engine))
