"""Measured-data format → observables: the phasor table, record channel positions, FRFs."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy.measured import (
    channel_positions,
    frf_block,
    phasor_block,
    read_phasor_table,
)
from surrogate_rbrdo.discrepancy.observables import THIN_IMPACTS
from surrogate_rbrdo.discrepancy.sweeps import Channel, Sweep
from surrogate_rbrdo.discrepancy.workflow import _drop_thin_impacts


def test_phasor_table_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    X = rng.normal(size=(6, 3, 2)) + 1j * rng.normal(size=(6, 3, 2))      # runs, speeds, ch
    speeds, chans = [1000.0, 2000.0, 3000.0], ["front_x", "tool_y"]
    path = tmp_path / "phasors.csv"
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["record", "build", "tool", "run", "speed_rpm", "channel", "re_m", "im_m"])
        for r in range(6):
            for i, s in enumerate(speeds):
                for j, c in enumerate(chans):
                    w.writerow([f"r{r}s{i}", 0, 0, r, s, c, X[r, i, j].real, X[r, i, j].imag])
    b = phasor_block(read_phasor_table(path), {"front_x": (100.0, "x"), "tool_y": (0.0, "y")})
    assert np.allclose(b.mean, X.mean(axis=0))
    assert [c.name for c in b.channels] == chans and b.dof == 5


def test_missing_phasor_or_position_raises(tmp_path):
    rows = [{"run": 0, "speed_rpm": 1000.0, "channel": "a", "re_m": 1.0, "im_m": 0.0}] * 5
    with pytest.raises(ValueError, match="no position"):
        phasor_block(rows, {})
    rows2 = rows + [{"run": 1, "speed_rpm": 2000.0, "channel": "a", "re_m": 1, "im_m": 0}]
    with pytest.raises(ValueError, match="every repeat needs every speed"):
        phasor_block(rows2, {"a": (0.0, "x")})
    with pytest.raises(ValueError, match="does not exist"):
        read_phasor_table(tmp_path / "nope.csv")


def test_channel_positions_from_a_native_record(tmp_path):
    meta = {"channels": [
        {"name": "front_x", "quantity": "displacement",
         "location": {"target": "front", "direction": "x", "position_mm": 100.0}},
        {"name": "keyphasor", "quantity": "keyphasor", "location": {"target": "shaft"}}]}
    path = tmp_path / "r.npz"
    np.savez(path, data=np.zeros((2, 4)), meta=np.array(json.dumps(meta)))
    assert channel_positions(path) == {"front_x": (100.0, "x")}


@pytest.mark.known_answer
def test_frf_variance_is_bendat_and_piersol():
    H = np.array([[1.0 + 1.0j, 2.0, 0.5j, 3.0]])
    g2 = np.array([[0.99, 0.95, 0.5, 0.97]])
    b = frf_block("impact", [10.0, 20.0, 30.0, 40.0], H, g2, 5, (Channel("t", 0.0, "x"),),
                  Channel("t", 0.0, "x"))
    assert b.mean.shape == (3, 1)                                  # γ² = 0.5 dropped
    var = abs(H[0, 0]) ** 2 * (1 - 0.99) / (2 * 5 * 0.99)
    assert b.cov[0, 0] == pytest.approx(var * np.eye(2))


def test_impact_records_at_speed_become_frf_blocks_with_their_speed(tmp_path):
    """A rig campaign with hits at standstill and at 12 000 rpm: one FRF block per speed and
    direction, each with its speed; the tool FRF at speed matches the model at that speed
    (not at standstill: the gyroscopic coupling moves the modes)."""
    from surrogate_rbrdo.discrepancy.experiment import data_from_folder
    from surrogate_rbrdo.discrepancy.forward import ForwardModel
    from surrogate_rbrdo.rig.campaign import CampaignOptions, run_campaign
    from surrogate_rbrdo.rig.truth import Variability, reference_truth
    from surrogate_rbrdo.spindle import reference_spindle

    opts = CampaignOptions(speeds_rpm=tuple(np.linspace(2000, 20000, 8)), repeats=5,
                           duration_s=0.2, runup=None, impacts_per_direction=6,
                           impact_duration_s=0.5, impact_speeds_rpm=(0.0, 12000.0))
    run_campaign(reference_truth(variability=Variability.none()), opts, tmp_path,
                 rng=np.random.default_rng(1))
    assert [b.name for b in data_from_folder(tmp_path, impacts=False).blocks] == [
        "unbalance_1x"]
    data = data_from_folder(tmp_path, impacts=True)
    names = [b.name for b in data.blocks]
    assert names == ["unbalance_1x", "impact_x_0rpm", "impact_y_0rpm", "impact_x_12000rpm",
                     "impact_y_12000rpm"]
    b = data.block("impact_x_12000rpm")
    assert b.sweep.speed_rpm == pytest.approx(12000.0) and b.meta["n_hits"] == 6
    assert len(b.channels) == 6 and b.dof == 5
    assert not np.any(np.abs(b.coord - 200.0) <= 10.0)        # the running frequency dropped
    sp = reference_spindle()
    g = sp.geometry_for(sp.baseline)
    fm = ForwardModel(g, sp.effects, b.channels, (0.0,))
    ones = np.ones((1, 2))
    at = fm.response(b.sweep, ones, ones)[0][..., 0]
    still = fm.response(Sweep.impact(b.coord, b.sweep.excitations), ones, ones)[0][..., 0]
    W = b.whitening()

    def chi2_dof(model):
        r = b.mean - model
        w = np.einsum("xcij,xcj->xci", W, np.stack([r.real, r.imag], axis=-1))
        return float(np.sum(w**2) / w.size)

    # the model at speed is off only by the probes' and the hammer's calibration (a few
    # percent: the workflow recalibrates them); the standstill model is far off
    assert chi2_dof(still) > 10 * chi2_dof(at), (chi2_dof(still), chi2_dof(at))


def test_a_speed_with_too_few_hits_is_left_out_with_a_warning(tmp_path):
    """Two hits per direction (a campaign planned for identification): no FRF block, a warning
    naming the speed and direction, the 1x data still read (impact records are read by
    default)."""
    from surrogate_rbrdo.discrepancy.experiment import data_from_folder
    from surrogate_rbrdo.rig.campaign import CampaignOptions, run_campaign
    from surrogate_rbrdo.rig.truth import Variability, reference_truth

    opts = CampaignOptions(speeds_rpm=(4000.0, 12000.0, 20000.0), repeats=5, duration_s=0.2,
                           runup=None, impacts_per_direction=2, impact_duration_s=0.5)
    run_campaign(reference_truth(variability=Variability.none()), opts, tmp_path,
                 rng=np.random.default_rng(2))
    with pytest.warns(UserWarning, match="2 impact records at 0 rpm in x left out"):
        data = data_from_folder(tmp_path)
    assert [b.name for b in data.blocks] == ["unbalance_1x"]
    # ... and the workflow's findings list them beside the blocks it leaves out itself
    left = [("impact_x_0rpm", 1), ("impact_y_0rpm", 1)]
    assert data.provenance[THIN_IMPACTS] == left
    assert _drop_thin_impacts(data, 9) == (data, tuple(left))
