"""Blind-test bookkeeping: outcome scoring, rates, strength coordinates; the slow grid."""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy.blind import (
    HIDDEN,
    Context,
    SyntheticSource,
    calibrate,
    rates,
    score,
    separable,
    separable_strength,
)
from surrogate_rbrdo.discrepancy.grid import build_grid, calibrate_grid, confounded_pairs
from surrogate_rbrdo.discrepancy.synthetic import Campaign, NoiseLevel
from surrogate_rbrdo.discrepancy.workflow import DiscrepancyOptions

F = frozenset


@pytest.mark.parametrize("truth, outside, verdict, names, expected", [
    (F(), False, "nothing_missing", (), "nothing"),
    (F(), False, "unnamed_residual", (), "false_alarm"),
    (F(), False, "named", ("housing",), "wrong_name"),
    (F({"housing"}), False, "named", ("housing",), "correct_name"),
    (F({"housing"}), False, "confounded", ("housing", "thermal_preload"),
     "correct_confounded"),
    (F({"housing"}), False, "confounded", ("gyroscopics", "thermal_preload"), "wrong_name"),
    (F({"housing", "anisotropy"}), False, "named", ("housing",), "partial"),
    (F({"housing"}), False, "unnamed_residual", (), "detected_unnamed"),
    (F(), True, "unnamed_residual", (), "detected_unnamed"),
    (F(), True, "named", ("gyroscopics",), "wrong_name"),
])
def test_score(truth, outside, verdict, names, expected):
    assert score(truth, outside, F(), verdict, names) == expected


def test_absorbed_effect_expects_nothing():
    assert score(F({"unbalance_error"}), False, F({"unbalance_error"}), "nothing_missing",
                 ()) == "nothing"
    assert score(F({"unbalance_error"}), False, F({"unbalance_error"}), "named",
                 ("housing",)) == "wrong_name"


def test_rates_and_strength_coordinate():
    rows = [{"class": "a", "strength": "s", "outcome": o} for o in ("nothing", "nothing",
                                                                    "wrong_name")]
    r = rates(rows)[("a", "s")]
    assert r["n"] == 3 and r["nothing"] == pytest.approx(2 / 3)
    h = HIDDEN["housing"]
    assert h.value(1.0) == h.knob_limit and h.value(0.5) > h.value(1.0)   # stiffer = weaker
    assert HIDDEN["disk_mass_error"].value(0.0) == pytest.approx(1.0, abs=1e-5)
    assert confounded_pairs(("a", "b"), np.array([[1, 0.97], [0.97, 1]]),
                            {"a": True, "b": True}) == [("a", "b", 0.97), ("b", "a", 0.97)]


@pytest.mark.slow
@pytest.mark.xfail(reason="issue 16: no wrong name any more (rival test), but one of the two "
                          "synthetic null scenarios (seed 3757552657) is an unnamed residual: "
                          "the generic lack-of-fit test gives p 0.00096 < 0.0033 (measured "
                          "2026-11-24; the rig's nulls pass, docs/discrepancy.md)", strict=False)
def test_blind_grid_small(spindle):
    """A reduced blind grid (synthetic source, one noise level, two seeds): no wrong name, no
    false alarm, strong single effects named or confounded (the full grid with rates:
    benchmarks/discrepancy_blind.py)."""
    from surrogate_rbrdo.discrepancy.blind import run_scenario

    sp, g = spindle
    src = SyntheticSource(Campaign(), {"default": NoiseLevel()},
                          2 * sp.geometry.unbalances[0].magnitude_kgm, (0.0, 350.0))
    ctx = Context(g, sp.effects, src, DiscrepancyOptions(n_draws=200))
    names = ("housing", "cross_coupling", "anisotropy", "shaft_stiffness_loss")
    cal = calibrate_grid(ctx, names, ("default",))
    grid = [sc for sc in build_grid(ctx, cal, ("default",), 2, [])
            if sc.strength in ("strong", "-") and (sc.label == "nothing hidden"
                                                    or sc.label.split(": ")[1] in names)]
    rows = [run_scenario(ctx, sc) for sc in grid]
    wrong = [(r["class"], r["names"]) for r in rows if r["outcome"] == "wrong_name"]
    assert not wrong, wrong
    assert all(r["outcome"] == "nothing" for r in rows if r["class"] == "nothing hidden")
    strong = [r for r in rows if r["class"].startswith("single")]
    assert all(r["outcome"] in ("correct_name", "correct_confounded") for r in strong)


@pytest.mark.parametrize("name, knob, ratio", [
    ("bearing_seal", 4e5, (0.0, 0.05)),      # the rival itself: a passive spring at a node
    ("magnetic_pull", 1e4, (0.0, 0.05)),     # a negative spring at the motor's node
    ("anisotropy", 2.3e-4, (0.99, 1.0)),     # backward whirl: no isotropic change has it
])
def test_separable_strength_known_cases(spindle, name, knob, ratio):
    """A hidden generic change is its own closest rival (nothing separable); an anisotropy's
    first-order signature at 1x is the backward-whirl part, orthogonal to every isotropic
    generic change once the recalibration is refitted (everything separable)."""
    ctx = _synthetic_ctx(spindle)
    z, z_sep, rival = separable_strength(ctx, ((HIDDEN[name], knob),), "default")
    assert z > 5.0                           # visible: the ratio is not about noise
    assert ratio[0] <= z_sep / z <= ratio[1], (z, z_sep, rival)
    if name != "anisotropy":
        assert rival.startswith("grounded spring")


def _synthetic_ctx(spindle):
    sp, g = spindle
    src = SyntheticSource(Campaign(), {"default": NoiseLevel()},
                          2 * sp.geometry.unbalances[0].magnitude_kgm, (0.0, 350.0))
    return Context(g, sp.effects, src, DiscrepancyOptions(n_draws=200))


@pytest.mark.known_answer
def test_calibrating_to_a_separable_strength_where_everything_is_separable(spindle):
    """An anisotropy's signature is all backward whirl, which no isotropic generic change has
    (z_sep ≈ z, the case above): calibrating its knob to z_sep = 8 lands where calibrating to
    z = 8 does."""
    ctx = _synthetic_ctx(spindle)
    k_sep, z_sep = calibrate(ctx, HIDDEN["anisotropy"], 8.0, "default", measure=separable)
    k_z, z = calibrate(ctx, HIDDEN["anisotropy"], 8.0, "default")
    assert abs(z_sep - 8.0) <= 0.4 and abs(z - 8.0) <= 0.4
    assert k_sep == pytest.approx(k_z, rel=0.1)


@pytest.mark.known_answer
def test_a_hidden_generic_change_is_separable_only_far_above_its_visibility(spindle):
    """A seal beside a bearing is its own closest rival (z_sep ≈ 0 while it is linear): only its
    nonlinearity in size separates it, so the knob that makes z_sep = 8 is many times the one
    that makes z = 8 — and ``calibrate`` bisects the measure it is given, not z."""
    ctx = _synthetic_ctx(spindle)
    h = HIDDEN["bearing_seal"]
    k_z, _ = calibrate(ctx, h, 8.0, "default")
    k_sep, z_sep = calibrate(ctx, h, 8.0, "default", measure=separable)
    assert abs(z_sep - 8.0) <= 0.4
    assert k_sep > 5 * k_z
