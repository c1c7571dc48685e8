"""Bearing damping from the rig's impact tests (``identification.impact``): FRF-based model
updating against the rig's known truth (each build's damping factors, the tool change's mass
factor, the run's bearing stiffness)."""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.identification.impact import ImpactOptions, impact_damping
from surrogate_rbrdo.identification.rigtruth import record_state
from surrogate_rbrdo.rig import CampaignOptions, open_dataset, reference_truth, run_campaign
from surrogate_rbrdo.rig.records import RecordError
from surrogate_rbrdo.rig.sensors import SensorSet
from surrogate_rbrdo.spindle import reference_spindle


@pytest.fixture(scope="module")
def model():
    sp = reference_spindle()
    return sp.model(sp.baseline)


def _impacts(path, seed, sensors, hits):
    truth = reference_truth()
    run_campaign(truth, CampaignOptions(speeds_rpm=(10000.0,), repeats=1, runup=None,
                                        impacts_per_direction=hits, sensors=sensors),
                 path, rng=np.random.default_rng(seed))
    ds = open_dataset(path / "dataset")
    recs = [ds.load(r) for r in ds.index if r["kind"] == "impact"]
    return truth, recs, [ds.load(r) for r in ds.index if r["kind"] == "steady"]


def _truth_factors(truth, rec):
    d = rec.provenance["truth_draws"]
    st = record_state(truth, rec.provenance)
    return (np.array(d["build"]["damping_factor"]), st.theta[0],
            float(d["tool"]["mass_factor"]))


@pytest.mark.known_answer
def test_noise_free_impacts_recover_bearing_damping_stiffness_and_tool_mass(tmp_path, model):
    """The rig with its noise off, one hit per direction, a random build (damping factors
    CoV 20 %), tool (mass 3 %) and thermal state: η of both bearings within 2 % (the rest is
    the rig's own FRF error above ~1.4 kHz, 0.3-1 % against its truth's model), the
    standstill stiffness factors within 0.5 %, the tool mass within 0.5 %."""
    truth, recs, _ = _impacts(tmp_path, 5, SensorSet(noise=False), 1)
    d_true, th_true, m_true = _truth_factors(truth, recs[0])
    res = impact_damping(model, recs)
    np.testing.assert_allclose(res.eta_s, 4e-6 * d_true, rtol=0.02)
    np.testing.assert_allclose([res.factor("front_stiffness"), res.factor("rear_stiffness")],
                               th_true, rtol=5e-3)
    assert res.factor("tool_mass") == pytest.approx(m_true, rel=5e-3)
    np.testing.assert_allclose(res.damping([2e8, 3e8]), [2e8 * res.eta_s[0],
                                                         3e8 * res.eta_s[1]])


def test_impact_damping_bad_inputs(tmp_path, model):
    truth, recs, steady = _impacts(tmp_path, 1, SensorSet(noise=False), 1)
    with pytest.raises(RecordError, match="hammer"):
        impact_damping(model, steady[:1])
    with pytest.raises(ValueError, match="band_hz"):
        impact_damping(model, recs, ImpactOptions(band_hz=(5.0, 10.0)))
    with pytest.raises(ValueError, match="tool_disk"):
        impact_damping(model, recs, ImpactOptions(tool_disk="no_such_disk"))
    with pytest.raises(ValueError, match="band_hz"):
        ImpactOptions(band_hz=(300.0, 200.0))
