"""H1 FRF with coherence and modal identification against closed forms.

The test records are exact: the response of each mode to the half-sine hammer pulse is
integrated in closed form (no ODE solver, no interpolated force), at 8x the sample rate, and
force and response are decimated through the same anti-aliasing filter (as a DAQ does; without
it the pulse's spectrum above Nyquist would alias into the force but not into the response)."""

import numpy as np
import pytest
from scipy.signal import decimate

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.rig.frf import h1_frf, modal_fit
from surrogate_rbrdo.rig.records import ChannelSpec, Record, SensorLocation
from surrogate_rbrdo.rig.simulate import hammer_pulse

FS = 10_000.0
CH = {q: ChannelSpec("x", q, u, SensorLocation("tool", "x"))
      for q, u in (("displacement", "m"), ("acceleration", "m/s^2"))}
FORCE = ChannelSpec("f", "force", "N", SensorLocation("tool", "x"))


def _mode_response(t, t_hit, F, width, m, fn, zeta):
    """Exact displacement of ``m x'' + c x' + k x = f`` to ``f = F sin(π (t − t_hit)/width)``
    on ``[t_hit, t_hit + width]``: Duhamel's integral
    of the impulse response ``Im(e^{λτ})/(m ω_d)`` in closed form."""
    wn = 2 * np.pi * fn
    lam = -zeta * wn + 1j * wn * np.sqrt(1 - zeta**2)
    Om = np.pi / width
    s = np.clip(t - t_hit, 0.0, None)
    u = np.minimum(s, width)
    I0 = (np.exp(-lam * u) * (-lam * np.sin(Om * u) - Om * np.cos(Om * u)) + Om) / (
        lam**2 + Om**2)
    return F / (m * wn * np.sqrt(1 - zeta**2)) * (np.exp(lam * s) * I0).imag


def _hits(systems, n_hits=4, noise=0.0, rng=None, duration=1.0):
    t = np.arange(int(8 * FS * duration)) / (8 * FS)
    recs = []
    for h in range(n_hits):
        t_hit, F, w = 0.02 + 0.00037 * h, 100.0 * (1 + 0.1 * h), 0.3e-3   # force null: 5 kHz
        f = hammer_pulse(t, t_hit, F, w)
        x = sum(_mode_response(t, t_hit, F, w, *mode) for mode in systems)
        x, f = decimate(np.vstack([x, f]), 8, ftype="fir", axis=1, zero_phase=True)
        if noise:
            x = x + rng.normal(0, noise, x.size)
        recs.append(Record(f"h{h}", "impact", FS, (CH["displacement"], FORCE),
                           np.vstack([x, f]), speed_rpm=0.0))
    return recs


def _closed_form(systems, s):
    """Receptance at Laplace variable ``s``."""
    return sum(1 / (m * (s**2 + 2 * z * 2 * np.pi * fn * s + (2 * np.pi * fn) ** 2))
               for m, fn, z in systems)


@pytest.mark.known_answer
@pytest.mark.parametrize("exp_end", [None, 0.01])
def test_h1_of_an_sdof_matches_the_closed_form_with_unit_coherence(exp_end):
    """Without a window H1 is H(iω); with the exponential window it is H(iω + σ_w) — both to
    0.5 % over 20 Hz – 3 kHz (the response's sampled pulse is exact; what is left is the
    spectrum's leakage of the 1 s record), coherence 1 without noise."""
    sdof = [(2.0, 350.0, 0.02)]
    est = h1_frf(_hits(sdof), ["x"], "f", exp_window_end=exp_end)
    band = (est.freq_hz > 20) & (est.freq_hz < 3000)
    exact = _closed_form(sdof, 2j * np.pi * est.freq_hz[band] + est.exp_decay_per_s)
    np.testing.assert_allclose(est.H[0, band], exact, rtol=5e-3)
    assert est.coherence[0, band].min() > 0.999


@pytest.mark.known_answer
@pytest.mark.parametrize("exp_end", [None, 0.01])
def test_modal_fit_recovers_undamped_f_and_zeta_of_a_known_system(exp_end):
    """Three modes with noise: pLSCF's natural frequencies are the *undamped* ones, to 0.05 %
    (the 920 Hz mode, ζ = 0.05, peaks 0.125 % lower) and ζ within 10 %; the exponential
    window's added damping is removed."""
    sys3 = [(2.0, 350.0, 0.02), (1.0, 920.0, 0.05), (0.5, 2200.0, 0.01)]
    est = h1_frf(_hits(sys3, noise=2e-9, rng=np.random.default_rng(0)), ["x"], "f",
                 exp_window_end=exp_end)
    fit = modal_fit(est, (100.0, 3500.0))
    order = np.argsort(fit.frequency_hz)
    np.testing.assert_allclose(fit.frequency_hz[order], [350.0, 920.0, 2200.0], rtol=5e-4)
    np.testing.assert_allclose(fit.damping_ratio[order], [0.02, 0.05, 0.01], rtol=0.1)
    np.testing.assert_allclose(fit.damped_frequency_hz[order][1], 920.0 * np.sqrt(1 - 0.05**2),
                               rtol=5e-4)


def test_modal_fit_failures_are_clear_errors():
    est = h1_frf(_hits([(2.0, 350.0, 0.02)], n_hits=2), ["x"], "f")
    with pytest.raises(ValueError, match="no FRF peak"):
        modal_fit(est, (1000.0, 2000.0))
    with pytest.raises((ModelError, ValueError), match="modal_fit"):
        modal_fit(est, (100.0, 120.0), approx_hz=[110.0], model_order=200)
