"""Noise statistics of the sensors and the fast (phasor-domain) path against records."""

import numpy as np
import pytest

from surrogate_rbrdo.rig.demod import demodulate
from surrogate_rbrdo.rig.phasors import phasor_noise_sd, sample_phasors, samples_in_revolutions
from surrogate_rbrdo.rig.sensors import SensorSet
from surrogate_rbrdo.rig.simulate import steady_records
from surrogate_rbrdo.rig.truth import Variability, reference_truth

from .conftest import seeds


def _setup(noise=True):
    truth = reference_truth(variability=Variability.none())
    st = truth.state(np.random.SeedSequence(0), build=0, tool=0, run=0)
    sens = SensorSet(noise=noise)
    return st, sens, sens.install(np.random.default_rng(7))


@pytest.mark.known_answer
def test_probe_noise_is_white_with_the_specified_rms():
    st, sens, inst = _setup()
    recs = steady_records(st.model(), st.theta, np.array([1000.0]), sens, inst, seeds(1),
                          duration_s=2.0, ids=["n"], provenance=[{}])
    x = recs[0].values("rear_x")            # 1x at 1000 rpm is ~0.1 nm: noise only
    x = x - x.mean()
    lsb = sens.daq.lsb_V / sens.probe.sensitivity_V_per_m
    expected = np.sqrt(sens.probe.noise_rms_m**2 + lsb**2 / 12)
    n = x.size
    assert abs(x.std() / expected - 1) < 4 / np.sqrt(2 * n)          # 4 sigma of the sd
    r1 = np.corrcoef(x[:-1], x[1:])[0, 1]
    assert abs(r1) < 4 / np.sqrt(n)                                    # white
    # quantised on the ADC's grid
    np.testing.assert_allclose(np.diff(np.unique(recs[0].data[2])) % 1, 0)


@pytest.mark.known_answer
def test_fast_path_has_the_statistics_of_demodulated_records():
    st, sens, inst = _setup()
    m = st.model()
    speeds = np.array([4000.0, 16000.0])
    R = 60
    dem = np.empty((R, 2, 6), complex)
    for r in range(R):
        recs = steady_records(m, st.theta, speeds, sens, inst, seeds(2, 100 * r),
                              duration_s=0.5, ids=["a", "b"], provenance=[{}] * 2)
        dem[r] = [demodulate(rec).X[:, 0] for rec in recs]
    fast = sample_phasors(m, st.theta, speeds, sens, inst, np.random.default_rng(5),
                          n_repeats=1200, duration_s=0.5)
    # scatter: the variance ratio pooled over 2 speeds x 6 channels x (re, im) — 24 sample
    # variances of R - 1 = 59 degrees of freedom each — is 1 within 4 of its standard errors
    var_dem = np.concatenate([dem.real.var(axis=0, ddof=1), dem.imag.var(axis=0, ddof=1)])
    var_fast = np.concatenate([fast.real.var(axis=0, ddof=1), fast.imag.var(axis=0, ddof=1)])
    ratio = np.mean(var_dem / var_fast)
    assert abs(ratio - 1) < 4 * np.sqrt(2.0 / (var_dem.size * (R - 1)))
    # means agree within 4 standard errors (the keyphasor's phase error is in both)
    for part in (np.real, np.imag):
        sd_d, sd_f = part(dem).std(axis=0), part(fast).std(axis=0)
        tol = 4 * np.hypot(sd_d / np.sqrt(R), sd_f / np.sqrt(fast.shape[0]))
        assert np.all(np.abs(part(dem).mean(axis=0) - part(fast).mean(axis=0)) < tol)


def test_noise_sd_formula_and_sample_count():
    N = samples_in_revolutions(np.array([6000.0]), 1.0, 10_000.0)[0]
    assert 9_700 <= N <= 9_900                       # 98 whole revolutions of 100
    assert phasor_noise_sd(1.0, 0.0, 200) == pytest.approx(0.1)


def test_fast_path_noise_off_is_deterministic():
    st, sens, inst = _setup(noise=False)
    a = sample_phasors(st.model(), st.theta, np.array([12000.0]), sens, inst,
                       np.random.default_rng(0), n_repeats=3)
    assert np.all(a[0] == a[2])
