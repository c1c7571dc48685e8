"""Blind tests of the discrepancy workflow: rates per class and strength, with both baselines.

    PYTHONPATH=$PWD python3 benchmarks/discrepancy_blind.py --source rig --seeds 5 --jobs 2 \
        --out /tmp/<you>/blind.csv

Sources: ``rig`` — the virtual rig (``surrogate_rbrdo.rig``): its truth with the default
variability (bearing stiffness 5 %, damping 20 % per build; thermal preload 8 % per run; tool
mass 3 %; unbalance per ISO 21940 with random phases), its sensors (gain 2 %, 10 kHz drivers,
skew, 50 nm noise, 16-bit ADC, keyphasor phase errors) through its statistical fast path
``rig.phasors.sample_phasors``, 20 runs × 50 speeds; identified stiffness is emulated per run
(the truth's effective bearing stiffness with 0.4 % error per record, the identification
note's figure) for the sparse baseline. With ``--impacts`` (the default test plan,
``rig.impacts.ImpactPlan``): impact tests at the tool at standstill, 10 000 and 20 000 rpm, x
and y, 20 hits each, all in one run after the 1x runs (its own thermal state), all six probes, FRF
lines 40–1 480 Hz every 40 Hz through the rig's sensors (probe and hammer gain, driver,
skew, noise, quantisation; ``rig.impacts.sample_frfs``); ``--impacts none``: the 1x campaign
alone (the data before this test plan). With ``--soak`` (the default, ``rig.thermal.SoakPlan``):
a thermal soak after them — 4 cold starts, each held for an hour, two at each of the sweep
speeds either side of its resonance, with a 1x record and a bearing temperature every 5–15 min
(``RigSource._soaks``), the separating test of an effect that drifts with temperature
(``discrepancy.soak``); ``--soak resonance``: the 4 at the resonance; ``--soak none``:
without. ``--tempco``: the probes' sensitivity tempco (default 0; the data-sheet scale is
``rig.sensors.PROBE_TEMPCO_SD_PER_K``), on the soak and (``--tempco-sweep yes``, the default)
the sweep too.
``synthetic`` — the phasor-level stand-in of ``discrepancy.synthetic`` (with impact FRFs).
Noise levels scale the probe noise and the run-to-run thermal scatter (rig) or every noise
component (synthetic) by 0.5, 1 and 3.

Prints: the calibrated knob values, the signature cosines and confounded pairs, the rates table
of the workflow and of both baselines, the targets, and the timings (measured under load: the
load average is printed).
"""

from __future__ import annotations

import argparse
import csv
import os
import resource
import time
from dataclasses import replace

import numpy as np
from joblib import Parallel, delayed

