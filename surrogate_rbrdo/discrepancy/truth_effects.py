"""Physical effects used only to build *truths* for blind tests — never candidates.

They change the truth's geometry, which no candidate of the library can do, so a workflow that
names a library effect for them is wrong by construction. They live in their own registry
(:data:`TRUTH_MODIFIERS`), apart from :data:`~surrogate_rbrdo.spindle.effects.EFFECTS`, and the
candidate list (:data:`~surrogate_rbrdo.discrepancy.candidates.DEFAULT_LIBRARY`) cannot name
them.

* ``magnetic_pull``: unbalanced magnetic pull of the motor, a *negative* radial stiffness
  ``−k_m`` at the motor-rotor plane (Dorrell & Smith, *IEE Proc. Electr. Power Appl.* 141,
  1994; for motor spindles Abele, Altintas & Brecher, *CIRP Annals* 59, 2010, §3.3). It pulls
  the bending mode down where bearing effects cannot act.
* ``disk_mass_error``: a disk (the motor rotor) heavier or lighter than drawn — the library
  has bearing, housing and interface effects, not mass errors of the rotor.
* ``shaft_stiffness_loss``: a local loss of bending stiffness of the shaft (a transverse crack,
  a fretted shrink fit) modelled as one shaft element of reduced diameter (the "equivalent
  reduced section" of Dimarogonas, *Eng. Fract. Mech.* 55, 1996, for an open crack; the
  crack's asymmetry and breathing are left out, so the truth stays linear and isotropic).
* ``bearing_seal``: a constant, speed-independent radial stiffness ``+k_s`` from shaft to
  ground beside a bearing (one mesh node from its plane) — a contact seal or an elastomer ring
  between shaft and housing there, or a bearing row whose stiffness does not change with speed
  (a cylindrical roller row beside angular-contact rows). Passive, so positive. With the
  model's bearing stiffness already falling with speed it makes the bearing's *relative*
  stiffness fall less — the sign of a thermal preload growth — which no library effect is
  (the sceptic's case against naming a bearing speed law).

>>> from surrogate_rbrdo.spindle.reference import reference_spindle
>>> sp = reference_spindle()
>>> g = sp.geometry_for(sp.baseline)
>>> gm = TRUTH_MODIFIERS["magnetic_pull"](g, k_N_per_m=2e7)
>>> [b.name for b in gm.bearings]
['front', 'rear', 'magnetic_pull']
>>> gs = TRUTH_MODIFIERS["shaft_stiffness_loss"](g, position_mm=250.0, depth=0.3)
>>> gb = TRUTH_MODIFIERS["bearing_seal"](g, k_N_per_m=1e7)
>>> [(b.name, float(b.position_mm)) for b in gb.bearings]
[('front', 100.0), ('rear', 600.0), ('seal_front', 75.0)]
>>> len(gs.sections) - len(g.sections), [round(float(s.outer_diameter_mm), 1) for s in gs.sections]
(2, [70.0, 65.0, 54.5, 65.0, 50.0])
"""

from __future__ import annotations

import math
from dataclasses import replace

from surrogate_rbrdo.core.registry import Registry
from surrogate_rbrdo.core.validate import check_positive, check_range
from surrogate_rbrdo.spindle.geometry import Bearing, ConstantLaw, SpindleGeometry

TRUTH_MODIFIERS = Registry("truth-only effect")


@TRUTH_MODIFIERS.register("magnetic_pull")
def magnetic_pull(geometry: SpindleGeometry, *, k_N_per_m: float,
                  position_mm: float | None = None) -> SpindleGeometry:
    """Negative stiffness ``−k_N_per_m`` (undamped, isotropic) at the motor plane
    (default: the disk named ``motor_rotor``, else mid-shaft)."""
    check_positive("magnetic_pull.k_N_per_m", k_N_per_m)
    if position_mm is None:
        pos = [d.position_mm for d in geometry.disks if d.name == "motor_rotor"]
        position_mm = pos[0] if pos else geometry.total_length_mm / 2
    law = ConstantLaw(k_matrix_N_per_m=((-k_N_per_m, 0.0), (0.0, -k_N_per_m)),
                      c_matrix_Ns_per_m=((0.0, 0.0), (0.0, 0.0)), damping_eta_s=0.0)
    return replace(geometry, bearings=geometry.bearings
                   + (Bearing("magnetic_pull", float(position_mm), law),))


