"""Shared builders: the reference spindle at its baseline design and small virtual campaigns."""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.observables import ComplexBlock, MeasuredData
from surrogate_rbrdo.discrepancy.sweeps import Sweep
from surrogate_rbrdo.discrepancy.synthetic import (
    Assembly,
    Campaign,
    NoiseLevel,
    Truth,
    default_channels,
    measure,
)
from surrogate_rbrdo.spindle.reference import reference_spindle

#: a small campaign that keeps the default suite fast (24 speeds, 10 repeats, 60 FRF lines of
#: 10 hits: the fewest the workflow uses, DiscrepancyOptions.min_impact_dof)
SMALL = Campaign(speeds_rpm=tuple(np.linspace(2000.0, 24000.0, 24).tolist()), repeats=10,
                 impact_freqs_hz=tuple(np.linspace(50.0, 1500.0, 60).tolist()),
                 impact_repeats=10)


@pytest.fixture(scope="session")
def spindle():
    sp = reference_spindle()
    return sp, sp.geometry_for(sp.baseline)


def campaign_data(spindle, hidden=(), *, seed, geometry=None, campaign=SMALL,
                  noise=None):
    """Virtual data of the baseline spindle with ``hidden`` effects and a drawn assembly."""
    sp, g = spindle
    noise = NoiseLevel() if noise is None else noise
    truth = Truth(geometry or g, sp.effects + tuple(hidden), planes_mm=(0.0, 350.0))
    rng = np.random.default_rng(seed)
    U = 2 * sp.geometry.unbalances[0].magnitude_kgm
    asm = Assembly.draw(U, 2, 2, rng=rng)
    return measure(truth, asm, campaign, noise, rng=rng), asm


def baseline_1x(spindle, *, seed, gain=1.0):
    """The baseline model's own 1x response at 9 speeds (unbalance 5 µ kg m at both planes, 90°
    apart), 8 repeats with 0.1 % complex noise, each channel read with ``gain``: the forward
    model and the data."""
    sp, g = spindle
    ch = default_channels(g)
    sw = Sweep.unbalance(np.linspace(3000, 22000, 9))
    fm = ForwardModel(g, sp.effects, ch, (0.0, 350.0))
    rng = np.random.default_rng(seed)
    y = fm.response(sw, np.ones((1, 2)), np.ones((1, 2)))[0] @ np.array([5e-6, 5e-6j])
    rec = y[None] * gain * (1 + 1e-3 * (rng.normal(size=(8,) + y.shape)
                                        + 1j * rng.normal(size=(8,) + y.shape)))
    return fm, MeasuredData((ComplexBlock.from_repeats("unbalance_1x", sw, ch, rec),))
