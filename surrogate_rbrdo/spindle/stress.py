"""Maximum von Mises stress in the shaft, and which loads produce it.

Loads combined (each can be switched off):

* **static weight** of a horizontal spindle (gravity along −y): consistent element loads and the
  disk weights, bearings at their stiffness at the evaluation speed;
* **unbalance response** at the evaluation speed (the speed of the peak tool amplitude by
  default): the rotating bending moment's largest value over a revolution (the semi-major
  axis of its moment ellipse), added to the static moment (an upper bound);
* **preload**: the front bearing's axial preload compresses the shaft between the bearings;
* **centrifugal hoop stress** of a rotating hollow cylinder at the maximum speed
  (Timoshenko & Goodier, plane stress) at the outer and inner surfaces;
* **torque** (optional): a rated motor torque carried between the motor rotor and the tool.

Element bending moments come from the element end forces (elastic, minus the element's own
distributed weight or plus its inertia; see :func:`_element_moments`) at both element ends.
With ``σ_z = ±(|M| r / I + |N| / A)`` and the hoop stress ``σ_θ`` the von Mises stress is
``sqrt(σ_z² − σ_z σ_θ + σ_θ² + 3 τ²)``; the sign giving the larger value is taken.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.errors import SingularSystemError
from surrogate_rbrdo.spindle.assembly import MM, RPM, SpindleModel
from surrogate_rbrdo.spindle.element import XPLANE, YPLANE
from surrogate_rbrdo.spindle.geometry import PreloadLaw
from surrogate_rbrdo.spindle.harmonic import orbit_amplitude, unbalance_response

GRAVITY = 9.81


@dataclass(frozen=True)
class StressResult:
    """Maximum von Mises stress (Pa), where it occurs (m from the tool tip) and its parts."""

    max_von_mises_Pa: float
    position_m: float
    bending_Pa: np.ndarray  # per element end (ne, 2)
    axial_Pa: np.ndarray  # per element
    hoop_outer_Pa: np.ndarray
    shear_Pa: np.ndarray


def hoop_stress(rho: float, nu: float, omega: float, r_in: float, r_out: float,
                r: float) -> float:
    """Centrifugal hoop stress of a free rotating hollow (or solid) disk at radius ``r``.

    >>> # solid disk, centre: (3 + ν)/8 ρ ω² b²
    >>> s = hoop_stress(7850.0, 0.3, 1000.0, 0.0, 0.05, 0.0)
    >>> round(s / ((3.3 / 8) * 7850.0 * 1e6 * 0.0025), 12)
    1.0
    """
    a2, b2 = r_in**2, r_out**2
    term = a2 * b2 / r**2 if (r > 0 and r_in > 0) else 0.0
    return (3 + nu) / 8 * rho * omega**2 * (a2 + b2 + term - (1 + 3 * nu) / (3 + nu) * r**2)


def _static_weight(model: SpindleModel, speed_rpm: float, theta) -> np.ndarray:
    M, _, K = model.system_matrices(speed_rpm * RPM, theta)
    f = np.zeros(M.shape[0])
    f[: model.n_dof] = -GRAVITY * (M[: model.n_dof, : model.n_dof] @ _y_rigid(model))
    try:
        return np.linalg.solve(K, f)[: model.n_dof]
    except np.linalg.LinAlgError as exc:
        raise SingularSystemError(
            "singular static stiffness: the rotor is not supported against rigid-body motion"
        ) from exc


def _y_rigid(model: SpindleModel) -> np.ndarray:
    """Unit rigid translation in y: M @ it is the consistent weight load of all parts."""
    v = np.zeros(model.n_dof)
    v[1::4] = 1.0
    return v


def _element_moments(model: SpindleModel, q: np.ndarray, *, omega: float = 0.0,
                     weight: bool = False) -> np.ndarray:
    """Bending-moment components at both ends of every element: (ne, 2 ends, 2 planes).

    The element end forces are ``(K_e − Ω² M_e + iΩ² G_e) q_e`` (elastic plus the element's
    own distributed inertia and gyroscopic moments; damping forces, < 1 % here, are left out)
    minus the element's consistent weight load when ``weight`` is set — so distributed loads
    give their fixed-end moments instead of being lumped at the nodes.
    """
    ne = model.n_nodes - 1
    out = np.zeros((ne, 2, 2), dtype=q.dtype)
    uy = np.zeros(8)
    uy[[1, 5]] = 1.0
    for e in range(ne):
        Me, Ke, Ge = model.element_mats[e]
        A = Ke if omega == 0.0 else Ke - omega**2 * Me + 1j * model.gyro_scale * omega**2 * Ge
        fe = A @ q[4 * e: 4 * e + 8]
        if weight:
            fe = fe + GRAVITY * (Me @ uy)  # minus the consistent load −g M_e u_y
        for p, plane in enumerate((XPLANE, YPLANE)):
            out[e, 0, p] = fe[plane[1]]
            out[e, 1, p] = fe[plane[3]]
    return out


def max_von_mises(
    model: SpindleModel,
    speed_rpm: float,
    theta: np.ndarray | None = None,
    *,
    weight: bool = True,
    unbalance: bool = True,
    preload: bool = True,
    centrifugal: bool = True,
    torque_Nm: float = 0.0,
) -> StressResult:
    """Maximum von Mises stress in the shaft at ``speed_rpm`` (see module docstring)."""
    ne = model.n_nodes - 1
    Ms = np.zeros((ne, 2, 2))
    if weight:
        Ms = _element_moments(model, _static_weight(model, speed_rpm, theta), weight=True)
    Md = np.zeros((ne, 2))
    if unbalance:
        q = unbalance_response(model, np.array([speed_rpm]), theta)[0, 0].reshape(-1)
        m = _element_moments(model, q, omega=speed_rpm * RPM)
        Md = orbit_amplitude(m[..., 0], m[..., 1])
    bending_M = np.hypot(Ms[..., 0], Ms[..., 1]) + Md  # (ne, 2)

    zb = {b.name: model.z[n] for b, n in zip(model.geometry.bearings, model.bearing_nodes,
                                           strict=True)}
    zmid = 0.5 * (model.z[:-1] + model.z[1:])
    N = np.zeros(ne)
    if preload and len(zb) >= 2:
        pre = [b for b in model.geometry.bearings if isinstance(b.law, PreloadLaw)]
        if pre:
            z0, z1 = min(zb.values()), max(zb.values())
            N[(zmid > z0) & (zmid < z1)] = max(b.law.preload_N for b in pre)
    T = np.zeros(ne)
    if torque_Nm:
        zd = [d.position_mm * MM for d in model.geometry.disks if "motor" in d.name]
        zt = model.z[model.tool_node]
        if zd:
            T[(zmid > min(zt, zd[0])) & (zmid < max(zt, zd[0]))] = abs(torque_Nm)

    omega_max = model.geometry.speed_max_rpm * RPM if centrifugal else 0.0
    best, where = 0.0, 0.0
    sb = np.zeros((ne, 2))
    sa = np.zeros(ne)
    sh = np.zeros(ne)
    ts = np.zeros(ne)
    for e in range(ne):
        s = model.sections[model.element_section[e]]
        ro, ri = s.outer_diameter / 2, s.inner_diameter / 2
        sa[e] = N[e] / s.area
        ts[e] = T[e] * ro / (2 * s.inertia)
        for r in (ro, ri) if ri > 0 else (ro,):
            hoop = hoop_stress(s.rho, s.nu, omega_max, ri, ro, r)
            if r == ro:
                sh[e] = hoop
            for end in (0, 1):
                sb[e, end] = bending_M[e, end] * ro / s.inertia
                sz = bending_M[e, end] * r / s.inertia + sa[e]
                tau = T[e] * r / (2 * s.inertia)
                vm = np.sqrt(sz**2 + sz * hoop + hoop**2 + 3 * tau**2)  # σ_z = −sz (worst)
                if vm > best:
                    best, where = vm, model.z[e + end]
    return StressResult(float(best), float(where), sb, sa, sh, ts)
