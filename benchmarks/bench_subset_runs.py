"""Subset simulation at small P_f: one run against the default independent runs (review 4 of
issue 13). Over ``--seeds`` generators per problem: mean P̂ / exact, the empirical CoV (run-to-run
std / exact), the mean reported CoV, the share of runs whose symmetric ``P̂ ± 3·SE`` covers the
exact P_f, the standard deviation of ``ln(P̂/P)``, runs per estimate and model calls::

    OMP_NUM_THREADS=1 PYTHONPATH=. python benchmarks/bench_subset_runs.py --seeds 200
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from surrogate_rbrdo.estimators import ESTIMATORS
from surrogate_rbrdo.estimators.problems import benchmark_problems

PROBLEMS = ("linear_10d_beta5", "paraboloid_10d_k0.05", "two_sided_linear_10d_b5",
            "exponential_sum_10d", "paraboloid_5d_k0.3", "linear_2d_beta3")
VARIANTS = (("one run (max_runs=1)", {"max_runs": 1}), ("default", {}))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=200)
    args = ap.parse_args()
    probs = {p.name: p for p in benchmark_problems()}
    print("| problem | exact P_f | subset | mean P̂/P | CoV empirical | CoV reported "
          "| 3 SE sym. | sd ln(P̂/P) | runs | model calls | s/run |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in PROBLEMS:
        prob = probs[name]
        exact = float(prob.pf_exact[0])
        for label, opts in VARIANTS:
            est = ESTIMATORS["subset"](**opts)
            rows = []
            t0 = time.perf_counter()
            for seed in range(args.seeds):
                e = est.estimate(prob.response, prob.inputs, prob.limit, prob.x,
                                 rng=np.random.default_rng(seed))
                rows.append((e.pf[0], e.pf_se[0], e.diagnostics["runs"][0], e.n_calls))
            dt = (time.perf_counter() - t0) / args.seeds
            pf, se, runs, calls = np.array(rows).T
            print(f"| {name} | {exact:.4e} | {label} | {pf.mean() / exact:.3f} "
                  f"| {pf.std() / exact:.3f} | {np.mean(se / pf):.3f} "
                  f"| {np.mean(np.abs(pf - exact) <= 3 * se):.3f} "
                  f"| {np.log(pf / exact).std():.3f} | {runs.mean():.2f} | {calls.mean():.0f} "
                  f"| {dt:.2f} |", flush=True)


if __name__ == "__main__":
    main()
