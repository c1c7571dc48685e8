"""The forward model against an independent dense solve of the whole system."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy import forward
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.impedance import (
    acts_on_rotor,
    condensed_dynamic_stiffness,
    condensed_dynamic_stiffness_dense,
    with_supports,
)
from surrogate_rbrdo.discrepancy.sweeps import Channel, Sweep, with_nodes_at
from surrogate_rbrdo.spindle.assembly import RPM, build_model
from surrogate_rbrdo.spindle.effects import (
    CrossCoupling,
    Gyroscopics,
    HousingFlexibility,
    Joint,
    ToolInterface,
)

CHANNELS = (Channel("tool_x", 0.0, "x"), Channel("tool_y", 0.0, "y"),
            Channel("front_x", 100.0, "x"), Channel("rear_y", 600.0, "y"),
            Channel("mid_x", 250.0, "x"))
EXTRA = (HousingFlexibility(k_N_per_m=5e8, m_kg=20.0, c_Ns_per_m=2000.0),
         CrossCoupling(kappa=0.1), Gyroscopics(g=0.3))


def _dense_model(fm, extra, ds):
    """The same spindle with the damping factors put into the bearing laws, assembled whole."""
    m = fm.model(extra)
    bs = tuple(replace(b, law=replace(b.law, damping_eta_s=b.law.damping_eta_s * s))
               for b, s in zip(m.geometry.bearings, ds, strict=True))
    return build_model(replace(m.geometry, bearings=bs), m.effects)


def _at(model, Q, c):
    n = int(np.argmin(np.abs(model.z - c.position_mm * 1e-3)))
    return Q[4 * n + c.dof_offset]


@pytest.mark.known_answer
def test_unbalance_response_equals_dense_solve(spindle):
    sp, g = spindle
    fm = ForwardModel(g, sp.effects, CHANNELS, (0.0, 350.0))
    speeds = np.linspace(1000.0, 24000.0, 6)
    th, ds = np.array([[0.9, 1.1]]), np.array([[1.3, 0.8]])
    G = fm.response(Sweep.unbalance(speeds), th, ds, [EXTRA])[0]
    m = _dense_model(fm, EXTRA, ds[0])
    for i, s in enumerate(speeds):
        w = s * RPM
        M, C, K = m.system_matrices(w, th)
        for j, plane in enumerate((0.0, 350.0)):
            n = int(np.argmin(np.abs(m.z - plane * 1e-3)))
            F = np.zeros(M.shape[0], complex)
            F[4 * n], F[4 * n + 1] = w**2, -1j * w**2
            Q = np.linalg.solve(K - w**2 * M + 1j * w * C, F)
            ref = np.array([_at(m, Q, c) for c in CHANNELS])
            assert np.allclose(G[i, :, j], ref, rtol=0, atol=1e-10 * np.abs(Q).max())


@pytest.mark.known_answer
def test_impact_frf_equals_dense_solve_at_standstill(spindle):
    sp, g = spindle
    fm = ForwardModel(g, sp.effects, CHANNELS, (0.0, 350.0))
    freqs = np.linspace(50.0, 2000.0, 7)
    th, ds = np.array([[1.0, 0.95]]), np.array([[0.7, 1.2]])
    H = fm.response(Sweep.impact(freqs, (CHANNELS[0],)), th, ds, [EXTRA])[0, :, :, 0]
    m = _dense_model(fm, EXTRA, ds[0])
    M, C, K = m.system_matrices(0.0, th)
    for i, f in enumerate(freqs):
        w = 2 * np.pi * f
        F = np.zeros(M.shape[0], complex)
        F[0] = 1.0
        Q = np.linalg.solve(K - w**2 * M + 1j * w * C, F)
        ref = np.array([_at(m, Q, c) for c in CHANNELS])
        assert np.allclose(H[i], ref, rtol=0, atol=1e-10 * np.abs(Q).max())


@pytest.mark.known_answer
@pytest.mark.parametrize("rpm", [9000.0, 21000.0])
def test_impact_frf_equals_dense_solve_at_speed(spindle, rpm):
    """An impact at spin Ω (ω ≠ Ω): the condensed, Woodbury-coupled FRF equals the dense
    solve of ``K(Ω) + iω (C(Ω) + Ω G) − ω² M`` with housing, cross-coupling and gyroscopics."""
    sp, g = spindle
    fm = ForwardModel(g, sp.effects, CHANNELS, (0.0, 350.0))
    freqs = np.linspace(50.0, 2000.0, 7)
    th, ds = np.array([[1.05, 0.9]]), np.array([[0.8, 1.3]])
    H = fm.response(Sweep.impact(freqs, (CHANNELS[1],), rpm), th, ds, [EXTRA])[0, :, :, 0]
    m = _dense_model(fm, EXTRA, ds[0])
    M, C, K = m.system_matrices(rpm * RPM, th)
    for i, f in enumerate(freqs):
        w = 2 * np.pi * f
        F = np.zeros(M.shape[0], complex)
        F[1] = 1.0                                        # tool tip, y
        Q = np.linalg.solve(K - w**2 * M + 1j * w * C, F)
        ref = np.array([_at(m, Q, c) for c in CHANNELS])
        assert np.allclose(H[i], ref, rtol=0, atol=1e-10 * np.abs(Q).max())
    # at speed the gyroscopic and cross-coupled terms couple x to a y hit
    assert np.max(np.abs(H[:, 0])) > 1e-3 * np.max(np.abs(H[:, 1]))


def test_rows_with_other_effects_are_solved_apart(spindle):
    sp, g = spindle
    fm = ForwardModel(g, sp.effects, CHANNELS[:2], (0.0, 350.0))
    t = Sweep.unbalance([8000.0, 16000.0])
    th, ds = np.ones((3, 2)), np.ones((3, 2))
    both = fm.response(t, th, ds, [(), EXTRA[:1], ()])
    assert np.allclose(both[0], both[2])
    alone = fm.response(t, th[:1], ds[:1], [EXTRA[:1]])
    assert np.allclose(both[1], alone[0])
    assert not np.allclose(both[0], both[1])


def test_rotor_hooks_are_told_apart():
    assert not acts_on_rotor(HousingFlexibility(k_N_per_m=1e9))
    assert acts_on_rotor(Gyroscopics(g=0.2))


def test_nodes_are_added_at_channel_positions(spindle):
    _, g = spindle
    m = build_model(with_nodes_at(g, [37.0]))
    assert np.min(np.abs(m.z - 0.037)) < 1e-12


def test_bad_input_names_the_field(spindle):
    sp, g = spindle
    with pytest.raises(ValueError, match="direction"):
        Channel("p", 0.0, "z")
    with pytest.raises(ValueError, match="channels"):
        ForwardModel(g, sp.effects, (), (0.0,))
    with pytest.raises(ValueError, match="speed_rpm"):
        Sweep.impact([10.0], CHANNELS[:1], -5.0)
    with pytest.raises(ValueError, match="one spin speed"):
        Sweep("impact", np.array([0.0, 1.0]), np.array([5.0, 6.0]), CHANNELS[:1])
    fm = ForwardModel(g, sp.effects, CHANNELS[:1], (0.0,))
    with pytest.raises(ValueError, match="damping_scale"):
        fm.response(Sweep.unbalance([1000.0]), np.ones((2, 2)), np.ones((1, 2)))
    with pytest.raises(ValueError, match="extras: 1 rows"):
        fm.bearing_impedance(Sweep.unbalance([1000.0]), np.ones((3, 2)), np.ones((3, 2)),
                             [()])
    with pytest.raises(ValueError, match="supports"):
        with_supports(np.zeros((2, 1, 2, 2, 2), dtype=complex), np.zeros(1), [(None, None)])


@pytest.mark.known_answer
def test_several_sweeps_in_one_pass_equal_each_sweep_and_row_alone(spindle):
    """``responses`` (every sweep and row in one pass: rows sharing a rotor coupled together,
    sweeps with one stiffness array sharing the bearing impedance, hits in x and in y at one
    speed sharing the coupled system's factorisation) gives what ``response`` gives sweep by
    sweep and row by row (to round-off: a factorisation solved for two loads at once), with a
    mass disk, a rotor-acting row effect (gyroscopics), a housing stage and per-sweep
    stiffness factors."""
    sp, g = spindle
    fm = ForwardModel(g, sp.effects, CHANNELS, (0.0, 350.0), mass_disks=("tool_holder",))
    f = np.linspace(50.0, 2000.0, 5)
    sweeps = [Sweep.unbalance([3000.0, 12000.0, 21000.0])] + [
        Sweep.impact(f, (CHANNELS[i],), rpm) for rpm in (0.0, 15000.0) for i in (0, 1)]
    rng = np.random.default_rng(3)
    th = 1 + 0.2 * rng.random((5, 2))
    th_impact = th * (1 + 0.05 * rng.random((5, 2)))
    ds, mass = 1 + 0.3 * rng.random((5, 2)), 1 + 0.05 * rng.random((5, 1))
    extras = [(), EXTRA[:1], (), EXTRA[1:2], EXTRA]
    thetas = [th] + [th_impact] * 4
    got = fm.responses(sweeps, thetas, ds, extras, mass)
    for s, t, G in zip(sweeps, thetas, got, strict=True):
        for i in range(5):
            one = fm.response(s, t[i:i + 1], ds[i:i + 1], [extras[i]], mass[i:i + 1])[0]
            np.testing.assert_allclose(G[i], one, rtol=0, atol=1e-13 * np.abs(one).max())
    # the hits in x and in y at one speed did share one coupled system, the speeds did not
    rotor = fm.model()
    sx, sy, s15 = (fm._rotor(rotor, s).system for s in sweeps[1:4])
    assert sx == sy != s15
    # the impact sweeps saw their own stiffness factors, not the 1x sweep's
    other = fm.response(sweeps[1], th[:1], ds[:1], [extras[0]], mass[:1])[0]
    assert not np.allclose(got[1][0], other, rtol=1e-6, atol=0)


@pytest.mark.known_answer
@pytest.mark.parametrize("extra", [(), (Gyroscopics(g=0.4),),
                                   (ToolInterface(k_t_N_per_m=3e8, k_r_Nm_per_rad=5e6),)])
def test_node_by_node_condensation_equals_the_dense_schur_complement(spindle, extra):
    """The forward model's condensation (interior eliminated node by node along the shaft)
    against the dense ``A_dd − A_di A_ii⁻¹ A_id`` at standstill and at speed, ω ≠ Ω, across
    the FRF band and past the first clamped-interior resonances, with a joint in the mesh."""
    sp, g = spindle
    fm = ForwardModel(g, sp.effects, CHANNELS, (0.0, 350.0), mass_disks=("tool_holder",))
    m = fm.model(extra)
    sweep = Sweep.impact(np.linspace(20.0, 4000.0, 60), (CHANNELS[0],), 18000.0)
    dofs = fm.layout(m, sweep)[0]
    for spin in (np.zeros(60), sweep.spin_rad_s):
        a = condensed_dynamic_stiffness(m, spin, sweep.freq_rad_s, dofs)
        b = condensed_dynamic_stiffness_dense(m, spin, sweep.freq_rad_s, dofs)
        scale = np.abs(b).max(axis=(1, 2))[:, None, None]
        assert np.allclose(a, b, rtol=0, atol=1e-11 * scale)


@pytest.mark.known_answer
def test_disk_mass_changes_equal_dense_solve(spindle):
    """Rows with a recalibrated disk (its change of mass and inertias coupled in with the
    bearings) against the dense solve of the spindle assembled with that disk's mass and
    inertias scaled: rows sharing a factor and a row with its own."""
    sp, g = spindle
    fm = ForwardModel(g, sp.effects, CHANNELS, (0.0, 350.0), mass_disks=("tool_holder",))
    speeds = np.linspace(2000.0, 22000.0, 4)
    th = np.array([[0.9, 1.1], [1.05, 0.95], [0.9, 1.1]])
    ds = np.array([[1.3, 0.8], [1.0, 1.0], [1.3, 0.8]])
    mass = np.array([[1.07], [1.07], [0.9]])
    G = fm.response(Sweep.unbalance(speeds), th, ds, [EXTRA[:2]] * 3, mass)
    for r in range(3):
        m = _dense_model(fm, EXTRA[:2], ds[r])
        disks = tuple(replace(d, mass_kg=d.mass_kg * mass[r, 0],
                              diametral_inertia_kgm2=d.diametral_inertia_kgm2 * mass[r, 0],
                              polar_inertia_kgm2=d.polar_inertia_kgm2 * mass[r, 0])
                      if d.name == "tool_holder" else d for d in m.geometry.disks)
        m = build_model(replace(m.geometry, disks=disks), m.effects)
        for i, s in enumerate(speeds):
            w = s * RPM
            M, C, K = m.system_matrices(w, th[r:r + 1])
            n = int(np.argmin(np.abs(m.z - 0.0)))
            F = np.zeros(M.shape[0], complex)
            F[4 * n], F[4 * n + 1] = w**2, -1j * w**2
            Q = np.linalg.solve(K - w**2 * M + 1j * w * C, F)
            ref = np.array([_at(m, Q, c) for c in CHANNELS])
            assert np.allclose(G[r, i, :, 0], ref, rtol=0, atol=1e-10 * np.abs(Q).max())
    # the disk change matters at this size (the test could fail)
    same = fm.response(Sweep.unbalance(speeds), th[:1], ds[:1], [EXTRA[:2]], mass[2:])
    assert not np.allclose(same[0], G[0], rtol=1e-4, atol=0)


#: a joint at the tool-holder interface (where the candidate puts it) with housing and
#: cross-coupling in the same rows; the stiffnesses span the plausible range
JOINTS = [(3e6, 4e4), (2.2e8, 3.1e6), (2.9e8, 4.6e6), (2.943e9, 4.9e7)]


def _joint_rows(extra=EXTRA[:2]):
    return [extra + (ToolInterface(k_t_N_per_m=kt, k_r_Nm_per_rad=kr),) for kt, kr in JOINTS]


def _per_row_path(extra):
    """Today's path for every row: the joint left in the rotor (re-condensed per value)."""
    return tuple(x for x in extra if acts_on_rotor(x)), None


@pytest.mark.known_answer
def test_joint_rows_equal_dense_solve(spindle):
    """Rows with a tool-interface joint (each its own k_t, k_r; one condensed rotor per
    joint position, the change coupled in by Woodbury) against the dense solve of the spindle
    assembled with that joint, 1x sweep and impact tests at standstill and at speed, with
    bearing θ, damping factors, a housing stage, cross-coupling and a disk mass factor."""
    sp, g = spindle
    fm = ForwardModel(g, sp.effects, CHANNELS, (0.0, 350.0), mass_disks=("tool_holder",))
    speeds, freqs = np.linspace(2000.0, 24000.0, 5), np.linspace(50.0, 3000.0, 9)
    sweeps = [Sweep.unbalance(speeds), Sweep.impact(freqs, (CHANNELS[0],)),
              Sweep.impact(freqs, (CHANNELS[1],), 15000.0)]
    extras = _joint_rows()
    B = len(extras)
    rng = np.random.default_rng(5)
    th, ds = 0.8 + 0.4 * rng.random((B, 2)), 0.7 + 0.6 * rng.random((B, 2))
    mass = 1 + 0.1 * rng.random((B, 1))
    got = fm.responses(sweeps, [th] * 3, ds, extras, mass)
    for r in range(B):
        m = _dense_model(fm, extras[r], ds[r])
        disks = tuple(replace(d, mass_kg=d.mass_kg * mass[r, 0],
                              diametral_inertia_kgm2=d.diametral_inertia_kgm2 * mass[r, 0],
                              polar_inertia_kgm2=d.polar_inertia_kgm2 * mass[r, 0])
                      if d.name == "tool_holder" else d for d in m.geometry.disks)
        m = build_model(replace(m.geometry, disks=disks), m.effects)
        for i, s in enumerate(speeds):                       # 1x: unit unbalance at 0 mm
            w = s * RPM
            M, C, K = m.system_matrices(w, th[r:r + 1])
            F = np.zeros(M.shape[0], complex)
            F[0], F[1] = w**2, -1j * w**2
            Q = np.linalg.solve(K - w**2 * M + 1j * w * C, F)
            ref = np.array([_at(m, Q, c) for c in CHANNELS])
            assert np.allclose(got[0][r, i, :, 0], ref, rtol=0, atol=1e-10 * np.abs(Q).max())
        for k, (rpm, dof) in enumerate(((0.0, 0), (15000.0, 1)), start=1):  # tool hits
            M, C, K = m.system_matrices(rpm * RPM, th[r:r + 1])
            for i, f in enumerate(freqs):
                w = 2 * np.pi * f
                F = np.zeros(M.shape[0], complex)
                F[dof] = 1.0
                Q = np.linalg.solve(K - w**2 * M + 1j * w * C, F)
                ref = np.array([_at(m, Q, c) for c in CHANNELS])
                assert np.allclose(got[k][r, i, :, 0], ref, rtol=0,
                                   atol=1e-10 * np.abs(Q).max())
    # the joint matters at the tool (the test could fail)
    assert not np.allclose(got[1][0], got[1][3], rtol=1e-3, atol=0)


@pytest.mark.known_answer
def test_joint_rows_equal_per_row_condensation(spindle, monkeypatch):
    """The joint rows coupled low-rank equal the rotor re-condensed at each row's own joint
    (the path every row took before) to round-off, with and without gyroscopics, and the
    rows of one rotor share one condensation per sweep."""
    sp, g = spindle
    sweeps = [Sweep.unbalance(np.linspace(1000.0, 24000.0, 12)),
              Sweep.impact(np.linspace(20.0, 4000.0, 30), (CHANNELS[0],), 9000.0)]
    extras = _joint_rows(EXTRA[:1]) + _joint_rows(EXTRA[1:2]) + _joint_rows(EXTRA[2:])
    B = len(extras)
    rng = np.random.default_rng(8)
    th, ds = 0.8 + 0.4 * rng.random((B, 2)), 0.7 + 0.6 * rng.random((B, 2))
    calls = []

    def counted(*args):
        calls.append(args[0])
        return condensed_dynamic_stiffness(*args)

    monkeypatch.setattr(forward, "condensed_dynamic_stiffness", counted)
    fm = ForwardModel(g, sp.effects, CHANNELS, (0.0, 350.0))
    got = fm.responses(sweeps, [th, th], ds, extras)
    # two reference rotors (with and without gyroscopics), two sweeps; the bearing parts once
    # per bearing effects (housing, cross-coupling, none; the sweeps share one stiffness
    # array: one evaluation over both sweeps' speeds)
    assert len(calls) == 2 * 2
    assert len(fm._parts) == 3
    monkeypatch.setattr(forward, "_rotor_and_joint", _per_row_path)
    old = ForwardModel(g, sp.effects, CHANNELS, (0.0, 350.0)).responses(
        sweeps, [th, th], ds, extras)
    assert len(calls) == 4 + 8 * 2
    for a, b in zip(got, old, strict=True):
        for r in range(B):
            np.testing.assert_allclose(a[r], b[r], rtol=0, atol=1e-9 * np.abs(b[r]).max())


def test_rows_without_a_joint_are_unchanged_bit_for_bit(spindle, monkeypatch):
    """In a batch mixing rows with a joint, without one and with the joint off (k = inf: the
    rigid rotor), the rows without a coupled joint are what the per-row path gives, bit for
    bit, and the off rows equal the rows without any joint."""
    sp, g = spindle
    sweeps = [Sweep.unbalance(np.linspace(3000.0, 21000.0, 6)),
              Sweep.impact(np.linspace(50.0, 2000.0, 8), (CHANNELS[1],))]
    off = ToolInterface()
    extras = [EXTRA[:1] + (off,), _joint_rows()[1], (), EXTRA, _joint_rows()[3], (off,),
              EXTRA[:1]]
    B = len(extras)
    th, ds = np.linspace(0.9, 1.1, 2 * B).reshape(B, 2), np.ones((B, 2))
    fm = ForwardModel(g, sp.effects, CHANNELS, (0.0, 350.0), mass_disks=("tool_holder",))
    got = fm.responses(sweeps, [th, th], ds, extras)
    monkeypatch.setattr(forward, "_rotor_and_joint", _per_row_path)
    plain = [0, 2, 3, 5, 6]
    old = ForwardModel(g, sp.effects, CHANNELS, (0.0, 350.0),
                       mass_disks=("tool_holder",)).responses(
        sweeps, [th[plain]] * 2, ds[plain], [extras[i] for i in plain])
    bare = fm.responses(sweeps, [th[5:6]] * 2, ds[5:6], [()])
    for a, b, c in zip(got, old, bare, strict=True):
        np.testing.assert_array_equal(a[plain], b)
        np.testing.assert_array_equal(a[5], c[0])


def test_which_rows_couple_a_joint():
    tool = ToolInterface(k_t_N_per_m=2.943e9, k_r_Nm_per_rad=4.9e7)
    rotor, joint = forward._rotor_and_joint((EXTRA[0], tool))
    assert joint == tool.joint()
    assert rotor[0].joint() == Joint(0.0, *forward.JOINT_REFERENCE)
    assert forward._rotor_and_joint((ToolInterface(),)) == ((ToolInterface(),), None)
    assert forward._rotor_and_joint((EXTRA[2], tool))[0][0] is EXTRA[2]


@pytest.mark.known_answer
def test_near_rigid_joints_equal_the_solve_in_relative_coordinates(spindle):
    """Near-rigid joints (a candidate keeps the stiffness it does not vary at 1e18: "just on")
    against the dense solve with the joint's right node in relative coordinates
    ``u_R = u_L + δ``, where ``k`` enters only on δ's diagonal (no cancellation): the response
    to round-off, and the departure of a 1e12 N/m joint from the rigid rotor (what a
    finite-difference column at the off state divides by a compliance step) to 1e-6 of
    itself (a condensation at the row's own stiffness gets it wrong by several times)."""
    sp, g = spindle
    fm = ForwardModel(g, sp.effects, CHANNELS, (0.0, 350.0))
    freqs = np.linspace(50.0, 3000.0, 12)
    sweep = Sweep.impact(freqs, (CHANNELS[0],))
    th, ds = np.array([[0.95, 1.05]]), np.ones((1, 2))
    rows = [(1e12, 1e18), (1e15, 1e15), (3e8, 5e6)]
    got = fm.response(sweep, np.repeat(th, 3, 0), np.ones((3, 2)),
                      [(ToolInterface(k_t_N_per_m=kt, k_r_Nm_per_rad=kr),) for kt, kr in rows])
    rigid = fm.response(sweep, th, ds, [()])[0, ..., 0]
    m0 = build_model(fm.geometry, fm.effects + (forward._ReferenceJoint(
        position_mm=0.0, k_t_N_per_m=0.0, k_r_Nm_per_rad=0.0),))   # the joint cut
    M, C, K = m0.system_matrices(0.0, th)
    left = int(np.argmin(np.abs(m0.z)))
    T = np.eye(M.shape[0])
    T[4 * left + 4:4 * left + 8, 4 * left:4 * left + 4] = np.eye(4)
    for r, (kt, kr) in enumerate(rows):
        ref = np.empty((freqs.size, len(CHANNELS)), dtype=complex)
        for i, f in enumerate(freqs):
            w = 2 * np.pi * f
            A = T.T @ (K - w**2 * M + 1j * w * C) @ T
            A[4 * left + 4:4 * left + 8, 4 * left + 4:4 * left + 8] += np.diag(
                [kt, kt, kr, kr]) * (1 + 1j * w * m0.beta)
            F = np.zeros(M.shape[0], complex)
            F[4 * left] = 1.0
            Q = T @ np.linalg.solve(A, F)
            ref[i] = [_at(m0, Q, c) for c in CHANNELS]
        G = got[r, ..., 0]
        np.testing.assert_allclose(G, ref, rtol=0, atol=1e-10 * np.abs(ref).max())
        if r == 0:         # k_t at 1e12 moves the response by ~1e-4 of it: resolved
            change = ref - rigid
            np.testing.assert_allclose(G - rigid, change, rtol=0,
                                       atol=1e-6 * np.abs(change).max())
