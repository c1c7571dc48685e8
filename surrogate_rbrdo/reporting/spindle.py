"""Designs of a spindle at nominal θ: design quantities, tool-tip unbalance responses and
Campbell diagrams, as one frozen :class:`SpindleOverview`, and its tables and figures.

Used by the ``spindle_report`` kind (all of it: its tables :class:`SpindleReportConfig`,
checked by :func:`build_spindle_report`; :func:`write_spindle_report`) and by the study's
report (the baseline and a compromise design).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from surrogate_rbrdo.core.memory import check_memory
from surrogate_rbrdo.core.validate import check_int, check_label
from surrogate_rbrdo.reporting.plots_spindle import plot_campbell, plot_unbalance_response
from surrogate_rbrdo.spindle.config import SpindleTable, build_spindle
from surrogate_rbrdo.spindle.evaluate import design_quantities
from surrogate_rbrdo.spindle.harmonic import tool_amplitude
from surrogate_rbrdo.spindle.modal import campbell, check_modes_of

#: peak bytes per speed and degree of freedom of one design's unbalance response (measured
#: with tracemalloc on the reference spindle: ~390 B; with margin)
BYTES_PER_SPEED_DOF = 512.0


def overview_memory(n_dof: int, n_designs: int, *, n_speeds: int, campbell_speeds: int,
                    n_modes: int) -> dict[str, float]:
    """Peak bytes of :func:`spindle_overview`'s arrays per size field (for
    ``core.memory.check_memory``): the unbalance response of one design at a time and every
    design's curve; the Campbell arrays (frequency, damping, whirl) of every design and one
    state-space eigenproblem.

    >>> overview_memory(80, 4, n_speeds=10 ** 12, campbell_speeds=25, n_modes=8)["n_speeds"] > 1e16
    True
    """
    return {"n_speeds": BYTES_PER_SPEED_DOF * n_speeds * n_dof + 8.0 * n_speeds * n_designs,
            "campbell_speeds": 24.0 * campbell_speeds * n_modes * n_designs
            + 64.0 * (2 * n_dof) ** 2}


def check_overview(spindle: Any, designs: Mapping[str, np.ndarray], *, n_speeds: int,
                   campbell_speeds: int, n_modes: int, where: str = "") -> None:
    """Refuse (before any work) more modes than the model has and sizes whose arrays would
    not fit in the memory available now; messages name ``<where>.<field>``."""
    pre = f"{where}." if where else ""
    n_dof = spindle.model(np.asarray(next(iter(designs.values())), float)).n_dof
    check_modes_of(n_dof, n_modes, f"{pre}n_modes")
    sizes = {"n_speeds": n_speeds, "campbell_speeds": campbell_speeds}
    check_memory({f"{pre}{k}": (sizes[k], b) for k, b in overview_memory(
        n_dof, len(designs), n_speeds=n_speeds, campbell_speeds=campbell_speeds,
        n_modes=n_modes).items()})


#: columns of :func:`quantity_rows`
QUANTITY_HEADER = ["design", "preload_N", "span_mm", "diameter_mm", "rotor_mass_kg",
                   "first_natural_frequency_hz", "critical_speeds_rpm", "peak_amplitude_um",
                   "peak_speed_rpm", "max_von_mises_MPa", "stress_ratio"]


@dataclass(frozen=True, eq=False)
class SpindleOverview:
    """Per design (label): ``X`` row, tool-tip amplitude (µm) at ``speeds_rpm``, the Campbell
    diagram (the first ``n_campbell`` designs) and, if asked, the design quantities."""

    labels: tuple[str, ...]
    X: np.ndarray
    speeds_rpm: np.ndarray
    amplitude_um: dict[str, np.ndarray]
    campbells: dict[str, Any]
    quantities: dict[str, Any] | None = None


def spindle_overview(spindle: Any, designs: Mapping[str, np.ndarray], *, n_speeds: int,
                     campbell_speeds: int, n_modes: int, n_campbell: int | None = None,
                     quantities: bool = False, progress: bool = False, label: str = ""
                     ) -> SpindleOverview:
    """Response curves over the spindle's speed range, Campbell diagrams over 0..top speed
    (``n_campbell`` designs, default all) and optionally the design quantities. Sizes whose
    arrays would not fit, or more modes than the model has, are refused before any work."""
    check_overview(spindle, designs, n_speeds=n_speeds, campbell_speeds=campbell_speeds,
                   n_modes=n_modes)
    g = spindle.geometry
    speeds = np.linspace(g.speed_min_rpm, g.speed_max_rpm, n_speeds)
    camp_speeds = np.linspace(0.0, g.speed_max_rpm, campbell_speeds)
    n_campbell = len(designs) if n_campbell is None else n_campbell
    curves, camps, qs = {}, {}, {}
    items: Any = list(designs.items())
    if progress:
        items = tqdm(items, desc=f"{label} designs".strip(), unit="design", leave=False)
    for name, x in items:
        if quantities:
            qs[name] = design_quantities(spindle, x)
        model = spindle.model(np.asarray(x, float))
        curves[name] = tool_amplitude(model, speeds)[0] * 1e6
        if len(camps) < n_campbell:
            camps[name] = campbell(model, camp_speeds, n_modes=n_modes)
    return SpindleOverview(tuple(designs), np.array(list(designs.values())), speeds, curves,
                           camps, qs if quantities else None)


def quantity_rows(ov: SpindleOverview) -> list[list[Any]]:
    """``QUANTITY_HEADER`` rows (needs ``quantities=True``)."""
    rows = []
    for name, x in zip(ov.labels, ov.X, strict=True):
        q = ov.quantities[name]
        rows.append([name, *np.round(x, 3), round(q.rotor_mass_kg, 3),
                     round(q.first_natural_frequency_hz, 2),
                     " ".join(f"{c:.0f}" for c in q.critical_speeds_rpm),
                     round(q.peak_amplitude_m * 1e6, 4), round(q.peak_speed_rpm, 1),
                     round(q.max_von_mises_Pa / 1e6, 3), round(q.stress_ratio, 5)])
    return rows


def write_overview(out: Any, ov: SpindleOverview, *, n_modes: int, speed_max_rpm: float,
                   limit_um: float | None = None, campbell_csv: bool = False,
                   critical_csv: bool = False) -> None:
    """``unbalance_response.csv``, ``campbell.png``, ``unbalance_response.png``; with
    ``critical_csv`` ``critical_speeds.csv`` (from the Campbell diagrams), with
    ``campbell_csv`` one ``campbell_<label>.csv`` per diagram."""
    names = ["preload_N", "span_mm", "diameter_mm"]
    out.write_csv("unbalance_response.csv", ["speed_rpm", *[f"{k}_um" for k in ov.labels]],
                  np.column_stack([ov.speeds_rpm, *ov.amplitude_um.values()]).tolist())
    if critical_csv:
        out.write_csv("critical_speeds.csv", ["design", *names, "critical_speeds_rpm"],
                      [[k, *np.round(x, 3), " ".join(f"{c:.0f}" for c in
                                                     ov.campbells[k].critical_speeds_rpm)]
                       for k, x in zip(ov.labels, ov.X, strict=True)])
    for name, c in ov.campbells.items() if campbell_csv else ():
        out.write_csv(f"campbell_{name.replace(' ', '_')}.csv",
                      ["speed_rpm", *[f"mode{k + 1}_hz" for k in range(n_modes)],
                       *[f"mode{k + 1}_whirl" for k in range(n_modes)]],
                      [[s, *f, *w] for s, f, w in zip(c.speeds_rpm, c.frequency_hz.tolist(),
                                                      c.whirl.tolist(), strict=True)])
    out.save_figure("campbell.png", plot_campbell(ov.campbells, speed_max_rpm=speed_max_rpm,
                                                  of_total=len(ov.labels)))
    out.save_figure("unbalance_response.png", plot_unbalance_response(
        {k: (ov.speeds_rpm, v) for k, v in ov.amplitude_um.items()}, limit_um=limit_um))


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
    """The tables of a ``spindle_report`` config."""

    spindle: SpindleTable = field(default_factory=SpindleTable)
    report: ReportTable = field(default_factory=ReportTable)


@dataclass(frozen=True, eq=False)
class SpindleReportPlan:
    """The spindle, its designs (label → x, checked) and the ``[report]`` table."""

    spindle: Any
    designs: dict[str, np.ndarray]
    report: ReportTable


def build_spindle_report(c: SpindleReportConfig, base_dir: str | Path = "."
                         ) -> SpindleReportPlan:
    """The checked plan of a ``spindle_report`` config: the designs in the design box, the
    modes and the memory of the figures (errors name the dotted path)."""
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
    return SpindleReportPlan(sp, designs, r)


def write_spindle_report(out: Any, p: SpindleReportPlan, ov: SpindleOverview) -> dict[str, Any]:
    """``summary.csv`` (the design quantities) and :func:`write_overview`'s tables and figures
    into ``out`` (a run folder); returns the summary."""
    rows = quantity_rows(ov)
    out.write_csv("summary.csv", QUANTITY_HEADER, rows)
    write_overview(out, ov, n_modes=p.report.n_modes,
                   speed_max_rpm=p.spindle.geometry.speed_max_rpm, campbell_csv=True)
    return {"designs": len(ov.labels),
            "summary": [dict(zip(QUANTITY_HEADER, r, strict=True)) for r in rows]}


__all__ = ["QUANTITY_HEADER", "ReportTable", "SpindleOverview", "SpindleReportConfig",
           "SpindleReportPlan", "build_spindle_report", "check_overview", "overview_memory",
           "quantity_rows", "spindle_overview", "write_overview", "write_spindle_report"]