from surrogate_rbrdo.discrepancy.blind import (
    HIDDEN,
    STRENGTHS,
    Context,
    SyntheticSource,
    rates,
    run_scenario,
)
from surrogate_rbrdo.discrepancy.candidates import library
from surrogate_rbrdo.discrepancy.grid import (
    build_grid,
    calibrate_grid,
    confounded_pairs,
    signature_cosines,
)
from surrogate_rbrdo.discrepancy.nuisance import NuisanceOptions
from surrogate_rbrdo.discrepancy.rig_source import FACTORS, RigSource
from surrogate_rbrdo.discrepancy.synthetic import Campaign, NoiseLevel
from surrogate_rbrdo.discrepancy.workflow import GENERIC_CONFOUND, DiscrepancyOptions
from surrogate_rbrdo.rig.impacts import ImpactPlan
from surrogate_rbrdo.rig.sensors import PROBE_TEMPCO_SD_PER_K
from surrogate_rbrdo.rig.thermal import SoakPlan
from surrogate_rbrdo.spindle.reference import reference_spindle


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--source", choices=("rig", "synthetic"), default="rig")
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--noise", nargs="+", default=list(FACTORS))
    ap.add_argument("--out", default="")
    ap.add_argument("--draws", type=int, default=400)
    ap.add_argument("--impacts", choices=("plan", "none"), default="plan",
                    help="impact tests at speed (rig.impacts.ImpactPlan) or the 1x data alone")
    ap.add_argument("--soak", choices=("plan", "resonance", "none"), default="plan",
                    help="a thermal soak after the sweep (rig.thermal.SoakPlan: 4 cold starts "
                         "held for an hour, 2 at each of the sweep speeds either side of the "
                         "resonance), the same at the resonance alone, or none")
    ap.add_argument("--tempco", type=float, default=0.0, metavar="SD_PER_K",
                    help="rig: SD of the probes' sensitivity tempco (1/K; rig.sensors."
                         "ProbeModel.tempco_sd_per_K; default 0: none; the data-sheet scale "
                         f"is {PROBE_TEMPCO_SD_PER_K:g})")
    ap.add_argument("--tempco-sweep", choices=("yes", "no"), default="yes",
                    help="rig: the tempco acts on the sweep too (each speed's equilibrium "
                         "temperature rise), not only on the soak")
    ap.add_argument("--calibrate-on", choices=("same", "none"), default="same",
                    help="strengths calibrated on the data the scenarios use (same) or on the "
                         "1x data alone (none: the 1x grid's physical sizes, measured with the "
                         "data of --impacts)")
    ap.add_argument("--classes", nargs="+", default=[],
                    help="run only scenarios whose class and strength contain every word of "
                         "one of these (e.g. 'strong' 'sub-noise' 'nothing' 'single strong')")
    ap.add_argument("--separable", type=float, default=None, metavar="Z_SEP",
                    help="add a 'separable' strength: every library effect alone where the "
                         "part of its strength no generic rival explains reaches Z_SEP "
                         "(grid.calibrate_grid; e.g. 12, the strong level)")
    ap.add_argument("--generic-confound", choices=GENERIC_CONFOUND,
                    default=DiscrepancyOptions.generic_confound,
                    help="the answer when a library effect and a generic local change explain "
                         "the data alike (DiscrepancyOptions.generic_confound)")
    ap.add_argument("--base-seed", type=int, default=0,
                    help="root of the scenarios' seeds (another value: an independent sample)")
    ap.add_argument("--report", nargs="+", default=[],
                    help="only print the rates of earlier runs' --out CSVs, pooled")
    ap.add_argument("--compare", nargs=2, default=[], metavar=("BEFORE", "AFTER"),
                    help="compare two runs' --out CSVs of the same scenarios (e.g. two commits): "
                         "verdicts, names, statistics and CPU")
    args = ap.parse_args()
    if args.compare:
        _compare(*args.compare)
        return
    if args.calibrate_on == "none" and args.source != "rig":
        ap.error("--calibrate-on none is for --source rig (the 1x data without the impacts)")
    if args.report:
        rows = []
        for path in args.report:
            with open(path, newline="") as fh:
                rows += list(csv.DictReader(fh))
        print(f"{len(rows)} scenarios from {len(args.report)} file(s)")
        _report(rows)
        return
    t0, c0 = time.perf_counter(), time.process_time()
    sp = reference_spindle()
    g = sp.geometry_for(sp.baseline)
    speeds = tuple(np.linspace(1000.0, 24000.0, 50).tolist())
    if args.source == "rig":
        source = RigSource(speeds, 20, FACTORS,
                           impacts=ImpactPlan() if args.impacts == "plan" else None,
                           soak=None if args.soak == "none" else SoakPlan(
                               rule="flanks" if args.soak == "plan" else "resonance"),
                           tempco_sd_per_K=args.tempco,
                           tempco_sweep=args.tempco_sweep == "yes")
        nuis = NuisanceOptions.probe_chain()
    else:
        lv = NoiseLevel()
        source = SyntheticSource(Campaign(), {k: replace(lv, **{f: getattr(lv, f) * s for f in (
            "additive_m", "gain", "phase_rad", "frf_additive", "k_relative")})
            for k, s in FACTORS.items()}, 2 * sp.geometry.unbalances[0].magnitude_kgm, (0.0, 350.0))
        nuis = NuisanceOptions()
    ctx = Context(g, sp.effects, source, DiscrepancyOptions(nuisance=nuis, n_draws=args.draws,
                                                           generic_confound=args.generic_confound))
    noises = tuple(args.noise)
    names = tuple(n for n in HIDDEN if HIDDEN[n].truth_only or n in ctx.options.library)
    cal = calibrate_grid(ctx if args.calibrate_on == "same" else replace(
        ctx, source=replace(source, impacts=None)), names, noises,
        separable_target=args.separable)
    c_cal = time.process_time() - c0
    print(f"calibration: {time.perf_counter() - t0:.0f} s ({c_cal:.0f} s CPU)")
    for k in sorted(cal.knob):
        sep = (f"  separable {cal.separable[k][0]:.2f} (closest rival: {cal.separable[k][1]})"
               if k in cal.separable else "")
        print(f"  {k[0]:22s} {k[1]:10s} {k[2]:8s} knob {cal.knob[k]:.4g}  z {cal.z[k]:.2f}"
              + sep)
    cn, cos = signature_cosines(ctx, "default")
    print("signature cosines (default noise):", cn)
    print(np.round(cos, 3))
    lib = {c.name: c.one_sided[0] for c in library(ctx.options.library, ("front", "rear"))}
    pairs = confounded_pairs(cn, cos, lib)
    print("confounded pairs:", pairs)
    if args.classes and not any("confounded" in c for c in args.classes):
        pairs = []                    # not run: their strengths need not be calibrated
    grid = build_grid(ctx, cal, noises, args.seeds, pairs, base_seed=args.base_seed)
    # the full grid's size (3 noise levels x 5 seeds) from this run's cells
    n_full = (len(grid) * 3 * 5 // (args.seeds * len(noises)), not pairs)
    if args.classes:
        grid = [sc for sc in grid if any(all(w in f"{sc.label} {sc.strength}"
                                             for w in c.split()) for c in args.classes)]
    print(f"{len(grid)} scenarios")
    # replicate k of every cell before replicate k + 1: a run stopped early is a balanced
    # sample; each row is written as it arrives
    grid = [sc for k in range(args.seeds) for sc in grid[k::args.seeds]]
    t1 = time.perf_counter()
    rows = []
    fh = open(args.out, "w", newline="") if args.out else None
    try:
        for sc, row in zip(grid, Parallel(n_jobs=args.jobs, verbose=0, return_as="generator")(
                delayed(run_scenario)(ctx, sc) for sc in grid), strict=True):
            sep = cal.separable.get((sc.label.removeprefix("single: "), sc.strength, sc.noise))
            row["z_separable"] = f"{sep[0]:.3g}" if sep else ""
            if fh is not None:
                if not rows:
                    w = csv.DictWriter(fh, fieldnames=list(row))
                    w.writeheader()
                w.writerow(row)
                fh.flush()
            rows.append(row)
    finally:
        if fh is not None:
            fh.close()
    t_grid = time.perf_counter() - t1
    _report(rows)
    _timings(rows, args.jobs, t_grid, time.perf_counter() - t0, c_cal, n_full)


def _timings(rows: list[dict], jobs: int, t_grid: float, t_total: float, c_cal: float,
             n_full: tuple[int, bool]) -> None:
    """CPU per scenario (which other jobs on the machine do not inflate), the wall time it
    implies on 2 idle cores (calibration serial, scenarios two at a time) and peak memory."""
    cpu = np.array([float(r["cpu_seconds"]) for r in rows])
    print(f"grid: {t_grid:.0f} s wall for {len(rows)} scenarios on {jobs} jobs "
          f"({np.mean([float(r['seconds']) for r in rows]):.1f} s workflow wall per "
          f"scenario); total {t_total:.0f} s; load average {os.getloadavg()}")
    print(f"CPU: calibration {c_cal:.0f} s + scenarios {cpu.sum():.0f} s ({cpu.mean():.2f} s "
          f"per scenario, median {np.median(cpu):.2f}, max {cpu.max():.2f}; data + workflow + "
          f"baselines); on 2 otherwise idle cores about {(c_cal + cpu.sum() / 2) / 60:.1f} "
          f"min; the full grid ({n_full[0]} scenarios"
          f"{', without the confounded pairs' if n_full[1] else ''}) at this sample's mean "
          f"about {(c_cal + n_full[0] * cpu.mean() / 2) / 60:.1f} min")
    rss = [float(r["peak_rss_mb"]) for r in rows if "peak_rss_mb" in r]
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak RSS: this process {own:.0f} MB" + (
        f", the process(es) running the scenarios at most {max(rss):.0f} MB each"
        if rss else ""))


