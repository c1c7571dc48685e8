"""Experiment kind ``rig``: a measurement campaign on the virtual rig (``docs/rig.md``).

Table ``[rig]`` (:class:`~surrogate_rbrdo.rig.config.RigTable`): the truth's hidden
``effects``, ``design``, ``variability``, ``sensors``, ``campaign``, ``figures``. Stage
``campaign`` streams the dataset into ``<run>/campaign/`` record by record
(``rig.campaign.run_campaign``; an interrupted run resumes at the first record not written);
the report writes the figures and ``rig_summary.json`` (``reporting.plots_rig``). Stream 0 of
the seed drives every draw.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.reporting.plots_rig import write_rig_report
from surrogate_rbrdo.rig.campaign import CampaignResult, footprint, run_campaign, stability_speeds
from surrogate_rbrdo.rig.config import RigConfig, RigTable
from surrogate_rbrdo.rig.simulate import check_nominal_stable
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind
from surrogate_rbrdo.runner.tables import require_memory


@dataclass(frozen=True)
class RigCampaignConfig:
    rig: RigTable = field(default_factory=RigTable)


@dataclass(frozen=True, eq=False)
class Plan:
    rig: RigConfig
    disk_need: tuple[str, Any, float, str]


def build(c: RigCampaignConfig, base_dir: Path) -> Plan:
    return rig_plan(c.rig.config(), c.rig.effects)


def rig_plan(cfg: RigConfig, effects: Any = ()) -> Plan:
    """The checks before work (the nominal truth stable at the campaign's speeds, memory) and
    the disk the campaign needs, for a truth and campaign made into objects (``[rig]``'s
    ``effects`` named in the error)."""
    sp = stability_speeds(cfg.options)       # the campaign checks them all for each tool
    try:
        check_nominal_stable(cfg.truth, np.linspace(sp[0], sp[-1], 12))
    except ModelError as exc:
        raise ValueError(f"rig.effects = {list(effects)} is not allowed: {exc}") from None
    o, fp = cfg.options, footprint(cfg.options)
    require_memory(f"rig.campaign.{fp.memory_by}", getattr(o, fp.memory_by), fp.memory_bytes,
                   "its records (a run's steady records, a ramp or an impact held at once)")
    return Plan(cfg, ("rig.campaign.repeats", o.repeats, fp.disk_bytes,
                      f"{fp.n_records} records ({len(o.speeds_rpm)} speeds x repeats x "
                      f"{o.duration_s:g} s, ramps, impacts)"))


def _campaign(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> CampaignResult:
    with ctx.bar("rig campaign", "record") as progress:
        return run_campaign(p.rig.truth, p.rig.options, ctx.run_dir / "campaign",
                            rng=ctx.stream(0), progress=progress)


def _report(p: Plan, done: Mapping[str, Any], run: Any, ctx: StageContext) -> dict[str, Any]:
    res = done["campaign"]
    summary = write_rig_report(res, p.rig.truth, run.path) if p.rig.figures else {}
    rows = [{"quantity": k, "value": v} for k, v in summary.items()
            if k not in ("figures", "seconds", "n_records")]
    return {"meta": {"n_records": res.n_records, "dataset": "campaign/dataset",
                     "campaign_s_last_session": res.seconds},
            "summary": [{"quantity": "records", "value": res.n_records}, *rows]}


register_kind(Kind(
    name="rig",
    summary="a measurement campaign on the virtual rig (hidden truth, sensors): steady-state "
            "sweeps x repeats, run-up/run-down, impact tests; dataset, Bode/polar/orbit/"
            "Campbell/FRF/waterfall figures",
    schema=RigCampaignConfig,
    stages=(Stage("campaign", _campaign),),
    report=_report,
    build=build,
))
