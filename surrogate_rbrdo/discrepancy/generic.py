"""Generic local sensitivities: the detector for what no library effect explains.

Sensitivity-based model updating (Friswell & Mottershead, *Finite Element Model Updating in
Structural Dynamics*, Kluwer 1995, ch. 7) parametrises "anything that could be wrong with the
structure" by local parameters: the bending stiffness and the mass of every shaft element, the
mass and diametral inertia of every disk, and a grounded spring at every node. Their first-order
changes of the observables span a subspace in which any local structural change — a crack, a
loose shrink fit, a magnetic pull on the motor, a mass error — leaves most of its signature.
The residual's best one-parameter fit among these directions (with the nuisance and the named
effects projected out first; the maximum over the directions calibrated by the bootstrap) is a
lack-of-fit statistic far more powerful against a local structural change than the omnibus χ²
with its thousands of degrees of freedom — and still only a detector: local parameters are not
named physical effects.

The derivatives are adjoint sensitivities of the full system at every point,
``∂y_c/∂p = −z_cᵀ (∂A/∂p) q`` with ``A q = F u`` (the fitted unbalance) and ``Aᵀ z_c = e_c``;
the bearings enter ``A`` through their impedance (housing stage condensed in).
"""

from __future__ import annotations

import numpy as np

from surrogate_rbrdo.discrepancy.fit import Fit
from surrogate_rbrdo.discrepancy.impedance import acts_on_rotor, bearing_dynamic_stiffness
from surrogate_rbrdo.discrepancy.problem import Problem

#: scale of a node spring's derivative (N/m): the order of a bearing's stiffness
NODE_SPRING_SCALE = 1e8


def _system(model, Z, sweep) -> np.ndarray:
    """Full dynamic stiffness ``(X, n, n)`` with the bearing impedances ``Z`` (X, nb, 2, 2)."""
    w = sweep.freq_rad_s[:, None, None]
    s = sweep.spin_rad_s[:, None, None]
    A = ((1 + 1j * w * model.beta) * model.K + (-(w**2) + 1j * w * model.alpha) * model.M
         + 1j * w * s * model.gyro_scale * model.G)
    for j, n in enumerate(model.bearing_nodes):
        d = slice(4 * n, 4 * n + 2)
        A[:, d, d] += Z[:, j]
    return A


