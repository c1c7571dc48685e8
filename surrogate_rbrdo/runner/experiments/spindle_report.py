"""Experiment kind ``spindle_report``: design quantities, Campbell diagrams and tool-tip
unbalance responses of a set of designs of a spindle.

Tables: ``[spindle]`` (:class:`~surrogate_rbrdo.runner.tables.SpindleTable`) and ``[report]``
(:class:`ReportTable`): ``designs`` (label → ``[F N, L mm, D mm]``, default the baseline),
``include_box`` (add the 8 corners and the centre of the design box), ``n_speeds``,
``campbell_speeds``, ``n_modes``, ``n_campbell`` (designs in the Campbell figure and CSVs).
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.reporting.plots_spindle import plot_campbell, plot_unbalance_response
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind
from surrogate_rbrdo.runner.tables import SpindleTable, build_spindle, require_memory
from surrogate_rbrdo.spindle.evaluate import design_quantities
from surrogate_rbrdo.spindle.harmonic import tool_amplitude
from surrogate_rbrdo.spindle.modal import campbell

HEADER = ["design", "preload_N", "span_mm", "diameter_mm", "rotor_mass_kg",
          "first_natural_frequency_hz", "critical_speeds_rpm", "peak_amplitude_um",
          "peak_speed_rpm", "max_von_mises_MPa", "stress_ratio"]


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
    raw = c.report.designs or {"baseline": tuple(sp.baseline.tolist())}
    for label, x in raw.items():
        try:
            designs[label] = sp.design_map.check(np.asarray(x, dtype=float))
        except ValueError as exc:
            raise ValueError(f"report.designs.{label}: {exc}") from None
    if c.report.include_box:
        b = sp.design_map.bounds
        for corner in itertools.product(*[(0, 1)] * b.shape[0]):
            designs["corner " + "".join("-+"[k] for k in corner)] = np.array(
                [b[i, k] for i, k in enumerate(corner)])
        designs["centre"] = b.mean(axis=1)
    require_memory("report.n_speeds", c.report.n_speeds,
                   65536.0 * c.report.n_speeds * (1 + len(designs) / 100),
                   "the unbalance responses (~64 kB per speed)")
    return Plan(sp, designs, c.report)


@dataclass(frozen=True, eq=False)
class DesignCurves:
    """Per design: the summary row, the response curve (µm) and (the first ``n_campbell``
    designs) the Campbell diagram."""

    rows: tuple[tuple[Any, ...], ...]
    speeds_rpm: np.ndarray
    curves: dict[str, np.ndarray]
    campbells: dict[str, Any]


def _compute(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> DesignCurves:
    g, r = p.spindle.geometry, p.report
    speeds = np.linspace(g.speed_min_rpm, g.speed_max_rpm, r.n_speeds)
    camp_speeds = np.linspace(0.0, g.speed_max_rpm, r.campbell_speeds)
    rows, curves, camps = [], {}, {}
    items = list(p.designs.items())
    if ctx.progress:
        items = tqdm(items, desc=f"{ctx.label} designs", unit="design", leave=False)
    for label, x in items:
        q = design_quantities(p.spindle, x)
        rows.append((label, *np.round(x, 3), round(q.rotor_mass_kg, 3),
                     round(q.first_natural_frequency_hz, 2),
                     " ".join(f"{c:.0f}" for c in q.critical_speeds_rpm),
                     round(q.peak_amplitude_m * 1e6, 4), round(q.peak_speed_rpm, 1),
                     round(q.max_von_mises_Pa / 1e6, 3), round(q.stress_ratio, 5)))
        model = p.spindle.model(x)
        curves[label] = tool_amplitude(model, speeds)[0] * 1e6
        if len(camps) < r.n_campbell:
            camps[label] = campbell(model, camp_speeds, n_modes=r.n_modes)
    return DesignCurves(tuple(rows), speeds, curves, camps)


def _report(p: Plan, done: Mapping[str, Any], run: Any, ctx: StageContext) -> dict[str, Any]:
    d: DesignCurves = done["designs"]
    run.write_csv("summary.csv", HEADER, d.rows)
    run.write_csv("unbalance_response.csv", ["speed_rpm", *[f"{k}_um" for k in d.curves]],
                  np.column_stack([d.speeds_rpm, *d.curves.values()]).tolist())
    n = p.report.n_modes
    for label, c in d.campbells.items():
        run.write_csv(f"campbell_{label.replace(' ', '_')}.csv",
                      ["speed_rpm", *[f"mode{k + 1}_hz" for k in range(n)],
                       *[f"mode{k + 1}_whirl" for k in range(n)]],
                      [[s, *f, *w] for s, f, w in zip(c.speeds_rpm, c.frequency_hz.tolist(),
                                                      c.whirl.tolist(), strict=True)])
    total = len(p.designs)
    run.save_figure("campbell.png", plot_campbell(
        d.campbells, speed_max_rpm=p.spindle.geometry.speed_max_rpm, of_total=total))
    run.save_figure("unbalance_response.png", plot_unbalance_response(
        {k: (d.speeds_rpm, v) for k, v in d.curves.items()}))
    return {"designs": total, "summary": [dict(zip(HEADER, r, strict=True)) for r in d.rows]}


register_kind(Kind(
    name="spindle_report",
    summary="a spindle's designs: mass, first natural frequency, critical speeds, peak "
            "amplitude, stress; Campbell diagrams and tool-tip unbalance responses",
    schema=SpindleReportConfig,
    stages=(Stage("designs", _compute),),
    report=_report,
    build=build,
))
