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
* ``shaft_stiffness_loss``: a local loss of bending stiffness of the shaft (a transverse crack,
  a fretted shrink fit) modelled as a short section of reduced diameter (the "equivalent
  reduced section" of Dimarogonas, *Eng. Fract. Mech.* 55, 1996, for an open crack; the
  crack's asymmetry and breathing are left out, so the truth stays linear and isotropic).

>>> from surrogate_rbrdo.spindle.reference import reference_spindle
>>> sp = reference_spindle()
>>> g = sp.geometry_for(sp.baseline)
>>> gm = TRUTH_MODIFIERS["magnetic_pull"](g, k_N_per_m=2e7)
>>> [b.name for b in gm.bearings]
['front', 'rear', 'magnetic_pull']
>>> gs = TRUTH_MODIFIERS["shaft_stiffness_loss"](g, position_mm=350.0, depth=0.3)
>>> len(gs.sections) - len(g.sections)
2
"""

from __future__ import annotations

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


@TRUTH_MODIFIERS.register("shaft_stiffness_loss")
def shaft_stiffness_loss(geometry: SpindleGeometry, *, position_mm: float, depth: float,
                         length_mm: float = 10.0) -> SpindleGeometry:
    """A ``length_mm`` piece of shaft centred at ``position_mm`` whose outer diameter is
    reduced by the fraction ``depth`` (bore kept); the section is split to insert it."""
    check_range("shaft_stiffness_loss.depth", depth, 0.0, 0.9)
    check_positive("shaft_stiffness_loss.length_mm", length_mm)
    z0 = position_mm - length_mm / 2
    out, start = [], 0.0
    for s in geometry.sections:
        end = start + s.length_mm
        if start < z0 and z0 + length_mm < end:
            d_new = s.inner_diameter_mm + (1 - depth) * (s.outer_diameter_mm
                                                         - s.inner_diameter_mm)
            n1 = max(1, round(s.elements * (z0 - start) / s.length_mm))
            n3 = max(1, round(s.elements * (end - z0 - length_mm) / s.length_mm))
            out += [replace(s, length_mm=z0 - start, elements=n1),
                    replace(s, length_mm=length_mm, outer_diameter_mm=d_new, elements=1),
                    replace(s, length_mm=end - z0 - length_mm, elements=n3)]
        else:
            out.append(s)
        start = end
    if len(out) == len(geometry.sections):
        raise ValueError(f"shaft_stiffness_loss.position_mm = {position_mm}: the reduced piece "
                         "must lie inside one shaft section")
    return replace(geometry, sections=tuple(out))
