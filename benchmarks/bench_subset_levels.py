"""Where subset simulation's nominal 95 % interval falls short at moderate P_f: by level count.

    OMP_NUM_THREADS=1 PYTHONPATH=. python benchmarks/bench_subset_levels.py --seeds 2000

For each problem, subset simulation with its default options runs with ``default_rng(seed)``;
every run's log-error ``ln(P̂/P)`` is standardised by the log-normal interval's own scale,
``z = (ln(P̂/P) + s²/2)/s`` with ``s² = ln(1 + δ²)`` (``|z| < 1.96``: the nominal 95 % interval
covers). The rows split the runs by the number of levels they used: a run whose last
intermediate level happens to hold fewer than ``p0·N`` failures takes one more level, and those
are the runs whose estimate landed low. Printed: runs, share, mean and standard deviation of
``z``, share covered, mean ``s`` and the standard deviation of ``ln(P̂/P)``.
"""

from __future__ import annotations

import argparse

import numpy as np
from threadpoolctl import threadpool_limits

from surrogate_rbrdo.estimators.problems import benchmark_problems
from surrogate_rbrdo.estimators.subset import SubsetSimulation

DEFAULT = ("linear_2d_beta3", "correlated_normal_3d", "series4_k6", "convex_waarts")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=2000)
    ap.add_argument("--problems", nargs="*", default=list(DEFAULT))
    args = ap.parse_args()
    est = SubsetSimulation()
    print("| problem | exact P_f | levels | runs | share | mean z | sd z | 95 % covered "
          "| mean s | sd ln(P̂/P) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    with threadpool_limits(1):
        for prob in benchmark_problems():
            if prob.name not in args.problems:
                continue
            p = float(prob.pf_exact[0])
            lr, s, lev = (np.empty(args.seeds) for _ in range(3))
            for seed in range(args.seeds):
                r = est.estimate(prob.response, prob.inputs, prob.limit, prob.x[:1],
                                 rng=np.random.default_rng(seed))
                lr[seed] = np.log(r.pf[0] / p)
                s[seed] = np.sqrt(np.log1p((r.pf_se[0] / r.pf[0]) ** 2))
                lev[seed] = r.diagnostics["levels"][0]
            z = (lr + 0.5 * s * s) / s
            for label, k in [("all", np.ones(args.seeds, bool))] + [
                    (f"{int(v)}", lev == v) for v in np.unique(lev)]:
                print(f"| {prob.name} | {p:.4e} | {label} | {int(k.sum())} "
                      f"| {k.mean():.3f} | {z[k].mean():+.2f} | {z[k].std():.2f} "
                      f"| {np.mean(np.abs(z[k]) < 1.96):.3f} | {s[k].mean():.3f} "
                      f"| {lr[k].std():.3f} |", flush=True)


if __name__ == "__main__":
    main()
