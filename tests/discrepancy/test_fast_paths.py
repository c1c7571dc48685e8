"""The hot path's reuse of θ-free parts and of built effects against the direct computation
(the same numbers, bit for bit)."""

from __future__ import annotations

import numpy as np

from surrogate_rbrdo.discrepancy.candidates import candidate
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.impedance import (
    BearingParts,
    bearing_dynamic_stiffness,
    bearing_parts,
    with_supports,
)
from surrogate_rbrdo.discrepancy.sweeps import Channel, Sweep
from surrogate_rbrdo.spindle.assembly import bearing_coefficients
from surrogate_rbrdo.spindle.effects import CrossCoupling, HousingFlexibility, ThermalPreload

EXTRA = (HousingFlexibility(k_N_per_m=5e8, m_kg=20.0, c_Ns_per_m=2000.0),
         CrossCoupling(kappa=0.1), ThermalPreload(b=0.4, q=1.5))


def test_bearing_parts_give_the_direct_coefficients(spindle):
    """θ applied to the kept θ-free stiffness equals bearing_coefficients at every row."""
    sp, g = spindle
    effects, stiff = sp.effects + EXTRA, sp.effects + EXTRA[1:]
    names = tuple(b.name for b in g.bearings)
    rng = np.random.default_rng(3)
    spin = np.linspace(0.0, 2500.0, 7)
    theta = rng.uniform(0.6, 1.4, (5, len(names)))
    ds = rng.uniform(0.5, 2.0, (5, len(names)))
    K, C = bearing_coefficients(g, stiff, names, np.broadcast_to(spin, (5, 7)), theta)
    w = 1.3 * spin[None, :, None, None, None]
    direct = K + 1j * w * C * ds[:, None, :, None, None]
    parts = bearing_parts(g, effects, spin)
    fast = bearing_dynamic_stiffness(g, effects, names, spin, 1.3 * spin, theta, ds, parts)
    plain = bearing_dynamic_stiffness(g, stiff, names, spin, 1.3 * spin, theta, ds)
    no_stage = bearing_dynamic_stiffness(g, stiff, names, spin, 1.3 * spin, theta, ds,
                                         bearing_parts(g, stiff, spin))
    np.testing.assert_array_equal(plain, no_stage)
    np.testing.assert_array_equal(no_stage, direct)
    # the housing stage condensed in: Z − Z (Z + z_h I)⁻¹ Z on the direct coefficients
    h = EXTRA[0]
    zh = h.k_N_per_m + 1j * 1.3 * spin * h.c_Ns_per_m - (1.3 * spin) ** 2 * h.m_kg
    Zs = direct - direct @ np.linalg.solve(direct + zh[None, :, None, None, None] * np.eye(2),
                                           direct)
    np.testing.assert_allclose(fast, Zs, rtol=1e-12, atol=0)


def test_candidate_effects_are_built_once_and_equal_a_fresh_build():
    c = candidate("housing", ("front", "rear"))
    vals = {"k_N_per_m": 2e-9, "m_kg": 10.0, "c_Ns_per_m": 0.0}
    a = c.effect(("front",), vals)
    assert c.effect(("front",), dict(vals)) is a
    assert a == c._effect(("front",), vals)
    assert c.effect((), vals) == c._effect((), vals) != a
    b = c.effect(("front",), {**vals, "m_kg": 10.0 + 1e-12})
    assert b != a and b.m_kg == 10.0 + 1e-12


def test_housing_stages_of_many_rows_at_once_equal_each_row_alone(spindle):
    """Rows with different housing stages (and none) condensed in one batch
    (:func:`with_supports`, what the forward model does for a linearisation's rows) give each
    row's own :func:`bearing_dynamic_stiffness`, bit for bit."""
    sp, g = spindle
    names = tuple(b.name for b in g.bearings)
    rng = np.random.default_rng(5)
    spin = np.linspace(0.0, 2500.0, 6)
    freq = 1.1 * spin + 30.0
    extras = [(), EXTRA[:1], (EXTRA[0].__class__(k_N_per_m=3e8, m_kg=5.0, c_Ns_per_m=0.0,
                                                 bearings=("front",)),), EXTRA[1:]]
    theta = rng.uniform(0.6, 1.4, (len(extras), len(names)))
    ds = rng.uniform(0.5, 2.0, (len(extras), len(names)))
    parts = [bearing_parts(g, sp.effects + e, spin) for e in extras]
    one = np.concatenate([bearing_dynamic_stiffness(g, sp.effects + e, names, spin, freq,
                                                    theta[i:i + 1], ds[i:i + 1], parts[i])
                          for i, e in enumerate(extras)])
    stiff = tuple(np.concatenate([p.stiffness[j] for p in parts]) for j in range(len(names)))
    Z = bearing_dynamic_stiffness(g, sp.effects, names, spin, freq, theta, ds,
                                  BearingParts(stiff, (None,) * len(names)))
    batch = with_supports(Z, freq, [p.supports for p in parts])
    assert any(s is not None for s in parts[2].supports) and parts[2].supports[1] is None
    np.testing.assert_array_equal(batch, one)
    # and the forward model's identified-stiffness path, rows grouped by their effects
    fm = ForwardModel(g, sp.effects, (Channel("tool_x", 0.0, "x"),), (0.0,))
    sw = Sweep.unbalance(spin[1:] * 60 / (2 * np.pi))
    rows = [extras[i % len(extras)] for i in range(7)]
    th = rng.uniform(0.6, 1.4, (7, len(names)))
    dd = rng.uniform(0.5, 2.0, (7, len(names)))
    got = fm.bearing_impedance(sw, th, dd, rows)
    for i, e in enumerate(rows):
        np.testing.assert_array_equal(got[i], fm.bearing_impedance(sw, th[i:i + 1],
                                                                   dd[i:i + 1], [e])[0])
