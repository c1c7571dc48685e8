"""Known answers for the unbalance response and the peak search.

Sources
-------
* Jeffcott rotor (Jeffcott 1919, Phil. Mag. 37:304; Genta, *Dynamics of Rotating Systems*,
  §3.4): a rigid symmetric rotor with the unbalance ``U`` at its centre, on two identical
  isotropic bearings (stiffness k, damping c each) has the circular forward orbit
  ``|X| = e r² / sqrt((1 − r²)² + (2ζr)²)`` with ``e = U/m``, ``r = Ω/ω_n``,
  ``ω_n² = 2k/m``, ``ζ = 2c / (2 sqrt(2k m))``; the conical mode is not excited by symmetry.
  Its maximum over Ω is ``e / (2ζ sqrt(1 − ζ²))`` at ``r = 1/sqrt(1 − 2ζ²)`` (differentiate
  r⁴/((1 − r²)² + 4ζ²r²)); at ``r = 1`` the amplitude is ``e / (2ζ)``.
* Independent computation: the dense complex system ``(K − Ω²M + iΩ(C + ΩG)) Q = F`` assembled
  from :meth:`SpindleModel.system_matrices` (housing DOFs kept, not condensed) and solved with
  ``numpy.linalg.solve``; the unbalance force ``U Ω² e^{iφ} [1, −i]`` rotates with the spin.
"""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.core.errors import SingularSystemError
from surrogate_rbrdo.spindle.assembly import RPM
from surrogate_rbrdo.spindle.effects import (
    Anisotropy,
    CrossCoupling,
    HousingFlexibility,
    UnbalanceError,
)
from surrogate_rbrdo.spindle.harmonic import (
    orbit_amplitude,
    peak_tool_amplitude,
    solve_block_tridiagonal,
    tool_amplitude,
    unbalance_response,
)
from surrogate_rbrdo.spindle.reference import reference_spindle

from .conftest import build, dense_response, rigid_rotor_geometry, rigid_rotor_properties

K_B = 1e7
U = 1e-4  # kg m


def jeffcott(zeta: float, effects=()):
    m = rigid_rotor_properties()[0]
    c = zeta * np.sqrt(2 * K_B * m)  # per bearing: ζ = 2c / (2 sqrt(2 k m))
    return build(rigid_rotor_geometry(K_B, c=c, unbalance_kgm=U), effects)


def jeffcott_amplitude(speeds_rpm, zeta, k=K_B):
    m = rigid_rotor_properties()[0]
    r = np.asarray(speeds_rpm) * RPM / np.sqrt(2 * k / m)
    return U / m * r**2 / np.sqrt((1 - r**2) ** 2 + (2 * zeta * r) ** 2)


# --------------------------------------------------------------------------- Jeffcott
@pytest.mark.known_answer
@pytest.mark.parametrize("zeta", [0.05, 0.005, 0.001])
def test_jeffcott_amplitude_versus_speed(zeta):
    """Off resonance to 1e-5; within ±2 % of ω_n to 1e-4 (the rigid-rotor idealisation is
    biased by ~1e-7 in ω_n, amplified by 1/ζ near resonance)."""
    m = rigid_rotor_properties()[0]
    mod = jeffcott(zeta)
    wn_rpm = np.sqrt(2 * K_B / m) / RPM
    far = np.array([1000.0, 3000.0, 6000.0, 14000.0, 24000.0])
    near = wn_rpm * np.array([0.98, 0.995, 1.0, 1.005, 1.02])
    A = tool_amplitude(mod, far)[0]
    assert np.allclose(A, jeffcott_amplitude(far, zeta), rtol=1e-5)
    A = tool_amplitude(mod, near)[0]
    assert np.allclose(A, jeffcott_amplitude(near, zeta), rtol=1e-4)
    assert A[2] == pytest.approx(U / m / (2 * zeta), rel=1e-4)  # r = 1: e/(2ζ)
    q = unbalance_response(mod, far)[0, :, mod.tool_node]
    assert np.allclose(q[:, 1], -1j * q[:, 0], rtol=1e-9)  # circular forward orbit


@pytest.mark.known_answer
@pytest.mark.parametrize("zeta", [0.005, 0.001])
def test_peak_search_finds_the_damped_jeffcott_peak(zeta):
    """peak_tool_amplitude = e/(2ζ sqrt(1−ζ²)) at Ω = ω_n/sqrt(1−2ζ²) to < 0.1 % (measured:
    3e-6 and 1e-4 in amplitude, 4e-7 in speed)."""
    m = rigid_rotor_properties()[0]
    pk = peak_tool_amplitude(jeffcott(zeta))
    e = U / m
    assert pk.amplitude[0] == pytest.approx(e / (2 * zeta * np.sqrt(1 - zeta**2)), rel=1e-3)
    w_peak = np.sqrt(2 * K_B / m) / np.sqrt(1 - 2 * zeta**2)
    assert pk.speed_rpm[0] == pytest.approx(w_peak / RPM, rel=1e-4)


