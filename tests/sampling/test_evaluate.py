import numpy as np
import pytest
from joblib import Memory

from surrogate_rbrdo.core import CallCounter, ModelError
from surrogate_rbrdo.sampling import evaluate_points


def branin(p):
    x1, x2 = p
    a, b, c, r, s, t = 1.0, 5.1 / (4 * np.pi**2), 5 / np.pi, 6.0, 10.0, 1 / (8 * np.pi)
    return a * (x2 - b * x1**2 + c * x1 - r) ** 2 + s * (1 - t) * np.cos(x1) + s


def nan_if_negative(p):
    return np.nan if p[0] < 0 else float(p[0] + p[1])


class Flaky:
    """Raises on one given point (simulates a crash in the middle of a run)."""

    def __init__(self, bad):
        self.bad = bad

    def __call__(self, p):
        if p[0] == self.bad:
            raise RuntimeError("solver crashed")
        return float(p.sum())


POINTS = np.array([[-np.pi, 12.275], [np.pi, 2.275], [9.42478, 2.475], [0.0, 0.0], [1.0, 5.0]])


@pytest.mark.known_answer
def test_serial_branin_known_minima():
    res = evaluate_points(branin, POINTS[:3])
    assert np.allclose(res.y, 0.397887, atol=1e-5)
    assert res.ok_mask.all() and res.n_evaluated == 3


def test_processes_equal_serial_and_counted():
    c = CallCounter()
    serial = evaluate_points(branin, POINTS)
    par = evaluate_points(branin, POINTS, n_jobs=2, backend="loky", counter=c)
    assert np.array_equal(par.y, serial.y)
    assert c.calls == 5 and c.batches == 1


def test_cache_resume(tmp_path):
    mem = Memory(tmp_path / "cache", verbose=0)
    c = CallCounter()
    first = evaluate_points(branin, POINTS[:3], cache=mem, counter=c)
    assert c.calls == 3 and not first.from_cache.any()
    again = evaluate_points(branin, POINTS, cache=mem, counter=c)
    assert c.calls == 5  # only the 2 new points computed
    assert again.from_cache.tolist() == [True, True, True, False, False]
    assert np.array_equal(again.y[:3], first.y)


def test_interrupted_run_resumes(tmp_path):
    mem = Memory(tmp_path / "cache", verbose=0)
    c = CallCounter()
    pts = np.arange(10.0).reshape(5, 2)
    with pytest.raises(RuntimeError, match="crashed"):
        evaluate_points(Flaky(bad=6.0), pts, cache=mem, counter=c)
    assert c.calls == 3  # the points before the crash were computed, counted and stored
    res = evaluate_points(Flaky(bad=-1.0), pts, cache=mem, counter=c)
    # a different object state is a different cache key -> everything recomputed
    assert res.n_evaluated == 5
    res2 = evaluate_points(Flaky(bad=-1.0), pts, cache=mem, counter=c)
    assert res2.n_evaluated == 0 and np.array_equal(res2.y, pts.sum(1))


def test_nonfinite_raise_names_point():
    pts = np.array([[1.0, 1.0], [-2.0, 3.0]])
    with pytest.raises(ModelError, match=r"nan at point index 1: \[-2.0, 3.0\]"):
        evaluate_points(nan_if_negative, pts)


def test_nonfinite_exclude():
    pts = np.array([[1.0, 1.0], [-2.0, 3.0], [2.0, 2.0]])
    res = evaluate_points(nan_if_negative, pts, on_nonfinite="exclude", n_jobs=2)
    assert res.ok_mask.tolist() == [True, False, True]
    assert res.bad_points.tolist() == [[-2.0, 3.0]]
    assert res.y_ok.tolist() == [2.0, 4.0]


def test_bad_arguments():
    with pytest.raises(ValueError, match="backend"):
        evaluate_points(branin, POINTS, backend="mpi")
    with pytest.raises(ValueError, match="on_nonfinite"):
        evaluate_points(branin, POINTS, on_nonfinite="ignore")
    with pytest.raises(ValueError, match="n_jobs"):
        evaluate_points(branin, POINTS, n_jobs=0)
    with pytest.raises(ValueError, match="cache"):
        evaluate_points(branin, POINTS, cache="/tmp/x")
    with pytest.raises(ValueError, match="client"):
        evaluate_points(branin, POINTS, backend="dask")
    with pytest.raises(ValueError, match="non-finite"):
        evaluate_points(branin, [[np.nan, 1.0]])


def ten_x(p):
    return float(10.0 * p[0])


def two_outputs(p):
    return np.array([p[0] + p[1], np.nan if p[0] < 0 else p[0] * p[1]])


def test_vector_outputs_counted_once_cached_apart_from_scalar(tmp_path):
    mem = Memory(tmp_path / "cache", verbose=0)
    c = CallCounter()
    pts = np.array([[1.0, 2.0], [3.0, 4.0], [-1.0, 5.0]])
    res = evaluate_points(two_outputs, pts, n_outputs=2, counter=c, cache=mem,
                          on_nonfinite="exclude")
    assert res.y.shape == (3, 2) and c.calls == 3
    assert np.array_equal(res.y[:2], [[3.0, 2.0], [7.0, 12.0]])
    assert res.ok_mask.tolist() == [True, True, False]
    assert res.y_ok.shape == (2, 2)
    par = evaluate_points(two_outputs, pts, n_outputs=2, n_jobs=2, on_nonfinite="exclude")
    assert np.array_equal(par.y[:2], res.y[:2])
    again = evaluate_points(two_outputs, pts, n_outputs=2, cache=mem, counter=c,
                            on_nonfinite="exclude")
    assert again.from_cache.all() and c.calls == 3
    # the same func and point through the scalar path never reads the vector entry
    vec = evaluate_points(ten_x, pts[:1], n_outputs=1, cache=mem)
    assert vec.y.shape == (1, 1) and vec.y[0, 0] == 10.0
    scal = evaluate_points(ten_x, pts[:1], cache=mem)
    assert not scal.from_cache.any() and scal.y.tolist() == [10.0]


def test_vector_outputs_wrong_length_and_bad_n_outputs():
    with pytest.raises(ValueError, match="returned 2 values"):
        evaluate_points(two_outputs, [[1.0, 2.0]], n_outputs=3)
    with pytest.raises(ValueError, match="n_outputs = 0"):
        evaluate_points(two_outputs, [[1.0, 2.0]], n_outputs=0)
    with pytest.raises(ModelError, match="point index 0"):
        evaluate_points(two_outputs, [[-1.0, 2.0]], n_outputs=2)