@TRUTH_MODIFIERS.register("bearing_seal")
def bearing_seal(geometry: SpindleGeometry, *, k_N_per_m: float, bearing: str = "front",
                 offset_mm: float = -25.0) -> SpindleGeometry:
    """Positive constant stiffness ``k_N_per_m`` (undamped, isotropic) from shaft to ground
    beside the named bearing, ``offset_mm`` from its plane (default: 25 mm towards the nose,
    where a spindle's front seal sits; one element of the reference spindle's nose section —
    the FE model cannot put two supports on one node)."""
    check_positive("bearing_seal.k_N_per_m", k_N_per_m)
    pos = {b.name: b.position_mm for b in geometry.bearings}
    if bearing not in pos:
        raise ValueError(f"bearing_seal.bearing = {bearing!r} is not a bearing; bearings are "
                         f"{list(pos)}")
    z = float(pos[bearing]) + check_range("bearing_seal.offset_mm", offset_mm, -math.inf,
                                          math.inf)
    if not 0.0 <= z <= geometry.total_length_mm:
        raise ValueError(f"bearing_seal.offset_mm = {offset_mm!r} is not allowed: the seal "
                         f"would sit at {z} mm, outside the shaft [0, "
                         f"{geometry.total_length_mm}] mm")
    law = ConstantLaw(k_matrix_N_per_m=((k_N_per_m, 0.0), (0.0, k_N_per_m)),
                      c_matrix_Ns_per_m=((0.0, 0.0), (0.0, 0.0)), damping_eta_s=0.0)
    return replace(geometry, bearings=geometry.bearings + (Bearing(f"seal_{bearing}", z, law),))


@TRUTH_MODIFIERS.register("shaft_stiffness_loss")
def shaft_stiffness_loss(geometry: SpindleGeometry, *, position_mm: float, depth: float
                         ) -> SpindleGeometry:
    """The shaft element containing ``position_mm`` gets its outer diameter reduced by the
    fraction ``depth`` of its wall (bore kept). The section is split at that element's ends,
    keeping every mesh node where it was, so only the element's stiffness and mass change."""
    check_range("shaft_stiffness_loss.depth", depth, 0.0, 0.9)
    out, start, done = [], 0.0, False
    for s in geometry.sections:
        end = start + s.length_mm
        if not done and start <= position_mm < end:
            h = s.length_mm / s.elements
            i = min(int((position_mm - start) // h), s.elements - 1)
            d_new = s.inner_diameter_mm + (1 - depth) * (s.outer_diameter_mm
                                                         - s.inner_diameter_mm)
            if i > 0:
                out.append(replace(s, length_mm=i * h, elements=i))
            out.append(replace(s, length_mm=h, outer_diameter_mm=d_new, elements=1))
            if i < s.elements - 1:
                out.append(replace(s, length_mm=(s.elements - 1 - i) * h,
                                   elements=s.elements - 1 - i))
            done = True
        else:
            out.append(s)
        start = end
    if not done:
        raise ValueError(f"shaft_stiffness_loss.position_mm = {position_mm} is not on the "
                         f"shaft [0, {geometry.total_length_mm}) mm")
    return replace(geometry, sections=tuple(out))


@TRUTH_MODIFIERS.register("disk_mass_error")
def disk_mass_error(geometry: SpindleGeometry, *, factor: float, disk: str = "motor_rotor"
                    ) -> SpindleGeometry:
    """The named disk's mass and inertias scaled by ``factor`` (a motor rotor whose
    laminations and sleeve weigh other than the drawing says)."""
    check_range("disk_mass_error.factor", factor, 0.1, 10.0)
    names = [d.name for d in geometry.disks]
    if disk not in names:
        raise ValueError(f"disk_mass_error.disk = {disk!r} is not a disk; disks are {names}")
    return replace(geometry, disks=tuple(
        replace(d, mass_kg=d.mass_kg * factor, polar_inertia_kgm2=d.polar_inertia_kgm2 * factor,
                diametral_inertia_kgm2=d.diametral_inertia_kgm2 * factor)
        if d.name == disk else d for d in geometry.disks))