@pytest.mark.known_answer
def test_peak_search_below_and_above_the_resonance():
    """Monotone response in the range: the peak sits at an end point. Above resonance (range
    wholly sub-critical) it is the upper end; in a super-critical range the lower end."""
    m = rigid_rotor_properties()[0]
    mod = jeffcott(0.01)
    wn_rpm = np.sqrt(2 * K_B / m) / RPM
    pk = peak_tool_amplitude(mod, speed_range_rpm=(1000.0, 0.5 * wn_rpm))
    assert pk.speed_rpm[0] == pytest.approx(0.5 * wn_rpm)
    assert pk.amplitude[0] == pytest.approx(jeffcott_amplitude(0.5 * wn_rpm, 0.01), rel=1e-5)
    pk = peak_tool_amplitude(mod, speed_range_rpm=(1.5 * wn_rpm, 3 * wn_rpm))
    assert pk.speed_rpm[0] == pytest.approx(1.5 * wn_rpm)


@pytest.mark.parametrize(
    "effects",
    [(), (HousingFlexibility(k_N_per_m=2e8, m_kg=3.0, c_Ns_per_m=800.0),
          Anisotropy(s=0.3), CrossCoupling(kappa=0.2), UnbalanceError(epsilon=0.2,
                                                                        delta_deg=30.0)),
     (HousingFlexibility(k_N_per_m=5e7, bearings=("rear",)),)],
    ids=["default", "housing+aniso+cross", "massless-housing-rear"],
)
def test_unbalance_response_equals_dense_solve(effects):
    """Block-tridiagonal solver with housing condensation = dense solve (rel 1e-8), on the
    reference spindle with its default effects plus the given ones, at two θ samples."""
    sp = reference_spindle()
    mod = sp.model(sp.baseline, effects=sp.effects + tuple(effects))
    speeds = np.array([1500.0, 7000.0, 15000.0, 23000.0])
    for th in (np.array([1.0, 1.0]), np.array([0.85, 1.1])):
        q = unbalance_response(mod, speeds, th)[0]
        ref = dense_response(mod, speeds, th)
        scale = np.abs(ref).max(axis=(1, 2), keepdims=True)
        assert np.all(np.abs(q - ref) <= 1e-8 * scale)


def test_batched_theta_and_speed_grids_match_single_calls():
    sp = reference_spindle()
    mod = sp.model(sp.baseline)
    th = np.array([[1.0, 1.0], [0.9, 1.1], [1.2, 0.7]])
    grids = np.array([[2000.0, 9000.0], [3000.0, 12000.0], [4000.0, 20000.0]])
    A = tool_amplitude(mod, grids, th)
    for b in range(3):
        assert np.allclose(A[b], tool_amplitude(mod, grids[b], th[b])[0], rtol=1e-12)


@pytest.mark.parametrize("k", [1, 2, 4])
def test_solve_block_tridiagonal_equals_dense_solve(k):
    rng = np.random.default_rng(12345)
    T, n = 4, 7
    D = rng.normal(size=(T, n, k, k)) + 1j * rng.normal(size=(T, n, k, k)) + 5 * np.eye(k)
    Up = rng.normal(size=(T, n - 1, k, k)) + 1j * rng.normal(size=(T, n - 1, k, k))
    Lo = rng.normal(size=(T, n - 1, k, k))
    f = rng.normal(size=(T, n, k)) + 1j * rng.normal(size=(T, n, k))
    x = solve_block_tridiagonal(D, Up, Lo, f)
    for t in range(T):
        A = np.zeros((n * k, n * k), dtype=complex)
        for i in range(n):
            A[i * k:(i + 1) * k, i * k:(i + 1) * k] = D[t, i]
            if i < n - 1:
                A[i * k:(i + 1) * k, (i + 1) * k:(i + 2) * k] = Up[t, i]
                A[(i + 1) * k:(i + 2) * k, i * k:(i + 1) * k] = Lo[t, i]
        assert np.allclose(x[t].ravel(), np.linalg.solve(A, f[t].ravel()), rtol=1e-10)


@pytest.mark.known_answer
def test_orbit_amplitude_of_an_ellipse():
    """x = a cos t, y = b sin t has semi-major axis max(a, b), for either sense of whirl."""
    for a, b in ((3.0, 1.0), (1.0, 2.5)):
        for sense in (1, -1):
            X, Y = np.array(a + 0j), np.array(-1j * sense * b)
            t = np.linspace(0, 2 * np.pi, 100001)
            r = np.hypot((X * np.exp(1j * t)).real, (Y * np.exp(1j * t)).real)
            assert float(orbit_amplitude(X, Y)) == pytest.approx(r.max(), rel=1e-9)


