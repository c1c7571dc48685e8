"""One call from a campaign's 1× phasors to the identified table and the uncertainty model.

:func:`identify_campaign` is what the ``identification`` experiment kind (phase 2) calls once
the rig's records are demodulated: it condenses the known rotor at the campaign's speeds,
identifies the eight coefficients of every record, sets flagged records aside (and counts them
by reason), and fits the uncertainty model on the coefficients the study uses.

>>> import numpy as np
>>> from surrogate_rbrdo.spindle import reference_spindle
>>> from surrogate_rbrdo.identification.virtual import phasor_campaign
>>> sp = reference_spindle()
>>> m = sp.model(sp.baseline)
>>> c = phasor_campaign(m, np.linspace(5000, 24000, 6), 12, theta_std=[0.015, 0.03],
...                     noise_m=1e-11, rng=np.random.default_rng(0))
>>> out = identify_campaign(m, c.speeds_rpm, c.repeats, c.phasors, phasor_sd=c.noise_m)
>>> out.uncertainty.names, out.n_used, list(out.table)[:4]
(('front', 'rear'), 72, ['speed_rpm', 'repeat', 'front_k_yy', 'front_k_yy_se'])
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_positive
from surrogate_rbrdo.identification.condensation import condense_reactions
from surrogate_rbrdo.identification.model import (
    IdentifiedUncertainty,
    model_reference,
    study_weights,
)
from surrogate_rbrdo.identification.phasor import (
    PhasorIdentification,
    catalog_coefficients,
    identify_phasors,
)
from surrogate_rbrdo.identification.scatter import fit_uncertainty
from surrogate_rbrdo.identification.systematic import (
    SystematicUncertainty,
    systematic_sensitivities,
)
from surrogate_rbrdo.spindle.assembly import SpindleModel

FIT_ON = ("stiffness", "all")
#: records whose fitted coefficients have a larger relative standard error are not used: the
#: first-order error model (and the ratio r/x itself) is unreliable beyond it
DEFAULT_MAX_REL_SE = 0.2


@dataclass(frozen=True, eq=False)
class CampaignResult:
    """Identified records, which were used, and the uncertainty model.

    ``table`` holds the columns of ``identified.csv``: ``speed_rpm``, ``repeat``, one column per
    coefficient (SI, as identified, NaN where not identifiable), its standard error
    ``<name>_se`` and flags ``<name>_flag`` (``unexcited``, ``imprecise``, ``outside_box``,
    ``near_pole``; empty if fine), ``used`` (in the uncertainty fit) and ``flags`` (plain
    language). ``flag_counts`` counts records by reason over the fitted coefficients and the
    records used per speed.
    """

    identification: PhasorIdentification
    used: np.ndarray
    uncertainty: IdentifiedUncertainty
    table: dict
    flag_counts: dict

    @property
    def n_used(self) -> int:
        return int(self.used.sum())


def identify_campaign(model: SpindleModel, speeds_rpm, repeats, phasors, *,
                      phasor_sd=None, probe_nodes: Sequence[int] | None = None,
                      unbalance=None, groups=None, fit_on: str = "stiffness",
                      max_rel_se: float = DEFAULT_MAX_REL_SE, law: str = "auto",
                      study: str = "isotropic", scatter: str = "auto", truth=None,
                      rng: np.random.Generator | None = None, n_boot: int = 200,
                      perturbations=None, systematic: SystematicUncertainty | None = None,
                      probe_bandwidth_hz: float | None = None,
                      summary_speed_rpm: float | None = None,
                      provenance: dict | None = None) -> CampaignResult:
    """Identify every record and fit the uncertainty model.

    Parameters
    ----------
    model : SpindleModel
        The known rotor (its bearings give the catalogue values of the paper's box and the
        nominal stiffness θ refers to).
    speeds_rpm, repeats : array (N,)
    phasors : array (N, 2 np) complex
        1× phasors ``[x, y]`` per probe node (trial-weight differences if ``unbalance`` is the
        trial mass).
    phasor_sd : float or array (N, 2 np), optional
        Standard deviation of the real (and imaginary) part of each phasor's noise (m):
        covariances, the SNR and precision flags and the physical/identification split.
    groups : array (N,), optional
        Run of each record (records sharing a physical state); default ``repeats``.
    fit_on : {"stiffness", "all"}
        Coefficients the uncertainty model is fitted on, and whose flags exclude a record:
        the four ``k`` (default — damping is not identifiable from unbalance response at
        realistic noise, docs/identification.md §3) or all eight.
    max_rel_se : float
        A fitted coefficient with a larger relative standard error excludes its record.
    perturbations : array (N, r, p) complex, optional
        Independent per-record phasor errors besides the noise (:func:`identify_phasors`).
    systematic : SystematicUncertainty, optional
        Tolerances of the measurement chain and rotor model: their systematic effect on the
        trends (:mod:`~surrogate_rbrdo.identification.systematic`; ``probe_bandwidth_hz`` is
        the nominal driver bandwidth the bandwidth source refers to).
    law, study, scatter, truth, rng, n_boot, summary_speed_rpm, provenance
        As :func:`~surrogate_rbrdo.identification.scatter.fit_uncertainty` (``truth (N, 8)``).
    """
    check_choice("fit_on", fit_on, FIT_ON)
    check_positive("max_rel_se", max_rel_se)
    sp = np.asarray(speeds_rpm, dtype=float).ravel()
    rep = np.asarray(repeats).ravel()
    grp = rep if groups is None else np.asarray(groups).ravel()
    if rep.shape != sp.shape or grp.shape != sp.shape:
        raise ValueError(f"repeats/groups have shapes {rep.shape}/{grp.shape}: need "
                         f"{sp.shape} like speeds_rpm")
    if truth is not None and np.shape(truth) != (sp.size, 8):
        raise ValueError(f"truth has shape {np.shape(truth)}: need ({sp.size}, 8)")
    speeds = np.unique(sp)
    cr = condense_reactions(model, speeds, probe_nodes=probe_nodes, unbalance=unbalance)
    res = identify_phasors(cr, phasors, sp, phasor_sd=phasor_sd,
                           catalog=catalog_coefficients(model, sp), max_rel_se=max_rel_se,
                           perturbations=perturbations)
    cols = [j for j, n in enumerate(res.names) if fit_on == "all" or "_k_" in n]
    used = res.usable(cols)
    if used.sum() < 3:
        raise ValueError(f"only {int(used.sum())} of {sp.size} records are usable: "
                         f"{_counts(res, cols, used, sp)}")
    names = [res.names[j] for j in cols]
    cov = None if res.covariance is None else res.covariance[used][:, cols][:, :, cols]
    tr = None if truth is None else np.asarray(truth, dtype=float)[used][:, cols]
    G, sources = (None, ()) if systematic is None else systematic_sensitivities(
        model, cr, np.asarray(phasors)[used], sp[used], systematic,
        probe_bandwidth_hz=probe_bandwidth_hz, unbalance=unbalance)
    unc = fit_uncertainty(
        res.estimate[used][:, cols], sp[used], names, law=law, study=study, scatter=scatter,
        per_record_cov=cov, truth=tr, groups=grp[used], rng=rng, n_boot=n_boot,
        reference=(speeds, model_reference(model, speeds, study_weights(names, study)[0])),
        systematic=None if G is None else G[:, :, cols], systematic_sources=sources,
        summary_speed_rpm=summary_speed_rpm,
        provenance={**(provenance or {}), "records": int(sp.size),
                    "records_used": int(used.sum()), "fit_on": fit_on, "max_rel_se": max_rel_se})
    return CampaignResult(res, used, unc, campaign_table(res, sp, rep, used),
                          _counts(res, cols, used, sp))


def campaign_table(res: PhasorIdentification, sp, rep, used) -> dict:
    """The columns of ``identified.csv`` (:class:`CampaignResult` ``table``)."""
    se = res.std if res.std is not None else np.full(res.estimate.shape, np.nan)
    fl = res.flag_names()
    cols = {"speed_rpm": sp, "repeat": rep}
    for j, n in enumerate(res.names):
        cols |= {n: res.estimate[:, j], f"{n}_se": se[:, j], f"{n}_flag": fl[:, j]}
    return cols | {"used": used,
                   "flags": np.array(["; ".join(res.flags(i)) for i in range(sp.size)])}


def _counts(res: PhasorIdentification, cols, used, sp) -> dict:
    u, inv = np.unique(sp, return_inverse=True)
    return {"records": int(sp.size), "used": int(used.sum()),
            "unexcited": int(res.unexcited[:, cols].any(axis=1).sum()),
            "imprecise": int((res.imprecise[:, cols] & ~res.unexcited[:, cols]).any(axis=1).sum()),
            "near_pole": int(res.near_pole.sum()),
            "outside_box_kept": int((res.outside_box[:, cols].any(axis=1) & used).sum()),
            "used_per_speed": dict(zip(u.tolist(), np.bincount(inv, used, u.size).astype(int)
                                       .tolist(), strict=True))}


__all__ = ["DEFAULT_MAX_REL_SE", "FIT_ON", "CampaignResult", "campaign_table", "identify_campaign"]