def _perturbations(model, sweep) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per generic parameter: its DOFs and ``∂A/∂p`` on them at every point, ``(X, k, k)``."""
    w = sweep.freq_rad_s[:, None, None]
    s = sweep.spin_rad_s[:, None, None]
    a_k = 1 + 1j * w * model.beta
    a_m = -(w**2) + 1j * w * model.alpha
    out = []
    for e in range(model.element_mats.shape[0]):
        d = np.arange(4 * e, 4 * e + 8)
        Me, Ke, Ge = model.element_mats[e]
        out.append((d, a_k * Ke))
        out.append((d, a_m * Me + 1j * w * s * model.gyro_scale * Ge))
    for disk in model.geometry.disks:
        n = int(np.argmin(np.abs(model.z - disk.position_mm * 1e-3)))
        out.append((np.arange(4 * n, 4 * n + 2), a_m * disk.mass_kg * np.eye(2)))
        out.append((np.arange(4 * n + 2, 4 * n + 4),
                    a_m * disk.diametral_inertia_kgm2 * np.eye(2)))
    for n in range(model.n_nodes):
        out.append((np.arange(4 * n, 4 * n + 2),
                    np.broadcast_to(NODE_SPRING_SCALE * np.eye(2), w.shape[:1] + (2, 2))))
    return out


#: plausible range of each kind of generic change (relative, or N/m / NODE_SPRING_SCALE for a
#: node spring): what a rival explanation may use (:mod:`.rivals`). A shaft element can lose
#: nearly all of its bending stiffness (a crack or a fretted fit: Dimarogonas 1996) and gain
#: some where a shrink-fitted part stiffens it; its mass follows drawn geometry and density,
#: with unmodelled nuts, spacers and balancing rings adding some; a disk's mass and inertia may
#: be off by half (a motor rotor's laminations and windings, a holder drawn without its tool);
#: a grounded spring (a seal, a bearing row the model lacks, magnetic pull) is a fraction of a
#: bearing's stiffness, which is of the order of NODE_SPRING_SCALE. Its sign: see
#: :func:`node_spring_ranges`.
PLAUSIBLE = {"element_stiffness": (-0.9, 0.3), "element_mass": (-0.2, 0.3),
             "disk_mass": (-0.5, 0.5), "disk_inertia": (-0.5, 0.5), "node_spring": (-0.5, 0.5)}

#: a disk whose name contains this word is the motor's rotor: the plane of its air gap
MOTOR_WORD = "motor"


def node_spring_ranges(model) -> np.ndarray:
    """Plausible range ``(n_nodes, 2)`` of a grounded spring at each node (column units).

    Between a spinning shaft and the ground there are bearings, seals and — in a motor spindle
    — the motor's air gap. A passive mechanical connection (a seal, an elastomer ring, a
    bearing row the model lacks) stores energy ``½ k x²`` and so has a positive stiffness; a
    *negative* radial stiffness needs a field doing work, and in a spindle without magnetic
    bearings that is the motor's unbalanced magnetic pull (Dorrell & Smith 1994; Abele,
    Altintas & Brecher 2010, §3.3), acting over the rotor's lamination stack. So a spring may
    be negative only at the motor rotor's node and its two neighbours (the lumped disk stands
    for a stack of finite length: two elements of the reference spindle, 83 mm, about 1.3
    shaft diameters); elsewhere it is one-sided, ``[0, hi]``. Without a disk named ``motor…``
    the air gap's place is unknown and every node keeps both signs. Left out: the small
    negative direct stiffness a gas labyrinth seal can have (Childs, *Turbomachinery
    Rotordynamics*, 1993, ch. 5; its force scales with the pressure drop, a spindle's sealing
    air is a bar or two).

    This matters most at a bearing's own node: a constant spring there, with the bearing's
    stiffness factor θ recalibrated, spans ``{1, k(Ω)}`` and mimics any change ``a + b k(Ω)``
    of that bearing's stiffness — a further softening with speed needs a *negative* one (θ up,
    a constant taken away), which no passive part supplies; a preload growth needs a positive
    one, which a seal or a non-softening bearing row does (``docs/discrepancy.md``).
    """
    lo, hi = PLAUSIBLE["node_spring"]
    out = np.tile([0.0, hi], (model.n_nodes, 1))
    motor = [d for d in model.geometry.disks if MOTOR_WORD in d.name.lower()]
    if not motor:
        out[:, 0] = lo
        return out
    for d in motor:
        n = int(np.argmin(np.abs(model.z - d.position_mm * 1e-3)))
        out[max(n - 1, 0):n + 2, 0] = lo
    return out


def generic_labels(model) -> tuple[tuple[str, float, float], ...]:
    """Per generic local parameter, in the column order of :func:`generic_columns` (the order
    :func:`_perturbations` builds them in): its name and plausible range (:data:`PLAUSIBLE`,
    :func:`node_spring_ranges`; in the column's units)."""
    out = []
    for e in range(model.element_mats.shape[0]):
        out += [(f"stiffness of shaft element {e}", *PLAUSIBLE["element_stiffness"]),
                (f"mass of shaft element {e}", *PLAUSIBLE["element_mass"])]
    for disk in model.geometry.disks:
        out += [(f"mass of disk {disk.name}", *PLAUSIBLE["disk_mass"]),
                (f"diametral inertia of disk {disk.name}", *PLAUSIBLE["disk_inertia"])]
    beside = beside_bearings(model)
    out += [(f"grounded spring at node {n}" + _beside_label(beside.get(n, ())), float(lo),
             float(hi)) for n, (lo, hi) in enumerate(node_spring_ranges(model))]
    return tuple(out)


#: the label of a grounded spring within one shaft diameter of a bearing (:func:`beside_bearings`)
#: ends with this and the bearing's name (``beside bearings a and b`` when two qualify): with
#: the bearing's stiffness factor recalibrated such a spring spans the bearing's speed laws
#: (:func:`node_spring_ranges`)
BESIDE_BEARING = "beside bearing"


def shaft_diameter_at(geometry, position_mm: float) -> float:
    """Outer diameter (mm) of the shaft at ``position_mm``: the larger of the two sections'
    where sections meet there.

    >>> from surrogate_rbrdo.spindle.reference import reference_spindle
    >>> g = reference_spindle().geometry
    >>> shaft_diameter_at(g, 100.0), shaft_diameter_at(g, 50.0)
    (70.0, 70.0)
    """
    ends = np.cumsum([0.0] + [s.length_mm for s in geometry.sections])
    tol = 1e-9 * max(ends[-1], 1.0)
    ds = [s.outer_diameter_mm for s, a, b in zip(geometry.sections, ends[:-1], ends[1:],
                                                 strict=True) if a - tol <= position_mm <= b + tol]
    if not ds:
        raise ValueError(f"position_mm = {position_mm} is not allowed: must lie on the shaft, "
                         f"0 to {ends[-1]} mm")
    return float(max(ds))


def beside_bearings(model) -> dict[int, tuple[str, ...]]:
    """The bearings each node lies beside: within one shaft diameter (at the bearing,
    :func:`shaft_diameter_at`) of the bearing's centre, by axial distance, not node count.

    The basis is the bearing's seat, not the mesh: a spindle bearing set — one to three
    angular-contact rows, each about 0.3 bore wide (a 7014 row: 70 mm bore, 20 mm wide; ISO 15
    / FAG and SKF super-precision catalogues), with its spacers, lock nut and labyrinth — takes
    about one diameter of shaft either side of its centre, so a grounded stiffness there (a
    seal, a row the model lacks, a preload the model misses) acts on the bearing's own stretch
    of shaft. That stretch is stiff against the bearing: a cantilever one diameter ``d`` long
    has ``3EI/d³ = 3πEd/64`` ≈ 2e9 N/m for steel and d = 65 mm, twenty times a spindle
    bearing's ≈ 1e8 N/m, so the shaft barely bends between the spring and the bearing and, with
    the bearing's stiffness factor recalibrated, the spring mimics a change of that bearing's
    stiffness law (:func:`node_spring_ranges`). A node within one diameter of two bearings (a
    pair mounted close together) lies beside both, in the geometry's order.
    """
    g = model.geometry
    z_mm = np.asarray(model.z) * 1e3
    out: dict[int, tuple[str, ...]] = {}
    for b in g.bearings:
        reach = shaft_diameter_at(g, b.position_mm)
        for n in np.flatnonzero(np.abs(z_mm - b.position_mm) <= reach * (1 + 1e-9)):
            out[int(n)] = out.get(int(n), ()) + (b.name,)
    return out


def beside_names(label: str) -> tuple[str, ...]:
    """The bearings a generic parameter's label says it lies beside (the inverse of the
    labels :func:`generic_labels` writes; empty for none).

    >>> beside_names("grounded spring at node 7 beside bearings a, b and c")
    ('a', 'b', 'c')
    >>> beside_names("grounded spring at node 4 beside bearing front"), beside_names("x")
    (('front',), ())
    """
    _, sep, tail = label.partition(f" {BESIDE_BEARING}")
    if not sep:
        return ()
    tail = tail.removeprefix("s").strip()
    head, _, last = tail.rpartition(" and ")
    return tuple(n for n in head.split(", ") if n) + (last,) if head else (tail,)


def _beside_label(names: tuple[str, ...]) -> str:
    """`` beside bearing a`` / `` beside bearings a and b`` (empty for none)."""
    if not names:
        return ""
    if len(names) == 1:
        return f" {BESIDE_BEARING} {names[0]}"
    return f" {BESIDE_BEARING}s {', '.join(names[:-1])} and {names[-1]}"


def generic_columns(problem: Problem, fit: Fit) -> np.ndarray:
    """Unwhitened derivatives of the observables (residual order) with respect to every
    generic local parameter, at ``fit`` (unbalance held at its fitted value)."""
    fm = problem.forward
    rows = fit.par.rows(fit.x[None])
    extra = rows.extras[0]
    model = fm.model(tuple(e for e in extra if acts_on_rotor(e)))
    u = [x[0] for x in fit.evaluation.unbalance]
    cols, k = [], 0
    for b, idx in zip(problem.blocks, problem.channel_index, strict=True):
        sw = b.sweep
        Z = bearing_dynamic_stiffness(fm.geometry, fm.effects + extra, fm.theta_bearings,
                                      sw.spin_rad_s, sw.freq_rad_s,
                                      rows.theta_for(sw.kind), rows.damping)[0]
        A = _system(model, Z, sw)
        if fm.disks:  # recalibrated disk masses
            Zd = fm.disk_impedance(sw, rows.mass, model)[0]
            for j, d in enumerate(fm.disks):
                n = fm.node(model, d.position_mm)
                A[:, 4 * n:4 * n + 4, 4 * n:4 * n + 4] += Zd[:, j]
        dofs, _, _, F = fm.layout(model, sw)
        Ff = np.zeros((sw.freq_rad_s.size, A.shape[-1], F.shape[-1]), dtype=complex)
        Ff[:, dofs] = F
        if sw.kind == "unbalance_1x":
            f = Ff @ u[k]
            k += 1
        else:
            f = Ff.sum(axis=-1)
        q = np.linalg.solve(A, f[..., None])[..., 0]                       # (X, n)
        out = [4 * fm.node(model, c.position_mm) + c.dof_offset
               for c in (fm.channels[i] for i in idx)]
        E = np.zeros((A.shape[-1], len(out)))
        E[out, np.arange(len(out))] = 1.0
        zc = np.linalg.solve(np.swapaxes(A, -1, -2), np.broadcast_to(E, A.shape[:1] + E.shape))
        D = np.stack([-np.einsum("xkc,xkl,xl->xc", zc[:, d], dA, q[:, d])
                      for d, dA in _perturbations(model, sw)], axis=-1)     # (X, C, P)
        chain = rows.gain[0, idx] / (1 + 1j * sw.freq_rad_s[:, None] * rows.tau[0, idx])
        if sw.kind == "impact":
            chain = chain * rows.force_chain(sw.freq_rad_s)[0][:, None]
        D = D * chain[..., None]
        cols.append(np.stack([D.real, D.imag], axis=2).reshape(-1, D.shape[-1]))
    G = np.concatenate(cols)
    n_real = problem.n_obs - G.shape[0]          # identified stiffness and priors: untouched
    return np.vstack([G, np.zeros((n_real, G.shape[1]))])
