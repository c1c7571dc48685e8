"""Bad input (issue 2, §6): each raises ValueError naming the field and the value; and the
design map's known geometric answers."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from surrogate_rbrdo.spindle.geometry import DesignMap, SpindleGeometry
from surrogate_rbrdo.spindle.reference import reference_spindle

from .conftest import constant_bearing

BASE = {
    "sections": [{"length_mm": 100.0, "outer_diameter_mm": 50.0, "elements": 4}],
    "bearings": [constant_bearing("a", 0.0, 1e8), constant_bearing("b", 100.0, 1e8)],
    "disks": [{"name": "d", "position_mm": 50.0, "mass_kg": 1.0}],
}


def with_(path, value):
    """BASE with one entry replaced: ``path`` is a tuple of keys/indices."""
    d = copy.deepcopy(BASE)
    target = d
    for p in path[:-1]:
        target = target[p]
    target[path[-1]] = value
    return d


@pytest.mark.parametrize(
    ("path", "value", "match"),
    [
        (("sections", 0, "length_mm"), 0.0, r"sections\[0\]\.length_mm = 0\.0"),
        (("sections", 0, "length_mm"), -5.0, r"sections\[0\]\.length_mm = -5\.0"),
        (("sections", 0, "outer_diameter_mm"), 0.0, r"sections\[0\]\.outer_diameter_mm = 0\.0"),
        (("sections", 0, "outer_diameter_mm"), -50.0,
         r"sections\[0\]\.outer_diameter_mm = -50\.0"),
        (("sections", 0, "inner_diameter_mm"), -1.0, r"sections\[0\]\.inner_diameter_mm = -1\.0"),
        (("sections", 0, "inner_diameter_mm"), 50.0,
         r"sections\[0\]\.inner_diameter_mm = 50\.0 .*outer_diameter_mm = 50\.0"),
        (("sections", 0, "inner_diameter_mm"), 60.0, r"sections\[0\]\.inner_diameter_mm = 60\.0"),
        (("sections", 0, "elements"), 0, r"sections\[0\]\.elements = 0"),
        (("sections", 0, "elements"), 4.0, r"sections\[0\]\.elements = 4\.0 .*an integer"),
        (("sections", 0, "elements"), 10 ** 6, r"sections\[0\]\.elements = 1000000 .*more than"),
        (("sections", 0, "length_mm"), "100", r"sections\[0\]\.length_mm = '100' .*a number"),
        (("sections",), "abc", r"sections = 'abc' is not allowed: must be an array of tables"),
        (("sections", 0), [100.0, 50.0], r"sections\[0\] = \[100\.0, 50\.0\] .*a table"),
        (("bearings", 1, "position_mm"), 120.0,
         r"bearings\[1\]\.position_mm = 120\.0 .*\[0, 100\.0\]"),
        (("bearings", 0, "position_mm"), -1.0, r"bearings\[0\]\.position_mm = -1\.0"),
        (("bearings", 1, "name"), 7, r"bearings\[1\]\.name = 7 .*a string"),
        (("bearings", 1, "name"), "a", r"bearings\[1\]\.name = 'a' .*unique"),
        (("bearings",), {"a": 1}, r"bearings = \{'a': 1\} .*an array of tables"),
        (("disks", 0, "position_mm"), 101.0, r"disks\[0\]\.position_mm = 101\.0"),
        (("disks", 0, "mass_kg"), 0.0, r"disks\[0\]\.mass_kg = 0\.0"),
        (("bearings", 0, "law", "k_N_per_m"), -1e8,
         r"bearings\[0\]\.law\.k_N_per_m = -100000000\.0"),
        (("bearings", 0, "law", "k_N_per_m"), "1e8", r"bearings\[0\]\.law\.k_N_per_m = '1e8'"),
        (("bearings", 0, "law"), "constant", r"bearings\[0\]\.law = 'constant' .*a table"),
        (("bearings", 0, "law", "type"), "magnetic", r"bearings\[0\]\.law\.type = 'magnetic'"),
        (("max_element_length_mm",), 1e-6, r"max_element_length_mm = 1e-06 .*finite elements"),
        (("tool_tip_mm",), 150.0, r"tool_tip_mm = 150\.0"),
        (("speed_max_rpm",), 500.0, r"speed_max_rpm = 500\.0 .*speed_min_rpm = 1000\.0"),
        (("speed_min_rpm",), 0.0, r"speed_min_rpm = 0\.0"),
        (("bearings",), [], r"bearings = \[\]"),
        (("sections",), [], r"sections = \[\]"),
        (("sections", 0, "material"), "unobtainium",
         r"sections\[0\]\.material = 'unobtainium'"),
        (("materials",), {"steel": {"E_Pa": -1.0}}, r"materials\.steel\.E_Pa = -1\.0"),
        (("materials",), {"steel": {"nu": 0.6}}, r"materials\.steel\.nu = 0\.6"),
    ],
)
def test_bad_geometry_values_raise(path, value, match):
    with pytest.raises(ValueError, match=match):
        SpindleGeometry.from_dict(with_(path, value))


@pytest.mark.parametrize(
    ("path", "where"),
    [((), r""), (("sections", 0), r"sections\[0\]\."), (("disks", 0), r"disks\[0\]\."),
     (("bearings", 0), r"bearings\[0\]\."), (("bearings", 0, "law"), r"bearings\[0\]\.law\.")],
)
def test_unknown_keys_raise_at_every_level(path, where):
    d = copy.deepcopy(BASE)
    target = d
    for p in path:
        target = target[p]
    target["lenght_mm"] = 1.0
    with pytest.raises(ValueError, match=rf"^unknown key {where}lenght_mm; allowed: \["):
        SpindleGeometry.from_dict(d)


def test_unknown_material_key_raises():
    with pytest.raises(ValueError, match=r"unknown key materials\.steel\.E; allowed"):
        SpindleGeometry.from_dict({**BASE, "materials": {"steel": {"E": 2e11}}})


def test_constant_law_needs_exactly_one_stiffness():
    d = with_(("bearings", 0, "law", "k_matrix_N_per_m"), [[1e8, 0.0], [0.0, 1e8]])
    with pytest.raises(ValueError, match="exactly one of k_N_per_m or k_matrix_N_per_m"):
        SpindleGeometry.from_dict(d)


@pytest.mark.parametrize(
    ("x", "match"),
    [((2000.0, 800.0, 65.0), r"design span_mm = 800\.0 is not allowed.*\[300\.0, 750\.0\]"),
     ((999.0, 500.0, 65.0), r"design preload_N = 999\.0"),
     ((2000.0, 500.0, 80.5), r"design diameter_mm = 80\.5"),
     ((2000.0, 500.0, np.nan), r"design diameter_mm = nan"),
     ((2000.0, 500.0), r"design vector has shape \(2,\)")],
)
def test_design_vector_outside_bounds_raises(x, match):
    with pytest.raises(ValueError, match=match):
        DesignMap().check(np.array(x))


def test_batch_check_names_the_first_bad_design_and_preloads_come_from_x():
    dm = DesignMap()
    X = np.array([[2000.0, 500.0, 65.0], [2000.0, 800.0, 65.0], [999.0, 500.0, 65.0]])
    with pytest.raises(ValueError, match=r"design span_mm = 800\.0 is not allowed"):
        dm.check_batch(X)
    with pytest.raises(ValueError, match=r"design preload_N = 999\.0"):
        dm.bearing_preloads(X[[0, 2]])
    with pytest.raises(ValueError, match=r"designs have shape \(2,\)"):
        dm.check_batch(np.array([2000.0, 500.0]))
    good = np.array([[1500.0, 400.0, 60.0], [2500.0, 700.0, 79.0]])
    pre = dm.bearing_preloads(good)
    assert list(pre) == ["front"]
    np.testing.assert_array_equal(pre["front"], [1500.0, 2500.0])
    # the geometry of each design has exactly this preload on that bearing
    sp = reference_spindle()
    for x, p in zip(good, pre["front"], strict=True):
        law = {b.name: b.law for b in dm.apply(sp.geometry, x).bearings}["front"]
        assert law.preload_N == p


def test_design_map_bounds_must_be_ordered():
    with pytest.raises(ValueError, match=r"design bounds for span_mm = \[750\.0, 300\.0\]"):
        DesignMap(lower=(1000.0, 750.0, 50.0), upper=(3000.0, 300.0, 80.0))


@pytest.mark.known_answer
def test_design_map_places_the_span_exactly():
    """x = [F, L, D]: the rear bearing sits at nose + L, later items shift by ΔL, the span
    sections get diameter D, the front bearing's preload is F."""
    sp = reference_spindle()
    base = sp.geometry
    for L, D, F in ((300.0, 50.0, 1000.0), (750.0, 80.0, 3000.0)):
        g = sp.geometry_for([F, L, D])
        span = [s for s in g.sections if s.tag == "span"]
        assert sum(s.length_mm for s in span) == pytest.approx(L)
        assert all(s.outer_diameter_mm == D for s in span)
        assert g.bearing("front").law.preload_N == F
        assert g.bearing("front").position_mm == base.bearing("front").position_mm
        assert g.bearing("rear").position_mm == pytest.approx(100.0 + L)
        assert g.total_length_mm == pytest.approx(base.total_length_mm + L - 500.0)
        rear_unit = [d for d in g.disks if d.name == "rear_unit"][0]
        assert rear_unit.position_mm == pytest.approx(680.0 + L - 500.0)
        motor = [d for d in g.disks if d.name == "motor_rotor"][0]  # inside the span: scales
        assert motor.position_mm == pytest.approx(100.0 + (350.0 - 100.0) * L / 500.0)


def test_to_dict_round_trip():
    g = reference_spindle().geometry
    assert SpindleGeometry.from_dict(g.to_dict()) == g
