"""A stage's candidate fits: the same on worker processes as in this one; which are fitted."""

from __future__ import annotations

from types import SimpleNamespace as ns

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy import naming
from surrogate_rbrdo.discrepancy.calibration import Linearisation
from surrogate_rbrdo.discrepancy.candidates import candidate
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.naming import fit_all
from surrogate_rbrdo.discrepancy.nuisance import Slot
from surrogate_rbrdo.discrepancy.problem import Problem
from surrogate_rbrdo.discrepancy.rivals import RivalTest
from surrogate_rbrdo.discrepancy.search import CandidateFit, fit_nuisance, warm_base
from surrogate_rbrdo.discrepancy.workflow import DiscrepancyOptions
from surrogate_rbrdo.spindle.effects import EFFECTS

from .conftest import campaign_data


def test_candidate_fits_on_two_workers_are_those_of_one_process(spindle):
    """The fits draw no random numbers and share nothing but their inputs, so on two loky
    workers every candidate's parameters and χ² are bit for bit those of the serial loop,
    in the candidates' order."""
    sp, g = spindle
    data, _ = campaign_data(spindle, (EFFECTS["gyroscopics"](g=0.3),), seed=3)
    prob = Problem(ForwardModel(g, sp.effects, data.channels, (0.0, 350.0)), data)
    base = fit_nuisance(prob)
    cands = [candidate(n, prob.forward.bearing_names)
             for n in ("gyroscopics", "unbalance_error", "anisotropy")]
    warm = warm_base(prob, base, max_nfev=60)
    kw = {"max_nfev": 60, "confound_delta": 6.63}
    serial = fit_all(prob, base, cands, warm, n_jobs=1, **kw)
    parallel = fit_all(prob, base, cands, warm, n_jobs=2, **kw)
    assert [f.name for f in parallel] == [c.name for c in cands]
    for a, b in zip(serial, parallel, strict=True):
        assert np.array_equal(a.fit.x, b.fit.x) and a.fit.chi2 == b.fit.chi2
    assert serial[0].delta_chi2 > serial[1].delta_chi2      # the hidden one fits best


def test_n_jobs_is_checked():
    with pytest.raises(ValueError, match="n_jobs = 0"):
        DiscrepancyOptions(n_jobs=0)


@pytest.mark.parametrize("base_p, fit_p, lin, at_bound, fitted", [
    (0.5, 0.5, 100.0, False, {"gyroscopics"}),      # the base looks like noise: the old screen
    (0.001, 0.5, 100.0, False, {"gyroscopics"}),    # the live candidate's fit explains the data
    (0.001, 0.01, 100.0, False, {"gyroscopics", "anisotropy"}),   # it does not: all fitted
    (0.001, 0.5, 100.0, True, {"gyroscopics", "anisotropy"}),     # on a bound: explains nothing
    (0.001, 0.5, 1.0, False, {"gyroscopics", "anisotropy"}),      # none above the fraction
    (0.5, 0.5, 1.0, False, set()),                  # ... in a quiet stage: none fitted
])
def test_a_candidate_far_below_its_threshold_is_fitted_only_while_the_data_are_unexplained(
        monkeypatch, base_p, fit_p, lin, at_bound, fitted):
    """Wiring of naming.run_stage's screen (everything else stubbed): a candidate whose
    first-order statistic is below REFIT_FRACTION of its threshold (anisotropy, 1 against 10)
    is not refitted when the base's residual looks like noise, nor when the best refitted
    candidate's residual does (its gof, structure and generic p-values above QUIET_P); it is
    refitted when a lack-of-fit test fails at both, when the best refitted fit is on a bound
    (it cannot be named), and when no candidate is above the fraction. A candidate above the
    fraction (gyroscopics, 100) is always refitted."""
    cands = tuple(candidate(n, ("front", "rear")) for n in ("gyroscopics", "anisotropy"))
    base = ns(chi2=100.0, evaluation=ns(residuals=np.zeros((1, 3))), par=ns(names=()))

    def fake_fit(problem, b, c, **kw):
        ev = ns(residuals=np.ones((1, 3)))        # a fit's residual: statistics 3.0, base 0.0
        return CandidateFit(c.name, Slot(c, ()), ns(chi2=50.0, evaluation=ev, jac=None,
                                                      par=None, x=None),
                            50.0, {}, {}, at_bound, True)

    tail = ns(isf=lambda p: 10.0, sf=lambda x: 0.5)
    null = ns(p_value=lambda k, v: base_p if v in (0.0, 100.0) else fit_p,
              tails=lambda: [tail, tail], critical_p=lambda a: 0.01, adjusted=lambda p: p)
    for name, value in {
            "linearise": lambda *a: Linearisation(np.zeros((0, 0)), tuple((c, ()) for c in cands),
                                                  (), np.zeros((0, 0))),
            "simulate_null": lambda *a, **k: null,
            "gp_statistic": lambda r, *a: float(r.sum()),
            "generic_statistic": lambda p, lin, r: float(r.sum()),
            "damping_law_columns": lambda *a: None,
            "linear_statistics": lambda *a: np.array([lin, 1.0]),
            "warm_base": lambda *a, **k: None, "fit_candidate": fake_fit,
            "rival_test": lambda *a, **k: RivalTest(0.0, 1.0, "none", 0.0),
            "interior": lambda p, b, cf, d, **k: cf}.items():
        monkeypatch.setattr(naming, name, value)
    stage = naming.run_stage(ns(series=lambda: None, unbalance_design=lambda *a: None), base,
                             cands, ns(chi2=lambda f, p: (0.0, 0.0)), alpha=0.05, n_draws=1,
                             holdout_tolerance=10.83, rng=np.random.default_rng(0),
                             max_nfev=1, confound_delta=6.63)
    assert {a.name for a in stage.assessments if a.fit is not None} == fitted
    assert [a.name for a in stage.assessments] == ["gyroscopics", "anisotropy"]
