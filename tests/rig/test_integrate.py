"""The time integrator: exact at constant speed (default options), the reduction basis against
the full FE harmonic solution, ramps against an independent solution with time-varying
matrices, Jeffcott known answers."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from surrogate_rbrdo.rig.integrate import (
    IntegratorOptions,
    SpeedProfile,
    simulate,
    unbalance_pattern,
)
from surrogate_rbrdo.rig.statespace import reduction
from surrogate_rbrdo.spindle import reference_spindle, unbalance_response
from surrogate_rbrdo.spindle.assembly import RPM, build_model
from surrogate_rbrdo.spindle.effects import (
    Anisotropy,
    CrossCoupling,
    HousingFlexibility,
    SpeedSoftening,
    ToolInterface,
)
from surrogate_rbrdo.spindle.geometry import SpindleGeometry

from .conftest import JEFFCOTT, jeffcott_model, jeffcott_response

SP = reference_spindle()


def _models():
    base = SP.effects
    return {
        "reference": SP.model(SP.baseline),
        "cross_coupling": SP.model(SP.baseline, base + (CrossCoupling(kappa=0.02),)),
        "tool_interface": SP.model(SP.baseline, base + (ToolInterface(k_t_N_per_m=3e8,
                                                                      k_r_Nm_per_rad=5e6),)),
        # massless housing stages: first-order DOFs (the bearing's damping in series)
        "massless_housing": SP.model(SP.baseline, base + (HousingFlexibility(k_N_per_m=5e8),)),
        "housing_with_mass": SP.model(SP.baseline, base + (HousingFlexibility(
            k_N_per_m=3e8, m_kg=5.0, c_Ns_per_m=2000.0),)),
    }


def _rel_error(s, Q, dofs):
    ref = (Q[dofs][None, :] * np.exp(1j * s.angle_rad[:, None])).real
    return (np.abs(s.q - ref).max(axis=0) / np.abs(Q[dofs])).max()


@pytest.mark.known_answer
@pytest.mark.parametrize("name", list(_models()))
def test_constant_speed_with_default_options_is_the_harmonic_solution(name):
    """Default options, from rest: the response converges to the FE harmonic solution."""
    m = _models()[name]
    theta = np.array([[0.95, 1.05]])
    dofs = np.array([4 * m.tool_node, 4 * m.tool_node + 1, 4 * m.bearing_nodes[0],
                     4 * m.bearing_nodes[1] + 1])
    for speed in (1234.5, 15000.0, 24000.0):
        Q = unbalance_response(m, np.array([speed]), theta)[0, 0].reshape(-1)
        t = 6.0 + np.arange(200) / 10_000.0     # 6 s after rest: the transient is < 1e-17
        s = simulate(m, SpeedProfile.constant(speed, 0.7), t, dofs, theta=theta, t0_s=0.0)
        assert _rel_error(s, Q, dofs) <= 1e-6, (name, speed)


@pytest.mark.known_answer
def test_massless_undamped_stage_is_condensed_exactly():
    """A rigid-ish rotor on undamped bearings with massless, undamped housing stages: the
    stages are condensed statically; the response is the harmonic solution of the series
    springs (the rotor's own Rayleigh damping keeps it stable)."""
    g = SpindleGeometry.from_dict({
        "sections": [{"length_mm": 300.0, "outer_diameter_mm": 60.0, "elements": 4}],
        "disks": [{"name": "d", "position_mm": 150.0, "mass_kg": 4.0,
                   "polar_inertia_kgm2": 0.01, "diametral_inertia_kgm2": 0.006}],
        "bearings": [{"name": n, "position_mm": z, "law": {"type": "constant",
                                                           "k_N_per_m": 5e7}}
                     for n, z in (("a", 0.0), ("b", 300.0))],
        "unbalances": [{"position_mm": 150.0, "magnitude_kgm": 1e-5}],
        "rayleigh_alpha_per_s": 5.0, "rayleigh_beta_s": 2e-6})
    m = build_model(g, (HousingFlexibility(k_N_per_m=1e8),))
    dofs = np.array([4 * m.tool_node, 4 * m.bearing_nodes[0]])
    Q = unbalance_response(m, np.array([9000.0]))[0, 0].reshape(-1)
    s = simulate(m, SpeedProfile.constant(9000.0), 8.0 + np.arange(100) / 1e4, dofs, t0_s=0.0)
    assert _rel_error(s, Q, dofs) <= 1e-6


@pytest.mark.known_answer
@pytest.mark.parametrize("name", ["reference", "tool_interface", "massless_housing"])
def test_ramp_basis_reproduces_the_full_harmonic_response(name):
    """The default Ritz basis of a ramp (modes below 10 kHz at three speeds, static shapes,
    their mass correction, gyroscopic/damping augmentation) against the full FE solution at
    every speed of 1 000–24 000 rpm, resonances included."""
    m = _models()[name]
    n = m.system_matrices(0.0)[0].shape[0]
    P = unbalance_pattern(m, n)
    red = reduction(m, None, np.array([1000.0, 12500.0, 24000.0]) * RPM, P[:, None],
                    IntegratorOptions().f_cut_hz)
    T = red.T
    dofs = np.array([4 * m.tool_node, 4 * m.bearing_nodes[0], 4 * m.bearing_nodes[1]])
    worst = 0.0
    for s in np.linspace(1000.0, 24000.0, 60):
        M, C, K = m.system_matrices(s * RPM)
        Z = K - (s * RPM) ** 2 * M + 1j * s * RPM * C
        X = np.linalg.solve(Z, P * (s * RPM) ** 2)
        Xr = T @ np.linalg.solve(T.T @ Z @ T, T.T @ (P * (s * RPM) ** 2))
        worst = max(worst, float((np.abs(Xr - X)[dofs] / np.abs(X[dofs])).max()))
    assert worst < 1e-4


def _overhung_rotor():
    """12 DOFs: an overhung disk on a shaft; bearings soften with speed (k ∝ 1 − 0.5 (Ω/Ω_r)²,
    50 % at the ramp's end) and are anisotropic; gyroscopics on."""
    g = SpindleGeometry.from_dict({
        "sections": [{"length_mm": 300, "outer_diameter_mm": 40, "elements": 1}],
        "disks": [{"name": "d", "position_mm": 300.0, "mass_kg": 5.0,
                   "polar_inertia_kgm2": 0.08, "diametral_inertia_kgm2": 0.045}],
        "bearings": [{"name": n, "position_mm": z, "law": {
            "type": "constant", "k_N_per_m": 5e7,
            "c_matrix_Ns_per_m": [[800.0, 0.0], [0.0, 800.0]]}}
            for n, z in (("front", 200.0), ("rear", 0.0))],
        "unbalances": [{"position_mm": 300.0, "magnitude_kgm": 1e-4}],
        "tool_tip_mm": 300.0, "rayleigh_alpha_per_s": 0.0, "rayleigh_beta_s": 1e-6})
    return build_model(g, (SpeedSoftening(a=0.5, exponent=2.0, omega_ref=6000 * RPM),
                           Anisotropy(s=0.2)))


def _ivp_runup(m, w0, w1, T, t):
    """Independent solution: DOP853 on ``M q'' + C(Ω(t)) q' + K(Ω(t)) q = Re(P (Ω² − iα)
    e^{iφ})`` from rest, with ``C, K`` exactly quadratic in Ω (fitted through three speeds and
    checked at a fourth)."""
    n = m.n_dof
    P = unbalance_pattern(m, n)
    M = m.system_matrices(0.0)[0]
    Mi = np.linalg.inv(M)
    ws = np.array([0.0, 0.5, 1.0]) * w1
    mats = [m.system_matrices(w) for w in ws]
    V = np.linalg.inv(np.vander(ws, 3, increasing=True))
    Cc = [sum(V[r, j] * mats[j][1] for j in range(3)) for r in range(3)]
    Kc = [sum(V[r, j] * mats[j][2] for j in range(3)) for r in range(3)]
    w4 = 0.37 * w1
    _, C4, K4 = m.system_matrices(w4)
    assert np.abs(Kc[0] + Kc[1] * w4 + Kc[2] * w4**2 - K4).max() < 1e-9 * np.abs(K4).max()
    assert np.abs(Cc[0] + Cc[1] * w4 + Cc[2] * w4**2 - C4).max() < 1e-9 * np.abs(C4).max()
    AK = [-Mi @ k for k in Kc]
    AC = [-Mi @ c for c in Cc]
    MP, al = Mi @ P, (w1 - w0) / T

    def rhs(tt, y):
        w = w0 + al * min(tt, T)
        a = al if tt < T else 0.0
        tr = min(tt, T)
        ph = w0 * tr + 0.5 * al * tr**2 + w1 * max(tt - T, 0.0)
        q, v = y[:n], y[n:]
        acc = ((AK[0] + w * AK[1] + w * w * AK[2]) @ q + (AC[0] + w * AC[1] + w * w * AC[2]) @ v
               + (MP * (w * w - 1j * a) * np.exp(1j * ph)).real)
        return np.concatenate([v, acc])

    return solve_ivp(rhs, (0.0, t[-1]), np.zeros(2 * n), t_eval=t, method="DOP853",
                     rtol=1e-10, atol=1e-16).y


@pytest.mark.known_answer
def test_ramp_with_time_varying_matrices_matches_an_independent_solution():
    """A fast run-up (1 000 → 6 000 rpm in 0.15 s, 33 000 rpm/s) from rest with bearings that
    lose half their stiffness on the way: default options within 1e-4 of DOP853 (docs/rig.md
    states this accuracy), and a tighter tolerance with a finer step is closer still."""
    m = _overhung_rotor()
    t = np.arange(2000) / 1e4
    ref = _ivp_runup(m, 1000 * RPM, 6000 * RPM, 0.15, t)
    dofs = np.array([4 * m.tool_node, 4 * m.tool_node + 1, 4 * m.bearing_nodes[0]])
    prof = SpeedProfile.ramp(1000.0, 6000.0, 0.15)
    errs = []
    for o in (IntegratorOptions(), IntegratorOptions(tol=1e-7, oversample=2)):
        s = simulate(m, prof, t, dofs, options=o)
        errs.append(np.abs(s.q - ref[dofs].T).max() / np.abs(ref[dofs]).max())
    assert errs[0] < 1e-4 and errs[1] < errs[0]


def test_segments_follow_the_error_estimate():
    """Tighter tolerance → more, shorter segments; a constant-speed stretch of a profile is
    one long segment per ``max_segment_s``; a fixed ``segment_s`` is obeyed."""
    m = _overhung_rotor()
    t = np.arange(1000) / 1e4
    prof = SpeedProfile((0.0, 0.05, 0.1), (1000.0, 4000.0, 4000.0))
    n = [simulate(m, prof, t, np.array([0]), options=IntegratorOptions(tol=tol)).segments
         for tol in (1e-4, 1e-8)]
    assert n[1] > n[0]
    fixed = simulate(m, prof, t, np.array([0]), options=IntegratorOptions(segment_s=0.01))
    assert fixed.segments == 10


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
    s = simulate(m, prof, t, np.array([4 * node, 4 * node + 1]), t0_s=-3.0)
    err = np.abs(s.q - ref.y[:2].T).max() / np.abs(ref.y[:2]).max()
    assert err < 1e-4


@pytest.mark.known_answer
def test_jeffcott_slow_runup_tends_to_the_steady_state_curve_first_order_in_the_rate():
    """The run-up's 1x amplitude departs from the closed-form steady state by an amount of
    first order in the sweep rate α (asymptotics of slow passage through resonance, e.g.
    Markert & Seidler 2001, *Int. J. Non-Linear Mech.* 36:1079): four times slower, the
    deviation falls by 4^p with p ≈ 1, and the run-up's peak lags the steady one."""
    m = jeffcott_model()
    wn = np.sqrt(2 * JEFFCOTT["k"] / m.rotor_mass_kg) / RPM
    errs, peaks = [], []
    for dur in (10.0, 40.0):                 # α / ω_n² ≈ 4e-5 and 1e-5, ζ² ≈ 4.5e-4
        prof = SpeedProfile.ramp(0.7 * wn, 1.3 * wn, dur)
        t = np.arange(0.0, dur, 1e-3)
        s = simulate(m, prof, t, np.array([4 * m.tool_node, 4 * m.tool_node + 1]),
                     t0_s=-3.0)
        amp = np.abs(s.q[:, 0] + 1j * s.q[:, 1])                 # forward whirl: |x + iy|
        exact = np.abs(jeffcott_response(m, s.speed_rpm * RPM))
        errs.append(np.max(np.abs(amp - exact)) / exact.max())
        peaks.append(s.speed_rpm[np.argmax(amp)] / s.speed_rpm[np.argmax(exact)] - 1)
    p = np.log(errs[0] / errs[1]) / np.log(4.0)
    assert abs(p - 1.0) < 0.25
    assert 0 < peaks[1] < peaks[0]


def test_start_must_be_at_constant_speed_and_times_need_two_samples():
    m = jeffcott_model()
    with pytest.raises(ValueError, match="constant between t0_s"):
        simulate(m, SpeedProfile.ramp(1000.0, 2000.0, 1.0), np.arange(10) * 1e-3 + 0.5,
                 np.array([0]), t0_s=0.0)
    with pytest.raises(ValueError, match="at least two times"):
        simulate(m, SpeedProfile.constant(1000.0), np.array([0.1]), np.array([0]))
