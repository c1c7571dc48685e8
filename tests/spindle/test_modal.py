"""Known answers for modal analysis: rigid rotor on springs, gyroscopic whirl splitting.

Sources
-------
* Rigid symmetric rotor on two identical isotropic bearings ``k`` at ``±a`` from the centre of
  mass (Genta, *Dynamics of Rotating Systems*, 2005, §4.3; Lalanne & Ferraris, *Rotordynamics
  Prediction in Engineering*, 2nd ed. 1998, ch. 3): translational (cylindrical) mode
  ``ω² = 2k/m``, unaffected by spin; conical mode ``J_t ω² ∓ J_p Ω ω − 2 k a² = 0``, whose
  forward branch ``ω_f = (J_p Ω + sqrt(J_p²Ω² + 4 J_t k_θ)) / (2 J_t)`` rises with Ω and
  whose backward branch falls.
* Overhung disk (mass m, diametral J_d, polar J_p) at the free end of a massless Euler–Bernoulli
  shaft on two spring supports (span a, overhang b): the 2x2 tip flexibility is the beam part
  (``b²(a+b)/3EI``, ``b(2a+3b)/6EI``, ``(a+3b)/3EI``; Roark's *Formulas for Stress and Strain*,
  overhanging beam) plus the rigid-body part of the springs; with the complex whirl coordinate
  ``r = x + iy`` the frequency equation is ``det(K_d − diag(m ω², J_d ω² − J_p Ω ω)) = 0``
  (Lalanne & Ferraris §2.3 for the disk's gyroscopic moment), a quartic in ω whose positive
  roots are forward and negative roots backward whirls.
"""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.spindle.assembly import RPM
from surrogate_rbrdo.spindle.effects import Gyroscopics, HousingFlexibility
from surrogate_rbrdo.spindle.geometry import SpindleGeometry
from surrogate_rbrdo.spindle.modal import (
    campbell,
    critical_speeds,
    first_natural_frequency,
    modal_analysis,
)

from .conftest import build, constant_bearing, rigid_rotor_geometry, rigid_rotor_properties

K_B = 1e7  # N/m per bearing


def conical(Om: float, k: float = K_B) -> tuple[float, float]:
    m, Jt, Jp, a = rigid_rotor_properties()
    kt = 2 * k * a**2
    root = np.sqrt((Jp * Om) ** 2 + 4 * Jt * kt)
    return (Jp * Om + root) / (2 * Jt), (-Jp * Om + root) / (2 * Jt)


# --------------------------------------------------------------------------- rigid rotor
@pytest.mark.known_answer
def test_rigid_rotor_translational_and_conical_modes_at_rest():
    """ω = sqrt(2k/m) and sqrt(2ka²/J_t) to 1e-6 (shaft flexibility bias ~1e-7)."""
    m, Jt, _, a = rigid_rotor_properties()
    mod = build(rigid_rotor_geometry(K_B))
    assert mod.rotor_mass_kg == pytest.approx(m, rel=1e-12)
    w = modal_analysis(mod, 0.0, n_modes=4).frequency_hz * 2 * np.pi
    assert np.allclose(w[:2], np.sqrt(2 * K_B / m), rtol=1e-6)
    assert np.allclose(w[2:], np.sqrt(2 * K_B * a**2 / Jt), rtol=1e-6)
    f1 = first_natural_frequency(mod) * 2 * np.pi
    assert f1 == pytest.approx(np.sqrt(2 * K_B / m), rel=1e-6)


@pytest.mark.known_answer
@pytest.mark.parametrize("rpm", [5000.0, 12000.0, 24000.0])
def test_rigid_rotor_gyroscopic_split_and_labels(rpm):
    """Conical forward/backward frequencies equal the analytic roots; the higher one is labelled
    forward; the translational pair keeps sqrt(2k/m) and is labelled one forward, one backward."""
    m = rigid_rotor_properties()[0]
    mod = build(rigid_rotor_geometry(K_B))
    res = modal_analysis(mod, rpm, n_modes=4)
    w = res.frequency_hz * 2 * np.pi
    wf, wb = conical(rpm * RPM)
    i_f = int(np.argmin(np.abs(w - wf)))
    i_b = int(np.argmin(np.abs(w - wb)))
    assert w[i_f] == pytest.approx(wf, rel=1e-6)
    assert w[i_b] == pytest.approx(wb, rel=1e-6)
    assert res.whirl[i_f] == "forward" and res.whirl[i_b] == "backward"
    tr = [i for i in range(4) if i not in (i_f, i_b)]
    assert np.allclose(w[tr], np.sqrt(2 * K_B / m), rtol=1e-6)
    assert sorted(res.whirl[tr].tolist()) == ["backward", "forward"]


