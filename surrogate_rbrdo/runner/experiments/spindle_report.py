"""Experiment kind ``spindle_report``: design quantities, Campbell diagrams and tool-tip
unbalance responses of a set of designs of a spindle (``reporting.spindle``).

Tables: ``[spindle]`` (:class:`~surrogate_rbrdo.spindle.config.SpindleTable`) and ``[report]``
(:class:`~surrogate_rbrdo.reporting.spindle.ReportTable`): ``designs`` (label → ``[F N, L mm,
D mm]``, default the baseline), ``include_box`` (add the 8 corners and the centre of the
design box), ``n_speeds``, ``campbell_speeds``, ``n_modes``, ``n_campbell`` (designs in the
Campbell figure and CSVs).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from surrogate_rbrdo.reporting.spindle import (
    SpindleOverview,
    SpindleReportConfig,
    SpindleReportPlan,
    build_spindle_report,
    spindle_overview,
    write_spindle_report,
)
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind


def _designs(p: SpindleReportPlan, done: Mapping[str, Any], ctx: StageContext
             ) -> SpindleOverview:
    r = p.report
    return spindle_overview(p.spindle, p.designs, n_speeds=r.n_speeds,
                            campbell_speeds=r.campbell_speeds, n_modes=r.n_modes,
                            n_campbell=r.n_campbell, quantities=True, progress=ctx.progress,
                            label=ctx.label)


register_kind(Kind(
    name="spindle_report",
    summary="a spindle's designs: mass, first natural frequency, critical speeds, peak "
            "amplitude, stress; Campbell diagrams and tool-tip unbalance responses",
    schema=SpindleReportConfig,
    stages=(Stage("designs", _designs),),
    report=lambda p, done, run, ctx: write_spindle_report(run, p, done["designs"]),
    build=build_spindle_report,
))
