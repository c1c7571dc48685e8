"""The bearings' damping of an identification run from its impact tests (``damping =
"impact"``).

The 1× unbalance response identifies the stiffness of every record; its damping, at the rig's
noise, is 76–4 900 % off (``docs/identification.md`` §5). With ``damping = "impact"`` each
installation's impact records (grouped by their ``build`` and ``tool`` labels; one group when
the dataset has neither) give the bearings' ``η`` (:func:`~.impact.impact_damping`), and every
record's damping becomes ``c = η̂ k̂`` with ``k̂`` that record's identified stiffness in the same
direction — the model's damping law ``C_b = η_b K_b``. Its covariance is propagated to first
order (``k̂`` and ``η̂`` independent: different tests); the ``c`` columns of ``identified.csv``
change, their flags are recomputed (``unexcited`` from ``k``, ``imprecise`` against
``max_rel_se``, ``outside_box`` against the paper's ``[0.5, 2.0] c_init``), and
``uncertainty.json``'s provenance gets ``damping``: the source, per installation ``η̂``, its
relative SE (delete-one-hit jackknife with 3 or more hits per direction), the other updated
factors and the lack-of-fit test, and ``lack_of_fit``: the installations whose FRFs the model
does not fit (a model error: their ``η̂`` and tool mass are not to be trusted).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from surrogate_rbrdo.identification.campaign import CampaignResult, campaign_table
from surrogate_rbrdo.identification.impact import ImpactDamping, ImpactOptions, impact_damping
from surrogate_rbrdo.identification.measured import dataset_root
from surrogate_rbrdo.identification.phasor import catalog_coefficients
from surrogate_rbrdo.identification.regression import PAPER_C_FACTORS
from surrogate_rbrdo.rig.store import Dataset, open_dataset
from surrogate_rbrdo.spindle.assembly import SpindleModel

DAMPING_SOURCES = ("response", "impact")
INSTALLATION_LABELS = ("build", "tool")


def installation_key(labels: Mapping) -> str:
    """The installation a record belongs to: its ``build`` and ``tool`` labels.

    >>> installation_key({"build": 0, "tool": 1, "run": 3}), installation_key({})
    ('build=0|tool=1', 'all')
    """
    return "|".join(f"{k}={labels[k]}" for k in INSTALLATION_LABELS if k in labels) or "all"


def impact_dampings(model: SpindleModel, source: str | Path | Dataset,
                    options: ImpactOptions | None = None) -> dict[str, ImpactDamping]:
    """:func:`~.impact.impact_damping` of every installation's impact records in ``source``
    (a dataset or rig campaign folder; ``options`` default ``ImpactOptions()``). Raises
    ``ValueError`` if it has none."""
    options = ImpactOptions() if options is None else options
    ds = source if isinstance(source, Dataset) else open_dataset(dataset_root(source))
    groups: dict[str, list] = {}
    for r in ds.index:
        # the standstill model of impact_damping: hits at speed (rig.impacts) are left out
        if r.get("kind") == "impact" and not (r.get("speed_rpm") or 0.0) > 0:
            groups.setdefault(installation_key(r.get("labels", {})), []).append(ds.load(r))
    if not groups:
        raise ValueError(f"damping = 'impact' is not allowed with source = '{ds.root}': it "
                         "has no impact records (measure with [rig.campaign] "
                         "impacts_per_direction > 0)")
    return {k: impact_damping(model, recs, options) for k, recs in sorted(groups.items())}


def with_impact_damping(model: SpindleModel, camp: CampaignResult, keys: Sequence[str],
                        dampings: Mapping[str, ImpactDamping], *, max_rel_se: float
                        ) -> CampaignResult:
    """``camp`` with every record's damping ``c = η̂ k̂`` (module docstring); ``keys`` is each
    record's installation (:func:`installation_key`)."""
    res = camp.identification
    missing = sorted(set(keys) - set(dampings))
    if missing:
        raise ValueError(f"records of installation(s) {missing} have no impact tests "
                         f"(installations with impacts: {sorted(dampings)})")
    names = list(res.names)
    nb = len(dampings[keys[0]].bearings)
    bearings = dampings[keys[0]].bearings
    eta = np.array([dampings[k].eta_s for k in keys])                    # (N, nb)
    s_eta = np.array([dampings[k].eta_rel_se for k in keys]) * eta
    est = res.estimate.copy()
    n = est.shape[0]
    cov = None if res.covariance is None else res.covariance.copy()
    k_idx, c_idx, b_idx = [], [], []
    for b, bearing in enumerate(bearings):
        for d in ("yy", "zz"):
            k_idx.append(names.index(f"{bearing}_k_{d}"))
            c_idx.append(names.index(f"{bearing}_c_{d}"))
            b_idx.append(b)
    k_idx, c_idx, b_idx = map(np.array, (k_idx, c_idx, b_idx))
    est[:, c_idx] = eta[:, b_idx] * est[:, k_idx]
    if cov is not None:
        # output = J [k (8 as identified), η (nb)]: c = η k; first order, k̂ and η̂ independent
        J = np.zeros((n, 8, 8 + nb))
        J[:, np.arange(8), np.arange(8)] = 1.0
        J[:, c_idx, :] = 0.0
        J[:, c_idx, k_idx] = eta[:, b_idx]
        J[:, c_idx, 8 + b_idx] = res.estimate[:, k_idx]
        full = np.zeros((n, 8 + nb, 8 + nb))
        full[:, :8, :8] = res.covariance
        full[:, 8 + np.arange(nb), 8 + np.arange(nb)] = s_eta**2
        cov = np.einsum("nij,njk,nlk->nil", J, full, J)
    unexcited = res.unexcited.copy()
    unexcited[:, c_idx] = res.unexcited[:, k_idx]
    imprecise = res.imprecise.copy()
    if cov is not None:
        with np.errstate(invalid="ignore", divide="ignore"):
            rel = np.sqrt(np.diagonal(cov, axis1=1, axis2=2)[:, c_idx]) / np.abs(est[:, c_idx])
        imprecise[:, c_idx] = ~unexcited[:, c_idx] & ~(rel <= max_rel_se)
    cat = catalog_coefficients(model, res.speed_rpm)[:, c_idx]
    outside = res.outside_box.copy()
    with np.errstate(invalid="ignore"):
        outside[:, c_idx] = ~unexcited[:, c_idx] & ((est[:, c_idx] < PAPER_C_FACTORS[0] * cat)
                                                    | (est[:, c_idx] > PAPER_C_FACTORS[1] * cat))
    new = replace(res, estimate=est, covariance=cov, unexcited=unexcited, imprecise=imprecise,
                  outside_box=outside)
    prov = {"source": "impact", "installations": {k: d.to_dict() for k, d in dampings.items()},
            "lack_of_fit": sorted(k for k, d in dampings.items()
                                  if d.lack_of_fit and d.lack_of_fit.flagged)}
    u = replace(camp.uncertainty, provenance={**camp.uncertainty.provenance, "damping": prov})
    return replace(camp, identification=new, uncertainty=u,
                   table=campaign_table(new, camp.table["speed_rpm"], camp.table["repeat"],
                                        camp.used))


def record_installations(source: str | Path | Dataset, record_ids: Sequence[str]) -> list[str]:
    """The installation of each identified vector (``record_ids`` as in ``Responses``: a
    trial pair is ``"<without>|<with>"``; the first record's labels are used)."""
    ds = source if isinstance(source, Dataset) else open_dataset(dataset_root(source))
    labels = {r["id"]: r.get("labels", {}) for r in ds.index}
    return [installation_key(labels.get(i.split("|")[0], {})) for i in record_ids]


__all__ = ["DAMPING_SOURCES", "impact_dampings", "installation_key", "record_installations",
           "with_impact_damping"]
