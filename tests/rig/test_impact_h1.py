"""The rig's impact records against the closed form: a noise-free hit's H1 (as the impact
updating reads it, :func:`~surrogate_rbrdo.identification.impact_frf.hit_frfs`) against the
accelerance ``s² [K + sC + s²M]⁻¹`` of the same model at standstill
(:class:`~surrogate_rbrdo.identification.updating.StandstillModel`, an independent frequency-
domain computation; the rig integrates in time)."""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.identification.impact_frf import ImpactOptions, accelerance, hit_frfs
from surrogate_rbrdo.identification.updating import StandstillModel
from surrogate_rbrdo.rig.sensors import SensorSet
from surrogate_rbrdo.rig.simulate import impact_record
from surrogate_rbrdo.spindle import reference_spindle


@pytest.mark.known_answer
def test_noise_free_impact_h1_is_the_models_accelerance_up_to_2_5_khz():
    """Both directions, 100 Hz–2.5 kHz, bins where ``|H|`` is at least a tenth of the band's
    median (at an antiresonance the relative error of any estimate is unbounded): H1 within
    1e-3 of the model (the held force's residual error grows with frequency, ∝ the fine step²;
    measured: median 1.1e-4 / 1.3–1.5e-4 / 4.7–4.8e-4 at 0.1–1 / 1–2 / 2–2.5 kHz, largest
    8.8e-4 at 2.39 kHz)."""
    sp = reference_spindle()
    model = sp.model(sp.baseline)
    nb = len(model.bearing_nodes)
    sens = SensorSet(noise=False)
    inst = sens.install(np.random.default_rng(0))
    recs = [impact_record(model, np.ones(nb), sens, inst, np.random.default_rng(1), rid=d,
                          provenance={}, direction=d) for d in "xy"]
    with pytest.warns(UserWarning, match="one hit"):
        frfs = hit_frfs(recs, ImpactOptions())
    up = StandstillModel(model, None)
    for d, est in frfs.items():
        f = est.freq_hz
        g = (f >= 100.0) & (f <= 2500.0)
        s = 2j * np.pi * f[g] + est.exp_decay_per_s
        dof = np.full(s.size, 4 * model.tool_node + (1 if d == "y" else 0))
        Hm, _ = up.accelerance(np.ones(nb), np.ones(nb), 1.0, s, dof)
        keep = np.abs(Hm) >= 0.1 * np.median(np.abs(Hm))
        err = np.abs(accelerance(est)[g] / Hm - 1)[keep]
        assert err.max() < 1e-3, (d, err.max())
        assert np.median(err[f[g][keep] < 2000.0]) < 3e-4, d
