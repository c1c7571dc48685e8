"""Size of the candidates' likelihood-ratio test on null data, every candidate refitted.

    PYTHONPATH=$PWD python3 benchmarks/discrepancy_null_lr.py --seeds 5 --base-seed 500

Nothing is hidden (the virtual rig with its default variability and sensors, the impact plan
of ``benchmarks/discrepancy_blind.py``); the workflow's first stage is run with
``naming.REFIT_FRACTION = 0`` so that every candidate gets its nonlinear fit (the search
:func:`~surrogate_rbrdo.discrepancy.search.fit_candidate`, continuation and valley included),
and its ``Δχ²`` is compared with the bootstrap tail the workflow calibrates it by
(:func:`~surrogate_rbrdo.discrepancy.calibration.simulate_null`). Under the null a calibrated
test puts the nonlinear ``Δχ²`` above the tail's 1 % critical value in about 1 % of the
candidates; the first-order statistic (the one the bootstrap simulates) is printed beside it.

Prints per seed and candidate the first-order and nonlinear statistics, the 1 % critical value
and whether the fit sits at a bound; then the fractions above the critical value, the fractions
of marginal p-values below 0.01, 0.05 and 0.10, and the CPU of the linearisation and bootstrap
per stage (measured under load: the load average is
printed).
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from surrogate_rbrdo.discrepancy import calibration, naming
from surrogate_rbrdo.discrepancy.blind import rig_context
from surrogate_rbrdo.discrepancy.candidates import library
from surrogate_rbrdo.discrepancy.forward import ForwardModel
from surrogate_rbrdo.discrepancy.holdout import split_speeds
from surrogate_rbrdo.discrepancy.observables import MeasuredData
from surrogate_rbrdo.discrepancy.rig_source import FACTORS
from surrogate_rbrdo.discrepancy.workflow import (
    _drop_thin_impacts,
    _recalibrate,
)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--base-seed", type=int, default=500)
    ap.add_argument("--noise", default="default", choices=tuple(FACTORS))
    ap.add_argument("--draws", type=int, default=400)
    ap.add_argument("--level", type=float, default=0.01, help="marginal level of the check")
    ap.add_argument("--impacts", choices=("plan", "none"), default="plan")
    args = ap.parse_args()
    ctx = rig_context(impacts=args.impacts == "plan", n_draws=args.draws)
    g, effects, opts = ctx.geometry, ctx.effects, ctx.options
    naming.REFIT_FRACTION = 0.0                   # every candidate gets its nonlinear fit
    timing: list[float] = []

    def timed_linearise(*a, **k):
        c0 = time.process_time()
        out = calibration.linearise(*a, **k)
        timing.append(time.process_time() - c0)
        return out

    def timed_null(*a, **k):
        c0 = time.process_time()
        out = calibration.simulate_null(*a, **k)
        timing.append(time.process_time() - c0)
        return out

    lin_stats: list[np.ndarray] = []

    def recorded(*a, **k):
        out = calibration.linear_statistics(*a, **k)
        lin_stats.append(out)
        return out

    naming.linearise, naming.simulate_null = timed_linearise, timed_null
    naming.linear_statistics = recorded
    rows = []
    cpu_lin, cpu_null = [], []
    for s in range(args.seeds):
        seed = args.base_seed + s
        data = ctx.source.measure(*ctx.truth(()), args.noise, seed)
        if not opts.use_identified:
            data = MeasuredData(data.blocks, None, data.provenance)
        data, _ = _drop_thin_impacts(data, opts.min_impact_dof)
        one_x = [b for b in data.blocks if b.sweep.kind == "unbalance_1x"]
        split = split_speeds(one_x[0].mean.shape[0], opts.holdout_every,
                             opts.extrapolate_fraction)
        fm = ForwardModel(g, effects, data.channels,
                          tuple(u.position_mm for u in g.unbalances), None,
                          opts.nuisance.mass_disks)
        train, ho, _, base, _ = _recalibrate(fm, data, split, opts)
        timing.clear()
        lin_stats.clear()
        st = naming.run_stage(train, base, library(opts.library, fm.bearing_names), ho,
                              alpha=opts.alpha, n_draws=opts.n_draws,
                              holdout_tolerance=opts.holdout_tolerance,
                              rng=np.random.default_rng([seed, 7]), max_nfev=opts.max_nfev,
                              confound_delta=opts.confound_delta)
        cpu_lin.append(timing[0])
        cpu_null.append(timing[1])
        tails = st.null.tails()
        for k, a in enumerate(st.assessments):
            crit = tails[k].isf(args.level)
            rows.append((seed, a.name, float(lin_stats[0][k]), a.delta_chi2, crit,
                         a.fit.at_bound, float(tails[k].sf(lin_stats[0][k])), a.p_raw))
            print(f"seed {seed} {a.name:16s} first order {lin_stats[0][k]:7.3f}  nonlinear "
                  f"{a.delta_chi2:7.3f}  {100 * args.level:g} % critical {crit:6.2f}  p "
                  f"{rows[-1][6]:.3f} / {a.p_raw:.3f}"
                  f"{'  at bound' if a.fit.at_bound else ''}", flush=True)
    lin = np.array([r[2] for r in rows])
    nl = np.array([r[3] for r in rows])
    crit = np.array([r[4] for r in rows])
    bound = np.array([r[5] for r in rows])
    n = len(rows)
    big = lin > 0.1
    ratio = nl[big] / lin[big]
    print(f"{n} candidate fits on {args.seeds} null data sets: above the {100 * args.level:g} % "
          f"critical value: first order {np.sum(lin > crit)}/{n}, nonlinear "
          f"{np.sum(nl > crit)}/{n} ({np.sum((nl > crit) & ~bound)} not at a bound); "
          f"nonlinear / first order where the first order > 0.1: median "
          f"{np.median(ratio) if ratio.size else np.nan:.2f}, "
          f"max {np.max(ratio) if ratio.size else np.nan:.2f}")
    for name, col in (("first order", 6), ("nonlinear", 7)):
        p = np.array([r[col] for r in rows])
        print(f"{name}: fraction of marginal p-values below 0.01 / 0.05 / 0.10: "
              + " / ".join(f"{np.mean(p < q):.3f}" for q in (0.01, 0.05, 0.10))
              + " (a calibrated test: 0.01 / 0.05 / 0.10)")
    print(f"CPU per stage: linearise {np.mean(cpu_lin):.2f} s, bootstrap "
          f"({args.draws} draws) {np.mean(cpu_null):.2f} s; load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
