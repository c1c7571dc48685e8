"""The candidate library is derived from the effects registry; truth-only effects stay out."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy.candidates import (
    DEFAULT_LIBRARY,
    acts_per_bearing,
    candidate,
    library,
)
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.sweeps import Sweep
from surrogate_rbrdo.discrepancy.synthetic import default_channels
from surrogate_rbrdo.discrepancy.truth_effects import TRUTH_MODIFIERS
from surrogate_rbrdo.spindle.effects import (
    EFFECTS,
    Effect,
    Gyroscopics,
    SpeedSoftening,
    Support,
    ToolInterface,
)
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


@dataclass(frozen=True)
class _Mount(Effect):
    """Not registered: a per-bearing support, to test the scope rule on a class of its own."""

    def support(self, bearing: str) -> Support | None:
        return None


@dataclass(frozen=True)
class _Heavier(Effect):
    """Not registered: a gyroscopic change only (no per-bearing hook)."""

    def gyroscopic_scale(self) -> float:
        return 1.1


def test_scopes_only_for_effects_acting_per_bearing():
    for name in ("speed_softening", "thermal_preload", "cross_coupling", "anisotropy",
                 "housing"):
        assert candidate(name, BEARINGS).scopes == ((), ("front",), ("rear",)), name
    for name in ("gyroscopics", "unbalance_error", "tool_interface"):
        assert candidate(name, BEARINGS).scopes == ((),), name
    assert acts_per_bearing(_Mount) and not acts_per_bearing(_Heavier)
    assert not acts_per_bearing(Effect)
    assert candidate("speed_softening", ("front",)).scopes == ((),)


def test_a_scope_changes_only_effects_acting_per_bearing(spindle):
    """The rule's premise, by the forward model: a bearing scope leaves the response of a
    rotor-level effect unchanged and changes a per-bearing one's."""
    sp, g = spindle
    fm = ForwardModel(g, sp.effects, default_channels(g), (0.0, 350.0))
    sw = Sweep.unbalance(np.linspace(3000.0, 22000.0, 5))

    def resp(e):
        return fm.response(sw, np.ones((1, 2)), np.ones((1, 2)), [(e,)])[0]

    for e in (Gyroscopics(g=0.4), ToolInterface(k_t_N_per_m=2e8, k_r_Nm_per_rad=2e5)):
        np.testing.assert_array_equal(resp(e), resp(replace(e, bearings=("front",))))
    soft = SpeedSoftening(a=0.3)
    assert np.max(np.abs(resp(soft) - resp(replace(soft, bearings=("front",))))) > 1e-3 * (
        np.max(np.abs(resp(soft))))