def _compare(before: str, after: str) -> None:
    """Per scenario (class, strength, noise, seed) of both files: whether the answers are the
    same, the largest relative change of the numbers, and the CPU of each."""
    def rows(path):
        with open(path, newline="") as fh:
            return {(r["class"], r["strength"], r["noise"], r["seed"]): r
                    for r in csv.DictReader(fh)}
    a, b = rows(before), rows(after)
    answers = ("verdict", "names", "outcome", "gp_verdict", "sparse_verdict", "sparse_names")
    numbers = ("statistic", "p_value", "gap_before_chi2", "gap_after_chi2")
    keys = [k for k in a if k in b]
    same, cpu_a, cpu_b = 0, 0.0, 0.0
    for k in keys:
        x, y = a[k], b[k]
        eq = all(x.get(c) == y.get(c) for c in answers)
        same += eq
        rel = max((abs(float(x[c]) - float(y[c])) / max(abs(float(x[c])), 1e-300), c)
                  for c in numbers if c in x and c in y)
        cpu_a, cpu_b = cpu_a + float(x["cpu_seconds"]), cpu_b + float(y["cpu_seconds"])
        print(f"{k[0][:34]:34s} {k[1]:9s} {k[2]:8s} {x['verdict']:17s} "
              f"{'same' if eq else 'DIFFERENT ' + y['verdict']:10s} max rel change "
              f"{rel[0]:.1e} ({rel[1]}); CPU {float(x['cpu_seconds']):.1f} -> "
              f"{float(y['cpu_seconds']):.1f} s")
    n = max(len(keys), 1)
    print(f"{len(keys)} scenarios in both: {same} with the same answers; CPU {cpu_a:.0f} -> "
          f"{cpu_b:.0f} s ({cpu_a / n:.2f} -> {cpu_b / n:.2f} s per scenario)")


