"""The workflow end to end on small virtual campaigns: silent when nothing is missing, names a
strong hidden housing stage and shrinks the gap, never names a library effect for a strong
effect outside the library; the run folder a study can load."""

from __future__ import annotations

import json
import tomllib
from dataclasses import replace

import numpy as np
import pytest

from surrogate_rbrdo.core.schema import parse
from surrogate_rbrdo.discrepancy.report import findings, write_run
from surrogate_rbrdo.discrepancy.search import slot_estimate
from surrogate_rbrdo.discrepancy.truth_effects import TRUTH_MODIFIERS
from surrogate_rbrdo.discrepancy.workflow import (
    DiscrepancyOptions,
    _drop_thin_impacts,
    find_discrepancy,
)
from surrogate_rbrdo.spindle.config import SpindleTable, build_spindle
from surrogate_rbrdo.spindle.effects import HousingFlexibility

from .conftest import SMALL, campaign_data

FAST = DiscrepancyOptions(n_draws=150)


@pytest.fixture(scope="module")
def housing_result(spindle):
    sp, g = spindle
    data, _ = campaign_data(spindle, (HousingFlexibility(k_N_per_m=2e9, m_kg=20.0),), seed=2)
    return find_discrepancy(data, g, sp.effects, options=FAST, rng=np.random.default_rng(0))


def test_nothing_missing_when_nothing_is_hidden(spindle):
    sp, g = spindle
    data, _ = campaign_data(spindle, seed=11)
    res = find_discrepancy(data, g, sp.effects, options=FAST, rng=np.random.default_rng(0))
    assert res.verdict == "nothing_missing"
    assert res.test["p_value"] > res.test["threshold"]
    assert res.gap_after == res.gap_before


def test_hidden_housing_is_named_with_its_parameters(housing_result):
    res = housing_result
    assert res.verdict == "named" and [a.name for a in res.effects] == ["housing"]
    p, ci = res.effects[0].fit.parameters, res.effects[0].fit.ci
    assert ci["k_N_per_m"][0] < 2e9 < ci["k_N_per_m"][1]
    assert ci["m_kg"][0] < 20.0 < ci["m_kg"][1]
    assert p["k_N_per_m"] == pytest.approx(2e9, rel=0.01)
    # the gap shrinks on held-out speeds (interleaved and extrapolated) to about the noise
    assert res.gap_after.chi2_dof < 3.0 < res.gap_before.chi2_dof / 10
    assert res.gap_after.rmse < res.gap_before.rmse / 5


@pytest.mark.slow
def test_outside_library_effect_is_never_given_a_library_name(spindle):
    sp, g = spindle
    geo = TRUTH_MODIFIERS["shaft_stiffness_loss"](g, position_mm=250.0, depth=0.3)
    data, _ = campaign_data(spindle, seed=5, geometry=geo)
    res = find_discrepancy(data, g, sp.effects, options=FAST, rng=np.random.default_rng(0))
    assert res.verdict in ("unnamed_residual", "nothing_missing")
    assert not res.effects
    if res.verdict == "unnamed_residual":       # the GP correction closes part of the gap
        assert res.gap_after.chi2_dof < res.gap_before.chi2_dof


def test_findings_and_updated_spindle_load_back(housing_result, spindle, tmp_path):
    sp, _ = spindle
    section = {"geometry": "reference", "baseline": [2000.0, 500.0, 65.0]}
    paths = write_run(housing_result, tmp_path, spindle_section=section,
                      model_effects=sp.effects)
    f = json.loads(paths["findings"].read_text())
    assert f["verdict"] == "named" and f["effects"][0]["name"] == "housing"
    assert set(f["test"]) >= {"statistic", "p_value", "threshold"}
    keys = {"rmse", "max_abs", "chi2_dof", "predictive_chi2_dof"}
    assert set(f["gap"]["before"]) == set(f["gap"]["after"]) == keys | {"interleaved",
                                                                       "extrapolated"}
    assert set(f["gap"]["after"]["extrapolated"]) == keys
    # the named housing predicts the held-out speeds within its uncertainty, the base not
    assert f["gap"]["after"]["predictive_chi2_dof"] < 3.0 < f["gap"]["before"][
        "predictive_chi2_dof"]
    assert set(f["effects"][0]["ci"]) == {"k_N_per_m", "m_kg", "c_Ns_per_m"}
    table = tomllib.loads(paths["spindle"].read_text())["spindle"]
    updated = build_spindle(parse(SpindleTable, table, "spindle"))
    assert [e.name for e in updated.effects][-1] == "housing"
    assert updated.effects[-1].k_N_per_m == pytest.approx(
        housing_result.effects[0].fit.parameters["k_N_per_m"])
    assert json.loads(json.dumps(findings(housing_result))) == f


