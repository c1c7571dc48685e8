"""Experiment kind ``spindle_report``: Campbell diagram, tool-tip unbalance response over speed
and a summary table for a set of designs of a spindle.

Config tables: ``[spindle]`` (see :func:`~surrogate_rbrdo.runner.config.spindle_from_config`)
and ``[report]``:

``designs``         labels -> design vectors ``[F_f N, L mm, D mm]`` (default: the baseline)
``include_box``     add the 8 corners and the centre of the design box (default false)
``n_speeds``        points of the response curve (default 400)
``campbell_speeds`` speeds of the Campbell grid over 0..max speed (default 25)
``n_modes``         modes in the Campbell diagram (default 8)
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from typing import Any

import numpy as np

from surrogate_rbrdo.core.validate import check_int, check_keys
from surrogate_rbrdo.reporting.plots_spindle import plot_campbell, plot_unbalance_response
from surrogate_rbrdo.runner.config import spindle_from_config
from surrogate_rbrdo.runner.experiments import EXPERIMENTS
from surrogate_rbrdo.runner.runfolder import RunFolder
from surrogate_rbrdo.spindle.evaluate import design_quantities
from surrogate_rbrdo.spindle.harmonic import tool_amplitude
from surrogate_rbrdo.spindle.modal import campbell

REPORT_KEYS = {"designs", "include_box", "n_speeds", "campbell_speeds", "n_modes"}


def report_designs(report: Mapping[str, Any], spindle) -> dict[str, np.ndarray]:
    designs: dict[str, np.ndarray] = {}
    raw = report.get("designs", {"baseline": spindle.baseline.tolist()})
    if not isinstance(raw, Mapping) or not raw:
        raise ValueError("report.designs is not allowed: must be a table label = [F, L, D]")
    for label, x in raw.items():
        try:
            designs[label] = spindle.design_map.check(np.asarray(x, dtype=float))
        except ValueError as exc:
            raise ValueError(f"report.designs.{label}: {exc}") from None
    if report.get("include_box", False):
        b = spindle.design_map.bounds
        for corner in itertools.product(*[(0, 1)] * b.shape[0]):
            x = np.array([b[i, c] for i, c in enumerate(corner)])
            designs["corner " + "".join("-+"[c] for c in corner)] = x
        designs["centre"] = b.mean(axis=1)
    return designs


@EXPERIMENTS.register("spindle_report")
def run_spindle_report(config: Mapping[str, Any], run: RunFolder, *, progress: bool = False
                       ) -> dict[str, Any]:
    report = dict(config.get("report", {}))
    check_keys("[report]", report, REPORT_KEYS)
    n_speeds = check_int("report.n_speeds", report.get("n_speeds", 400), minimum=2)
    n_camp = check_int("report.campbell_speeds", report.get("campbell_speeds", 25), minimum=2)
    n_modes = check_int("report.n_modes", report.get("n_modes", 8), minimum=1)
    spindle = spindle_from_config(config.get("spindle", {}), config.get("_base_dir", "."))
    designs = report_designs(report, spindle)
    g = spindle.geometry
    speeds = np.linspace(g.speed_min_rpm, g.speed_max_rpm, n_speeds)
    camp_speeds = np.linspace(0.0, g.speed_max_rpm, n_camp)

    rows, curves, camps = [], {}, {}
    header = ["design", "preload_N", "span_mm", "diameter_mm", "rotor_mass_kg",
              "first_natural_frequency_hz", "critical_speeds_rpm", "peak_amplitude_um",
              "peak_speed_rpm", "max_von_mises_MPa", "stress_ratio"]
    items = list(designs.items())
    if progress:
        from tqdm import tqdm

        items = tqdm(items, desc="designs", unit="design")
    for label, x in items:
        with run.timed("design_quantities"):
            q = design_quantities(spindle, x)
        rows.append([label, *np.round(x, 3), round(q.rotor_mass_kg, 3),
                     round(q.first_natural_frequency_hz, 2),
                     " ".join(f"{c:.0f}" for c in q.critical_speeds_rpm),
                     round(q.peak_amplitude_m * 1e6, 4), round(q.peak_speed_rpm, 1),
                     round(q.max_von_mises_Pa / 1e6, 3), round(q.stress_ratio, 5)])
        model = spindle.model(x)
        with run.timed("unbalance_response"):
            curves[label] = (speeds, tool_amplitude(model, speeds)[0] * 1e6)
        if len(camps) < 4:  # keep the Campbell figure readable
            with run.timed("campbell"):
                camps[label] = campbell(model, camp_speeds, n_modes=n_modes)
    run.write_csv("summary.csv", header, rows)
    run.write_csv("unbalance_response.csv", ["speed_rpm", *[f"{k}_um" for k in curves]],
                  np.column_stack([speeds, *[c[1] for c in curves.values()]]).tolist())
    for label, c in camps.items():
        safe = label.replace(" ", "_")
        run.write_csv(f"campbell_{safe}.csv",
                      ["speed_rpm", *[f"mode{k + 1}_hz" for k in range(n_modes)],
                       *[f"mode{k + 1}_whirl" for k in range(n_modes)]],
                      [[s, *f, *w] for s, f, w in zip(c.speeds_rpm, c.frequency_hz.tolist(),
                                                      c.whirl.tolist(), strict=True)])
    plot_campbell(camps, run.file("campbell.png"), speed_max_rpm=g.speed_max_rpm)
    plot_unbalance_response(dict(list(curves.items())[:6]), run.file("unbalance_response.png"))
    return {"designs": len(designs), "summary": [dict(zip(header, r, strict=True)) for r in rows]}
