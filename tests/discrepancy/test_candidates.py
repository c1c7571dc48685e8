"""The candidate library is derived from the effects registry; truth-only effects stay out."""

from __future__ import annotations

import math

import pytest

from surrogate_rbrdo.discrepancy.candidates import DEFAULT_LIBRARY, candidate, library
from surrogate_rbrdo.discrepancy.truth_effects import TRUTH_MODIFIERS
from surrogate_rbrdo.spindle.effects import EFFECTS
from surrogate_rbrdo.spindle.reference import reference_spindle

BEARINGS = ("front", "rear")


@pytest.mark.parametrize("name", DEFAULT_LIBRARY)
def test_every_candidate_has_an_off_state_that_builds(name):
    c = candidate(name, BEARINGS)
    vals = dict(zip(c.strength, c.off, strict=True))
    vals.update({p: s[0] for p, s in zip(c.shape, c.shape_starts, strict=True)})
    assert c.effect((), vals).is_off
    assert all(lo <= o <= hi for o, lo, hi in zip(c.off, c.lower, c.upper, strict=True))


def test_strength_sides_and_reciprocals_follow_the_registry():
    soft = candidate("speed_softening", BEARINGS)
    assert soft.one_sided == (True,) and soft.shape == ("exponent",)
    cc = candidate("cross_coupling", BEARINGS)
    assert cc.one_sided == (False,) and cc.scopes == ((), ("front",), ("rear",))
    h = candidate("housing", BEARINGS)
    assert h.reciprocal == (True,) and h.upper == (1.0 / EFFECTS["housing"].bounds[
        "k_N_per_m"][0],)
    e = h.effect((), {"k_N_per_m": 0.0, "m_kg": 5.0, "c_Ns_per_m": 0.0})
    assert math.isinf(e.k_N_per_m)
    assert candidate("unbalance_error", BEARINGS).strength == ("epsilon", "delta_deg")


def test_library_names_are_registered_and_truth_only_effects_are_not():
    assert set(DEFAULT_LIBRARY) <= set(EFFECTS)
    assert not set(TRUTH_MODIFIERS) & set(EFFECTS)
    assert not set(TRUTH_MODIFIERS) & set(DEFAULT_LIBRARY)
    with pytest.raises(ValueError, match="unknown effect"):
        library(("no_such_effect",), BEARINGS)
    with pytest.raises(ValueError, match="twice"):
        library(("housing", "housing"), BEARINGS)


def test_bearing_seal_off_the_shaft_names_its_offset():
    sp = reference_spindle()
    g = sp.geometry_for(sp.baseline)
    with pytest.raises(ValueError, match=r"bearing_seal.offset_mm = -500.0 .* -400.0 mm"):
        TRUTH_MODIFIERS["bearing_seal"](g, k_N_per_m=1e7, offset_mm=-500.0)
