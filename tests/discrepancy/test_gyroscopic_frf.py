"""Known answer: the FRF of an impact at speed peaks at the closed-form forward and backward
whirl frequencies of a rigid rotor (the data that tell gyroscopics from an inertia change).

A rigid symmetric rotor on two identical isotropic bearings ``k`` at ``±a`` from its centre
(Genta, *Dynamics of Rotating Systems*, 2005, §4.3; Lalanne & Ferraris 1998, ch. 3): the
cylindrical mode ``ω² = 2k/m`` does not depend on the spin; the conical modes solve
``J_t ω² ∓ J_p Ω ω − 2 k a² = 0``, forward ``ω_f = (J_p Ω + √(J_p²Ω² + 4 J_t k_θ)) / (2 J_t)``
and backward ``ω_b = (−J_p Ω + √(…)) / (2 J_t)``. A hit at the rotor's end excites both; with
light damping the FRF's peaks sit at these frequencies. Under 1x excitation only ``ω = Ω`` is
seen, where a polar-inertia change equals minus a diametral one; off it the split is
``(ω_f − ω_b) = J_p Ω / J_t`` exactly.
"""

from __future__ import annotations

import numpy as np
import pytest

from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.sweeps import Channel, Sweep
from surrogate_rbrdo.spindle.assembly import RPM

from ..spindle.conftest import rigid_rotor_geometry, rigid_rotor_properties

K_B = 1e7


def _peak_hz(fm, rpm, lo, hi):
    f = np.linspace(lo, hi, 4001)
    end = fm.channels[0]
    H = fm.response(Sweep.impact(f, (end,), rpm), np.ones((1, 2)), np.ones((1, 2)))[0, :, 0, 0]
    return f[int(np.argmax(np.abs(H)))], f[1] - f[0]


@pytest.mark.known_answer
@pytest.mark.parametrize("rpm", [0.0, 12000.0, 24000.0])
def test_impact_at_speed_peaks_at_forward_and_backward_whirl(rpm):
    g = rigid_rotor_geometry(K_B, c=2.0)           # ζ ~ 1e-4: peaks at the undamped roots
    fm = ForwardModel(g, (), (Channel("end_x", 0.0, "x"),), (100.0,))
    m, Jt, Jp, a = rigid_rotor_properties()
    Om = rpm * RPM
    root = np.sqrt((Jp * Om) ** 2 + 4 * Jt * 2 * K_B * a**2)
    wf, wb = (Jp * Om + root) / (2 * Jt), (-Jp * Om + root) / (2 * Jt)
    for w in {wf, wb}:
        f0 = w / (2 * np.pi)
        peak, df = _peak_hz(fm, rpm, 0.97 * f0, 1.03 * f0)
        assert peak == pytest.approx(f0, abs=2 * df)
    ft = np.sqrt(2 * K_B / m) / (2 * np.pi)        # cylindrical: the same at every speed
    peak, df = _peak_hz(fm, rpm, 0.97 * ft, 1.03 * ft)
    assert peak == pytest.approx(ft, abs=2 * df)
    if rpm > 0:   # precondition: the split J_p Ω / J_t is resolved by the FRF lines
        assert (wf - wb) / (2 * np.pi) > 50 * df
