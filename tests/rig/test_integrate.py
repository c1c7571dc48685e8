"""The time integrator: exact at constant speed, convergent on ramps, Jeffcott known answers."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from surrogate_rbrdo.rig.integrate import IntegratorOptions, SpeedProfile, simulate
from surrogate_rbrdo.spindle import reference_spindle, unbalance_response
from surrogate_rbrdo.spindle.assembly import RPM

from .conftest import JEFFCOTT, jeffcott_model, jeffcott_response


@pytest.mark.known_answer
@pytest.mark.parametrize("speed", [3000.0, 15000.0, 24000.0])
def test_constant_speed_from_rest_converges_to_harmonic(speed):
    sp = reference_spindle()
    m = sp.model(sp.baseline)
    theta = np.array([[0.95, 1.05]])
    Q = unbalance_response(m, np.array([speed]), theta)[0, 0].reshape(-1)
    dofs = np.array([4 * m.tool_node, 4 * m.tool_node + 1, 4 * m.bearing_nodes[0],
                     4 * m.bearing_nodes[1] + 1])
    t = 3.0 + np.arange(400) / 10_000.0     # 3 s after starting from rest
    s = simulate(m, SpeedProfile.constant(speed, 0.7), t, dofs, theta=theta, t0_s=0.0,
                 options=IntegratorOptions(f_cut_hz=None))
    ref = (Q[dofs][None, :] * np.exp(1j * s.angle_rad[:, None])).real
    err = np.abs(s.q - ref).max(axis=0) / np.abs(Q[dofs])
    assert err.max() <= 1e-6


def test_ritz_truncation_error_is_small_and_shrinks():
    sp = reference_spindle()
    m = sp.model(sp.baseline)
    Q = unbalance_response(m, np.array([15000.0]))[0, 0].reshape(-1)
    dof = np.array([4 * m.tool_node])
    t = 3.0 + np.arange(200) / 10_000.0
    errs = []
    for fc in (20_000.0, 50_000.0):
        s = simulate(m, SpeedProfile.constant(15000.0), t, dof, t0_s=0.0,
                     options=IntegratorOptions(f_cut_hz=fc))
        ref = (Q[dof] * np.exp(1j * s.angle_rad[:, None])).real
        errs.append(np.abs(s.q - ref).max() / abs(Q[dof][0]))
    assert errs[0] < 1e-3 and errs[1] < errs[0] / 10


def test_ramp_converges_with_segment_length():
    sp = reference_spindle()
    m = sp.model(sp.baseline)
    dof = np.array([4 * m.tool_node])
    prof = SpeedProfile.ramp(20000.0, 23000.0, 0.4)
    t = np.arange(4000) / 10_000.0
    runs = {seg: simulate(m, prof, t, dof, t0_s=-2.0,
                          options=IntegratorOptions(segment_s=seg, f_cut_hz=20_000.0)).q
            for seg in (0.0025, 0.005, 0.01, 0.02)}
    ref = runs[0.0025]
    e = [np.abs(runs[s] - ref).max() / np.abs(ref).max() for s in (0.005, 0.01, 0.02)]
    assert e[2] < 1e-3
    assert e[0] < e[1] < e[2]
    assert e[1] / e[0] > 2.0          # better than first order


@pytest.mark.known_answer
def test_jeffcott_runup_matches_an_independent_ode_solution():
    """A fast run-up through the critical speed: the modal integrator vs solve_ivp (DOP853) on
    the Jeffcott equations with the exact unbalance force of a ramp (φ'² and φ'' terms)."""
    m = jeffcott_model()
    M, k, c, U = m.rotor_mass_kg, 2 * JEFFCOTT["k"], 2 * JEFFCOTT["c"], JEFFCOTT["U"]
    wn = np.sqrt(k / M) / RPM
    prof = SpeedProfile.ramp(0.6 * wn, 1.4 * wn, 0.3)
    t = np.arange(3000) / 10_000.0

    def rhs(tt, y):
        ph, w, a = prof.angle(tt), prof.omega(tt), prof.alpha(tt)
        fx = U * (w**2 * np.cos(ph) + a * np.sin(ph))
        fy = U * (w**2 * np.sin(ph) - a * np.cos(ph))
        x, yy, vx, vy = y
        return [vx, vy, (fx - c * vx - k * x) / M, (fy - c * vy - k * yy) / M]

    w0 = prof.omega(np.array([0.0]))[0]
    X0 = jeffcott_response(m, w0) * np.exp(1j * prof.angle(np.array([0.0]))[0])
    y0 = [X0.real, (-1j * X0).real, (1j * w0 * X0).real, (w0 * X0).real]
    ref = solve_ivp(rhs, (0, t[-1]), y0, t_eval=t, method="DOP853", rtol=1e-10, atol=1e-14)
    node = m.tool_node
    s = simulate(m, prof, t, np.array([4 * node, 4 * node + 1]), t0_s=-3.0,
                 options=IntegratorOptions(segment_s=0.002, f_cut_hz=None))
    err = np.abs(s.q - ref.y[:2].T).max() / np.abs(ref.y[:2]).max()
    assert err < 2e-4


@pytest.mark.known_answer
def test_jeffcott_slow_runup_tends_to_the_steady_state_curve():
    """The run-up's 1x amplitude departs from the closed-form steady state by an amount that
    falls in proportion to the sweep rate (first order in α/ω_n²)."""
    m = jeffcott_model()
    wn = np.sqrt(2 * JEFFCOTT["k"] / m.rotor_mass_kg) / RPM
    errs, peaks = [], []
    for dur in (10.0, 40.0):                 # α / ω_n² ≈ 4e-5 and 1e-5, ζ² ≈ 4.5e-4
        prof = SpeedProfile.ramp(0.7 * wn, 1.3 * wn, dur)
        t = np.arange(0.0, dur, 1e-3)
        s = simulate(m, prof, t, np.array([4 * m.tool_node, 4 * m.tool_node + 1]),
                     t0_s=-3.0, options=IntegratorOptions(segment_s=0.02, f_cut_hz=None))
        amp = np.abs(s.q[:, 0] + 1j * s.q[:, 1])                 # forward whirl: |x + iy|
        exact = np.abs(jeffcott_response(m, s.speed_rpm * RPM))
        errs.append(np.max(np.abs(amp - exact)) / exact.max())
        peaks.append(s.speed_rpm[np.argmax(amp)] / s.speed_rpm[np.argmax(exact)] - 1)
    assert errs[1] < 0.015 and 3.0 < errs[0] / errs[1] < 5.0
    assert 0 < peaks[1] < peaks[0] < 0.01   # the run-up's peak lags, less when slower


def test_start_must_be_at_constant_speed():
    m = jeffcott_model()
    with pytest.raises(ValueError, match="constant between t0_s"):
        simulate(m, SpeedProfile.ramp(1000.0, 2000.0, 1.0), np.arange(10) * 1e-3 + 0.5,
                 np.array([0]), t0_s=0.0)
