import numpy as np
import pytest

from surrogate_rbrdo.core import CallCounter
from surrogate_rbrdo.core.protocols import LimitState
from surrogate_rbrdo.surrogates import GPR, GPROptions
from surrogate_rbrdo.surrogates.active import AKMCSOptions, ak_mcs


def quadratic_ls(z):
    """y = z0 + z1 + 0.2 (z0 - z1)^2 : curved limit state, failure y > 3."""
    return float(z[0] + z[1] + 0.2 * (z[0] - z[1]) ** 2)


def factory(r):
    return GPR(GPROptions(n_restarts=0), rng=r)


@pytest.mark.known_answer
def test_akmcs_reaches_pool_pf_with_few_calls():
    rng = np.random.default_rng(1)
    pool = rng.normal(size=(5000, 2))
    y_pool = np.array([quadratic_ls(z) for z in pool])
    limit = LimitState(3.0)
    pf_true = np.mean(y_pool > 3.0)  # the target: same pool, exact model
    c = CallCounter()
    res = ak_mcs(quadratic_ls, pool, [[-4.5, 4.5]] * 2, limit, factory, rng=rng,
                 options=AKMCSOptions(n_initial=10, max_added=60), counter=c)
    assert res.converged and res.n_calls == c.calls == 10 + res.added.shape[0]
    assert res.n_calls < 70
    assert abs(res.pf - pf_true) <= 2 / pool.shape[0]
    assert res.history[-1]["min_u"] >= 2.0
    assert [h["n_points"] for h in res.history] == list(range(10, 10 + len(res.history)))


def test_pf_stop_rule_and_budget():
    rng = np.random.default_rng(3)
    pool = rng.normal(size=(500, 2))
    res = ak_mcs(quadratic_ls, pool, [[-4, 4]] * 2, LimitState(3.0), factory, rng=rng,
                 options=AKMCSOptions(n_initial=6, max_added=2, stop="both"))
    assert res.added.shape[0] <= 2
    assert not res.converged or "P_f" in res.stop_reason


def test_pf_rule_fires_once_pf_is_stable():
    """stop = "pf": the loop ends at the first iteration whose last ``patience`` P_f changes
    are all within ``pf_rel_change`` of the current P_f (checked on the history)."""
    rng = np.random.default_rng(3)
    pool = rng.normal(size=(500, 2))
    o = AKMCSOptions(n_initial=6, max_added=30, stop="pf", patience=2, pf_rel_change=0.05)
    res = ak_mcs(quadratic_ls, pool, [[-4, 4]] * 2, LimitState(3.0), factory, rng=rng,
                 options=o)
    assert res.converged and "P_f stable" in res.stop_reason
    pf = [h["pf"] for h in res.history]

    def stable(n):  # the rule on the first n P_f values
        return n > o.patience and all(abs(pf[n - 1 - k] - pf[n - 2 - k])
                                      <= o.pf_rel_change * pf[n - 1] for k in range(o.patience))

    assert stable(len(pf))
    assert not any(stable(n) for n in range(1, len(pf)))
    assert res.added.shape[0] < o.max_added


def test_bad_options():
    with pytest.raises(ValueError, match="stop"):
        AKMCSOptions(stop="never")
    with pytest.raises(ValueError, match="bounds"):
        ak_mcs(quadratic_ls, np.zeros((5, 2)), [[0, 1]], LimitState(1.0), factory,
               rng=np.random.default_rng(0))
