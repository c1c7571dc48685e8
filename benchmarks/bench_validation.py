"""Benchmark and reference run of the validation on the virtual rig (``docs/validation.md``).

Run:  PYTHONPATH=$PWD python3 benchmarks/bench_validation.py [--out /tmp/bench_validation]
      [--designs baseline rbrdo5 ...] [--model-samples 1000] [--seed 2024] [--quick]

Designs (by name): the paper study's baseline [2000 N, 465.8 mm, 65 mm] and its RBRDO
compromises (docs/paper-study.md, physics-structured surrogate): ``rbrdo5`` [3000, 477.4, 71.80],
``rbrdo10`` [3000, 475.4, 71.59], ``rbrdo1`` [3000, 478.2, 72.00]; ``ref500`` is the reference
spindle's own baseline [2000, 500, 65] (first bending critical speed inside the range). Default:
baseline and rbrdo5. The model is the reference spindle with θ ~ N(1, diag(0.0605², 0.0641²))
(the study's Table 4 CoVs).

Prints: wall time of each stage at default options (n = 20, 231 speeds, one run-up/run-down
per design), steady-state records, peak RSS; the fast path against time records for one
replication (same records, ratio measured side by side); the truth's own μ, σ, P_f of every
design (400 truth states through the FE peak search, no sensors); the spread of P_f within an
assembly (20 builds x 20 runs/tool changes each): how often a build's conditional P_f is
strictly between 0 and 1. Writes tables, figures and ``validation.md`` into ``--out``.
"""

from __future__ import annotations

import argparse
import os
import resource
import time
from dataclasses import replace

import numpy as np

from surrogate_rbrdo.reporting.plots_validation import write_validation_report
from surrogate_rbrdo.spindle.harmonic import peak_tool_amplitude
from surrogate_rbrdo.spindle.reference import reference_spindle
from surrogate_rbrdo.uncertainty import MultivariateNormal
from surrogate_rbrdo.validation import (
    ValidationOptions,
    reference_family,
    spindle_model_spec,
    validate_designs,
)
from surrogate_rbrdo.validation.measure import measure_replica
from surrogate_rbrdo.validation.replicas import replica_states

DESIGNS = {"baseline": [2000.0, 465.8, 65.0], "rbrdo5": [3000.0, 477.4, 71.80],
           "rbrdo10": [3000.0, 475.4, 71.59], "rbrdo1": [3000.0, 478.2, 72.00],
           "ref500": [2000.0, 500.0, 65.0]}


def _campaign(args, designs, opts):
    spec = spindle_model_spec(reference_spindle(),
                              MultivariateNormal(np.ones(2), std=[0.0605, 0.0641]),
                              n_samples=args.model_samples)
    t0 = time.perf_counter()
    res = validate_designs(reference_family(), designs, options=opts,
                           rng=np.random.default_rng(args.seed), model=spec)
    t1 = time.perf_counter()
    paths = write_validation_report(res, args.out)
    t2 = time.perf_counter()
    print(f"validate_designs ({len(designs)} designs): {t1 - t0:.1f} s  "
          + "  ".join(f"{k} {v:.1f} s" for k, v in res.timings.items()))
    print(f"write_validation_report: {t2 - t1:.1f} s ({len(paths)} files)")
    print(f"steady-state records: {sum(d.n_records for d in res.designs)}; model calls "
          f"{res.model.n_calls}; model step: "
          + "  ".join(f"{k} {v:.1f} s" for k, v in res.model.timings.items()))
    for d in res.designs:
        m = d.moments["peak"]
        print(f"  {d.name:9s} measured μ {m.mean * 1e6:8.3f} µm  σ {m.std * 1e6:7.3f} µm  "
              f"P_f {m.pf:.2f} {m.pf_ci}")
    for v in res.disagreements:
        print(f"  disagree: {v.design} {v.quantity} {v.metric}: measured {v.measured:.4g}, "
              f"model {v.model:.4g}, p_holm {v.p_holm:.2g}")
    return res


def _fast_vs_records(opts):
    st = replica_states(reference_family(), {"b": DESIGNS["baseline"]}, 1,
                        seed=np.random.SeedSequence(1))["b"][0]
    inst = opts.sensors.install(np.random.default_rng(0))
    out = {}
    for method in ("phasors", "records"):
        t0 = time.perf_counter()
        m = measure_replica(st, replace(opts, method=method), inst, np.random.default_rng(2))
        out[method] = (time.perf_counter() - t0, m)
    (tf, mf), (tr, mr) = out["phasors"], out["records"]
    big = mr.curve > 0.1e-6
    print(f"one replication, {mf.n_records} steady-state records: phasor path {tf:.3f} s, "
          f"time records {tr:.1f} s (x{tr / tf:.0f}); peak {mf.peak * 1e6:.4f} vs "
          f"{mr.peak * 1e6:.4f} µm; where the amplitude > 0.1 µm the curves differ by at most "
          f"{np.max(np.abs(mf.curve - mr.curve)[big] / mr.curve[big]):.1e} (relative; each "
          "path draws its own noise, 0.73 nm per part)")


def _truth_moments(designs, limit_m):
    states = replica_states(reference_family(), designs, 400, seed=np.random.SeedSequence(99))
    for k, v in states.items():
        y = np.array([peak_tool_amplitude(s.model(), s.theta).amplitude[0] for s in v])
        print(f"  truth {k:9s} μ {y.mean() * 1e6:8.3f} µm  σ {y.std(ddof=1) * 1e6:7.3f} µm  "
              f"P_f {np.mean(y > limit_m):.3f}  (400 states, FE, no sensors)")


def _within_assembly(limit_m):
    fam = reference_family()
    cond = []
    for b in range(20):
        st = replica_states(fam, {"b": DESIGNS["baseline"]}, 20,
                            seed=np.random.SeedSequence([7, b]), replicate=("tool", "run"))
        y = np.array([peak_tool_amplitude(s.model(), s.theta).amplitude[0] for s in st["b"]])
        cond.append(np.mean(y > limit_m))
    cond = np.array(cond)
    print(f"baseline, P_f within an assembly (20 builds x 20 tool changes/runs): "
          f"{np.sum((cond > 0) & (cond < 1))} of 20 builds strictly between 0 and 1; "
          f"values {np.round(cond, 2).tolist()}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="/tmp/bench_validation")
    ap.add_argument("--designs", nargs="+", choices=list(DESIGNS),
                    default=["baseline", "rbrdo5"])
    ap.add_argument("--model-samples", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=2024)
    ap.add_argument("--quick", action="store_true", help="campaign only")
    args = ap.parse_args()
    print(f"load average: {os.getloadavg()}")
    designs = {k: DESIGNS[k] for k in args.designs}
    opts = ValidationOptions()
    res = _campaign(args, designs, opts)
    if not args.quick:
        _fast_vs_records(opts)
        _truth_moments(designs, res.options.delta_lim_m)
        _within_assembly(res.options.delta_lim_m)
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak RSS {rss:.0f} MB; load average: {os.getloadavg()}")


if __name__ == "__main__":
    main()