@pytest.mark.known_answer
def test_critical_speeds_of_an_isotropic_rigid_rotor():
    """Exactly one 1x forward crossing in 1000–24000 rpm: the translational critical speed
    sqrt(2k/m) (the forward conical branch stays above 1x since J_p/J_t < 1 here:
    ω_f = Ω needs Ω² = 2ka²/(J_t − J_p), i.e. 36 900 rpm).

    Regression test of a bug: the two modes of the (spin-independent, degenerate) translational
    pair got arbitrary forward/backward labels, so the k-th forward mode jumped between
    branches and ``critical_speeds`` returned up to 15 spurious crossings.
    """
    m, Jt, Jp, a = rigid_rotor_properties()
    for c in (None, 50.0):  # undamped and damped bearings
        mod = build(rigid_rotor_geometry(K_B, c=c))
        crit = critical_speeds(mod, np.linspace(1000.0, 24000.0, 24))
        zeta = (2 * (c or 0.0)) / (2 * np.sqrt(2 * K_B * m))
        wn = np.sqrt(2 * K_B / m)
        expected = wn * np.sqrt(1 - zeta**2) / RPM  # damped frequency = Ω
        assert crit.size == 1, crit
        assert crit[0] == pytest.approx(expected, rel=1e-6)
    assert np.sqrt(2 * K_B * a**2 / (Jt - Jp)) / RPM > 24000.0


@pytest.mark.known_answer
def test_campbell_forward_rises_backward_falls():
    """Over a speed grid the forward conical branch rises and the backward one falls, and each
    point matches the analytic branches."""
    mod = build(rigid_rotor_geometry(K_B))
    sp = np.linspace(0.0, 24000.0, 7)
    c = campbell(mod, sp, n_modes=4, refine=False)
    fw = np.array([conical(s * RPM)[0] for s in sp]) / (2 * np.pi)
    bw = np.array([conical(s * RPM)[1] for s in sp]) / (2 * np.pi)
    for i in range(1, sp.size):
        f, wh = c.frequency_hz[i], c.whirl[i]
        assert np.min(np.abs(f[wh == "forward"] - fw[i])) < 1e-6 * fw[i]
        assert np.min(np.abs(f[wh == "backward"] - bw[i])) < 1e-6 * bw[i]
    assert np.all(np.diff(fw) > 0) and np.all(np.diff(bw) < 0)


# --------------------------------------------------------------------------- overhung disk
OVH = {"a_mm": 300.0, "b_mm": 150.0, "d_mm": 30.0, "k": 5e6, "m": 5.0, "Jp": 0.04, "Jd": 0.02}


def overhung_geometry(rho=7.85e-2):
    """Nearly massless (ρ = 1e-5 steel: shaft mass 2.5e-5 kg vs a 5 kg disk) EB shaft."""
    o = OVH
    return SpindleGeometry.from_dict({
        "sections": [
            {"length_mm": o["a_mm"], "outer_diameter_mm": o["d_mm"], "material": "light"},
            {"length_mm": o["b_mm"], "outer_diameter_mm": o["d_mm"], "material": "light"}],
        "materials": {"light": {"E_Pa": 2.1e11, "nu": 0.3, "rho_kg_m3": rho}},
        "disks": [{"name": "disk", "position_mm": o["a_mm"] + o["b_mm"], "mass_kg": o["m"],
                   "polar_inertia_kgm2": o["Jp"], "diametral_inertia_kgm2": o["Jd"]}],
        "bearings": [constant_bearing("b1", 0.0, o["k"]),
                     constant_bearing("b2", o["a_mm"], o["k"])],
        "rayleigh_alpha_per_s": 0.0, "rayleigh_beta_s": 0.0})


