import numpy as np
import pytest
from joblib import Memory

from surrogate_rbrdo.core import CallCounter
from surrogate_rbrdo.doe import lhs
from surrogate_rbrdo.sampling import evaluate_points

distributed = pytest.importorskip("distributed")


def f5(p):
    x, t = p[:3], p[3:]
    return float(np.sin(3 * x[0]) + x[1] * x[2] ** 2 + t[0] * np.exp(0.5 * x[0] * t[1]))


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                       dashboard_address=":0")
    c = distributed.Client(cluster, set_as_default=False)
    yield c
    c.close()
    cluster.close()


@pytest.fixture(scope="module")
def points():
    return lhs(24, [[0, 1], [-1, 1], [0, 2], [0.5, 1.5], [0.5, 1.5]],
               rng=np.random.default_rng(0))


def test_dask_equals_serial(client, points, tmp_path):
    serial = evaluate_points(f5, points)
    c = CallCounter()
    mem = Memory(tmp_path / "c", verbose=0)
    dask = evaluate_points(f5, points, backend="dask", client=client, counter=c, cache=mem)
    assert np.array_equal(dask.y, serial.y)
    assert c.calls == 24
    again = evaluate_points(f5, points, backend="dask", client=client, counter=c, cache=mem)
    assert again.n_evaluated == 0 and c.calls == 24
    assert np.array_equal(again.y, serial.y)


def test_dask_local_cluster_on_request(points):
    res = evaluate_points(f5, points[:6], backend="dask", client="local", n_jobs=2)
    assert np.array_equal(res.y, evaluate_points(f5, points[:6]).y)
