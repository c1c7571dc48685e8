"""Known answers for the stress module.

* Simply supported uniform beam under its own weight w = ρAg: M_max = w L²/8 at mid-span,
  σ = M r / I (Timoshenko & Gere, *Mechanics of Materials*). The module takes element bending
  moments from the elastic end forces ``K_e q_e`` without subtracting the fixed-end moments
  of the distributed load (w L_e²/12), which under-/over-states the mid-span moment by
  (2/3)/n_e² of w L²/8: the error measured is 2.6e-3 with 16 elements, 6.5e-4 with 32.
* Rotating disk hoop stress (Timoshenko & Goodier, *Theory of Elasticity*, §32): solid disk
  centre ``(3+ν)/8 ρω²b²``; hollow disk inner surface ``(3+ν)/4 ρω² (b² + (1−ν)/(3+ν) a²)``.
"""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.core.errors import SingularSystemError
from surrogate_rbrdo.spindle.geometry import SpindleGeometry
from surrogate_rbrdo.spindle.reference import reference_spindle
from surrogate_rbrdo.spindle.stress import GRAVITY, hoop_stress, max_von_mises

from .conftest import build, constant_bearing, uniform_beam_geometry


@pytest.mark.known_answer
def test_simply_supported_beam_under_its_weight():
    d, L = 0.05, 1.0
    w = 7850.0 * GRAVITY * np.pi / 4 * d**2
    sigma = w * L**2 / 8 * (d / 2) / (np.pi * d**4 / 64)
    errs = []
    for n in (16, 32):
        mod = build(uniform_beam_geometry(1000.0, 50.0, n, 1e13))
        r = max_von_mises(mod, 1000.0, unbalance=False, centrifugal=False, preload=False)
        assert r.position_m == pytest.approx(0.5)
        errs.append(r.max_von_mises_Pa / sigma - 1)
    errs = np.array(errs)
    # element end forces include the fixed-end moments of the distributed weight, so the
    # nodal moments of a uniformly loaded beam are exact at any mesh (wL²/8 at mid-span)
    assert np.all(np.abs(errs) < 1e-9), errs


@pytest.mark.known_answer
def test_hoop_stress_closed_forms():
    rho, nu, om, a, b = 7850.0, 0.3, 2500.0, 0.015, 0.035
    assert hoop_stress(rho, nu, om, 0.0, b, 0.0) == pytest.approx(
        (3 + nu) / 8 * rho * om**2 * b**2, rel=1e-13)
    assert hoop_stress(rho, nu, om, a, b, a) == pytest.approx(
        (3 + nu) / 4 * rho * om**2 * (b**2 + (1 - nu) / (3 + nu) * a**2), rel=1e-13)
    # outer surface of the hollow disk: (3+ν)/4 ρω² (a² + (1−ν)/(3+ν) b²)
    assert hoop_stress(rho, nu, om, a, b, b) == pytest.approx(
        (3 + nu) / 4 * rho * om**2 * (a**2 + (1 - nu) / (3 + nu) * b**2), rel=1e-13)


@pytest.mark.known_answer
def test_centrifugal_only_stress_is_the_inner_hoop_stress():
    """With only the centrifugal load (at the maximum speed) the von Mises stress is the
    largest bore hoop stress σ_θ(a) over the shaft sections."""
    sp = reference_spindle()
    mod = sp.model(sp.baseline)
    r = max_von_mises(mod, 10000.0, weight=False, unbalance=False, preload=False)
    om = mod.geometry.speed_max_rpm * np.pi / 30
    expected = max(hoop_stress(s.rho, s.nu, om, s.inner_diameter / 2, s.outer_diameter / 2,
                               s.inner_diameter / 2) for s in mod.sections)
    assert r.max_von_mises_Pa == pytest.approx(expected, rel=1e-12)


@pytest.mark.known_answer
def test_preload_only_stress_is_axial():
    """Preload only: σ = F / A of the span sections between the bearings (largest F / A)."""
    sp = reference_spindle()
    mod = sp.model(sp.baseline)
    r = max_von_mises(mod, 10000.0, weight=False, unbalance=False, centrifugal=False)
    F = max(b.law.preload_N for b in mod.geometry.bearings)
    span = [s for s, g in zip(mod.sections, mod.geometry.sections, strict=True)
            if g.tag == "span"]
    assert r.max_von_mises_Pa == pytest.approx(F / min(s.area for s in span), rel=1e-12)


def test_unsupported_rotor_raises_model_error_not_linalg_error():
    """Regression test: a rotor whose bearings carry no stiffness has a singular static
    stiffness; the weight load case raised numpy's LinAlgError instead of the package's
    SingularSystemError (fixed in stress._static_weight)."""
    zero = [[0.0, 0.0], [0.0, 0.0]]
    geo = SpindleGeometry.from_dict({
        "sections": [{"length_mm": 1000.0, "outer_diameter_mm": 50.0, "elements": 8}],
        "bearings": [constant_bearing("a", 0.0, None, k_matrix=zero),
                     constant_bearing("b", 1000.0, None, k_matrix=zero)]})
    with pytest.raises(SingularSystemError, match="not supported"):
        max_von_mises(build(geo), 1000.0)