def overhung_analytic(Om: float) -> tuple[np.ndarray, np.ndarray]:
    """Forward and backward whirl frequencies (rad/s) of the overhung disk."""
    o = OVH
    EI = 2.1e11 * np.pi * (o["d_mm"] * 1e-3) ** 4 / 64
    a, b = o["a_mm"] * 1e-3, o["b_mm"] * 1e-3
    flex = np.array([[b * b * (a + b) / (3 * EI), b * (2 * a + 3 * b) / (6 * EI)],
                     [b * (2 * a + 3 * b) / (6 * EI), (a + 3 * b) / (3 * EI)]])
    for j, (P, Q) in enumerate(((1.0, 0.0), (0.0, 1.0))):  # rigid motion on the springs
        F2 = (P * (a + b) + Q) / a  # support reactions from statics
        d1, d2 = (P - F2) / o["k"], F2 / o["k"]
        flex[0, j] += d1 + (d2 - d1) * (a + b) / a
        flex[1, j] += (d2 - d1) / a
    Kd = np.linalg.inv(flex)
    w = np.polynomial.Polynomial([0.0, 1.0])
    p = (Kd[0, 0] - o["m"] * w**2) * (Kd[1, 1] - o["Jd"] * w**2 + o["Jp"] * Om * w) \
        - Kd[0, 1] * Kd[1, 0]
    r = p.roots()
    r = np.real(r[np.abs(r.imag) < 1e-9 * np.abs(r)])
    return np.sort(r[r > 0]), np.sort(-r[r < 0])


@pytest.mark.known_answer
@pytest.mark.parametrize("rpm", [0.0, 6000.0, 20000.0])
def test_overhung_disk_whirl_frequencies(rpm):
    """All four whirl frequencies (two forward, two backward) to 2e-5 (shaft-mass bias 3e-6);
    forward = higher of each pair, labels from modal_analysis agree."""
    mod = build(overhung_geometry(), shear=False, rotary=False)
    res = modal_analysis(mod, rpm, n_modes=4)
    w = res.frequency_hz * 2 * np.pi
    fw, bw = overhung_analytic(rpm * RPM)
    assert fw.size == 2 and bw.size == 2
    if rpm == 0.0:
        assert np.allclose(fw, bw)
        assert np.allclose(w, np.repeat(fw, 2), rtol=2e-5)
        return
    assert np.allclose(np.sort(w[res.whirl == "forward"]), fw, rtol=2e-5)
    assert np.allclose(np.sort(w[res.whirl == "backward"]), bw, rtol=2e-5)
    w0 = overhung_analytic(0.0)[0]
    assert np.all(fw > w0) and np.all(bw < w0)


@pytest.mark.known_answer
def test_gyroscopics_off_removes_the_split():
    """g = −1: forward and backward frequencies coincide at speed and equal the Ω = 0 ones."""
    mod = build(overhung_geometry(), [Gyroscopics(g=-1.0)], shear=False, rotary=False)
    w = modal_analysis(mod, 20000.0, n_modes=4).frequency_hz * 2 * np.pi
    w0 = overhung_analytic(0.0)[0]
    assert np.allclose(w, np.repeat(w0, 2), rtol=2e-5)
    # and g = +1 doubles J_p: the analytic split with 2 J_p
    mod2 = build(overhung_geometry(), [Gyroscopics(g=1.0)], shear=False, rotary=False)
    w2 = modal_analysis(mod2, 10000.0, n_modes=4).frequency_hz * 2 * np.pi
    OVH["Jp"] *= 2
    try:
        fw, bw = overhung_analytic(10000.0 * RPM)
    finally:
        OVH["Jp"] /= 2
    assert np.allclose(np.sort(w2), np.sort(np.concatenate([fw, bw])), rtol=2e-5)


# --------------------------------------------------------------------------- errors
@pytest.mark.known_answer
def test_massless_housing_stage_gives_the_series_spring_frequencies():
    """A housing stage without mass leaves DOFs with zero mass. Modal analysis (pencil form) and
    the first natural frequency (static condensation) must then give the rigid-rotor result
    with the series stiffness k k_h / (k + k_h): translation sqrt(2 k_s / m) and, at standstill,
    tilt sqrt(2 k_s a^2 / J_t)."""
    k_h = 1e7
    mod = build(rigid_rotor_geometry(K_B), [HousingFlexibility(k_N_per_m=k_h)])
    m, Jt, _, a = rigid_rotor_properties()
    ks = K_B * k_h / (K_B + k_h)
    w = np.sort(modal_analysis(mod, 0.0, n_modes=4).frequency_hz) * 2 * np.pi
    assert np.allclose(w[:2], np.sqrt(2 * ks / m), rtol=1e-6)
    assert np.allclose(w[2:], np.sqrt(2 * ks * a**2 / Jt), rtol=1e-6)
    f1 = first_natural_frequency(mod) * 2 * np.pi
    assert f1 == pytest.approx(np.sqrt(2 * ks / m), rel=1e-6)


def test_bad_speed_raises():
    mod = build(rigid_rotor_geometry(K_B))
    with pytest.raises(ValueError, match=r"speed_rpm = -1\.0"):
        modal_analysis(mod, -1.0)
    with pytest.raises(ValueError, match="speeds_rpm"):
        campbell(mod, np.array([2000.0, 1000.0]))
