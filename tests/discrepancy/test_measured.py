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
from surrogate_rbrdo.discrepancy.sweeps import Channel


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
