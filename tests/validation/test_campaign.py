"""validate_designs end to end on the reference truth: files, formats, determinism, bad input."""

import csv
from dataclasses import replace

import numpy as np
import pytest

from surrogate_rbrdo.reporting.plots_validation import write_validation_report
from surrogate_rbrdo.rig.campaign import read_phasors
from surrogate_rbrdo.rig.sensors import SensorSet
from surrogate_rbrdo.spindle.harmonic import PeakOptions
from surrogate_rbrdo.spindle.reference import reference_spindle
from surrogate_rbrdo.uncertainty import MultivariateNormal
from surrogate_rbrdo.validation import (
    ValidationOptions,
    reference_family,
    spindle_model_spec,
    validate_designs,
)

DESIGNS = {"base": [2000.0, 500.0, 65.0], "opt": [3000.0, 350.0, 75.0]}
FAST = ValidationOptions(n_replications=6, ramps=1, ramp_rpm=(19000.0, 24000.0), ramp_s=2.0,
                         n_boot=300, band_samples=10, campbell_speeds=6,
                         speeds_rpm={"start": 1000, "stop": 24000, "step": 2000},
                         peak=PeakOptions(n_grid=16, n_candidates=2, n_refine=7, n_zoom=3))


@pytest.fixture(scope="module")
def result():
    spec = spindle_model_spec(reference_spindle(),
                              MultivariateNormal(np.ones(2), std=[0.015, 0.033]), n_samples=40)
    return validate_designs(reference_family(), DESIGNS, options=FAST,
                            rng=np.random.default_rng(3), model=spec)


def test_result_shapes_and_order(result):
    assert result.baseline == "base"
    assert [d.name for d in result.designs] == ["base", "opt"]
    d = result.design("opt")
    S, P = len(FAST.speeds_rpm), len(result.channels)
    assert d.curve.shape == (6, S) and d.phasors.shape == (6, S, P)
    assert d.peak.shape == d.rated.shape == (6,)
    assert [c.quantity for c in result.comparisons] == ["peak", "rated"]
    assert len(result.verdicts) == 2 * 2 * 3
    assert all(0 <= v.p_value <= v.p_holm <= 1 for v in result.verdicts)
    # the baseline's first bending critical speed (~21 800 rpm) is seen in its ramps
    assert any(19000 < c.speed_rpm < 24000 for c in result.design("base").criticals)


def test_same_seed_same_measurement_and_other_seed_differs(result):
    seen = []
    again = validate_designs(reference_family(), DESIGNS, options=replace(FAST, ramps=0),
                             rng=np.random.default_rng(3),
                             progress=lambda k, n, label: seen.append((k, n)))
    np.testing.assert_array_equal(again.design("base").peak, result.design("base").peak)
    assert seen[0] == (1, 12) and seen[-1] == (12, 12)
    other = validate_designs(reference_family(), DESIGNS, options=replace(FAST, ramps=0),
                             rng=np.random.default_rng(4))
    assert not np.allclose(other.design("base").peak, result.design("base").peak)


def test_written_report(result, tmp_path):
    paths = write_validation_report(result, tmp_path)
    for name in ("table7", "measured", "model_vs_measured", "replications", "critical_speeds",
                 "curves", "summary", "fig8_response", "fig7_campbell", "markdown"):
        assert paths[name].is_file(), name
    with open(paths["table7"]) as fh:
        rows = list(csv.DictReader(fh))
    assert [r["metric"] for r in rows] == ["P_f", "mu_y", "sigma_y"] * 2
    # the phasor tables are the rig campaign's format (what the discrepancy workflow reads)
    tab = read_phasors(paths["phasors_opt"])
    X = tab.array("re_m") + 1j * tab.array("im_m")
    np.testing.assert_allclose(X, result.design("opt").phasors.ravel(), rtol=1e-6)
    assert set(tab.array("build").tolist()) == set(range(6))
    md = paths["markdown"].read_text()
    assert "](fig8_response.png)" in md and "Table 7 analogue" in md


def test_bad_input():
    fam = reference_family()
    rng = np.random.default_rng(0)
    o = replace(FAST, ramps=0)
    with pytest.raises(ValueError, match="at least one other design"):
        validate_designs(fam, {"a": DESIGNS["base"]}, options=o, rng=rng)
    with pytest.raises(ValueError, match="baseline"):
        validate_designs(fam, DESIGNS, options=replace(o, baseline="nope"), rng=rng)
    with pytest.raises(ValueError, match="design name"):
        validate_designs(fam, {"a b": DESIGNS["base"], "c": DESIGNS["opt"]}, options=o, rng=rng)
    with pytest.raises(ValueError, match="preload_N"):
        validate_designs(fam, {"a": [500.0, 500.0, 65.0], "c": DESIGNS["opt"]}, options=o,
                         rng=rng)
    with pytest.raises(ValueError, match="rng"):
        validate_designs(fam, DESIGNS, options=o, rng=None)


@pytest.mark.parametrize(("kw", "match"), [
    ({"n_replications": 3}, "n_replications"),
    ({"speeds_rpm": [1000.0, 900.0]}, "speeds_rpm"),
    ({"method": "fft"}, "method"),
    ({"shared": ("bearings", "lot")}, "shared"),
    ({"ramps": 30}, "ramps"),
    ({"ramp_channel": "spindle_x"}, "ramp_channel"),
    ({"speed_range_rpm": (5000.0, 1000.0)}, "speed_range_rpm"),
    ({"confidence": 1.5}, "confidence"),
    ({"sensors": SensorSet(targets=("front", "rear"))}, "'tool' must be a target"),
])
def test_options_bad_values(kw, match):
    with pytest.raises(ValueError, match=match):
        ValidationOptions(**kw)


def test_options_from_dict_rejects_unknown_keys():
    with pytest.raises(ValueError, match="validation"):
        ValidationOptions.from_dict({"n_reps": 3})
    with pytest.raises(ValueError, match="validation.peak"):
        ValidationOptions.from_dict({"peak": {"grid": 3}})
