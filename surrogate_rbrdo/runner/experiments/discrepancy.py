"""Experiment kind ``discrepancy``: where the model and the measurement part, which effect is
missing, the model with it added and the gap before/after (``docs/discrepancy.md``).

The tables (``[spindle]``, ``[discrepancy]`` and the data: ``[rig]``, a campaign on the
virtual rig streamed into ``<run>/campaign/`` and resumed record by record, or ``[data]
path``, whose files are hashed into ``meta.json`` ``inputs`` so that ``--resume`` refuses
changed data) and their checks are :mod:`surrogate_rbrdo.discrepancy.plan`'s. Stages:
``campaign`` (the ``rig`` kind's, or the data folder resolved) → ``analyse``
(``discrepancy.find_discrepancy``, stream 1 of the seed); the report
(``reporting.plots_discrepancy.write_discrepancy_run``) writes ``findings.json``,
``spindle_updated.toml``, ``candidates.csv``, ``curves.csv``, ``figures/`` and the verdict.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from surrogate_rbrdo.core.workers import preload
from surrogate_rbrdo.discrepancy.experiment import data_from_folder
from surrogate_rbrdo.discrepancy.plan import DiscrepancyConfig, DiscrepancyPlan, build_discrepancy
from surrogate_rbrdo.discrepancy.workflow import find_discrepancy
from surrogate_rbrdo.reporting.plots_discrepancy import write_discrepancy_run
from surrogate_rbrdo.rig.campaign import CampaignResult
from surrogate_rbrdo.runner.experiments import rig as rig_kind
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind


def _campaign(p: DiscrepancyPlan, done: Mapping[str, Any], ctx: StageContext
              ) -> CampaignResult | Path:
    """The rig's campaign into ``<run>/campaign`` (resumable), or the data folder."""
    return p.folder if p.rig is None else rig_kind.campaign(p.rig, done, ctx)


#: what the workers of the candidate fits and the figures import (:func:`analyse`)
WORKER_MODULES = ("surrogate_rbrdo.discrepancy.naming",
                  "surrogate_rbrdo.reporting.plots_discrepancy", "matplotlib.pyplot")


def analyse(p: DiscrepancyPlan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    src = done["campaign"]
    # the workers import the fits' and figures' modules while this process reads the data
    ready = preload(WORKER_MODULES, p.options.n_jobs)
    data = data_from_folder(src if isinstance(src, Path) else src.root,
                            impacts=p.options.use_impacts)
    for _ in ready:
        pass
    sp = p.spindle
    with ctx.bar("discrepancy: recalibrate, fit the candidates, test", "step") as progress:
        progress(0, 1, f"{len(p.options.library)} candidates")
        return find_discrepancy(data, sp.geometry_for(sp.baseline), sp.effects,
                                options=p.options, rng=ctx.stream(1))


register_kind(Kind(
    name="discrepancy",
    summary="where the model and measured data part, which library effect is missing (named, "
            "confounded, nothing missing or an unnamed residual), the updated [spindle] and "
            "the held-out gap before/after; data from the virtual rig ([rig]) or [data] path",
    schema=DiscrepancyConfig,
    stages=(Stage("campaign", _campaign), Stage("analyse", analyse)),
    report=lambda p, done, run, ctx: write_discrepancy_run(run.path, p, done["analyse"],
                                                           done["campaign"]),
    build=build_discrepancy,
))
