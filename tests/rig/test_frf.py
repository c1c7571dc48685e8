"""H1 FRF with coherence and modal identification against closed forms."""

import numpy as np
import pytest
from scipy.signal import lsim

from surrogate_rbrdo.rig.frf import h1_frf, modal_fit
from surrogate_rbrdo.rig.records import ChannelSpec, Record, SensorLocation
from surrogate_rbrdo.rig.simulate import hammer_pulse

pytest.importorskip("sdypy.FRF")
pytest.importorskip("sdypy.EMA")

FS = 10_000.0
CH = (ChannelSpec("x", "displacement", "m", SensorLocation("tool", "x")),
      ChannelSpec("f", "force", "N", SensorLocation("tool", "x")))


def _hits(systems, n_hits=4, noise=0.0, rng=None):
    """Impact records of a sum of SDOF modes (m_k, f_k, ζ_k) driven by half-sine hits."""
    t = np.arange(int(FS)) / FS
    recs = []
    for h in range(n_hits):
        f = hammer_pulse(t, 0.02 + 0.001 * h, 100.0 * (1 + 0.1 * h), 0.5e-3)
        x = np.zeros_like(t)
        for m, fn, z in systems:
            wn = 2 * np.pi * fn
            _, y, _ = lsim(([1.0 / m], [1.0, 2 * z * wn, wn**2]), f, t)
            x += y
        if noise:
            x = x + rng.normal(0, noise, t.size)
        recs.append(Record(f"h{h}", "impact", FS, CH, np.vstack([x, f]), speed_rpm=0.0))
    return recs


def _closed_form(systems, f_hz):
    w = 2 * np.pi * f_hz
    return sum(1 / (m * ((2 * np.pi * fn) ** 2 - w**2 + 2j * z * 2 * np.pi * fn * w))
               for m, fn, z in systems)


@pytest.mark.known_answer
def test_h1_of_an_sdof_matches_the_closed_form_with_unit_coherence():
    sdof = [(2.0, 350.0, 0.02)]
    est = h1_frf(_hits(sdof), ["x"], "f")
    band = (est.freq_hz > 20) & (est.freq_hz < 1500)
    exact = _closed_form(sdof, est.freq_hz[band])
    np.testing.assert_allclose(est.H[0, band], exact, rtol=0.01, atol=0.002 * abs(exact).max())
    assert est.coherence[0, band].min() > 0.999


@pytest.mark.known_answer
def test_modal_fit_recovers_f_and_zeta_of_a_known_system():
    sys2 = [(2.0, 350.0, 0.02), (1.0, 920.0, 0.01)]
    est = h1_frf(_hits(sys2, noise=2e-9, rng=np.random.default_rng(0)), ["x"], "f",
                 force_window=0.05)
    fit = modal_fit(est, (100.0, 2000.0))
    fd = np.array([350.0 * np.sqrt(1 - 0.02**2), 920.0 * np.sqrt(1 - 0.01**2)])
    np.testing.assert_allclose(np.sort(fit.frequency_hz), fd, rtol=2e-3)
    np.testing.assert_allclose(fit.damping_ratio[np.argsort(fit.frequency_hz)], [0.02, 0.01],
                               rtol=0.1)