# --------------------------------------------------------------------------- bad input
def test_bad_speed_grids_raise():
    mod = jeffcott(0.01)
    with pytest.raises(ValueError, match=r"speeds_rpm = \[\]"):
        unbalance_response(mod, np.array([]))
    with pytest.raises(ValueError, match=r"speeds_rpm = \[3000.0, \.\.\., 1000.0\].*increasing"):
        unbalance_response(mod, np.array([3000.0, 2000.0, 1000.0]))
    with pytest.raises(ValueError, match="speeds_rpm"):
        unbalance_response(mod, np.array([-5.0, 1000.0]))
    with pytest.raises(ValueError, match=r"speed_range_rpm = \(2000.0, 1000.0\)"):
        peak_tool_amplitude(mod, speed_range_rpm=(2000.0, 1000.0))
    with pytest.raises(ValueError, match=r"theta = \[-1.0, 1.0\]"):
        unbalance_response(mod, np.array([1000.0]), np.array([-1.0, 1.0]))
    with pytest.raises(ValueError, match="theta has shape"):
        unbalance_response(mod, np.array([1000.0]), np.array([1.0, 1.0, 1.0]))


def test_undamped_resonance_raises_instead_of_nan():
    """An undamped Jeffcott rotor driven exactly at a (numerically) singular speed raises
    SingularSystemError; it never returns NaN or inf."""
    m = rigid_rotor_properties()[0]
    mod = build(rigid_rotor_geometry(K_B, unbalance_kgm=U))  # no damping at all
    wn_rpm = np.sqrt(2 * K_B / m) / RPM
    speeds = wn_rpm * (1 + np.linspace(-1e-12, 1e-12, 2001))
    with pytest.raises(SingularSystemError):
        tool_amplitude(mod, speeds)


# --------------------------------------------------------------------------- reference spindle
def fine_sweep_peak(model, theta, lo=1000.0, hi=24000.0):
    """Independent peak: 1 000-point geometric sweep, then 4 001 points in ±1 % around each of
    its three highest local maxima (final spacing 5e-6 of the speed)."""
    g = np.geomspace(lo, hi, 1000)
    A = tool_amplitude(model, g, theta)[0]
    is_max = np.r_[True, A[1:] >= A[:-1]] & np.r_[A[:-1] >= A[1:], True]
    best = A.max()
    for j in np.flatnonzero(is_max)[np.argsort(-A[is_max])][:3]:
        f = np.linspace(max(lo, 0.99 * g[j]), min(hi, 1.01 * g[j]), 4001)
        best = max(best, tool_amplitude(model, f, theta)[0].max())
    return best


PEAK_CASES = [
    ("baseline", (2000.0, 500.0, 65.0), (1.0, 1.0)),
    ("long-thick", (3000.0, 750.0, 80.0), (1.2, 0.8)),
    ("long-thin", (1000.0, 750.0, 50.0), (0.8, 1.2)),
]
SLOW_CASES = [
    (f"x{i}-t{j}", x, th)
    for i, x in enumerate([(2000.0, 500.0, 65.0), (1000.0, 300.0, 50.0), (3000.0, 750.0, 80.0),
                           (1000.0, 750.0, 50.0), (3000.0, 300.0, 80.0), (1000.0, 300.0, 80.0),
                           (3000.0, 750.0, 50.0), (1500.0, 600.0, 60.0)])
    for j, th in enumerate([(1.0, 1.0), (0.8, 1.2), (1.2, 0.8), (0.7, 0.7)])
]


def _check_peak(x, th, tol=1e-3):
    sp = reference_spindle()
    mod = sp.model(np.array(x))
    th = np.array(th)
    pk = peak_tool_amplitude(mod, th)
    ref = fine_sweep_peak(mod, th)
    assert abs(pk.amplitude[0] / ref - 1) < tol, (x, th, pk.amplitude[0] / ref - 1)
    return pk.amplitude[0] / ref - 1


@pytest.mark.known_answer
@pytest.mark.parametrize(("name", "x", "th"), PEAK_CASES, ids=[c[0] for c in PEAK_CASES])
def test_peak_search_on_reference_spindle(name, x, th):
    """Within 0.1 % of a fine sweep (measured ≤ 9e-5 at the centre and corners)."""
    _check_peak(x, th)


@pytest.mark.slow
@pytest.mark.known_answer
@pytest.mark.parametrize(("name", "x", "th"), SLOW_CASES, ids=[c[0] for c in SLOW_CASES])
def test_peak_search_on_reference_spindle_many_designs(name, x, th):
    _check_peak(x, th)
