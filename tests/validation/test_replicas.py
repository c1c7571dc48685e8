"""Paired replications on the rig's truth: what a pair shares, what each replication redraws."""

import numpy as np
import pytest

from surrogate_rbrdo.rig.truth import reference_truth
from surrogate_rbrdo.validation.replicas import (
    SHARE_GROUPS,
    TruthFamily,
    reference_family,
    replica_states,
)

XS = {"a": [2000.0, 500.0, 65.0], "b": [3000.0, 400.0, 70.0]}


def _draw(st, level, key):
    return st.draws[level][key]


def test_share_groups_cover_every_draw_of_the_truth():
    st = reference_truth().state(np.random.SeedSequence(0), build=0, tool=0, run=0)
    drawn = {(lvl, k) for lvl, d in st.draws.items() for k in d}
    grouped = {(lvl, k) for lvl, keys in SHARE_GROUPS.values() for k in keys}
    assert drawn == grouped


def test_default_pairing_shares_bearings_tool_thermal_only():
    st = replica_states(reference_family(), XS, 3, seed=np.random.SeedSequence(1))
    for r in range(3):
        a, b = st["a"][r], st["b"][r]
        for lvl, key in [("build", "k_factor"), ("build", "damping_factor"),
                         ("tool", "mass_factor"), ("run", "preload_factor")]:
            assert _draw(a, lvl, key) == _draw(b, lvl, key)
        for lvl, key in [("build", "unbalance_phase_deg"), ("tool", "interface_factor")]:
            assert _draw(a, lvl, key) != _draw(b, lvl, key)
    # replications differ from each other at every level
    assert _draw(st["a"][0], "build", "k_factor") != _draw(st["a"][1], "build", "k_factor")
    assert _draw(st["a"][0], "run", "preload_factor") != _draw(st["a"][1], "run",
                                                                "preload_factor")


def test_shared_unbalance_is_the_same_fraction_of_each_rotors_permissible_value():
    fam = reference_family()
    st = replica_states(fam, XS, 2, seed=np.random.SeedSequence(2),
                        shared=tuple(SHARE_GROUPS))
    ua = np.array(_draw(st["a"][0], "build", "unbalance_kgm"))
    ub = np.array(_draw(st["b"][0], "build", "unbalance_kgm"))
    u_perm = {k: fam.at(x).permissible_unbalance_kgm() for k, x in XS.items()}
    ratio = u_perm["b"] / u_perm["a"]
    np.testing.assert_allclose(ub / ua, ratio, rtol=1e-12)
    assert _draw(st["a"][0], "build", "unbalance_phase_deg") == \
        _draw(st["b"][0], "build", "unbalance_phase_deg")


def test_nothing_shared_and_replicate_only_runs():
    st = replica_states(reference_family(), XS, 3, seed=np.random.SeedSequence(3), shared=(),
                        replicate=("run",))
    assert _draw(st["a"][0], "build", "k_factor") != _draw(st["b"][0], "build", "k_factor")
    # one build and one tool for all replications of a design; new thermal state each time
    assert _draw(st["a"][0], "build", "k_factor") == _draw(st["a"][2], "build", "k_factor")
    assert _draw(st["a"][0], "tool", "mass_factor") == _draw(st["a"][2], "tool", "mass_factor")
    assert _draw(st["a"][0], "run", "preload_factor") != _draw(st["a"][2], "run",
                                                                "preload_factor")


def test_same_seed_same_spindles_and_geometry_follows_x():
    fam = reference_family()
    s1 = replica_states(fam, XS, 2, seed=np.random.SeedSequence(4))
    s2 = replica_states(fam, XS, 2, seed=np.random.SeedSequence(4))
    assert s1["b"][1].draws == s2["b"][1].draws
    assert s1["a"][0].geometry.bearings[0].law.preload_N == pytest.approx(2000.0)
    assert s1["b"][0].geometry.bearings[0].law.preload_N == pytest.approx(3000.0)


def test_bad_input():
    fam = reference_family()
    with pytest.raises(ValueError, match="span_mm"):
        fam.at([2000.0, 900.0, 65.0])
    with pytest.raises(ValueError, match="shared"):
        replica_states(fam, XS, 2, seed=np.random.SeedSequence(0), shared=("bearing",))
    with pytest.raises(ValueError, match="appears twice"):
        replica_states(fam, XS, 2, seed=np.random.SeedSequence(0), replicate=("run", "run"))
    assert isinstance(fam, TruthFamily)