@pytest.mark.known_answer
def test_written_spindle_and_findings_carry_the_final_joint_fit(housing_result, spindle,
                                                                  tmp_path):
    """Regression: findings.json reported an effect's fit from the stage that named it while
    spindle_updated.toml carried the final joint fit (refitted with later effects). Here the
    final fit's housing compliance is set apart from the stage fit's: both files must carry
    the final one (known answer: the value put in)."""
    sp, _ = spindle
    res = housing_result
    final = res.final
    k = final.par.n_nuisance                         # the housing slot's compliance (1/k)
    x = final.x.copy()
    x[k] *= 1.25
    moved = replace(res, final=replace(final, x=x))
    k_final = 1.0 / x[k]
    assert k_final != pytest.approx(res.effects[0].fit.parameters["k_N_per_m"], rel=0.1)
    section = {"geometry": "reference", "baseline": [2000.0, 500.0, 65.0]}
    paths = write_run(moved, tmp_path, spindle_section=section, model_effects=sp.effects)
    f = json.loads(paths["findings"].read_text())
    assert f["effects"][0]["parameters"]["k_N_per_m"] == pytest.approx(k_final, rel=1e-12)
    assert f["updated_effects"][0]["parameters"]["k_N_per_m"] == pytest.approx(k_final,
                                                                                rel=1e-12)
    assert f["effects"][0]["parameters_when_named"]["k_N_per_m"] == pytest.approx(
        res.effects[0].fit.parameters["k_N_per_m"])
    table = tomllib.loads(paths["spindle"].read_text())["spindle"]
    assert table["effects"][-1]["name"] == "housing"
    assert table["effects"][-1]["k_N_per_m"] == pytest.approx(k_final, rel=1e-12)
    for p in ("m_kg", "c_Ns_per_m"):
        assert table["effects"][-1][p] == pytest.approx(f["effects"][0]["parameters"][p])


@pytest.mark.known_answer
@pytest.mark.parametrize("seen", [1e-4, 0.0])
def test_a_strength_the_data_barely_see_is_reported_unidentified(housing_result, seen):
    """Known answer: scaling the Jacobian column of the housing compliance by ``seen`` scales
    its Wald half-width by ``1/seen`` (unbounded at 0), so the interval contains the rigid
    housing: the stiffness is reported unidentified with no interval, never as a bound."""
    final = housing_result.final
    k = final.par.n_nuisance
    e = slot_estimate(final, 0)
    assert e.identified["k_N_per_m"] and e.ci["k_N_per_m"] is not None
    jac = final.jac.copy()
    jac[:, k] *= seen
    blind = slot_estimate(replace(final, jac=jac), 0)
    assert blind.identified == {**e.identified, "k_N_per_m": False}
    assert blind.ci["k_N_per_m"] is None
    assert blind.parameters == e.parameters


def test_impact_blocks_with_too_few_hits_are_left_out_and_reported(spindle):
    """5 hits give a covariance with 4 degrees of freedom, under ``min_impact_dof = 9``: the
    impact blocks are left out with a warning naming them, and kept from 10 hits on."""
    five = replace(SMALL, impact_repeats=5)
    data, _ = campaign_data(spindle, seed=3, campaign=five)
    impacts = [b.name for b in data.blocks if b.sweep.kind == "impact"]
    with pytest.warns(UserWarning, match="min_impact_dof = 9"):
        kept, dropped = _drop_thin_impacts(data, 9)
    assert impacts and dropped == tuple((n, 4) for n in impacts)
    assert all(b.sweep.kind != "impact" for b in kept.blocks)
    ten, _ = campaign_data(spindle, seed=3)
    assert _drop_thin_impacts(ten, 9)[1] == ()


def test_findings_list_the_dropped_impact_blocks(housing_result):
    assert findings(housing_result)["dropped_impact_blocks"] == []
    res = replace(housing_result, dropped_blocks=(("impact_tool_x", 4),))
    assert findings(res)["dropped_impact_blocks"] == [{"name": "impact_tool_x", "dof": 4}]
