"""Systematic (type B) uncertainty of identified coefficients from the measurement chain.

Some errors are the same in every record of a campaign: a probe's residual gain error after
calibration, its driver's bandwidth, its channel's timing skew, the keyphasor mark's angle, the
trial mass, the rotor model (a tool that was not weighed). They do not scatter the identified
values — they shift all of them — so repeats cannot reveal them; the experimenter knows only
their tolerances (datasheets, calibration sheets). Following the GUM (JCGM 100:2008, §5.1),
each is an independent zero-mean variable ``ξ`` with a stated standard deviation, propagated to
the coefficients by first-order sensitivities:

* per probe channel ``p`` a complex relative error of its phasor, ``q_p ← q_p (1 + u ξ)``:
  gain ``u = 1``; driver bandwidth ``f_c (1 + ξ)``: ``u = (i f/f_c) / (1 + i f/f_c)``; timing
  skew ``ξ`` seconds: ``u = iΩ``; ``dZ_j = (∂Z_j/∂q_p) q_p u ξ`` with
  ``∂Z/∂q = (L_r − Z L_x) / x`` (:mod:`.phasor`);
* the keyphasor mark's angle (common to all channels): ``u = −i`` (rad) on every channel;
* the trial mass's magnitude: the known load scales by ``1 + ξ``: ``dZ = (c_r − Z c_x)/x · ξ``;
* the tool/holder mass of the rotor model: ``dZ`` by finite difference of the condensation with
  the tool disk's mass and inertias scaled by ``1 + ξ``.

:func:`systematic_sensitivities` returns, per record, the coefficients' change for one standard
deviation of every ``ξ`` (``(N, n_ξ, 8)``); the trend's systematic covariance at a speed is
``Ḡᵀ Ḡ`` with ``Ḡ`` the mean over that speed's records (the sources are common to all records).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

from surrogate_rbrdo.core.validate import check_positive
from surrogate_rbrdo.identification.condensation import CondensedReactions, condense_reactions
from surrogate_rbrdo.identification.phasor import coefficient_changes, impedance_sensitivity
from surrogate_rbrdo.spindle.assembly import RPM, SpindleModel, build_model


@dataclass(frozen=True)
class SystematicUncertainty:
    """Standard deviations of the systematic error sources (module docstring).

    Defaults are the virtual rig's documented tolerances (``docs/rig.md``): probe gain 2 %
    after calibration (API 670 allows ±5 % uncalibrated), driver bandwidth 10 %, channel skew
    0.2 µs; the keyphasor mark and the trial mass are exact on the rig (0); the tool/holder
    mass varies 3 % between tool changes and is not weighed.
    """

    gain_sd: float = 0.02
    bandwidth_sd: float = 0.10
    skew_sd_s: float = 0.2e-6
    keyphasor_angle_sd_deg: float = 0.0
    trial_magnitude_sd: float = 0.0
    tool_mass_sd: float = 0.03
    tool_disk: str = "tool_holder"

    def __post_init__(self) -> None:
        for f in ("gain_sd", "bandwidth_sd", "skew_sd_s", "keyphasor_angle_sd_deg",
                  "trial_magnitude_sd", "tool_mass_sd"):
            check_positive(f, getattr(self, f), allow_zero=True)

    def to_dict(self) -> dict:
        return asdict(self)


def _tool_scaled(model: SpindleModel, disk: str, factor: float) -> SpindleModel:
    g = model.geometry
    if not any(d.name == disk for d in g.disks):
        raise ValueError(f"tool_disk = {disk!r} is not a disk of the model "
                         f"{[d.name for d in g.disks]}")
    disks = tuple(replace(d, mass_kg=d.mass_kg * factor,
                          polar_inertia_kgm2=d.polar_inertia_kgm2 * factor,
                          diametral_inertia_kgm2=d.diametral_inertia_kgm2 * factor)
                  if d.name == disk else d for d in g.disks)
    return build_model(replace(g, disks=disks), model.effects,
                       theta_bearings=model.theta_bearings)


def systematic_sensitivities(model: SpindleModel, cr: CondensedReactions, phasors, speeds_rpm,
                             unc: SystematicUncertainty, *, probe_bandwidth_hz: float | None,
                             unbalance=None) -> tuple[np.ndarray, tuple[str, ...]]:
    """Change of every record's eight coefficients for one standard deviation of each
    systematic source: ``(N, n_ξ, 8)`` and the sources' names.

    ``model``, ``unbalance`` and the probe nodes of ``cr`` are those of the condensation (the
    tool-mass source re-condenses a perturbed model at ``cr.speeds_rpm``).
    """
    sp = np.atleast_1d(np.asarray(speeds_rpm, dtype=float))
    q = np.asarray(phasors, dtype=complex)
    x, r = cr.reactions(q, sp)
    si = cr.speed_index(sp)
    with np.errstate(divide="ignore", invalid="ignore"):
        Z = r / x
        A = impedance_sensitivity(cr, si, x, Z)                              # (N, m, p)
    w = sp * RPM
    f = sp / 60.0
    nch = q.shape[1]
    cols, names = [], []
    per_channel = [("gain", unc.gain_sd, np.ones_like(w)),
                   ("skew", unc.skew_sd_s, 1j * w)]
    if probe_bandwidth_hz is not None:
        h = 1j * f / probe_bandwidth_hz
        per_channel.insert(1, ("bandwidth", unc.bandwidth_sd, h / (1 + h)))
    for label, sd, u in per_channel:
        if sd > 0:
            for p in range(nch):
                cols.append(A[:, :, p] * (q[:, p] * u * sd)[:, None])
                names.append(f"{label}[{p}]")
    if unc.skew_sd_s > 0:                        # the keyphasor's own skew: common to all
        cols.append(np.einsum("nmp,np->nm", A, q) * (-1j * w * unc.skew_sd_s)[:, None])
        names.append("skew[keyphasor]")
    if unc.keyphasor_angle_sd_deg > 0:
        cols.append(np.einsum("nmp,np->nm", A, q) * (-1j * np.radians(unc.keyphasor_angle_sd_deg)))
        names.append("keyphasor_angle")
    if unc.trial_magnitude_sd > 0:
        with np.errstate(divide="ignore", invalid="ignore"):
            cols.append((cr.cr[si] - Z * cr.cx[si]) / x * unc.trial_magnitude_sd)
        names.append("trial_magnitude")
    if unc.tool_mass_sd > 0:
        pert = condense_reactions(_tool_scaled(model, unc.tool_disk, 1 + unc.tool_mass_sd),
                                  cr.speeds_rpm, probe_nodes=cr.probe_nodes, unbalance=unbalance)
        x2, r2 = pert.reactions(q, sp)
        with np.errstate(divide="ignore", invalid="ignore"):
            cols.append(r2 / x2 - Z)
        names.append("tool_mass")
    if not cols:
        return np.zeros((sp.size, 0, 2 * x.shape[1])), ()
    return coefficient_changes(np.stack(cols, axis=1), w), tuple(names)


__all__ = ["SystematicUncertainty", "systematic_sensitivities"]