def _report(rows: list[dict]) -> None:
    cols = ("correct_name", "correct_confounded", "partial", "wrong_name", "false_alarm",
            "detected_unnamed", "nothing")
    for column in ("outcome", "gp_outcome", "sparse_outcome"):
        print(f"\n== {column} ==")
        print(f"{'class':44s} {'strength':10s} {'n':>3s} " + " ".join(f"{c[:9]:>9s}"
                                                                    for c in cols))
        for (cl, s), v in sorted(rates(rows, column).items()):
            print(f"{cl:44s} {s:10s} {v['n']:3d} " + " ".join(f"{v.get(c, 0.0):9.2f}"
                                                           for c in cols))
    wrong = np.mean([r["outcome"] == "wrong_name" for r in rows])
    print(f"\nwrong name overall: {wrong:.3f} (target <= 0.02)")
    _target(rows, lambda r: r["class"].startswith("single") and r["strength"] == "strong",
            ("correct_name", "correct_confounded"), "strong single: name or confounded set",
            ">= 0.95")
    # the part of a strong effect no single generic rival explains (blind.separable_strength):
    # below the grid's marginal strength the encompassing test withholds the name by design
    cut = STRENGTHS["marginal"]
    for above in (True, False):
        _target(rows, lambda r, a=above: r["class"].startswith("single")
                and r["strength"] == "strong" and r.get("z_separable", "") != ""
                and (float(r["z_separable"]) >= cut) == a,
                ("correct_name", "correct_confounded"),
                f"  of which separable part z_sep {'>=' if above else '<'} {cut:g}",
                "- (diagnostic)")
    _target(rows, lambda r: r["class"].startswith("single") and r["strength"] == "separable",
            ("correct_name", "correct_confounded"),
            "single at separable strength (--separable): name or confounded set", "- (diagnostic)")
    _target(rows, lambda r: r["class"] == "nothing hidden", ("nothing",),
            "nothing hidden: no false alarm", ">= 0.95")
    _target(rows, lambda r: r["strength"] == "sub-noise", ("nothing",),
            "sub-noise: nothing missing", ">= 0.90")
    _target(rows, lambda r: r["class"].startswith("outside"), ("detected_unnamed", "nothing"),
            "outside: unnamed or nothing", "= 1.00")


def _target(rows, sel, good, label, target) -> None:
    r = [x for x in rows if sel(x)]
    if r:
        print(f"{label}: {np.mean([x['outcome'] in good for x in r]):.3f} of {len(r)} "
              f"(target {target})")


if __name__ == "__main__":
    main()
