"""The truth's variability model: what is drawn, at which level, with which statistics."""

import numpy as np
import pytest

from surrogate_rbrdo.rig.truth import Truth, Variability, reference_truth
from surrogate_rbrdo.spindle.effects import CrossCoupling


def test_levels_are_nested_and_reproducible():
    tr = reference_truth()
    ss = np.random.SeedSequence(11)
    a = tr.state(ss, build=0, tool=0, run=0)
    b = tr.state(ss, build=0, tool=0, run=1)
    c = tr.state(ss, build=1, tool=0, run=0)
    assert a.draws["build"] == b.draws["build"] and a.draws["run"] != b.draws["run"]
    assert a.draws["build"] != c.draws["build"]
    again = tr.state(np.random.SeedSequence(11), build=0, tool=0, run=1)
    assert again.draws == b.draws


def test_draw_statistics_match_the_variability_model():
    v = Variability(bearing_k_cov=0.05, thermal_preload_cov=0.08)
    tr = reference_truth(variability=v)
    ss = np.random.SeedSequence(2)
    k = np.array([tr.draw_build(np.random.SeedSequence(i))["k_factor"] for i in range(3000)])
    assert np.allclose(k.mean(0), 1.0, atol=0.005)
    assert np.allclose(k.std(0), 0.05, rtol=0.08)
    th = np.array([tr.state(ss, build=0, tool=0, run=r).theta[0] for r in range(1500)])
    # per run only the thermal preload varies: k ∝ F^{1/3}, CoV ≈ 0.08 / 3
    assert np.allclose(np.std(np.log(th), axis=0), np.sqrt(np.log1p(0.08**2)) / 3, rtol=0.1)
    U = np.array([tr.draw_build(np.random.SeedSequence(i))["unbalance_kgm"]
                  for i in range(500)])
    per_plane = tr.permissible_unbalance_kgm() / 2
    assert U.max() <= per_plane and U.min() >= 0.25 * per_plane


def test_hidden_effects_reach_the_model():
    tr = reference_truth(hidden=[{"name": "cross_coupling", "kappa": 0.1}])
    st = tr.state(np.random.SeedSequence(0), build=0, tool=0, run=0)
    assert any(isinstance(e, CrossCoupling) and e.kappa == 0.1 for e in st.model().effects)
    assert tr.describe()["hidden"] == [{"name": "cross_coupling", "kappa": 0.1,
                                        "bearings": []}]


def test_bad_variability_names_the_field():
    with pytest.raises(ValueError, match="variability.bearing_k_cov"):
        Variability(bearing_k_cov=-0.1)
    with pytest.raises(ValueError, match="unbalance"):
        Truth(reference_truth().geometry.__class__.from_dict({
            "sections": [{"length_mm": 100, "outer_diameter_mm": 50}],
            "bearings": [{"name": "a", "position_mm": 0,
                          "law": {"type": "constant", "k_N_per_m": 1e8}}]}))
