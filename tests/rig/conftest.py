"""Small rotors and rig set-ups shared by the rig tests."""

from __future__ import annotations

import numpy as np

from surrogate_rbrdo.spindle.assembly import build_model
from surrogate_rbrdo.spindle.geometry import SpindleGeometry

#: a Jeffcott rotor: a rigid symmetric rotor (E x 1e4) of mass M on two identical isotropic
#: bearings (k, c each), unbalance at the centre: x'' + (2c/M) x' + (2k/M) x = (U/M) Ω² e^{iΩt}
JEFFCOTT = {"k": 2.0e7, "c": 600.0, "U": 1e-5}


def jeffcott_model():
    L = 200.0
    data = {
        "sections": [{"length_mm": L, "outer_diameter_mm": 100.0, "elements": 2,
                      "material": "rigid"}],
        "materials": {"rigid": {"E_Pa": 2.1e15, "nu": 0.3, "rho_kg_m3": 7850.0}},
        "disks": [{"name": "disk", "position_mm": L / 2, "mass_kg": 8.0,
                   "polar_inertia_kgm2": 0.05, "diametral_inertia_kgm2": 0.03}],
        "bearings": [
            {"name": n, "position_mm": z, "law": {
                "type": "constant", "k_N_per_m": JEFFCOTT["k"],
                "c_matrix_Ns_per_m": [[JEFFCOTT["c"], 0.0], [0.0, JEFFCOTT["c"]]]}}
            for n, z in (("front", 0.0), ("rear", L))],
        "unbalances": [{"position_mm": L / 2, "magnitude_kgm": JEFFCOTT["U"]}],
        "tool_tip_mm": L / 2, "rayleigh_alpha_per_s": 0.0, "rayleigh_beta_s": 0.0,
    }
    return build_model(SpindleGeometry.from_dict(data))


def jeffcott_response(model, omega):
    """Closed-form steady-state complex amplitude of the centre node."""
    M = model.rotor_mass_kg
    k, c, U = 2 * JEFFCOTT["k"], 2 * JEFFCOTT["c"], JEFFCOTT["U"]
    return U * omega**2 / (k - M * omega**2 + 1j * c * omega)


def seeds(n, base=0):
    return [np.random.default_rng(base + i) for i in range(n)]
