import numpy as np
import pytest
from scipy.spatial.distance import pdist

from surrogate_rbrdo.doe import check_bounds, lhs, min_distance, phi_p

BOUNDS = [[1000.0, 3000.0], [300.0, 750.0], [50.0, 80.0], [0.5, 1.5], [0.5, 1.5]]


@pytest.mark.parametrize("criterion", ["maximin", "random"])
def test_latin_property_and_bounds(criterion):
    n = 50
    X = lhs(n, BOUNDS, rng=np.random.default_rng(3), criterion=criterion)
    b = np.asarray(BOUNDS)
    U = (X - b[:, 0]) / (b[:, 1] - b[:, 0])
    assert X.shape == (n, 5)
    strata = np.sort(np.floor(U * n).astype(int), axis=0)
    assert np.array_equal(strata, np.tile(np.arange(n)[:, None], (1, 5)))


def test_seeded_and_reproducible():
    a = lhs(20, BOUNDS, rng=np.random.default_rng(7))
    b = lhs(20, BOUNDS, rng=np.random.default_rng(7))
    c = lhs(20, BOUNDS, rng=np.random.default_rng(8))
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_maximin_improves_space_filling():
    # same rng stream start: the optimised design starts from the same random LHS
    unit = [[0.0, 1.0]] * 5
    rand = lhs(100, unit, rng=np.random.default_rng(0), criterion="random")
    opt = lhs(100, unit, rng=np.random.default_rng(0), criterion="maximin", iterations=3000)
    assert phi_p(opt) < phi_p(rand)
    assert min_distance(opt) > min_distance(rand)


def test_metrics_known_answers():
    X = np.array([[0.0, 0.0], [3.0, 4.0], [0.0, 1.0]])
    assert min_distance(X) == 1.0
    d = pdist(X)
    assert phi_p(X, p=2.0) == pytest.approx(np.sum(d**-2.0) ** 0.5)
    # bounds: distances measured in the unit cube
    assert min_distance(np.array([[0.0], [5.0]]), bounds=[[0.0, 10.0]]) == 0.5


def test_too_few_points():
    with pytest.raises(ValueError, match=r"n = 5 .*>= 6"):
        lhs(5, BOUNDS, rng=np.random.default_rng(0))


@pytest.mark.parametrize("bad", [[[1.0, 1.0]], [[2.0, 1.0], [0.0, 1.0]], [[0.0, np.inf]],
                                 [0.0, 1.0]])
def test_bad_bounds(bad):
    with pytest.raises(ValueError, match="bounds"):
        lhs(10, bad, rng=np.random.default_rng(0))


def test_bad_options():
    with pytest.raises(ValueError, match="criterion"):
        lhs(10, [[0, 1]], rng=np.random.default_rng(0), criterion="best")
    with pytest.raises(ValueError, match="rng"):
        lhs(10, [[0, 1]], rng=None)
    with pytest.raises(ValueError, match="lower must be < upper"):
        check_bounds([[0, 1], [3, 2]])
