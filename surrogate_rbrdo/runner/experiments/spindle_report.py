"""Experiment kind ``spindle_report``: design quantities, Campbell diagrams and tool-tip
unbalance responses of a set of designs of a spindle (``reporting.spindle``).

Tables: ``[spindle]`` (:class:`~surrogate_rbrdo.runner.tables.SpindleTable`) and ``[report]``
(:class:`ReportTable`): ``designs`` (label → ``[F N, L mm, D mm]``, default the baseline),
``include_box`` (add the 8 corners and the centre of the design box), ``n_speeds``,
``campbell_speeds``, ``n_modes``, ``n_campbell`` (designs in the Campbell figure and CSVs).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.validate import check_int, check_label
from surrogate_rbrdo.reporting.spindle import (
    QUANTITY_HEADER,
    SpindleOverview,
    check_overview,
    quantity_rows,
    spindle_overview,
    write_overview,
)
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind
from surrogate_rbrdo.runner.tables import SpindleTable, build_spindle


@dataclass(frozen=True)
class ReportTable:
    """``[report]`` of a spindle report."""

    designs: dict[str, tuple[float, float, float]] | None = None
    include_box: bool = False
    n_speeds: int = 400
    campbell_speeds: int = 25
    n_modes: int = 8
    n_campbell: int = 4

    def __post_init__(self) -> None:
        if self.designs is not None and not self.designs:
            raise ValueError("designs = {} is not allowed: give label = [F, L, D] entries")
        for label in self.designs or ():
            check_label("designs", label)
        check_int("n_speeds", self.n_speeds, minimum=2)
        check_int("campbell_speeds", self.campbell_speeds, minimum=2)
        check_int("n_modes", self.n_modes, minimum=1)
        check_int("n_campbell", self.n_campbell, minimum=1)


@dataclass(frozen=True)
class SpindleReportConfig:
    spindle: SpindleTable = field(default_factory=SpindleTable)
    report: ReportTable = field(default_factory=ReportTable)


@dataclass(frozen=True, eq=False)
class Plan:
    spindle: Any
    designs: dict[str, np.ndarray]
    report: ReportTable


def build(c: SpindleReportConfig, base_dir: Path) -> Plan:
    sp = build_spindle(c.spindle, base_dir)
    designs: dict[str, np.ndarray] = {}
    for label, x in (c.report.designs or {"baseline": tuple(sp.baseline.tolist())}).items():
        try:
            designs[label] = sp.design_map.check(np.asarray(x, dtype=float))
        except ValueError as exc:
            raise ValueError(f"report.designs.{label}: {exc}") from None
    if c.report.include_box:
        designs.update(sp.design_map.corners())
    r = c.report
    check_overview(sp, designs, n_speeds=r.n_speeds, campbell_speeds=r.campbell_speeds,
                   n_modes=r.n_modes, where="report")
    return Plan(sp, designs, r)


def _designs(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> SpindleOverview:
    r = p.report
    return spindle_overview(p.spindle, p.designs, n_speeds=r.n_speeds,
                            campbell_speeds=r.campbell_speeds, n_modes=r.n_modes,
                            n_campbell=r.n_campbell, quantities=True, progress=ctx.progress,
                            label=ctx.label)


def _report(p: Plan, done: Mapping[str, Any], run: Any, ctx: StageContext) -> dict[str, Any]:
    ov = done["designs"]
    rows = quantity_rows(ov)
    run.write_csv("summary.csv", QUANTITY_HEADER, rows)
    write_overview(run, ov, n_modes=p.report.n_modes,
                   speed_max_rpm=p.spindle.geometry.speed_max_rpm, campbell_csv=True)
    return {"designs": len(ov.labels),
            "summary": [dict(zip(QUANTITY_HEADER, r, strict=True)) for r in rows]}


register_kind(Kind(
    name="spindle_report",
    summary="a spindle's designs: mass, first natural frequency, critical speeds, peak "
            "amplitude, stress; Campbell diagrams and tool-tip unbalance responses",
    schema=SpindleReportConfig,
    stages=(Stage("designs", _designs),),
    report=_report,
    build=build,
))
