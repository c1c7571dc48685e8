"""Experiment kind ``rig``: a measurement campaign on the virtual rig (``docs/rig.md``).

Table ``[rig]`` (:class:`~surrogate_rbrdo.rig.config.RigTable`): the truth's hidden
``effects``, ``design``, ``variability``, ``sensors``, ``campaign``, ``figures``, checked by
:func:`~surrogate_rbrdo.rig.config.rig_plan`. Stage ``campaign`` streams the dataset into
``<run>/campaign/`` record by record (``rig.campaign.run_campaign``; an interrupted run
resumes at the first record not written); the report writes the figures and
``rig_summary.json`` (``reporting.plots_rig``). Stream 0 of the seed drives every draw.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from surrogate_rbrdo.reporting.plots_rig import rig_summary
from surrogate_rbrdo.rig.campaign import CampaignResult, run_campaign
from surrogate_rbrdo.rig.config import RigPlan, RigTable, rig_plan
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind


@dataclass(frozen=True)
class RigCampaignConfig:
    rig: RigTable = field(default_factory=RigTable)


def build(c: RigCampaignConfig, base_dir: Path) -> RigPlan:
    return rig_plan(c.rig.config(), c.rig.effects)


def campaign(p: RigPlan, done: Mapping[str, Any], ctx: StageContext) -> CampaignResult:
    """Stage ``campaign`` (also the ``discrepancy`` and ``end_to_end`` kinds')."""
    with ctx.bar("rig campaign", "record") as progress:
        return run_campaign(p.rig.truth, p.rig.options, ctx.run_dir / "campaign",
                            rng=ctx.stream(0), progress=progress,
                            n_jobs=p.rig.n_jobs)


register_kind(Kind(
    name="rig",
    summary="a measurement campaign on the virtual rig (hidden truth, sensors): steady-state "
            "sweeps x repeats, run-up/run-down, impact tests; dataset, Bode/polar/orbit/"
            "Campbell/FRF/waterfall figures",
    schema=RigCampaignConfig,
    stages=(Stage("campaign", campaign),),
    report=lambda p, done, run, ctx: rig_summary(done["campaign"], p.rig, run.path),
    build=build,
))
