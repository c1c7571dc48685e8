"""Sequential Monte Carlo p-values of the residual tests (:mod:`.sequential`), against the
exact tail of a maximum of independent χ²₁ statistics — the form of the generic lack-of-fit
statistic (the best of many one-parameter likelihood ratios)."""

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.stats import chi2

from surrogate_rbrdo.discrepancy.calibration import NullDistribution, TailModel
from surrogate_rbrdo.discrepancy.sequential import (
    FAR,
    FAR_DRAWS,
    MAX_DRAWS,
    MIN_EXCEED,
    sequential_p_values,
)

K = 64                      # directions, as the rig's generic statistic has
LEVEL = 0.01 / 3


def _exact_sf(t: float) -> float:
    """``P(max of K iid χ²₁ > t) = 1 − F₁(t)^K``."""
    return float(-np.expm1(K * chi2.logcdf(t, 1)))


def _at(p: float) -> float:
    return brentq(lambda t: _exact_sf(t) - p, 1.0, 80.0)


def _sampler(rng):
    return lambda n: (rng.standard_normal((n, K)) ** 2).max(axis=1)


@pytest.mark.known_answer
def test_sequential_p_of_a_maximum_matches_its_exact_tail_where_the_moment_fit_does_not():
    """At the statistic whose exact tail is the level (0.0033), the 400-draw moment-matched
    scaled χ² puts the p-value far below it (the maximum's tail is heavier than the fit's), so
    a calibrated statistic would be rejected; the sequential p-value is within Monte Carlo
    error of the exact one, and its rejection rate there is near one half."""
    t = _at(LEVEL)
    rng = np.random.default_rng(11)
    draw = _sampler(rng)
    moment, seq = [], []
    for _ in range(30):
        d = draw(400)
        moment.append(float(TailModel.from_draws(d).sf(t)))
        seq.append(sequential_p_values({"g": d}, {"g": t}, LEVEL,
                                       lambda n: {"g": draw(n)})["g"])
    moment, seq = np.array(moment), np.array(seq)
    assert np.median(moment) < 0.5 * LEVEL          # the flaw the module corrects
    assert 0.8 * LEVEL < np.mean(seq) < 1.25 * LEVEL
    assert 0.15 < np.mean(seq <= LEVEL) < 0.85


@pytest.mark.known_answer
@pytest.mark.parametrize("p_exact", [0.03, 0.01])
def test_sequential_p_stops_after_min_exceed_draws_beyond(p_exact):
    """Above the level the rule stops once MIN_EXCEED draws lie beyond the statistic: the
    p-value is (1 + h)/(1 + n) with h ≥ MIN_EXCEED (one chunk earlier h was below it), within a
    factor 1.6 of the exact tail."""
    t = _at(p_exact)
    draw = _sampler(np.random.default_rng(5))
    taken = []

    def more(n):
        taken.append(n)
        return {"g": draw(n)}

    p = sequential_p_values({"g": draw(400)}, {"g": t}, LEVEL, more)["g"]
    n = 400 + sum(taken)
    assert n < MAX_DRAWS
    h = p * (1 + n) - 1
    assert h == pytest.approx(round(h)) and round(h) >= MIN_EXCEED and taken
    assert p_exact / 1.6 < p < 1.6 * p_exact


def test_no_draw_is_taken_when_the_first_draws_settle_every_p_value():
    """A p-value in the empirical range is settled by the first draws: the answer is
    NullDistribution.p_value's and ``more`` is never called."""
    rng = np.random.default_rng(2)
    d = _sampler(rng)(400)
    null = NullDistribution(d, d, d, np.zeros((400, 0)), ())
    observed = {"gof": float(np.quantile(d, 0.5)), "generic": float(np.quantile(d, 0.9))}

    def more(n):
        raise AssertionError("no draw should be taken")

    out = sequential_p_values({k: d for k in observed}, observed, LEVEL, more)
    assert out == {k: null.p_value(k, v) for k, v in observed.items()}


def test_a_statistic_far_beyond_every_draw_costs_one_chunk():
    """A real misfit (exact p 1e-9): its moment-fit p-value is far below the level, but it is
    taken as it stands only after FAR_DRAWS draws with none beyond it — one chunk more, not
    MAX_DRAWS."""
    draw = _sampler(np.random.default_rng(2))
    far, taken = _at(1e-9), []

    def more(n):
        taken.append(n)
        return {"g": draw(n)}

    p = sequential_p_values({"g": draw(400)}, {"g": far}, LEVEL, more)["g"]
    assert sum(taken) + 400 == FAR_DRAWS and p <= FAR * LEVEL
