"""Known answers for the Timoshenko rotor element: uniform beams, exact statics, convergence.

Sources
-------
* Simply supported Timoshenko beam: with ``w = W sin kz``, ``ψ = Ψ cos kz`` (``k = nπ/L``)
  Timoshenko's equations ``ρA w_tt = κGA (w'' − ψ')`` and ``ρI ψ_tt = EI ψ'' + κGA (w' − ψ)``
  give the 2x2 determinant ``(κGA k² − ρAω²)(EI k² + κGA − ρIω²) − (κGA k)² = 0``, i.e. the
  quadratic in ω² ``ρA ρI s ω⁴ − (ρI k² + ρA s EI k² + ρA) ω² + EI k⁴ = 0`` with
  ``s = 1/(κGA)`` (Han, Benaroya & Wei 1999, J. Sound Vib. 225:935, Eq. for the hinged–hinged
  beam; ``s = 0`` is the Rayleigh beam, ``ρI = 0`` the shear beam, both the Euler–Bernoulli one).
* Free–free Timoshenko beam: the 4x4 boundary determinant of the general solution
  ``w = C1 cosh αz + C2 sinh αz + C3 cos βz + C4 sin βz`` (Huang 1961, J. Appl. Mech. 28:579;
  Han et al. 1999 §4) solved here with scipy's brentq; its Euler–Bernoulli limit
  ``cosh βL cos βL = 1`` has roots βL = 4.7300, 7.8532, 10.9956 (Blevins, *Formulas for
  Natural Frequency and Mode Shape*, Table 8-1).
* Timoshenko cantilever tip deflection ``P L³/(3EI) + P L/(κGA)`` (Timoshenko & Gere).

Mesh convergence (measured, 1 m x 100 mm steel beam, relative frequency error):

* Euler–Bernoulli (shear=False, rotary=False), simply supported, mode 3:
  4/8/16/32 elements -> 1.8e-2, 1.3e-3, 8.3e-5, 5.2e-6 (rate 3.8, 3.96, 3.99: O(h⁴)).
* Timoshenko (shear + rotary), simply supported, mode 3:
  4/8/16/32 elements -> 4.2e-2, 8.4e-3, 1.9e-3, 4.8e-4 (rate 2.3, 2.1, 2.0: O(h²)).
  The element is statically exact but its shear strain ``w' − ψ`` is constant per element
  (the shear force of a load-free element); the dynamic mode's shear strain varies along the
  beam, so the shear-energy part of the Rayleigh quotient converges as O(h²). The rate is
  therefore 4 only as long as shear energy is negligible (slender beams) and 2 asymptotically.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
from scipy.optimize import brentq

from surrogate_rbrdo.spindle.element import (
    BeamSection,
    element_matrices,
    planar_stiffness,
    shear_coefficient_hollow,
)

from .conftest import build, uniform_beam_geometry

L_M = 1.0  # beam length (m)


def _section(d_m: float) -> BeamSection:
    return BeamSection(d_m, 0.0, 2.1e11, 0.3, 7850.0)


def _props(d_m: float):
    s = _section(d_m)
    EI = s.E * s.inertia
    return EI, s.rho * s.area, s.rho * s.inertia, s.kappa * s.shear_modulus * s.area


def ss_timoshenko(n: int, d_m: float, *, shear: bool = True, rotary: bool = True) -> float:
    """Exact ω (rad/s) of mode ``n`` of a simply supported beam (bending branch)."""
    EI, rhoA, rhoI, kGA = _props(d_m)
    k = n * np.pi / L_M
    s = 1.0 / kGA if shear else 0.0
    rI = rhoI if rotary else 0.0
    a = rhoA * rI * s
    b = rI * k**2 + rhoA * s * EI * k**2 + rhoA
    c = EI * k**4
    return float(np.sqrt(2 * c / (b + np.sqrt(b * b - 4 * a * c))))  # smaller root, stable


def ff_timoshenko_det(w: float, d_m: float) -> float:
    """Free–free frequency determinant of a Timoshenko beam (below the cut-off frequency)."""
    EI, rhoA, rhoI, kGA = _props(d_m)
    # e^{sz}: κGA EI s⁴ + ω²(κGA ρI + EI ρA) s² + ρA ω² (ρI ω² − κGA) = 0
    a, b = kGA * EI, w**2 * (kGA * rhoI + EI * rhoA)
    c = rhoA * w**2 * (rhoI * w**2 - kGA)
    disc = np.sqrt(b * b - 4 * a * c)
    al, be = np.sqrt((-b + disc) / (2 * a)), np.sqrt((b + disc) / (2 * a))
    cc = rhoA * w**2 / kGA
    pa, pb = al + cc / al, be - cc / be  # ψ from κGA(w'' − ψ') = −ρAω² w

    def rows(z):
        ch, sh, co, si = np.cosh(al * z), np.sinh(al * z), np.cos(be * z), np.sin(be * z)
        dw = np.array([al * sh, al * ch, -be * si, be * co])
        psi = np.array([pa * sh, pa * ch, -pb * si, pb * co])
        dpsi = np.array([pa * al * ch, pa * al * sh, -pb * be * co, -pb * be * si])
        return [dpsi, dw - psi]  # bending moment EIψ' = 0, shear force κGA(w' − ψ) = 0

    A = np.array(rows(0.0) + rows(L_M))
    return float(np.linalg.det(A / np.abs(A).max(axis=0)))


def ff_timoshenko(n_modes: int, d_m: float) -> np.ndarray:
    grid = np.linspace(10.0, 20000.0, 4001)
    vals = np.array([ff_timoshenko_det(w, d_m) for w in grid])
    idx = np.nonzero(np.sign(vals[:-1]) != np.sign(vals[1:]))[0][:n_modes]
    return np.array([brentq(ff_timoshenko_det, grid[i], grid[i + 1], args=(d_m,), xtol=1e-10,
                            rtol=1e-13) for i in idx])


def fe_frequencies(d_m, elements, k_bearing, *, shear=True, rotary=True):
    """Sorted ω (rad/s) of eigh(K_total, M) at Ω = 0; every bending mode appears twice (x, y)."""
    g = uniform_beam_geometry(L_M * 1e3, d_m * 1e3, elements, k_bearing)
    M, _, K = build(g, shear=shear, rotary=rotary).system_matrices(0.0)
    return np.sqrt(np.abs(sla.eigh(K, M, eigvals_only=True)))


def ss_k_bearing(d_m: float) -> float:
    """Pin stiffness 1e9 EI/L³: the springs in series lower mode n by ≈ 2 n² π² / 1e9 (< 2e-7
    for n ≤ 3; energy of the end reactions EI k³ in the springs against the bending energy),
    while the eigen solve keeps ~eps x 1e9 ~ 1e-7 relative accuracy."""
    EI = _props(d_m)[0]
    return 1e9 * EI / L_M**3


# --------------------------------------------------------------------------- simply supported
@pytest.mark.known_answer
@pytest.mark.parametrize(
    ("shear", "rotary", "tol"),
    [(True, True, 5e-4), (True, False, 6e-4), (False, True, 1e-5), (False, False, 1e-5)],
)
def test_simply_supported_beam_matches_closed_form(shear, rotary, tol):
    """32 elements, L/d = 10: modes 1–3 of all four beam theories against the exact result."""
    d = 0.1
    w = fe_frequencies(d, 32, ss_k_bearing(d), shear=shear, rotary=rotary)
    # x and y planes identical (to the ~eps x 1e9 round-off of the stiff pins)
    assert np.allclose(w[0::2][:3], w[1::2][:3], rtol=1e-7)
    exact = np.array([ss_timoshenko(n, d, shear=shear, rotary=rotary) for n in (1, 2, 3)])
    err = np.abs(w[0::2][:3] / exact - 1)
    assert np.all(err < tol), err
    assert np.all(w[0::2][:3] >= exact * (1 - 1e-6))  # Rayleigh–Ritz bound: from above


@pytest.mark.known_answer
def test_shear_and_rotary_inertia_lower_the_frequencies_by_the_exact_amount():
    """Thick beam (L/d = 5): the Timoshenko/EB ratio of mode 2 equals the closed-form one."""
    d = 0.2
    w_t = fe_frequencies(d, 64, ss_k_bearing(d))[2]
    w_eb = fe_frequencies(d, 64, ss_k_bearing(d), shear=False, rotary=False)[2]
    ratio = ss_timoshenko(2, d) / ss_timoshenko(2, d, shear=False, rotary=False)
    assert ratio < 0.9  # a visible effect, not a rounding-level one
    assert w_t / w_eb == pytest.approx(ratio, rel=5e-4)


@pytest.mark.known_answer
def test_euler_bernoulli_formula_in_the_slender_limit():
    """ω_n = (nπ/L)² sqrt(EI/ρA): the EB element (1e-5) and the full Timoshenko element on a
    slender beam (L/d = 200, where shear + rotary inertia lower mode 1 by ~3e-5)."""
    EI, rhoA, _, _ = _props(0.1)
    d = 0.1
    eb = np.array([(n * np.pi / L_M) ** 2 * np.sqrt(EI / rhoA) for n in (1, 2, 3)])
    w = fe_frequencies(d, 32, ss_k_bearing(d), shear=False, rotary=False)[0::2][:3]
    assert np.allclose(w, eb, rtol=1e-5)
    d = 0.005
    EI, rhoA, _, _ = _props(d)
    eb1 = (np.pi / L_M) ** 2 * np.sqrt(EI / rhoA)
    w1 = fe_frequencies(d, 16, ss_k_bearing(d))[0]
    assert w1 == pytest.approx(eb1, rel=1e-4)
    assert w1 < eb1


def _rates(errors):
    e = np.asarray(errors)
    return np.log2(e[:-1] / e[1:])


@pytest.mark.known_answer
def test_mesh_convergence_simply_supported():
    """Error falls monotonically with 4/8/16/32 elements: O(h⁴) for Euler–Bernoulli, O(h²) for
    Timoshenko (constant shear strain per element, see the module docstring)."""
    d = 0.1
    meshes = (4, 8, 16, 32)
    for (shear, rotary), lo, hi in (((False, False), 3.7, 4.3), ((True, True), 1.9, 2.5)):
        exact = ss_timoshenko(3, d, shear=shear, rotary=rotary)
        err = [fe_frequencies(d, n, ss_k_bearing(d), shear=shear, rotary=rotary)[4] / exact - 1
               for n in meshes]
        assert np.all(np.asarray(err) > 0)
        r = _rates(err)
        assert np.all((r > lo) & (r < hi)), (shear, err, r)


# --------------------------------------------------------------------------- free–free
@pytest.mark.known_answer
def test_free_free_euler_bernoulli_roots():
    """cosh βL cos βL = 1 solved with brentq reproduces the tabulated 4.7300, 7.8532,
    10.9956; the EB element (32 elements, bearings of 1e-3 N/m) reproduces the frequencies."""
    f = lambda x: np.cosh(x) * np.cos(x) - 1.0  # noqa: E731
    roots = np.array([brentq(f, a, b, xtol=1e-14) for a, b in ((4, 5), (7, 8.5), (10.5, 11.5))])
    assert np.allclose(roots, [4.7300, 7.8532, 10.9956], atol=5e-5)
    d = 0.1
    EI, rhoA, _, _ = _props(d)
    exact = roots**2 / L_M**2 * np.sqrt(EI / rhoA)
    w = fe_frequencies(d, 32, 1e-3, shear=False, rotary=False)
    assert np.all(w[:4] < 1e-3 * exact[0])  # four rigid-body modes (2 planes x 2)
    assert np.allclose(w[4::2][:3], exact, rtol=1e-5)


@pytest.mark.known_answer
def test_free_free_timoshenko_beam_and_convergence():
    """Full Timoshenko element vs the roots of the free–free frequency determinant; relative
    error of modes 1–3 with 4/8/16/32 elements (measured: mode 1 2.9e-3, 6.1e-4, 1.4e-4,
    3.5e-5) decreases monotonically, at rate ≈ 2 (see module docstring)."""
    d = 0.1
    exact = ff_timoshenko(3, d)
    # EB limit as a sanity check of the root finder: Timoshenko is lower
    EI, rhoA, _, _ = _props(d)
    assert np.all(exact < np.array([4.7300, 7.8532, 10.9956]) ** 2 * np.sqrt(EI / rhoA))
    errs = []
    for n in (4, 8, 16, 32):
        w = fe_frequencies(d, n, 1e-3)
        errs.append(w[4::2][:3] / exact - 1)
    errs = np.array(errs)
    assert np.all(errs > 0)
    assert np.all(errs[-1] < 1e-3)
    assert np.all(np.diff(errs, axis=0) < 0)
    r = np.log2(errs[1:-1] / errs[2:])  # 8->16 and 16->32 (mode 3 on 4 elements: pre-asymptotic)
    assert np.all((r > 1.9) & (r < 2.2)), r


# --------------------------------------------------------------------------- element level
@pytest.mark.known_answer
@pytest.mark.parametrize("d_m", [0.02, 0.2])
def test_timoshenko_cantilever_tip_deflection_is_exact(d_m):
    """One element clamped at node 1: tip deflection P L³/(3EI) + P L/(κGA) exactly."""
    s = _section(d_m)
    L = 0.3
    EI = s.E * s.inertia
    kGA = s.kappa * s.shear_modulus * s.area
    k = planar_stiffness(EI, L, 12 * EI / (kGA * L**2))
    P = 1000.0
    w = np.linalg.solve(k[2:, 2:], [P, 0.0])
    assert w[0] == pytest.approx(P * L**3 / (3 * EI) + P * L / kGA, rel=1e-12)
    assert w[1] == pytest.approx(P * L**2 / (2 * EI), rel=1e-12)  # slope = rotation


@pytest.mark.known_answer
def test_element_rigid_body_inertia_is_exact():
    """Rigid translation and rotation carry m = ρAL and J = ρAL³/12 + ρIL about the centre;
    the gyroscopic matrix under a rigid tilt gives the polar inertia 2ρIL."""
    s = BeamSection(0.06, 0.02, 2.1e11, 0.3, 7850.0)
    L = 0.25
    M, K, G = element_matrices(s, L)
    tx = np.array([1, 0, 0, 0, 1, 0, 0, 0.0])
    assert tx @ M @ tx == pytest.approx(s.rho * s.area * L, rel=1e-13)
    assert np.allclose(K @ tx, 0, atol=1e-6 * np.abs(K).max())
    rot = np.array([-L / 2, 0, 1, 0, L / 2, 0, 1, 0.0])  # tilt about the centre, x plane
    J = s.rho * s.area * L**3 / 12 + s.rho * s.inertia * L
    assert rot @ M @ rot == pytest.approx(J, rel=1e-12)
    assert np.allclose(K @ rot, 0, atol=1e-6 * np.abs(K).max())
    roty = np.array([0, -L / 2, 0, 1, 0, L / 2, 0, 1.0])
    assert rot @ G @ roty == pytest.approx(2 * s.rho * s.inertia * L, rel=1e-12)


@pytest.mark.known_answer
def test_cowper_shear_coefficients():
    """Cowper (1966) Table 1: solid circle 6(1+ν)/(7+6ν); thin tube limit 2(1+ν)/(4+3ν)."""
    nu = 0.3
    assert shear_coefficient_hollow(nu, 0.0) == pytest.approx(6 * (1 + nu) / (7 + 6 * nu))
    assert shear_coefficient_hollow(nu, 1.0) == pytest.approx(2 * (1 + nu) / (4 + 3 * nu))
