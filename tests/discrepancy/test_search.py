"""The candidate search's global part (the continuation in the data: 1x-only fits and the 1x
valley) and when a stage runs it: skipped when a local fit already explains the data, run — and
finding the truth — when the local fit sits in a wrong well."""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy import naming
from surrogate_rbrdo.discrepancy.calibration import linearise, simulate_null
from surrogate_rbrdo.discrepancy.candidates import library
from surrogate_rbrdo.discrepancy.fit import fit
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.holdout import split_speeds
from surrogate_rbrdo.discrepancy.search import describe, fit_candidate, fit_valley, warm_base
from surrogate_rbrdo.discrepancy.workflow import DiscrepancyOptions, _recalibrate
from surrogate_rbrdo.spindle.effects import HousingFlexibility

from .conftest import campaign_data

#: the hidden housing stage (the truth the fits must recover)
K_TRUE, M_TRUE = 2e9, 20.0
OPT = DiscrepancyOptions(n_draws=150)


@pytest.fixture(scope="module")
def stage(spindle):
    """The recalibrated baseline on data with a hidden housing stage (1x and impact FRFs), the
    stage's null distribution and the 1x-only recalibration."""
    sp, g = spindle
    data, _ = campaign_data(spindle, (HousingFlexibility(k_N_per_m=K_TRUE, m_kg=M_TRUE),),
                            seed=2)
    one_x = next(b for b in data.blocks if b.sweep.kind == "unbalance_1x")
    split = split_speeds(one_x.mean.shape[0], OPT.holdout_every, OPT.extrapolate_fraction)
    fm = ForwardModel(g, sp.effects, data.channels, tuple(u.position_mm for u in g.unbalances),
                      None, OPT.nuisance.mass_disks)
    train, ho, _, base, _ = _recalibrate(fm, data, split, OPT)
    cands = {c.name: c for c in library(OPT.library, fm.bearing_names)}
    lin = linearise(train, base, (cands["housing"],))
    null = simulate_null(train, lin, n_draws=OPT.n_draws, rng=np.random.default_rng(0))
    return train, ho, base, cands, lin, null, warm_base(train, base)


@pytest.mark.known_answer
def test_a_local_fit_at_the_truth_explains_the_data_and_the_base_does_not(stage):
    train, _, base, cands, lin, null, warm = stage
    cf = fit_candidate(train, base, cands["housing"], warm=warm)
    assert cf.parameters["k_N_per_m"] == pytest.approx(K_TRUE, rel=0.01)
    assert cf.parameters["m_kg"] == pytest.approx(M_TRUE, rel=0.01)
    assert naming.explains(train, lin, null, cf.fit)
    assert not naming.explains(train, lin, null, base)


@pytest.mark.known_answer
def test_the_valley_finds_the_truth_from_a_wrong_well(stage):
    train, _, base, cands, lin, null, warm = stage
    c = cands["housing"]
    cf = fit_candidate(train, base, c, warm=warm)
    # a local fit started ten times too heavy on the 1x valley (same k/m) stays in a wrong well
    lab, par = cf.slot.label, cf.fit.par
    x0 = par.x0({f"{lab}.m_kg": 10 * M_TRUE, f"{lab}.k_N_per_m": 1 / (10 * K_TRUE),
                 f"{lab}.c_Ns_per_m": 0.0})
    x0[:base.x.size] = base.x
    wrong = describe(c, cf.slot, fit(train, par, x0), base.chi2)       # no 1x fit yet
    assert not naming.explains(train, lin, null, wrong.fit)
    assert abs(wrong.parameters["m_kg"] - M_TRUE) > 0.5 * M_TRUE
    found = fit_valley(train, base, wrong, warm)
    assert found.parameters["k_N_per_m"] == pytest.approx(K_TRUE, rel=0.01)
    assert found.parameters["m_kg"] == pytest.approx(M_TRUE, rel=0.01)
    assert found.fit.chi2 < wrong.fit.chi2 / 100


def _count_valleys(monkeypatch) -> list:
    """Names of the candidates continued (fit_valley), "warm_base" for each 1x-only
    recalibration."""
    calls = []

    def counted(*a, **k):
        calls.append(a[2].name)
        return fit_valley(*a, **k)

    def counted_base(*a, **k):
        calls.append("warm_base")
        return warm_base(*a, **k)

    monkeypatch.setattr(naming, "fit_valley", counted)
    monkeypatch.setattr(naming, "warm_base", counted_base)
    return calls


def _run(stage, names):
    train, ho, base, cands, *_ = stage
    return naming.run_stage(train, base, tuple(cands[n] for n in names), ho, alpha=OPT.alpha,
                            n_draws=OPT.n_draws, holdout_tolerance=OPT.holdout_tolerance,
                            rng=np.random.default_rng(1), max_nfev=OPT.max_nfev,
                            confound_delta=OPT.confound_delta)


def test_a_stage_skips_the_continuation_when_a_local_fit_explains_the_data(stage, monkeypatch):
    calls = _count_valleys(monkeypatch)
    st = _run(stage, ("housing", "speed_softening"))
    assert calls == []
    best = min((a for a in st.assessments if a.fit is not None), key=lambda a: a.fit.fit.chi2)
    assert best.name == "housing"


def test_a_stage_runs_the_continuation_when_no_local_fit_explains_the_data(stage, monkeypatch):
    calls = _count_valleys(monkeypatch)
    _run(stage, ("speed_softening", "thermal_preload"))
    assert sorted(calls) == ["speed_softening", "thermal_preload", "warm_base"]
