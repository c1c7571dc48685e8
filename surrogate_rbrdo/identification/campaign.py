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
(('front', 'rear'), 72, ['speed_rpm', 'repeat', 'front_k_yy', 'front_k_zz'])
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.validate import check_choice
from surrogate_rbrdo.identification.condensation import condense_reactions
from surrogate_rbrdo.identification.model import IdentifiedUncertainty
from surrogate_rbrdo.identification.phasor import (
    PhasorIdentification,
    catalog_coefficients,
    identify_phasors,
)
from surrogate_rbrdo.identification.scatter import fit_uncertainty
from surrogate_rbrdo.spindle.assembly import SpindleModel

FIT_ON = ("stiffness", "all")


@dataclass(frozen=True, eq=False)
class CampaignResult:
    """Identified records, which were used, and the uncertainty model.

    ``table`` holds the columns of ``identified.csv``: ``speed_rpm``, ``repeat``, one column per
    coefficient (SI, NaN where not identifiable), ``ok`` (used in the fit) and ``flags``
    (``"; "``-joined reasons, empty if fine).
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
                      unbalance=None, fit_on: str = "stiffness", law: str = "auto",
                      study: str = "isotropic", scatter: str = "total", truth=None,
                      provenance: dict | None = None) -> CampaignResult:
    """Identify every record and fit the uncertainty model.

    Parameters
    ----------
    model : SpindleModel
        The known rotor (its bearings give the catalogue values of the paper's box).
    speeds_rpm, repeats : array (N,)
    phasors : array (N, 2 np) complex
        1× phasors ``[x, y]`` per probe node (trial-weight differences if ``unbalance`` is the
        trial mass).
    phasor_sd : float or array (N, 2 np), optional
        Standard deviation of the real (and imaginary) part of each phasor's noise (m), as
        ``rig.phasors.phasor_noise_sd``: gives covariances and the estimated variance split.
    fit_on : {"stiffness", "all"}
        Coefficients the uncertainty model is fitted on, and whose flags exclude a record:
        the four ``k`` (default — damping is not identifiable from unbalance response at
        realistic noise, docs/identification.md §3) or all eight.
    law, study, scatter, truth, provenance
        As :func:`~surrogate_rbrdo.identification.scatter.fit_uncertainty` (``truth (N, 8)``).
    """
    check_choice("fit_on", fit_on, FIT_ON)
    sp = np.asarray(speeds_rpm, dtype=float).ravel()
    rep = np.asarray(repeats).ravel()
    if rep.shape != sp.shape:
        raise ValueError(f"repeats has shape {rep.shape}: need {sp.shape} like speeds_rpm")
    speeds = np.unique(sp)
    cr = condense_reactions(model, speeds, probe_nodes=probe_nodes, unbalance=unbalance)
    res = identify_phasors(cr, phasors, sp, phasor_sd=phasor_sd,
                           catalog=catalog_coefficients(model, sp))
    cols = [j for j, n in enumerate(res.names) if fit_on == "all" or "_k_" in n]
    bad_bound = res.at_bound[:, cols].any(axis=1)
    bad_exc = res.unexcited[:, cols].any(axis=1)
    used = ~(bad_bound | bad_exc)
    if used.sum() < 3:
        raise ValueError(f"only {int(used.sum())} of {sp.size} records are usable (at a bound: "
                         f"{int(bad_bound.sum())}, not excited: {int(bad_exc.sum())})")
    cov = None if res.covariance is None else res.covariance[used][:, cols][:, :, cols]
    tr = None if truth is None else np.asarray(truth, dtype=float)[used][:, cols]
    unc = fit_uncertainty(res.estimate[used][:, cols], sp[used], [res.names[j] for j in cols],
                          law=law, study=study, scatter=scatter, per_record_cov=cov, truth=tr,
                          provenance={**(provenance or {}), "records": int(sp.size),
                                      "records_used": int(used.sum()), "fit_on": fit_on})
    table = {"speed_rpm": sp, "repeat": rep,
             **{n: res.estimate[:, j] for j, n in enumerate(res.names)},
             "ok": used, "flags": np.array(["; ".join(res.flags(i)) for i in range(sp.size)])}
    counts = {"at_bound": int(bad_bound.sum()), "unexcited": int(bad_exc.sum()),
              "any_coefficient_flagged": int((~res.ok).sum())}
    return CampaignResult(res, used, unc, table, counts)


__all__ = ["FIT_ON", "CampaignResult", "identify_campaign"]
