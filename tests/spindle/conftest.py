"""Builders of simple verification rotors, shared by the spindle tests.

Every builder goes through :class:`SpindleGeometry.from_dict` and :func:`build_model`, so the
tests exercise the same path as the reference spindle. Units at input: mm, kg, N/m (field names).
"""

from __future__ import annotations

import numpy as np

from surrogate_rbrdo.spindle.assembly import RPM, build_model
from surrogate_rbrdo.spindle.geometry import SpindleGeometry

STEEL = {"E_Pa": 2.1e11, "nu": 0.3, "rho_kg_m3": 7850.0}


def constant_bearing(name, position_mm, k, *, c=None, eta=0.0, k_matrix=None):
    """A constant-law bearing: isotropic ``k`` (or a 2x2 ``k_matrix``), damping ``c`` (N s/m)."""
    law = {"type": "constant", "damping_eta_s": eta}
    if k_matrix is not None:
        law["k_matrix_N_per_m"] = k_matrix
    else:
        law["k_N_per_m"] = k
    if c is not None:
        law["c_matrix_Ns_per_m"] = [[c, 0.0], [0.0, c]]
    return {"name": name, "position_mm": position_mm, "law": law}


def uniform_beam_geometry(length_mm, diameter_mm, elements, k_bearing, *, material=None,
                          inner_mm=0.0, **extra):
    """A uniform shaft with isotropic constant-law bearings at both ends, undamped."""
    data = {
        "sections": [{"length_mm": length_mm, "outer_diameter_mm": diameter_mm,
                      "inner_diameter_mm": inner_mm, "elements": elements, "material": "m"}],
        "materials": {"m": dict(material or STEEL)},
        "bearings": [constant_bearing("left", 0.0, k_bearing),
                     constant_bearing("right", length_mm, k_bearing)],
        "rayleigh_alpha_per_s": 0.0,
        "rayleigh_beta_s": 0.0,
    }
    data.update(extra)
    return SpindleGeometry.from_dict(data)


#: the short "rigid" rotor: a 200 mm x 100 mm cylinder (E x 1e4, so its first bending mode is
#: ~100x the rigid-body modes: relative frequency bias ~ (1/100)^2 x 1e-4 ~ 1e-8) carrying a
#: central disk, on two identical bearings at its ends (a = 100 mm from the centre).
RIGID = {"length_mm": 200.0, "diameter_mm": 100.0, "disk_kg": 8.0, "disk_Ip": 0.05,
         "disk_Id": 0.03, "E_Pa": 2.1e15, "rho": 7850.0}


def rigid_rotor_geometry(k_bearing, *, c=None, unbalance_kgm=0.0, speed_range=(1000, 24000),
                         k_matrix=None, **extra):
    """Rigid symmetric rotor (see :data:`RIGID`) on two identical constant-law bearings."""
    L = RIGID["length_mm"]
    data = {
        "sections": [{"length_mm": L, "outer_diameter_mm": RIGID["diameter_mm"],
                      "elements": 2, "material": "rigid"}],
        "materials": {"rigid": {"E_Pa": RIGID["E_Pa"], "nu": 0.3, "rho_kg_m3": RIGID["rho"]}},
        "disks": [{"name": "disk", "position_mm": L / 2, "mass_kg": RIGID["disk_kg"],
                   "polar_inertia_kgm2": RIGID["disk_Ip"],
                   "diametral_inertia_kgm2": RIGID["disk_Id"]}],
        "bearings": [constant_bearing("left", 0.0, k_bearing, c=c, k_matrix=k_matrix),
                     constant_bearing("right", L, k_bearing, c=c, k_matrix=k_matrix)],
        "unbalances": [{"position_mm": L / 2, "magnitude_kgm": unbalance_kgm}],
        "tool_tip_mm": L / 2,
        "rayleigh_alpha_per_s": 0.0,
        "rayleigh_beta_s": 0.0,
        "speed_min_rpm": float(speed_range[0]),
        "speed_max_rpm": float(speed_range[1]),
    }
    data.update(extra)
    return SpindleGeometry.from_dict(data)


def rigid_rotor_properties():
    """Analytic mass, transverse and polar inertia (about the centre) of :data:`RIGID` (SI).

    Uniform cylinder: m = ρ A L, J_t = m (L²/12 + r²/4), J_p = m r²/2; plus the disk.
    """
    L = RIGID["length_mm"] * 1e-3
    r = RIGID["diameter_mm"] * 1e-3 / 2
    ms = RIGID["rho"] * np.pi * r**2 * L
    m = ms + RIGID["disk_kg"]
    Jt = ms * (L**2 / 12 + r**2 / 4) + RIGID["disk_Id"]
    Jp = ms * r**2 / 2 + RIGID["disk_Ip"]
    return m, Jt, Jp, L / 2


def build(geometry, effects=(), **kw):
    return build_model(geometry, effects, **kw)


def dense_response(model, speeds_rpm, theta=None):
    """Independent solve of the full dense system (rotor + housing DOFs)."""
    out = []
    for s in speeds_rpm:
        Om = s * RPM
        M, C, K = model.system_matrices(Om, theta)
        F = np.zeros(M.shape[0], dtype=complex)
        for node, u in zip(model.unbalance_nodes, model.unbalance, strict=True):
            F[4 * node] += u * Om**2
            F[4 * node + 1] += -1j * u * Om**2
        Q = np.linalg.solve(K - Om**2 * M + 1j * Om * C, F)
        out.append(Q[: model.n_dof].reshape(-1, 4))
    return np.array(out)
